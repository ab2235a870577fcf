//! The plots of a consolidation curve: Φ(P*) against the paper's law (GRC08 Fig. 5–6),
//! z and its parts (Fig. 17), the moduli (Fig. 22), the blob size (Fig. 16) and I(k) (Fig. 15).

use super::curves::{MeanCurve, SeedCurve};
use super::levels::{loading_level, same_pressure, Level, SCATTERING_AT};
use crate::metrics::consolidation::{ConsolidationFit, ConsolidationLaw};
use crate::metrics::density;
use crate::metrics::fractal_fit::FractalFit;
use crate::report::figures::Written;
use crate::report::plots::{self, PlotError};
use std::path::{Path, PathBuf};

/// Every plot of the curves: Φ(P*) ([`plot`]), z, the moduli, I(k) along the cycle and the
/// blob size, in that order; a plot that cannot be drawn is a warning.
pub fn all(
    out: &Path,
    seeds: &[SeedCurve],
    mean: Option<&MeanCurve>,
    paper: Option<(ConsolidationLaw, String)>,
    cycle_ik: &[(f64, &'static str, density::MeanScattering)],
) -> Written {
    let mut written = Written::default();
    for (what, r) in [
        ("consolidation plot", plot(out, seeds, mean, paper)),
        ("coordination plot", plot_coordination(out, seeds)),
        ("moduli plot", plot_moduli(out, seeds)),
        (
            "I(k) plot of the cycle",
            plot_scattering(out, seeds, cycle_ik),
        ),
        ("blob-size plot", plot_blob_size(out, seeds)),
    ] {
        written.record(what, r);
    }
    written
}

/// Φ(P*) of every seed (loading and unloading levels, markers), the seeds' mean with its
/// s.d. band and its fit by GRC08 (9) when there are several seeds (each seed's fit when there
/// is one), and the paper's (lines): `consolidation.svg` and `.png` in `out`.
pub fn plot(
    out: &Path,
    seeds: &[SeedCurve],
    mean: Option<&MeanCurve>,
    paper: Option<(ConsolidationLaw, String)>,
) -> Result<Vec<PathBuf>, PlotError> {
    // (label, points, marks, band) of each curve.
    type Curve = (
        String,
        Vec<(f64, f64)>,
        plots::Marks,
        Option<Vec<(f64, f64, f64)>>,
    );
    let mut owned: Vec<Curve> = Vec::new();
    let (mut p_min, mut p_max) = (f64::INFINITY, 0.0f64);
    let fit_label = |who: &str, f: &ConsolidationFit| {
        format!(
            "{who}: GRC08 (9), λ = {:.3}, Φmax = {:.4}",
            f.law.lambda,
            f.law.phi_max()
        )
    };
    for SeedCurve { seed, levels, .. } in seeds {
        for loading in [true, false] {
            let pts: Vec<(f64, f64)> = levels
                .iter()
                .filter(|l| l.loading == loading)
                .map(|l| (l.pressure, l.phi))
                .collect();
            for p in &pts {
                p_min = p_min.min(p.0);
                p_max = p_max.max(p.0);
            }
            if !pts.is_empty() {
                let branch = if loading { "loading" } else { "unloading" };
                owned.push((
                    format!("seed {seed} {branch}"),
                    pts,
                    plots::Marks::Points,
                    None,
                ));
            }
        }
    }
    match mean {
        Some(m) => {
            let band = m.points.iter().map(|&(p, phi, sd)| (p, phi - sd, phi + sd));
            owned.push((
                format!("mean of {} seeds ± s.d.", m.seeds),
                m.points.iter().map(|&(p, phi, _)| (p, phi)).collect(),
                plots::Marks::LinesAndPoints,
                Some(band.collect()),
            ));
            if let Some(f) = &m.fit {
                let label = fit_label("mean", f);
                owned.push((
                    label,
                    curve(&f.law, f.law.p0, p_max),
                    plots::Marks::Lines,
                    None,
                ));
            }
        }
        None => {
            for SeedCurve { seed, fit, .. } in seeds {
                if let Some(f) = fit {
                    let label = fit_label(&format!("seed {seed}"), f);
                    owned.push((
                        label,
                        curve(&f.law, f.law.p0, p_max),
                        plots::Marks::Lines,
                        None,
                    ));
                }
            }
        }
    }
    if let Some((law, source)) = paper {
        if p_max > 0.0 {
            owned.push((
                format!("{source}, λ = {}, Φmax = {:.4}", law.lambda, law.phi_max()),
                curve(&law, law.p0, p_max),
                plots::Marks::Lines,
                None,
            ));
        }
    }
    if owned.is_empty() {
        return Ok(Vec::new());
    }
    let series: Vec<plots::Series> = owned
        .iter()
        .map(|(l, p, m, band)| {
            let s = plots::Series::new(l, p).with_marks(*m);
            match band {
                Some(b) => s.with_band(b),
                None => s,
            }
        })
        .collect();
    let mut spec = plots::LinePlot::new("Consolidation curve Φ(P*)", "P* = Pa/F0", "Φ", &series);
    spec.x_axis = plots::Axis::Log;
    spec.x_range = Some((p_min * 0.8, p_max * 1.25));
    spec.legend_lower_right = true;
    let files = plots::line_plot(&out.join("consolidation"), &spec)?;
    Ok(vec![files.svg, files.png])
}

/// A quantity read from a level, with its legend label.
type Pick = (&'static str, fn(&Level) -> Option<f64>);
/// (label, points, marks) of a curve along the cycle.
type BranchCurve = (String, Vec<(f64, f64)>, plots::Marks);

/// The seeds' mean of each quantity of `picks` at every level of each branch where every seed
/// has it (lines on loading, markers on unloading); positive values only when `positive`
/// (for a log axis).
fn branch_curves(seeds: &[SeedCurve], picks: &[Pick], positive: bool) -> Vec<BranchCurve> {
    let mut out = Vec::new();
    for loading in [true, false] {
        let (name, marks) = if loading {
            ("loading", plots::Marks::LinesAndPoints)
        } else {
            ("unloading", plots::Marks::Points)
        };
        for (label, pick) in picks {
            let branch: Vec<Vec<(f64, f64)>> = seeds
                .iter()
                .map(|s| {
                    s.levels
                        .iter()
                        .filter(|l| l.loading == loading)
                        .filter_map(|l| Some((l.pressure, pick(l)?)))
                        .collect()
                })
                .collect();
            let Some(first) = branch.first() else {
                continue;
            };
            let pts: Vec<(f64, f64)> = first
                .iter()
                .filter_map(|&(p, _)| {
                    let at: Vec<f64> = branch
                        .iter()
                        .filter_map(|b| b.iter().find(|q| same_pressure(q.0, p)).map(|q| q.1))
                        .collect();
                    let mean = at.iter().sum::<f64>() / at.len() as f64;
                    (at.len() == branch.len() && (!positive || mean > 0.0)).then_some((p, mean))
                })
                .collect();
            if !pts.is_empty() {
                out.push((format!("{label}, {name}"), pts, marks));
            }
        }
    }
    out
}

/// A log-P* plot of `curves` titled with the seed count, into `out/<file>.svg` and `.png`;
/// nothing without curves.
fn cycle_plot(
    out: &Path,
    file: &str,
    what: &str,
    y_label: &str,
    seeds: usize,
    curves: &[BranchCurve],
    style: impl FnOnce(&mut plots::LinePlot),
) -> Result<Vec<PathBuf>, PlotError> {
    if curves.is_empty() {
        return Ok(Vec::new());
    }
    let series: Vec<plots::Series> = curves
        .iter()
        .map(|(l, p, m)| plots::Series::new(l, p).with_marks(*m))
        .collect();
    let title = match seeds {
        1 => format!("{what} along the cycle"),
        n => format!("{what} along the cycle (mean of {n} seeds)"),
    };
    let mut spec = plots::LinePlot::new(&title, "P* = Pa/F0", y_label, &series);
    spec.x_axis = plots::Axis::Log;
    style(&mut spec);
    let files = plots::line_plot(&out.join(file), &spec)?;
    Ok(vec![files.svg, files.png])
}

/// GRC08 Fig. 17: z, z+, z− and z0 along the cycle, averaged over the seeds at each level
/// every seed reached with its state: `consolidation-z.svg` and `.png` in `out`; nothing
/// without the levels' states.
pub fn plot_coordination(out: &Path, seeds: &[SeedCurve]) -> Result<Vec<PathBuf>, PlotError> {
    let picks: [Pick; 4] = [
        ("z", |l| l.z.map(|c| c.z)),
        ("z+ (compressive)", |l| l.z.map(|c| c.z_plus)),
        ("z− (tensile)", |l| l.z.map(|c| c.z_minus)),
        ("z0 (no force)", |l| l.z.map(|c| c.z_zero)),
    ];
    let curves = branch_curves(seeds, &picks, false);
    let top = curves
        .iter()
        .flat_map(|(_, p, _)| p.iter().map(|q| q.1))
        .fold(0.0, f64::max);
    let (file, y) = ("consolidation-z", "interactions per grain");
    cycle_plot(out, file, "Coordination", y, seeds.len(), &curves, |spec| {
        // Room above the curves for the legend.
        spec.y_range = Some((0.0, 1.75 * top));
    })
}

/// GRC08 Fig. 22: the bulk and shear moduli along the cycle (in K_N, log scale), mean over
/// the seeds at each level every seed reached with its moduli, with the Voigt estimates:
/// `consolidation-moduli.svg` and `.png` in `out`; nothing without them.
pub fn plot_moduli(out: &Path, seeds: &[SeedCurve]) -> Result<Vec<PathBuf>, PlotError> {
    let picks: [Pick; 4] = [
        ("B", |l| l.moduli.map(|m| m.bulk)),
        ("G", |l| l.moduli.map(|m| m.shear)),
        ("B^V (Voigt)", |l| l.moduli.map(|m| m.voigt_bulk)),
        ("G^V (Voigt)", |l| l.moduli.map(|m| m.voigt_shear)),
    ];
    let curves = branch_curves(seeds, &picks, true);
    let (file, y) = ("consolidation-moduli", "modulus / K_N");
    cycle_plot(
        out,
        file,
        "Elastic moduli",
        y,
        seeds.len(),
        &curves,
        |spec| {
            spec.y_axis = plots::Axis::Log;
            spec.legend_lower_right = true;
        },
    )
}

/// GRC08 Fig. 16 (and ξ of Fig. 15's fits): ξ' = ⟨R⟩_w, the pores' mean radius of gyration,
/// and ξ of the fractal fit of I(k) along the cycle, mean over the seeds:
/// `consolidation-xi.svg` and `.png` in `out`; nothing without the levels' states.
pub fn plot_blob_size(out: &Path, seeds: &[SeedCurve]) -> Result<Vec<PathBuf>, PlotError> {
    let picks: [Pick; 2] = [
        ("ξ' (pores' radius of gyration)", Level::pore_radius),
        ("ξ (fit of I(k))", Level::xi),
    ];
    let curves = branch_curves(seeds, &picks, true);
    let (file, y) = ("consolidation-xi", "length / a");
    cycle_plot(out, file, "Blob size", y, seeds.len(), &curves, |spec| {
        spec.y_axis = plots::Axis::Log;
    })
}

/// GRC08 Fig. 15: I(k) at P* = 0.01, 0.178 and 1 on the loading branch — the seeds' mean over
/// its standard-error band with its fit by GRC07 (28) (`means`, [`mean_scattering`]), or one
/// seed's own — into `consolidation-ik.svg` and `.png` in `out`; nothing without the states.
pub fn plot_scattering(
    out: &Path,
    seeds: &[SeedCurve],
    means: &[(f64, &'static str, density::MeanScattering)],
) -> Result<Vec<PathBuf>, PlotError> {
    let mut owned: Vec<plots::OwnedCurve> = Vec::new();
    let fit_curve =
        |p: f64, f: &FractalFit| (format!("P* = {p}: {}", f.legend()), f.curve(60), None);
    for (p, _) in SCATTERING_AT {
        if let Some((_, _, m)) = means.iter().find(|(q, _, _)| *q == p) {
            let s = &m.scattering;
            let label = format!("P* = {p}, mean of {} seeds ± s.e.", m.samples);
            owned.push((label, s.points(), Some(s.error_band())));
            let fit = m.fit.as_ref().filter(|f| f.has_fractal_range());
            owned.extend(fit.map(|f| fit_curve(p, f)));
        } else if let [one] = seeds {
            let Some(l) = loading_level(&one.levels, p) else {
                continue;
            };
            let Some(d) = &l.density else { continue };
            let label = format!("P* = {p}, seed {}", one.seed);
            owned.push((label, d.scattering.points(), None));
            owned.extend(l.fractal().map(|f| fit_curve(p, f)));
        }
    }
    if owned.is_empty() {
        return Ok(Vec::new());
    }
    let title = "Scattering function I(k) along the loading branch";
    let files = plots::scattering(&out.join("consolidation-ik"), title, &owned)?;
    Ok(vec![files.svg, files.png])
}

fn curve(law: &ConsolidationLaw, from: f64, to: f64) -> Vec<(f64, f64)> {
    (0..=80)
        .map(|q| from * (to / from).powf(q as f64 / 80.0))
        .map(|p| (p, law.phi(p)))
        .collect()
}
