//! Packing metrics of one snapshot (AR07 §III–§IV, GRC07 §III–§IV): Φ, z, rattlers, z*, x_k,
//! force moments, friction mobilisation, and the exact pressure/force relations AR07 (22),
//! GRC07 (17)–(18).
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
//! angles: [`force_distribution`]) use the same set of contacts as `z`, so that
//! `z⟨N⟩ = (2/n) Σ N` enters the pressure relations consistently.
//!
//! # Geometry
//!
//! g(r) and z(h) ([`structure`]), bond-orientational order ([`mod@bond_order`], 3D)
//! and the variant II of x_k with the rattlers fixed onto the backbone
//! ([`fixed_rattlers`]) are measured on the positions, in units of a = the largest
//! diameter. [`Analysis::metric_values`] lists every scalar under a canonical key.
//!
//! # Pressure relations
//!
//! The measured pressure against the exact identity AR07 (8) and the approximations GRC07
//! (17), AR07 (22), GRC07 (18): [`pressure`].
//!
//! # Layout
//!
//! * [`mod@rattlers`]: the rattler algorithm and x_k (AR07 §III.B, §IV.D; GRC07 §III.A).
//! * [`fixed_rattlers`]: rattlers fixed onto the backbone, x_k variant II (AR07 §III.C).
//! * [`force_distribution`]: P(f), Z(α), X1/M1/M2 and their T.VI breakdown (AR07), the
//!   force-angle histogram (GRC07 Fig. 15).
//! * [`structure`]: g(r) and z(h) (AR07 §III.D).
//! * [`mod@bond_order`]: Q4/Q6 local and global, crystalline bonds and grains (AR07 (31)–(34), T.II).
//! * [`consolidation`]: GRC08 (9), the consolidation curve 1/Φ(P*), and its fit (T.III).
//! * [`contact_changes`]: contacts kept, lost and gained in one compression step (GRC08 T.IV).
//! * [`pressure`]: the pressure checks.
//! * [`series`]: the data series (curves, histograms) the metrics return for plots.
//! * this module: [`analyze`], [`Options`], [`Analysis`], [`Analysis::metric_values`].

pub mod bond_order;
pub mod consolidation;
pub mod contact_changes;
pub mod density;
pub mod density_field;
pub mod fixed_rattlers;
pub mod force_distribution;
pub mod fractal_fit;
pub mod holes;
pub mod impact;
mod math;
pub mod moduli;
mod neighbors;
pub mod pair_history;
pub mod pressure;
pub mod rattlers;
pub mod series;
pub mod stiffness;
pub mod structure;

#[cfg(test)]
pub(crate) mod fixtures;
#[cfg(test)]
mod tests;

use bond_order::{bond_order, local_environments, BondOrder, LocalEnvironments, DEFAULT_CUTOFF};
use density::{density_correlations, DensityCorrelations};
use fixed_rattlers::{fix_rattlers, FixedRattlers, DEFAULT_SEED};
use force_distribution::force_stats;
pub use force_distribution::{ForceStats, PopulationStats};
use grainbench_engine::network::wrapped_axes;
use grainbench_engine::snapshot::{Contact, Snapshot};
use math::mean;
use moduli::{elastic_moduli, Moduli};
pub use pressure::{contact_pressure, Ar07Eq22, Grc07Eq18, Pressure, Rumpf};
pub use rattlers::X_K_MIN_LEN;
use rattlers::{contact_number_fractions, find_rattlers, Rule};
use serde::Serialize;
use structure::{default_gap_grid, gap_coordination, pair_correlation, unit_length, Structure};

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
    /// Mesh spacing, in a, of the density field of 2D cohesive packings (GRC07 §V.C).
    pub density_spacing: f64,
    /// The contact stiffnesses, to compute the elastic moduli ([`moduli`]); `None` skips them
    /// (a snapshot does not carry its law: `analyze --moduli` takes it from the scene).
    pub moduli: Option<stiffness::ContactStiffness>,
    /// With the moduli, also the mechanisms and force indeterminacy (GRC07 App. A; a dense
    /// rank, seconds per 1400-disk state).
    pub rigidity: bool,
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
            density_spacing: density::DEFAULT_SPACING,
            moduli: None,
            rigidity: true,
        }
    }
}

