//! Tests of [`analyze`] on hand-built packings and on the snapshot example of
//! `docs/snapshot-format.md`.

use super::fixtures::{bond, lattice, snapshot, Bond, Lcg};
use super::math::{dot, norm};
use super::*;
use grainbench_engine::snapshot::Vector;
use std::f64::consts::PI;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1.0)
}

macro_rules! assert_close {
    ($a:expr, $b:expr, $tol:expr) => {{
        let (a, b): (f64, f64) = ($a, $b);
        assert!(close(a, b, $tol), "{} = {a}, expected {b}", stringify!($a));
    }};
}

#[test]
fn rule_follows_the_snapshot() {
    let (l, r, p, b) = lattice(3, 3, 1.0, 0.5, 1.0);
    let mut s = snapshot(l, r, p, &b, false, Some(0.0));
    assert_eq!(Rule::for_snapshot(&s), Rule::Frictionless { dim: 3 });
    s.mu = Some(0.3);
    assert_eq!(Rule::for_snapshot(&s), Rule::Frictional);
    s.mu = None;
    assert_eq!(Rule::for_snapshot(&s), Rule::Frictional);
    s.cohesive = true;
    s.mu = Some(0.0);
    assert_eq!(Rule::for_snapshot(&s), Rule::Cohesive);
}

/// Compressed square lattice: z = 4, no rattler, Φ = π/4 (d/s)².
#[test]
fn square_lattice() {
    let s = 0.99;
    let (l, r, p, b) = lattice(2, 4, s, 0.5, 1.0);
    let snap = snapshot(l, r, p, &b, false, Some(0.5));
    let a = analyze(&snap, &Options::default());
    assert_eq!(a.rule, Rule::Frictional);
    assert_eq!(
        (a.n, a.interactions, a.force_carrying, a.contacts),
        (16, 32, 32, 32)
    );
    assert_close!(a.z, 4.0, 1e-15);
    assert_eq!((a.rattlers, a.rattler_sweeps), (0, 0));
    assert_eq!(a.z_backbone, Some(4.0));
    assert_close!(a.packing_fraction, PI / 4.0 / (s * s), 1e-14);
    assert_eq!(a.x_k.len(), 13);
    assert_eq!(a.x_k[4], 1.0);
    assert_eq!(a.forces.mean_normal, Some(1.0));
    assert_eq!(a.forces.z2, Some(1.0));
    assert_eq!(a.forces.x1, Some(0.0));
    assert_eq!((a.forces.m1, a.forces.m2), (None, None), "no N ≠ ⟨N⟩");
    // P = Σ N|r|/(dΩ) = 2n·s/(2 n s²) = 1/s, and the stress written agrees.
    assert_close!(a.pressure.measured.unwrap(), 1.0 / s, 1e-14);
    assert_close!(a.pressure.exact, 1.0 / s, 1e-14);
    assert!(a.pressure.exact_rel_diff.unwrap().abs() < 1e-13);
    // GRC07 (17) neglects the deflection: predicted/measured = s/d.
    let rumpf = a.pressure.rumpf.as_ref().unwrap();
    assert_close!(rumpf.rel_diff.unwrap(), s - 1.0, 1e-12);
    assert!(a.pressure.ar07_22.is_none(), "2D");
    assert!(a.pressure.grc07_18.is_some());
    // Frictionless 2D needs 3 contacts: still no rattler.
    let opts = Options {
        rule: Some(Rule::Frictionless { dim: 2 }),
        ..Options::default()
    };
    assert_eq!(analyze(&snap, &opts).rattlers, 0);
}

/// Simple cubic lattice, frictionless: z = 6, nobody removed, AR07 (22) off by a/s − 1.
#[test]
fn cubic_lattice_and_ar07_22() {
    let diam = 1.2;
    for s in [diam, 0.999 * diam] {
        let (l, r, p, b) = lattice(3, 3, s, diam / 2.0, 2.0);
        let snap = snapshot(l, r, p, &b, false, Some(0.0));
        let a = analyze(&snap, &Options::default());
        assert_eq!(a.rule, Rule::Frictionless { dim: 3 });
        assert_close!(a.z, 6.0, 1e-15);
        assert_eq!(a.rattlers, 0);
        assert_eq!(a.x_k[6], 1.0);
        assert_close!(a.packing_fraction, PI / 6.0 * (diam / s).powi(3), 1e-14);
        let eq22 = a.pressure.ar07_22.as_ref().expect("3D monodisperse");
        assert_close!(eq22.diameter, diam, 1e-15);
        // measured P = N/s², predicted zΦ⟨N⟩/(πa²) = aN/s³.
        assert_close!(eq22.p_measured, 2.0 / (s * s), 1e-14);
        assert_close!(eq22.p_predicted, 2.0 * diam / (s * s * s), 1e-14);
        assert_close!(eq22.rel_diff, diam / s - 1.0, 1e-12);
        assert!(a.pressure.exact_rel_diff.unwrap().abs() < 1e-13);
        assert!(a.pressure.grc07_18.is_none(), "3D");
    }
}

