//! `grainbench`: run DEM scenes, analyze packings.

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use grainbench_engine::checkpoint::Checkpoint;
use grainbench_engine::run::{CheckpointSpec, Outcome, Progress, RunError, RunOptions};
use grainbench_engine::{library, snapshot, Scene, Snapshot};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

mod accuracy;
mod bench;
mod compare;
mod reproduce;
mod xcode;

/// Set by the first Ctrl-C (or SIGTERM): runs stop cleanly at their next check.
static STOP: AtomicBool = AtomicBool::new(false);

#[derive(Parser)]
#[command(
    name = "grainbench",
    version,
    about = "Periodic stress-controlled DEM for granular packings (AR07, GRC07), with packing metrics"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene (a TOML file, or the name of an embedded scene; default: `default`).
    Run {
        /// Scene file or embedded scene name.
        scene: Option<String>,
        /// Output directory (default: `runs/<scene name>`).
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Worker threads (default: all cores).
        #[arg(long, short = 'j')]
        threads: Option<usize>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
        /// Exit with status 3 unless every protocol step ends at equilibrium.
        #[arg(long)]
        require_equilibrium: bool,
        /// Continue the interrupted run whose checkpoint is in the output directory; the
        /// result is bit-identical to an uninterrupted run.
        #[arg(long)]
        resume: bool,
        /// Seconds of wall time between checkpoints (`<out>/checkpoint.bin`); 0 = at every
        /// check. The checkpoint is removed when the run completes.
        #[arg(long, default_value_t = 60.0, value_name = "SECS")]
        checkpoint_every: f64,
        /// Seed of the initial state instead of the scene's.
        #[arg(long)]
        seed: Option<u64>,
    },
    /// Packing metrics of a snapshot: Φ, z, z*, x0, force moments, AR07 (22) / GRC07 (18) checks.
    Analyze {
        /// A grainbench snapshot, or with --from a directory of another code's final dumps.
        snapshot: PathBuf,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Read the final state of another code from a directory: `lammps` (dump custom +
        /// dump local), `liggghts` (dump custom + pair/gran/local), `yade` (text export); the
        /// directory needs a `deck.json` (written with the decks; format in
        /// docs/external-formats/).
        #[arg(long, value_name = "CODE")]
        from: Option<String>,
        /// Also write the state read as a grainbench snapshot.
        #[arg(long, value_name = "FILE")]
        write: Option<PathBuf>,
    },
    /// List the embedded scenes.
    Scenes,
    /// Write LAMMPS, LIGGGHTS and YADE decks (input + data file of the same initial
    /// configuration) of a scene into `reference-inputs/<scene>/<code>/`.
    Decks {
        /// Scene files or embedded scene names.
        scenes: Vec<String>,
        /// Every embedded scene.
        #[arg(long)]
        all: bool,
        /// Codes, comma-separated (default: lammps,liggghts,yade).
        #[arg(long, value_delimiter = ',')]
        codes: Vec<String>,
        /// Output directory instead of `reference-inputs/<scene>/` (one scene only).
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// Run a scene in our engine and in LAMMPS, LIGGGHTS and YADE from the same start, and
    /// compare every metric with the paper, the golden values and each other (Markdown table,
    /// CSV, JSON, overlaid P(f) and g(r)). Exit status 1 when a check fails. Bare `grainbench`
    /// runs `compare xcode-smoke`.
    Compare {
        /// Scene file or embedded scene name.
        scene: String,
        /// Codes, comma-separated (default: rust,lammps,liggghts,yade).
        #[arg(long, value_delimiter = ',')]
        codes: Vec<String>,
        /// Output directory (default: `runs/compare/<scene>`).
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Wall-time limit of each external run, seconds.
        #[arg(long, default_value_t = 3600.0, value_name = "SECS")]
        time_limit: f64,
        /// Run LAMMPS and LIGGGHTS under `mpirun -np K`.
        #[arg(long, value_name = "K")]
        np: Option<usize>,
        /// Worker threads of our engine.
        #[arg(long, short = 'j')]
        threads: Option<usize>,
        /// Every metric in the terminal table (the files always have all).
        #[arg(long)]
        all_metrics: bool,
        #[arg(long, short)]
        quiet: bool,
    },
    /// Speed against error: sweep the time step (dt), the strain-rate cap (inertia), the
    /// equilibrium tolerance and κ one at a time from the scene's settings over several seeds,
    /// and table wall time against the error of Φ, z*, x0 and P(f) (KS distance) relative to
    /// the tightest settings, with the Pareto front (accuracy.md/csv/json, plots). Time steps
    /// past stability are tabled as `unstable: <message>`.
    Accuracy(accuracy::Args),
    /// Golden values: `grainbench golden update SCENE` records the last `compare` run of the
    /// scene as golden/<scene>/<code>.json (only when asked: nothing else writes them).
    Golden {
        #[command(subcommand)]
        action: GoldenAction,
    },
    /// Print the capability matrix: how each external code expresses each scene feature
    /// (`exact`, `approximate` with the deviation, `unsupported`); with a scene, only its features.
    Capabilities { scene: Option<String> },
    /// Run a paper's state at paper size over several seeds and compare every metric with the
    /// published values (table in Markdown/CSV/JSON, P(f) and g(r) plots). Interrupted runs
    /// continue where they stopped when the same command is given again.
    Reproduce {
        /// ar07, grc07 or grc08.
        paper: String,
        /// State: A, Aprime, B, C, D, Z, D-QS (AR07); type1-phi036-mu05, type2-phi036-rr, …
        /// (GRC07); cycle-rr (GRC08). `grainbench scenes` lists them as <paper>-<state>.
        #[arg(long)]
        state: String,
        /// Seeds, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "1")]
        seeds: Vec<u64>,
        /// The reduced CI variant of the scene (`<paper>-<state>-ci`).
        #[arg(long)]
        ci: bool,
        /// Output directory (default: `runs/reproduce/<scene>`).
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Also write golden/<scene>/rust.json (command, seeds, wall times, metrics).
        #[arg(long)]
        record: bool,
        /// Cap the time limit of every stage (reduced time units): bounds the cost of a run
        /// whose criteria are slow to meet; such stages end at `time-limit` and say so.
        #[arg(long, value_name = "T")]
        max_time: Option<f64>,
        #[arg(long, short = 'j')]
        threads: Option<usize>,
        #[arg(long, short)]
        quiet: bool,
        /// Seconds of wall time between checkpoints.
        #[arg(long, default_value_t = 60.0, value_name = "SECS")]
        checkpoint_every: f64,
    },
    /// Time a scene in our engine and in LAMMPS, LIGGGHTS and YADE from the same start, runs
    /// alternated, each code a child process: particle-steps/s, time and steps to equilibrium
    /// (or `--steps S` fixed steps), peak RSS, ratio to ours (bench.md/csv/json). `--scale
    /// N,…` times our engine alone on dense packings of growing size (scale.md/csv/json/svg).
    Bench(bench::Args),
}

#[derive(Subcommand)]
enum GoldenAction {
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

fn main() {
    let cli = Cli::parse();
    let code = match dispatch(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            2
        }
    };
    std::process::exit(code);
}

fn dispatch(cli: Cli) -> Result<i32> {
    match cli.command.unwrap_or(Command::Compare {
        scene: DEFAULT_COMPARE.into(),
        codes: Vec::new(),
        out: None,
        time_limit: 3600.0,
        np: None,
        threads: None,
        all_metrics: false,
        quiet: false,
    }) {
        Command::Compare {
            scene,
            codes,
            out,
            time_limit,
            np,
            threads,
            all_metrics,
            quiet,
        } => {
            set_threads(threads)?;
            install_stop_handler();
            compare::compare(&compare::Args {
                scene,
                codes,
                out,
                time_limit,
                np,
                quiet,
                all_metrics,
            })
        }
        Command::Accuracy(args) => {
            set_threads(args.threads)?;
            accuracy::accuracy(&args)
        }
        Command::Golden {
            action: GoldenAction::Update { scene, codes, from },
        } => compare::golden_update(&scene, &codes, from, None),
        Command::Golden {
            action: GoldenAction::Show { scene, all_metrics },
        } => compare::golden_show(&scene, all_metrics),
        Command::Run {
            scene,
            out,
            threads,
            quiet,
            require_equilibrium,
            resume,
            checkpoint_every,
            seed,
        } => {
            set_threads(threads)?;
            let flags = RunFlags {
                quiet,
                report: true,
                resume,
                checkpoint_every,
            };
            let (mut scene, out) = scene_and_out(scene.as_deref(), out, resume)?;
            if let Some(s) = seed {
                scene.seed = s;
            }
            let (code, outcome) = run(&scene, &out, &flags)?;
            if let Some(o) = outcome {
                if code == 0 && require_equilibrium && !o.equilibrated() {
                    eprintln!("not every step reached equilibrium (--require-equilibrium)");
                    return Ok(3);
                }
            }
            Ok(code)
        }
        Command::Analyze {
            snapshot,
            json,
            from,
            write,
        } => analyze(&snapshot, json, from.as_deref(), write.as_deref()),
        Command::Reproduce {
            paper,
            state,
            seeds,
            ci,
            out,
            record,
            max_time,
            threads,
            quiet,
            checkpoint_every,
        } => {
            set_threads(threads)?;
            reproduce::reproduce(&reproduce::Args {
                paper,
                state,
                seeds,
                ci,
                out,
                record,
                max_time,
                flags: RunFlags {
                    quiet,
                    report: true,
                    resume: false,
                    checkpoint_every,
                },
            })
        }
        Command::Decks {
            scenes,
            all,
            codes,
            out,
        } => xcode::decks_command(&scenes, all, &codes, out),
        Command::Capabilities { scene } => xcode::capabilities_command(scene.as_deref()),
        Command::Bench(args) => bench::bench(&args),
        Command::Scenes => {
            for (name, text) in library::SCENES {
                let scene = Scene::from_toml(text, Path::new(name))?;
                println!(
                    "{name:<24} {}D N={:<6} {}",
                    scene.dimension, scene.particles.count, scene.description
                );
            }
            Ok(0)
        }
    }
}

/// Loads a scene from a file, or an embedded one by name.
pub(crate) fn load_scene(spec: &str) -> Result<Scene> {
    let path = Path::new(spec);
    if path.is_file() || (path.exists() && library::scene_text(spec).is_none()) {
        return Ok(Scene::from_file(path)?);
    }
    if let Some(text) = library::scene_text(spec) {
        return Ok(Scene::from_toml(
            text,
            Path::new(&format!("<embedded:{spec}>")),
        )?);
    }
    let names: Vec<&str> = library::SCENES.iter().map(|(n, _)| *n).collect();
    bail!(
        "no scene file {spec:?} and no embedded scene of that name (embedded: {}; `grainbench scenes` lists them)",
        names.join(", ")
    )
}

/// Options of one run.
#[derive(Clone)]
pub(crate) struct RunFlags {
    pub(crate) quiet: bool,
    /// Print the metrics table of the final state.
    pub(crate) report: bool,
    pub(crate) resume: bool,
    pub(crate) checkpoint_every: f64,
}

fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(t) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("setting the thread count")?;
    }
    Ok(())
}

