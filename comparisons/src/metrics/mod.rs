//! Packing metrics of one snapshot (SPEC §5): Φ, z, rattlers, z*, x_k, force moments,
//! friction mobilisation, and the exact pressure/force relations AR07 (22), GRC07 (17)–(18).
//!
//! # Which contacts count
//!
//! * Cohesionless snapshots: a contact *carries force* if `|N| > force_tolerance · ⟨|N|⟩`, the
//!   mean taken over all listed contacts (AR07 §III.B, GRC07 §III.A: forces below the
//!   equilibrium tolerance are ignored). The rattler rule then runs on those contacts, and
//!   `N_c` counts the force-carrying contacts between backbone grains (AR07 §III.B:
//!   `z = 2N_c/n`, "thereby discarding possible contacts of the rattlers").
//! * Cohesive snapshots: every listed interaction (contact or distant attraction) counts,
//!   split into repulsive `N > tol`, attractive `N < −tol` and unstressed `|N| ≤ tol`, with the
//!   absolute tolerance `cohesive_tolerance = 1e-4` (F0 = 1 is the force unit), so that
//!   `z = z+ + z− + z0` (GRC07 T.VI: e.g. z = 2.004 = 0.12 + 0.12 + 1.76). Unstressed
//!   contacts sit at the deflection h0 and may carry tangential force up to μF0 (GRC07 (11)).
//!
//! Force statistics (⟨N⟩, Z(α), X1, M1, M2, P(f), the AR07 T.VI breakdown, the GRC07 Fig. 15
//! angles: [`crate::force_distribution`]) use the same set of contacts as `z`, so that
//! `z⟨N⟩ = (2/n) Σ N` enters the pressure relations consistently.
//!
//! # Geometry
//!
//! g(r) and z(h) ([`crate::structure`]), bond-orientational order ([`mod@crate::bond_order`], 3D)
//! and the variant II of x_k with the rattlers fixed onto the backbone
//! ([`crate::fixed_rattlers`]) are measured on the positions, in units of a = the largest
//! diameter. [`Analysis::metric_values`] lists every scalar under a canonical key.
//!
//! # Pressure relations
//!
//! With `σ_αβ = (1/Ω) Σ F_α r_β` (AR07 (8), contact part, compressive positive, `F` exerted by
//! `i` on `j`, `r = r_j − r_i`) and `F = N r/|r| + T`,
//! `P = tr σ / d = (1/(dΩ)) Σ (N |r| + T·r)` exactly; `T·r = 0` as `T ⟂ r`. This is
//! [`Pressure::exact`], summed over *all* listed contacts like the stress written by the code.
//! Neglecting deflections (`|r| ≈ (d_i + d_j)/2`) and size–force correlations gives GRC07 (17)
//! `P = (1/π) (⟨d⟩/⟨d^D⟩) zΦ ⟨N⟩`, which is AR07 (22) `P = zΦ⟨N⟩/(πa²)` for equal spheres and
//! GRC07 (18) `⟨N⟩ = 7πaP/(9zΦ)` for disk diameters uniform in `[a/2, a]` (`⟨d⟩ = 3a/4`,
//! `⟨d²⟩ = 7a²/12`).

use crate::bond_order::{bond_order, BondOrder, DEFAULT_CUTOFF};
use crate::fixed_rattlers::{fix_rattlers, FixedRattlers, DEFAULT_SEED};
use crate::force_distribution::force_stats;
pub use crate::force_distribution::{ForceStats, PopulationStats};
use crate::rattlers::{find_rattlers, Rule};
use crate::structure::{
    default_gap_grid, gap_coordination, pair_correlation, unit_length, Structure,
};
use grainbench_engine::snapshot::{Contact, Snapshot};
use serde::Serialize;
use std::f64::consts::PI;

/// Largest contact number given its own `x_k` entry at least (more are added if present).
pub const X_K_MIN_LEN: usize = 13;

