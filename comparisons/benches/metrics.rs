//! Cost of the packing metrics on a 3D configuration of N = 4000 grains.
//!
//! ```text
//! cargo bench -p grainbench-comparisons --bench metrics
//! ```
//!
//! - `rattlers`: iterated rattler removal (AR07 §III.B) on the pairs closer than 0.02 a;
//! - `pair_correlation`: g(r) up to r = 3 a, bins of 0.02 a (AR07 §III.D);
//! - `gap_coordination`: z(h) on the default gap grid up to h = 0.1 a (AR07 §III.D).
//! - `density_2d/*`: GRC07 §V on 1400 disks at Φ = 0.36 (a 42 a cell), mesh a/50: the
//!   indicator field, I(k) by 2D FFT, the fit of GRC07 (28) and the holes, and all of it.
//! - `moduli/*`: the elastic moduli (GRC08 (6)) of the 3D configuration's near pairs taken as
//!   frictional Hertz contacts (24 003 degrees of freedom: assembly and sparse Cholesky), and
//!   the mechanism count (GRC07 App. A, dense eigenvalues) of 400 disks with friction.
//!
//! The configuration is the engine's random gas at Φ = 0.36 rescaled to Φ ≈ 0.6 (grains
//! overlap; the metrics do not care), so the bench does not depend on a DEM run.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use grainbench_comparisons::metrics::density::{density_correlations, DEFAULT_SPACING};
use grainbench_comparisons::metrics::density_field::{rasterize, scattering};
use grainbench_comparisons::metrics::holes::holes;
use grainbench_comparisons::metrics::moduli::elastic_moduli;
use grainbench_comparisons::metrics::stiffness::{
    rigidity, ContactStiffness, Network, NormalStiffness,
};
use grainbench_comparisons::metrics::structure::default_gap_grid;
use grainbench_comparisons::{find_rattlers, gap_coordination, pair_correlation, Rule};
use grainbench_engine::geometry::{D2, D3};
use grainbench_engine::init::random_gas;
use grainbench_engine::snapshot::{Cell, Contact, Particles, Snapshot, Vector, FORMAT, VERSION};
use std::hint::black_box;
use std::time::Duration;

fn metrics(c: &mut Criterion) {
    let n = 4000;
    let gas = random_gas::<D3>(n, 1.0, None, 0.36, 7).expect("random gas");
    let shrink = (0.36f64 / 0.6).powf(1.0 / 3.0);
    let lengths: Vec<f64> = (0..3).map(|a| gas.l[a] * shrink).collect();
    let position: Vec<Vec<f64>> = gas
        .s
        .iter()
        .map(|s| (0..3).map(|a| s[a] * lengths[a]).collect())
        .collect();
    let radius: Vec<f64> = gas.diameter.iter().map(|d| 0.5 * d).collect();
    // Near pairs by brute force (setup, not timed).
    let mut pairs = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            let mut d2 = 0.0;
            for a in 0..3 {
                let mut x = position[j][a] - position[i][a];
                x -= lengths[a] * (x / lengths[a]).round();
                d2 += x * x;
            }
            let cut = radius[i] + radius[j] + 0.02;
            if d2 < cut * cut {
                pairs.push((i, j));
            }
        }
    }
    let grid = default_gap_grid(0.1);
    let mut group = c.benchmark_group("metrics_3d");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(n as u64));
    group.bench_function("rattlers", |b| {
        b.iter(|| find_rattlers(n, black_box(&pairs), Rule::Frictional))
    });
    group.bench_function("pair_correlation", |b| {
        b.iter(|| pair_correlation(&lengths, black_box(&position), 1.0, 0.02, 3.0))
    });
    group.bench_function("gap_coordination", |b| {
        b.iter(|| gap_coordination(&lengths, black_box(&position), &radius, None, 1.0, &grid))
    });
    group.finish();
}

fn density(c: &mut Criterion) {
    let n = 1400;
    let gas = random_gas::<D2>(n, 0.5, None, 0.36, 7).expect("random gas");
    let lengths: Vec<f64> = (0..2).map(|a| gas.l[a]).collect();
    let position: Vec<Vec<f64>> = gas
        .s
        .iter()
        .map(|s| (0..2).map(|a| s[a] * lengths[a]).collect())
        .collect();
    let radius: Vec<f64> = gas.diameter.iter().map(|d| 0.5 * d).collect();
    let mesh = rasterize(&lengths, &position, &radius, DEFAULT_SPACING).expect("mesh");
    let mut group = c.benchmark_group("density_2d");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Elements((mesh.nx * mesh.ny) as u64));
    group.bench_function("rasterize", |b| {
        b.iter(|| rasterize(&lengths, black_box(&position), &radius, DEFAULT_SPACING))
    });
    group.bench_function("scattering", |b| {
        b.iter(|| scattering(black_box(&mesh), 4.0 * std::f64::consts::PI))
    });
    group.bench_function("holes", |b| b.iter(|| holes(black_box(&mesh))));
    group.bench_function("all", |b| {
        b.iter(|| {
            density_correlations(
                &lengths,
                black_box(&position),
                &radius,
                1.0,
                0.36,
                DEFAULT_SPACING,
            )
        })
    });
    group.finish();
}

