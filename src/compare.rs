//! `grainbench compare SCENE --codes …`: runs a scene in our engine and in the external codes
//! from the same start, reads every final state into our snapshot format, measures all of
//! them with the same `comparisons/` code, and writes the table (Markdown, CSV, JSON) and the
//! overlaid P(f) and g(r) plots. `grainbench golden update` records the results.

use crate::common::{
    analysis_with_moduli, install_stop_handler, load_scene, on_threads, seed_list, STOP,
};
use crate::external;
use crate::run::{run, RunFlags};
use crate::xcode;
use anyhow::{bail, Context, Result};
use grainbench_comparisons::metrics::impact::ImpactReport;
use grainbench_comparisons::metrics::pair_history;
use grainbench_comparisons::metrics::Analysis;
use grainbench_comparisons::outcome::Outcome;
use grainbench_comparisons::report::figures;
use grainbench_comparisons::xcode::crosscode::{
    self, Bands, CodeImpact, CodePairs, CodeResult, Comparison,
};
use grainbench_comparisons::xcode::decks::generic::OUT_TRACE_CONTACTS;
use grainbench_comparisons::xcode::decks::{Code, StageKind, Start};
use grainbench_comparisons::xcode::import::{self, Meta};
use grainbench_comparisons::xcode::seeds;
use grainbench_engine::snapshot::{write_atomic, Snapshot};
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file or embedded scene name.
    pub scene: String,
    /// Codes, comma-separated: rust, lammps (Debian's 2021), lammps-2025, liggghts, yade
    /// (default: all), and NAME=PATH.toml for any code with an adapter file
    /// (docs/exchange-format.md).
    #[arg(long, value_delimiter = ',')]
    pub codes: Vec<String>,
    /// Seeds, comma-separated (default: the scene's). With several, each seed is compared
    /// in `seed-K/` and `compare-seeds.md` gives every code's mean ± s.d., with P(f) per
    /// code over its seeds' band.
    #[arg(long, value_delimiter = ',')]
    pub seeds: Vec<u64>,
    /// Output directory (default: `runs/compare/<scene>`).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Wall-time limit of each external run, seconds.
    #[arg(long, default_value_t = 3600.0, value_name = "SECS")]
    pub time_limit: f64,
    /// Run LAMMPS and LIGGGHTS under `mpirun -np K`.
    #[arg(long, value_name = "K")]
    pub np: Option<usize>,
    /// Worker threads of our engine.
    #[arg(long, short = 'j')]
    pub threads: Option<usize>,
    /// Every metric in the terminal table (the files always have all).
    #[arg(long)]
    pub all_metrics: bool,
    #[arg(long, short)]
    pub quiet: bool,
}

/// `grainbench compare`.
pub fn command(a: Args) -> Result<i32> {
    install_stop_handler();
    on_threads(a.threads, || compare(&a))
}