/// Analysis settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Options {
    /// Cohesionless laws: a contact carries force if `|N| > force_tolerance · ⟨|N|⟩`.
    pub force_tolerance: f64,
    /// Cohesive laws: `|N| ≤ cohesive_tolerance` (in F0) is "unstressed" (GRC07 T.VI: 1e-4 F0).
    pub cohesive_tolerance: f64,
    /// Rattler rule; `None` picks [`Rule::for_snapshot`].
    pub rule: Option<Rule>,
    /// Bin width of P(f), in f = N/⟨N⟩.
    pub pdf_bin_width: f64,
    /// Bin width of the force-angle histogram (GRC07 Fig. 15), degrees.
    pub angle_bin_width: f64,
    /// Bin width and range of g(r), in a (the range is clipped to half the cell).
    pub gr_bin_width: f64,
    pub gr_r_max: f64,
    /// Largest h/a of z(h) (grid: 0, then 10 points per decade from 1e-5).
    pub gap_h_max: f64,
    /// Bond length d_c/a of the bond-orientational order (AR07 T.II: 1.35 or 1.40).
    pub bond_cutoff: f64,
    /// Fix the rattlers onto the backbone for x_k^II and z^II(h) (AR07 §III.C, variant II).
    pub fix_rattlers: bool,
    /// Seed of the random force directions on the rattlers (variant II).
    pub seed: u64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            force_tolerance: 1e-6,
            cohesive_tolerance: 1e-4,
            rule: None,
            pdf_bin_width: 0.1,
            angle_bin_width: 5.0,
            gr_bin_width: 0.01,
            gr_r_max: 5.0,
            gap_h_max: 1.0,
            bond_cutoff: DEFAULT_CUTOFF,
            fix_rattlers: true,
            seed: DEFAULT_SEED,
        }
    }
}

/// Everything [`analyze`] measures on one snapshot.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Analysis {
    /// Copied from the snapshot.
    pub scene: String,
    pub code: String,
    pub status: String,
    pub step: u64,
    pub time: f64,
    pub dimension: usize,
    pub cohesive: bool,
    pub mu: Option<f64>,
    /// Number of grains.
    pub n: usize,
    /// Solid fraction Φ ([`Snapshot::packing_fraction`]).
    pub packing_fraction: f64,
    /// Rattler rule used.
    pub rule: Rule,
    /// Number of listed interactions (contacts and distant attractions).
    pub interactions: usize,
    /// Absolute force threshold used (`force_tolerance·⟨|N|⟩`, or `cohesive_tolerance`).
    pub force_threshold: f64,
    /// Listed interactions with `|N|` above the threshold (before rattler removal).
    pub force_carrying: usize,
    /// N_c: counted contacts between backbone grains (AR07 §III.B).
    pub contacts: usize,
    /// z = 2N_c/n (AR07 §III.B, GRC07 (13)).
    pub z: f64,
    /// Number of rattlers and x0 = their fraction of n.
    pub rattlers: usize,
    pub rattler_fraction: f64,
    /// z* = z/(1 − x0) (AR07 §III.B, GRC07 (13)); `None` if every grain is a rattler.
    pub z_backbone: Option<f64>,
    /// Removal sweeps the rattler algorithm needed (AR07: one, rarely two).
    pub rattler_sweeps: usize,
    /// x_k, k = 0, 1, …: fraction of *all* n grains with k counted contacts, contacts with or
    /// between rattlers ignored (AR07 T.I and T.V, variant I); `x_k[0]` = x0, Σ x_k = 1.
    /// At least [`X_K_MIN_LEN`] entries (k = 0..=12).
    pub x_k: Vec<f64>,
    /// Variant II (AR07 T.I, T.V): rattlers fixed onto the backbone, x_k^II and z^II(0);
    /// `None` if disabled or if there is no backbone to fix them onto.
    pub fixed_rattlers: Option<FixedRattlers>,
    /// Cohesive snapshots: z+ / z− / z0 split and force levels (GRC07 T.VI).
    pub cohesive_split: Option<CohesiveSplit>,
    /// Normal-force distribution and friction mobilisation (AR07 (27), Figs. 4, 15, T.IV,
    /// T.VI; GRC07 Fig. 15).
    pub forces: ForceStats,
    /// g(r) and z(h) (AR07 §III.D).
    pub structure: Structure,
    /// Bond-orientational order and crystallinity (AR07 (31)–(34), T.II); 3D only.
    pub bond_order: Option<BondOrder>,
    /// Measured pressure and the exact relations.
    pub pressure: Pressure,
}

