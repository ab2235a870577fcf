//! `grainbench bench --scale N1,N2,…`: cost per particle-step and peak memory per particle of
//! our engine on dense 3D Hertz–Mindlin packings (κ = 39000, μ = 0.3, ζ = 0.98) of growing
//! size, each size in a child process of its own so that the high-water marks do not mix.
//!
//! The packing is a dense random packing of at most 1000 spheres (a gas compressed fast, as
//! the step benchmark prepares one) tiled k×k×k times: periodic copies of a periodic packing
//! are a packing, so the 1e6-sphere case costs one 1000-sphere compression and an O(N) copy. The cell is stress-controlled (P = 1) with a
//! small strain-rate cap (1e-3) so that it stays dense over the timed steps; it is not
//! equilibrated.

use crate::common::{install_stop_handler, on_threads, STOP};
use crate::external;
use anyhow::{bail, Context, Result};
use grainbench_comparisons::report::plots::{line_plot, Axis, LinePlot, Marks, Series};
use grainbench_comparisons::stats::Stat;
use grainbench_engine::cell::{Cell, Control};
use grainbench_engine::contact::slider::Coulomb;
use grainbench_engine::geometry::{Dim, VectorOps as _, D3};
use grainbench_engine::parallel::KeepAwake;
use grainbench_engine::run::{cell_mass, compress_until, hertz_mindlin_law, time_step};
use grainbench_engine::scene::Scene;
use grainbench_engine::snapshot::write_atomic;
use grainbench_engine::system::System;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// Steps timed per size unless `--steps` says otherwise.
pub const DEFAULT_STEPS: u64 = 100;
/// Timed segments per size (the reported cost is their median).
const SEGMENTS: u64 = 5;

/// What a child reports for one size.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Point {
    pub n: usize,
    pub threads: usize,
    pub steps: u64,
    /// Copies per axis of the random base packing, and its grains.
    pub copies: usize,
    pub base: usize,
    pub prepare_seconds: f64,
    /// ns per particle-step of each segment.
    pub segment_ns: Vec<f64>,
    pub ns_per_particle_step: f64,
    pub z_start: f64,
    pub z_end: f64,
    pub packing_fraction: f64,
    /// VmHWM of the child after the timed steps, bytes.
    pub vm_hwm_bytes: Option<u64>,
    /// Filled in by the parent: `wait4` ru_maxrss of the child, bytes, and per particle.
    #[serde(default)]
    pub peak_rss_bytes: u64,
    #[serde(default)]
    pub bytes_per_particle: f64,
    #[serde(default)]
    pub wall_seconds: f64,
}

/// Largest random packing that is tiled: sizes up to `BASE`·k³ are k×k×k copies of one.
const BASE: usize = 1000;

/// Copies per axis k and grains per copy for about `n` grains: k = ⌊(n/BASE)^⅓⌋ (at least 1).
pub fn tiling(n: usize) -> (usize, usize) {
    let mut k = ((n as f64 / BASE as f64).cbrt().floor() as usize).max(1);
    while k > 1 && (k * k * k) > n {
        k -= 1;
    }
    (
        k,
        ((n as f64) / (k * k * k) as f64).round().max(2.0) as usize,
    )
}

/// Gas at Φ = 0.3 compressed at P = 1 with a large strain-rate cap (0.1) until Φ ≥ 0.58
/// (`run::compress_until`, as the step benchmark prepares its packings): a dense random
/// packing, its reduced positions and cell lengths.
pub(super) fn random_packing(n: usize) -> Result<(Vec<<D3 as Dim>::V>, <D3 as Dim>::V)> {
    let text = format!(
        "name = \"scale-base\"\ndimension = 3\nseed = 7\n[particles]\ncount = {n}\n\
         [law]\nkind = \"hertz-mindlin\"\nkappa = 39000.0\nmu = 0.3\nzeta = 0.98\n\
         [initial]\npacking_fraction = 0.3\n[numerics]\ncell_mass = 0.01\n\
         [[protocol]]\nkind = \"compress\"\npressure = 1.0\ninertia_cap = 0.1\nmax_time = 5.0\n"
    );
    let scene = Scene::from_toml(&text, Path::new("scale-base.toml"))
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let law = hertz_mindlin_law(&scene.law, Coulomb { mu: 0.3 });
    let sys = compress_until::<D3, _>(&scene, law, 0.58).map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok((sys.s.clone(), sys.cell.l))
}

