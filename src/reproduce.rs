//! `grainbench reproduce PAPER --state S`: runs the named state of a paper over several seeds
//! (checkpointed, resumable), measures every metric with the same code as `analyze`, and
//! writes the table against the published values (golden/paper-values.toml) and the plots.

use crate::common::{analysis_with_moduli, on_threads, seed_list};
use crate::run::{run, RunFlags};
use anyhow::{bail, Context, Result};
use grainbench_comparisons::metrics::{analyze, density, Analysis, MODULI_METRICS};
use grainbench_comparisons::report::reproduction::{self, SeedStats};
use grainbench_comparisons::report::{consolidation, figures, paper};
use grainbench_comparisons::xcode::crosscode;
use grainbench_comparisons::xcode::Code;
use grainbench_engine::run::layout::{stage_file, CHECKPOINT, STAGES, SUMMARY};
use grainbench_engine::run::StepEnd;
use grainbench_engine::{library, snapshot, Snapshot};
use std::path::{Path, PathBuf};

/// The arguments of `grainbench reproduce`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// ar07, grc07 or grc08.
    pub paper: String,
    /// State: A, Aprime, B, C, D, Z, D-QS (AR07); type1-phi036-mu05, type2-phi036-rr, …
    /// (GRC07); cycle-rr (GRC08). `grainbench scenes` lists them as <paper>-<state>.
    #[arg(long)]
    pub state: String,
    /// Seeds, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub seeds: Vec<u64>,
    /// The reduced CI variant of the scene (`<paper>-<state>-ci`).
    #[arg(long)]
    pub ci: bool,
    /// Output directory (default: `runs/reproduce/<scene>`).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Also write golden/<scene>/rust.json (command, seeds, wall times, metrics).
    #[arg(long)]
    pub record: bool,
    /// Cap the time limit of every stage (reduced time units): bounds the cost of a run
    /// whose criteria are slow to meet; such stages end at `time-limit` and say so.
    #[arg(long, value_name = "T")]
    pub max_time: Option<f64>,
    #[arg(long, short = 'j')]
    pub threads: Option<usize>,
    #[arg(long, short)]
    pub quiet: bool,
    /// Seconds of wall time between checkpoints.
    #[arg(long, default_value_t = 60.0, value_name = "SECS")]
    pub checkpoint_every: f64,
}

impl Args {
    fn flags(&self) -> RunFlags {
        RunFlags {
            quiet: self.quiet,
            report: true,
            resume: false,
            force: false,
            checkpoint_every: self.checkpoint_every,
            dump_every: None,
            trace_every: None,
            stage_snapshots: false,
        }
    }
}

/// `grainbench reproduce`.
pub fn command(a: Args) -> Result<i32> {
    on_threads(a.threads, || reproduce(&a))
}

/// One finished seed.
struct SeedRun {
    seed: u64,
    snapshot: Snapshot,
    wall_seconds: f64,
    status: StepEnd,
    steps: serde_json::Value,
    /// Worker threads of the run (results do not depend on it; wall time does).
    threads: usize,
    /// Contacts at their Coulomb or rolling threshold at the end (GRC07 §II.D: none at
    /// equilibrium); `None` for summaries written before it was recorded.
    contacts_at_threshold: Option<usize>,
    /// Of those, the contacts whose threshold (μN, μ_r N) is below the equilibrium tolerance;
    /// `None` for summaries written before it was recorded.
    below_tolerance: Option<usize>,
}

/// The states `reproduce` knows for `paper`: embedded scenes named `<paper>-<state>` with
/// published values to compare with.
fn states_of(paper: &str) -> Vec<String> {
    library::SCENES
        .iter()
        .filter(|(n, text)| {
            let key = grainbench_engine::Scene::from_toml(text, Path::new(n))
                .ok()
                .and_then(|s| s.paper_state)
                .unwrap_or_else(|| n.to_string());
            !n.ends_with("-ci") && paper::paper_values(&key).is_some()
        })
        .filter_map(|(n, _)| n.strip_prefix(&format!("{paper}-")))
        .map(String::from)
        .collect()
}