impl Analysis {
    /// Every scalar metric under its canonical key (fractions, not percent), for tables
    /// comparing with the papers. Keys whose metric is undefined for this snapshot (Q6 in
    /// 2D, z± without cohesion, N^(2) without divalent grains, …) are left out.
    ///
    /// `phi`, `z`, `z_star`, `x0`, `xk2`…`xk12` (x_k, variant I), `xk2_II`…`xk12_II`,
    /// `mean_N`, `Z2`, `Z5_3`, `X1`, `M1`, `M2`, `N_2`, `X1_2`, `M1_2`, `M2_2`, `N_3`, `X1_3`,
    /// `M1_3`, `M2_3`, `Q4`, `Q6`, `Q4loc`, `Q6loc`, `Z_bond`, `Z_cr`, `Q6loc_cr`, `x_cr`,
    /// `n_cr`, `z_plus`, `z_minus`, `z_zero`, `pressure` (measured).
    pub fn metric_values(&self) -> Vec<(String, f64)> {
        let mut v: Vec<(String, f64)> = Vec::new();
        let mut put = |k: &str, x: Option<f64>| {
            if let Some(x) = x.filter(|x| x.is_finite()) {
                v.push((k.to_string(), x));
            }
        };
        put("phi", Some(self.packing_fraction));
        put("z", Some(self.z));
        put("z_star", self.z_backbone);
        put("x0", Some(self.rattler_fraction));
        for k in 2..=12 {
            put(
                &format!("xk{k}"),
                Some(self.x_k.get(k).copied().unwrap_or(0.0)),
            );
        }
        if let Some(f) = &self.fixed_rattlers {
            for k in 2..=12 {
                put(
                    &format!("xk{k}_II"),
                    Some(f.x_k.get(k).copied().unwrap_or(0.0)),
                );
            }
        }
        let f = &self.forces;
        put("mean_N", f.mean_normal);
        put("Z2", f.z2);
        put("Z5_3", f.z5_3);
        put("X1", f.x1);
        put("M1", f.m1);
        put("M2", f.m2);
        for (k, pop) in [(2, &f.coordination_2), (3, &f.coordination_3)] {
            if let Some(p) = pop {
                put(&format!("N_{k}"), p.mean_normal_reduced);
                put(&format!("X1_{k}"), Some(p.x1));
                put(&format!("M1_{k}"), p.m1);
                put(&format!("M2_{k}"), p.m2);
            }
        }
        if let Some(b) = &self.bond_order {
            put("Q4", b.q4_global);
            put("Q6", b.q6_global);
            put("Q4loc", b.q4_local);
            put("Q6loc", b.q6_local);
            put("Z_bond", Some(b.z_bond));
            put("Z_cr", Some(b.z_cr));
            put("Q6loc_cr", b.q6_local_cr);
            put("x_cr", Some(b.x_cr));
            put("n_cr", b.n_cr);
        }
        if let Some(s) = &self.cohesive_split {
            put("z_plus", Some(s.z_plus));
            put("z_minus", Some(s.z_minus));
            put("z_zero", Some(s.z_zero));
        }
        put("pressure", self.pressure.measured);
        v
    }
}

/// GRC07 T.VI: interactions split by the sign of N (tolerance `cohesive_tolerance`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CohesiveSplit {
    /// Contributions to z of repulsive (N > tol), attractive (N < −tol), unstressed (|N| ≤ tol)
    /// interactions, over backbone grains: z = z_plus + z_minus + z_zero.
    pub z_plus: f64,
    pub z_minus: f64,
    pub z_zero: f64,
    /// Interactions with a positive gap (distant attractions, GRC07 §III.A).
    pub distant: usize,
    /// N+ and N+^(2): mean and quadratic mean of repulsive forces.
    pub mean_repulsive: Option<f64>,
    pub rms_repulsive: Option<f64>,
    /// N− and N−^(2): mean and quadratic mean of |N| over attractive forces.
    pub mean_attractive: Option<f64>,
    pub rms_attractive: Option<f64>,
}