/// AR07 (22) only for equal radii.
#[test]
fn ar07_22_needs_equal_radii() {
    let (l, mut r, p, b) = lattice(3, 3, 1.0, 0.5, 1.0);
    r[0] = 0.45;
    let a = analyze(
        &snapshot(l, r, p, &b, false, Some(0.0)),
        &Options::default(),
    );
    assert!(a.pressure.ar07_22.is_none());
    assert!(a.pressure.rumpf.is_some());
}

/// Cubic lattice plus grain 27 (3 force-carrying contacts, with 0, 1 and 28, and 1 below
/// tolerance) and grain 28 (4 contacts, one with 27): frictionless 3D removes 27, then 28
/// by cascade.
#[test]
fn frictionless_cascade_in_snapshot() {
    let (l, mut r, mut p, mut b) = lattice(3, 3, 1.0, 0.5, 1.0);
    r.extend([0.5, 0.5]);
    p.extend([vec![0.5, 0.5, 0.5], vec![1.5, 0.5, 0.5]]);
    b.extend([
        bond(27, 0, 5.0),
        bond(27, 1, 5.0),
        bond(27, 4, 1e-9), // below 1e-6 ⟨|N|⟩
        bond(28, 27, 5.0),
        bond(28, 2, 5.0),
        bond(28, 5, 5.0),
        bond(28, 11, 5.0),
    ]);
    let snap = snapshot(l, r, p, &b, false, Some(0.0));
    let a = analyze(&snap, &Options::default());
    assert_eq!((a.interactions, a.force_carrying, a.contacts), (88, 87, 81));
    assert_eq!((a.rattlers, a.rattler_sweeps), (2, 2));
    assert_close!(a.z, 2.0 * 81.0 / 29.0, 1e-15);
    assert_close!(a.rattler_fraction, 2.0 / 29.0, 1e-15);
    assert_close!(a.z_backbone.unwrap(), 6.0, 1e-14);
    assert_close!(a.x_k[0], 2.0 / 29.0, 1e-15);
    assert_close!(a.x_k[6], 27.0 / 29.0, 1e-15);
    // The rattlers' (strong) forces are out of ⟨N⟩.
    assert_eq!(a.forces.mean_normal, Some(1.0));
    // Under the frictional rule both stay.
    let opts = Options {
        rule: Some(Rule::Frictional),
        ..Options::default()
    };
    let f = analyze(&snap, &opts);
    assert_eq!((f.rattlers, f.contacts), (0, 87));
}

/// Square lattice plus a chain 0-16-17-18 and grain 19 with one force-carrying contact
/// and one below tolerance: the frictional rule removes 18, 19, then 17, then 16.
#[test]
fn frictional_cascade_in_snapshot() {
    let (l, mut r, mut p, mut b) = lattice(2, 4, 1.0, 0.5, 1.0);
    r.extend([0.5; 4]);
    p.extend([
        vec![0.5, 0.5],
        vec![0.5, 1.5],
        vec![1.5, 1.5],
        vec![2.5, 2.5],
    ]);
    b.extend([
        bond(0, 16, 1.0),
        bond(16, 17, 1.0),
        bond(17, 18, 1.0),
        bond(19, 5, 1.0),
        bond(19, 6, 1e-8),
    ]);
    let a = analyze(
        &snapshot(l, r, p, &b, false, Some(0.3)),
        &Options::default(),
    );
    assert_eq!(a.rule, Rule::Frictional);
    assert_eq!((a.force_carrying, a.contacts), (36, 32));
    assert_eq!((a.rattlers, a.rattler_sweeps), (4, 3));
    assert_close!(a.z, 3.2, 1e-15);
    assert_close!(a.z_backbone.unwrap(), 4.0, 1e-14);
    assert_close!(a.x_k[0], 0.2, 1e-15);
    assert_close!(a.x_k[4], 0.8, 1e-15);
    assert_close!(a.x_k.iter().sum::<f64>(), 1.0, 1e-15);
}

/// The tolerance is relative to ⟨|N|⟩: scaling every force leaves z unchanged.
#[test]
fn tolerance_is_relative() {
    let (l, r, p, mut b) = lattice(2, 4, 1.0, 0.5, 1e-9);
    b[0].normal = 1e-17; // below 1e-6 × ⟨|N|⟩
    let a = analyze(
        &snapshot(l, r, p, &b, false, Some(0.3)),
        &Options::default(),
    );
    assert_eq!((a.force_carrying, a.contacts, a.rattlers), (31, 31, 0));
    let loose = Options {
        force_tolerance: 1e-9,
        ..Options::default()
    };
    let (l, r, p, mut b) = lattice(2, 4, 1.0, 0.5, 1e-9);
    b[0].normal = 1e-17;
    let a = analyze(&snapshot(l, r, p, &b, false, Some(0.3)), &loose);
    assert_eq!(a.force_carrying, 32);
}

