//! `grainbench bench --memory N1,N2,…`: peak resident memory per particle of a whole
//! `grainbench run`, preparation included (the target is ≤ 1 KiB per particle,
//! docs/performance.md), on dense 3D Hertz–Mindlin packings of growing size.
//!
//! Each size is the random packing of `--scale` (≤ 1000 spheres compressed fast, tiled
//! k×k×k), written as the start snapshot of a scene that runs AR07 D's last stage for a
//! short time: stress-controlled cell (P = 1, I ≤ 1e-3), the ar07 criteria with the velocity
//! quench, a checkpoint at every check. The child is `grainbench run` itself, so the peak
//! (`wait4` ru_maxrss) holds everything a user's run holds: reading the start, building the
//! system, the checks and their interaction lists, the last good state, the checkpoints, the
//! final snapshot written to disk and the metrics report. The slope between consecutive sizes
//! removes what does not grow with N (the executable's pages, the runtime, the thread pool).

use super::scale::{random_packing, tile, tiling};
use crate::common::{install_stop_handler, STOP};
use crate::external;
use anyhow::{bail, Context, Result};
use grainbench_engine::geometry::{Dim, D3};
use grainbench_engine::run::layout::SUMMARY;
use grainbench_engine::snapshot::{self, write_atomic, Snapshot};
use serde::Serialize;
use std::path::Path;
use std::process::Command;

/// Simulated time of the run at each size (reduced units; a few thousand steps).
const RUN_TIME: f64 = 0.3;

/// One size.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    pub n: usize,
    pub steps: u64,
    pub peak_rss_bytes: u64,
    pub bytes_per_particle: f64,
    /// (peak − peak of the previous size) / (N − N of the previous size).
    pub slope_bytes_per_particle: Option<f64>,
    pub wall_seconds: f64,
}

/// The start snapshot of `n` spheres of diameter 1 at rest (reduced positions `s`, lengths `l`).
fn start_snapshot(s: &[<D3 as Dim>::V], l: <D3 as Dim>::V) -> Snapshot {
    let n = s.len();
    Snapshot {
        format: snapshot::FORMAT.into(),
        version: snapshot::VERSION,
        code: format!("grainbench {}", env!("CARGO_PKG_VERSION")),
        scene: "memory".into(),
        dimension: 3,
        time: 0.0,
        step: 0,
        status: "imported".into(),
        force_unit: "P_ref a^2".into(),
        pressure_target: Some(1.0),
        cohesive: false,
        mu: Some(0.3),
        cell: snapshot::Cell {
            lengths: (0..3).map(|a| l[a]).collect(),
            contact_stress: vec![vec![0.0; 3]; 3],
            kinetic_stress: vec![vec![0.0; 3]; 3],
        },
        particles: snapshot::Particles {
            radius: vec![0.5; n],
            mass: vec![1.0; n],
            position: s
                .iter()
                .map(|x| (0..3).map(|a| x[a] * l[a]).collect())
                .collect(),
            velocity: vec![snapshot::Vector::from_elem(0.0, 3); n],
            angular_velocity: Vec::new(),
        },
        contacts: Vec::new(),
    }
}

fn scene_text(n: usize, phi: f64) -> String {
    format!(
        "name = \"memory-hm3d\"\n\
         description = \"bench --memory: AR07 D's compression stage from a dense start (n = {n})\"\n\
         dimension = 3\nseed = 7\n[particles]\ncount = {n}\n\
         [law]\nkind = \"hertz-mindlin\"\nkappa = 39000.0\nmu = 0.3\nzeta = 0.98\n\
         [initial]\nsnapshot = \"start.snap.json\"\npacking_fraction = {phi}\n\
         [[protocol]]\nkind = \"compress\"\npressure = 1.0\ninertia_cap = 0.001\n\
         max_time = {RUN_TIME}\ncriteria = {{ preset = \"ar07\", quench = true }}\n"
    )
}

