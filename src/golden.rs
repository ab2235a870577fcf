//! `grainbench golden update SCENE` records the last `compare` run of a scene as
//! `golden/<scene>/<code>.json`; `grainbench golden show SCENE` prints what is recorded.

use crate::common::{load_scene, seed_list};
use crate::xcode;
use anyhow::{bail, Context, Result};
use grainbench_comparisons::outcome::Outcome;
use grainbench_comparisons::xcode::crosscode::{self, Bands, CodeResult, Comparison};
use grainbench_comparisons::xcode::decks::{self, Code, Start};
use grainbench_comparisons::xcode::import::logs::clean_version;
use grainbench_engine::snapshot::write_atomic;
use std::path::{Path, PathBuf};

/// The arguments of `grainbench golden`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub action: Action,
}

#[derive(clap::Subcommand, Debug)]
pub enum Action {
    /// Record the results of the last `grainbench compare SCENE`.
    Update {
        scene: String,
        /// Only these codes (default: every code that ran).
        #[arg(long, value_delimiter = ',')]
        codes: Vec<String>,
        /// The compare output directory (default: `runs/compare/<scene>`).
        #[arg(long)]
        from: Option<PathBuf>,
    },
    /// Print the recorded golden values of a scene as the cross-code table (no runs).
    Show {
        scene: String,
        /// Every metric, not only the main ones.
        #[arg(long)]
        all_metrics: bool,
    },
}

pub fn command(a: Args) -> Result<i32> {
    match a.action {
        Action::Update { scene, codes, from } => update(&scene, &codes, from),
        Action::Show { scene, all_metrics } => show(&scene, all_metrics),
    }
}

/// The comparisons of the last `compare` run in `dir`: one (`compare.json`) or one per seed
/// (`compare-seeds.json` and `seed-K/compare.json`), whichever was written last.
fn compare_runs(dir: &Path, scene: &grainbench_engine::Scene) -> Result<Vec<(u64, Comparison)>> {
    let (name, seed) = (scene.name.as_str(), scene.seed);
    let single = dir.join("compare.json");
    let over = dir.join("compare-seeds.json");
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    let use_seeds = match (modified(&single), modified(&over)) {
        (Some(a), Some(b)) => b > a,
        (None, Some(_)) => true,
        _ => false,
    };
    let read = |path: &Path| -> Result<Comparison> {
        let text = std::fs::read_to_string(path).with_context(|| {
            format!(
                "reading {}: run `grainbench compare {name}` first (golden update records its results)",
                path.display()
            )
        })?;
        let cmp: Comparison =
            serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
        if cmp.scene != name {
            bail!("{} holds scene {}, not {name}", path.display(), cmp.scene);
        }
        Ok(cmp)
    };
    if !use_seeds {
        return Ok(vec![(seed, read(&single)?)]);
    }
    let text =
        std::fs::read_to_string(&over).with_context(|| format!("reading {}", over.display()))?;
    let summary: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", over.display()))?;
    let seeds: Vec<u64> = summary["seeds"]
        .as_array()
        .map(|a| a.iter().filter_map(|s| s.as_u64()).collect())
        .unwrap_or_default();
    if seeds.is_empty() {
        bail!("{} lists no seed", over.display());
    }
    seeds
        .into_iter()
        .map(|s| {
            Ok((
                s,
                read(&dir.join(format!("seed-{s}")).join("compare.json"))?,
            ))
        })
        .collect()
}

/// Was `path` written by `reproduce --record` (several seeds and a paper table)?
fn recorded_by_reproduce(path: &Path) -> bool {
    std::fs::read_to_string(path)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .is_some_and(|d| d.get("table").is_some())
}

