//! `grainbench bench SCENE --codes …`: runs the same scene from the same start in each code,
//! alternating the codes run by run, and reports throughput (particle-steps/s), wall time and
//! steps to equilibrium (or for `--steps S` a fixed number of steps), peak resident memory per
//! child process and the ratio to our engine. `--scale N1,N2,…` times our engine alone on
//! dense packings of growing size ([`scale`]).

use crate::common::{install_stop_handler, load_scene, on_threads, STOP};
use crate::external;
use crate::run::{run, RunFlags};
use anyhow::{bail, Context, Result};
use grainbench_comparisons::outcome::Outcome;
use grainbench_comparisons::xcode::crosscode::CodeResult;
use grainbench_comparisons::xcode::decks::{lammps_bench, Code, Deck, Start};
use grainbench_comparisons::xcode::import::logs;
use grainbench_engine::run::layout::SUMMARY;
use grainbench_engine::run::StepEnd;
use grainbench_engine::scene::Scene;
use grainbench_engine::snapshot::write_atomic;
use report::{notes, rows_of, run_line, to_csv, to_markdown, Report, Run};
use setup::{fixed_steps, from_snapshot, Mode};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::Ordering;

mod memory;
mod report;
mod scale;
mod setup;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file or embedded scene name (not with --scale).
    pub scene: Option<String>,
    /// Codes, comma-separated: rust, lammps (Debian's 2021), lammps-2025, liggghts, yade
    /// (default: all).
    #[arg(long, value_delimiter = ',')]
    pub codes: Vec<String>,
    /// Thread counts, comma-separated: rust `-j T`, LAMMPS/LIGGGHTS `mpirun -np T` (T > 1),
    /// YADE `-j T`.
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub threads: Vec<usize>,
    /// Runs of each code and thread count (alternated: A B C A B C …).
    #[arg(long, default_value_t = 3, value_name = "K")]
    pub repeat: usize,
    /// Fixed number of MD steps of the first DEM stage (criteria off) instead of the run to
    /// equilibrium; rounded up to a multiple of the scene's check period.
    #[arg(long, value_name = "S")]
    pub steps: Option<u64>,
    /// Start every code from the grains of this snapshot (e.g. a dense packing of the same
    /// scene, `final.snap.json`) instead of the scene's start; the hard-grain prelude is skipped.
    #[arg(long, value_name = "SNAP")]
    pub start: Option<PathBuf>,
    /// Output directory (default: `runs/bench/<scene>`, `runs/bench/scale` with --scale).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Wall-time limit of each run, seconds (killed and reported as `timeout`).
    #[arg(long, default_value_t = 3600.0, value_name = "SECS")]
    pub time_limit: f64,
    /// Scale sweep of our engine: dense 3D Hertz–Mindlin packings of these sizes.
    #[arg(long, value_delimiter = ',', value_name = "N,…")]
    pub scale: Vec<usize>,
    /// Peak memory of whole `grainbench run`s (preparation, checks, checkpoints, output) on
    /// dense 3D Hertz–Mindlin packings of these sizes, per particle (memory.md/json).
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "N,…",
        conflicts_with = "scale"
    )]
    pub memory: Vec<usize>,
    /// No progress lines.
    #[arg(long, short)]
    pub quiet: bool,
    /// Internal: run SCENE (a file) into --out as the rust child of a benchmark.
    #[arg(long, hide = true)]
    pub child_run: bool,
    /// Internal: one size of the scale sweep, result as JSON on stdout.
    #[arg(long, hide = true, value_name = "N")]
    pub child_scale: Option<usize>,
}

/// `grainbench bench`.
pub fn command(a: Args) -> Result<i32> {
    bench(&a)
}