/// Variant II fixes rattlers onto a backbone; above this rattler fraction there is hardly one
/// (a gas, an unfinished loose state: the rattlers fall through an empty periodic cell for the
/// whole step budget, 45 s for 200 disks — found by tests/fuzz.rs). Recorded packings have
/// x0 ≤ 0.21.
pub const MAX_FIXED_RATTLER_FRACTION: f64 = 0.5;

/// The keys of [`Analysis::metric_values`] that only [`Options::moduli`] measures.
pub const MODULI_METRICS: &[&str] = &[
    "B",
    "G",
    "B_V",
    "G_V",
    "B_R",
    "E95",
    "mechanisms",
    "H",
    "H_over_Nf",
];

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
    /// `None` if disabled, or if there is no backbone to fix them onto (more than
    /// [`MAX_FIXED_RATTLER_FRACTION`] of the grains are rattlers).
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
    /// Fractions of fcc-like, hcp-like and disordered local environments at d_c = 1.1a…1.4a
    /// (AR07 App. D, T.VII–T.VIII); 3D only.
    pub local_environments: Option<Vec<LocalEnvironments>>,
    /// Density correlations, fractal dimension and holes (GRC07 §V); 2D cohesive packings.
    pub density: Option<DensityCorrelations>,
    /// Elastic moduli and rigidity of the backbone (GRC08 §VI, GRC07 App. A), when
    /// [`Options::moduli`] gives the stiffnesses; the error says why they could not be computed.
    pub moduli: Option<Result<Moduli, String>>,
    /// Measured pressure and the exact relations.
    pub pressure: Pressure,
}