/// GRC07 T.VI split: z = z+ + z− + z0, only the isolated grain is a rattler.
#[test]
fn cohesive_split() {
    let mut p: Vec<Vec<f64>> = (0..6).map(|g| vec![0.99 * g as f64 + 1.0, 1.0]).collect();
    p.push(vec![0.99 * 5.0 + 1.0005 + 1.0, 1.0]); // grain 6: distant from 5
    p.push(vec![15.0, 4.0]); // grain 7: isolated
    let b = [
        bond(0, 1, 0.5),
        bond(1, 2, -0.3),
        bond(2, 3, 0.0),   // at h0: N = 0
        bond(3, 4, 5e-5),  // below 1e-4 F0
        bond(4, 5, -2e-5), // below 1e-4 F0
        bond(5, 6, -0.5),  // distant attraction
    ];
    let snap = snapshot(vec![20.0, 8.0], vec![0.5; 8], p, &b, true, Some(0.5));
    assert!(snap.contacts[5].gap > 0.0);
    let a = analyze(&snap, &Options::default());
    assert_eq!(a.rule, Rule::Cohesive);
    assert_eq!((a.interactions, a.force_carrying, a.contacts), (6, 3, 6));
    assert_close!(a.z, 1.5, 1e-15);
    assert_eq!((a.rattlers, a.rattler_sweeps), (1, 1));
    assert_close!(a.z_backbone.unwrap(), 1.5 / (1.0 - 1.0 / 8.0), 1e-15);
    let s = a.cohesive_split.as_ref().unwrap();
    assert_close!(s.z_plus, 0.25, 1e-15);
    assert_close!(s.z_minus, 0.5, 1e-15);
    assert_close!(s.z_zero, 0.75, 1e-15);
    assert_close!(s.z_plus + s.z_minus + s.z_zero, a.z, 1e-15);
    assert_eq!(s.distant, 1);
    // Grains 0–6 in one chain; the isolated grain 7 is no cluster. The chain stops short of
    // its own image: it wraps no axis.
    assert_eq!(s.clusters, 1);
    assert_eq!(s.wrapped_axes, 0);
    assert_eq!(s.mean_repulsive, Some(0.5));
    assert_close!(s.mean_attractive.unwrap(), 0.4, 1e-15);
    assert_close!(s.rms_attractive.unwrap(), (0.17f64).sqrt(), 1e-15);
    // GRC07 T.VI's N±, N±^(2) in the metric table (F0 = 1).
    let v = a.metric_values();
    assert_eq!(value(&v, "N_plus"), Some(0.5));
    assert_eq!(value(&v, "N_plus_rms"), Some(0.5));
    assert_close!(value(&v, "N_minus").unwrap(), 0.4, 1e-15);
    assert_close!(value(&v, "N_minus_rms").unwrap(), (0.17f64).sqrt(), 1e-15);
    assert_close!(a.x_k[1], 2.0 / 8.0, 1e-15);
    assert_close!(a.x_k[2], 5.0 / 8.0, 1e-15);
    assert!(a.forces.z5_3.is_none(), "negative forces");
    // The frictional rule would peel this open chain away entirely.
    let opts = Options {
        rule: Some(Rule::Frictional),
        ..Options::default()
    };
    assert_eq!(analyze(&snap, &opts).rattlers, 8);
    // Cohesionless snapshots have no split.
    let (l, r, p, b) = lattice(2, 4, 1.0, 0.5, 1.0);
    let a = analyze(
        &snapshot(l, r, p, &b, false, Some(0.3)),
        &Options::default(),
    );
    assert!(a.cohesive_split.is_none());
}

/// Z(2), Z(5/3), X1, M1, M2 (AR07 (27), T.VI) on known forces.
#[test]
fn force_moments_and_mobilisation() {
    let (l, r, p, mut b) = lattice(2, 4, 1.0, 0.5, 1.0);
    // Bond 0 is along x (0 → 1): tangential along y.
    for (k, bd) in b.iter_mut().enumerate() {
        let t = if k == 0 { 0.3 } else { 0.2 };
        bd.tangential = if k % 2 == 0 {
            vec![0.0, t]
        } else {
            vec![t, 0.0]
        };
    }
    b[0].normal = 3.0;
    let a = analyze(
        &snapshot(l, r, p, &b, false, Some(0.3)),
        &Options::default(),
    );
    let m = 34.0 / 32.0;
    let f = &a.forces;
    assert_close!(f.mean_normal.unwrap(), m, 1e-15);
    assert_close!(f.z2.unwrap(), (40.0 / 32.0) / (m * m), 1e-14);
    let z53 = (31.0 + 3f64.powf(5.0 / 3.0)) / 32.0 / m.powf(5.0 / 3.0);
    assert_close!(f.z5_3.unwrap(), z53, 1e-14);
    assert_close!(f.x1.unwrap(), 1.0 / 32.0, 1e-15);
    assert_close!(f.m1.unwrap(), 0.1, 1e-14);
    assert_close!(f.m2.unwrap(), 0.2, 1e-14);
    // Tangential forces ⟂ branch: no contribution to the pressure.
    assert!(a.pressure.exact_tangential.abs() < 1e-15);
}