/// `k`×`k`×`k` periodic copies of a packing (reduced positions `s`, lengths `l`): a valid
/// packing of k³ times as many grains, made in O(N).
pub(super) fn tile(
    s: &[<D3 as Dim>::V],
    l: <D3 as Dim>::V,
    k: usize,
) -> (Vec<<D3 as Dim>::V>, <D3 as Dim>::V) {
    let kf = k as f64;
    let mut out = Vec::with_capacity(s.len() * k * k * k);
    for cx in 0..k {
        for cy in 0..k {
            for cz in 0..k {
                let c = [cx as f64, cy as f64, cz as f64];
                for x in s {
                    let mut y = *x;
                    for a in 0..3 {
                        y[a] = (x[a] + c[a]) / kf;
                    }
                    out.push(y);
                }
            }
        }
    }
    let mut lk = l;
    for a in 0..3 {
        lk[a] = l[a] * kf;
    }
    (out, lk)
}

/// Coordination number: twice the overlapping listed pairs per grain (no allocation).
fn coordination<L: grainbench_engine::contact::ContactLaw<D3>>(sys: &System<D3, L>) -> f64 {
    let l = sys.cell.l;
    let mut contacts = 0usize;
    for i in 0..sys.len() {
        for k in sys.nlist.row(i) {
            let j = sys.nlist.partner[k] as usize;
            let mut d2 = 0.0;
            for a in 0..3 {
                let mut d = sys.s[j][a] - sys.s[i][a];
                d -= d.round();
                d2 += (d * l[a]) * (d * l[a]);
            }
            let reach = sys.radius[i] + sys.radius[j];
            if d2 < reach * reach {
                contacts += 1;
            }
        }
    }
    2.0 * contacts as f64 / sys.len() as f64
}

fn scene_for(n: usize) -> Scene {
    let text = format!(
        "name = \"scale-hm3d\"\ndimension = 3\nseed = 7\n[particles]\ncount = {n}\n\
         [law]\nkind = \"hertz-mindlin\"\nkappa = 39000.0\nmu = 0.3\nzeta = 0.98\n\
         [initial]\npacking_fraction = 0.36\n\
         [numerics]\ncell_mass = 0.01\n\
         [[protocol]]\nkind = \"compress\"\npressure = 1.0\ninertia_cap = 0.001\nmax_time = 1.0\n"
    );
    Scene::from_toml(&text, Path::new("scale-hm3d.toml")).expect("scale scene")
}

fn vm_hwm() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = text.lines().find(|l| l.starts_with("VmHWM:"))?;
    Some(line.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
}

/// The child: prepares one size, times `steps` steps, prints a [`Point`] as JSON.
pub fn child(n_wanted: usize, steps: u64, threads: usize) -> Result<i32> {
    on_threads(Some(threads), || child_on_pool(n_wanted, steps, threads))
}

/// [`child`] on a thread of the sized pool.
fn child_on_pool(n_wanted: usize, steps: u64, threads: usize) -> Result<i32> {
    let t0 = Instant::now();
    let (copies, base) = tiling(n_wanted);
    let (s0, l0) = random_packing(base)?;
    let (s, l) = tile(&s0, l0, copies);
    drop(s0);
    let n = s.len();
    let scene = scene_for(n);
    let volume = l[0] * l[1] * l[2];
    let mut cell = Cell::<D3>::new(l, cell_mass(&scene.numerics, n as f64, volume, 3));
    let mut target = <D3 as Dim>::V::zero();
    for a in 0..3 {
        target[a] = 1.0;
    }
    cell.control = Control::Stress {
        target,
        rate_cap: 1e-3,
        servo: None,
    };
    let law = hertz_mindlin_law(&scene.law, Coulomb { mu: 0.3 });
    let mut sys = System::new(law, cell, s, &vec![1.0; n], scene.numerics.skin);
    sys.dt = time_step(&scene, &sys).0;
    let segment = (steps / SEGMENTS).max(1);
    // On a thread of the pool (`on_threads`), the other threads kept awake as in a run.
    let (prepare_seconds, z_start, segment_ns) = {
        let _awake = KeepAwake::new();
        sys.init_forces();
        let z_start = coordination(&sys);
        let prep = t0.elapsed().as_secs_f64();
        let mut ns = Vec::new();
        for _ in 0..SEGMENTS {
            let t = Instant::now();
            for _ in 0..segment {
                sys.step();
            }
            ns.push(t.elapsed().as_secs_f64() * 1e9 / (segment as f64 * n as f64));
        }
        (prep, z_start, ns)
    };
    let vm_hwm_bytes = vm_hwm();
    let z_end = coordination(&sys);
    let point = Point {
        n,
        threads,
        steps: segment * SEGMENTS,
        copies,
        base,
        prepare_seconds,
        ns_per_particle_step: Stat::of(&segment_ns).map_or(f64::NAN, |s| s.median),
        segment_ns,
        z_start,
        z_end,
        packing_fraction: sys.packing_fraction(),
        vm_hwm_bytes,
        peak_rss_bytes: 0,
        bytes_per_particle: 0.0,
        wall_seconds: 0.0,
    };
    println!("{}", serde_json::to_string(&point)?);
    Ok(0)
}

