//! The reader of one code's final state.

use super::{assemble, generic, lammps, liggghts, yade, ImportError, Meta};
use crate::xcode::code::Code;
use crate::xcode::decks::generic::OUTPUT_DIR;
use grainbench_engine::snapshot::Snapshot;
use std::path::Path;

/// Reads the final state a deck of `code` left in `dir`.
pub fn read(code: Code, dir: &Path, meta: &Meta) -> Result<Snapshot, ImportError> {
    let raw = match code {
        Code::Lammps | Code::Lammps2025 => lammps::read_dir(dir, meta)?,
        Code::Liggghts => liggghts::read_dir(dir, meta)?,
        Code::Yade => yade::read_dir(dir, meta)?,
        // The code's output directory of the exchange format.
        Code::Generic | Code::Adapter(_) => {
            let out = dir.join(OUTPUT_DIR);
            generic::read_dir(if out.is_dir() { &out } else { dir }, meta)?
        }
        Code::Rust => {
            return Snapshot::read(&dir.join("final.json")).map_err(|e| ImportError::new(dir, e))
        }
    };
    assemble(raw, meta).map_err(|m| ImportError::new(dir, m))
}