pub(crate) const CHECKPOINT: &str = "checkpoint.bin";

/// The scene and output directory of `run`: with `--resume` the scene may come from the
/// checkpoint of the output directory.
fn scene_and_out(
    spec: Option<&str>,
    out: Option<PathBuf>,
    resume: bool,
) -> Result<(Scene, PathBuf)> {
    match (spec, &out, resume) {
        (None, Some(dir), true) => {
            let cp = Checkpoint::read(&dir.join(CHECKPOINT)).map_err(anyhow::Error::msg)?;
            let scene = cp.scene().map_err(anyhow::Error::msg)?;
            Ok((scene, dir.clone()))
        }
        _ => {
            let scene = load_scene(spec.unwrap_or("default"))?;
            let out = out.unwrap_or_else(|| Path::new("runs").join(&scene.name));
            Ok((scene, out))
        }
    }
}

/// Runs one scene into `out` (writing the snapshot, summary and checkpoints); returns the
/// exit status and the outcome when the run ended normally or was interrupted.
pub(crate) fn run(scene: &Scene, out: &Path, flags: &RunFlags) -> Result<(i32, Option<Outcome>)> {
    let quiet = flags.quiet;
    let cp_path = out.join(CHECKPOINT);
    let resume = if flags.resume {
        let cp = Checkpoint::read(&cp_path).map_err(|e| {
            anyhow::anyhow!("{e}\n(--resume continues a run from {}; there is nothing to resume without it: run without --resume)", cp_path.display())
        })?;
        let saved = cp.scene().map_err(anyhow::Error::msg)?;
        if &saved != scene {
            bail!(
                "the checkpoint {} belongs to scene {:?} with other settings than the scene given; resume with the same scene, or omit the scene and give only --out",
                cp_path.display(),
                saved.name
            );
        }
        Some(cp)
    } else {
        None
    };
    if !(flags.checkpoint_every.is_finite() && flags.checkpoint_every >= 0.0) {
        bail!("--checkpoint-every must be a number of seconds ≥ 0");
    }
    std::fs::create_dir_all(out)
        .with_context(|| format!("creating the output directory {}", out.display()))?;
    install_stop_handler();
    let stop = &STOP;
    eprintln!(
        "grainbench {}: scene {} ({}D, N = {}, {} threads) → {}",
        env!("CARGO_PKG_VERSION"),
        scene.name,
        scene.dimension,
        scene.particles.count,
        rayon::current_num_threads(),
        out.display()
    );
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(1000);
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {prefix} {bar:30} {msg}")
                .expect("valid template"),
        );
        b
    };
    // Without a terminal (CI logs), a plain line every few seconds instead of the bar.
    let plain = !quiet && !std::io::IsTerminal::is_terminal(&std::io::stderr());
    let mut last_line = std::time::Instant::now();
    let mut on_progress = |p: &Progress| {
        let c = &p.checks;
        if plain && last_line.elapsed().as_secs_f64() >= 5.0 {
            last_line = std::time::Instant::now();
            eprintln!(
                "  stage {}/{} {} t={:.4e}/{:.1e} Φ={:.4} {} Ek/grain={:.2e} force/crit={:.2e} stress/crit={:.2e} Ek/crit={:.2e} contacts={}{}",
                p.step_index + 1,
                p.step_count,
                p.step_kind,
                p.time,
                p.max_time,
                c.packing_fraction,
                pressure_text(c),
                c.kinetic_per_grain,
                c.force_ratio,
                c.stress_ratio,
                c.kinetic_ratio,
                c.interactions,
                clusters_text(c)
            );
        }
        bar.set_prefix(format!(
            "stage {}/{} {}",
            p.step_index + 1,
            p.step_count,
            p.step_kind
        ));
        bar.set_position(((p.time / p.max_time).min(1.0) * 1000.0) as u64);
        bar.set_message(format!(
            "t={:.4e} Φ={:.4} {} Ek/grain={:.2e} F/crit={:.2e} contacts={}",
            p.time,
            c.packing_fraction,
            pressure_text(c),
            c.kinetic_per_grain,
            c.force_ratio,
            c.interactions
        ));
    };
    if let Some(cp) = &resume {
        eprintln!(
            "resuming from {} (stage {} of {})",
            cp_path.display(),
            cp.header.stage + 1,
            scene.stages().len()
        );
    }
    let result = grainbench_engine::run_scene(
        scene,
        &mut RunOptions {
            progress: Some(&mut on_progress),
            stop: Some(stop),
            checkpoint: Some(CheckpointSpec {
                path: cp_path.clone(),
                every: flags.checkpoint_every,
            }),
            resume,
        },
    );
    bar.finish_and_clear();
    let outcome = match result {
        Ok(o) => o,
        Err(e @ RunError::Unstable { .. }) => {
            let RunError::Unstable { last_good, .. } = &e else {
                unreachable!()
            };
            let path = out.join("last-good.snap.json");
            last_good.write(&path)?;
            eprintln!("error: {e}");
            eprintln!(
                "the last state that passed the checks is in {}",
                path.display()
            );
            return Ok((4, None));
        }
        Err(e) => return Err(e.into()),
    };
    let snap_path = out.join(&scene.output.snapshot);
    outcome.snapshot.write(&snap_path)?;
    let summary = serde_json::json!({
        "scene": scene.name,
        "seed": scene.seed,
        "settings": scene,
        "engine": env!("CARGO_PKG_VERSION"),
        "dimension": scene.dimension,
        "n": scene.particles.count,
        "law": outcome.law,
        "dt": outcome.dt,
        "k_max": outcome.k_max,
        "threads": rayon::current_num_threads(),
        "wall_seconds": outcome.wall_seconds,
        "neighbor_builds": outcome.neighbor_builds,
        "contacts_at_threshold": outcome.contacts_at_threshold,
        "status": outcome.snapshot.status,
        "steps": outcome.steps,
        "snapshot": snap_path,
    });
    snapshot::write_atomic(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    println!("scene      {} — {}", scene.name, scene.description);
    println!("law        {}", outcome.law);
    println!(
        "time step  dt = {:.4e} ({} of the contact duration at K_max = {:.4e})",
        outcome.dt, scene.numerics.dt_fraction, outcome.k_max
    );
    for s in &outcome.steps {
        let c = &s.checks;
        let head = format!(
            "stage {:<3} {:<16} ended at {:<11} t = {:.4e}",
            s.index + 1,
            s.kind,
            s.end.as_str(),
            s.time
        );
        if s.end == grainbench_engine::run::StepEnd::Done {
            // Hard-grain stages: `steps` counts pair collisions.
            println!(
                "{head} ({} collisions, {:.1} s): Φ = {:.5}",
                s.steps, s.wall_seconds, c.packing_fraction
            );
        } else {
            println!(
                "{head} ({} steps, {:.1} s): Φ = {:.5}, P = {:.6}, force/crit = {:.3}, Ek/crit = {:.3}, stress/crit = {:.3}{}",
                s.steps,
                s.wall_seconds,
                c.packing_fraction,
                c.pressure,
                c.force_ratio,
                c.kinetic_ratio,
                c.stress_ratio,
                clusters_text(c)
            );
        }
    }
    if outcome.contacts_at_threshold > 0 {
        println!(
            "warning    {} contacts sit at their Coulomb or rolling threshold (GRC07 §II.D expects none at equilibrium)",
            outcome.contacts_at_threshold
        );
    }
    if flags.report {
        print!(
            "{}",
            grainbench_comparisons::report::to_markdown(&analysis_of(&outcome.snapshot))
        );
    }
    println!("snapshot   {}", snap_path.display());
    println!("wall time  {:.1} s", outcome.wall_seconds);
    if outcome.snapshot.status == "interrupted" {
        eprintln!(
            "interrupted: the state at the stop is in {}; continue with `grainbench run --resume --out {}`",
            snap_path.display(),
            out.display()
        );
        return Ok((130, Some(outcome)));
    }
    Ok((0, Some(outcome)))
}