fn bench(a: &Args) -> Result<i32> {
    if a.threads.is_empty() || a.threads.contains(&0) {
        bail!("--threads: give thread counts ≥ 1, e.g. --threads 1,2");
    }
    if a.child_run {
        return child_run(a);
    }
    if let Some(n) = a.child_scale {
        return scale::child(n, a.steps.unwrap_or(scale::DEFAULT_STEPS), a.threads[0]);
    }
    if a.time_limit.is_nan() || a.time_limit <= 0.0 {
        bail!("--time-limit must be a positive number of seconds");
    }
    if a.repeat == 0 {
        bail!("--repeat must be at least 1");
    }
    if a.steps == Some(0) {
        bail!("--steps must be at least 1");
    }
    if !a.scale.is_empty() {
        if a.scene.is_some() {
            bail!("--scale times our engine on its own packings: give no scene with it");
        }
        if !a.codes.is_empty() && a.codes.iter().any(|c| c != "rust") {
            bail!("--scale runs our engine only (--codes rust)");
        }
        return scale::sweep(&scale::Sweep {
            sizes: &a.scale,
            threads: &a.threads,
            steps: a.steps,
            out: a.out.as_deref(),
            time_limit: a.time_limit,
            quiet: a.quiet,
        });
    }
    if !a.memory.is_empty() {
        if a.scene.is_some() {
            bail!("--memory runs our engine on its own packings: give no scene with it");
        }
        if !a.codes.is_empty() && a.codes.iter().any(|c| c != "rust") {
            bail!("--memory runs our engine only (--codes rust)");
        }
        if a.threads.len() != 1 {
            bail!("--memory: give one thread count (--threads T)");
        }
        return memory::sweep(
            &a.memory,
            a.threads[0],
            a.out.as_deref(),
            a.time_limit,
            a.quiet,
        );
    }
    let Some(spec) = &a.scene else {
        bail!("give a scene (`grainbench bench xcode-smoke`), --scale N,… or --memory N,…");
    };
    bench_scene(a, spec)
}

/// The rust child: `run` without the metrics report or periodic checkpoints; a plain progress
/// line every 5 s on stderr (its log).
fn child_run(a: &Args) -> Result<i32> {
    let (Some(scene), Some(out)) = (&a.scene, &a.out) else {
        bail!("--child-run needs a scene file and --out");
    };
    on_threads(Some(a.threads[0]), || {
        let scene = load_scene(scene)?;
        let flags = RunFlags {
            quiet: false,
            report: false,
            resume: false,
            // A harness scratch directory: a leftover checkpoint is not a run to keep.
            force: true,
            checkpoint_every: 1e12,
            dump_every: None,
            trace_every: None,
            stage_snapshots: false,
        };
        Ok(run(&scene, out, &flags)?.0)
    })
}

/// A code, its column of results, and its binary and deck (external codes that can run).
type Setup = (Code, CodeResult, Option<(PathBuf, Deck)>);

fn bench_scene(a: &Args, spec: &str) -> Result<i32> {
    let mut scene = load_scene(spec)?;
    if let Some(snap) = &a.start {
        scene = from_snapshot(&scene, snap)?;
    }
    let codes = if a.codes.is_empty() {
        Code::ALL.to_vec()
    } else {
        crate::xcode::parse_codes(&a.codes, true)?
    };
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs/bench").join(&scene.name));
    std::fs::create_dir_all(&out)
        .with_context(|| format!("creating the output directory {}", out.display()))?;
    let out = std::path::absolute(&out)?;
    install_stop_handler();
    let externals = codes.iter().any(|c| *c != Code::Rust);
    let (scene, start, mode) = match a.steps {
        Some(s) => {
            let (cut, start, steps) = fixed_steps(&scene, s)?;
            if steps != s {
                eprintln!(
                    "--steps {s} rounded up to {steps} (a multiple of the check period numerics.check_every = {})",
                    scene.numerics.check_every
                );
            }
            (cut, Some(start), Mode::Steps { steps })
        }
        None if externals => {
            let start =
                Start::of(&scene).map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
            (scene, Some(start), Mode::Equilibrium)
        }
        None => (scene, None, Mode::Equilibrium),
    };
    let n = scene.particles.count;
    // The scene as run, for the rust child (and the record).
    let scene_file = out.join("scene.toml");
    let text = toml::to_string(&scene).context("encoding the scene as TOML")?;
    Scene::from_toml(&text, &scene_file)
        .map_err(|e| anyhow::anyhow!("the scene does not read back from TOML: {e}"))?;
    write_atomic(&scene_file, text.as_bytes())?;
    eprintln!(
        "bench {} (N = {n}), {}: {} × threads {:?} × {} repeat(s) → {}",
        scene.name,
        mode.describe(),
        crate::xcode::code_names(&codes),
        a.threads,
        a.repeat,
        out.display()
    );
    let mut setups = prepare(&codes, start.as_ref(), mode, a);
    let total = a.repeat
        * a.threads.len()
        * setups
            .iter()
            .filter(|s| s.0 == Code::Rust || s.2.is_some())
            .count();
    let mut runs: Vec<Run> = Vec::new();
    'outer: for rep in 1..=a.repeat {
        for &t in &a.threads {
            for (code, r, ready) in &mut setups {
                if *code != Code::Rust && ready.is_none() {
                    continue;
                }
                if STOP.load(Ordering::SeqCst) {
                    break 'outer;
                }
                let dir = out.join("runs").join(format!("{}-j{t}-{rep}", code.name()));
                let order = runs.len() + 1;
                let mut run = Run {
                    order,
                    code: *code,
                    threads: t,
                    repeat: rep,
                    outcome: Outcome::Ran,
                    status: None,
                    message: None,
                    steps: None,
                    wall_seconds: None,
                    process_seconds: None,
                    loop_seconds: None,
                    particle_steps_per_second: None,
                    loop_particle_steps_per_second: None,
                    peak_rss_kib: None,
                    dir: dir.clone(),
                };
                match code {
                    Code::Rust => run_rust(&scene_file, &dir, t, a, &mut run)?,
                    _ => {
                        let (binary, deck) = ready.as_ref().expect("checked");
                        run_external(*code, binary, deck, &dir, t, a, r, &mut run)?
                    }
                }
                if let (Some(s), Some(w)) = (run.steps, run.wall_seconds) {
                    run.particle_steps_per_second = Some(n as f64 * s as f64 / w);
                }
                if let (Some(s), Some(w)) = (run.steps, run.loop_seconds) {
                    run.loop_particle_steps_per_second = Some(n as f64 * s as f64 / w);
                }
                if !a.quiet {
                    eprintln!("[{order}/{total}] {}", run_line(&run));
                }
                runs.push(run);
            }
        }
    }
    let columns: Vec<(Code, &CodeResult)> = setups.iter().map(|(c, r, _)| (*c, r)).collect();
    let rows = rows_of(&columns, &a.threads, &runs);
    let report = Report {
        scene: scene.name.clone(),
        n,
        mode,
        repeat: a.repeat,
        threads: a.threads.clone(),
        command: std::env::args().collect::<Vec<_>>().join(" "),
        notes: notes(&mode, a.start.as_deref()),
        run_order: runs
            .iter()
            .map(|r| format!("{}/-j{}/#{}", r.code, r.threads, r.repeat))
            .collect(),
        rows,
        runs,
    };
    let md = to_markdown(&report);
    println!("{md}");
    write_atomic(
        &out.join("bench.json"),
        (serde_json::to_string_pretty(&report)? + "\n").as_bytes(),
    )?;
    write_atomic(&out.join("bench.csv"), to_csv(&report).as_bytes())?;
    write_atomic(&out.join("bench.md"), md.as_bytes())?;
    grainbench_comparisons::report::html::write(
        &out,
        &format!("grainbench bench {}", scene.name),
        &md,
        &[],
    )?;
    eprintln!(
        "wrote {0}/bench.md, bench.csv, bench.json, report.html",
        out.display()
    );
    Ok(if STOP.load(Ordering::SeqCst) { 130 } else { 0 })
}

