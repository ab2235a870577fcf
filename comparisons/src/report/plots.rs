//! Plots of packing metrics, written as SVG and PNG with `plotters` (pure Rust: text in the PNG is
//! drawn with the DejaVu Sans font embedded from `comparisons/assets/`, so no system library or
//! installed font is needed).
//!
//! Every function takes plain data ([`Series`]: a label and `&[(x, y)]` points) and an output path
//! stem `out`: it writes `out.svg` and `out.png` (any extension of `out` is replaced). Both files
//! are first written to hidden temporary files in the same directory and renamed into place only
//! once both are complete, so a failure leaves neither a partial file nor a stray temporary.
//!
//! * [`force_distribution`]: P(f), f = N/⟨N⟩, on a log-linear plot, with the DTS fit that AR07
//!   overlays in Fig. 4 ([`dts_fit`]).
//! * [`pair_correlation`]: g(r) versus r/a, one curve per code or seed.
//! * [`line_plot`]: any set of series, e.g. z(h) (AR07 Figs. 6, 9), with linear or log axes.
//!
//! ```no_run
//! use grainbench_comparisons::report::plots::{force_distribution, Series};
//! let hist = vec![(0.1, 0.55), (0.3, 0.80), (0.5, 0.85), (1.0, 0.60), (2.0, 0.20)];
//! let files = force_distribution(
//!     std::path::Path::new("out/pf-state-A"),
//!     &[Series::new("grainbench, seed 1", &hist)],
//!     true,
//!     false,
//! )
//! .unwrap();
//! println!("{} {}", files.svg.display(), files.png.display());
//! ```

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

/// DejaVu Sans (Bitstream Vera licence, see `comparisons/assets/LICENSE-DejaVu.txt`).
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
/// The family name the embedded font is registered under.
const FONT_FAMILY: &str = "sans-serif";

/// Image size in pixels (SVG user units) of every plot.
pub const SIZE: (u32, u32) = (900, 600);

/// Colours for successive series (the "tab10" palette).
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The fit of the distribution of normalized normal forces f = N/⟨N⟩ proposed by Donev,
/// Torquato & Stillinger (DTS, PRE 71, 011105 (2005), AR07 ref. \[53\]) for rigid frictionless
/// sphere packings, as AR07 quotes it in the caption of Fig. 4:
///
/// P(f) = (3.43 f² + 1.45 − 1.18 / (1 + 4.71 f)) · exp(−2.25 f).
///
/// It is a fit, not an exact density: its integral over f ≥ 0 is 1.009 and its mean 1.028.
/// Defined for f ≥ 0; returns 0 for negative f.
pub fn dts_fit(f: f64) -> f64 {
    if f < 0.0 {
        return 0.0;
    }
    (3.43 * f * f + 1.45 - 1.18 / (1.0 + 4.71 * f)) * (-2.25 * f).exp()
}

/// [`dts_fit`] sampled at `n` evenly spaced points of [0, f_max].
pub fn dts_fit_curve(f_max: f64, n: usize) -> Vec<(f64, f64)> {
    let n = n.max(2);
    (0..n)
        .map(|i| {
            let f = f_max * i as f64 / (n - 1) as f64;
            (f, dts_fit(f))
        })
        .collect()
}

/// A point of a shaded band: x, low, high.
pub type Band = (f64, f64, f64);

/// The mean of several curves and their spread.
#[derive(Debug, Clone, PartialEq)]
pub struct SeedBand {
    pub mean: Vec<(f64, f64)>,
    pub band: Vec<Band>,
}

/// The mean of curves sampled on one grid (histograms of one bin width: P(f) of several
/// seeds) and their spread, (x, min, max); a bin a curve lacks counts as 0 (no samples there).
/// `None` when the grids differ (another bin width) or there are fewer than two curves.
pub fn seed_band(curves: &[Vec<(f64, f64)>]) -> Option<SeedBand> {
    let width = |c: &Vec<(f64, f64)>| (c.len() >= 2).then(|| c[1].0 - c[0].0);
    let w = width(curves.first()?)?;
    if curves.len() < 2
        || curves
            .iter()
            .any(|c| width(c).is_none_or(|v| (v - w).abs() > 1e-9 * w.abs()))
    {
        return None;
    }
    let key = |x: f64| (x / w).round() as i64;
    let mut grid: std::collections::BTreeMap<i64, Vec<f64>> = Default::default();
    for (k, c) in curves.iter().enumerate() {
        for &(x, y) in c {
            grid.entry(key(x))
                .or_insert_with(|| vec![0.0; curves.len()])[k] = y;
        }
    }
    let n = curves.len() as f64;
    let offset = curves[0][0].0 - key(curves[0][0].0) as f64 * w;
    let mut mean = Vec::new();
    let mut band = Vec::new();
    for (k, ys) in grid {
        let x = k as f64 * w + offset;
        mean.push((x, ys.iter().sum::<f64>() / n));
        let lo = ys.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        band.push((x, lo, hi));
    }
    Some(SeedBand { mean, band })
}