fn reproduce(a: &Args) -> Result<i32> {
    let (scene_name, base, state_key) = scene_of(a)?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs/reproduce").join(&scene_name));
    let runs = match run_seeds(a, &base, &scene_name, &out)? {
        Ok(runs) => runs,
        Err(code) => return Ok(code),
    };
    // The elastic moduli and rigidity counts (seconds a seed) only where the paper publishes
    // one of them (AR07 Z's H/N_f).
    let with_moduli = paper::paper_values(&state_key).is_some_and(|p| {
        p.values
            .keys()
            .any(|k| MODULI_METRICS.contains(&k.as_str()))
    });
    let analyses: Vec<Analysis> = runs
        .iter()
        .map(|r| {
            if with_moduli {
                analysis_with_moduli(&r.snapshot, &base)
            } else {
                analyze(&r.snapshot, &Default::default())
            }
        })
        .collect();
    let mut values: Vec<Vec<(String, f64)>> = analyses.iter().map(|a| a.metric_values()).collect();
    // GRC08 §III: the consolidation curve of each seed and its fit by GRC08 (9).
    let mut curves = Vec::new();
    if consolidation::is_cycle(&base, &state_key) {
        for (r, v) in runs.iter().zip(values.iter_mut()) {
            let mut scene = base.clone();
            scene.seed = r.seed;
            let levels = consolidation::levels(&scene, &r.steps, &seed_dir(&out, r.seed))?;
            let curve = consolidation::SeedCurve::new(r.seed, levels);
            v.extend(consolidation::values(&curve.levels, curve.fit.as_ref()));
            curves.push(curve);
        }
    }
    // GRC08 T.III fits the seeds' mean curve and GRC07 §V.D their mean I(k): those fits'
    // parameters stand for the seeds' own.
    let mean = consolidation::MeanCurve::of(&curves);
    let mut pooled = mean.as_ref().map(|m| m.pooled()).unwrap_or_default();
    let cycle_ik = consolidation::mean_scattering(&curves);
    pooled.extend(consolidation::pooled_density(&cycle_ik));
    let densities: Vec<_> = analyses.iter().filter_map(|a| a.density.as_ref()).collect();
    let mean_ik = (densities.len() == analyses.len())
        .then(|| density::mean_scattering(&densities))
        .flatten();
    if let Some(f) = mean_ik.as_ref().and_then(|m| m.fit.as_ref()) {
        let n = densities.len();
        pooled.push((
            "d_F".into(),
            SeedStats::mean_curve_fit(f.model.d_f, Some(f.d_f_error), n),
        ));
        pooled.push((
            "xi".into(),
            SeedStats::mean_curve_fit(f.model.xi, Some(f.xi_error), n),
        ));
    }
    let table = reproduction::build_pooled(&state_key, &values, &pooled)
        .with_context(|| format!("building the table of {state_key}"))?;
    // GRC08 T.IV: the contacts of one compression step, where the paper gives them.
    let step_state = state_key.replacen("consolidation", "step", 1);
    let mut step_seeds = Vec::new();
    if step_state != state_key && paper::paper_values(&step_state).is_some() {
        for c in &curves {
            let dir = seed_dir(&out, c.seed);
            step_seeds.extend(consolidation::step_values(c, &dir)?);
        }
    }
    let step_table = if step_seeds.is_empty() {
        None
    } else {
        Some(
            reproduction::build(&step_state, &step_seeds)
                .with_context(|| format!("building the table of {step_state}"))?,
        )
    };
    let level_tables = level_tables(&base, &state_key, &runs, &out)?;
    let mut markdown = format!("{}{}", table.to_markdown(), seed_summary(&runs));
    for t in step_table.iter().chain(&level_tables) {
        markdown = format!("{markdown}\n{}", t.to_markdown());
    }
    std::fs::create_dir_all(&out)?;
    snapshot::write_atomic(&out.join("report.md"), markdown.as_bytes())?;
    snapshot::write_atomic(&out.join("report.csv"), table.to_csv().as_bytes())?;
    snapshot::write_atomic(&out.join("report.json"), table.to_json().as_bytes())?;
    for t in &level_tables {
        let file = out.join(format!("report-{}.json", t.state));
        snapshot::write_atomic(&file, t.to_json().as_bytes())?;
    }
    let labels: Vec<String> = runs.iter().map(|r| format!("seed {}", r.seed)).collect();
    let figures = figures::packings(&out, &labels, &analyses, true, mean_ik.as_ref());
    for w in &figures.warnings {
        eprintln!("warning: {w}");
    }
    let mut plotted = figures.files;
    if !curves.is_empty() {
        plotted.push(consolidation::write_csv(&out, &curves)?);
        let paper = consolidation::paper_curve(&state_key);
        let more = consolidation::figures::all(&out, &curves, mean.as_ref(), paper, &cycle_ik);
        for w in &more.warnings {
            eprintln!("warning: {w}");
        }
        plotted.extend(more.files);
    }
    let svgs: Vec<PathBuf> = plotted
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "svg"))
        .cloned()
        .collect();
    let html = grainbench_comparisons::report::html::write(
        &out,
        &format!("grainbench reproduce {} --state {}", a.paper, a.state),
        &markdown,
        &svgs,
    )?;
    let not_equilibrated: Vec<u64> = runs
        .iter()
        .filter(|r| r.status != StepEnd::Equilibrium)
        .map(|r| r.seed)
        .collect();
    println!();
    print!("{markdown}");
    if !not_equilibrated.is_empty() {
        println!(
            "\nwarning: seeds {not_equilibrated:?} ended on a time limit, not at equilibrium: their metrics are of an unfinished packing"
        );
    }
    println!("report     {}", out.join("report.md").display());
    println!("report     {}", html.display());
    for p in plotted {
        println!("plot       {}", p.display());
    }
    if a.record {
        let tables = Tables {
            main: &table,
            step: step_table.as_ref(),
            levels: &level_tables,
        };
        let path = record(a, &scene_name, &base, &state_key, &runs, &values, tables)?;
        println!("recorded   {}", path.display());
        record_files(&out, &path)?;
    }
    Ok(0)
}

