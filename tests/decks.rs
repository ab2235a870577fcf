//! The committed decks under `reference-inputs/<scene>/<code>/` (the external codes' and the
//! exchange format's, `generic/exchange.json`) are exactly what the generators
//! write: any change to a generator, the capability matrix or a scene shows as a reviewed diff
//! of those files. After a deliberate change: `cargo run --release -- decks --all`, review
//! `git diff reference-inputs/`, commit. (Data files are generated, not committed; their
//! checksums are in each `deck.json`.)

use grainbench_comparisons::xcode::decks::{self, Start};
use grainbench_comparisons::xcode::Code;
use grainbench_engine::{library, Scene};
use std::path::Path;

const REFUSED: &str = "refused.txt";

fn first_difference(want: &str, got: &str) -> String {
    for (k, (w, g)) in want.lines().zip(got.lines()).enumerate() {
        if w != g {
            return format!("line {}:\n  committed: {w}\n  generated: {g}", k + 1);
        }
    }
    format!(
        "committed has {} lines, generated {}",
        want.lines().count(),
        got.lines().count()
    )
}

#[test]
fn committed_decks_match_the_generators() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("reference-inputs");
    let mut problems = Vec::new();
    let mut written = 0;
    for (name, text) in library::SCENES {
        let scene = Scene::from_toml(text, Path::new(name)).unwrap();
        let start = Start::of(&scene).unwrap_or_else(|e| panic!("scene {name}: {e}"));
        for code in Code::DECKS {
            let dir = root.join(name).join(code.name());
            let mut expected: Vec<(String, String)> = match decks::deck(&start, code) {
                Ok(deck) => deck
                    .files
                    .iter()
                    .filter(|(f, _)| !decks::is_data_file(&deck, f))
                    .cloned()
                    .collect(),
                Err(refusal) => vec![(REFUSED.into(), format!("{refusal}\n"))],
            };
            expected.sort();
            for (file, want) in &expected {
                let path = dir.join(file);
                match std::fs::read_to_string(&path) {
                    Ok(have) if &have == want => written += 1,
                    Ok(have) => problems.push(format!(
                        "{} differs from the generator: {}",
                        path.display(),
                        first_difference(&have, want)
                    )),
                    Err(_) => problems.push(format!("{} is missing", path.display())),
                }
            }
            // No stale files beside them (data files — data.*, grains.txt, cohesion.table, the
            // exchange's particles.csv — are ignored by git and allowed).
            if let Ok(entries) = std::fs::read_dir(&dir) {
                for e in entries.flatten() {
                    let f = e.file_name().to_string_lossy().to_string();
                    let data = f.starts_with("data.")
                        || f == "grains.txt"
                        || f == "cohesion.table"
                        || f == "particles.csv";
                    if !data && !expected.iter().any(|(n, _)| n == &f) {
                        problems.push(format!(
                            "{} is not written by the generator",
                            e.path().display()
                        ));
                    }
                }
            }
        }
    }
    assert!(
        problems.is_empty(),
        "{} committed deck file(s) disagree with the generators (after a deliberate change run \
         `cargo run --release -- decks --all` and review `git diff reference-inputs/`):\n{}",
        problems.len(),
        problems.join("\n")
    );
    assert!(written > 0);
}

/// docs/capabilities.md is the output of `grainbench capabilities` (regenerate it with
/// `cargo run --release -- capabilities > docs/capabilities.md`).
#[test]
fn capability_doc_matches_the_matrix() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/capabilities.md");
    let doc = std::fs::read_to_string(&path).unwrap();
    assert_eq!(
        doc,
        grainbench_comparisons::xcode::decks::capability::markdown(),
        "{} is stale: run `cargo run --release -- capabilities > docs/capabilities.md`",
        path.display()
    );
}