/// `grainbench bench --memory …`.
pub fn sweep(
    sizes: &[usize],
    threads: usize,
    out: Option<&Path>,
    time_limit: f64,
    quiet: bool,
) -> Result<i32> {
    if sizes.iter().any(|&n| n < 32) {
        bail!("--memory: sizes must be at least 32 particles");
    }
    let out = out.unwrap_or(Path::new("runs/bench/memory"));
    std::fs::create_dir_all(out)
        .with_context(|| format!("creating the output directory {}", out.display()))?;
    let out = std::path::absolute(out)?;
    install_stop_handler();
    let exe = std::env::current_exe().context("locating the grainbench executable")?;
    let mut points: Vec<Point> = Vec::new();
    let mut failures = Vec::new();
    for &wanted in sizes {
        if STOP.load(std::sync::atomic::Ordering::SeqCst) {
            break;
        }
        let (copies, base) = tiling(wanted);
        let (s0, l0) = random_packing(base)?;
        let (s, l) = tile(&s0, l0, copies);
        let n = s.len();
        let dir = out.join("runs").join(format!("n{n}"));
        std::fs::create_dir_all(&dir)?;
        let start = start_snapshot(&s, l);
        let phi = start.packing_fraction();
        start.write(&dir.join("start.snap.json"))?;
        drop(start);
        write_atomic(&dir.join("scene.toml"), scene_text(n, phi).as_bytes())?;
        if !quiet {
            eprintln!("memory: N = {n}, {threads} thread(s) …");
        }
        let mut cmd = Command::new(&exe);
        cmd.args(["run", "scene.toml", "--out", "run", "--force", "--quiet"])
            .args(["--threads", &threads.to_string(), "--checkpoint-every", "0"]);
        let done = external::supervise(&mut cmd, &dir, "memory", time_limit, quiet, None)?;
        let summary: Option<serde_json::Value> =
            std::fs::read_to_string(dir.join("run").join(SUMMARY))
                .ok()
                .and_then(|t| serde_json::from_str(&t).ok());
        match (done.status, summary) {
            (Some(st), Some(sum)) if st.success() => {
                let steps = sum["steps"]
                    .as_array()
                    .map_or(0, |a| a.iter().filter_map(|s| s["steps"].as_u64()).sum());
                let peak = done.max_rss_kib * 1024;
                let slope = points.last().map(|p: &Point| {
                    (peak as f64 - p.peak_rss_bytes as f64) / (n as f64 - p.n as f64)
                });
                let p = Point {
                    n,
                    steps,
                    peak_rss_bytes: peak,
                    bytes_per_particle: peak as f64 / n as f64,
                    slope_bytes_per_particle: slope,
                    wall_seconds: done.wall_seconds,
                };
                if !quiet {
                    eprintln!(
                        "  N = {n}: peak RSS {:.1} MiB, {:.0} B/particle{}",
                        peak as f64 / 1048576.0,
                        p.bytes_per_particle,
                        slope.map_or(String::new(), |s| format!(
                            ", {s:.0} B/particle above the previous size"
                        ))
                    );
                }
                points.push(p);
            }
            (status, _) => {
                let why = external::why_failed(status, &dir, time_limit);
                eprintln!("  N = {n}: {why}; logs in {}", dir.display());
                failures.push(format!("N = {n}: {why}"));
            }
        }
    }
    let md = markdown(&points, &failures, threads);
    println!("{md}");
    let doc = serde_json::json!({
        "command": std::env::args().collect::<Vec<_>>().join(" "),
        "run": format!("grainbench run (checkpoint at every check) of AR07 D's compression stage for t = {RUN_TIME} from the random packing of --scale tiled k×k×k"),
        "threads": threads,
        "points": points,
        "failures": failures,
    });
    write_atomic(
        &out.join("memory.json"),
        (serde_json::to_string_pretty(&doc)? + "\n").as_bytes(),
    )?;
    write_atomic(&out.join("memory.md"), md.as_bytes())?;
    eprintln!("wrote {}/memory.md, memory.json", out.display());
    Ok(if failures.is_empty() { 0 } else { 1 })
}

fn markdown(points: &[Point], failures: &[String], threads: usize) -> String {
    let mut s = format!(
        "## grainbench bench --memory: peak RSS of `grainbench run` on dense 3D Hertz–Mindlin packings ({threads} thread(s))\n\n"
    );
    s += "| N | steps | peak RSS MiB | bytes / particle | above the previous size, bytes / particle | wall s |\n";
    s += "| ---: | ---: | ---: | ---: | ---: | ---: |\n";
    for p in points {
        s += &format!(
            "| {} | {} | {:.1} | {:.0} | {} | {:.1} |\n",
            p.n,
            p.steps,
            p.peak_rss_bytes as f64 / 1048576.0,
            p.bytes_per_particle,
            p.slope_bytes_per_particle
                .map_or("—".into(), |x| format!("{x:.0}")),
            p.wall_seconds
        );
    }
    s += &format!("\n- each size: `grainbench run` (start snapshot read, system built, checks, last good state, a checkpoint at every check, final snapshot written, metrics report) of AR07 D's compression stage (P = 1, I ≤ 1e-3, ar07 criteria with the quench) for t = {RUN_TIME}\n");
    s += "- peak RSS: wait4 ru_maxrss of that child process; the column above the previous size removes what does not grow with N (executable, runtime)\n";
    for f in failures {
        s += &format!("- failed: {f}\n");
    }
    s
}