/// What `bench --scale` was asked for.
pub struct Sweep<'a> {
    /// Particle counts wanted.
    pub sizes: &'a [usize],
    pub threads: &'a [usize],
    /// Steps timed per size (default [`DEFAULT_STEPS`]).
    pub steps: Option<u64>,
    /// Output directory (default `runs/bench/scale`).
    pub out: Option<&'a Path>,
    /// Wall-time limit of each child, seconds.
    pub time_limit: f64,
    pub quiet: bool,
}

/// `grainbench bench --scale …`.
pub fn sweep(a: &Sweep) -> Result<i32> {
    if a.sizes.iter().any(|&n| n < 32) {
        bail!("--scale: sizes must be at least 32 particles");
    }
    let steps = a.steps.unwrap_or(DEFAULT_STEPS);
    let out = a.out.unwrap_or(Path::new("runs/bench/scale"));
    std::fs::create_dir_all(out)
        .with_context(|| format!("creating the output directory {}", out.display()))?;
    let out = std::path::absolute(out)?;
    install_stop_handler();
    let exe = std::env::current_exe().context("locating the grainbench executable")?;
    let mut points: Vec<Point> = Vec::new();
    let mut failures = Vec::new();
    for &n in a.sizes {
        for &t in a.threads {
            if STOP.load(std::sync::atomic::Ordering::SeqCst) {
                break;
            }
            let dir = out.join("runs").join(format!("n{n}-j{t}"));
            std::fs::create_dir_all(&dir)?;
            if !a.quiet {
                eprintln!("scale: N ≈ {n}, {t} thread(s), {steps} steps …");
            }
            let mut cmd = Command::new(&exe);
            cmd.args(["bench", "--child-scale", &n.to_string(), "--steps"])
                .arg(steps.to_string())
                .args(["--threads", &t.to_string()]);
            let done = external::supervise(&mut cmd, &dir, "scale", a.time_limit, a.quiet, None)?;
            let text = std::fs::read_to_string(dir.join("stdout.log")).unwrap_or_default();
            let parsed = text
                .lines()
                .rev()
                .find_map(|l| serde_json::from_str::<Point>(l).ok());
            match (done.status, parsed) {
                (Some(s), Some(mut p)) if s.success() => {
                    p.peak_rss_bytes = done.max_rss_kib * 1024;
                    p.bytes_per_particle = p.peak_rss_bytes as f64 / p.n as f64;
                    p.wall_seconds = done.wall_seconds;
                    if !a.quiet {
                        eprintln!(
                            "  N = {}: {:.1} ns/particle-step, {:.0} B/particle, z = {:.2} → {:.2}, prepared in {:.1} s",
                            p.n, p.ns_per_particle_step, p.bytes_per_particle, p.z_start, p.z_end, p.prepare_seconds
                        );
                    }
                    points.push(p);
                }
                (status, _) => {
                    let why = external::why_failed(status, &dir, a.time_limit);
                    eprintln!("  N ≈ {n}, {t} thread(s): {why}; logs in {}", dir.display());
                    failures.push(format!("N ≈ {n}, {t} thread(s): {why}"));
                }
            }
        }
    }
    let md = scale_markdown(&points, &failures, steps);
    println!("{md}");
    let doc = serde_json::json!({
        "command": std::env::args().collect::<Vec<_>>().join(" "),
        "steps": steps,
        "packing": "random packing of ≤ 1000 spheres (gas Φ = 0.3 compressed at P = 1, I ≤ 0.1, to Φ ≥ 0.58) tiled k×k×k, 3D Hertz–Mindlin κ = 39000, μ = 0.3, ζ = 0.98, stress-controlled cell P = 1, rate cap 1e-3",
        "points": points,
        "failures": failures,
    });
    write_atomic(
        &out.join("scale.json"),
        (serde_json::to_string_pretty(&doc)? + "\n").as_bytes(),
    )?;
    let mut csv = String::from(
        "n,threads,steps,ns_per_particle_step,ns_min,ns_max,peak_rss_bytes,bytes_per_particle,z_start,z_end,packing_fraction,prepare_seconds,wall_seconds\n",
    );
    for p in &points {
        let s = Stat::of(&p.segment_ns);
        csv += &format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            p.n,
            p.threads,
            p.steps,
            p.ns_per_particle_step,
            s.map_or(f64::NAN, |s| s.min),
            s.map_or(f64::NAN, |s| s.max),
            p.peak_rss_bytes,
            p.bytes_per_particle,
            p.z_start,
            p.z_end,
            p.packing_fraction,
            p.prepare_seconds,
            p.wall_seconds
        );
    }
    write_atomic(&out.join("scale.csv"), csv.as_bytes())?;
    write_atomic(&out.join("scale.md"), md.as_bytes())?;
    let mut threads: Vec<usize> = points.iter().map(|p| p.threads).collect();
    threads.sort();
    threads.dedup();
    let curves: Vec<(String, Vec<(f64, f64)>)> = threads
        .iter()
        .map(|&t| {
            (
                format!("{t} thread(s)"),
                points
                    .iter()
                    .filter(|p| p.threads == t)
                    .map(|p| (p.n as f64, p.ns_per_particle_step))
                    .collect(),
            )
        })
        .collect();
    if !points.is_empty() {
        let series: Vec<Series> = curves.iter().map(|(l, p)| Series::new(l, p)).collect();
        let mut plot = LinePlot::new(
            "grainbench: time per particle-step vs N (dense 3D Hertz–Mindlin)",
            "N",
            "ns per particle-step",
            &series,
        );
        plot.x_axis = Axis::Log;
        plot.marks = Marks::LinesAndPoints;
        let ys: Vec<f64> = points.iter().map(|p| p.ns_per_particle_step).collect();
        let ymax = ys.iter().cloned().fold(0.0, f64::max);
        plot.y_range = Some((0.0, 1.2 * ymax.max(1e-9)));
        line_plot(&out.join("scale"), &plot).context("drawing scale.svg/png")?;
    }
    eprintln!(
        "wrote {}/scale.md, scale.csv, scale.json{}",
        out.display(),
        if points.is_empty() {
            ""
        } else {
            ", scale.svg/png"
        }
    );
    Ok(if failures.is_empty() { 0 } else { 1 })
}