/// One labelled curve: points (x, y) in drawing order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Series<'a> {
    /// Legend text.
    pub label: &'a str,
    /// The points.
    pub points: &'a [(f64, f64)],
    /// How this series is drawn, if not as the plot's [`LinePlot::marks`] say.
    pub marks: Option<Marks>,
    /// A shaded band (x, low, high) behind the curve, e.g. the spread over seeds.
    pub band: Option<&'a [(f64, f64, f64)]>,
}

impl<'a> Series<'a> {
    /// A series from a label and its points.
    pub fn new(label: &'a str, points: &'a [(f64, f64)]) -> Self {
        Series {
            label,
            points,
            marks: None,
            band: None,
        }
    }

    /// The same series over a shaded band (x, low, high).
    pub fn with_band(self, band: &'a [(f64, f64, f64)]) -> Self {
        Series {
            band: Some(band),
            ..self
        }
    }

    /// The same series drawn with `marks` whatever the plot's.
    pub fn with_marks(self, marks: Marks) -> Self {
        Series {
            marks: Some(marks),
            ..self
        }
    }
}

/// Scale of an axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Axis {
    /// Linear.
    #[default]
    Linear,
    /// Logarithmic (points with a non-positive coordinate on this axis are left out).
    Log,
}

/// How the series of a [`LinePlot`] are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Marks {
    /// Lines joining the points.
    #[default]
    Lines,
    /// Markers only.
    Points,
    /// Lines and markers.
    LinesAndPoints,
}

/// A plot of several series.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot<'a> {
    /// Caption above the plot.
    pub title: &'a str,
    /// Horizontal axis label.
    pub x_label: &'a str,
    /// Vertical axis label.
    pub y_label: &'a str,
    /// The curves, coloured in turn.
    pub series: &'a [Series<'a>],
    /// Horizontal scale.
    pub x_axis: Axis,
    /// Vertical scale.
    pub y_axis: Axis,
    /// Horizontal range; `None`: the data's.
    pub x_range: Option<(f64, f64)>,
    /// Vertical range; `None`: the data's.
    pub y_range: Option<(f64, f64)>,
    /// Lines, markers or both.
    pub marks: Marks,
    /// Where the legend goes (upper right unless the curves are there).
    pub legend_lower_right: bool,
}

impl<'a> LinePlot<'a> {
    /// Linear axes, lines, ranges from the data.
    pub fn new(
        title: &'a str,
        x_label: &'a str,
        y_label: &'a str,
        series: &'a [Series<'a>],
    ) -> Self {
        LinePlot {
            title,
            x_label,
            y_label,
            series,
            x_axis: Axis::Linear,
            y_axis: Axis::Linear,
            x_range: None,
            y_range: None,
            marks: Marks::Lines,
            legend_lower_right: false,
        }
    }
}

/// The two files a plot function wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlotFiles {
    /// `out.svg`
    pub svg: PathBuf,
    /// `out.png`
    pub png: PathBuf,
}

/// Why a plot was not written. Nothing is left on disk in any of these cases.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The directory of the output path does not exist (or is not a directory).
    #[error("plot output directory {0} does not exist")]
    MissingDirectory(PathBuf),
    /// The output path has no file name.
    #[error("plot output path {0} has no file name")]
    InvalidPath(PathBuf),
    /// No series has a point that can be drawn (finite, and positive on log axes).
    #[error("nothing to plot in {0:?}: no finite point (positive on log axes)")]
    NoData(String),
    /// An explicit axis range is empty, reversed, not finite or not positive on a log axis.
    #[error("invalid {axis} range {range:?} in {title:?}")]
    InvalidRange {
        /// `"x"` or `"y"`.
        axis: &'static str,
        /// The range given.
        range: (f64, f64),
        /// The plot's title.
        title: String,
    },
    /// The embedded font could not be registered.
    #[error("the embedded DejaVu Sans font could not be loaded")]
    Font,
    /// plotters failed while drawing.
    #[error("drawing {path}: {message}")]
    Draw {
        /// The file being drawn.
        path: PathBuf,
        /// plotters' message.
        message: String,
    },
    /// Writing or renaming a file failed.
    #[error("writing {path}: {source}")]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// P(f) of normalized normal forces f = N/⟨N⟩ on a log-linear plot (AR07 Figs. 4 and 15), or,
