//! A/B timing of `System::step` by CPU time, for machines too busy for wall-clock benches.
//!
//! ```text
//! cargo run --release -p grainbench-engine --example step_timing -- prepare DIR
//! cargo run --release -p grainbench-engine --example step_timing -- time DIR [STEPS] [THREADS]
//! ```
//!
//! `prepare` compresses the packings of `benches/step.rs` (3D Hertz–Mindlin N = 4000 μ = 0.3,
//! 2D adhesive N = 1400) and saves their positions, velocities and cells in `DIR`; `time`
//! loads them, rebuilds the systems (history reset), runs 50 warm-up steps and then `STEPS`
//! steps (default 1000) in a pool of `THREADS` threads (default 1), and prints the CPU time
//! (all threads, from /proc/self/task/*/schedstat, ns resolution) and the wall time per
//! particle-step, for 3D μ = 0.3, 3D μ = 0 and 2D. Run two builds alternately on the same
//! `DIR` to compare them. `STEP_TIMING_ORDER=shuffle` (or `morton`) relabels the grains at
//! random (or along the Morton curve) after loading.

use grainbench_engine::cell::Cell;
use grainbench_engine::contact::slider::{Coulomb, Frictionless};
use grainbench_engine::contact::ContactLaw;
use grainbench_engine::geometry::{Dim, D2, D3};
use grainbench_engine::neighbor::morton_order;
use grainbench_engine::system::System;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use std::path::Path;
use std::time::Instant;

#[path = "../benches/common/packings.rs"]
#[allow(dead_code)]
mod packings;
use packings::*;

#[derive(serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
struct Saved<D: Dim> {
    cell: Cell<D>,
    s: Vec<D::V>,
    u: Vec<D::V>,
    diameter: Vec<f64>,
    dt: f64,
    skin: f64,
}

fn save<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>, path: &Path) {
    let saved = Saved::<D> {
        cell: sys.cell.clone(),
        s: sys.s.clone(),
        u: sys.u.clone(),
        diameter: sys.radius.iter().map(|r| 2.0 * r).collect(),
        dt: sys.dt,
        skin: sys.nlist.skin,
    };
    std::fs::write(path, bincode::serialize(&saved).expect("serialize")).expect("write");
}

fn load<D: Dim, L: ContactLaw<D>>(path: &Path, law: L) -> System<D, L> {
    let bytes = std::fs::read(path).expect("read (run `prepare` first)");
    let mut saved: Saved<D> = bincode::deserialize(&bytes).expect("deserialize");
    match std::env::var("STEP_TIMING_ORDER").as_deref() {
        // Random labels (what a gas placed without the Morton labelling has).
        Ok("shuffle") => {
            let n = saved.s.len();
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
            let mut order: Vec<usize> = (0..n).collect();
            order.shuffle(&mut rng);
            saved.s = order.iter().map(|&k| saved.s[k]).collect();
            saved.u = order.iter().map(|&k| saved.u[k]).collect();
            saved.diameter = order.iter().map(|&k| saved.diameter[k]).collect();
        }
        Ok("morton") => {
            let order = morton_order::<D>(&saved.s);
            saved.s = order.iter().map(|&k| saved.s[k as usize]).collect();
            saved.u = order.iter().map(|&k| saved.u[k as usize]).collect();
            saved.diameter = order.iter().map(|&k| saved.diameter[k as usize]).collect();
        }
        _ => {}
    }
    let mut sys = System::new(law, saved.cell, saved.s, &saved.diameter, saved.skin);
    sys.u = saved.u;
    sys.dt = saved.dt;
    sys.init_forces();
    sys
}

/// CPU time of all threads of this process so far, in seconds.
fn cpu_seconds() -> f64 {
    let mut ns = 0u64;
    for task in std::fs::read_dir("/proc/self/task").expect("/proc/self/task") {
        let path = task.expect("task").path().join("schedstat");
        if let Ok(text) = std::fs::read_to_string(path) {
            ns += text
                .split_whitespace()
                .next()
                .and_then(|x| x.parse::<u64>().ok())
                .unwrap_or(0);
        }
    }
    ns as f64 * 1e-9
}

fn time<D: Dim, L: ContactLaw<D>>(
    label: &str,
    mut sys: System<D, L>,
    steps: usize,
    threads: usize,
) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        for _ in 0..50 {
            sys.step();
        }
    });
    let builds = sys.nlist.builds;
    let (cpu0, wall0) = (cpu_seconds(), Instant::now());
    pool.install(|| {
        for _ in 0..steps {
            sys.step();
        }
    });
    let cpu = cpu_seconds() - cpu0;
    let wall = wall0.elapsed().as_secs_f64();
    let per = 1e9 / (steps * sys.len()) as f64;
    println!(
        "{label:<12} threads {threads}: cpu {:>7.1} ns/particle-step, wall {:>7.1} ns/particle-step ({} rebuilds)",
        cpu * per,
        wall * per,
        sys.nlist.builds - builds
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dir = Path::new(
        args.get(2)
            .map(String::as_str)
            .unwrap_or("/tmp/step_timing"),
    );
    let s3 = scene_3d(4000);
    let s2 = scene_2d(1400);
    match args.get(1).map(String::as_str) {
        Some("prepare") => {
            std::fs::create_dir_all(dir).expect("mkdir");
            let sys = prepare::<D3, _>(&s3, law_3d(&s3, Coulomb { mu: 0.3 }), 0.58);
            save(&sys, &dir.join("hm3d.bin"));
            let sys = prepare::<D2, _>(&s2, law_2d(&s2), 0.76);
            save(&sys, &dir.join("adh2d.bin"));
        }
        Some("time") => {
            let steps = args.get(3).and_then(|x| x.parse().ok()).unwrap_or(1000);
            let threads = args.get(4).and_then(|x| x.parse().ok()).unwrap_or(1);
            let p3 = dir.join("hm3d.bin");
            let p2 = dir.join("adh2d.bin");
            let mu = load::<D3, _>(&p3, law_3d(&s3, Coulomb { mu: 0.3 }));
            time("hm3d_mu0.3", mu, steps, threads);
            let mu0 = load::<D3, _>(&p3, law_3d(&s3, Frictionless));
            time("hm3d_mu0", mu0, steps, threads);
            let adh = load::<D2, _>(&p2, law_2d(&s2));
            time("adh2d_rr", adh, steps, threads);
        }
        _ => eprintln!("usage: step_timing prepare|time DIR [STEPS] [THREADS]"),
    }
}
