//! Packing metrics on snapshots from grainbench or any other DEM code (SPEC §5).
//!
//! A [`Snapshot`](grainbench_engine::snapshot::Snapshot) (format in `docs/snapshot-format.md`)
//! is measured by [`metrics::analyze`] into an [`Analysis`]: solid fraction Φ, force-carrying
//! contacts and coordination number z, rattlers (x0) and backbone coordination z*, the
//! distribution x_k of contact numbers, normal-force moments and friction mobilisation
//! (AR07 T.IV, T.VI), the cohesive z+/z−/z0 split (GRC07 T.VI), and the pressure checks
//! AR07 (22) and GRC07 (17)–(18) against the stress written in the snapshot.
//!
//! * [`rattlers`]: the rattler algorithm (AR07 §III.B, §IV.D; GRC07 §III.A).
//! * [`metrics`]: [`analyze`], [`Options`], [`Analysis`].
//! * [`report`]: markdown table and JSON renderings.
//! * [`paper`]: the published values of `golden/paper-values.toml` (SPEC §6).
//! * [`reproduction`]: our values over seeds against the published ones, with verdicts.
//! * [`plots`]: P(f) with the DTS fit, g(r) and generic line plots as SVG + PNG.
//!
//! ```no_run
//! use grainbench_comparisons::{analyze, report, Options};
//! use grainbench_engine::snapshot::Snapshot;
//! let snap = Snapshot::read(std::path::Path::new("out/state-A.json")).unwrap();
//! let a = analyze(&snap, &Options::default());
//! println!("{}", report::to_markdown(&a));
//! ```

pub mod metrics;
pub mod paper;
pub mod plots;
pub mod rattlers;
pub mod report;
pub mod reproduction;

#[cfg(test)]
mod fixtures;

pub use metrics::{analyze, Analysis, Options};
pub use rattlers::{find_rattlers, Rattlers, Rule};
