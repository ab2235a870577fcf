//! Checkpoints on disk: what a run needs to continue bit for bit after Ctrl-C, a kill or a
//! crash — the scene, where in the protocol the run stands, the step reports so far and the
//! complete integrator state ([`crate::system::State`]: positions, velocities, forces, cell,
//! neighbour list and contact history). Binary (bincode), written atomically, so an
//! interrupted write leaves the previous checkpoint intact, and closed by a CRC-32 of all the
//! bytes before it (since version 4), so a damaged file is refused instead of resuming a
//! different packing (docs/reliability.md). Version 5: the stage watch keeps the pressures of
//! `relax.mean_stress`. Version 6: the stage watch logs the quenches of `criteria.quench` and
//! the step reports say what they did. Version 7: the stage watch keeps FIRE's state
//! (`relax.method = "fire"`). Older checkpoints are refused by their version, not misread.

use super::report::StepReport;
use crate::scene::Scene;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;

pub const FORMAT: &str = "grainbench-checkpoint";
pub const VERSION: u32 = 7;

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
        let damaged = |why: String| {
            format!(
                "{} is not a grainbench checkpoint or is damaged ({why}): it cannot be resumed: start the run over without --resume, or restore the file",
                path.display()
            )
        };
        let sealed = bytes.len() >= 4 && {
            let (body, tail) = bytes.split_at(bytes.len() - 4);
            crc32fast::hash(body).to_le_bytes() == tail
        };
        let (header, payload): (Header, Vec<u8>) =
            bincode::deserialize(&bytes).map_err(|e| damaged(e.to_string()))?;
        if !sealed {
            return Err(damaged("checksum mismatch".into()));
        }
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

    /// Writes header and payload atomically, streamed: the bytes are those of
    /// `bincode::serialize(&(header, encode(payload)))` and its CRC, but neither the encoded
    /// state nor the file is assembled in memory (a copy of the state would double the peak
    /// memory of a large run at every checkpoint).
    pub fn write<P: Serialize>(path: &Path, header: &Header, payload: &P) -> std::io::Result<()> {
        let len = bincode::serialized_size(payload).map_err(std::io::Error::other)?;
        crate::snapshot::write_atomic_with(path, |w| {
            let mut w = Crc {
                inner: w,
                hasher: crc32fast::Hasher::new(),
            };
            bincode::serialize_into(&mut w, header).map_err(std::io::Error::other)?;
            // The payload is a byte vector inside the file: its length, then its bytes.
            w.write_all(&len.to_le_bytes())?;
            bincode::serialize_into(&mut w, payload).map_err(std::io::Error::other)?;
            let crc = w.hasher.finalize();
            w.inner.write_all(&crc.to_le_bytes())
        })
    }
}

/// A writer that hashes what passes through it (the checkpoint's closing CRC-32).
struct Crc<'a> {
    inner: &'a mut dyn Write,
    hasher: crc32fast::Hasher,
}

impl Write for Crc<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
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

#[cfg(test)]
mod tests {
    use super::*;

    fn header(version: u32) -> Header {
        Header {
            format: FORMAT.into(),
            version,
            code: code(),
            scene_json: "{}".into(),
            stage: 1,
            inside: true,
            stage_time0: 0.5,
            stage_steps0: 7,
            stage_wall: 1.0,
            wall_seconds: 2.0,
            reports: Vec::new(),
            pressure: Some(0.01),
            neighbor_builds: 3,
        }
    }

