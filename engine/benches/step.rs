//! Cost of one time step (`System::step`) on dense packings, for 1 and 2 threads.
//!
//! ```text
//! cargo bench -p grainbench-engine --bench step
//! ```
//!
//! - `hm3d_mu0.3`: 3D Hertz–Mindlin, N = 4000, μ = 0.3, κ = 39000, ζ = 0.98;
//! - `hm3d_mu0`: the same configuration with μ = 0 (frictionless kernel, no tangential state);
//! - `adh2d_rr`: 2D adhesive linear disks with rolling resistance, N = 1400, diameters in
//!   [0.5, 1], κ = 1e5, μ = 0.5, ζ = 0.8, D0 = 1e-3, K_r = 1e-4, μ_r = 0.005.
//!
//! The packings are compressed from a gas (Φ_I = 0.36 in 3D, 0.5 in 2D) at P = 1 (P* = 1 in
//! 2D) with a large inertia cap until they are close to jamming; they are dense but not
//! equilibrated, and the cell stays stress-controlled while the steps are timed. Throughput is in particles, so criterion's
//! elements/s give ns per particle-step = 1e9 / (elements/s).
//!
//! Each sample starts from a fresh clone of the prepared system (clone not timed) and times
//! that many consecutive steps inside `pool.install`, so the parallel loops fork from a worker
//! of a pool of exactly 1 or 2 threads, and neighbour-list rebuilds count at their natural
//! rate. The preparation is the same as in `examples/memory.rs`.

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};
use grainbench_engine::contact::hertz_mindlin::HertzMindlin;
use grainbench_engine::contact::linear::{Adhesion, Linear};
use grainbench_engine::contact::slider::{Coulomb, Frictionless, RollingSpring};
use grainbench_engine::contact::ContactLaw;
use grainbench_engine::geometry::{Dim, D2, D3};
use grainbench_engine::run::{build_system, run_protocol, Progress, RunOptions};
use grainbench_engine::scene::{Law, Scene};
use grainbench_engine::system::System;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// 3D Hertz–Mindlin scene: gas at Φ = 0.36 compressed at P = 1, inertia cap 0.1.
fn scene_3d(n: usize) -> Scene {
    let text = format!(
        r#"
name = "bench-hm3d"
dimension = 3
seed = 7
[particles]
count = {n}
[law]
kind = "hertz-mindlin"
kappa = 39000.0
mu = 0.3
zeta = 0.98
[initial]
packing_fraction = 0.36
[numerics]
cell_mass = 0.01
[[protocol]]
kind = "compress"
pressure = 1.0
inertia_cap = 0.1
max_time = 5.0
"#
    );
    Scene::from_toml(&text, Path::new("bench-hm3d.toml")).expect("3D bench scene")
}

/// 2D adhesive disks with rolling resistance (GRC07 T.I parameters), compressed at P* = 1,
/// inertia cap 0.05.
fn scene_2d(n: usize) -> Scene {
    let text = format!(
        r#"
name = "bench-adh2d"
dimension = 2
seed = 7
[particles]
count = {n}
min_diameter = 0.5
[law]
kind = "linear"
kappa = 1e5
mu = 0.5
zeta = 0.8
cohesion = {{ d0 = 1e-3 }}
rolling = {{ kr = 1e-4, mu_r = 0.005 }}
[initial]
packing_fraction = 0.5
[numerics]
cell_mass = 0.01
[[protocol]]
kind = "compress"
pressure = 1.0
inertia_cap = 0.05
max_time = 6.0
criteria = {{ preset = "grc07" }}
"#
    );
    Scene::from_toml(&text, Path::new("bench-adh2d.toml")).expect("2D bench scene")
}

/// The Hertz–Mindlin law of a scene, with the friction kind `f` (as `run::dispatch_law`).
fn law_3d<F>(scene: &Scene, f: F) -> HertzMindlin<F> {
    let Law::HertzMindlin {
        kappa,
        zeta,
        poisson,
        ..
    } = scene.law
    else {
        unreachable!()
    };
    // κ = (Ẽ/P_ref)^(2/3).
    HertzMindlin::new(kappa.powf(1.5), poisson, zeta, f)
}

fn law_2d(scene: &Scene) -> Linear<Adhesion, Coulomb, RollingSpring> {
    let Law::Linear {
        kappa,
        mu,
        zeta,
        kt_over_kn,
        cohesion,
        rolling,
    } = scene.law
    else {
        unreachable!()
    };
    let (c, r) = (cohesion.unwrap(), rolling.unwrap());
    Linear {
        kn: kappa,
        kt: kappa * kt_over_kn,
        zeta,
        cohesion: Adhesion { f0: 1.0, d0: c.d0 },
        friction: Coulomb { mu: mu.value() },
        rolling: RollingSpring {
            kr: r.kr * kappa,
            mu_r: r.mu_r,
        },
    }
}

