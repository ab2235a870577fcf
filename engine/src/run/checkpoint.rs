//! Checkpoints on disk: what a run needs to continue bit for bit after Ctrl-C, a kill or a
//! crash — the scene, where in the protocol the run stands, the step reports so far and the
//! complete integrator state ([`crate::system::State`]: positions, velocities, forces, cell,
//! neighbour list and contact history). Binary (bincode), written atomically, so an
//! interrupted write leaves the previous checkpoint intact.

use super::report::StepReport;
use crate::scene::Scene;
use serde::{Deserialize, Serialize};
use std::path::Path;

pub const FORMAT: &str = "grainbench-checkpoint";
pub const VERSION: u32 = 3;

/// Where the run stands.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Header {
    pub format: String,
    pub version: u32,
    /// `grainbench x.y.z` that wrote it: a checkpoint only resumes in the same version.
    pub code: String,
    /// The scene, as JSON (exact floats).
    pub scene_json: String,
    /// Index of the current stage in [`Scene::stages`], and whether the run stands inside it
    /// (the payload is then the integrator state) or at its start (the payload is the grains).
    pub stage: usize,
    pub inside: bool,
    /// Time and step count at the start of the stage, wall seconds spent in it so far.
    pub stage_time0: f64,
    pub stage_steps0: u64,
    pub stage_wall: f64,
    /// Wall seconds of the whole run so far.
    pub wall_seconds: f64,
    pub reports: Vec<StepReport>,
    /// Last prescribed pressure.
    pub pressure: Option<f64>,
    pub neighbor_builds: u64,
}

/// A checkpoint read back: the header and the (typed, still encoded) state.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    pub header: Header,
    pub payload: Vec<u8>,
}

impl Checkpoint {
    /// Reads a checkpoint file and checks its format and version.
    pub fn read(path: &Path) -> Result<Checkpoint, String> {
        let bytes = std::fs::read(path)
            .map_err(|e| format!("cannot read checkpoint {}: {e}", path.display()))?;
        let (header, payload): (Header, Vec<u8>) = bincode::deserialize(&bytes).map_err(|e| {
            format!(
                "{} is not a grainbench checkpoint or is damaged: {e}",
                path.display()
            )
        })?;
        if header.format != FORMAT || header.version != VERSION {
            return Err(format!(
                "{} is a {} v{} file; this grainbench reads {FORMAT} v{VERSION}",
                path.display(),
                header.format,
                header.version
            ));
        }
        let me = code();
        if header.code != me {
            return Err(format!(
                "checkpoint {} was written by {}, this is {me}: a run only resumes bit for bit in the version that started it",
                path.display(),
                header.code
            ));
        }
        Ok(Checkpoint { header, payload })
    }

    /// The scene the checkpoint belongs to.
    pub fn scene(&self) -> Result<Scene, String> {
        serde_json::from_str(&self.header.scene_json)
            .map_err(|e| format!("checkpoint holds an unreadable scene: {e}"))
    }

    /// Writes header and payload atomically.
    pub fn write(path: &Path, header: &Header, payload: &[u8]) -> std::io::Result<()> {
        let bytes = bincode::serialize(&(header, payload)).map_err(std::io::Error::other)?;
        crate::snapshot::write_atomic(path, &bytes)
    }
}

/// Name and version of this program, as stored in checkpoints and snapshots.
pub fn code() -> String {
    format!("grainbench {}", env!("CARGO_PKG_VERSION"))
}

/// Encodes a typed state.
pub fn encode<T: Serialize>(x: &T) -> Vec<u8> {
    bincode::serialize(x).expect("in-memory state encodes")
}

/// Decodes a typed state.
pub fn decode<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> Result<T, String> {
    bincode::deserialize(bytes).map_err(|e| format!("checkpoint state does not decode: {e}"))
}
