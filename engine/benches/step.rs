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
//! of a pool of exactly 1 or 2 threads, the other worker kept awake between passes as in a run
//! (`parallel::KeepAwake`), and neighbour-list rebuilds count at their natural rate. The preparation is the same as in `examples/memory.rs`.

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};
use grainbench_engine::contact::slider::{Coulomb, Frictionless};
use grainbench_engine::contact::ContactLaw;
use grainbench_engine::geometry::{Dim, D2, D3};
use grainbench_engine::parallel::KeepAwake;
use grainbench_engine::system::System;
use std::time::{Duration, Instant};

#[path = "common/packings.rs"]
mod packings;
use packings::*;

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
                    // The other worker kept awake between passes, as in a run.
                    let _awake = KeepAwake::new();
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