/// Exact identity (AR07 (8), trace): P = (1/(dΩ)) Σ (N|r| + T·r) on a random contact set,
/// against the stress tensor built from the same contacts.
#[test]
fn exact_pressure_identity() {
    let mut rng = Lcg(7);
    let (n, l) = (40, vec![5.0, 6.0, 7.0]);
    let pos: Vec<Vec<f64>> = (0..n)
        .map(|_| l.iter().map(|x| x * rng.next()).collect())
        .collect();
    let mut bonds: Vec<Bond> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for _ in 0..120 {
        let i = (rng.next() * n as f64) as usize;
        let j = (i + 1 + (rng.next() * (n - 1) as f64) as usize) % n;
        if !seen.insert((i.min(j), i.max(j))) {
            continue; // each pair listed once, as `Snapshot::check` requires
        }
        let r = super::fixtures::branch(&l, &pos[i], &pos[j]);
        let rr = dot(&r, &r);
        let raw: Vec<f64> = (0..3).map(|_| rng.next() - 0.5).collect();
        let c = dot(&raw, &r) / rr;
        let t: Vec<f64> = raw.iter().zip(&r).map(|(x, y)| x - c * y).collect();
        bonds.push(Bond {
            i,
            j,
            normal: 3.0 * rng.next() - 0.5,
            tangential: t,
        });
    }
    let radius: Vec<f64> = (0..n).map(|_| 0.3 + 0.2 * rng.next()).collect();
    let snap = snapshot(
        l.clone(),
        radius.clone(),
        pos.clone(),
        &bonds,
        false,
        Some(0.3),
    );
    let a = analyze(&snap, &Options::default());
    let pm = a.pressure.measured.unwrap();
    assert!(pm > 0.0);
    assert!(a.pressure.exact_rel_diff.unwrap().abs() < 1e-12);
    assert!(a.pressure.exact_tangential.abs() < 1e-12 * pm);
    // With a component of T along r, the identity still holds and T·r shows.
    for bd in &mut bonds {
        bd.tangential[0] += 0.1;
    }
    let snap = snapshot(l, radius, pos, &bonds, false, Some(0.3));
    let a = analyze(&snap, &Options::default());
    assert!(a.pressure.exact_rel_diff.unwrap().abs() < 1e-12);
    assert!(a.pressure.exact_tangential.abs() > 1e-6);
    // A stress that disagrees with the contacts is caught.
    let mut wrong = snap.clone();
    for row in &mut wrong.cell.contact_stress {
        row.iter_mut().for_each(|s| *s *= 2.0);
    }
    let w = analyze(&wrong, &Options::default());
    assert_close!(w.pressure.exact_rel_diff.unwrap(), -0.5, 1e-12);
}

/// Checkerboard of diameters a and a/2 touching (spacing 3a/4): no deflection and no
/// size–force correlation, so GRC07 (16)–(17) are exact; (18) assumes ⟨d²⟩/⟨d⟩ = 7a/9
/// instead of the actual (5/8)/(3/4) a = 5a/6.
#[test]
fn grc07_17_and_18_on_a_bidisperse_checkerboard() {
    let (l, mut r, p, b) = lattice(2, 4, 0.75, 0.5, 1.0);
    for (g, rad) in r.iter_mut().enumerate() {
        if (g % 4 + g / 4) % 2 == 1 {
            *rad = 0.25;
        }
    }
    let snap = snapshot(l, r, p, &b, false, Some(0.5));
    assert!(snap.contacts.iter().all(|c| c.gap.abs() < 1e-12));
    let a = analyze(&snap, &Options::default());
    assert_close!(a.z, 4.0, 1e-15);
    let rumpf = a.pressure.rumpf.as_ref().unwrap();
    assert_close!(rumpf.mean_diameter, 0.75, 1e-15);
    assert_close!(rumpf.mean_diameter_pow_d, 0.625, 1e-15);
    assert!(rumpf.rel_diff.unwrap().abs() < 1e-12);
    let g = a.pressure.grc07_18.as_ref().unwrap();
    assert_eq!(g.a, 1.0);
    assert_close!(g.mean_diameter_over_a, 0.75, 1e-15);
    assert_close!(g.mean_diameter_sq_over_a2, 0.625, 1e-15);
    assert_close!(g.rel_diff.unwrap(), (7.0 / 9.0) / (5.0 / 6.0) - 1.0, 1e-12);
    assert_close!(g.mean_normal_measured, 1.0, 1e-15);
}

#[test]
fn empty_snapshot_does_not_divide_by_zero() {
    let snap = snapshot(vec![2.0, 2.0], vec![], vec![], &[], false, Some(0.3));
    let a = analyze(&snap, &Options::default());
    assert_eq!((a.n, a.z, a.rattler_fraction), (0, 0.0, 0.0));
    assert!(a.z_backbone.is_none() && a.forces.mean_normal.is_none());
    assert!(crate::report::to_json(&a).contains("\"z\": 0.0"));
}