/// The scene `reproduce` runs (the paper size or its CI variant, `--max-time` applied), its
/// name, and the published state it is compared with.
fn scene_of(a: &Args) -> Result<(String, grainbench_engine::Scene, String)> {
    let paper = a.paper.to_lowercase();
    if !["ar07", "grc07", "grc08"].contains(&paper.as_str()) {
        bail!("unknown paper {:?}: expected ar07, grc07 or grc08", a.paper);
    }
    let state_key = format!("{paper}-{}", a.state);
    let scene_name = if a.ci {
        format!("{state_key}-ci")
    } else {
        state_key.clone()
    };
    if library::scene_text(&scene_name).is_none() {
        bail!(
            "no scene {scene_name:?} for {paper} state {:?}; states with scenes: {}{}",
            a.state,
            states_of(&paper).join(", "),
            if a.ci {
                " (CI variants exist for some: drop --ci for the paper-size scene)"
            } else {
                ""
            }
        );
    }
    if a.seeds.is_empty() {
        bail!("--seeds needs at least one seed");
    }
    let mut base = library::scene(&scene_name).expect("checked above")?;
    if let Some(t) = a.max_time {
        if !(t.is_finite() && t > 0.0) {
            bail!("--max-time must be a positive number of reduced time units, got {t}");
        }
        base.cap_max_time(t);
    }
    // A scene may reproduce another published row (the CI variant of D runs at 10 kPa).
    let state_key = base.paper_state.clone().unwrap_or(state_key);
    if paper::paper_values(&state_key).is_none() {
        bail!(
            "scene {scene_name} has no published values to compare with (no state {state_key:?} in golden/paper-values.toml); run it with `grainbench run {scene_name}`. {paper} states with scenes and values: {}",
            match states_of(&paper).join(", ") {
                s if s.is_empty() => "none yet".to_string(),
                s => s,
            }
        );
    }
    Ok((scene_name, base, state_key))
}