/// The cluster count of aggregation stages (empty elsewhere).
fn clusters_text(c: &grainbench_engine::run::Checks) -> String {
    if c.clusters > 0 {
        format!(" clusters={}", c.clusters)
    } else {
        String::new()
    }
}

/// P/P₀ against a positive target, else P itself (fixed cell, or P* = 0).
fn pressure_text(c: &grainbench_engine::run::Checks) -> String {
    if c.pressure_target > 0.0 {
        format!("P/P₀={:.4}", c.pressure / c.pressure_target)
    } else {
        format!("P={:.3e}", c.pressure)
    }
}

/// The scene bare `grainbench` compares across codes.
const DEFAULT_COMPARE: &str = "xcode-smoke";

/// Ctrl-C / SIGTERM: the first stops runs cleanly at their next check (external codes are
/// killed, logs kept); a second one exits at once.
fn install_stop_handler() {
    static HANDLER: std::sync::Once = std::sync::Once::new();
    HANDLER.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            if STOP.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
        });
    });
}

fn analysis_of(snap: &Snapshot) -> grainbench_comparisons::metrics::Analysis {
    grainbench_comparisons::metrics::analyze(snap, &Default::default())
}

fn analyze(path: &Path, json: bool, from: Option<&str>, write: Option<&Path>) -> Result<i32> {
    use grainbench_comparisons::{decks::Code, import};
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