/// Each code's deck and binary, once: a code that cannot run is a row without runs, with why.
fn prepare(codes: &[Code], start: Option<&Start>, mode: Mode, a: &Args) -> Vec<Setup> {
    let mut setups: Vec<Setup> = Vec::new();
    for &code in codes {
        let mut r = CodeResult::new(code, Outcome::Ran);
        let ready = match (code, start) {
            (Code::Rust, _) => {
                r.version = Some(format!("grainbench {}", env!("CARGO_PKG_VERSION")));
                None
            }
            (_, Some(st)) => external::prepare(st, code, &mut r),
            (_, None) => unreachable!("a start is made when external codes run"),
        };
        let ready = match (ready, code, mode, start) {
            // Adhesion: the bench-only LAMMPS deck (throughput only).
            (None, Code::Lammps, Mode::Steps { .. }, Some(st))
                if r.outcome == Outcome::Refused && st.cohesive() =>
            {
                match (
                    Code::Lammps.find(),
                    lammps_bench::deck(st, lammps_bench::CLASSES),
                ) {
                    (Some(bin), Ok(deck)) => {
                        r.outcome = Outcome::Ran;
                        r.message = None;
                        r.deviations = deck.deviations.clone();
                        eprintln!(
                            "lammps    bench-only deck: diameters in {} size classes, GRC07 attraction by pair_style table (approximate, throughput only)",
                            lammps_bench::CLASSES
                        );
                        Some((bin, deck))
                    }
                    _ => None,
                }
            }
            (ready, ..) => ready,
        };
        if code != Code::Rust && ready.is_none() {
            eprintln!(
                "{:<9} {}: {}",
                code.name(),
                r.outcome,
                r.message.as_deref().unwrap_or("")
            );
        }
        if code != Code::Rust
            && matches!(code, Code::Lammps | Code::Liggghts)
            && a.threads.iter().any(|&t| t > 1)
            && grainbench_comparisons::xcode::decks::which("mpirun").is_none()
            && ready.is_some()
        {
            r.outcome = Outcome::Missing;
            r.message = Some("`mpirun` not found on PATH (needed for threads > 1); install with `apt-get install -y --no-install-recommends openmpi-bin`".into());
            eprintln!(
                "{:<9} missing: {}",
                code.name(),
                r.message.as_deref().unwrap_or("")
            );
            setups.push((code, r, None));
            continue;
        }
        setups.push((code, r, ready));
    }
    setups
}

