//! Packing metrics on snapshots from grainbench or any other DEM code (SPEC §5).
//!
//! A [`Snapshot`](grainbench_engine::snapshot::Snapshot) (format in `docs/snapshot-format.md`)
//! is measured by [`metrics::analyze`] into an [`Analysis`]: solid fraction Φ, force-carrying
//! contacts and coordination number z, rattlers (x0) and backbone coordination z*, the
//! distribution x_k of contact numbers with rattlers ignored (I) or fixed onto the backbone
//! (II), the normal-force distribution, its moments and friction mobilisation (AR07 T.IV,
//! T.VI), the cohesive z+/z−/z0 split and force-angle histogram (GRC07 T.VI, Fig. 15), g(r)
//! and z(h), bond-orientational order (AR07 T.II), and the pressure checks AR07 (22) and
//! GRC07 (17)–(18) against the stress written in the snapshot.
//!
//! * [`rattlers`]: the rattler algorithm (AR07 §III.B, §IV.D; GRC07 §III.A).
//! * [`fixed_rattlers`]: rattlers fixed onto the backbone, x_k variant II (AR07 §III.C).
//! * [`force_distribution`]: P(f), Z(α), X1/M1/M2 and their T.VI breakdown (AR07), the
//!   force-angle histogram (GRC07 Fig. 15).
//! * [`structure`]: g(r) and z(h) (AR07 §III.D).
//! * [`mod@bond_order`]: Q4/Q6 local and global, crystalline bonds and grains (AR07 (31)–(34), T.II).
//! * [`metrics`]: [`analyze`], [`Options`], [`Analysis`], [`Analysis::metric_values`].
//! * [`report`]: markdown table and JSON renderings.
//! * [`series`]: the data series returned for plots.
//! * [`outcome`]: how the run of one code ended (`ran`, `missing`, `timeout`, …).
//! * [`paper`]: the published values of `golden/paper-values.toml` (SPEC §6).
//! * [`reproduction`]: our values over seeds against the published ones, with verdicts.
//! * [`plots`]: P(f) with the DTS fit, g(r) and generic line plots as SVG + PNG.
//! * [`stats`]: mean, sample s.d., median/min/max, KS distance, Pareto front.
//!
//! ```no_run
//! use grainbench_comparisons::{analyze, report, Options};
//! use grainbench_engine::snapshot::Snapshot;
//! let snap = Snapshot::read(std::path::Path::new("out/state-A.json")).unwrap();
//! let a = analyze(&snap, &Options::default());
//! println!("{}", report::to_markdown(&a));
//! ```

pub mod bond_order;
pub mod crosscode;
pub mod decks;
pub mod fixed_rattlers;
pub mod force_distribution;
pub mod import;
pub mod metrics;
mod neighbors;
pub mod outcome;
pub mod paper;
pub mod plots;
pub mod rattlers;
pub mod report;
pub mod reproduction;
pub mod series;
pub mod stats;
pub mod structure;

#[cfg(test)]
mod fixtures;

pub use bond_order::bond_order;
pub use force_distribution::{force_angle_histogram, force_moment, pf_histogram};
pub use metrics::{analyze, Analysis, Options};
pub use rattlers::{find_rattlers, Rattlers, Rule};
pub use series::{Histogram, Series};
pub use structure::{gap_coordination, pair_correlation};
