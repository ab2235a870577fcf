//! Hand-built snapshots for unit tests.

use grainbench_engine::snapshot::{Cell, Contact, Particles, Snapshot, Vector, FORMAT, VERSION};

/// One interaction to place in a fixture: grains, total normal force, tangential force.
#[derive(Clone, Debug)]
pub struct Bond {
    pub i: usize,
    pub j: usize,
    pub normal: f64,
    pub tangential: Vec<f64>,
}

pub fn bond(i: usize, j: usize, normal: f64) -> Bond {
    Bond {
        i,
        j,
        normal,
        tangential: Vec::new(),
    }
}

/// Nearest periodic image of `r_j − r_i`.
pub fn branch(lengths: &[f64], pi: &[f64], pj: &[f64]) -> Vec<f64> {
    lengths
        .iter()
        .zip(pi.iter().zip(pj))
        .map(|(l, (a, b))| {
            let d = b - a;
            d - l * (d / l).round()
        })
        .collect()
}

/// Builds a checked snapshot; branches and gaps come from the positions, and the contact
/// stress is computed from the bonds by AR07 (8): `σ_αβ = (1/Ω) Σ F_α r_β`, `F = N r̂ + T`.
pub fn snapshot(
    lengths: Vec<f64>,
    radius: Vec<f64>,
    position: Vec<Vec<f64>>,
    bonds: &[Bond],
    cohesive: bool,
    mu: Option<f64>,
) -> Snapshot {
    let snap = unchecked_snapshot(lengths, radius, position, bonds, cohesive, mu);
    snap.check().expect("fixture is a valid snapshot");
    snap
}

/// As [`snapshot`], without [`Snapshot::check`]: for the analysis of impossible snapshots.
pub fn unchecked_snapshot(
    lengths: Vec<f64>,
    radius: Vec<f64>,
    position: Vec<Vec<f64>>,
    bonds: &[Bond],
    cohesive: bool,
    mu: Option<f64>,
) -> Snapshot {
    let d = lengths.len();
    let n = radius.len();
    let volume: f64 = lengths.iter().product();
    let mut stress = vec![vec![0.0; d]; d];
    let contacts: Vec<Contact> = bonds
        .iter()
        .map(|b| {
            let r = branch(&lengths, &position[b.i], &position[b.j]);
            let len = r.iter().map(|x| x * x).sum::<f64>().sqrt();
            for (al, row) in stress.iter_mut().enumerate() {
                let t = b.tangential.get(al).copied().unwrap_or(0.0);
                let f = b.normal * r[al] / len + t;
                for (be, s) in row.iter_mut().enumerate() {
                    *s += f * r[be] / volume;
                }
            }
            Contact {
                i: b.i,
                j: b.j,
                gap: len - radius[b.i] - radius[b.j],
                branch: Vector::from_slice(&r),
                normal: b.normal,
                normal_elastic: b.normal.max(0.0),
                tangential: Vector::from_slice(&b.tangential),
                rolling: Vector::new(),
            }
        })
        .collect();
    Snapshot {
        format: FORMAT.to_string(),
        version: VERSION,
        code: "fixture".to_string(),
        scene: "fixture".to_string(),
        dimension: d,
        time: 0.0,
        step: 0,
        status: "equilibrium".to_string(),
        force_unit: if cohesive { "F0" } else { "P_ref a^(d-1)" }.to_string(),
        pressure_target: Some(1.0),
        cohesive,
        mu,
        cell: Cell {
            lengths,
            contact_stress: stress,
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

/// Periodic simple lattice (square in 2D, cubic in 3D) of `k^d` equal grains of radius
/// `radius`, spacing `spacing`, each bonded to its +x, +y (+z) neighbours with force `normal`:
/// 2d contacts per grain. Grain index `x + k y (+ k² z)`.
pub fn lattice(
    d: usize,
    k: usize,
    spacing: f64,
    radius: f64,
    normal: f64,
) -> (Vec<f64>, Vec<f64>, Vec<Vec<f64>>, Vec<Bond>) {
    assert!(k >= 3, "k >= 3 avoids double bonds across the cell");
    let n = k.pow(d as u32);
    let coords = |g: usize| -> Vec<usize> { (0..d).map(|a| (g / k.pow(a as u32)) % k).collect() };
    let index =
        |c: &[usize]| -> usize { c.iter().enumerate().map(|(a, x)| x * k.pow(a as u32)).sum() };
    let position = (0..n)
        .map(|g| coords(g).iter().map(|&x| x as f64 * spacing).collect())
        .collect();
    let mut bonds = Vec::new();
    for g in 0..n {
        for a in 0..d {
            let mut c = coords(g);
            c[a] = (c[a] + 1) % k;
            bonds.push(bond(g, index(&c), normal));
        }
    }
    (
        vec![k as f64 * spacing; d],
        vec![radius; n],
        position,
        bonds,
    )
}

/// Deterministic pseudo-random numbers in [0, 1) (64-bit LCG, high bits).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}