    /// One damaged byte anywhere, or a cut file, is refused as damaged, never resumed as a
    /// different packing.
    #[test]
    fn damaged_checkpoints_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("checkpoint.bin");
        let state: Vec<u64> = (0..200u64).map(|k| k * k).collect();
        Checkpoint::write(&path, &header(VERSION), &state).unwrap();
        let good = std::fs::read(&path).unwrap();
        let cp = Checkpoint::read(&path).unwrap();
        assert_eq!((cp.payload.clone(), cp.header.stage), (encode(&state), 1));
        assert_eq!(decode::<Vec<u64>>(&cp.payload).unwrap(), state);
        for k in (0..good.len()).step_by(7).chain([good.len() - 1]) {
            let mut bad = good.clone();
            bad[k] ^= 0x10;
            std::fs::write(&path, &bad).unwrap();
            let e = Checkpoint::read(&path).expect_err("a flipped byte must be refused");
            assert!(e.contains("damaged"), "byte {k}: {e}");
        }
        std::fs::write(&path, &good[..good.len() - 9]).unwrap();
        assert!(Checkpoint::read(&path).unwrap_err().contains("damaged"));
    }

    /// The streamed file has the layout of the one assembled in memory before (bincode of
    /// the header and the encoded state as a byte vector, then the CRC-32 of all of it), so
    /// checkpoints of version 7 stay readable both ways.
    #[test]
    fn streamed_checkpoints_keep_the_file_layout() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("checkpoint.bin");
        let state = (
            vec![[1.5f64, -2.0, 3.25]; 40],
            Some(7u32),
            "watch".to_string(),
        );
        Checkpoint::write(&path, &header(VERSION), &state).unwrap();
        let mut expected = bincode::serialize(&(header(VERSION), encode(&state))).unwrap();
        let crc = crc32fast::hash(&expected);
        expected.extend_from_slice(&crc.to_le_bytes());
        assert_eq!(std::fs::read(&path).unwrap(), expected);
    }

    /// A header whose step reports hold a damped relaxation (no FIRE) reads back: its `fire`
    /// field, skipped when empty, shifted every byte after it, and no stage after such a
    /// relaxation could be resumed (a GRC08 cycle interrupted at P* = 0.178, 2026-12-06).
    #[test]
    fn reports_of_every_kind_read_back() {
        use super::super::relax::Relaxation;
        use super::super::report::{Checks, StepEnd};
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("checkpoint.bin");
        let relaxation = Relaxation {
            start_time: 17.0,
            damping: 1.0,
            tangential_zeta: 0.5,
            pairs: 1419,
            pairs_gained: 0,
            pairs_lost: 0,
            delta_phi: -2e-7,
            max_displacement: 9.6e-4,
            free_rollers: 3,
            fire: None,
        };
        let report = |index: usize, relaxation: Option<Relaxation>| StepReport {
            index,
            kind: "compress".into(),
            end: StepEnd::Equilibrium,
            time: 45.5,
            steps: 647_800,
            wall_seconds: 57.4,
            checks: Checks::default(),
            peak_strain_rate: 0.004,
            relaxation,
            quench: None,
        };
        let mut h = header(VERSION);
        h.reports = vec![
            report(0, None),
            report(1, Some(relaxation.clone())),
            report(2, None),
        ];
        Checkpoint::write(&path, &h, &[1u8, 2, 3]).unwrap();
        let cp = Checkpoint::read(&path).unwrap();
        assert_eq!(cp.header.reports.len(), 3);
        assert_eq!(cp.header.reports[1].relaxation, Some(relaxation));
        assert_eq!(cp.header.reports[2].steps, 647_800);
        assert_eq!(decode::<[u8; 3]>(&cp.payload).unwrap(), [1, 2, 3]);
    }

    /// Checkpoints of an older version (5: a stage watch without the quench log) are refused
    /// by their version, naming the one this build reads.
    #[test]
    fn older_versions_are_refused_by_version() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("checkpoint.bin");
        Checkpoint::write(&path, &header(VERSION - 1), &[1u8, 2, 3]).unwrap();
        let e = Checkpoint::read(&path).unwrap_err();
        assert!(
            e.contains(&format!("v{}", VERSION - 1)) && e.contains(&format!("v{VERSION}")),
            "{e}"
        );
    }
}