#[test]
fn reports() {
    let (l, r, p, b) = lattice(2, 4, 0.99, 0.5, 1.0);
    let a = analyze(
        &snapshot(l, r, p, &b, false, Some(0.5)),
        &Options::default(),
    );
    let md = crate::report::to_markdown(&a);
    assert!(md.contains("| metric | value | note |"), "{md}");
    assert!(md.contains("| z | 4.00000 |"), "{md}");
    assert!(md.contains("| x_4 | 100.000% |"), "{md}");
    assert!(md.contains("GRC07 (18)"), "{md}");
    let json: serde_json::Value = serde_json::from_str(&crate::report::to_json(&a)).unwrap();
    assert_eq!(json["z"], 4.0);
    assert_eq!(json["rule"]["kind"], "frictional");
    assert_eq!(json["x_k"][4], 1.0);
    assert_eq!(json["cohesive_split"], serde_json::Value::Null);
    // The series are in the JSON, the markdown has their summaries.
    assert!(json["forces"]["pdf"]["x"].is_array());
    assert!(json["structure"]["pair_correlation"]["y"].is_array());
    assert!(json["structure"]["gap_coordination_iii"]["x"].is_array());
    assert_eq!(json["bond_order"], serde_json::Value::Null, "2D");
    assert!(md.contains("| z^III(h) | 4.00000 |"), "{md}");
    assert!(md.contains("| x_4^II | 100.000% |"), "{md}");
    assert!(!md.contains("| Q6 |"), "{md}");
}

/// Every key [`Analysis::metric_values`] may return, as listed in its documentation.
fn canonical_keys() -> Vec<String> {
    let mut k: Vec<String> = ["phi", "z", "z_star", "x0"].map(String::from).to_vec();
    k.push("xk1".into());
    k.extend((2..=12).map(|i| format!("xk{i}")));
    k.extend((2..=12).map(|i| format!("xk{i}_II")));
    k.extend(
        [
            "mean_N",
            "Z2",
            "Z5_3",
            "X1",
            "M1",
            "M2",
            "N_2",
            "X1_2",
            "M1_2",
            "M2_2",
            "N_3",
            "X1_3",
            "M1_3",
            "M2_3",
            "Q4",
            "Q6",
            "Q4loc",
            "Q6loc",
            "Z_bond",
            "Z_cr",
            "Q6loc_cr",
            "x_cr",
            "n_cr",
            "z_plus",
            "z_minus",
            "z_zero",
            "clusters",
            "wrapped_axes",
            "N_plus",
            "N_plus_rms",
            "N_minus",
            "N_minus_rms",
            "pressure",
        ]
        .map(String::from),
    );
    for dc in [110, 120, 130, 140] {
        k.push(format!("fcc_{dc}"));
        k.push(format!("hcp_{dc}"));
        for sample in ["F", "D", "B"] {
            k.push(format!("dis_{sample}_{dc}"));
        }
        for sample in ["F", "D", "B"] {
            k.push(format!("hcp_not_{sample}_{dc}"));
        }
    }
    k
}

fn value(v: &[(String, f64)], key: &str) -> Option<f64> {
    v.iter().find(|(k, _)| k == key).map(|(_, x)| *x)
}

/// A tangential force of magnitude `t` perpendicular to `branch` (3D).
fn perpendicular(branch: &[f64], t: f64) -> Vec<f64> {
    let e = if branch[0].abs() < 0.9 * norm(branch) {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let c = [
        branch[1] * e[2] - branch[2] * e[1],
        branch[2] * e[0] - branch[0] * e[2],
        branch[0] * e[1] - branch[1] * e[0],
    ];
    let l = norm(&c);
    c.iter().map(|x| t * x / l).collect()
}

/// Cohesive FCC packing (3×3×3 cells, nearest neighbours at 1, radius 0.49, every nearest
/// pair listed with N = 1 or −0.2) plus two small grains in octahedral holes, one with 2
/// interactions (N = 2 with |T| = 0.5, N = 0.1 with |T| = 0.02), one with 3 (N = 2, 0.1,
/// 0.1, same |T|): every key but Z(5/3) is defined. P = 2.
fn fcc_cohesive() -> Snapshot {
    let c = 2f64.sqrt();
    let basis = [
        [0.0, 0.0, 0.0],
        [0.5, 0.5, 0.0],
        [0.5, 0.0, 0.5],
        [0.0, 0.5, 0.5],
    ];
    let mut p: Vec<Vec<f64>> = Vec::new();
    for x in 0..3 {
        for y in 0..3 {
            for z in 0..3 {
                for b in &basis {
                    let q = [x as f64 + b[0], y as f64 + b[1], z as f64 + b[2]];
                    p.push(q.iter().map(|v| v * c).collect());
                }
            }
        }
    }
    let l = vec![3.0 * c; 3];
    let mut bonds = Vec::new();
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            if norm(&super::fixtures::branch(&l, &p[i], &p[j])) < 1.01 {
                let n = if bonds.len() % 2 == 0 { 1.0 } else { -0.2 };
                bonds.push(bond(i, j, n));
            }
        }
    }
    assert_eq!(bonds.len(), 6 * 108);
    let mut r = vec![0.49; p.len()];
    for (g, centre, forces) in [
        (108, [0.5, 0.5, 0.5], &[2.0, 0.1][..]),
        (109, [1.5, 0.5, 0.5], &[2.0, 0.1, 0.1][..]),
    ] {
        p.push(centre.iter().map(|v| v * c).collect());
        r.push(0.2);
        let near: Vec<usize> = (0..108)
            .filter(|&h| norm(&super::fixtures::branch(&l, &p[g], &p[h])) < 0.75)
            .collect();
        assert_eq!(near.len(), 6);
        for (&h, &n) in near.iter().zip(forces) {
            let br = super::fixtures::branch(&l, &p[g], &p[h]);
            let t = if n > 1.0 { 0.5 } else { 0.02 };
            bonds.push(Bond {
                i: g,
                j: h,
                normal: n,
                tangential: perpendicular(&br, t),
            });
        }
    }
    let mut snap = snapshot(l, r, p, &bonds, true, Some(0.5));
    snap.pressure_target = Some(2.0);
    snap
}