fn scale_markdown(points: &[Point], failures: &[String], steps: u64) -> String {
    let mut s = format!(
        "## grainbench bench --scale: dense 3D Hertz–Mindlin (random packing tiled k×k×k, κ = 39000, μ = 0.3), {steps} steps per size\n\n"
    );
    s += "| N | threads | ns / particle-step (median [min–max] of 5 segments) | peak RSS MiB | bytes / particle | z start → end | Φ | prepare s | wall s |\n";
    s += "| ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: |\n";
    for p in points {
        let st = Stat::of(&p.segment_ns);
        s += &format!(
            "| {} | {} | {:.1} [{:.1}–{:.1}] | {:.1} | {:.0} | {:.2} → {:.2} | {:.4} | {:.2} | {:.2} |\n",
            p.n,
            p.threads,
            p.ns_per_particle_step,
            st.map_or(f64::NAN, |s| s.min),
            st.map_or(f64::NAN, |s| s.max),
            p.peak_rss_bytes as f64 / 1048576.0,
            p.bytes_per_particle,
            p.z_start,
            p.z_end,
            p.packing_fraction,
            p.prepare_seconds,
            p.wall_seconds
        );
    }
    s += "\n- peak RSS: wait4 ru_maxrss of the child process that prepared and ran the size (preparation included)\n";
    s += "- the packing is dense but not equilibrated; each size runs in its own process\n";
    for f in failures {
        s += &format!("- failed: {f}\n");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiling_hits_round_sizes() {
        assert_eq!(tiling(1000), (1, 1000));
        assert_eq!(tiling(8000), (2, 1000));
        assert_eq!(tiling(125_000), (5, 1000));
        assert_eq!(tiling(1_000_000), (10, 1000));
        assert_eq!(tiling(500), (1, 500));
        assert_eq!(tiling(10_000), (2, 1250));
    }

    #[test]
    fn tiled_copies_are_periodic_images() {
        let s = vec![[0.1, 0.2, 0.3].into(), [0.9, 0.5, 0.05].into()];
        let l: <D3 as Dim>::V = [2.0, 3.0, 4.0].into();
        let (t, lk) = tile(&s, l, 2);
        assert_eq!(t.len(), 16);
        assert_eq!([lk[0], lk[1], lk[2]], [4.0, 6.0, 8.0]);
        // Every copy is the base shifted by whole base cells.
        for (c, chunk) in t.chunks(2).enumerate() {
            for (x, y) in s.iter().zip(chunk) {
                for a in 0..3 {
                    let shift = (y[a] * 2.0 - x[a]) * l[a];
                    assert!((shift - shift.round()).abs() < 1e-12, "copy {c}");
                    assert!((0.0..1.0).contains(&y[a]));
                }
            }
        }
    }
}