criterion_group!(benches, metrics, density, moduli);
criterion_main!(benches);

/// A snapshot of `d`-dimensional grains whose pairs closer than `cut` (surface gap, negative
/// for overlaps) are listed as contacts carrying no force.
fn packed(d: usize, n: usize, phi: f64, cut: f64) -> Snapshot {
    let gas = if d == 3 {
        let g = random_gas::<D3>(n, 1.0, None, 0.36, 7).expect("random gas");
        (
            g.l.as_slice().to_vec(),
            g.s.iter()
                .map(|s| s.as_slice().to_vec())
                .collect::<Vec<_>>(),
            g.diameter,
        )
    } else {
        let g = random_gas::<D2>(n, 0.5, None, 0.36, 7).expect("random gas");
        (
            g.l.as_slice().to_vec(),
            g.s.iter()
                .map(|s| s.as_slice().to_vec())
                .collect::<Vec<_>>(),
            g.diameter,
        )
    };
    let shrink = (0.36f64 / phi).powf(1.0 / d as f64);
    let lengths: Vec<f64> = gas.0.iter().map(|l| l * shrink).collect();
    let position: Vec<Vec<f64>> = gas
        .1
        .iter()
        .map(|s| (0..d).map(|a| s[a] * lengths[a]).collect())
        .collect();
    let radius: Vec<f64> = gas.2.iter().map(|x| 0.5 * x).collect();
    let mut contacts = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            let branch: Vec<f64> = (0..d)
                .map(|a| {
                    let x = position[j][a] - position[i][a];
                    x - lengths[a] * (x / lengths[a]).round()
                })
                .collect();
            let gap = branch.iter().map(|x| x * x).sum::<f64>().sqrt() - radius[i] - radius[j];
            if gap < cut {
                contacts.push(Contact {
                    i,
                    j,
                    branch: Vector::from_slice(&branch),
                    normal: 0.0,
                    normal_elastic: 0.0,
                    tangential: Vector::from_elem(0.0, d),
                    rolling: Vector::new(),
                    gap: gap.min(-1e-3),
                });
            }
        }
    }
    Snapshot {
        format: FORMAT.into(),
        version: VERSION,
        code: "bench".into(),
        scene: "bench".into(),
        dimension: d,
        time: 0.0,
        step: 0,
        status: "equilibrium".into(),
        force_unit: "P_ref a^(d-1)".into(),
        pressure_target: Some(1.0),
        cohesive: false,
        mu: Some(0.3),
        cell: Cell {
            lengths,
            contact_stress: vec![vec![0.0; d]; d],
            kinetic_stress: vec![vec![0.0; d]; d],
        },
        particles: Particles {
            mass: vec![1.0; n],
            velocity: vec![Vector::from_elem(0.0, d); n],
            position: position.iter().map(|p| Vector::from_slice(p)).collect(),
            radius,
            angular_velocity: Vec::new(),
        },
        contacts,
    }
}

fn moduli(c: &mut Criterion) {
    let law = ContactStiffness {
        normal: NormalStiffness::Hertz { e_tilde: 1e6 },
        tangential_ratio: Some(0.82),
        rolling: None,
        attraction: None,
    };
    let snap3 = packed(3, 4000, 0.6, 0.02);
    let all3: Vec<&Contact> = snap3.contacts.iter().collect();
    let snap2 = packed(2, 400, 0.8, 0.02);
    let all2: Vec<&Contact> = snap2.contacts.iter().collect();
    let net2 = Network::build(&snap2, &all2, &law, false).expect("network");
    let mut group = c.benchmark_group("moduli");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5));
    group.bench_function("solve_3d_n4000", |b| {
        b.iter(|| elastic_moduli(black_box(&snap3), &all3, &law, true))
    });
    group.bench_function("rigidity_2d_n400", |b| {
        b.iter(|| rigidity(black_box(&net2)))
    });
    group.finish();
}
