//! `grainbench analyze`: the packing metrics of a snapshot, or of another code's final dumps.

use crate::common::analysis_of;
use anyhow::{bail, Result};
use grainbench_comparisons::xcode::{import, Code};
use grainbench_engine::Snapshot;
use std::path::Path;

/// `grainbench analyze SNAPSHOT [--from CODE] [--write FILE] [--json]`.
pub fn analyze(path: &Path, json: bool, from: Option<&str>, write: Option<&Path>) -> Result<i32> {
    let snap = match from {
        None => Snapshot::read(path)?,
        Some(name) => {
            let code = match Code::parse(name) {
                Some(Code::Rust) | None => {
                    bail!("--from: expected lammps, liggghts or yade, got `{name}`")
                }
                Some(c) => c,
            };
            if !path.is_dir() {
                bail!(
                    "--from {name}: {} is not a directory (give the directory holding the final dumps and deck.json)",
                    path.display()
                );
            }
            let meta = import::Meta::read(path)?;
            import::read(code, path, &meta)?
        }
    };
    if let Some(w) = write {
        snap.write(w)?;
    }
    let a = analysis_of(&snap);
    if json {
        println!("{}", serde_json::to_string_pretty(&a)?);
    } else {
        print!("{}", grainbench_comparisons::report::to_markdown(&a));
    }
    Ok(0)
}
