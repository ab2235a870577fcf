//! Bond-orientational order and incipient crystallisation, 3D only (AR07 §III.D, (31)–(34),
//! T.II, App. D; after Volkov et al., AR07 ref. 67).
//!
//! * *Bonds* join grains whose centres are closer than `d_c` (AR07 T.II: d_c = 1.35a and
//!   1.40a, near the first minimum of g(r); a = largest diameter).
//! * Local order, AR07 (31)–(32): `q_lm(i) = (1/N_b(i)) Σ_j Y_lm(n_ij)` and
//!   `Q_l^loc(i) = [4π/(2l+1) Σ_m |q_lm(i)|²]^{1/2}`; Q_l^loc is its mean over grains with
//!   at least one bond.
//! * Global order: the same with the average of `Y_lm` over all bonds of the sample.
//! * Crystalline bonds, AR07 (33)–(34): with `q̄_lm(i) = q_lm(i)/[Σ_m |q_lm(i)|²]^{1/2}`, the
//!   bond i–j is crystalline if `|Σ_m q̄_6m(i) q̄*_6m(j)| ≥ 0.5`; a grain is crystalline with
//!   at least 7 crystalline bonds.
//!
//! Real spherical harmonics are used: they are a unitary recombination of the complex
//! `Y_lm` at each l, so every sum `Σ_m q_lm(i) q*_lm(j)` is unchanged.

use super::neighbors::{for_each_pair, points, valid_cell, CellGrid, Point};
use serde::Serialize;
use std::f64::consts::PI;

/// AR07 T.II default bond length d_c/a.
pub const DEFAULT_CUTOFF: f64 = 1.35;
/// AR07 (34): threshold on `|Σ_m q̄_6m(i) q̄*_6m(j)|`.
pub const CRYSTALLINE_PRODUCT: f64 = 0.5;
/// AR07 §III.D: a crystalline grain has at least this many crystalline bonds.
pub const CRYSTALLINE_BONDS: usize = 7;

/// Everything of AR07 T.II for one snapshot.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BondOrder {
    /// d_c/a.
    pub cutoff: f64,
    /// Number of bonds N_b.
    pub bonds: usize,
    /// Z = 2N_b/n, the coordination number of first neighbours.
    pub z_bond: f64,
    /// Global Q4 and Q6 (average of Y_lm over all bonds).
    pub q4_global: Option<f64>,
    pub q6_global: Option<f64>,
    /// Mean of Q4^loc(i) and Q6^loc(i), AR07 (31), over grains with at least one bond.
    pub q4_local: Option<f64>,
    pub q6_local: Option<f64>,
    /// Crystalline bonds, AR07 (34), and Z_cr = 2 × their number / n.
    pub crystalline_bonds: usize,
    pub z_cr: f64,
    /// Crystalline grains (≥ 7 crystalline bonds) and x_cr, their fraction of n.
    pub crystalline_grains: usize,
    pub x_cr: f64,
    /// Q6^{loc,cr}: mean Q6^loc(i) over the crystalline grains.
    pub q6_local_cr: Option<f64>,
    /// Crystalline clusters: crystalline grains joined by bonds.
    pub clusters: usize,
    /// ⟨n_cr⟩: mass average of the cluster size, Σ n_c² / Σ n_c.
    pub n_cr: Option<f64>,
    /// Size of the largest cluster.
    pub largest_cluster: usize,
}

/// Associated Legendre function P_l^m(x), 0 ≤ m ≤ l, without the Condon–Shortley phase.
fn legendre_assoc(l: usize, m: usize, x: f64) -> f64 {
    let s = (1.0 - x * x).max(0.0).sqrt();
    let mut pmm = 1.0;
    for k in 1..=m {
        pmm *= (2 * k - 1) as f64 * s;
    }
    if l == m {
        return pmm;
    }
    let mut pm1 = x * (2 * m + 1) as f64 * pmm;
    if l == m + 1 {
        return pm1;
    }
    let mut pll = 0.0;
    for ll in m + 2..=l {
        pll = ((2 * ll - 1) as f64 * x * pm1 - (ll + m - 1) as f64 * pmm) / (ll - m) as f64;
        pmm = pm1;
        pm1 = pll;
    }
    pll
}

/// Real spherical harmonics of degree `l` at the unit vector `n`, `out[l + m]` for
/// m = −l..=l: `N_l0 P_l`, `√2 N_lm P_l^m cos mφ` (m > 0), `√2 N_l|m| P_l^|m| sin |m|φ`
/// (m < 0), with `N_lm = [(2l+1)/(4π) (l−m)!/(l+m)!]^{1/2}`. Orthonormal on the sphere.
pub fn real_spherical_harmonics(l: usize, n: &[f64; 3]) -> Vec<f64> {
    let mut out = vec![0.0; 2 * l + 1];
    harmonics_into(l, n, &mut out);
    out
}