/// Measured pressure and the exact or approximate relations that predict it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Pressure {
    /// P = tr(σ_contact)/d, as written in the snapshot; `None` if the stress is malformed.
    pub measured: Option<f64>,
    /// Kinetic part tr(σ_kinetic)/d.
    pub kinetic: Option<f64>,
    /// (1/(dΩ)) Σ_all listed (N|r| + T·r): must equal `measured` (AR07 (8)).
    pub exact: f64,
    /// (exact − measured)/|measured|.
    pub exact_rel_diff: Option<f64>,
    /// Tangential part (1/(dΩ)) Σ T·r alone (0 when T ⟂ r).
    pub exact_tangential: f64,
    /// GRC07 (17), any dimension and size distribution.
    pub rumpf: Option<Rumpf>,
    /// AR07 (22), 3D with all radii equal.
    pub ar07_22: Option<Ar07Eq22>,
    /// GRC07 (18), 2D.
    pub grc07_18: Option<Grc07Eq18>,
}

/// GRC07 (17): `⟨N⟩ = π ⟨d^D⟩ P / (⟨d⟩ zΦ)` with the measured diameter moments.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Rumpf {
    /// ⟨d⟩ and ⟨d^D⟩ over grains.
    pub mean_diameter: f64,
    pub mean_diameter_pow_d: f64,
    pub mean_normal_predicted: f64,
    pub mean_normal_measured: f64,
    /// (predicted − measured)/|measured|; `None` if ⟨N⟩ = 0.
    pub rel_diff: Option<f64>,
}

/// AR07 (22): `P = zΦ⟨N⟩/(πa²)`, monodisperse spheres, deflections neglected.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Ar07Eq22 {
    /// Sphere diameter a.
    pub diameter: f64,
    pub p_predicted: f64,
    pub p_measured: f64,
    /// (predicted − measured)/|measured|; of order of the overlaps h/a.
    pub rel_diff: f64,
}

/// GRC07 (18): `⟨N⟩ = 7πaP/(9zΦ)`, a = largest diameter, diameters uniform in `[a/2, a]`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Grc07Eq18 {
    /// Largest diameter a.
    pub a: f64,
    /// ⟨d⟩/a and ⟨d²⟩/a²: 3/4 and 7/12 for the uniform distribution the formula assumes.
    pub mean_diameter_over_a: f64,
    pub mean_diameter_sq_over_a2: f64,
    pub mean_normal_predicted: f64,
    pub mean_normal_measured: f64,
    /// (predicted − measured)/|measured|; `None` if ⟨N⟩ = 0.
    pub rel_diff: Option<f64>,
}

/// Relative difference `(x − reference)/|reference|`, `None` for a zero reference.
fn rel_diff(x: f64, reference: f64) -> Option<f64> {
    (reference != 0.0 && reference.is_finite()).then(|| (x - reference) / reference.abs())
}

fn mean(xs: impl Iterator<Item = f64>) -> Option<f64> {
    let (s, k) = xs.fold((0.0, 0usize), |(s, k), x| (s + x, k + 1));
    (k > 0).then(|| s / k as f64)
}

