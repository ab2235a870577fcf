//! The files a run writes in its output directory, by name: the run writes them, `reproduce`
//! and the consolidation curves read them back, and a scene may not name its snapshot after
//! one of them.

/// The summary of a finished run (stage reports, wall time, threads).
pub const SUMMARY: &str = "summary.json";

/// The checkpoint of an unfinished run; removed when the run completes.
pub const CHECKPOINT: &str = "checkpoint.bin";

/// The last state that passed the blow-up checks, kept when a run fails.
pub const LAST_GOOD: &str = "last-good.snap.json";

/// The advisory lock of the directory while a run writes into it.
pub const LOCK: &str = ".grainbench.lock";

/// The folder of the stage-end snapshots (`--stage-snapshots`).
pub const STAGES: &str = "stages";

/// The snapshot of the state at the end of stage `index` (0-based, as in `Scene::stages`),
/// in [`STAGES`].
pub fn stage_file(index: usize) -> String {
    format!("stage-{index:03}.snap.json")
}

/// The names a scene's own output may not take: the run's files would overwrite each other.
pub const RESERVED: [&str; 4] = [SUMMARY, CHECKPOINT, LAST_GOOD, LOCK];