/// [`real_spherical_harmonics`] into `out` (length 2l + 1), without allocating.
fn harmonics_into(l: usize, n: &[f64; 3], out: &mut [f64]) {
    let z = n[2].clamp(-1.0, 1.0);
    let phi = n[1].atan2(n[0]);
    for m in 0..=l {
        // (l−m)!/(l+m)! as a product, no overflow for the l of interest.
        let ratio: f64 = (l - m + 1..=l + m).map(|k| 1.0 / k as f64).product();
        let norm = ((2 * l + 1) as f64 / (4.0 * PI) * ratio).sqrt();
        let p = legendre_assoc(l, m, z);
        if m == 0 {
            out[l] = norm * p;
        } else {
            let c = std::f64::consts::SQRT_2 * norm * p;
            out[l + m] = c * (m as f64 * phi).cos();
            out[l - m] = c * (m as f64 * phi).sin();
        }
    }
}

/// Sums of Y_4m and Y_6m over bonds.
type Sums46 = ([f64; 9], [f64; 13]);

/// Y_4m and Y_6m at the unit vector `u`.
fn y46(u: &[f64; 3]) -> Sums46 {
    let (mut y4, mut y6) = ([0.0; 9], [0.0; 13]);
    harmonics_into(4, u, &mut y4);
    harmonics_into(6, u, &mut y6);
    (y4, y6)
}

/// `sums += y`.
fn add46(sums: (&mut [f64; 9], &mut [f64; 13]), y: &Sums46) {
    sums.0.iter_mut().zip(&y.0).for_each(|(a, b)| *a += b);
    sums.1.iter_mut().zip(&y.1).for_each(|(a, b)| *a += b);
}

/// The unit vector of a separation `r` of squared length `r2`; `None` for a zero or NaN one.
fn unit(r: &Point, r2: f64) -> Option<[f64; 3]> {
    let len = r2.sqrt();
    (len > 0.0).then(|| [r[0] / len, r[1] / len, r[2] / len])
}

/// `[4π/(2l+1) Σ_m q_m²]^{1/2}` of AR07 (31).
fn q_norm(l: usize, q: &[f64]) -> f64 {
    (4.0 * PI / (2 * l + 1) as f64 * q.iter().map(|x| x * x).sum::<f64>()).sqrt()
}

/// Q_l of a set of bond directions (AR07 (31)–(32) for one grain): `None` if empty.
pub fn q_l(l: usize, directions: &[[f64; 3]]) -> Option<f64> {
    if directions.is_empty() {
        return None;
    }
    let mut q = vec![0.0; 2 * l + 1];
    for d in directions {
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let y = real_spherical_harmonics(l, &[d[0] / len, d[1] / len, d[2] / len]);
        q.iter_mut().zip(&y).for_each(|(a, b)| *a += b);
    }
    q.iter_mut().for_each(|a| *a /= directions.len() as f64);
    Some(q_norm(l, &q))
}

/// Per-grain sums of Y_4m and Y_6m over bonds. The bonds themselves are not kept: a metric
/// that needs them walks them again with [`for_each_bond`] (a pass over the cell grid costs
/// less than the harmonics, and a list of ~6 bonds a grain would be the largest array here).
struct Bonds {
    count: Vec<u32>,
    q4: Vec<[f64; 9]>,
    q6: Vec<[f64; 13]>,
    /// Number of bonds, and sums over all bonds (global order).
    total: usize,
    g4: [f64; 9],
    g6: [f64; 13],
}

impl Bonds {
    /// AR07 (31) for grain `g`: (Q4^loc(g), Q6^loc(g)); `None` without bonds.
    fn local(&self, g: usize) -> Option<(f64, f64)> {
        let k = self.count[g] as f64;
        (self.count[g] > 0).then(|| (q_norm(4, &self.q4[g]) / k, q_norm(6, &self.q6[g]) / k))
    }
}

/// Calls `f(i, j, u)` for every bond `i < j` shorter than `cutoff`, `u` its unit vector; the
/// same bonds, in the same order, at every call with the same points.
fn for_each_bond(
    lengths: &[f64],
    pts: &[Point],
    cutoff: f64,
    mut f: impl FnMut(usize, usize, [f64; 3]),
) {
    for_each_pair(lengths, pts, cutoff, |i, j, r: &Point, r2| {
        if let Some(u) = unit(r, r2) {
            f(i, j, u);
        }
    });
}

fn bonds(lengths: &[f64], pts: &[Point], cutoff: f64) -> Bonds {
    let n = pts.len();
    let mut b = Bonds {
        count: vec![0; n],
        q4: vec![[0.0; 9]; n],
        q6: vec![[0.0; 13]; n],
        total: 0,
        g4: [0.0; 9],
        g6: [0.0; 13],
    };
    for_each_bond(lengths, pts, cutoff, |i, j, u| {
        // Even l: Y_lm(−u) = Y_lm(u), both ends get the same harmonics.
        let y = y46(&u);
        for g in [i, j] {
            b.count[g] += 1;
            add46((&mut b.q4[g], &mut b.q6[g]), &y);
        }
        add46((&mut b.g4, &mut b.g6), &y);
        b.total += 1;
    });
    b
}