/// with `cohesive`, of N in the force unit, tensile forces negative (GRC07 Fig. 9).
///
/// `histograms`: one series per code, seed or state, as (bin centre, probability density); empty
/// bins (P = 0) are left out on the log scale. With `with_dts_fit`, the DTS fit ([`dts_fit`]) is
/// drawn as a dashed line over the same f range — it describes frictionless (A-type) packings.
pub fn force_distribution(
    out: &Path,
    histograms: &[Series],
    with_dts_fit: bool,
    cohesive: bool,
) -> Result<PlotFiles, PlotError> {
    let f_max = histograms
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|(f, p)| f.is_finite() && p.is_finite() && *p > 0.0)
        .map(|(f, _)| *f)
        .fold(f64::NAN, f64::max);
    let fit = if with_dts_fit {
        dts_fit_curve(
            if f_max.is_finite() && f_max > 0.0 {
                f_max
            } else {
                5.0
            },
            200,
        )
    } else {
        Vec::new()
    };
    let mut curves: Vec<Curve> = histograms
        .iter()
        .enumerate()
        .map(|(i, s)| Curve::new(s, PALETTE[i % PALETTE.len()], Marks::LinesAndPoints))
        .collect();
    if with_dts_fit {
        curves.push(Curve {
            label: "DTS fit (AR07 Fig. 4)".to_string(),
            points: &fit,
            color: BLACK,
            marks: Marks::Lines,
            dashed: true,
            band: None,
        });
    }
    let spec = Spec {
        title: "Normal force distribution P(f)",
        x_label: if cohesive {
            "f = N in the force unit (tensile < 0)"
        } else {
            "f = N / <N>"
        },
        y_label: "P(f)",
        curves,
        x_axis: Axis::Linear,
        y_axis: Axis::Log,
        x_range: None,
        y_range: None,
        legend_lower_right: false,
    };
    write_plot(out, &spec)
}

/// Pair correlation g(r) versus r/a, one curve per code or seed (AR07 Figs. 5 and 8).
///
/// `y_max` caps the vertical axis (the contact peak of g(r) at r = a diverges as the contacts
/// stiffen); `None` takes the data's maximum.
pub fn pair_correlation(
    out: &Path,
    curves: &[Series],
    y_max: Option<f64>,
) -> Result<PlotFiles, PlotError> {
    let y_range = y_max.map(|m| (0.0, m));
    let spec = Spec {
        title: "Pair correlation g(r)",
        x_label: "r / a",
        y_label: "g(r)",
        curves: curves
            .iter()
            .enumerate()
            .map(|(i, s)| Curve::new(s, PALETTE[i % PALETTE.len()], Marks::Lines))
            .collect(),
        x_axis: Axis::Linear,
        y_axis: Axis::Linear,
        x_range: None,
        y_range,
        legend_lower_right: false,
    };
    write_plot(out, &spec)
}

/// A generic plot of several series: z(h), consolidation curves, anything (x, y).
pub fn line_plot(out: &Path, plot: &LinePlot) -> Result<PlotFiles, PlotError> {
    let spec = Spec {
        title: plot.title,
        x_label: plot.x_label,
        y_label: plot.y_label,
        curves: plot
            .series
            .iter()
            .enumerate()
            .map(|(i, s)| Curve::new(s, PALETTE[i % PALETTE.len()], s.marks.unwrap_or(plot.marks)))
            .collect(),
        x_axis: plot.x_axis,
        y_axis: plot.y_axis,
        x_range: plot.x_range,
        y_range: plot.y_range,
        legend_lower_right: plot.legend_lower_right,
    };
    write_plot(out, &spec)
}

/// A curve that owns its data (label, points, optional band), as plots assembled in a loop
/// collect them.
pub type OwnedCurve = (String, Vec<(f64, f64)>, Option<Vec<Band>>);

/// The scattering function I(k) against k a on log–log axes (GRC07 Fig. 23, GRC08 Fig. 15).
pub fn scattering(out: &Path, title: &str, curves: &[OwnedCurve]) -> Result<PlotFiles, PlotError> {
    let series: Vec<Series> = curves
        .iter()
        .map(|(label, points, band)| {
            let s = Series::new(label, points);
            match band {
                Some(b) => s.with_band(b),
                None => s,
            }
        })
        .collect();
    let mut plot = LinePlot::new(title, "k a", "I(k) / a²", &series);
    plot.x_axis = Axis::Log;
    plot.y_axis = Axis::Log;
    line_plot(out, &plot)
}