/// Simple cubic frictional lattice (4³, touching, μ = 0.3) with varied normal forces and
/// tangential forces on a quarter of the bonds.
fn cubic_frictional() -> Snapshot {
    let (l, r, p, mut b) = lattice(3, 4, 1.0, 0.5, 1.0);
    let pos = p.clone();
    for (k, bd) in b.iter_mut().enumerate() {
        bd.normal = 0.5 + (k % 3) as f64;
        if k % 4 == 0 {
            let br = super::fixtures::branch(&l, &pos[bd.i], &pos[bd.j]);
            bd.tangential = perpendicular(&br, 0.1);
        }
    }
    snapshot(l, r, p, &b, false, Some(0.3))
}

/// `metric_values` uses exactly the canonical keys: the union over a cohesive FCC packing
/// and a cohesionless frictional lattice is the whole list, with no other key.
#[test]
fn metric_values_use_the_canonical_keys() {
    let a = analyze(&fcc_cohesive(), &Options::default());
    let b = analyze(&cubic_frictional(), &Options::default());
    let canon = canonical_keys();
    let mut union: Vec<String> = Vec::new();
    for v in [a.metric_values(), b.metric_values()] {
        for (k, x) in v {
            assert!(canon.contains(&k), "unknown key {k}");
            assert!(x.is_finite());
            if !union.contains(&k) {
                union.push(k);
            }
        }
    }
    let mut missing: Vec<&String> = canon.iter().filter(|k| !union.contains(k)).collect();
    missing.sort();
    assert!(missing.is_empty(), "never returned: {missing:?}");
    // Cohesive: Z(5/3) undefined (negative forces), z± present.
    let va = a.metric_values();
    assert!(value(&va, "Z5_3").is_none());
    assert!(value(&va, "z_plus").is_some());
    // Values are the fields, as fractions.
    let vb = b.metric_values();
    assert_eq!(value(&vb, "z"), Some(6.0));
    assert_eq!(value(&vb, "xk6"), Some(1.0));
    assert_eq!(value(&vb, "xk6_II"), Some(1.0));
    assert_eq!(value(&vb, "x0"), Some(0.0));
    assert_eq!(value(&vb, "Z_bond"), Some(6.0));
    assert!((value(&vb, "Q6").unwrap() - 0.3536).abs() < 5e-5);
    assert_eq!(value(&vb, "x_cr"), Some(0.0));
    assert!(
        value(&vb, "n_cr").is_none(),
        "no crystalline grain in a simple cubic lattice"
    );
    assert_eq!(value(&vb, "pressure"), b.pressure.measured);
    assert_eq!(value(&vb, "Z5_3"), b.forces.z5_3);
    assert!(value(&vb, "z_plus").is_none(), "cohesionless");
    // 2D: no bond order.
    let (l, r, p, bd) = lattice(2, 4, 0.99, 0.5, 1.0);
    let v2 = analyze(
        &snapshot(l, r, p, &bd, false, Some(0.5)),
        &Options::default(),
    )
    .metric_values();
    assert!(value(&v2, "Q6").is_none() && value(&v2, "z").is_some());
}

/// AR07 T.VI through `analyze`: N^(k) is the mean force of the population over P a²,
/// with P the snapshot's pressure target and a its largest diameter (0.98 here).
#[test]
fn t6_populations_in_analysis() {
    let a = analyze(&fcc_cohesive(), &Options::default());
    let v = a.metric_values();
    let pa2 = 2.0 * 0.98 * 0.98;
    assert!((value(&v, "N_2").unwrap() - 1.05 / pa2).abs() < 1e-12);
    assert!((value(&v, "N_3").unwrap() - 2.2 / 3.0 / pa2).abs() < 1e-12);
    assert_eq!(value(&v, "X1_2"), Some(0.5));
    assert!((value(&v, "X1_3").unwrap() - 1.0 / 3.0).abs() < 1e-15);
    for key in ["M1_2", "M1_3"] {
        assert!((value(&v, key).unwrap() - 0.25).abs() < 1e-12, "{key}");
    }
    for key in ["M2_2", "M2_3"] {
        assert!((value(&v, key).unwrap() - 0.2).abs() < 1e-12, "{key}");
    }
    // Cohesive P(f) is in units of F0 (GRC07 Fig. 9): bins below 0 for tensile forces.
    assert_eq!(a.forces.pdf_unit, Some(1.0));
    assert!(a.forces.pdf.as_ref().unwrap().x[0] < 0.0);
    // FCC bond order survives the two interstitials: most grains crystalline.
    let b = a.bond_order.as_ref().unwrap();
    assert!(b.x_cr > 0.8 && b.n_cr.is_some(), "{b:?}");
}