impl Analysis {
    /// Every scalar metric under its canonical key (fractions, not percent), for tables
    /// comparing with the papers. Keys whose metric is undefined for this snapshot (Q6 in
    /// 2D, z± without cohesion, N^(2) without divalent grains, …) are left out.
    ///
    /// `phi`, `z`, `z_star`, `x0`, `xk1` (cohesive only), `xk2`…`xk12` (x_k, variant I), `xk2_II`…`xk12_II`,
    /// `mean_N`, `Z2`, `Z5_3`, `X1`, `M1`, `M2`, `N_2`, `X1_2`, `M1_2`, `M2_2`, `N_3`, `X1_3`,
    /// `M1_3`, `M2_3`, `Q4`, `Q6`, `Q4loc`, `Q6loc`, `Z_bond`, `Z_cr`, `Q6loc_cr`, `x_cr`,
    /// `n_cr`, `fcc_110`…`fcc_140`, `hcp_110`…`hcp_140`, `dis_F_110`…`dis_F_140` (and `dis_D_…`,
    /// `dis_B_…`; `hcp_not_F_…`, `hcp_not_D_…`, `hcp_not_B_…`: hcp-like outside that disordered
    /// box — AR07 T.VII–T.VIII at d_c = 1.1a…1.4a, 3D), `z_plus`, `z_minus`, `z_zero`,
    /// `clusters`, `wrapped_axes`, `N_plus`, `N_plus_rms`, `N_minus`, `N_minus_rms` (GRC07 T.VI,
    /// units of F0), `d_F`, `xi`, `R_w` (GRC07 T.VII and (30), lengths in a), `B`, `G`, `B_V`,
    /// `G_V`, `B_R`, `E95`, `mechanisms`, `H`, `H_over_Nf` (GRC08 §VI, GRC07 App. A; with
    /// [`Options::moduli`]), `pressure` (measured).
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
        // x_1 counts for cohesive packings only (one-interaction grains hold by adhesion;
        // without it they are rattlers).
        let k_min = if self.cohesive_split.is_some() { 1 } else { 2 };
        for k in k_min..=12 {
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
        for e in self.local_environments.iter().flatten() {
            let dc = (e.cutoff * 100.0).round();
            put(&format!("fcc_{dc}"), Some(e.fcc));
            put(&format!("hcp_{dc}"), Some(e.hcp));
            for (sample, x) in &e.disordered {
                put(&format!("dis_{sample}_{dc}"), Some(*x));
            }
            for (sample, x) in &e.hcp_outside {
                put(&format!("hcp_not_{sample}_{dc}"), Some(*x));
            }
        }
        if let Some(s) = &self.cohesive_split {
            put("z_plus", Some(s.z_plus));
            put("z_minus", Some(s.z_minus));
            put("z_zero", Some(s.z_zero));
            put("clusters", Some(s.clusters as f64));
            put("wrapped_axes", Some(s.wrapped_axes as f64));
            put("N_plus", s.mean_repulsive);
            put("N_plus_rms", s.rms_repulsive);
            put("N_minus", s.mean_attractive);
            put("N_minus_rms", s.rms_attractive);
        }
        if let Some(c) = &self.density {
            put("d_F", c.fit.as_ref().map(|f| f.model.d_f));
            put("xi", c.fit.as_ref().map(|f| f.model.xi));
            put("R_w", c.holes.weighted_radius);
        }
        if let Some(Ok(m)) = &self.moduli {
            put("B", Some(m.bulk));
            put("G", Some(m.shear));
            put("B_V", Some(m.voigt_bulk));
            put("G_V", Some(m.voigt_shear));
            put("B_R", m.reuss_bulk);
            put("E95", m.energy_95);
            if let Some(r) = &m.rigidity {
                put("mechanisms", Some(r.mechanisms as f64));
                put("H", Some(r.indeterminacy as f64));
                put("H_over_Nf", Some(r.indeterminacy as f64 / r.dofs as f64));
            }
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
    /// Clusters: connected groups of grains linked by interactions, among the grains with at
    /// least one (1 for a packing that holds together; GRC07 §III.B method 2 aggregates to 1).
    pub clusters: usize,
    /// Axes of the cell along which the interaction network wraps (connects to its own periodic
    /// image, [`grainbench_engine::network::wrapped_axes`]): all of them for a network that holds
    /// the cell at P* = 0 (GRC07 §III.B.1); fewer, and the cell length along the others is free.
    pub wrapped_axes: usize,
    /// N+ and N+^(2): mean and quadratic mean of repulsive forces.
    pub mean_repulsive: Option<f64>,
    pub rms_repulsive: Option<f64>,
    /// N− and N−^(2): mean and quadratic mean of |N| over attractive forces.
    pub mean_attractive: Option<f64>,
    pub rms_attractive: Option<f64>,
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
    let x_k = contact_number_fractions(&k_of);

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
            clusters: clusters(n, &pairs),
            wrapped_axes: wrapped_axes(
                &snap.cell.lengths,
                n,
                &counted,
                |c| (c.i, c.j),
                |c| c.branch.clone(),
            )
            .into_iter()
            .filter(|&w| w)
            .count(),
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
    let fixed = if opts.fix_rattlers && x0 <= MAX_FIXED_RATTLER_FRACTION {
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
    let local_environments = a.and_then(|a| local_environments(lengths, position, a));
    let density = a.filter(|_| snap.cohesive).and_then(|a| {
        density_correlations(lengths, position, radius, a, phi, opts.density_spacing)
    });
    let fixed_rattlers = fixed.map(|(f, _)| f);
    let moduli = opts
        .moduli
        .map(|law| elastic_moduli(snap, &backbone, &law, opts.rigidity));

    let pressure = pressure::measure(snap, z, phi, mean_n);

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
        moduli,
        bond_order,
        local_environments,
        density,
        pressure,
    }
}

/// Connected groups of grains linked by `pairs`, among the `n` grains those that appear in a
/// pair (union–find).
fn clusters(n: usize, pairs: &[(usize, usize)]) -> usize {
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut parent: Vec<usize> = (0..n).collect();
    let mut linked = vec![false; n];
    let mut merges = 0;
    for &(i, j) in pairs {
        linked[i] = true;
        linked[j] = true;
        let (a, b) = (root(&mut parent, i), root(&mut parent, j));
        if a != b {
            parent[a] = b;
            merges += 1;
        }
    }
    linked.iter().filter(|&&l| l).count() - merges
}