// ---------------------------------------------------------------------------------------------

struct Curve<'a> {
    label: String,
    points: &'a [(f64, f64)],
    color: RGBColor,
    marks: Marks,
    dashed: bool,
    band: Option<&'a [(f64, f64, f64)]>,
}

impl<'a> Curve<'a> {
    fn new(s: &Series<'a>, color: RGBColor, marks: Marks) -> Self {
        Curve {
            label: s.label.to_string(),
            points: s.points,
            color,
            marks,
            dashed: false,
            band: s.band,
        }
    }
}

/// An axis range (low, high).
type AxisRange = (f64, f64);

struct Spec<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    curves: Vec<Curve<'a>>,
    x_axis: Axis,
    y_axis: Axis,
    x_range: Option<(f64, f64)>,
    y_range: Option<(f64, f64)>,
    legend_lower_right: bool,
}

impl Spec<'_> {
    /// Whether a point can be drawn on these axes.
    fn drawable(&self, &(x, y): &(f64, f64)) -> bool {
        x.is_finite()
            && y.is_finite()
            && (self.x_axis == Axis::Linear || x > 0.0)
            && (self.y_axis == Axis::Linear || y > 0.0)
    }

    /// The drawable points of a curve that fall in the plotted ranges.
    fn visible(&self, c: &Curve, xr: (f64, f64), yr: (f64, f64)) -> Vec<(f64, f64)> {
        self.segments(c.points, xr, yr).concat()
    }

    /// The runs of drawable points in the plotted x range: a point that cannot be drawn (an
    /// empty histogram bin on a log axis) breaks the line instead of being bridged or drawn at
    /// the axis floor.
    fn segments(
        &self,
        points: &[(f64, f64)],
        xr: (f64, f64),
        yr: (f64, f64),
    ) -> Vec<Vec<(f64, f64)>> {
        let mut out: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for &p in points {
            if self.drawable(&p) && p.0 >= xr.0 && p.0 <= xr.1 {
                out.last_mut()
                    .expect("one run")
                    .push((p.0, p.1.clamp(yr.0, yr.1)));
            } else if !out.last().expect("one run").is_empty() {
                out.push(Vec::new());
            }
        }
        out.retain(|r| !r.is_empty());
        out
    }

    /// The band of a curve as closed polygons, one per run of x where both edges are drawable.
    fn band_polygons(
        &self,
        band: &[(f64, f64, f64)],
        xr: (f64, f64),
        yr: (f64, f64),
    ) -> Vec<Vec<(f64, f64)>> {
        let lo: Vec<(f64, f64)> = band.iter().map(|&(x, l, _)| (x, l)).collect();
        let hi: Vec<(f64, f64)> = band.iter().map(|&(x, _, h)| (x, h)).collect();
        // A run needs both edges: an empty lower edge on a log axis drops to the axis floor.
        let mut runs = Vec::new();
        for run in self.segments(&hi, xr, yr) {
            let (a, b) = (run[0].0, run[run.len() - 1].0);
            let low: Vec<(f64, f64)> = lo
                .iter()
                .filter(|p| p.0 >= a && p.0 <= b)
                .map(|&(x, y)| {
                    let y = if self.drawable(&(x, y)) { y } else { yr.0 };
                    (x, y.clamp(yr.0, yr.1))
                })
                .collect();
            let mut poly = run.clone();
            poly.extend(low.into_iter().rev());
            runs.push(poly);
        }
        runs
    }

    /// Axis ranges: explicit ones checked, others from the data with a margin.
    fn ranges(&self) -> Result<(AxisRange, AxisRange), PlotError> {
        let pts: Vec<(f64, f64)> = self
            .curves
            .iter()
            .flat_map(|c| c.points.iter().copied())
            .filter(|p| self.drawable(p))
            .collect();
        if pts.is_empty() {
            return Err(PlotError::NoData(self.title.to_string()));
        }
        let x = match self.x_range {
            Some(r) => check_range(r, self.x_axis, "x", self.title)?,
            None => data_range(pts.iter().map(|p| p.0), self.x_axis),
        };
        let y = match self.y_range {
            Some(r) => check_range(r, self.y_axis, "y", self.title)?,
            None => data_range(pts.iter().map(|p| p.1), self.y_axis),
        };
        Ok((x, y))
    }
}