/// Variant II through `analyze`: a caged rattler (perturbed cubic lattice, radius 0.3 in
/// a cell centre) ends on 3 contacts, x_k^II and z^II(h = 0) follow; z^III(0) = z*.
#[test]
fn fixed_rattlers_in_analysis() {
    let (l, mut r, mut p, b) = lattice(3, 4, 1.0, 0.5, 1.0);
    let mut rng = Lcg(21);
    for q in p.iter_mut() {
        q.iter_mut().for_each(|x| *x += 0.03 * (rng.next() - 0.5));
    }
    r.push(0.3);
    p.push(vec![0.5; 3]);
    let a = analyze(
        &snapshot(l, r, p, &b, false, Some(0.3)),
        &Options::default(),
    );
    assert_eq!(a.rattlers, 1);
    let f = a.fixed_rattlers.as_ref().unwrap();
    assert_eq!((f.rattlers, f.rattler_contacts, f.unsettled), (1, 3, 0));
    let v = a.metric_values();
    assert!((value(&v, "xk3_II").unwrap() - 1.0 / 65.0).abs() < 1e-15);
    assert!((value(&v, "xk7_II").unwrap() - 3.0 / 65.0).abs() < 1e-15);
    assert!((value(&v, "xk6_II").unwrap() - 61.0 / 65.0).abs() < 1e-15);
    assert_eq!(value(&v, "xk3"), Some(0.0));
    let z2 = a.structure.gap_coordination_ii.as_ref().unwrap();
    assert_eq!(z2.x[0], 0.0);
    // The perturbed lattice bonds are listed but not all overlap: z^II(0) counts the
    // geometric overlaps only, ≤ z_geometric.
    assert!(z2.y[0] <= f.z_geometric);
    let z3 = a.structure.gap_coordination_iii.as_ref().unwrap();
    let zi = a.structure.gap_coordination_i.as_ref().unwrap();
    assert!(z3.y.iter().zip(&z3.x).all(|(y, _)| y.is_finite()));
    assert!(
        zi.y.windows(2).all(|w| w[0] <= w[1]),
        "z(h) is non-decreasing"
    );
    // Without the relaxation: no variant II.
    let opts = Options {
        fix_rattlers: false,
        ..Options::default()
    };
    let (l, r, p, b) = lattice(3, 4, 1.0, 0.5, 1.0);
    let a = analyze(&snapshot(l, r, p, &b, false, Some(0.3)), &opts);
    assert!(a.fixed_rattlers.is_none() && a.structure.gap_coordination_ii.is_none());
    assert!(value(&a.metric_values(), "xk6_II").is_none());
    // Touching lattice: z^III(0) = z* = 6.
    assert_eq!(a.structure.gap_coordination_iii.as_ref().unwrap().y[0], 6.0);
}

/// A cohesive gas with one bonded pair: 198 rattlers and a backbone of 2. Variant II would
/// let the rattlers fall through the empty cell for its whole step budget (45 s, found by
/// tests/fuzz.rs); above `MAX_FIXED_RATTLER_FRACTION` it is skipped.
#[test]
fn variant_ii_is_skipped_without_a_backbone_to_speak_of() {
    let mut rng = Lcg(5);
    let mut p: Vec<Vec<f64>> = (0..198)
        .map(|_| (0..2).map(|_| 30.0 * rng.next()).collect())
        .collect();
    p.push(vec![15.0, 15.0]);
    p.push(vec![15.999, 15.0]);
    let gas = snapshot(
        vec![30.0; 2],
        vec![0.5; 200],
        p,
        &[bond(198, 199, -1e-3)],
        true,
        Some(0.5),
    );
    let a = analyze(&gas, &Options::default());
    assert!(a.rattlers > 100 && a.rattlers < 200, "{}", a.rattlers);
    assert!(a.fixed_rattlers.is_none());
}

/// Foreign snapshots that are odd but pass `Snapshot::check` never panic: no contacts
/// (every grain a rattler), zero radii, a degenerate cell, non-finite positions.
#[test]
fn odd_snapshots_do_not_panic() {
    let mut rng = Lcg(2);
    let p: Vec<Vec<f64>> = (0..200)
        .map(|_| (0..3).map(|_| 6.0 * rng.next()).collect())
        .collect();
    let gas = snapshot(
        vec![6.0; 3],
        vec![0.3; 200],
        p.clone(),
        &[],
        false,
        Some(0.3),
    );
    let a = analyze(&gas, &Options::default());
    assert_eq!(a.rattlers, 200);
    assert!(
        a.fixed_rattlers.is_none(),
        "nothing to fix the rattlers onto"
    );
    assert!(a.structure.pair_correlation.is_some() && a.bond_order.is_some());
    assert!(a.forces.pdf.is_none() && a.forces.angles.is_none());
    let v = a.metric_values();
    assert!(value(&v, "xk2_II").is_none() && value(&v, "mean_N").is_none());
    let _ = crate::report::to_markdown(&a);

    // Refused by `Snapshot::check`, but `analyze` must not panic on it either.
    let zero = super::fixtures::unchecked_snapshot(
        vec![6.0; 3],
        vec![0.0; 200],
        p.clone(),
        &[],
        false,
        Some(0.3),
    );
    let a = analyze(&zero, &Options::default());
    assert!(a.structure.unit.is_none() && a.bond_order.is_none());
    let _ = crate::report::to_json(&a);

    let mut bad = gas.clone();
    bad.cell.lengths = vec![6.0, 0.0, -1.0];
    bad.particles.position[3] = Vector::from_slice(&[f64::NAN, 0.0, f64::INFINITY]);
    let a = analyze(&bad, &Options::default());
    assert!(a.structure.pair_correlation.is_none() && a.bond_order.is_none());
    let _ = crate::report::to_markdown(&a);

    let mut nan = gas;
    nan.particles.position[3] = Vector::from_slice(&[f64::NAN, 0.0, f64::INFINITY]);
    nan.particles.radius[5] = f64::NAN;
    let a = analyze(&nan, &Options::default());
    let _ = (crate::report::to_markdown(&a), a.metric_values());
}