/// Runs each seed into `out/seed-K/`, reusing a seed that finished earlier with the same
/// settings and resuming one that was interrupted; `Err(status)` when a run did not finish.
fn run_seeds(
    a: &Args,
    base: &grainbench_engine::Scene,
    scene_name: &str,
    out: &Path,
) -> Result<std::result::Result<Vec<SeedRun>, i32>> {
    let mut runs = Vec::new();
    for (k, &seed) in a.seeds.iter().enumerate() {
        let mut scene = base.clone();
        scene.seed = seed;
        let dir = seed_dir(out, seed);
        eprintln!(
            "reproduce {scene_name}: seed {seed} ({} of {}) → {}",
            k + 1,
            a.seeds.len(),
            dir.display()
        );
        if let Some(done) = finished(&dir, &scene)? {
            eprintln!("  finished earlier: reusing {}", dir.display());
            runs.push(done);
            continue;
        }
        let flags = RunFlags {
            resume: dir.join(CHECKPOINT).exists(),
            // The levels of a pressure program (GRC08 §II.D.2) are the points of its curve.
            stage_snapshots: consolidation::has_program(&scene),
            ..a.flags()
        };
        let (code, outcome) = run(&scene, &dir, &flags)?;
        if code != 0 {
            if code == 130 {
                eprintln!("interrupted: run the same command again to continue where it stopped");
            }
            return Ok(Err(code));
        }
        let o = outcome.expect("a run that exits 0 has an outcome");
        runs.push(SeedRun {
            seed,
            status: o.status,
            wall_seconds: o.wall_seconds,
            steps: serde_json::to_value(&o.steps)?,
            threads: rayon::current_num_threads(),
            contacts_at_threshold: Some(o.contacts_at_threshold.all),
            below_tolerance: Some(o.contacts_at_threshold.below_tolerance),
            snapshot: o.snapshot,
        });
    }
    Ok(Ok(runs))
}

/// The table and the vector plots go beside the record (`path`), for reading on the web.
fn record_files(out: &Path, path: &Path) -> Result<()> {
    for f in [
        "report.md",
        "pf.svg",
        "gr.svg",
        "ik.svg",
        "consolidation.svg",
        "consolidation-z.svg",
        "consolidation-moduli.svg",
        "consolidation-ik.svg",
        "consolidation-xi.svg",
        "consolidation.csv",
    ] {
        let (from, to) = (out.join(f), path.with_file_name(f));
        if from.exists() {
            let bytes = std::fs::read(&from)?;
            snapshot::write_atomic(&to, &bytes)?;
            println!("recorded   {}", to.display());
        }
    }
    Ok(())
}

/// How each seed ended, with its contacts at a Coulomb or rolling threshold (GRC07 §II.D: none
/// at equilibrium; those whose threshold is below the equilibrium tolerance counted apart).
fn seed_summary(runs: &[SeedRun]) -> String {
    let seeds: Vec<String> = runs
        .iter()
        .map(|r| {
            let at = match (r.contacts_at_threshold, r.below_tolerance) {
                (Some(0), _) => ", no contact at a threshold".to_string(),
                (Some(n), Some(b)) => format!(
                    ", {n} contact(s) at a threshold ({b} with the threshold below the tolerance)"
                ),
                (Some(n), None) => format!(", {n} contact(s) at a threshold"),
                (None, _) => String::new(),
            };
            format!("{} ({}{at})", r.seed, r.status.as_str())
        })
        .collect();
    format!("\nSeeds: {}.\n", seeds.join("; "))
}