fn check_range(
    r: (f64, f64),
    axis: Axis,
    name: &'static str,
    title: &str,
) -> Result<(f64, f64), PlotError> {
    let ok = r.0.is_finite() && r.1.is_finite() && r.0 < r.1 && (axis == Axis::Linear || r.0 > 0.0);
    if ok {
        Ok(r)
    } else {
        Err(PlotError::InvalidRange {
            axis: name,
            range: r,
            title: title.to_string(),
        })
    }
}

fn data_range(values: impl Iterator<Item = f64>, axis: Axis) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    match axis {
        Axis::Log => {
            if hi > lo {
                (lo / 1.5, hi * 1.5)
            } else {
                (lo / 10.0, hi * 10.0)
            }
        }
        Axis::Linear => {
            let pad = if hi > lo {
                0.05 * (hi - lo)
            } else {
                0.5 * lo.abs().max(1.0)
            };
            (lo - pad, hi + pad)
        }
    }
}

fn register_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, FONT).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(PlotError::Font)
    }
}

/// Draws `spec` on `root` with the axis kinds chosen at run time.
fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    spec: &Spec,
    xr: (f64, f64),
    yr: (f64, f64),
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    match (spec.x_axis, spec.y_axis) {
        (Axis::Linear, Axis::Linear) => draw_in(&root, spec, xr, yr, xr.0..xr.1, yr.0..yr.1),
        (Axis::Linear, Axis::Log) => {
            draw_in(&root, spec, xr, yr, xr.0..xr.1, (yr.0..yr.1).log_scale())
        }
        (Axis::Log, Axis::Linear) => {
            draw_in(&root, spec, xr, yr, (xr.0..xr.1).log_scale(), yr.0..yr.1)
        }
        (Axis::Log, Axis::Log) => draw_in(
            &root,
            spec,
            xr,
            yr,
            (xr.0..xr.1).log_scale(),
            (yr.0..yr.1).log_scale(),
        ),
    }?;
    root.present().map_err(|e| e.to_string())
}

