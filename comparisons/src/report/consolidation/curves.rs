//! A seed's consolidation curve and the seeds' mean: the values the reproduction table
//! compares (the fit of GRC08 (9), d_F, ξ and ξ' of §IV, the step of T.IV) and the CSV.

use super::levels::{
    fit_loading, loading_level, loading_points, same_pressure, BlobScaling, Level, SCATTERING_AT,
};
use crate::metrics::consolidation::{self, ConsolidationFit};
use crate::metrics::contact_changes::contact_changes;
use crate::metrics::density::{self, DensityCorrelations};
use crate::report::reproduction::SeedStats;
use grainbench_engine::run::layout::{stage_file, STAGES};
use grainbench_engine::snapshot::{self, SnapshotError};
use grainbench_engine::Snapshot;
use std::path::{Path, PathBuf};

/// The values a reproduction table compares (paper-values.toml keys): the fit's P0_star,
/// phi0, lambda, alpha, P1_star, phi_max, and phi_at_pmax, Φ at the highest loading level.
pub fn values(levels: &[Level], fit: Option<&ConsolidationFit>) -> Vec<(String, f64)> {
    let mut v = fit.map(|f| f.values()).unwrap_or_default();
    if let Some(top) = levels
        .iter()
        .filter(|l| l.loading)
        .max_by(|a, b| a.pressure.total_cmp(&b.pressure))
    {
        v.push(("phi_at_pmax".into(), top.phi));
    }
    // GRC08 §IV: d_F, ξ and ξ' where Fig. 15 shows I(k), and the test of (10).
    for (p, key) in SCATTERING_AT {
        let Some(l) = loading_level(levels, p) else {
            continue;
        };
        for (name, x) in [("d_F", l.d_f()), ("xi", l.xi()), ("R_w", l.pore_radius())] {
            if let Some(x) = x {
                v.push((format!("{name}_{key}"), x));
            }
        }
    }
    if let Some(b) = BlobScaling::of(levels) {
        v.push(("xi_phi_slope".into(), b.slope));
        v.push(("xi_phi_slope_eq10".into(), b.predicted));
    }
    v
}

/// The seeds' mean I(k) at each pressure of [`SCATTERING_AT`] every seed reached with its
/// state, and its fit (`None` for one seed: [`density::mean_scattering`] needs two).
pub fn mean_scattering(seeds: &[SeedCurve]) -> Vec<(f64, &'static str, density::MeanScattering)> {
    SCATTERING_AT
        .iter()
        .filter_map(|&(p, key)| {
            let at: Vec<&DensityCorrelations> = seeds
                .iter()
                .filter_map(|s| loading_level(&s.levels, p)?.density.as_ref())
                .collect();
            if at.len() < seeds.len() {
                return None;
            }
            Some((p, key, density::mean_scattering(&at)?))
        })
        .collect()
}