/// (Q4^loc(g), Q6^loc(g)) of AR07 (31) for every grain, `None` without bonds, grain by grain
/// from its neighbours in the cell grid: only the two numbers a grain are kept (the sums of
/// [`Bonds`] are 176 B a grain), at twice the harmonics (each bond is seen from both ends).
fn local_orders(lengths: &[f64], pts: &[Point], cutoff: f64) -> Vec<Option<(f64, f64)>> {
    let Some(grid) = CellGrid::new(lengths, pts, cutoff) else {
        return vec![None; pts.len()];
    };
    pts.iter()
        .map(|p| {
            let (mut q4, mut q6, mut k) = ([0.0; 9], [0.0; 13], 0usize);
            grid.query(p, |_, r, r2| {
                if let Some(u) = unit(r, r2) {
                    add46((&mut q4, &mut q6), &y46(&u));
                    k += 1;
                }
            });
            (k > 0).then(|| (q_norm(4, &q4) / k as f64, q_norm(6, &q6) / k as f64))
        })
        .collect()
}

/// Per-grain local order Q_l^loc(i) (AR07 (31)) for l = 4 or 6 (AR07 App. D plots the pairs
/// (Q4^loc(i), Q6^loc(i))); `None` entries for grains without bonds. `None` unless 3D, or for
/// another l, a bad cell or a.
pub fn local_order(
    lengths: &[f64],
    position: &[impl std::ops::Deref<Target = [f64]>],
    a: f64,
    cutoff_over_a: f64,
    l: usize,
) -> Option<Vec<Option<f64>>> {
    if lengths.len() != 3 || !valid_cell(lengths) || !(a > 0.0 && a.is_finite()) {
        return None;
    }
    let b = bonds(lengths, &points(3, position), cutoff_over_a * a);
    let per = |g: usize| b.local(g).map(|(q4, q6)| if l == 4 { q4 } else { q6 });
    matches!(l, 4 | 6).then(|| (0..position.len()).map(per).collect())
}

/// One Aste sample: its name and, for d_c = 1.1a…1.4a, `(d_c/a, Q̂4, Q̂6)`.
pub type AsteSample = (&'static str, [(f64, f64, f64); 4]);

/// AR07 App. D, T.VII–T.VIII: the most frequent local order (Q̂4, Q̂6) that Aste et al. measured
/// for bonds shorter than d_c (in diameters), in their samples F (Φ ≈ 0.640, compared with A, A'
/// and C), D (Φ ≈ 0.626, compared with B) and B (Φ ≈ 0.596, compared with D): `(sample,
/// [(d_c, Q̂4, Q̂6); 4])`.
pub const ASTE_MODES: [AsteSample; 3] = [
    (
        "F",
        [
            (1.1, 0.23, 0.44),
            (1.2, 0.16, 0.45),
            (1.3, 0.13, 0.42),
            (1.4, 0.10, 0.38),
        ],
    ),
    (
        "D",
        [
            (1.1, 0.25, 0.44),
            (1.2, 0.19, 0.44),
            (1.3, 0.15, 0.40),
            (1.4, 0.11, 0.36),
        ],
    ),
    (
        "B",
        [
            (1.1, 0.30, 0.45),
            (1.2, 0.23, 0.44),
            (1.3, 0.16, 0.38),
            (1.4, 0.14, 0.35),
        ],
    ),
];
/// AR07 App. D: (Q4, Q6) of fcc-like and hcp-like neighbourhoods.
pub const FCC_LIKE: (f64, f64) = (0.191, 0.574);
pub const HCP_LIKE: (f64, f64) = (0.097, 0.485);
/// AR07 App. D: a grain is in a class when both its Q4^loc and Q6^loc are within this of it.
pub const ENVIRONMENT_HALF_WIDTH: f64 = 0.05;

/// AR07 T.VII–T.VIII for one bond length: fractions of all grains whose (Q4^loc(i), Q6^loc(i))
/// lie within ±0.05 of the fcc-like, the hcp-like and each Aste sample's disordered mode.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LocalEnvironments {
    /// d_c/a.
    pub cutoff: f64,
    pub fcc: f64,
    pub hcp: f64,
    /// *dis* for each sample of [`ASTE_MODES`], in its order.
    pub disordered: Vec<(String, f64)>,
    /// hcp-like grains outside each sample's disordered box, in the same order: the hcp box
    /// overlaps sample F's disordered one at d_c = 1.2a and 1.3a, and App. D does not say
    /// which class a grain in both belongs to.
    pub hcp_outside: Vec<(String, f64)>,
}