fn run_rust(scene_file: &Path, dir: &Path, threads: usize, a: &Args, run: &mut Run) -> Result<()> {
    if dir.exists() {
        std::fs::remove_dir_all(dir).with_context(|| format!("clearing {}", dir.display()))?;
    }
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let exe = std::env::current_exe().context("locating the grainbench executable")?;
    let mut cmd = Command::new(exe);
    cmd.args(["bench", "--child-run"]).arg(scene_file).args([
        "--out",
        ".",
        "--threads",
        &threads.to_string(),
    ]);
    let done = external::supervise(
        &mut cmd,
        dir,
        "rust",
        a.time_limit,
        a.quiet,
        Some("stderr.log"),
    )?;
    run.peak_rss_kib = Some(done.peak_rss_kib());
    run.process_seconds = Some(done.wall_seconds);
    match done.status {
        None => {
            run.outcome = if STOP.load(Ordering::SeqCst) {
                Outcome::Interrupted
            } else {
                Outcome::Timeout
            };
            run.message = Some(format!(
                "stopped at the time limit of {} s (--time-limit); logs in {}",
                a.time_limit,
                dir.display()
            ));
            return Ok(());
        }
        Some(s) if !s.success() => {
            run.outcome = Outcome::Failed;
            run.message = Some(format!(
                "exited with {s}: {:?}; logs in {}",
                logs::failure_line(&dir.join("stderr.log")),
                dir.display()
            ));
            return Ok(());
        }
        Some(_) => {}
    }
    let path = dir.join(SUMMARY);
    let summary: serde_json::Value = serde_json::from_slice(
        &std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?,
    )
    .with_context(|| format!("parsing {}", path.display()))?;
    let (mut steps, mut loop_s, mut prelude) = (0u64, 0.0, 0.0);
    for s in summary["steps"].as_array().into_iter().flatten() {
        let wall = s["wall_seconds"].as_f64().unwrap_or(0.0);
        if s["end"].as_str().and_then(StepEnd::parse) == Some(StepEnd::Done) {
            // Hard-grain stage: `steps` counts collisions.
            prelude += wall;
        } else {
            steps += s["steps"].as_u64().unwrap_or(0);
            loop_s += wall;
        }
    }
    run.status = summary["status"].as_str().map(String::from);
    run.steps = Some(steps);
    run.loop_seconds = Some(loop_s);
    run.wall_seconds = Some(done.wall_seconds - prelude);
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn run_external(
    code: Code,
    binary: &Path,
    deck: &Deck,
    dir: &Path,
    threads: usize,
    a: &Args,
    r: &mut CodeResult,
    run: &mut Run,
) -> Result<()> {
    external::write_fresh_deck(deck, dir)?;
    let np = (threads > 1).then_some(threads);
    let mut cmd = external::command(code, binary, deck, np, Some(threads))?;
    let done = external::supervise(
        &mut cmd,
        dir,
        code.name(),
        a.time_limit,
        a.quiet,
        Some("stdout.log"),
    )?;
    run.peak_rss_kib = Some(done.peak_rss_kib());
    run.wall_seconds = Some(done.wall_seconds);
    let throughput_only = deck
        .files
        .iter()
        .any(|(n, _)| n == lammps_bench::BENCH_TABLE);
    if throughput_only && done.status.is_some_and(|s| s.success()) {
        // No final state to read back: steps and status from the log.
        if r.version.is_none() {
            r.version = external::version_line(code, &dir.join("stdout.log"));
        }
        run.status = Some(grainbench_comparisons::xcode::import::read_status(
            &dir.join("final.status"),
        ));
        run.steps = logs::log_steps(dir);
        run.loop_seconds = logs::loop_time(code, dir);
        if run.steps.is_none() {
            run.outcome = Outcome::Failed;
            run.message = Some(format!(
                "no `Loop time` line in {}/stdout.log",
                dir.display()
            ));
            run.wall_seconds = None;
        }
        return Ok(());
    }
    let mut res = CodeResult::new(code, Outcome::Ran);
    let snap = external::finish(code, dir, &done, a.time_limit, &mut res)?;
    if r.version.is_none() {
        r.version = res.version.clone();
    }
    run.outcome = res.outcome;
    run.message = res.message;
    if let Some(snap) = snap {
        run.status = Some(snap.status.clone());
        run.steps = Some(snap.step);
        run.loop_seconds = logs::loop_time(code, dir);
    } else {
        run.wall_seconds = None;
    }
    Ok(())
}