/// Overlapping pairs.
fn contacts<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>) -> usize {
    sys.interactions().iter().filter(|c| c.gap < 0.0).count()
}

fn report<D: Dim, L: ContactLaw<D>>(what: &str, sys: &System<D, L>) {
    let z = contacts(sys);
    eprintln!(
        "{what}: N = {}, Φ = {:.4}, contacts = {z} (z = {:.2}), listed pairs = {}, dt = {:.3e}",
        sys.len(),
        sys.packing_fraction(),
        2.0 * z as f64 / sys.len() as f64,
        sys.nlist.pairs(),
        sys.dt
    );
}

/// Compresses the gas of `scene` until Φ ≥ `phi_stop` (or the step's max_time). The cell
/// stays stress-controlled: at a fixed volume the unequilibrated packing, still below its
/// jamming density, would lose most of its contacts within a few hundred steps.
fn prepare<D: Dim, L: ContactLaw<D>>(scene: &Scene, law: L, phi_stop: f64) -> System<D, L> {
    let start = Instant::now();
    let mut sys = build_system::<D, L>(scene, law).expect("build_system");
    let stop = AtomicBool::new(false);
    let mut progress = |p: &Progress| {
        if p.checks.packing_fraction >= phi_stop {
            stop.store(true, Ordering::Relaxed);
        }
    };
    let mut opts = RunOptions {
        progress: Some(&mut progress),
        stop: Some(&stop),
    };
    // On a pool worker, as `run_scene` does.
    rayon::scope(|_| run_protocol(scene, &mut sys, &mut opts)).expect("preparation run");
    report(
        &format!(
            "prepared {} in {} steps, {:.1} s",
            scene.name,
            sys.step,
            start.elapsed().as_secs_f64()
        ),
        &sys,
    );
    sys
}

/// The same grains, velocities and cell (lengths, rates, stress control) with another law
/// (history reset), forces initialized.
fn with_law<D: Dim, L: ContactLaw<D>, M: ContactLaw<D>>(
    sys: &System<D, L>,
    law: M,
) -> System<D, M> {
    let diameter: Vec<f64> = sys.radius.iter().map(|r| 2.0 * r).collect();
    let cell = sys.cell.clone();
    let mut other = System::new(law, cell, sys.s.clone(), &diameter, sys.nlist.skin);
    other.u = sys.u.clone();
    other.dt = sys.dt;
    other.init_forces();
    other
}

/// One group: one step of `sys`, for 1 and 2 threads.
fn bench_step<D: Dim, L: ContactLaw<D>>(c: &mut Criterion, name: &str, sys: &System<D, L>) {
    let mut group = c.benchmark_group(name);
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .sampling_mode(SamplingMode::Flat)
        .throughput(Throughput::Elements(sys.len() as u64));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        group.bench_function(format!("threads/{threads}"), |b| {
            b.iter_custom(|iters| {
                let mut s = sys.clone();
                pool.install(|| {
                    let start = Instant::now();
                    for _ in 0..iters {
                        s.step();
                    }
                    start.elapsed()
                })
            })
        });
    }
    group.finish();
}

fn steps_then_report<D: Dim, L: ContactLaw<D>>(what: &str, sys: &System<D, L>, steps: usize) {
    let mut s = sys.clone();
    let builds = s.nlist.builds;
    let start = Instant::now();
    rayon::scope(|_| {
        for _ in 0..steps {
            s.step();
        }
    });
    let wall = start.elapsed().as_secs_f64();
    report(
        &format!(
            "{what} after {steps} more steps ({} list rebuilds, {:.0} µs/step on the global pool)",
            s.nlist.builds - builds,
            1e6 * wall / steps as f64
        ),
        &s,
    );
}

fn hertz_mindlin(c: &mut Criterion) {
    let scene = scene_3d(4000);
    let mu = prepare::<D3, _>(&scene, law_3d(&scene, Coulomb { mu: 0.3 }), 0.58);
    let mu0 = with_law::<D3, _, _>(&mu, law_3d(&scene, Frictionless));
    // How much the contact network changes over a typical sample.
    steps_then_report("hm3d_mu0.3", &mu, 500);
    steps_then_report("hm3d_mu0", &mu0, 500);
    bench_step(c, "hm3d_mu0.3", &mu);
    bench_step(c, "hm3d_mu0", &mu0);
}

fn adhesive_2d(c: &mut Criterion) {
    let scene = scene_2d(1400);
    let sys = prepare::<D2, _>(&scene, law_2d(&scene), 0.76);
    steps_then_report("adh2d_rr", &sys, 500);
    bench_step(c, "adh2d_rr", &sys);
}

criterion_group!(benches, hertz_mindlin, adhesive_2d);
criterion_main!(benches);
