//! grainbench engine: periodic, stress-controlled discrete-element simulation of Hertz–Mindlin
//! spheres (Agnolin & Roux 2007, "AR07") and adhesive disks (Gilabert, Roux & Castellanos
//! 2007/2008, "GRC07", "GRC08"), one code base for 2D and 3D.
//!
//! Layout: [`geometry`] (2D/3D abstraction), [`cell`] (periodic cell and barostat, AR07 (6)–(8)),
//! [`contact`] (contact laws), [`neighbor`] (cell lists + Verlet skin), [`network`] (the axes an
//! interaction network wraps), [`system`] (state and
//! integrator), [`init`] (random gas), [`scene`] (scene files), [`plan`] (the protocol resolved into
//! absolute units, read by the run and the cross-code decks), [`run`] (protocols, equilibrium
//! criteria, blow-up detection, checkpoints), [`snapshot`] (on-disk configurations), [`library`] (embedded
//! scenes), [`protocols`] (event-driven hard grains, Lubachevsky–Stillinger growth, FCC).

pub mod cell;
pub mod contact;
pub mod geometry;
pub mod init;
pub mod library;
pub mod neighbor;
pub mod network;
pub mod parallel;
pub mod plan;
pub mod protocols;
pub mod run;
pub mod scene;
pub mod snapshot;
pub mod system;

pub use run::checkpoint;
pub use run::{run_scene, Outcome, RunError, RunOptions};
pub use scene::Scene;
pub use snapshot::Snapshot;