fn compare(a: &Args) -> Result<i32> {
    let scene = load_scene(&a.scene)?;
    let codes = if a.codes.is_empty() {
        Code::ALL.to_vec()
    } else {
        xcode::parse_codes(&a.codes, true)?
    };
    if a.np == Some(0) {
        bail!("--np must be at least 1");
    }
    if a.time_limit.is_nan() || a.time_limit <= 0.0 {
        bail!("--time-limit must be a positive number of seconds");
    }
    let seeds = &a.seeds;
    if let Some((_, s)) = seeds
        .iter()
        .enumerate()
        .find(|(i, s)| seeds[..*i].contains(s))
    {
        bail!("--seeds lists seed {s} twice");
    }
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs/compare").join(&scene.name));
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    if seeds.len() <= 1 {
        let mut scene = scene;
        if let Some(&s) = seeds.first() {
            scene.seed = s;
        }
        let (cmp, analyses) = compare_one(a, &scene, &codes, &out)?;
        write_outputs(&out, &cmp, analyses, a.all_metrics)?;
        return Ok(if cmp.failures.is_empty() { 0 } else { 1 });
    }
    // Several seeds: each compared on its own, then every code over its seeds.
    let mut runs = Vec::new();
    let mut per_code: Vec<(String, Vec<Analysis>)> = Vec::new();
    for (k, &seed) in seeds.iter().enumerate() {
        if STOP.load(Ordering::SeqCst) {
            break;
        }
        let mut scene = scene.clone();
        scene.seed = seed;
        let dir = out.join(format!("seed-{seed}"));
        eprintln!(
            "seed {seed} ({} of {}) → {}",
            k + 1,
            seeds.len(),
            dir.display()
        );
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        let (cmp, analyses) = compare_one(a, &scene, &codes, &dir)?;
        for (code, analysis) in &analyses {
            match per_code.iter_mut().find(|(c, _)| c == code) {
                Some((_, list)) => list.push(analysis.clone()),
                None => per_code.push((code.clone(), vec![analysis.clone()])),
            }
        }
        write_outputs(&dir, &cmp, analyses, a.all_metrics)?;
        runs.push((seed, cmp));
    }
    let summary = seeds::over_seeds(&runs);
    println!("{}", summary.to_markdown(a.all_metrics));
    write_atomic(
        &out.join("compare-seeds.md"),
        summary.to_markdown(true).as_bytes(),
    )?;
    write_atomic(&out.join("compare-seeds.csv"), summary.to_csv().as_bytes())?;
    write_atomic(
        &out.join("compare-seeds.json"),
        (serde_json::to_string_pretty(&summary)? + "\n").as_bytes(),
    )?;
    let bands = figures::seed_bands(&out, &per_code);
    for w in &bands.warnings {
        eprintln!("warning: {w}");
    }
    let svgs: Vec<PathBuf> = bands.svgs().cloned().collect();
    grainbench_comparisons::report::html::write(
        &out,
        &format!(
            "grainbench compare {} --seeds {}",
            scene.name,
            seed_list(seeds)
        ),
        &summary.to_markdown(true),
        &svgs,
    )?;
    eprintln!(
        "wrote {0}/compare-seeds.md, compare-seeds.csv, compare-seeds.json, report.html, pf.svg/png; each seed in {0}/seed-K/{1}",
        out.display(),
        if summary.failures.is_empty() {
            String::new()
        } else {
            format!("; {} check(s) failed", summary.failures.len())
        }
    );
    if runs.len() < seeds.len() {
        eprintln!("interrupted after {} of {} seeds", runs.len(), seeds.len());
        return Ok(130);
    }
    Ok(if summary.failures.is_empty() { 0 } else { 1 })
}

/// One seed: every code run from the scene's start, measured and compared.
fn compare_one(
    a: &Args,
    scene: &grainbench_engine::Scene,
    codes: &[Code],
    out: &Path,
) -> Result<(Comparison, Vec<(String, Analysis)>)> {
    let start = Start::of(scene).map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
    let (p_target, p_tol) = match start.stages.last() {
        Some(s) => match s.kind {
            StageKind::Compress { pressure } => (Some(pressure), Some(s.tolerances.stress)),
            _ => (None, None),
        },
        None => (None, None),
    };
    eprintln!(
        "compare {} (N = {}, seed {}): {} → {}",
        scene.name,
        start.n(),
        scene.seed,
        xcode::code_names(codes),
        out.display()
    );
    let mut results = Vec::new();
    let mut analyses: Vec<(String, Analysis)> = Vec::new();
    // A traced scene leaves every code's trace as ours (trace-grains.csv, trace-contacts.csv);
    // with two grains it is an impact test in every code.
    let traced = scene.output.trace_every.is_some();
    let mut impacts = (traced && start.n() == 2).then(Vec::new);
    for &code in codes {
        if STOP.load(Ordering::SeqCst) {
            break;
        }
        let dir = out.join(code.name());
        let mut r = CodeResult {
            golden: crosscode::golden_metrics(Path::new("."), &scene.name, code),
            pressure_target: p_target,
            pressure_tolerance: p_tol,
            ..CodeResult::new(code, Outcome::Ran)
        };
        let snap = match code {
            Code::Rust => run_rust(scene, &dir, a.quiet, &mut r)?,
            _ => external::run(&start, code, &dir, a.time_limit, a.np, a.quiet, &mut r)?,
        };
        if let (Some(snap), true) = (&snap, traced) {
            if let (Some(report), Some(list)) = (trace_of(code, &dir, scene, snap)?, &mut impacts) {
                list.push(CodeImpact { code, report });
            }
        }
        if let Some(snap) = snap {
            let analysis = analysis_with_moduli(&snap, scene);
            r.metrics = analysis.metric_values().into_iter().collect();
            r.status = Some(snap.status.clone());
            analyses.push((code.name().to_string(), analysis));
        }
        eprintln!(
            "{:<9} {}{}",
            code.name(),
            r.outcome,
            r.status
                .as_deref()
                .map(|s| format!(" ({s}, {:.1} s)", r.wall_seconds.unwrap_or(f64::NAN)))
                .or(r.message.as_deref().map(|m| format!(": {m}")))
                .unwrap_or_default()
        );
        results.push(r);
    }
    let mut cmp = crosscode::build_with(
        &scene.name,
        start.n(),
        Some(scene.paper_state.as_deref().unwrap_or(&scene.name)),
        results,
        &Bands::embedded(),
        impacts,
        matches!(
            scene.protocol.last(),
            Some(grainbench_engine::scene::Step::FixedVolume {
                full_time: true,
                ..
            })
        ),
    );
    // More than two grains traced: each code's contacts, pair by pair, against ours.
    if traced && start.n() > 2 {
        let mut pairs = Vec::new();
        for c in cmp.codes.iter().filter(|c| c.outcome == Outcome::Ran) {
            let path = out.join(c.code.name()).join(OUT_TRACE_CONTACTS);
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("reading {}", path.display()))?;
            pairs.push(CodePairs {
                code: c.code,
                pairs: pair_history::from_csv(&text)
                    .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?,
            });
        }
        cmp.add_pairs(pairs);
    }
    Ok((cmp, analyses))
}