/// AR07 T.VII–T.VIII on a 3D snapshot, for d_c = 1.1a, 1.2a, 1.3a, 1.4a (a the largest
/// diameter). Grains without bonds are in no class. `None` unless 3D, or for a bad cell or a.
pub fn local_environments(
    lengths: &[f64],
    position: &[impl std::ops::Deref<Target = [f64]>],
    a: f64,
) -> Option<Vec<LocalEnvironments>> {
    if lengths.len() != 3 || !valid_cell(lengths) || !(a > 0.0 && a.is_finite()) {
        return None;
    }
    let n = position.len().max(1) as f64;
    let within = |q: (f64, f64), mode: (f64, f64)| {
        (q.0 - mode.0).abs() <= ENVIRONMENT_HALF_WIDTH
            && (q.1 - mode.1).abs() <= ENVIRONMENT_HALF_WIDTH
    };
    let pts = points(3, position);
    let per_cutoff = (0..4).map(|k| {
        let cutoff = ASTE_MODES[0].1[k].0;
        let q = local_orders(lengths, &pts, cutoff * a);
        let fraction = |class: &dyn Fn((f64, f64)) -> bool| {
            q.iter().flatten().filter(|&&x| class(x)).count() as f64 / n
        };
        let dis = |modes: &[(f64, f64, f64); 4]| (modes[k].1, modes[k].2);
        LocalEnvironments {
            cutoff,
            fcc: fraction(&|x| within(x, FCC_LIKE)),
            hcp: fraction(&|x| within(x, HCP_LIKE)),
            disordered: ASTE_MODES
                .iter()
                .map(|(name, modes)| (name.to_string(), fraction(&|x| within(x, dis(modes)))))
                .collect(),
            hcp_outside: ASTE_MODES
                .iter()
                .map(|(name, modes)| {
                    let class = |x| within(x, HCP_LIKE) && !within(x, dis(modes));
                    (name.to_string(), fraction(&class))
                })
                .collect(),
        }
    });
    Some(per_cutoff.collect())
}

/// Crystalline clusters: connected components of the crystalline grains through the bonds
/// that `pairs` walks (it calls its argument once per bond `(i, j)`).
/// Returns (number of clusters, mass-average size Σ n_c²/Σ n_c, largest size).
pub fn crystalline_clusters(
    crystalline: &[bool],
    pairs: impl FnOnce(&mut dyn FnMut(usize, usize)),
) -> (usize, Option<f64>, usize) {
    let n = crystalline.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    pairs(&mut |i, j| {
        if i < n && j < n && crystalline[i] && crystalline[j] {
            let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
            if ri != rj {
                parent[ri.max(rj)] = ri.min(rj);
            }
        }
    });
    let mut size = vec![0usize; n];
    for g in (0..n).filter(|&g| crystalline[g]) {
        let r = find(&mut parent, g);
        size[r] += 1;
    }
    let sizes: Vec<usize> = size.into_iter().filter(|&s| s > 0).collect();
    let total: usize = sizes.iter().sum();
    let mass =
        (total > 0).then(|| sizes.iter().map(|&s| (s * s) as f64).sum::<f64>() / total as f64);
    (sizes.len(), mass, sizes.iter().copied().max().unwrap_or(0))
}

