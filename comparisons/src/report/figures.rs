//! The figures of a set of packings (seeds of one state, or one state in several codes): P(f)
//! and g(r) overlaid, with the DTS fit for cohesionless frictionless spheres (AR07 Fig. 4), and
//! I(k) with its GRC07 (28) fit for 2D cohesive packings (GRC07 Fig. 23).

use crate::metrics::density::MeanScattering;
use crate::metrics::fractal_fit::FractalFit;
use crate::metrics::Analysis;
use crate::report::plots;
use std::path::{Path, PathBuf};

/// What a set of figures wrote, and why any figure is missing (one sentence each).
#[derive(Debug, Default)]
pub struct Written {
    pub files: Vec<PathBuf>,
    pub warnings: Vec<String>,
}

impl Written {
    fn add(&mut self, what: &str, r: Result<plots::PlotFiles, plots::PlotError>) {
        self.record(&format!("{what} plot"), r.map(|f| vec![f.svg, f.png]));
    }

    /// The files of a plot, or a warning that `what` could not be drawn.
    pub fn record(&mut self, what: &str, r: Result<Vec<PathBuf>, plots::PlotError>) {
        match r {
            Ok(files) => self.files.extend(files),
            Err(e) => self.warnings.push(format!("no {what}: {e}")),
        }
    }

    /// The SVG files (what `report.html` inlines).
    pub fn svgs(&self) -> impl Iterator<Item = &PathBuf> {
        self.files
            .iter()
            .filter(|p| p.extension().is_some_and(|e| e == "svg"))
    }
}

/// P(f) and g(r) of every analysis (one curve per label: seeds, codes), overlaid; I(k) where
/// the packings have it.
/// With `seeds` (the analyses are seeds of one state), P(f) is their mean over the band of
/// their spread; with `mean_ik` (their mean I(k), [`crate::metrics::density::mean_scattering`])
/// the I(k) plot shows it over its standard-error band with its fit, in place of each seed's fit.
pub fn packings(
    out: &Path,
    labels: &[String],
    analyses: &[Analysis],
    seeds: bool,
    mean_ik: Option<&MeanScattering>,
) -> Written {
    let mut written = Written::default();
    let pf: Vec<Vec<(f64, f64)>> = analyses.iter().map(pf_points).collect();
    let gr: Vec<Vec<(f64, f64)>> = analyses
        .iter()
        .map(|a| points(a.structure.pair_correlation.as_ref().map(|g| (&g.x, &g.y))))
        .collect();
    fn series<'a>(pts: &'a [Vec<(f64, f64)>], labels: &'a [String]) -> Vec<plots::Series<'a>> {
        pts.iter()
            .zip(labels)
            .filter(|(p, _)| !p.is_empty())
            .map(|(p, l)| plots::Series::new(l, p))
            .collect()
    }
    let banded = seeds.then(|| plots::seed_band(&pf)).flatten();
    let band_label = format!("mean of {} seeds (band: their spread)", pf.len());
    let pf_series = match &banded {
        Some(b) => vec![plots::Series::new(&band_label, &b.mean).with_band(&b.band)],
        None => series(&pf, labels),
    };
    written.add("P(f)", pf_plot(out, &pf_series, analyses.first()));
    written.add(
        "g(r)",
        plots::pair_correlation(&out.join("gr"), &series(&gr, labels), Some(8.0)),
    );
    // GRC07 Fig. 23: I(k) of each seed and its fit by GRC07 (28), 2D cohesive packings; over
    // seeds, their mean and its fit.
    let mut ik: Vec<plots::OwnedCurve> = Vec::new();
    let fit_curve =
        |who: &str, f: &FractalFit| (format!("{who}: {}", f.legend()), f.curve(60), None);
    for (a, l) in analyses.iter().zip(labels) {
        let Some(d) = &a.density else { continue };
        ik.push((l.clone(), d.scattering.points(), None));
        if let (None, Some(f)) = (mean_ik, &d.fit) {
            ik.push(fit_curve(l, f));
        }
    }
    if let Some(m) = mean_ik {
        let s = &m.scattering;
        let label = format!("mean of {} seeds ± s.e.", m.samples);
        ik.push((label, s.points(), Some(s.error_band())));
        if let Some(f) = &m.fit {
            ik.push(fit_curve("mean", f));
        }
    }
    if !ik.is_empty() {
        written.add(
            "I(k)",
            plots::scattering(&out.join("ik"), "Scattering function I(k)", &ik),
        );
    }
    written
}

/// P(f) of every code as the mean of its seeds over the band of their spread (`pf.svg/png`);
/// nothing when no code has two seeds with P(f).
pub fn seed_bands(out: &Path, per_code: &[(String, Vec<Analysis>)]) -> Written {
    let mut written = Written::default();
    let bands: Vec<(String, plots::SeedBand)> = per_code
        .iter()
        .filter_map(|(code, list)| {
            let pf: Vec<Vec<(f64, f64)>> = list.iter().map(pf_points).collect();
            let label = format!("{code} (mean of {} seeds, band: their spread)", pf.len());
            Some((label, plots::seed_band(&pf)?))
        })
        .collect();
    let series: Vec<plots::Series> = bands
        .iter()
        .map(|(l, b)| plots::Series::new(l, &b.mean).with_band(&b.band))
        .collect();
    if !series.is_empty() {
        let like = per_code.first().and_then(|(_, l)| l.first());
        written.add("P(f)", pf_plot(out, &series, like));
    }
    written
}

/// P(f) of an analysis as points (empty without one).
fn pf_points(a: &Analysis) -> Vec<(f64, f64)> {
    points(a.forces.pdf.as_ref().map(|h| (&h.x, &h.y)))
}

/// `pf.svg` and `.png` of `series`, styled for the packings `like` is one of: the DTS fit for
/// cohesionless frictionless spheres only, P(f) of N itself for cohesive ones.
fn pf_plot(
    out: &Path,
    series: &[plots::Series],
    like: Option<&Analysis>,
) -> Result<plots::PlotFiles, plots::PlotError> {
    let cohesive = like.is_some_and(|a| a.cohesive);
    let frictionless_spheres =
        like.is_some_and(|a| a.dimension == 3 && a.mu == Some(0.0) && !a.cohesive);
    plots::force_distribution(&out.join("pf"), series, frictionless_spheres, cohesive)
}

fn points(xy: Option<(&Vec<f64>, &Vec<f64>)>) -> Vec<(f64, f64)> {
    xy.map(|(x, y)| x.iter().copied().zip(y.iter().copied()).collect())
        .unwrap_or_default()
}
