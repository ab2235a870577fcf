//! The levels of a pressure program as their stages ended: Φ, z and its parts, the moduli
//! and the density correlations of each, and the fit of the loading branch by GRC08 (9).

use super::program::program_levels;
use crate::metrics::consolidation::{self, ConsolidationFit};
use crate::metrics::density::DensityCorrelations;
use crate::metrics::fractal_fit::FractalFit;
use crate::metrics::moduli::Moduli;
use crate::metrics::stiffness::{ContactStiffness, NormalStiffness};
use crate::metrics::{analyze, Options};
use grainbench_engine::run::layout::{stage_file, STAGES};
use grainbench_engine::snapshot::SnapshotError;
use grainbench_engine::{Scene, Snapshot};
use std::path::Path;

/// Why the levels of a run could not be read.
#[derive(Debug, thiserror::Error)]
pub enum LevelError {
    #[error(transparent)]
    Snapshot(#[from] SnapshotError),
    #[error("stage {stage} report without a packing fraction")]
    NoPackingFraction { stage: usize },
}

/// One pressure level of a program, as its stage ended.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    /// Stage index (`Scene::stages`).
    pub stage: usize,
    pub loading: bool,
    /// Reduced pressure P* of the level.
    pub pressure: f64,
    pub phi: f64,
    /// Coordination of the stage-end state (`None` without its snapshot).
    pub z: Option<Coordination>,
    /// Elastic moduli of the stage-end state (`None` without its snapshot, or when they
    /// cannot be computed: the error is printed).
    pub moduli: Option<LevelModuli>,
    /// GRC08 §IV: I(k), its fractal fit (d_F, ξ) and the holes (ξ' = ⟨R⟩_w) of the stage-end
    /// state (`None` without its snapshot).
    pub density: Option<DensityCorrelations>,
    /// How the stage ended (`equilibrium`, `time-limit`, …).
    pub end: String,
}

/// Coordination number of a level's state and its parts by the sign of the normal force,
/// GRC08 Fig. 17: z = z+ (compressive) + z− (tensile) + z0 (no force).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coordination {
    pub z: f64,
    pub z_plus: f64,
    pub z_minus: f64,
    pub z_zero: f64,
}

impl Coordination {
    pub(super) fn of(values: &[(String, f64)]) -> Option<Coordination> {
        let get = |k: &str| values.iter().find(|(key, _)| key == k).map(|(_, v)| *v);
        Some(Coordination {
            z: get("z")?,
            z_plus: get("z_plus")?,
            z_minus: get("z_minus")?,
            z_zero: get("z_zero")?,
        })
    }

    pub(super) fn parts(&self) -> [f64; 4] {
        [self.z, self.z_plus, self.z_minus, self.z_zero]
    }
}

/// Elastic moduli of a level's state, in units of K_N (GRC08 §VI, Fig. 22): B, G from the
/// stiffness matrix, the Voigt B^V, G^V and Reuss B^R estimates, and the fraction of contacts
/// carrying 95 % of the elastic energy of a pressure increment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelModuli {
    pub bulk: f64,
    pub shear: f64,
    pub voigt_bulk: f64,
    pub voigt_shear: f64,
    pub reuss_bulk: Option<f64>,
    pub energy_95: Option<f64>,
}

impl LevelModuli {
    /// `m` divided by the linear law's K_N.
    fn of(m: &Moduli, k_n: f64) -> LevelModuli {
        LevelModuli {
            bulk: m.bulk / k_n,
            shear: m.shear / k_n,
            voigt_bulk: m.voigt_bulk / k_n,
            voigt_shear: m.voigt_shear / k_n,
            reuss_bulk: m.reuss_bulk.map(|b| b / k_n),
            energy_95: m.energy_95,
        }
    }

    pub(super) fn fields(&self) -> [Option<f64>; 6] {
        [
            Some(self.bulk),
            Some(self.shear),
            Some(self.voigt_bulk),
            Some(self.voigt_shear),
            self.reuss_bulk,
            self.energy_95,
        ]
    }
}

impl Level {
    /// The fit of I(k) by GRC07 (28), where it finds a fractal range
    /// ([`FractalFit::has_fractal_range`]; GRC08 Fig. 15: none left at P* = 1).
    pub(super) fn fractal(&self) -> Option<&FractalFit> {
        let f = self.density.as_ref()?.fit.as_ref()?;
        f.has_fractal_range().then_some(f)
    }

    /// d_F of the fractal fit of I(k).
    pub fn d_f(&self) -> Option<f64> {
        Some(self.fractal()?.model.d_f)
    }

    /// ξ of the fractal fit of I(k), in a.
    pub fn xi(&self) -> Option<f64> {
        Some(self.fractal()?.model.xi)
    }

    /// ξ' of GRC08 Fig. 16: the mass-weighted mean radius of gyration of the pores ⟨R⟩_w
    /// (GRC07 (30)), in a.
    pub fn pore_radius(&self) -> Option<f64> {
        self.density.as_ref()?.holes.weighted_radius
    }
}