fn trace_over_d(m: &[Vec<f64>], d: usize) -> Option<f64> {
    if m.len() != d || m.iter().any(|row| row.len() != d) {
        return None;
    }
    Some((0..d).map(|a| m[a][a]).sum::<f64>() / d as f64)
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Virial pressure of a set of contacts, split into normal and tangential parts:
/// `(1/(dΩ)) Σ N|r|` and `(1/(dΩ)) Σ T·r` (AR07 (8), trace).
pub fn contact_pressure(contacts: &[Contact], dimension: usize, volume: f64) -> (f64, f64) {
    let (mut pn, mut pt) = (0.0, 0.0);
    for c in contacts {
        pn += c.normal * norm(&c.branch);
        pt += dot(&c.tangential, &c.branch);
    }
    let f = 1.0 / (dimension as f64 * volume);
    (pn * f, pt * f)
}

/// Measures a snapshot. Expects a snapshot that passed [`Snapshot::check`] (as
/// [`Snapshot::read`] does).
///
/// # Panics
/// If a contact names a grain out of range.
pub fn analyze(snap: &Snapshot, opts: &Options) -> Analysis {
    let d = snap.dimension;
    let n = snap.particles.radius.len();
    let rule = opts.rule.unwrap_or_else(|| Rule::for_snapshot(snap));
    let volume: f64 = snap.cell.lengths.iter().product();
    let phi = snap.packing_fraction();
    let all = &snap.contacts;

    // Which interactions count, and the threshold.
    let threshold = if snap.cohesive {
        opts.cohesive_tolerance
    } else {
        opts.force_tolerance * mean(all.iter().map(|c| c.normal.abs())).unwrap_or(0.0)
    };
    let above = |c: &Contact| c.normal.abs() > threshold;
    let force_carrying = all.iter().filter(|c| above(c)).count();
    let counted: Vec<&Contact> = if snap.cohesive {
        all.iter().collect()
    } else {
        all.iter().filter(|c| above(c)).collect()
    };

    // Rattlers (AR07 §III.B).
    let pairs: Vec<(usize, usize)> = counted.iter().map(|c| (c.i, c.j)).collect();
    let r = find_rattlers(n, &pairs, rule);
    let backbone: Vec<&Contact> = counted
        .iter()
        .zip(&r.kept)
        .filter(|(_, &k)| k)
        .map(|(c, _)| *c)
        .collect();
    let nc = r.contacts;
    let nf = n as f64;
    let z = if n > 0 { 2.0 * nc as f64 / nf } else { 0.0 };
    let rattlers = r.count();
    let x0 = if n > 0 { rattlers as f64 / nf } else { 0.0 };
    let z_backbone = (rattlers < n).then(|| z / (1.0 - x0));

    // x_k, AR07 T.I / T.V variant I.
    let k_of = r.contact_numbers(n, &pairs);
    let kmax = k_of.iter().copied().max().unwrap_or(0);
    let mut x_k = vec![0.0; X_K_MIN_LEN.max(kmax + 1)];
    for &k in &k_of {
        x_k[k] += 1.0;
    }
    if n > 0 {
        x_k.iter_mut().for_each(|x| *x /= nf);
    }

    // GRC07 T.VI split.
    let cohesive_split = snap.cohesive.then(|| {
        let tol = opts.cohesive_tolerance;
        let rep: Vec<f64> = backbone
            .iter()
            .map(|c| c.normal)
            .filter(|&f| f > tol)
            .collect();
        let att: Vec<f64> = backbone
            .iter()
            .map(|c| -c.normal)
            .filter(|&f| f > tol)
            .collect();
        let per_grain = |k: usize| if n > 0 { 2.0 * k as f64 / nf } else { 0.0 };
        let rms = |v: &[f64]| mean(v.iter().map(|f| f * f)).map(f64::sqrt);
        CohesiveSplit {
            z_plus: per_grain(rep.len()),
            z_minus: per_grain(att.len()),
            z_zero: per_grain(nc - rep.len() - att.len()),
            distant: backbone.iter().filter(|c| c.gap > 0.0).count(),
            mean_repulsive: mean(rep.iter().copied()),
            rms_repulsive: rms(&rep),
            mean_attractive: mean(att.iter().copied()),
            rms_attractive: rms(&att),
        }
    });

    // Force statistics, AR07 (27), T.VI; GRC07 Fig. 15.
    let a = unit_length(&snap.particles.radius);
    let pressure_scale = match (snap.pressure_target, a) {
        (Some(p), Some(a)) => Some(p * a.powi(d as i32 - 1)),
        _ => None,
    };
    // P(f) in units of ⟨N⟩, or of F0 for cohesive packings (GRC07 Fig. 9).
    let pdf_unit = snap.cohesive.then_some(1.0);
    let forces = force_stats(
        &backbone,
        &k_of,
        pressure_scale,
        pdf_unit,
        opts.pdf_bin_width,
        opts.angle_bin_width,
    );
    let mean_n = forces.mean_normal;

    // Geometry: variant II, g(r), z(h), bond order.
    let lengths = &snap.cell.lengths;
    let position = &snap.particles.position;
    let radius = &snap.particles.radius;
    let kept: Vec<(usize, usize)> = pairs
        .iter()
        .zip(&r.kept)
        .filter(|(_, &k)| k)
        .map(|(p, _)| *p)
        .collect();
    let fixed = if opts.fix_rattlers {
        fix_rattlers(lengths, position, radius, &r.is_rattler, &kept, opts.seed)
    } else {
        None
    };
    let structure = match a {
        None => Structure {
            unit: None,
            pair_correlation: None,
            gap_coordination_i: None,
            gap_coordination_ii: None,
            gap_coordination_iii: None,
        },
        Some(a) => {
            let grid = default_gap_grid(opts.gap_h_max);
            let backbone_grains: Vec<bool> = r.is_rattler.iter().map(|&x| !x).collect();
            let z_ii = fixed.as_ref().and_then(|(_, relaxed)| {
                let moved: Vec<Vec<f64>> =
                    relaxed.position.iter().map(|p| p[..d].to_vec()).collect();
                gap_coordination(lengths, &moved, radius, None, a, &grid)
            });
            Structure {
                unit: Some(a),
                pair_correlation: pair_correlation(
                    lengths,
                    position,
                    a,
                    opts.gr_bin_width,
                    opts.gr_r_max,
                ),
                gap_coordination_i: gap_coordination(lengths, position, radius, None, a, &grid),
                gap_coordination_ii: z_ii,
                gap_coordination_iii: gap_coordination(
                    lengths,
                    position,
                    radius,
                    Some(&backbone_grains),
                    a,
                    &grid,
                ),
            }
        }
    };
    let bond_order = a.and_then(|a| bond_order(lengths, position, a, opts.bond_cutoff));
    let fixed_rattlers = fixed.map(|(f, _)| f);

    // Pressures.
    let measured = trace_over_d(&snap.cell.contact_stress, d);
    let kinetic = trace_over_d(&snap.cell.kinetic_stress, d);
    let (pn, pt) = contact_pressure(all, d, volume);
    let exact = pn + pt;
    let exact_rel_diff = measured.and_then(|p| rel_diff(exact, p));

    let diam: Vec<f64> = snap.particles.radius.iter().map(|r| 2.0 * r).collect();
    let mean_d = mean(diam.iter().copied());
    let mean_dd = mean(diam.iter().map(|x| x.powi(d as i32)));
    let zphi = z * phi;
    let usable = |p: f64| zphi > 0.0 && p.is_finite();

    // GRC07 (17).
    let rumpf = match (measured, mean_d, mean_dd, mean_n) {
        (Some(p), Some(md), Some(mdd), Some(m)) if usable(p) && md > 0.0 => {
            let pred = PI * mdd * p / (md * zphi);
            Some(Rumpf {
                mean_diameter: md,
                mean_diameter_pow_d: mdd,
                mean_normal_predicted: pred,
                mean_normal_measured: m,
                rel_diff: rel_diff(pred, m),
            })
        }
        _ => None,
    };

    // AR07 (22): 3D, all radii equal.
    let monodisperse = match (diam.first(), diam.iter().copied().reduce(f64::max)) {
        (Some(&d0), Some(dmax)) => {
            let dmin = diam.iter().copied().fold(f64::INFINITY, f64::min);
            (dmax - dmin) <= 1e-9 * d0.abs()
        }
        _ => false,
    };
    let ar07_22 = match (measured, mean_n) {
        (Some(p), Some(m)) if d == 3 && monodisperse && p != 0.0 => {
            let a = diam[0];
            let pred = zphi * m / (PI * a * a);
            rel_diff(pred, p).map(|rd| Ar07Eq22 {
                diameter: a,
                p_predicted: pred,
                p_measured: p,
                rel_diff: rd,
            })
        }
        _ => None,
    };

    // GRC07 (18): 2D.
    let grc07_18 = match (measured, mean_n, mean_d, mean_dd) {
        (Some(p), Some(m), Some(md), Some(mdd)) if d == 2 && usable(p) => {
            let a = diam.iter().copied().fold(0.0, f64::max);
            let pred = 7.0 * PI * a * p / (9.0 * zphi);
            Some(Grc07Eq18 {
                a,
                mean_diameter_over_a: md / a,
                mean_diameter_sq_over_a2: mdd / (a * a),
                mean_normal_predicted: pred,
                mean_normal_measured: m,
                rel_diff: rel_diff(pred, m),
            })
        }
        _ => None,
    };

    Analysis {
        scene: snap.scene.clone(),
        code: snap.code.clone(),
        status: snap.status.clone(),
        step: snap.step,
        time: snap.time,
        dimension: d,
        cohesive: snap.cohesive,
        mu: snap.mu,
        n,
        packing_fraction: phi,
        rule,
        interactions: all.len(),
        force_threshold: threshold,
        force_carrying,
        contacts: nc,
        z,
        rattlers,
        rattler_fraction: x0,
        z_backbone,
        rattler_sweeps: r.sweeps,
        x_k,
        fixed_rattlers,
        cohesive_split,
        forces,
        structure,
        bond_order,
        pressure: Pressure {
            measured,
            kinetic,
            exact,
            exact_rel_diff,
            exact_tangential: pt,
            rumpf,
            ar07_22,
            grc07_18,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{bond, lattice, snapshot, Bond, Lcg};

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
        assert_eq!(s.mean_repulsive, Some(0.5));
        assert_close!(s.mean_attractive.unwrap(), 0.4, 1e-15);
        assert_close!(s.rms_attractive.unwrap(), (0.17f64).sqrt(), 1e-15);
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
        for _ in 0..120 {
            let i = (rng.next() * n as f64) as usize;
            let j = (i + 1 + (rng.next() * (n - 1) as f64) as usize) % n;
            let r = crate::fixtures::branch(&l, &pos[i], &pos[j]);
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
        k.extend((2..=12).map(|i| format!("xk{i}")));
        k.extend((2..=12).map(|i| format!("xk{i}_II")));
        k.extend(
            [
                "mean_N", "Z2", "Z5_3", "X1", "M1", "M2", "N_2", "X1_2", "M1_2", "M2_2", "N_3",
                "X1_3", "M1_3", "M2_3", "Q4", "Q6", "Q4loc", "Q6loc", "Z_bond", "Z_cr", "Q6loc_cr",
                "x_cr", "n_cr", "z_plus", "z_minus", "z_zero", "pressure",
            ]
            .map(String::from),
        );
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
                if norm(&crate::fixtures::branch(&l, &p[i], &p[j])) < 1.01 {
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
                .filter(|&h| norm(&crate::fixtures::branch(&l, &p[g], &p[h])) < 0.75)
                .collect();
            assert_eq!(near.len(), 6);
            for (&h, &n) in near.iter().zip(forces) {
                let br = crate::fixtures::branch(&l, &p[g], &p[h]);
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
                let br = crate::fixtures::branch(&l, &pos[bd.i], &pos[bd.j]);
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

        let zero = snapshot(
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
        bad.particles.position[3] = vec![f64::NAN, 0.0, f64::INFINITY];
        let a = analyze(&bad, &Options::default());
        assert!(a.structure.pair_correlation.is_none() && a.bond_order.is_none());
        let _ = crate::report::to_markdown(&a);

        let mut nan = gas;
        nan.particles.position[3] = vec![f64::NAN, 0.0, f64::INFINITY];
        nan.particles.radius[5] = f64::NAN;
        let a = analyze(&nan, &Options::default());
        let _ = (crate::report::to_markdown(&a), a.metric_values());
    }
}

#[cfg(test)]
mod doc_example {
    use super::*;

    /// The example in docs/snapshot-format.md parses, passes the checks, and its stress agrees
    /// with its contact.
    #[test]
    fn documented_example_is_valid() {
        let doc = include_str!("../../docs/snapshot-format.md");
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
}