/// Where `reproduce` runs seed `seed` of a state whose output folder is `out`.
fn seed_dir(out: &Path, seed: u64) -> PathBuf {
    out.join(format!("seed-{seed}"))
}

/// A seed that finished earlier with the same settings.
fn finished(dir: &Path, scene: &grainbench_engine::Scene) -> Result<Option<SeedRun>> {
    let summary = dir.join(SUMMARY);
    if dir.join(CHECKPOINT).exists() || !summary.exists() {
        return Ok(None);
    }
    let s: serde_json::Value = serde_json::from_slice(&std::fs::read(&summary)?)
        .with_context(|| format!("reading {}", summary.display()))?;
    // Compared as scenes, so fields added later with defaults do not count as changes.
    let same = serde_json::from_value::<grainbench_engine::Scene>(s["settings"].clone())
        .is_ok_and(|saved| saved.same_run(scene));
    let text = s["status"].as_str().unwrap_or("");
    let Some(status) = StepEnd::parse(text) else {
        bail!(
            "{}: status {text:?} is not one a run writes (equilibrium, time-limit, interrupted, …): delete {} to run the seed again",
            summary.display(),
            dir.display()
        );
    };
    if !same || status == StepEnd::Interrupted {
        return Ok(None);
    }
    let snap = Snapshot::read(&dir.join(&scene.output.snapshot))?;
    Ok(Some(SeedRun {
        seed: scene.seed,
        snapshot: snap,
        wall_seconds: s["wall_seconds"].as_f64().unwrap_or(f64::NAN),
        status,
        steps: s["steps"].clone(),
        threads: s["threads"].as_u64().unwrap_or(0) as usize,
        contacts_at_threshold: s["contacts_at_threshold"].as_u64().map(|c| c as usize),
        below_tolerance: s["contacts_at_threshold_below_tolerance"]
            .as_u64()
            .map(|c| c as usize),
    }))
}

/// The reproduction tables of a run: the state's, and GRC08 T.IV's step where it applies.
struct Tables<'a> {
    main: &'a reproduction::Reproduction,
    step: Option<&'a reproduction::Reproduction>,
    levels: &'a [reproduction::Reproduction],
}

/// The tables of the states reached at levels of `state_key`'s pressure program
/// ([`paper::levels_of`]: AR07 T.III's QS rows), each from the seeds' stage-end snapshots of
/// that level.
fn level_tables(
    scene: &grainbench_engine::Scene,
    state_key: &str,
    runs: &[SeedRun],
    out: &Path,
) -> Result<Vec<reproduction::Reproduction>> {
    let mut tables = Vec::new();
    for (state, pressure) in paper::levels_of(state_key) {
        let Some(stage) = consolidation::program_stage(scene, pressure) else {
            bail!(
                "golden/paper-values.toml: {state} is the level P = {pressure} of {state_key}, but scene {} has no program level at that pressure; fix `level_of` or the scene's `pressure-program`",
                scene.name
            );
        };
        let mut seeds = Vec::new();
        for r in runs {
            let path = seed_dir(out, r.seed).join(STAGES).join(stage_file(stage));
            let snap = Snapshot::read(&path).with_context(|| {
                format!("the state of {state} (stage {stage}); run the seed again to write it")
            })?;
            seeds.push(analyze(&snap, &Default::default()).metric_values());
        }
        tables.push(
            reproduction::build(state, &seeds)
                .with_context(|| format!("building the table of {state}"))?,
        );
    }
    Ok(tables)
}