fn draw_in<DB, XR, YR>(
    root: &DrawingArea<DB, Shift>,
    spec: &Spec,
    xr: (f64, f64),
    yr: (f64, f64),
    x_coord: XR,
    y_coord: YR,
) -> Result<(), String>
where
    DB: DrawingBackend,
    XR: AsRangedCoord<Value = f64>,
    YR: AsRangedCoord<Value = f64>,
    XR::CoordDescType: ValueFormatter<f64>,
    YR::CoordDescType: ValueFormatter<f64>,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let mut chart = ChartBuilder::on(root)
        .caption(spec.title, (FONT_FAMILY, 24))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(x_coord, y_coord)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(spec.x_label)
        .y_desc(spec.y_label)
        .label_style((FONT_FAMILY, 15))
        .axis_desc_style((FONT_FAMILY, 17))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    for c in &spec.curves {
        if let Some(band) = c.band {
            for poly in spec.band_polygons(band, xr, yr) {
                chart
                    .draw_series(std::iter::once(Polygon::new(
                        poly,
                        c.color.mix(0.2).filled(),
                    )))
                    .map_err(err)?;
            }
        }
    }
    for c in &spec.curves {
        let pts = spec.visible(c, xr, yr);
        let runs = spec.segments(c.points, xr, yr);
        let color = c.color;
        let style = color.stroke_width(2);
        let lines = matches!(c.marks, Marks::Lines | Marks::LinesAndPoints);
        let markers = matches!(c.marks, Marks::Points | Marks::LinesAndPoints);
        // The legend entry hangs on the first element drawn for the curve; lines are drawn run
        // by run (gaps at points that cannot be drawn).
        let anno = if lines && c.dashed {
            chart
                .draw_series(
                    runs.iter()
                        .flat_map(|r| DashedLineSeries::new(r.clone(), 10, 6, style)),
                )
                .map_err(err)?
        } else if lines {
            chart
                .draw_series(runs.iter().flat_map(|r| LineSeries::new(r.clone(), style)))
                .map_err(err)?
        } else {
            chart
                .draw_series(pts.iter().map(|p| Circle::new(*p, 3, color.filled())))
                .map_err(err)?
        };
        anno.label(c.label.as_str()).legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(2))
        });
        if lines && markers {
            chart
                .draw_series(pts.iter().map(|p| Circle::new(*p, 3, color.filled())))
                .map_err(err)?;
        }
    }
    chart
        .configure_series_labels()
        .label_font((FONT_FAMILY, 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(if spec.legend_lower_right {
            SeriesLabelPosition::LowerRight
        } else {
            SeriesLabelPosition::UpperRight
        })
        .draw()
        .map_err(err)?;
    Ok(())
}

/// A temporary file next to the final one, removed on drop unless kept.
struct TempFile {
    path: PathBuf,
    keep: bool,
}

impl TempFile {
    /// `.<name>.<pid>-<counter>.tmp.<ext>` in `dir` (the extension stays last: the PNG encoder
    /// picks the format from it).
    fn new(dir: &Path, name: &str, ext: &str) -> TempFile {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let file = format!(".{name}.{}-{n}.tmp.{ext}", std::process::id());
        TempFile {
            path: dir.join(file),
            keep: false,
        }
    }

    fn persist(mut self, to: &Path) -> Result<(), PlotError> {
        std::fs::rename(&self.path, to).map_err(|source| PlotError::Io {
            path: to.to_path_buf(),
            source,
        })?;
        self.keep = true;
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if !self.keep {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

fn with_ext(stem: &Path, ext: &str) -> PathBuf {
    let mut p = stem.to_path_buf();
    p.set_extension(ext);
    p
}

/// Renders `spec` to `out.svg` and `out.png`, each through a temporary file renamed at the end.
fn write_plot(out: &Path, spec: &Spec) -> Result<PlotFiles, PlotError> {
    let name: OsString = out
        .file_stem()
        .filter(|s| !s.is_empty())
        .ok_or_else(|| PlotError::InvalidPath(out.to_path_buf()))?
        .to_os_string();
    let name = name.to_string_lossy().into_owned();
    let dir = match out.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(PlotError::MissingDirectory(dir));
    }
    let (xr, yr) = spec.ranges()?;
    register_font()?;
    let files = PlotFiles {
        svg: with_ext(out, "svg"),
        png: with_ext(out, "png"),
    };

    // SVG: render into memory, then write the temporary file.
    let mut svg = String::new();
    draw(
        SVGBackend::with_string(&mut svg, SIZE).into_drawing_area(),
        spec,
        xr,
        yr,
    )
    .map_err(|message| PlotError::Draw {
        path: files.svg.clone(),
        message,
    })?;
    let svg_tmp = TempFile::new(&dir, &name, "svg");
    std::fs::write(&svg_tmp.path, svg.as_bytes()).map_err(|source| PlotError::Io {
        path: svg_tmp.path.clone(),
        source,
    })?;

    // PNG: the bitmap backend encodes to the temporary path when the drawing is presented.
    let png_tmp = TempFile::new(&dir, &name, "png");
    draw(
        BitMapBackend::new(&png_tmp.path, SIZE).into_drawing_area(),
        spec,
        xr,
        yr,
    )
    .map_err(|message| PlotError::Draw {
        path: files.png.clone(),
        message,
    })?;
    if !png_tmp.path.is_file() {
        return Err(PlotError::Draw {
            path: files.png.clone(),
            message: "the PNG encoder wrote nothing".into(),
        });
    }
    svg_tmp.persist(&files.svg)?;
    png_tmp.persist(&files.png)?;
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    fn assert_png(path: &Path) {
        let bytes = std::fs::read(path).unwrap();
        assert!(
            bytes.len() > 1000,
            "{} is {} bytes",
            path.display(),
            bytes.len()
        );
        assert_eq!(bytes[..8], PNG_SIGNATURE, "{}", path.display());
    }

    /// An exponential-ish histogram like AR07 Fig. 15, with an empty bin.
    fn histogram(scale: f64) -> Vec<(f64, f64)> {
        (0..30)
            .map(|i| {
                let f = 0.1 + 0.2 * i as f64;
                let p = if i == 25 { 0.0 } else { scale * dts_fit(f) };
                (f, p)
            })
            .collect()
    }

    #[test]
    fn seed_band_is_the_mean_and_spread_on_the_common_bins() {
        let a = vec![(0.05, 1.0), (0.15, 2.0)];
        let b = vec![(0.05, 3.0), (0.15, 0.0), (0.25, 4.0)];
        let SeedBand { mean, band } = seed_band(&[a.clone(), b]).unwrap();
        assert_eq!(mean.len(), 3);
        assert!((mean[0].1 - 2.0).abs() < 1e-12 && (mean[2].1 - 2.0).abs() < 1e-12);
        assert!((mean[2].0 - 0.25).abs() < 1e-12);
        assert_eq!((band[1].1, band[1].2), (0.0, 2.0));
        // A bin a seed lacks is empty for it: the band reaches 0.
        assert_eq!((band[2].1, band[2].2), (0.0, 4.0));
        // Another bin width: no band.
        assert!(seed_band(&[a.clone(), vec![(0.1, 1.0), (0.3, 1.0)]]).is_none());
        assert!(seed_band(&[a]).is_none());
    }

    #[test]
    fn lines_break_at_points_that_cannot_be_drawn() {
        let pts = [
            (0.1, 1.0),
            (0.2, 0.0),
            (0.3, 2.0),
            (0.4, 3.0),
            (0.5, f64::NAN),
        ];
        let c = Series::new("p", &pts);
        let spec = Spec {
            title: "t",
            x_label: "x",
            y_label: "y",
            curves: vec![Curve::new(&c, BLACK, Marks::Lines)],
            x_axis: Axis::Linear,
            y_axis: Axis::Log,
            x_range: None,
            y_range: None,
            legend_lower_right: false,
        };
        let runs = spec.segments(&pts, (0.0, 1.0), (1e-3, 10.0));
        assert_eq!(runs, vec![vec![(0.1, 1.0)], vec![(0.3, 2.0), (0.4, 3.0)]]);
        // The band's polygon closes along its lower edge, an empty bin at the axis floor.
        let band = [(0.3, 0.0, 2.0), (0.4, 1.0, 3.0)];
        let poly = spec.band_polygons(&band, (0.0, 1.0), (1e-3, 10.0));
        assert_eq!(
            poly,
            vec![vec![(0.3, 2.0), (0.4, 3.0), (0.4, 1.0), (0.3, 1e-3)]]
        );
    }

    #[test]
    fn dts_fit_matches_the_formula_of_ar07_fig4() {
        assert!((dts_fit(0.0) - (1.45 - 1.18)).abs() < 1e-15);
        let f = 1.0f64;
        let expect = (3.43 + 1.45 - 1.18 / 5.71) * (-2.25f64).exp();
        assert!((dts_fit(f) - expect).abs() < 1e-15);
        assert_eq!(dts_fit(-1.0), 0.0);
        // Midpoint-rule moments: a fit close to a normalized density of mean 1.
        let h = 1e-3;
        let (mut norm, mut mean) = (0.0, 0.0);
        for i in 0..60_000 {
            let f = (i as f64 + 0.5) * h;
            norm += dts_fit(f) * h;
            mean += f * dts_fit(f) * h;
        }
        assert!((norm - 1.009).abs() < 1e-3, "integral {norm}");
        assert!((mean - 1.028).abs() < 1e-3, "mean {mean}");
        let c = dts_fit_curve(4.0, 5);
        assert_eq!(c.len(), 5);
        assert_eq!(c[4].0, 4.0);
        assert_eq!(c[2].1, dts_fit(2.0));
    }

    #[test]
    fn force_distribution_writes_svg_and_png_with_labels() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (histogram(1.0), histogram(0.9));
        let files = force_distribution(
            &dir.path().join("pf-A"),
            &[
                Series::new("grainbench seed 1", &a),
                Series::new("LIGGGHTS seed 1", &b),
            ],
            true,
            false,
        )
        .unwrap();
        assert_eq!(files.svg, dir.path().join("pf-A.svg"));
        assert_eq!(files.png, dir.path().join("pf-A.png"));
        let svg = std::fs::read_to_string(&files.svg).unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..60.min(svg.len())]);
        for label in [
            "grainbench seed 1",
            "LIGGGHTS seed 1",
            "DTS fit (AR07 Fig. 4)",
            "P(f)",
        ] {
            assert!(svg.contains(label), "SVG lacks {label:?}");
        }
        assert_png(&files.png);
        assert_eq!(
            entries(dir.path()),
            ["pf-A.png", "pf-A.svg"],
            "no temporary left"
        );
        assert!(svg.contains("f = N / &lt;N&gt;") || svg.contains("f = N / <N>"));
        // Cohesive: forces in the force unit, tensile ones negative, no DTS fit.
        let t = vec![(-0.4, 0.1), (0.2, 0.8), (1.0, 0.3)];
        let files = force_distribution(
            &dir.path().join("pf-c"),
            &[Series::new("c", &t)],
            false,
            true,
        )
        .unwrap();
        let svg = std::fs::read_to_string(&files.svg).unwrap();
        assert!(svg.contains("tensile &lt; 0") || svg.contains("tensile < 0"));
        assert!(!svg.contains("DTS fit"));
    }

    #[test]
    fn pair_correlation_one_curve_per_seed() {
        let dir = tempfile::tempdir().unwrap();
        let curves: Vec<Vec<(f64, f64)>> = (0..3)
            .map(|s| {
                (0..300)
                    .map(|i| {
                        let r = 0.9 + 0.01 * i as f64;
                        let g = if r < 1.0 {
                            0.0
                        } else {
                            1.0 + (-(r - 1.0) * 3.0).exp()
                                * (8.0 + s as f64)
                                * (6.0 * r).cos().abs()
                        };
                        (r, g)
                    })
                    .collect()
            })
            .collect();
        let labels = ["seed 1", "seed 2", "seed 3"];
        let series: Vec<Series> = labels
            .iter()
            .zip(&curves)
            .map(|(l, c)| Series::new(l, c))
            .collect();
        let files = pair_correlation(&dir.path().join("g_r.anything"), &series, Some(4.0)).unwrap();
        assert_eq!(files.svg, dir.path().join("g_r.svg"), "extension replaced");
        let svg = std::fs::read_to_string(&files.svg).unwrap();
        for l in labels {
            assert!(svg.contains(l), "SVG lacks {l:?}");
        }
        assert!(svg.contains("r / a") && svg.contains("g(r)"));
        assert_png(&files.png);
    }

    #[test]
    fn generic_line_plot_log_axes_and_escaping() {
        let dir = tempfile::tempdir().unwrap();
        let zh: Vec<(f64, f64)> = (0..40)
            .map(|i| {
                let h = 1e-4 * 10f64.powf(i as f64 / 10.0);
                (h, 0.8 * h.powf(0.6))
            })
            .collect();
        let with_zero = [(0.0, 1.0), (1e-3, 0.02), (1e-2, 0.1)];
        let series = [
            Series::new("z^II(h) - z^II(0), D", &zh),
            Series::new("a <b> & c", &with_zero),
        ];
        let mut plot = LinePlot::new("z(h), AR07 Fig. 10", "h / a", "z(h) - z(0)", &series);
        plot.x_axis = Axis::Log;
        plot.y_axis = Axis::Log;
        plot.marks = Marks::Points;
        let files = line_plot(&dir.path().join("zh"), &plot).unwrap();
        let svg = std::fs::read_to_string(&files.svg).unwrap();
        assert!(svg.contains("z^II(h) - z^II(0), D"));
        assert!(
            svg.contains("a &lt;b&gt; &amp; c"),
            "labels are XML-escaped"
        );
        assert_png(&files.png);
        // Overwriting an existing plot replaces it.
        plot.marks = Marks::LinesAndPoints;
        line_plot(&dir.path().join("zh"), &plot).unwrap();
        assert_eq!(entries(dir.path()), ["zh.png", "zh.svg"]);
    }

    #[test]
    fn missing_directory_is_a_clear_error_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("no-such-dir");
        let h = histogram(1.0);
        let err = force_distribution(&missing.join("pf"), &[Series::new("s", &h)], true, false)
            .unwrap_err();
        assert!(
            matches!(&err, PlotError::MissingDirectory(d) if d == &missing),
            "{err:?}"
        );
        let msg = err.to_string();
        assert!(
            msg.contains("does not exist") && msg.contains("no-such-dir"),
            "{msg}"
        );
        assert!(!missing.exists());
        assert!(entries(dir.path()).is_empty(), "{:?}", entries(dir.path()));
    }

    #[test]
    fn bad_input_is_rejected_without_leaving_files() {
        let dir = tempfile::tempdir().unwrap();
        let nothing: [(f64, f64); 2] = [(f64::NAN, 1.0), (1.0, f64::INFINITY)];
        let err = line_plot(
            &dir.path().join("empty"),
            &LinePlot::new("empty", "x", "y", &[Series::new("nan", &nothing)]),
        )
        .unwrap_err();
        assert!(matches!(err, PlotError::NoData(_)), "{err:?}");
        // Only zeros on a log axis: nothing drawable.
        let zeros = [(1.0, 0.0), (2.0, 0.0)];
        let err = force_distribution(
            &dir.path().join("pf"),
            &[Series::new("z", &zeros)],
            false,
            false,
        )
        .unwrap_err();
        assert!(matches!(err, PlotError::NoData(_)), "{err:?}");
        let ok = [(1.0, 1.0), (2.0, 2.0)];
        let series = [Series::new("ok", &ok)];
        let mut plot = LinePlot::new("bad range", "x", "y", &series);
        plot.y_axis = Axis::Log;
        plot.y_range = Some((0.0, 1.0));
        let err = line_plot(&dir.path().join("range"), &plot).unwrap_err();
        assert!(
            matches!(err, PlotError::InvalidRange { axis: "y", .. }),
            "{err:?}"
        );
        let err = line_plot(Path::new(""), &LinePlot::new("t", "x", "y", &series)).unwrap_err();
        assert!(matches!(err, PlotError::InvalidPath(_)), "{err:?}");
        assert!(entries(dir.path()).is_empty(), "{:?}", entries(dir.path()));
    }
}
