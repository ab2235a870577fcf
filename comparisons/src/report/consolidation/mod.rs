//! GRC08 §III: the consolidation curve of a run with pressure programs — Φ and z at the end
//! of each pressure level, loading and unloading — its fit by GRC08 (9) (T.III), the CSV and
//! the plot of Φ(P*) against the paper's fit; along the cycle, z (Fig. 17), the moduli
//! (Fig. 22) and the density correlations of §IV (I(k), Fig. 15; ξ and ξ', Fig. 16; (10)).
//!
//! [`program`] finds the levels in a scene, [`levels`] reads them from a run's stage-end
//! snapshots, [`curves`] gives a seed's curve and the seeds' mean with the values a
//! reproduction table compares, [`published`] the law of GRC08 T.III each is judged against,
//! [`figures`] the plots.

pub mod curves;
pub mod figures;
pub mod levels;
pub mod program;
pub mod published;
#[cfg(test)]
mod tests;

pub use curves::{
    mean_scattering, pooled_density, step_values, values, write_csv, MeanCurve, SeedCurve, STEP,
};
pub use figures::{plot, plot_blob_size, plot_coordination, plot_moduli, plot_scattering};
pub use levels::{
    fit_loading, levels, BlobScaling, Coordination, Level, LevelError, LevelModuli, SCATTERING_AT,
};
pub use program::{has_program, program_stage};
pub use published::{is_cycle, paper_curve, paper_law};
