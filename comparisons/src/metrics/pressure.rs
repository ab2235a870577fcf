//! The measured pressure against the relations that predict it: the exact virial identity
//! AR07 (8), GRC07 (17), AR07 (22) and GRC07 (18).
//!
//! With `σ_αβ = (1/Ω) Σ F_α r_β` (AR07 (8), contact part, compressive positive, `F` exerted by
//! `i` on `j`, `r = r_j − r_i`) and `F = N r/|r| + T`,
//! `P = tr σ / d = (1/(dΩ)) Σ (N |r| + T·r)` exactly; `T·r = 0` as `T ⟂ r`. This is
//! [`Pressure::exact`], summed over *all* listed contacts like the stress written by the code.
//! Neglecting deflections (`|r| ≈ (d_i + d_j)/2`) and size–force correlations gives GRC07 (17)
//! `P = (1/π) (⟨d⟩/⟨d^D⟩) zΦ ⟨N⟩`, which is AR07 (22) `P = zΦ⟨N⟩/(πa²)` for equal spheres and
//! GRC07 (18) `⟨N⟩ = 7πaP/(9zΦ)` for disk diameters uniform in `[a/2, a]` (`⟨d⟩ = 3a/4`,
//! `⟨d²⟩ = 7a²/12`).

use super::math::{dot, mean, norm};
use grainbench_engine::snapshot::{Contact, Snapshot};
use serde::Serialize;
use std::f64::consts::PI;

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

fn trace_over_d(m: &[Vec<f64>], d: usize) -> Option<f64> {
    if m.len() != d || m.iter().any(|row| row.len() != d) {
        return None;
    }
    Some((0..d).map(|a| m[a][a]).sum::<f64>() / d as f64)
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

/// The pressure checks of `snap`, given its coordination number `z` (AR07 §III.B), solid
/// fraction `phi` and mean normal force `mean_n` over the counted contacts.
pub fn measure(snap: &Snapshot, z: f64, phi: f64, mean_n: Option<f64>) -> Pressure {
    let d = snap.dimension;
    let volume: f64 = snap.cell.lengths.iter().product();
    let all = &snap.contacts;
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

    Pressure {
        measured,
        kinetic,
        exact,
        exact_rel_diff,
        exact_tangential: pt,
        rumpf,
        ar07_22,
        grc07_18,
    }
}
