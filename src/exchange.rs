//! `grainbench run-exchange IN OUT`: the reference implementation of the exchange format
//! (docs/exchange-format.md). It reads only `IN/exchange.json` and `IN/particles.csv`, runs
//! them in our engine as an explicit-particle scene, and writes `OUT/particles.csv`,
//! `OUT/contacts.csv` and `OUT/status.txt` as any code must (with the exchange's `trace`, also
//! `OUT/trace-grains.csv` and `OUT/trace-contacts.csv`). With the adapter
//! `reference-inputs/adapters/grainbench.toml` it proves the format end to end
//! (`tests/adapter.rs`).

use crate::common::on_threads;
use crate::run::{run, RunFlags};
use anyhow::{bail, Context, Result};
use grainbench_comparisons::xcode::decks::generic::{
    Exchange, ExchangeKind, ExchangeStage, EXCHANGE, OUT_CONTACTS, OUT_PARTICLES, OUT_STATUS,
    OUT_TRACE_CONTACTS, OUT_TRACE_GRAINS,
};
use grainbench_comparisons::xcode::decks::num;
use grainbench_engine::plan::rate_time_unit;
use grainbench_engine::scene::{Initial, Output, Particles, Scene, Step};
use grainbench_engine::snapshot::{write_atomic, Snapshot};
use std::path::{Path, PathBuf};

/// The arguments of `grainbench run-exchange`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Directory holding exchange.json and particles.csv (`grainbench decks SCENE --codes generic`).
    pub input: PathBuf,
    /// Where the final state goes.
    pub output: PathBuf,
    /// Threads.
    #[arg(long, short = 'j')]
    pub threads: Option<usize>,
    #[arg(long, short)]
    pub quiet: bool,
}

/// `grainbench run-exchange`.
pub fn command(a: Args) -> Result<i32> {
    on_threads(a.threads, || run_exchange(&a.input, &a.output, a.quiet))
}

/// Runs the exchange in `input`, writing the final state into `output`.
fn run_exchange(input: &Path, output: &Path, quiet: bool) -> Result<i32> {
    let ex = Exchange::read(&input.join(EXCHANGE)).map_err(anyhow::Error::msg)?;
    let particles = input.join(&ex.particles.file);
    let scene = scene_of(&ex, &particles)?;
    let work = output.join("grainbench");
    let flags = RunFlags {
        quiet,
        report: false,
        resume: false,
        force: true,
        checkpoint_every: 0.0,
        dump_every: None,
        trace_every: ex.trace.as_ref().map(|t| t.every),
        stage_snapshots: false,
    };
    let (code, outcome) = run(&scene, &work, &flags)?;
    let Some(outcome) = outcome else {
        bail!("the run stopped before its final state (exit status {code})");
    };
    let loop_time: f64 = outcome.wall_seconds;
    if let Some(t) = &ex.trace {
        // Our run writes the exchange's trace files under these names; moved before the
        // status line, which says the output is complete.
        for (ours, theirs) in [
            (OUT_TRACE_GRAINS, &t.grains),
            (OUT_TRACE_CONTACTS, &t.contacts),
        ] {
            let from = work.join(ours);
            std::fs::rename(&from, output.join(theirs))
                .with_context(|| format!("moving {} into {}", from.display(), output.display()))?;
        }
    }
    write_state(&outcome.snapshot, output, loop_time)?;
    Ok(0)
}

/// The scene the exchange describes.
fn scene_of(ex: &Exchange, particles: &Path) -> Result<Scene> {
    let cohesive = ex.law.cohesion().is_some();
    let protocol = ex
        .stages
        .iter()
        .enumerate()
        .map(|(k, s)| step(s, cohesive).with_context(|| format!("{EXCHANGE}: stages[{k}]")))
        .collect::<Result<Vec<_>>>()?;
    // Diameters set the size range the scene checks; the file is read again by the engine.
    let mut rd = csv::Reader::from_path(particles)
        .with_context(|| format!("reading {}", particles.display()))?;
    let col = rd
        .headers()?
        .iter()
        .position(|h| h == "diameter")
        .with_context(|| format!("{}: no column `diameter`", particles.display()))?;
    let mut d_min = f64::INFINITY;
    let mut solid = 0.0;
    for r in rd.records() {
        let d: f64 = r?[col]
            .parse()
            .with_context(|| format!("{}: a diameter", particles.display()))?;
        d_min = d_min.min(d);
        solid += if ex.dimension == 2 {
            std::f64::consts::PI * d * d / 4.0
        } else {
            std::f64::consts::PI * d * d * d / 6.0
        };
    }
    let scene = Scene {
        name: ex.scene.clone(),
        description: ex.description.clone(),
        paper_state: None,
        dimension: ex.dimension,
        seed: 1,
        particles: Particles {
            count: ex.particles.count,
            min_diameter: d_min.min(1.0),
            classes: None,
        },
        law: ex.law.clone(),
        initial: Initial {
            arrangement: Default::default(),
            packing_fraction: solid / ex.cell.lengths.iter().product::<f64>(),
            rms_velocity: 0.0,
            maxwell: Default::default(),
            snapshot: None,
            particles: Some(std::path::absolute(particles)?),
            grains: None,
            cell: Some(ex.cell.lengths.clone()),
        },
        numerics: ex.numerics.clone(),
        protocol,
        output: Output::default(),
    };
    scene.validate(Path::new(EXCHANGE))?;
    Ok(scene)
}