fn write_outputs(
    out: &Path,
    cmp: &Comparison,
    analyses: Vec<(String, Analysis)>,
    all: bool,
) -> Result<()> {
    let md = cmp.to_markdown(all);
    println!("{md}");
    write_atomic(&out.join("compare.md"), cmp.to_markdown(true).as_bytes())?;
    write_atomic(&out.join("compare.csv"), cmp.to_csv().as_bytes())?;
    write_atomic(
        &out.join("compare.json"),
        (serde_json::to_string_pretty(cmp)? + "\n").as_bytes(),
    )?;
    let labels: Vec<String> = analyses.iter().map(|(c, _)| c.clone()).collect();
    let analyses: Vec<Analysis> = analyses.into_iter().map(|(_, a)| a).collect();
    let plots = figures::packings(out, &labels, &analyses, false, None);
    for w in &plots.warnings {
        eprintln!("warning: {w}");
    }
    let svgs: Vec<PathBuf> = plots.svgs().cloned().collect();
    grainbench_comparisons::report::html::write(
        out,
        &format!("grainbench compare {}", cmp.scene),
        &cmp.to_markdown(true),
        &svgs,
    )?;
    eprintln!(
        "wrote {0}/compare.md, compare.csv, compare.json, report.html, pf.svg/png, gr.svg/png{1}",
        out.display(),
        if cmp.failures.is_empty() {
            String::new()
        } else {
            format!("; {} check(s) failed", cmp.failures.len())
        }
    );
    Ok(())
}

/// The trace of a traced run, and the impact of two grains: ours wrote its files and
/// `impact.json` itself; an external code's trace is read (closed by its final state) and
/// written as ours is (`trace-grains.csv`, `trace-contacts.csv`, and for two grains
/// `impact.json`, measured the same way).
fn trace_of(
    code: Code,
    dir: &Path,
    scene: &grainbench_engine::Scene,
    last: &Snapshot,
) -> Result<Option<ImpactReport>> {
    if code == Code::Rust {
        let path = dir.join("impact.json");
        if !path.exists() {
            return Ok(None);
        }
        let text = std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
        return Ok(Some(
            serde_json::from_slice(&text).with_context(|| format!("reading {}", path.display()))?,
        ));
    }
    let meta = Meta::read(dir)?;
    let Some(mut frames) = import::trace::read(code, dir, &meta)? else {
        return Ok(None);
    };
    if frames.last().is_some_and(|f| f.step < last.step) {
        frames.push(last.clone());
    }
    crate::trace::write(dir, scene, &frames)
}

/// Our engine, in this process.
fn run_rust(
    scene: &grainbench_engine::Scene,
    dir: &Path,
    quiet: bool,
    r: &mut CodeResult,
) -> Result<Option<Snapshot>> {
    let flags = RunFlags {
        quiet,
        report: false,
        resume: false,
        // A harness scratch directory: a leftover checkpoint is not a run to keep.
        force: true,
        checkpoint_every: 60.0,
        dump_every: None,
        trace_every: None,
        stage_snapshots: false,
    };
    r.version = Some(format!("grainbench {}", env!("CARGO_PKG_VERSION")));
    let t = Instant::now();
    let (code, outcome) = run(scene, dir, &flags)?;
    r.wall_seconds = Some(t.elapsed().as_secs_f64());
    match outcome {
        Some(o) if code == 0 => Ok(Some(o.snapshot)),
        Some(o) => {
            r.outcome = Outcome::Interrupted;
            Ok(Some(o.snapshot))
        }
        None => {
            r.outcome = Outcome::Failed;
            r.message = Some(format!("grainbench run exited with status {code}"));
            Ok(None)
        }
    }
}
