//! Packing metrics on snapshots from grainbench or any other DEM code (those of AR07 §III–§IV,
//! GRC07 §III–§V and GRC08), the cross-code comparison with LAMMPS, LIGGGHTS and YADE, and the
//! reports.
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
//! Three folders, imported one way (`report` and `xcode` take from `metrics`, `xcode` takes
//! the paper values and number formats from `report`; `metrics` takes from neither):
//!
//! * [`metrics`]: one snapshot's measures — [`analyze`], [`Options`], [`Analysis`], and the
//!   algorithms beside them (rattlers, fixed rattlers, force distribution, structure, bond
//!   order, pressure checks, the returned data series).
//! * [`xcode`]: other codes — the [`Code`](xcode::Code) enum, deck generators with the
//!   capability matrix ([`xcode::decks`]), readers of their dumps ([`xcode::import`]) and the
//!   cross-code table ([`xcode::crosscode`]).
//! * [`report`]: what people read — the analysis as markdown/JSON, the number formats
//!   ([`mod@report::format`]), the paper values, the reproduction table and the plots.
//! * [`outcome`] and [`stats`]: how the run of one code ended (`ran`, `missing`, `timeout`,
//!   …) and the statistics shared by the reports (mean, sample s.d., median, KS distance,
//!   Pareto front).
//!
//! ```no_run
//! use grainbench_comparisons::{analyze, report, Options};
//! use grainbench_engine::snapshot::Snapshot;
//! let snap = Snapshot::read(std::path::Path::new("out/state-A.json")).unwrap();
//! let a = analyze(&snap, &Options::default());
//! println!("{}", report::to_markdown(&a));
//! ```

pub mod metrics;
pub mod outcome;
pub mod report;
pub mod stats;
pub mod xcode;

pub use metrics::bond_order::bond_order;
pub use metrics::force_distribution::{force_angle_histogram, force_moment, pf_histogram};
pub use metrics::rattlers::{find_rattlers, Rattlers, Rule};
pub use metrics::series::{Histogram, Series};
pub use metrics::structure::{gap_coordination, pair_correlation};
pub use metrics::{analyze, Analysis, Options};