/// A stage as a scene step: the strain-rate cap back in the scene's inertia units, in the
/// plan's time unit ([`rate_time_unit`]: AR07 (23) I = ε̇√(m/(aP)); GRC08's I_a = ε̇ T0).
fn step(s: &ExchangeStage, cohesive: bool) -> Result<Step> {
    Ok(match s.kind {
        ExchangeKind::Compress => {
            let p = s.pressure.context("a `compress` stage needs `pressure`")?;
            Step::Compress {
                pressure: p,
                inertia_cap: s.max_strain_rate * rate_time_unit(p, cohesive),
                max_time: s.max_time,
                criteria: s.criteria,
                mu: Some(s.mu),
                kappa: Some(s.kappa),
                relax: s.relax,
            }
        }
        ExchangeKind::FixedVolume => Step::FixedVolume {
            max_time: s.max_time,
            criteria: s.criteria,
            full_time: s.full_time,
            mu: Some(s.mu),
            kappa: Some(s.kappa),
            relax: s.relax,
        },
        ExchangeKind::Aggregate => Step::Aggregate {
            max_time: s.max_time,
            mu: Some(s.mu),
            kappa: Some(s.kappa),
        },
    })
}

/// `particles.csv`, `contacts.csv` and `status.txt` of a final state, atomically.
pub fn write_state(snap: &Snapshot, out: &Path, loop_time: f64) -> Result<()> {
    let d = snap.dimension;
    let axes = &["x", "y", "z"][..d];
    let spin: Vec<String> = if d == 2 {
        vec!["w".into()]
    } else {
        axes.iter().map(|a| format!("w{a}")).collect()
    };
    let mut head = vec!["id".to_string()];
    head.extend(axes.iter().map(|a| a.to_string()));
    head.extend(["diameter", "mass"].map(String::from));
    head.extend(axes.iter().map(|a| format!("v{a}")));
    head.extend(spin);
    let p = &snap.particles;
    let mut text = head.join(",") + "\n";
    for i in 0..p.radius.len() {
        let mut row = vec![i.to_string()];
        row.extend(p.position[i].iter().map(|&x| num(x)));
        row.push(num(2.0 * p.radius[i]));
        row.push(num(p.mass[i]));
        row.extend(p.velocity[i].iter().map(|&x| num(x)));
        let w = p.angular_velocity.get(i).cloned().unwrap_or_default();
        let nw = if d == 2 { 1 } else { 3 };
        row.extend((0..nw).map(|k| num(w.get(k).copied().unwrap_or(0.0))));
        text += &(row.join(",") + "\n");
    }
    write_atomic(&out.join(OUT_PARTICLES), text.as_bytes())?;
    let mut head = vec!["i", "j", "fn", "fn_elastic"]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
    head.extend(axes.iter().map(|a| format!("ft_{a}")));
    let rolling = snap.contacts.iter().any(|c| !c.rolling.is_empty());
    if rolling {
        if d == 2 {
            head.push("mr".into());
        } else {
            head.extend(axes.iter().map(|a| format!("mr_{a}")));
        }
    }
    let mut text = head.join(",") + "\n";
    for c in &snap.contacts {
        let mut row = vec![
            c.i.to_string(),
            c.j.to_string(),
            num(c.normal),
            num(c.normal_elastic),
        ];
        row.extend((0..d).map(|a| num(c.tangential.get(a).copied().unwrap_or(0.0))));
        if rolling {
            let nr = if d == 2 { 1 } else { 3 };
            row.extend((0..nr).map(|a| num(c.rolling.get(a).copied().unwrap_or(0.0))));
        }
        text += &(row.join(",") + "\n");
    }
    write_atomic(&out.join(OUT_CONTACTS), text.as_bytes())?;
    // Written last: its presence says the other two are complete.
    let status = format!(
        "status={} cell={} steps={} time={} loop_time={} version=\"grainbench {} (exchange reference)\"\n",
        snap.status,
        snap.cell.lengths.iter().map(|&l| num(l)).collect::<Vec<_>>().join(","),
        snap.step,
        num(snap.time),
        num(loop_time),
        env!("CARGO_PKG_VERSION")
    );
    write_atomic(&out.join(OUT_STATUS), status.as_bytes())?;
    Ok(())
}