/// The pressures at which GRC08 Fig. 15 shows I(k): P* = 0.01 (its Fig. 2), 0.178 (Fig. 3,
/// "the largest one for which [the fractal range] is clearly observed") and 1, with the
/// suffixes of their table keys.
pub const SCATTERING_AT: [(f64, &str); 3] = [(0.01, "p001"), (0.178, "p0178"), (1.0, "p1")];

/// The loading level at pressure `p` (within 1 %: 0.178 stands for 10^(−3/4)).
pub(super) fn loading_level(levels: &[Level], p: f64) -> Option<&Level> {
    levels
        .iter()
        .find(|l| l.loading && (l.pressure / p - 1.0).abs() < 0.01)
}

/// GRC08 (10), ξ ∝ Φ^(−1/(2−d_F)), along the loading branch up to P* = 0.178 (beyond it
/// I(k) has no fractal range to fit, GRC08 §IV): the least-squares slope of ln ξ against
/// ln Φ over the levels with a fit, and the slope (10) predicts from their mean d_F.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlobScaling {
    pub slope: f64,
    pub predicted: f64,
    pub levels: usize,
}

impl BlobScaling {
    /// `None` with fewer than three fitted levels.
    pub fn of(levels: &[Level]) -> Option<BlobScaling> {
        let top = SCATTERING_AT[1].0 * 1.01;
        let pts: Vec<(f64, f64, f64)> = levels
            .iter()
            .filter(|l| l.loading && l.pressure <= top)
            .filter_map(|l| Some((l.phi, l.xi()?, l.d_f()?)))
            .collect();
        Self::fit(&pts)
    }

    /// The same from (Φ, ξ, d_F) of each level.
    pub(super) fn fit(levels: &[(f64, f64, f64)]) -> Option<BlobScaling> {
        let pts: Vec<(f64, f64, f64)> = levels
            .iter()
            .map(|&(phi, xi, d)| (phi.ln(), xi.ln(), d))
            .collect();
        if pts.len() < 3 {
            return None;
        }
        let n = pts.len() as f64;
        let (mx, my) = (
            pts.iter().map(|p| p.0).sum::<f64>() / n,
            pts.iter().map(|p| p.1).sum::<f64>() / n,
        );
        let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let d_f = pts.iter().map(|p| p.2).sum::<f64>() / n;
        (sxx > 0.0).then(|| BlobScaling {
            slope: sxy / sxx,
            predicted: -1.0 / (2.0 - d_f),
            levels: pts.len(),
        })
    }
}

/// The levels of the scene's pressure programs, from the run's stage reports (`steps`, as in
/// summary.json) and the stage-end snapshots in `dir/stages/` where present.
pub fn levels(
    scene: &Scene,
    steps: &serde_json::Value,
    dir: &Path,
) -> Result<Vec<Level>, LevelError> {
    let reports = steps.as_array().map(Vec::as_slice).unwrap_or_default();
    let mut out = Vec::new();
    for (stage, loading, pressure) in program_levels(scene) {
        let Some(r) = reports
            .iter()
            .find(|r| r["index"].as_u64() == Some(stage as u64))
        else {
            continue;
        };
        let path = dir.join(STAGES).join(stage_file(stage));
        let (z, moduli, density) = if path.exists() {
            let snap = Snapshot::read(&path)?;
            // The moduli of the linear law (GRC08), without the rigidity counts (~10 s a level).
            let law = ContactStiffness::of_scene(scene, &snap).ok();
            let k_n = match law.map(|l| l.normal) {
                Some(NormalStiffness::Constant(k)) => Some(k),
                _ => None,
            };
            let opts = Options {
                moduli: law.filter(|_| k_n.is_some()),
                rigidity: false,
                ..Default::default()
            };
            let a = analyze(&snap, &opts);
            let moduli = match (&a.moduli, k_n) {
                (Some(Ok(m)), Some(k_n)) => Some(LevelModuli::of(m, k_n)),
                (Some(Err(e)), _) => {
                    eprintln!(
                        "warning: no moduli at stage {stage} ({}): {e}",
                        path.display()
                    );
                    None
                }
                _ => None,
            };
            (Coordination::of(&a.metric_values()), moduli, a.density)
        } else {
            (None, None, None)
        };
        out.push(Level {
            stage,
            loading,
            pressure,
            phi: r["checks"]["packing_fraction"]
                .as_f64()
                .ok_or(LevelError::NoPackingFraction { stage })?,
            z,
            moduli,
            density,
            end: r["end"].as_str().unwrap_or("?").to_string(),
        });
    }
    Ok(out)
}

/// GRC08 (9) fitted to the loading levels (the first program that raises the pressure; a
/// level repeated at the start of the program counts once).
pub fn fit_loading(levels: &[Level]) -> Option<ConsolidationFit> {
    consolidation::fit(&loading_points(levels))
}

pub(super) fn loading_points(levels: &[Level]) -> Vec<(f64, f64)> {
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for l in levels.iter().filter(|l| l.loading) {
        match pts.last_mut() {
            Some(last) if l.pressure <= last.0 => {
                if l.pressure == last.0 {
                    *last = (l.pressure, l.phi);
                } else {
                    break;
                }
            }
            _ => pts.push((l.pressure, l.phi)),
        }
    }
    pts
}

/// Whether two levels' pressures are the same level of a program (seeds share the program).
pub(super) fn same_pressure(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}
