//! What is shown to people: tables, JSON, plots and the comparison with the papers.
//!
//! * [`analysis`]: markdown table and JSON renderings of an [`Analysis`](crate::Analysis).
//! * [`mod@format`]: the number formats of every table.
//! * [`paper`]: the published values of `golden/paper-values.toml` (AR07, GRC07, GRC08).
//! * [`reproduction`]: our values over seeds against the published ones, with verdicts.
//! * [`plots`]: P(f) with the DTS fit, g(r) and generic line plots as SVG + PNG.
//! * [`consolidation`]: the consolidation curve of a pressure program (GRC08 §III–IV).
//! * [`figures`]: P(f), g(r) and I(k) of several packings (seeds, codes) overlaid.
//! * [`html`]: `report.html`, a Markdown report with its plots inlined.

pub mod analysis;
pub mod consolidation;
pub mod figures;
pub mod format;
pub mod html;
pub mod paper;
pub mod plots;
pub mod reproduction;
pub mod vtk;

pub use analysis::{to_json, to_markdown};
