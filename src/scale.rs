//! `grainbench bench --scale N1,N2,…`: cost per particle-step and peak memory per particle of
//! our engine on dense 3D Hertz–Mindlin packings (κ = 39000, μ = 0.3, ζ = 0.98) of growing
//! size, each size in a child process of its own so that the high-water marks do not mix.
//!
//! The packing is a jittered FCC lattice (nearest-neighbour distance = the diameter, every
//! coordinate moved by up to 1e-3 a): about half of the 12 lattice bonds overlap, so z ≈ 6,
//! made in O(N) without any compression run. The cell is stress-controlled (P = 1) with a
//! small strain-rate cap (1e-3) so that it stays dense over the timed steps; it is not
//! equilibrated.

use crate::bench::{Args, Stat};
use crate::compare;
use anyhow::{bail, Context, Result};
use grainbench_comparisons::plots::{line_plot, Axis, LinePlot, Marks, Series};
use grainbench_engine::cell::{Cell, Control};
use grainbench_engine::contact::slider::Coulomb;
use grainbench_engine::geometry::{Dim, Linear as _, D3};
use grainbench_engine::run::{cell_mass, hertz_mindlin_law, time_step};
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
/// Largest displacement of a lattice site per coordinate, in diameters.
const JITTER: f64 = 1e-3;

/// What a child reports for one size.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Point {
    pub n: usize,
    pub threads: usize,
    pub steps: u64,
    /// FCC cells along each axis.
    pub cells: [usize; 3],
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

/// FCC cells (kx, ky, kz) with 4·kx·ky·kz closest to `n`, as cubic as the factors allow.
pub fn fcc_cells(n: usize) -> [usize; 3] {
    let m = (n as f64 / 4.0).round().max(1.0) as usize;
    let mut best = [1, 1, m];
    let mut best_score = (usize::MAX, f64::INFINITY);
    let c = (m as f64).cbrt();
    let lo = (c * 0.6).floor().max(1.0) as usize;
    let hi = (c * 1.6).ceil() as usize + 1;
    for kx in lo..=hi {
        for ky in kx..=hi {
            let kz = ((m as f64) / (kx * ky) as f64).round().max(1.0) as usize;
            if kz < ky {
                continue;
            }
            let miss = (4 * kx * ky * kz).abs_diff(n);
            let aspect = kz as f64 / kx as f64;
            if (miss, aspect) < best_score {
                best_score = (miss, aspect);
                best = [kx, ky, kz];
            }
        }
    }
    best
}

/// SplitMix64: a fixed, dependency-free stream of jitters.
struct SplitMix(u64);