/// GRC07 §V.D fits I(k) averaged over samples (one 1400-disk sample is too small to fix ξ):
/// d_F and ξ at each pressure of [`SCATTERING_AT`] from the fit of the seeds' mean I(k),
/// standing for the seeds' own in the table.
pub fn pooled_density(
    means: &[(f64, &'static str, density::MeanScattering)],
) -> Vec<(String, SeedStats)> {
    let mut out = Vec::new();
    for (_, key, m) in means {
        if let Some(f) = m.fit.as_ref().filter(|f| f.has_fractal_range()) {
            out.push((
                format!("d_F_{key}"),
                SeedStats::mean_curve_fit(f.model.d_f, Some(f.d_f_error), m.samples),
            ));
            out.push((
                format!("xi_{key}"),
                SeedStats::mean_curve_fit(f.model.xi, Some(f.xi_error), m.samples),
            ));
        }
    }
    out
}

/// The compression step of GRC08 T.IV, P* = 0.177 → 0.237 (10^(-3/4) → 10^(-5/8) of the
/// 10^(1/8) program).
pub const STEP: (f64, f64) = (0.177, 0.237);

/// GRC08 T.IV for one seed: the contacts kept, lost and gained in the loading step
/// [`STEP`], with the relative changes of Φ and z (`dphi_rel`, `dz_rel`), from the levels'
/// states in `dir/stages/`; `None` when the program has no such step or its states are
/// missing.
pub fn step_values(
    curve: &SeedCurve,
    dir: &Path,
) -> Result<Option<Vec<(String, f64)>>, SnapshotError> {
    let at = |p: f64| {
        curve
            .levels
            .iter()
            .find(|l| l.loading && (l.pressure / p - 1.0).abs() < 0.01)
    };
    let (Some(a), Some(b)) = (at(STEP.0), at(STEP.1)) else {
        return Ok(None);
    };
    let read = |l: &Level| -> Result<Option<Snapshot>, SnapshotError> {
        let path = dir.join(STAGES).join(stage_file(l.stage));
        Ok(if path.exists() {
            Some(Snapshot::read(&path)?)
        } else {
            None
        })
    };
    let (Some(sa), Some(sb)) = (read(a)?, read(b)?) else {
        return Ok(None);
    };
    let Some(changes) = contact_changes(&sa, &sb) else {
        return Ok(None);
    };
    let mut v = changes.values();
    v.push(("dphi_rel".into(), b.phi / a.phi - 1.0));
    if let (Some(za), Some(zb)) = (a.z, b.z) {
        v.push(("dz_rel".into(), zb.z / za.z - 1.0));
    }
    Ok(Some(v))
}

/// One seed's levels and the fit of its loading branch.
pub struct SeedCurve {
    pub seed: u64,
    pub levels: Vec<Level>,
    pub fit: Option<ConsolidationFit>,
}

impl SeedCurve {
    pub fn new(seed: u64, levels: Vec<Level>) -> Self {
        let fit = fit_loading(&levels);
        SeedCurve { seed, levels, fit }
    }
}

/// The seeds' mean loading curve and its fit by GRC08 (9): GRC08 §II.C averages "over all
/// available samples" and T.III fits the averaged data, where one seed's fit can degenerate
/// on the jumps of its curve.
#[derive(Clone, Debug)]
pub struct MeanCurve {
    /// (P*, mean Φ, sample s.d. of Φ) at each loading pressure every seed reached.
    pub points: Vec<(f64, f64, f64)>,
    pub seeds: usize,
    pub fit: Option<ConsolidationFit>,
}

impl MeanCurve {
    /// The mean of two or more seeds' loading curves; `None` for fewer seeds.
    pub fn of(seeds: &[SeedCurve]) -> Option<MeanCurve> {
        if seeds.len() < 2 {
            return None;
        }
        let curves: Vec<Vec<(f64, f64)>> =
            seeds.iter().map(|s| loading_points(&s.levels)).collect();
        let points: Vec<(f64, f64, f64)> = curves[0]
            .iter()
            .filter_map(|&(p, _)| {
                let phis: Vec<f64> = curves
                    .iter()
                    .filter_map(|c| c.iter().find(|q| same_pressure(q.0, p)).map(|q| q.1))
                    .collect();
                (phis.len() == curves.len()).then(|| {
                    let sd = crate::stats::sample_sd(&phis).unwrap_or(0.0);
                    (p, phis.iter().sum::<f64>() / phis.len() as f64, sd)
                })
            })
            .collect();
        let xy: Vec<(f64, f64)> = points.iter().map(|&(p, phi, _)| (p, phi)).collect();
        Some(MeanCurve {
            fit: consolidation::fit(&xy),
            points,
            seeds: seeds.len(),
        })
    }

    /// The fit's values for the reproduction table, each with its standard error where the fit
    /// gives one (λ, α, P1*).
    pub fn pooled(&self) -> Vec<(String, SeedStats)> {
        let Some(f) = &self.fit else {
            return Vec::new();
        };
        let se = |k: &str| match k {
            "lambda" => Some(f.lambda_error),
            "alpha" => Some(f.alpha_error),
            "P1_star" => Some(f.p1_error),
            _ => None,
        };
        f.values()
            .into_iter()
            .map(|(k, v)| {
                let stats = SeedStats::mean_curve_fit(v, se(&k), self.seeds);
                (k, stats)
            })
            .collect()
    }
}

/// Writes `consolidation.csv` (seed, branch, P*, Φ, z, z+, z−, z0, the moduli in K_N, d_F, ξ
/// and ξ' in a, end of every level) into `out`.
pub fn write_csv(out: &Path, seeds: &[SeedCurve]) -> std::io::Result<PathBuf> {
    let mut text = String::from(
        "seed,branch,stage,pressure,phi,z,z_plus,z_minus,z_zero,B,G,B_V,G_V,B_R,E95,d_F,xi,R_w,end\n",
    );
    let cell = |x: Option<f64>| x.map(|v| v.to_string()).unwrap_or_default();
    for SeedCurve { seed, levels, .. } in seeds {
        for l in levels {
            let z = match l.z {
                Some(c) => c.parts().map(|x| x.to_string()).join(","),
                None => ",,,".to_string(),
            };
            let m = match l.moduli {
                Some(m) => m.fields().map(cell).join(","),
                None => ",,,,,".to_string(),
            };
            let d = [l.d_f(), l.xi(), l.pore_radius()].map(cell).join(",");
            text.push_str(&format!(
                "{seed},{},{},{},{},{z},{m},{d},{}\n",
                if l.loading { "loading" } else { "unloading" },
                l.stage,
                l.pressure,
                l.phi,
                l.end
            ));
        }
    }
    let path = out.join("consolidation.csv");
    snapshot::write_atomic(&path, text.as_bytes())?;
    Ok(path)
}
