//! `run --trace-every T`: the time series of a few-body run, for the classic two- and few-body
//! DEM validation tests — every grain's position, velocity and spin (`trace-grains.csv`) and
//! every contact's forces (`trace-contacts.csv`) — and, for two grains, the impact they make
//! (`impact.json`: duration, peak force, restitution, angles, spins) beside the analytic values
//! it is checked against.

use anyhow::Result;
use grainbench_comparisons::metrics::impact::{self, ImpactReport};
// The exchange format's trace files are ours (docs/exchange-format.md).
use grainbench_comparisons::xcode::decks::generic::{OUT_TRACE_CONTACTS, OUT_TRACE_GRAINS};
use grainbench_engine::scene::Scene;
use grainbench_engine::snapshot::{write_atomic, Snapshot};
use std::path::Path;

/// Writes the trace of `frames` into `out`; with two grains, also `impact.json`, returned.
pub fn write(out: &Path, scene: &Scene, frames: &[Snapshot]) -> Result<Option<ImpactReport>> {
    let Some(first) = frames.first() else {
        return Ok(None);
    };
    let d = first.dimension;
    let axes = &["x", "y", "z"][..d];
    let spin_cols: Vec<String> = if d == 2 {
        vec!["w".into()]
    } else {
        axes.iter().map(|a| format!("w{a}")).collect()
    };
    let mut grains = format!(
        "t,id,{},{},{}\n",
        axes.join(","),
        axes.iter()
            .map(|a| format!("v{a}"))
            .collect::<Vec<_>>()
            .join(","),
        spin_cols.join(",")
    );
    let mut contacts = format!(
        "t,i,j,gap,fn,{}\n",
        axes.iter()
            .map(|a| format!("ft_{a}"))
            .collect::<Vec<_>>()
            .join(",")
    );
    for s in frames {
        let p = &s.particles;
        for i in 0..p.radius.len() {
            let w = p.angular_velocity.get(i).cloned().unwrap_or_default();
            let row: Vec<String> = p.position[i]
                .iter()
                .chain(&p.velocity[i])
                .chain((0..spin_cols.len()).map(|k| w.get(k).unwrap_or(&0.0)))
                .map(|x| format!("{x:e}"))
                .collect();
            grains += &format!("{:e},{i},{}\n", s.time, row.join(","));
        }
        for c in &s.contacts {
            let t: Vec<String> = (0..d)
                .map(|a| format!("{:e}", c.tangential.get(a).copied().unwrap_or(0.0)))
                .collect();
            contacts += &format!(
                "{:e},{},{},{:e},{:e},{}\n",
                s.time,
                c.i,
                c.j,
                c.gap,
                c.normal,
                t.join(",")
            );
        }
    }
    write_atomic(&out.join(OUT_TRACE_GRAINS), grains.as_bytes())?;
    write_atomic(&out.join(OUT_TRACE_CONTACTS), contacts.as_bytes())?;
    if first.particles.radius.len() != 2 {
        return Ok(None);
    }
    let Some(measured) = impact::measure(frames) else {
        return Ok(None);
    };
    let report = impact::against_theory(scene, first, measured);
    write_atomic(
        &out.join("impact.json"),
        (serde_json::to_string_pretty(&report)? + "\n").as_bytes(),
    )?;
    Ok(Some(report))
}

/// The report as a few lines for the terminal.
pub fn describe(r: &ImpactReport) -> String {
    let m = &r.measured;
    let mut s = format!(
        "impact     contact {:.6e} to {:.6e}: duration {:.5e}, peak normal force {:.5e}, e_n {:.6}, incidence {:.2}°, rebound {:.2}°\n",
        m.contact_start, m.contact_end, m.duration, m.peak_normal_force, m.restitution_normal, m.incidence_angle, m.rebound_angle
    );
    if let Some(h) = &r.hertz {
        s += &format!(
            "Hertz      duration {:.5e} ({:+.2} %), peak force {:.5e} ({:+.2} %), e_n 1\n",
            h.duration,
            100.0 * (m.duration / h.duration - 1.0),
            h.peak_normal_force,
            100.0 * (m.peak_normal_force / h.peak_normal_force - 1.0)
        );
    }
    if let Some(sl) = &r.sliding {
        s += &format!(
            "sliding    tangential speed after {:.6e} (measured {:.6e}), spin gained {:.6e} each\n",
            sl.tangential_speed_after, m.tangential_speed_after, sl.spin_gained[0]
        );
    }
    s
}