/// Writes golden/<scene>/rust.json: the command, the scene as run (`settings`, seed aside, with
/// `--max-time` applied), and each seed's status, wall time, stages and metrics.
fn record(
    a: &Args,
    scene_name: &str,
    scene: &grainbench_engine::Scene,
    state_key: &str,
    runs: &[SeedRun],
    values: &[Vec<(String, f64)>],
    tables: Tables,
) -> Result<PathBuf> {
    let path = crosscode::golden_file(scene_name, Code::Rust);
    let mut doc = serde_json::json!({
        "code": format!("grainbench {}", env!("CARGO_PKG_VERSION")),
        "scene": scene_name,
        "paper_state": state_key,
        "paper_description": paper::paper_values(state_key).map(|s| s.description.clone()),
        "command": format!(
            "grainbench reproduce {} --state {}{} --seeds {}{} -j {}",
            a.paper, a.state, if a.ci { " --ci" } else { "" }, seed_list(&a.seeds),
            a.max_time.map(|t| format!(" --max-time {t}")).unwrap_or_default(),
            runs.first().map_or(rayon::current_num_threads(), |r| r.threads)
        ),
        "n": runs.first().map(|r| r.snapshot.particles.radius.len()),
        "max_time": a.max_time,
        "settings": scene,
        "seeds": runs.iter().zip(values).map(|(r, v)| serde_json::json!({
            "seed": r.seed,
            "status": r.status.as_str(),
            "wall_seconds": r.wall_seconds,
            "threads": r.threads,
            "contacts_at_threshold": r.contacts_at_threshold,
            "contacts_at_threshold_below_tolerance": r.below_tolerance,
            "stages": r.steps,
            "metrics": v.iter().cloned().collect::<std::collections::BTreeMap<String, f64>>(),
        })).collect::<Vec<_>>(),
        "table": tables.main,
    });
    if let Some(step) = tables.step {
        doc["step_table"] = serde_json::to_value(step)?;
    }
    if !tables.levels.is_empty() {
        doc["level_tables"] = serde_json::to_value(tables.levels)?;
    }
    snapshot::write_atomic(&path, serde_json::to_string_pretty(&doc)?.as_bytes())?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A seed whose stage-end state at `stage` is `snap`, written where `reproduce` keeps it.
    fn seed_with_stage(out: &Path, seed: u64, stage: usize, snap: &Snapshot) -> SeedRun {
        let dir = seed_dir(out, seed).join(STAGES);
        std::fs::create_dir_all(&dir).unwrap();
        snap.write(&dir.join(stage_file(stage))).unwrap();
        SeedRun {
            seed,
            snapshot: snap.clone(),
            wall_seconds: 0.0,
            status: StepEnd::Equilibrium,
            steps: serde_json::Value::Null,
            threads: 1,
            contacts_at_threshold: Some(0),
            below_tolerance: Some(0),
        }
    }

    #[test]
    fn qs_levels_are_judged_on_their_stage_states() {
        let scene = library::scene("ar07-D-QS").unwrap().unwrap();
        let start = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/reference-inputs/starts/ar07-D-10kPa-n1372.snap.json"
        );
        let snap = Snapshot::read(Path::new(start)).unwrap();
        let phi = analyze(&snap, &Default::default()).packing_fraction;
        let out = tempfile::tempdir().unwrap();
        // The 10 kPa level ends stage 4 (melt, 1 kPa, then 1, √10, 10 kPa).
        let runs = vec![seed_with_stage(out.path(), 1, 4, &snap)];
        let tables = level_tables(&scene, "ar07-D-QS-100kPa", &runs, out.path()).unwrap();
        assert_eq!(tables.len(), 1);
        assert_eq!(tables[0].state, "ar07-D-QS-10kPa");
        let row = tables[0].rows.iter().find(|r| r.metric == "phi").unwrap();
        assert_eq!(row.ours.as_ref().unwrap().mean, phi);
        // No level states for a state without a program's levels.
        assert!(level_tables(&scene, "ar07-D", &runs, out.path())
            .unwrap()
            .is_empty());
        // A seed without that level's state: the error names the state and the stage.
        let missing = tempfile::tempdir().unwrap();
        let err = level_tables(&scene, "ar07-D-QS-100kPa", &runs, missing.path()).unwrap_err();
        let msg = format!("{err:#}");
        assert!(
            msg.contains("ar07-D-QS-10kPa") && msg.contains("stage 4"),
            "{msg}"
        );
    }
}