/// The example in docs/snapshot-format.md parses, passes the checks, and its stress agrees
/// with its contact.
#[test]
fn documented_example_is_valid() {
    let doc = include_str!("../../../docs/snapshot-format.md");
    let start = doc.find("```json\n").expect("json block") + "```json\n".len();
    let end = start + doc[start..].find("```").expect("end of block");
    let snap: Snapshot = serde_json::from_str(&doc[start..end]).expect("example parses");
    snap.check().expect("example passes Snapshot::check");
    let a = analyze(&snap, &Options::default());
    assert_eq!((a.n, a.interactions, a.force_carrying), (2, 1, 1));
    assert!(a.pressure.exact_rel_diff.unwrap().abs() < 1e-12);
    // Frictional rule: two grains with one contact each are rattlers, N_c = 0.
    assert_eq!((a.rattlers, a.contacts), (2, 0));
}

/// GRC07 §III.B.1: a cohesive square lattice wraps both axes of its cell; without the bonds
/// that close it across x, only y.
#[test]
fn wrapped_axes_of_a_cohesive_network() {
    let (l, r, p, b) = lattice(2, 4, 0.99, 0.5, -0.1);
    let wraps = |bonds: &[Bond]| {
        let snap = snapshot(l.clone(), r.clone(), p.clone(), bonds, true, Some(0.5));
        let a = analyze(&snap, &Options::default());
        let v = a.metric_values();
        let w = a.cohesive_split.unwrap().wrapped_axes;
        assert_eq!(value(&v, "wrapped_axes"), Some(w as f64));
        w
    };
    assert_eq!(wraps(&b), 2);
    // Bonds from x = 3 to x = 0 cross the boundary along x.
    let open: Vec<Bond> = b
        .iter()
        .filter(|b| !(p[b.i][0] > 2.0 && p[b.j][0] < 1.0))
        .cloned()
        .collect();
    assert_eq!(b.len() - open.len(), 4);
    assert_eq!(wraps(&open), 1);
}

/// GRC07 §V runs on 2D cohesive packings only: a square lattice of slightly overlapping disks
/// (one closed hole per lattice cell, nothing percolates) has ⟨R⟩_w of that hole; the same
/// grains without cohesion get no density section.
#[test]
fn density_correlations_of_a_cohesive_2d_packing() {
    let (l, r, p, b) = lattice(2, 6, 1.0, 0.505, -0.1);
    let snap = snapshot(l.clone(), r.clone(), p.clone(), &b, true, Some(0.5));
    let a = analyze(&snap, &Options::default());
    let d = a.density.as_ref().expect("2D cohesive");
    assert_eq!(d.holes.count, 36);
    assert!(!d.holes.percolating);
    // The concave square between four disks, area 1 − π·0.505² ≈ 0.2 a².
    let r_w = value(&a.metric_values(), "R_w").expect("R_w");
    assert!(r_w > 0.2 && r_w < 0.5, "{r_w}");
    let dry = snapshot(l, r, p, &b, false, Some(0.5));
    let a = analyze(&dry, &Options::default());
    assert!(a.density.is_none());
    assert_eq!(value(&a.metric_values(), "R_w"), None);
}

/// [`MODULI_METRICS`] are exactly the metric keys that asking for the moduli adds.
#[test]
fn moduli_metric_keys_are_listed() {
    use super::stiffness::{ContactStiffness, NormalStiffness};
    let (l, r, p, b) = lattice(2, 4, 0.99, 0.5, 1.0);
    let snap = snapshot(l, r, p, &b, false, Some(0.5));
    let keys = |o: &Options| -> std::collections::BTreeSet<String> {
        analyze(&snap, o)
            .metric_values()
            .into_iter()
            .map(|(k, _)| k)
            .collect()
    };
    let plain = keys(&Options::default());
    let with = keys(&Options {
        moduli: Some(ContactStiffness {
            normal: NormalStiffness::Constant(1e3),
            tangential_ratio: Some(0.5),
            rolling: None,
            attraction: None,
        }),
        ..Options::default()
    });
    let added: Vec<&str> = with.difference(&plain).map(|k| k.as_str()).collect();
    let mut listed = MODULI_METRICS.to_vec();
    listed.sort_unstable();
    assert_eq!(added, listed);
    assert!(plain.is_subset(&with));
}