/// `grainbench golden update SCENE`: records the results of the last `compare` run of the
/// scene (from `runs/compare/<scene>/` or `--from`) as `golden/<scene>/<code>.json`.
fn update(scene: &str, codes: &[String], from: Option<PathBuf>) -> Result<i32> {
    let scene = load_scene(scene)?;
    let dir = from.unwrap_or_else(|| Path::new("runs/compare").join(&scene.name));
    // Before the results: a code run through an adapter is read back by its registered name.
    let wanted = if codes.is_empty() {
        Vec::new()
    } else {
        xcode::parse_codes(codes, true)?
    };
    let runs = compare_runs(&dir, &scene)?;
    let cmp = &runs[0].1;
    let mut written = 0;
    for c in &cmp.codes {
        if !wanted.is_empty() && !wanted.contains(&c.code) {
            continue;
        }
        if c.outcome != Outcome::Ran {
            eprintln!("{}: not recorded ({})", c.code, c.outcome);
            continue;
        }
        let out = crosscode::golden_file(&scene.name, c.code);
        if recorded_by_reproduce(&out) {
            eprintln!(
                "{}: not recorded: {} holds a `grainbench reproduce --record` result over seeds; rerun that command to change it",
                c.code,
                out.display()
            );
            continue;
        }
        // Every seed the code finished, in the order they ran.
        let seeds: Vec<serde_json::Value> = runs
            .iter()
            .filter_map(|(seed, cmp)| {
                let r = cmp
                    .codes
                    .iter()
                    .find(|r| r.code == c.code && r.outcome == Outcome::Ran)?;
                Some(serde_json::json!({
                    "seed": seed,
                    "status": r.status,
                    "wall_seconds": r.wall_seconds,
                    "metrics": r.metrics,
                }))
            })
            .collect();
        let seed_list = if runs.len() > 1 {
            format!(
                " --seeds {}",
                seed_list(&runs.iter().map(|(s, _)| *s).collect::<Vec<_>>())
            )
        } else {
            String::new()
        };
        let doc = serde_json::json!({
            "code": c.version.as_deref().map(clean_version),
            "scene": scene.name,
            "n": cmp.n,
            "command": format!("grainbench compare {} --codes {}{seed_list}", scene.name, c.code),
            "deviations": c.deviations,
            "seeds": seeds,
        });
        write_atomic(
            &out,
            (serde_json::to_string_pretty(&doc)? + "\n").as_bytes(),
        )?;
        println!("wrote {}", out.display());
        written += 1;
    }
    if written == 0 {
        bail!(
            "nothing recorded: no code in {} ran to its end",
            dir.display()
        );
    }
    if written > 1 {
        // The overlaid plots of a run that recorded several codes at once.
        for plot in ["pf.svg", "gr.svg"] {
            if let Ok(bytes) = std::fs::read(dir.join(plot)) {
                let to = crosscode::golden_file(&scene.name, Code::Rust).with_file_name(plot);
                write_atomic(&to, &bytes)?;
                println!("wrote {}", to.display());
            }
        }
    }
    Ok(0)
}

/// `grainbench golden show SCENE`: the recorded values of every code, as the compare table.
fn show(scene: &str, all_metrics: bool) -> Result<i32> {
    let scene = load_scene(scene)?;
    let start = Start::of(&scene).ok();
    let mut codes = Vec::new();
    for c in Code::ALL {
        if let Some(r) = crosscode::recorded(Path::new("."), &scene.name, c) {
            codes.push(r);
            continue;
        }
        // Not recorded: say why when the code cannot express the scene.
        if let (Some(st), true) = (&start, c != Code::Rust) {
            if let Err(refusal) = decks::deck(st, c) {
                codes.push(CodeResult {
                    message: Some(refusal.to_string()),
                    ..CodeResult::new(c, Outcome::Refused)
                });
            }
        }
    }
    if codes.iter().all(|c| c.outcome != Outcome::Recorded) {
        bail!(
            "no golden/{}/<code>.json recorded; run `grainbench compare {0}` and `grainbench golden update {0}`",
            scene.name
        );
    }
    let cmp = crosscode::build(
        &scene.name,
        scene.particles.count,
        Some(scene.paper_state.as_deref().unwrap_or(&scene.name)),
        codes,
        &Bands::embedded(),
    );
    print!("{}", cmp.to_markdown(all_metrics));
    for c in cmp.codes.iter().filter(|c| c.outcome == Outcome::Recorded) {
        println!("{}: `{}`", c.code, c.message.as_deref().unwrap_or(""));
    }
    Ok(0)
}
