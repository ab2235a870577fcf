//! `grainbench decks`, `capabilities`: the cross-code decks of a scene.

use crate::common::load_scene;
use anyhow::{bail, Context, Result};
use grainbench_comparisons::xcode::adapter::Adapter;
use grainbench_comparisons::xcode::decks::{self, capability, Deck, Start};
use grainbench_comparisons::xcode::Code;
use grainbench_engine::snapshot::write_atomic;
use std::path::{Path, PathBuf};

/// The arguments of `grainbench decks`.
#[derive(clap::Args, Debug)]
pub struct DecksArgs {
    /// Scene files or embedded scene names.
    pub scenes: Vec<String>,
    /// Every embedded scene.
    #[arg(long)]
    pub all: bool,
    /// Codes, comma-separated: lammps (Debian's 2021), lammps-2025, liggghts, yade, and
    /// `generic`, the neutral exchange format (docs/exchange-format.md) (default: all five).
    #[arg(long, value_delimiter = ',')]
    pub codes: Vec<String>,
    /// Output directory instead of `reference-inputs/<scene>/` (one scene only).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
}

/// The arguments of `grainbench capabilities`.
#[derive(clap::Args, Debug)]
pub struct CapabilitiesArgs {
    pub scene: Option<String>,
    /// Columns, comma-separated (default: lammps, lammps-2025, liggghts, yade); NAME=PATH.toml
    /// adds a code with an adapter file.
    #[arg(long, value_delimiter = ',')]
    pub codes: Vec<String>,
}

/// `grainbench decks`.
pub fn decks(a: DecksArgs) -> Result<i32> {
    decks_command(&a.scenes, a.all, &a.codes, a.out)
}

/// `grainbench capabilities`.
pub fn capabilities(a: CapabilitiesArgs) -> Result<i32> {
    capabilities_command(a.scene.as_deref(), &a.codes)
}

/// Written instead of a deck when a code cannot express the scene.
pub const REFUSED: &str = "refused.txt";

/// Parses `--codes a,b,c`; `NAME=PATH.toml` adds a code described by an adapter file
/// (docs/exchange-format.md).
pub fn parse_codes(list: &[String], allow_rust: bool) -> Result<Vec<Code>> {
    let mut out = Vec::new();
    for name in list {
        let code = match name.split_once('=') {
            Some((n, path)) => Some(Code::Adapter(
                Adapter::register(n, Path::new(path))
                    .map_err(|e| anyhow::anyhow!("--codes: {e}"))?,
            )),
            None => Code::parse(name),
        };
        match code {
            Some(Code::Rust) if !allow_rust => {
                bail!("--codes: `rust` has no deck (grainbench runs the scene itself)")
            }
            Some(c) => {
                if !out.contains(&c) {
                    out.push(c)
                }
            }
            None => bail!(
                "--codes: unknown code `{name}`; expected a comma-separated list of {}, generic (the exchange format, for `decks`), or NAME=PATH.toml for a code with an adapter file",
                Code::ALL.map(Code::name).join(", ")
            ),
        }
    }
    Ok(out)
}

