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

/// Every deck and exchange file carries the engine's plan, not numbers of its own: for every
/// embedded scene, the DEM stages of the common start are the plan's, and each exchange stage
/// carries the plan's target, strain-rate cap, time step, time limit and tolerances.
#[test]
fn decks_and_exchange_files_carry_the_plan() {
    use grainbench_comparisons::xcode::decks::generic::{exchange, ExchangeKind};
    use grainbench_engine::plan::{PlanStep, StageKind};
    for (name, text) in library::SCENES {
        let scene = Scene::from_toml(text, Path::new(name)).unwrap();
        let plan = grainbench_engine::run::plan_of(&scene).unwrap();
        let start = Start::of(&scene).unwrap();
        let hard: Vec<_> = plan.steps[..start.prelude.len()]
            .iter()
            .map(PlanStep::name)
            .collect();
        assert_eq!(start.prelude, hard, "{name}: the start's prelude");
        let dem: Vec<_> = plan.steps[start.prelude.len()..]
            .iter()
            .filter_map(PlanStep::dem)
            .copied()
            .collect();
        assert_eq!(start.stages, dem, "{name}: the decks' stages");
        let (ex, _) = exchange(&start);
        assert_eq!(ex.stages.len(), dem.len(), "{name}");
        for (e, p) in ex.stages.iter().zip(&dem) {
            let (kind, target) = match p.kind {
                StageKind::Compress { pressure } => (ExchangeKind::Compress, Some(pressure)),
                StageKind::FixedVolume { .. } => (ExchangeKind::FixedVolume, None),
                StageKind::Aggregate => (ExchangeKind::Aggregate, None),
            };
            assert_eq!((e.kind, e.pressure), (kind, target), "{name}");
            assert_eq!(e.max_strain_rate, p.max_strain_rate, "{name}: rate cap");
            assert_eq!(
                (e.dt, e.max_steps),
                (p.dt, p.max_steps),
                "{name}: time step"
            );
            assert_eq!(
                (e.max_time, e.mu, e.kappa),
                (p.max_time, p.mu, p.kappa),
                "{name}"
            );
            let t = &e.tolerances;
            assert_eq!(
                [t.force, t.moment, t.stress, t.kinetic_per_grain],
                [
                    p.tolerances.force,
                    p.tolerances.moment,
                    p.tolerances.stress,
                    p.tolerances.kinetic_per_grain
                ],
                "{name}: tolerances"
            );
            assert_eq!((e.criteria, e.relax), (p.criteria, p.relax), "{name}");
        }
    }
}
