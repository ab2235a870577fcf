//! Cost of each part of a time step, one thread, on the dense 3D Hertz–Mindlin packing of
//! `benches/step.rs` (N = 4000, μ = 0.3), so that a regression shows in the part it hits.
//!
//! ```text
//! cargo bench -p grainbench-engine --bench kernels
//! ```
//!
//! - `forces`: the force pass over the listed pairs (`System::compute_forces`), by the SIMD
//!   kernel where the CPU has one (`contact::hertz_mindlin_avx`);
//! - `forces_scalar`: the same pass on the scalar reference path (`System::simd = false`);
//! - `gather_kick`: the fixed-order force sums and the closing half kick (`System::accumulate`);
//! - `kick_drift`: the opening half kick and drift of the grains (`System::kick_drift`);
//! - `rebuild`: a neighbour-list build, history carried over (`System::rebuild`);
//! - `barostat`: the stress (AR07 (8)) and the cell kick and drift (AR07 (7)).
//!
//! Throughput is in particles: 1e9 / (elements/s) is ns per particle.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use grainbench_engine::contact::slider::Coulomb;
use grainbench_engine::geometry::D3;
use grainbench_engine::system::System;
use std::hint::black_box;
use std::time::{Duration, Instant};

#[path = "common/packings.rs"]
#[allow(dead_code)]
mod packings;
use packings::*;

fn kernels(c: &mut Criterion) {
    let scene = scene_3d(4000);
    let sys = prepare::<D3, _>(&scene, law_3d(&scene, Coulomb { mu: 0.3 }), 0.58);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    let mut group = c.benchmark_group("kernels_hm3d_mu0.3");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(sys.len() as u64));
    let dt = sys.dt;
    // Each sample times `iters` calls inside the one-thread pool (set-up not timed).
    let timed = |iters: u64, s: &mut System<D3, _>, f: &(dyn Fn(&mut System<D3, _>) + Sync)| {
        pool.install(|| {
            let start = Instant::now();
            for _ in 0..iters {
                f(s);
            }
            start.elapsed()
        })
    };
    group.bench_function("forces", |b| {
        b.iter_custom(|iters| {
            timed(iters, &mut sys.clone(), &|s| {
                s.compute_forces(black_box(dt))
            })
        })
    });
    group.bench_function("forces_scalar", |b| {
        b.iter_custom(|iters| {
            let mut s = sys.clone();
            s.simd = false;
            timed(iters, &mut s, &|s| s.compute_forces(black_box(dt)))
        })
    });
    group.bench_function("gather_kick", |b| {
        b.iter_custom(|iters| timed(iters, &mut sys.clone(), &|s| s.accumulate(black_box(0.0))))
    });
    // Kicks and drifts move the grains; a few hundred do not change the cost.
    group.bench_function("kick_drift", |b| {
        b.iter_custom(|iters| timed(iters, &mut sys.clone(), &|s| s.kick_drift()))
    });
    group.bench_function("rebuild", |b| {
        b.iter_custom(|iters| timed(iters, &mut sys.clone(), &|s| s.rebuild()))
    });
    group.bench_function("barostat", |b| {
        b.iter_custom(|iters| {
            timed(iters, &mut sys.clone(), &|s| {
                let (stress, contact) = (s.stress(), s.contact_stress());
                s.cell.kick(&stress, &contact, dt);
                s.cell.drift(dt);
            })
        })
    });
    group.finish();
}

criterion_group!(benches, kernels);
criterion_main!(benches);