/// "rust, lammps, …" for progress lines.
pub fn code_names(codes: &[Code]) -> String {
    codes
        .iter()
        .map(|c| c.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Writes one deck's files into `dir` (removing a refusal left there by an earlier matrix).
pub fn write_deck(deck: &Deck, dir: &Path) -> Result<()> {
    let _ = std::fs::remove_file(dir.join(REFUSED));
    for (name, text) in &deck.files {
        let path = dir.join(name);
        write_atomic(&path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// Writes the decks of `start` for `codes` into `root/<code>/`; a refusal is written as
/// `refused.txt` instead.
pub fn write_decks(start: &Start, codes: &[Code], root: &Path, quiet: bool) -> Result<()> {
    for &code in codes {
        match decks::deck(start, code) {
            Ok(deck) => {
                let dir = root.join(code.name());
                write_deck(&deck, &dir)?;
                if !quiet {
                    println!(
                        "{}: {} ({} file(s){})",
                        code,
                        dir.display(),
                        deck.files.len(),
                        if deck.deviations.is_empty() {
                            String::new()
                        } else {
                            format!(", {} approximate feature(s)", deck.deviations.len())
                        }
                    );
                }
            }
            Err(refusal) => {
                // Recorded beside the decks, so a change of the matrix shows as a diff; a deck
                // written there before the scene or the matrix changed goes.
                remove_stale_deck(&root.join(code.name()), code)?;
                let path = root.join(code.name()).join(REFUSED);
                write_atomic(&path, format!("{refusal}\n").as_bytes())
                    .with_context(|| format!("writing {}", path.display()))?;
                if !quiet {
                    eprintln!("{code}: not written: {refusal}");
                }
            }
        }
    }
    Ok(())
}

/// Removes the deck a generator wrote into `dir` for `code` (its `deck.json`, the data files
/// it lists, the input scripts headed `# grainbench deck for scene` and the LAMMPS 2021
/// tables), leaving any other file alone.
fn remove_stale_deck(dir: &Path, code: Code) -> Result<()> {
    let Ok(bytes) = std::fs::read(dir.join("deck.json")) else {
        return Ok(());
    };
    let Ok(doc) = serde_json::from_slice::<serde_json::Value>(&bytes) else {
        return Ok(());
    };
    if doc["code"].as_str() != Some(code.name()) {
        return Ok(());
    }
    let data: Vec<String> = doc["data"]
        .as_object()
        .map(|m| m.keys().cloned().collect())
        .unwrap_or_default();
    for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let path = entry?.path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let generated = name == "deck.json"
            || data.iter().any(|d| d == name)
            || name == decks::lammps_table::TABLE
            || name == decks::lammps_bench::BENCH_TABLE
            || std::fs::read(&path).is_ok_and(|b| b.starts_with(b"# grainbench deck for scene"));
        if generated && path.is_file() {
            std::fs::remove_file(&path)
                .with_context(|| format!("removing the stale deck file {}", path.display()))?;
        }
    }
    Ok(())
}

/// `grainbench decks`.
fn decks_command(
    scenes: &[String],
    all: bool,
    codes: &[String],
    out: Option<PathBuf>,
) -> Result<i32> {
    let codes = if codes.is_empty() {
        Code::DECKS.to_vec()
    } else {
        parse_codes(codes, false)?
    };
    let names: Vec<String> = if all {
        grainbench_engine::library::SCENES
            .iter()
            .map(|(n, _)| n.to_string())
            .collect()
    } else if scenes.is_empty() {
        bail!("name a scene (`grainbench scenes` lists them) or pass --all")
    } else {
        scenes.to_vec()
    };
    if out.is_some() && names.len() > 1 {
        bail!("--out takes one scene; without it each scene goes to reference-inputs/<scene>/");
    }
    for name in &names {
        let scene = load_scene(name)?;
        let start = Start::of(&scene).map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
        let root = out
            .clone()
            .unwrap_or_else(|| Path::new("reference-inputs").join(&scene.name));
        write_decks(&start, &codes, &root, false)?;
    }
    Ok(0)
}

/// `grainbench capabilities`.
fn capabilities_command(scene: Option<&str>, codes: &[String]) -> Result<i32> {
    let codes = if codes.is_empty() {
        Code::EXTERNAL.to_vec()
    } else {
        parse_codes(codes, false)?
    };
    match scene {
        None => print!("{}", capability::markdown_for(&codes)),
        Some(spec) => {
            let scene = load_scene(spec)?;
            let start =
                Start::of(&scene).map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
            println!("scene {} uses:", scene.name);
            println!("{}", capability::header_for(&codes));
            for f in decks::features(&start) {
                print!("| `{}` |", f.key());
                for &c in &codes {
                    print!(" {} |", capability::support(c, f).cell());
                }
                println!();
            }
        }
    }
    Ok(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scene that a code refused after it had a deck there: the refusal replaces the deck,
    /// other files stay.
    #[test]
    fn a_refusal_removes_the_deck_written_before() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("liggghts");
        let smoke = Start::of(&load_scene("xcode-smoke").unwrap()).unwrap();
        write_decks(&smoke, &[Code::Liggghts], root.path(), true).unwrap();
        assert!(dir.join("in.liggghts").exists() && dir.join("deck.json").exists());
        std::fs::write(dir.join("notes.txt"), "mine").unwrap();
        let quench = Start::of(&load_scene("ar07-D-10kPa-n1372-quench").unwrap()).unwrap();
        write_decks(&quench, &[Code::Liggghts], root.path(), true).unwrap();
        let mut left: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, ["notes.txt", REFUSED]);
    }
}