impl SplitMix {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

const BASIS: [[usize; 3]; 4] = [[0, 0, 0], [1, 1, 0], [1, 0, 1], [0, 1, 1]];
/// Side of the cubic FCC cell for a nearest-neighbour distance of 1.
const SIDE: f64 = std::f64::consts::SQRT_2;

fn index(cells: [usize; 3], c: [usize; 3], b: usize) -> usize {
    ((c[0] * cells[1] + c[1]) * cells[2] + c[2]) * 4 + b
}

/// Reduced positions of the jittered lattice and the cell lengths.
fn lattice(cells: [usize; 3], seed: u64) -> (Vec<<D3 as Dim>::V>, <D3 as Dim>::V) {
    let mut l = <D3 as Dim>::V::zero();
    for a in 0..3 {
        l[a] = SIDE * cells[a] as f64;
    }
    let mut rng = SplitMix(seed);
    let n = 4 * cells.iter().product::<usize>();
    let mut s = vec![<D3 as Dim>::V::zero(); n];
    for cx in 0..cells[0] {
        for cy in 0..cells[1] {
            for cz in 0..cells[2] {
                let c = [cx, cy, cz];
                for (b, half) in BASIS.iter().enumerate() {
                    let i = index(cells, c, b);
                    for a in 0..3 {
                        let r = SIDE * (c[a] as f64 + 0.5 * half[a] as f64)
                            + JITTER * (2.0 * rng.uniform() - 1.0);
                        s[i][a] = (r / l[a]).rem_euclid(1.0);
                    }
                }
            }
        }
    }
    (s, l)
}

/// Overlapping lattice bonds per grain ×2 (z), from the 12 lattice neighbours of each grain.
fn lattice_z(cells: [usize; 3], position: impl Fn(usize) -> [f64; 3], l: [f64; 3]) -> f64 {
    let n = 4 * cells.iter().product::<usize>();
    let mut contacts = 0usize;
    for cx in 0..cells[0] {
        for cy in 0..cells[1] {
            for cz in 0..cells[2] {
                for (b, half) in BASIS.iter().enumerate() {
                    let i = index(cells, [cx, cy, cz], b);
                    let q = [2 * cx + half[0], 2 * cy + half[1], 2 * cz + half[2]];
                    let pi = position(i);
                    for (p0, p1) in [(0, 1), (0, 2), (1, 2)] {
                        for (s0, s1) in [(1, 1), (1, -1), (-1, 1), (-1, -1)] {
                            let mut qq = [q[0] as i64, q[1] as i64, q[2] as i64];
                            qq[p0] += s0;
                            qq[p1] += s1;
                            let mut c = [0; 3];
                            let mut parity = [0; 3];
                            for a in 0..3 {
                                let m = 2 * cells[a] as i64;
                                let v = qq[a].rem_euclid(m) as usize;
                                c[a] = v / 2;
                                parity[a] = v % 2;
                            }
                            let bj = BASIS.iter().position(|h| *h == parity).expect("FCC site");
                            let j = index(cells, c, bj);
                            let pj = position(j);
                            let mut d2 = 0.0;
                            for a in 0..3 {
                                let mut d = pj[a] - pi[a];
                                d -= l[a] * (d / l[a]).round();
                                d2 += d * d;
                            }
                            if d2 < 1.0 {
                                contacts += 1;
                            }
                        }
                    }
                }
            }
        }
    }
    // Each bond was seen from both ends.
    contacts as f64 / n as f64
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
    crate::set_threads(Some(threads))?;
    let t0 = Instant::now();
    let cells = fcc_cells(n_wanted);
    let n = 4 * cells.iter().product::<usize>();
    let scene = scene_for(n);
    let (s, l) = lattice(cells, 7);
    let la = [l[0], l[1], l[2]];
    let z_start = lattice_z(
        cells,
        |i| [s[i][0] * l[0], s[i][1] * l[1], s[i][2] * l[2]],
        la,
    );
    let volume = l[0] * l[1] * l[2];
    let mut cell = Cell::<D3>::new(l, cell_mass(&scene.numerics, n as f64, volume, 3));
    let mut target = <D3 as Dim>::V::zero();
    for a in 0..3 {
        target[a] = 1.0;
    }
    cell.control = Control::Stress {
        target,
        rate_cap: 1e-3,
    };
    let law = hertz_mindlin_law(&scene.law, Coulomb { mu: 0.3 });
    let mut sys = System::new(law, cell, s, &vec![1.0; n], scene.numerics.skin);
    sys.dt = time_step(&scene, &sys).0;
    let segment = (steps / SEGMENTS).max(1);
    let (prepare_seconds, segment_ns) = rayon::scope(|_| {
        sys.init_forces();
        let prep = t0.elapsed().as_secs_f64();
        let mut ns = Vec::new();
        for _ in 0..SEGMENTS {
            let t = Instant::now();
            for _ in 0..segment {
                sys.step();
            }
            ns.push(t.elapsed().as_secs_f64() * 1e9 / (segment as f64 * n as f64));
        }
        (prep, ns)
    });
    let vm_hwm_bytes = vm_hwm();
    let l = sys.cell.l;
    let z_end = lattice_z(
        cells,
        |i| {
            let p = sys.position(i);
            [p[0], p[1], p[2]]
        },
        [l[0], l[1], l[2]],
    );
    let point = Point {
        n,
        threads,
        steps: segment * SEGMENTS,
        cells,
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

/// `grainbench bench --scale …`.
pub fn sweep(a: &Args) -> Result<i32> {
    if a.scale.iter().any(|&n| n < 32) {
        bail!("--scale: sizes must be at least 32 particles");
    }
    let steps = a.steps.unwrap_or(DEFAULT_STEPS);
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs/bench/scale").into());
    std::fs::create_dir_all(&out)
        .with_context(|| format!("creating the output directory {}", out.display()))?;
    let out = std::path::absolute(&out)?;
    crate::install_stop_handler();
    let exe = std::env::current_exe().context("locating the grainbench executable")?;
    let mut points: Vec<Point> = Vec::new();
    let mut failures = Vec::new();
    for &n in &a.scale {
        for &t in &a.threads {
            if crate::STOP.load(std::sync::atomic::Ordering::SeqCst) {
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
            let done = compare::supervise(&mut cmd, &dir, "scale", a.time_limit, a.quiet, None)?;
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
                    let why = match status {
                        None => format!("killed after the time limit of {} s", a.time_limit),
                        Some(s) => format!(
                            "exited with {s}: {:?}",
                            compare::failure_line(&dir.join("stderr.log"))
                        ),
                    };
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
        "packing": "jittered FCC (±1e-3 a per coordinate), 3D Hertz–Mindlin κ = 39000, μ = 0.3, ζ = 0.98, stress-controlled cell P = 1, rate cap 1e-3",
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
        "## grainbench bench --scale: dense 3D Hertz–Mindlin (jittered FCC, κ = 39000, μ = 0.3), {steps} steps per size\n\n"
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
    fn fcc_cells_hit_round_sizes() {
        for n in [1000, 10000, 100000, 1000000] {
            let c = fcc_cells(n);
            let m = 4 * c[0] * c[1] * c[2];
            assert!((m as f64 - n as f64).abs() <= 0.02 * n as f64, "{n}: {c:?}");
            assert!(c[2] as f64 / c[0] as f64 <= 3.0, "{n}: {c:?}");
        }
    }

    #[test]
    fn jittered_lattice_has_about_six_contacts() {
        let cells = [4, 4, 5];
        let (s, l) = lattice(cells, 7);
        let z = lattice_z(
            cells,
            |i| [s[i][0] * l[0], s[i][1] * l[1], s[i][2] * l[2]],
            [l[0], l[1], l[2]],
        );
        assert!((4.5..7.5).contains(&z), "z = {z}");
    }
}