/// AR07 T.II on a 3D snapshot: bonds shorter than `cutoff_over_a · a`, a the largest
/// diameter. `None` unless 3D, or for a bad cell or a. Defined (with `None` entries) when
/// there are no bonds.
pub fn bond_order(
    lengths: &[f64],
    position: &[impl std::ops::Deref<Target = [f64]>],
    a: f64,
    cutoff_over_a: f64,
) -> Option<BondOrder> {
    if lengths.len() != 3 || !valid_cell(lengths) || !(a > 0.0 && a.is_finite()) {
        return None;
    }
    if !(cutoff_over_a > 0.0 && cutoff_over_a.is_finite()) {
        return None;
    }
    let n = position.len();
    let pts = points(3, position);
    let cutoff = cutoff_over_a * a;
    let b = bonds(lengths, &pts, cutoff);
    let nb = b.total;
    let per_grain = |x: usize| {
        if n > 0 {
            2.0 * x as f64 / n as f64
        } else {
            0.0
        }
    };

    // Local order.
    let bonded: Vec<usize> = (0..n).filter(|&g| b.count[g] > 0).collect();
    let (q4loc, q6loc): (Vec<f64>, Vec<f64>) =
        (0..n).map(|g| b.local(g).unwrap_or((0.0, 0.0))).unzip();
    let mean_over = |v: &[f64], set: &[usize]| {
        (!set.is_empty()).then(|| set.iter().map(|&g| v[g]).sum::<f64>() / set.len() as f64)
    };

    // Global order.
    let global = |l: usize, sum: &[f64]| (nb > 0).then(|| q_norm(l, sum) / nb as f64);

    // Crystalline bonds, AR07 (33)–(34).
    // |q6| of each grain (NaN where q6 vanishes or is not finite: no crystalline bond); the
    // product of the unit vectors is taken pair by pair, without a normalized copy of q6.
    let norm6: Vec<f64> =
        b.q6.iter()
            .map(|q| {
                let s = q.iter().map(|x| x * x).sum::<f64>().sqrt();
                if s > 0.0 && s.is_finite() {
                    s
                } else {
                    f64::NAN
                }
            })
            .collect();
    let mut cr_of = vec![0u32; n];
    let mut crystalline_bonds = 0;
    for_each_bond(lengths, &pts, cutoff, |i, j, _| {
        if !(norm6[i].is_nan() || norm6[j].is_nan()) {
            let (qi, qj) = (&b.q6[i], &b.q6[j]);
            let s: f64 = qi
                .iter()
                .zip(qj)
                .map(|(x, y)| (x / norm6[i]) * (y / norm6[j]))
                .sum();
            if s.abs() >= CRYSTALLINE_PRODUCT {
                crystalline_bonds += 1;
                cr_of[i] += 1;
                cr_of[j] += 1;
            }
        }
    });
    let crystalline: Vec<bool> = cr_of
        .iter()
        .map(|&k| k as usize >= CRYSTALLINE_BONDS)
        .collect();
    let cr_set: Vec<usize> = (0..n).filter(|&g| crystalline[g]).collect();
    let (clusters, n_cr, largest_cluster) = crystalline_clusters(&crystalline, |each| {
        for_each_bond(lengths, &pts, cutoff, |i, j, _| each(i, j))
    });

    Some(BondOrder {
        cutoff: cutoff_over_a,
        bonds: nb,
        z_bond: per_grain(nb),
        q4_global: global(4, &b.g4),
        q6_global: global(6, &b.g6),
        q4_local: mean_over(&q4loc, &bonded),
        q6_local: mean_over(&q6loc, &bonded),
        crystalline_bonds,
        z_cr: per_grain(crystalline_bonds),
        crystalline_grains: cr_set.len(),
        x_cr: if n > 0 {
            cr_set.len() as f64 / n as f64
        } else {
            0.0
        },
        q6_local_cr: mean_over(&q6loc, &cr_set),
        clusters,
        n_cr,
        largest_cluster,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::fixtures::Lcg;

    fn legendre(l: usize, x: f64) -> f64 {
        legendre_assoc(l, 0, x)
    }

    fn unit(rng: &mut Lcg) -> [f64; 3] {
        loop {
            let v = [
                2.0 * rng.next() - 1.0,
                2.0 * rng.next() - 1.0,
                2.0 * rng.next() - 1.0,
            ];
            let s = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if s > 0.1 && s < 1.0 {
                return [v[0] / s, v[1] / s, v[2] / s];
            }
        }
    }

    fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    /// Q_l by the addition theorem: Q_l² = (1/N²) Σ_{j,k} P_l(n_j·n_k). Independent of the
    /// harmonics.
    fn q_l_legendre(l: usize, dirs: &[[f64; 3]]) -> f64 {
        let mut s = 0.0;
        for u in dirs {
            for v in dirs {
                s += legendre(l, dot(u, v));
            }
        }
        s.sqrt() / dirs.len() as f64
    }

    /// Addition theorem Σ_m Y_lm(u) Y_lm(v) = (2l+1)/(4π) P_l(u·v) for l ≤ 8, plus
    /// Y_00 = 1/√(4π), Y_10 = √(3/4π) z, P_2, P_4.
    #[test]
    fn harmonics_satisfy_the_addition_theorem() {
        let mut rng = Lcg(3);
        for _ in 0..50 {
            let (u, v) = (unit(&mut rng), unit(&mut rng));
            for l in 0..=8 {
                let (yu, yv) = (
                    real_spherical_harmonics(l, &u),
                    real_spherical_harmonics(l, &v),
                );
                let s: f64 = yu.iter().zip(&yv).map(|(a, b)| a * b).sum();
                let want = (2 * l + 1) as f64 / (4.0 * PI) * legendre(l, dot(&u, &v));
                assert!((s - want).abs() < 1e-12, "l = {l}: {s} vs {want}");
            }
            let y0 = real_spherical_harmonics(0, &u);
            assert!((y0[0] - 1.0 / (4.0 * PI).sqrt()).abs() < 1e-15);
            let y1 = real_spherical_harmonics(1, &u);
            assert!((y1[1] - (3.0 / (4.0 * PI)).sqrt() * u[2]).abs() < 1e-14);
        }
        let x: f64 = 0.3;
        assert!((legendre(2, x) - (3.0 * x * x - 1.0) / 2.0).abs() < 1e-15);
        let p4 = (35.0 * x.powi(4) - 30.0 * x * x + 3.0) / 8.0;
        assert!((legendre(4, x) - p4).abs() < 1e-15);
    }

    /// Q_l of a neighbour set is rotation invariant and agrees with the addition theorem.
    #[test]
    fn q_l_is_rotation_invariant() {
        let mut rng = Lcg(9);
        let dirs: Vec<[f64; 3]> = (0..9).map(|_| unit(&mut rng)).collect();
        // Rotation by angle t about the unit axis k (Rodrigues).
        let (k, t) = (unit(&mut rng), 1.234f64);
        let rot = |v: &[f64; 3]| {
            let c = [
                k[1] * v[2] - k[2] * v[1],
                k[2] * v[0] - k[0] * v[2],
                k[0] * v[1] - k[1] * v[0],
            ];
            let kv = dot(&k, v);
            let mut r = [0.0; 3];
            for a in 0..3 {
                r[a] = v[a] * t.cos() + c[a] * t.sin() + k[a] * kv * (1.0 - t.cos());
            }
            r
        };
        let turned: Vec<[f64; 3]> = dirs.iter().map(rot).collect();
        for l in [2, 4, 6, 8] {
            let q = q_l(l, &dirs).unwrap();
            assert!((q - q_l(l, &turned).unwrap()).abs() < 1e-12);
            assert!((q - q_l_legendre(l, &dirs)).abs() < 1e-12);
        }
        assert_eq!(q_l(6, &[]), None);
    }

    /// A periodic crystal: `cells` unit cells with the given basis (fractions of the cell).
    fn crystal(cells: [usize; 3], side: [f64; 3], basis: &[[f64; 3]]) -> (Vec<f64>, Vec<Vec<f64>>) {
        let mut p = Vec::new();
        for x in 0..cells[0] {
            for y in 0..cells[1] {
                for z in 0..cells[2] {
                    for b in basis {
                        let c = [x as f64, y as f64, z as f64];
                        p.push((0..3).map(|a| (c[a] + b[a]) * side[a]).collect());
                    }
                }
            }
        }
        ((0..3).map(|a| cells[a] as f64 * side[a]).collect(), p)
    }

    fn fcc() -> (Vec<f64>, Vec<Vec<f64>>) {
        let c = 2f64.sqrt();
        let basis = [
            [0.0, 0.0, 0.0],
            [0.5, 0.5, 0.0],
            [0.5, 0.0, 0.5],
            [0.0, 0.5, 0.5],
        ];
        crystal([3, 3, 3], [c; 3], &basis)
    }

    fn hcp() -> (Vec<f64>, Vec<Vec<f64>>) {
        let (b, c) = (3f64.sqrt(), (8.0f64 / 3.0).sqrt());
        let basis = [
            [0.0, 0.0, 0.0],
            [0.5, 0.5, 0.0],
            [0.5, 1.0 / 6.0, 0.5],
            [0.0, 2.0 / 3.0, 0.5],
        ];
        crystal([4, 2, 2], [1.0, b, c], &basis)
    }

    fn bcc() -> (Vec<f64>, Vec<Vec<f64>>) {
        let c = 2.0 / 3f64.sqrt();
        crystal([3, 3, 3], [c; 3], &[[0.0; 3], [0.5; 3]])
    }

    fn sc() -> (Vec<f64>, Vec<Vec<f64>>) {
        crystal([4, 4, 4], [1.0; 3], &[[0.0; 3]])
    }

    /// Bond directions of every bond, for the Legendre cross-check of the global order.
    fn all_bond_dirs(l: &[f64], p: &[Vec<f64>], cut: f64) -> Vec<[f64; 3]> {
        let mut v = Vec::new();
        for_each_pair(l, &points(3, p), cut, |_, _, r, r2| {
            let s = r2.sqrt();
            v.push([r[0] / s, r[1] / s, r[2] / s]);
        });
        v
    }

    /// Perfect FCC (nearest neighbours at a, next at √2 a > 1.35a): 12 bonds per grain,
    /// Q6 = 0.5745 and Q4 = 0.1909 both locally and globally, every bond crystalline,
    /// every grain crystalline, one cluster of all grains.
    #[test]
    fn fcc_order() {
        let (l, p) = fcc();
        let n = p.len();
        let b = bond_order(&l, &p, 1.0, DEFAULT_CUTOFF).unwrap();
        assert_eq!(b.bonds, 6 * n);
        assert_eq!(b.z_bond, 12.0);
        for q in [b.q6_local, b.q6_global] {
            assert!((q.unwrap() - 0.5745).abs() < 5e-5, "{q:?}");
        }
        for q in [b.q4_local, b.q4_global] {
            assert!((q.unwrap() - 0.1909).abs() < 5e-5, "{q:?}");
        }
        assert_eq!(b.crystalline_bonds, 6 * n);
        assert_eq!(b.z_cr, 12.0);
        assert_eq!((b.crystalline_grains, b.x_cr), (n, 1.0));
        assert!((b.q6_local_cr.unwrap() - b.q6_local.unwrap()).abs() < 1e-12);
        assert_eq!((b.clusters, b.largest_cluster), (1, n));
        assert_eq!(b.n_cr, Some(n as f64));
        // Per-grain values are all the same.
        let q6 = local_order(&l, &p, 1.0, DEFAULT_CUTOFF, 6).unwrap();
        assert!(q6
            .iter()
            .all(|q| (q.unwrap() - b.q6_local.unwrap()).abs() < 1e-12));
    }

    /// AR07 T.VII–T.VIII classes: every grain of a perfect FCC crystal is fcc-like and every
    /// grain of an HCP one hcp-like at each d_c = 1.1a…1.4a (second neighbours at √2 a);
    /// neither is in any disordered mode; a dilute simple cubic lattice (no bonds) is in none.
    #[test]
    fn local_environments_of_crystals() {
        for (lattice, fcc_like) in [(fcc(), true), (hcp(), false)] {
            let (l, p) = lattice;
            let envs = local_environments(&l, &p, 1.0).unwrap();
            assert_eq!(
                envs.iter().map(|e| e.cutoff).collect::<Vec<_>>(),
                [1.1, 1.2, 1.3, 1.4]
            );
            for e in &envs {
                let (fcc, hcp) = if fcc_like { (1.0, 0.0) } else { (0.0, 1.0) };
                assert_eq!((e.fcc, e.hcp), (fcc, hcp), "{e:?}");
                let names: Vec<&str> = e.disordered.iter().map(|(s, _)| s.as_str()).collect();
                assert_eq!(names, ["F", "D", "B"]);
                assert!(e.disordered.iter().all(|(_, x)| *x == 0.0), "{e:?}");
                assert!(e.hcp_outside.iter().all(|(_, x)| *x == hcp), "{e:?}");
            }
        }
        let (l, p) = sc();
        let spread: Vec<Vec<f64>> = p
            .iter()
            .map(|x| x.iter().map(|c| 2.0 * c).collect())
            .collect();
        let wide: Vec<f64> = l.iter().map(|x| 2.0 * x).collect();
        for e in local_environments(&wide, &spread, 1.0).unwrap() {
            assert_eq!((e.fcc, e.hcp), (0.0, 0.0));
        }
        assert!(local_environments(&[4.0, 4.0], &[vec![0.0, 0.0]], 1.0).is_none());
    }

    /// The hcp box (0.097, 0.485) ± 0.05 overlaps the disordered box of Aste's sample F at
    /// d_c = 1.2a and 1.3a only (and sample D's at 1.2a and 1.3a), never sample B's: on the
    /// committed dense D packing the hcp-like grains outside a box are those of the hcp box less
    /// some grains there, and all of them where the boxes are disjoint.
    #[test]
    fn hcp_like_grains_outside_the_disordered_modes() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../reference-inputs/starts/ar07-D-10kPa-n4000.snap.json"
        );
        let s = grainbench_engine::snapshot::Snapshot::read(std::path::Path::new(path)).unwrap();
        let envs = local_environments(&s.cell.lengths, &s.particles.position, 1.0).unwrap();
        for e in &envs {
            let names: Vec<&str> = e.hcp_outside.iter().map(|(s, _)| s.as_str()).collect();
            assert_eq!(names, ["F", "D", "B"]);
            for ((_, outside), (_, dis)) in e.hcp_outside.iter().zip(&e.disordered) {
                assert!(*outside <= e.hcp && e.hcp - outside <= *dis, "{e:?}");
            }
            let overlaps = [1.2, 1.3].contains(&e.cutoff);
            let outside_f = e.hcp_outside[0].1;
            assert_eq!(outside_f < e.hcp, overlaps, "{e:?}");
            assert_eq!(e.hcp_outside[2].1, e.hcp, "{e:?}");
        }
    }

    /// Perfect HCP: Q6 = 0.4848, Q4 = 0.0972, local and global. The two stacking sites have
    /// environments turned by 60° about c, which flips the m = ±3 parts of q_lm, but each
    /// environment is mirror-symmetric about the basal plane, so those parts vanish for even l
    /// and both sites share q_lm: the global value equals the local one. Checked against the
    /// addition theorem over all bond pairs, and on the normalised product of an A–B bond.
    #[test]
    fn hcp_order() {
        let (l, p) = hcp();
        let n = p.len();
        let b = bond_order(&l, &p, 1.0, DEFAULT_CUTOFF).unwrap();
        assert_eq!(b.z_bond, 12.0);
        for q in [b.q6_local, b.q6_global] {
            assert!((q.unwrap() - 0.4848).abs() < 5e-5, "{q:?}");
        }
        for q in [b.q4_local, b.q4_global] {
            assert!((q.unwrap() - 0.0972).abs() < 5e-5, "{q:?}");
        }
        let dirs = all_bond_dirs(&l, &p, DEFAULT_CUTOFF);
        assert_eq!(dirs.len(), 6 * n);
        assert!((b.q6_global.unwrap() - q_l_legendre(6, &dirs)).abs() < 1e-12);
        assert!((b.q4_global.unwrap() - q_l_legendre(4, &dirs)).abs() < 1e-12);
        // Normalised product of an A site (grain 0) and a B site (grain 2), by Legendre sums.
        let nb = |g: usize| -> Vec<[f64; 3]> {
            let pts = points(3, &p);
            let mut v = Vec::new();
            for h in 0..n {
                let r = crate::metrics::neighbors::separation(&l, &pts[g], &pts[h]);
                let s = crate::metrics::neighbors::norm2(&r).sqrt();
                if h != g && s < DEFAULT_CUTOFF {
                    v.push([r[0] / s, r[1] / s, r[2] / s]);
                }
            }
            v
        };
        let (na, nbb) = (nb(0), nb(2));
        let cross: f64 = na
            .iter()
            .flat_map(|u| nbb.iter().map(move |v| legendre(6, dot(u, v))))
            .sum();
        let prod =
            cross / (q_l_legendre(6, &na) * q_l_legendre(6, &nbb) * (na.len() * nbb.len()) as f64);
        assert!((prod - 1.0).abs() < 1e-12, "{prod}");
        assert_eq!(b.crystalline_bonds, 6 * n);
        assert_eq!((b.x_cr, b.clusters), (1.0, 1));
    }

    /// BCC with d_c = 1.35a: 8 + 6 neighbours, Q6 = 0.5107, Q4 = 0.0364 (local = global),
    /// all 14 bonds crystalline. Simple cubic: 6 neighbours, Q6 = 0.3536, Q4 = 0.7638, all
    /// bonds crystalline but 6 < 7: no crystalline grain.
    #[test]
    fn bcc_and_simple_cubic_order() {
        let (l, p) = bcc();
        let b = bond_order(&l, &p, 1.0, DEFAULT_CUTOFF).unwrap();
        assert_eq!(b.z_bond, 14.0);
        for q in [b.q6_local, b.q6_global] {
            assert!((q.unwrap() - 0.5107).abs() < 5e-5, "{q:?}");
        }
        for q in [b.q4_local, b.q4_global] {
            assert!((q.unwrap() - 0.0364).abs() < 5e-5, "{q:?}");
        }
        assert_eq!((b.z_cr, b.x_cr), (14.0, 1.0));
        // With d_c = 1.1a only the 8 nearest neighbours: Q6 = 0.6285, Q4 = 0.5092.
        let b8 = bond_order(&l, &p, 1.0, 1.1).unwrap();
        assert_eq!(b8.z_bond, 8.0);
        assert!((b8.q6_local.unwrap() - 0.6285).abs() < 5e-5);
        assert!((b8.q4_local.unwrap() - 0.5092).abs() < 5e-5);

        let (l, p) = sc();
        let b = bond_order(&l, &p, 1.0, DEFAULT_CUTOFF).unwrap();
        assert_eq!(b.z_bond, 6.0);
        assert!((b.q6_local.unwrap() - 0.3536).abs() < 5e-5);
        assert!((b.q4_local.unwrap() - 0.7638).abs() < 5e-5);
        assert!((b.q6_global.unwrap() - 0.3536).abs() < 5e-5);
        assert_eq!((b.crystalline_bonds, b.z_cr), (p.len() * 3, 6.0));
        assert_eq!((b.crystalline_grains, b.x_cr), (0, 0.0));
        assert_eq!((b.q6_local_cr, b.n_cr, b.clusters), (None, None, 0));
    }

    /// Mass average of cluster sizes: clusters {0,1,2} and {4} (3 is not crystalline and
    /// does not connect them): (9 + 1)/4.
    #[test]
    fn cluster_mass_average() {
        let cr = [true, true, true, false, true];
        const PAIRS: [(usize, usize); 4] = [(0, 1), (2, 1), (2, 3), (3, 4)];
        let walk = |pairs: &'static [(usize, usize)]| {
            move |each: &mut dyn FnMut(usize, usize)| pairs.iter().for_each(|&(i, j)| each(i, j))
        };
        assert_eq!(crystalline_clusters(&cr, walk(&PAIRS)), (2, Some(2.5), 3));
        assert_eq!(
            crystalline_clusters(&[false; 3], walk(&PAIRS[..1])),
            (0, None, 0)
        );
    }

    /// 2D, no bonds, degenerate cells.
    #[test]
    fn bond_order_where_undefined() {
        let p = vec![vec![0.0, 0.0]];
        assert!(bond_order(&[2.0, 2.0], &p, 1.0, 1.35).is_none());
        let p = vec![vec![0.0, 0.0, 0.0], vec![3.0, 3.0, 3.0]];
        let b = bond_order(&[8.0; 3], &p, 1.0, 1.35).unwrap();
        assert_eq!(
            (b.bonds, b.z_bond, b.q6_local, b.q6_global),
            (0, 0.0, None, None)
        );
        assert!(bond_order(&[8.0, 0.0, 8.0], &p, 1.0, 1.35).is_none());
        assert!(bond_order(&[8.0; 3], &p, 0.0, 1.35).is_none());
        let e: Vec<Vec<f64>> = Vec::new();
        assert_eq!(bond_order(&[8.0; 3], &e, 1.0, 1.35).unwrap().x_cr, 0.0);
    }
}
