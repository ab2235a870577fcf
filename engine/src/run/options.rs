//! Options of a run: progress callback, stop flag, checkpoints.

use super::checkpoint::Checkpoint;
use super::report::{Progress, StepReport};
use crate::snapshot::Snapshot;
use std::sync::atomic::AtomicBool;

/// Periodic checkpoints on disk.
#[derive(Clone, Debug)]
pub struct CheckpointSpec {
    pub path: std::path::PathBuf,
    /// Wall-clock seconds between checkpoints (one is also written at each stage start that
    /// runs hard-sphere dynamics, and when the run is stopped).
    pub every: f64,
}

/// Snapshots taken during a run (`run --dump-every`).
pub struct DumpSpec<'a> {
    /// Time (reduced units) between snapshots: one at the first check at or after each
    /// multiple of `every`.
    pub every: f64,
    /// Receives each snapshot (status `running`).
    pub sink: &'a mut (dyn FnMut(&Snapshot) + Send),
    /// Index ⌊t/every⌋ of the last snapshot taken.
    pub last: Option<u64>,
}

/// Receives a stage's report and the state it ended in.
pub type StageEndHook<'a> = dyn FnMut(&StepReport, &Snapshot) + Send + 'a;

/// Options of a run.
#[derive(Default)]
pub struct RunOptions<'a> {
    /// Called at every check (every `numerics.check_every` steps).
    pub progress: Option<&'a mut (dyn FnMut(&Progress) + Send)>,
    /// Set to stop the run cleanly at the next check (Ctrl-C).
    pub stop: Option<&'a AtomicBool>,
    /// Write checkpoints.
    pub checkpoint: Option<CheckpointSpec>,
    /// Continue from a checkpoint of the same scene.
    pub resume: Option<Checkpoint>,
    /// Snapshots every so much simulated time.
    pub dump: Option<DumpSpec<'a>>,
    /// Called when a DEM stage ends (not when it is interrupted) with its report and the
    /// state it ended in: the points of a pressure program (GRC08 §II.D.2, `run
    /// --stage-snapshots`).
    pub stage_end: Option<&'a mut StageEndHook<'a>>,
}
