//! `grainbench`: run DEM scenes, analyze packings.

//!
//! Only the command line and its dispatch live here; each command is a module, and the
//! pieces several commands share are in [`common`] (stop flag, threads, scenes, analysis),
//! [`run`] (one run of our engine) and [`external`] (an external code as a child process).

use anyhow::Result;
use clap::{Parser, Subcommand};
use common::{install_stop_handler, on_threads};
use run::RunFlags;
use std::path::PathBuf;

mod accuracy;
mod analyze;
mod bench;
mod common;
mod compare;
mod consolidation;
mod exchange;
mod external;
mod plan;
mod reproduce;
mod run;
mod trace;
mod xcode;

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
        /// Start over even if the output directory holds the checkpoint of an unfinished run
        /// (which is then deleted); without it such a run is refused.
        #[arg(long, conflicts_with = "resume")]
        force: bool,
        /// Seconds of wall time between checkpoints (`<out>/checkpoint.bin`); 0 = at every
        /// check. The checkpoint is removed when the run completes.
        #[arg(long, default_value_t = 60.0, value_name = "SECS")]
        checkpoint_every: f64,
        /// Seed of the initial state instead of the scene's.
        #[arg(long)]
        seed: Option<u64>,
        /// Write a ParaView frame (grains and contacts, `.vtu`) every T of simulated time (the
        /// first check at or after each multiple of T) into `<out>/vtk/`, listed in
        /// `<out>/vtk/run.pvd`; a resumed run extends the series.
        #[arg(long, value_name = "T")]
        dump_every: Option<f64>,
        /// Few-body runs (≤ 1000 grains): record every grain and contact at the first check
        /// at or after each multiple of T into `<out>/trace-grains.csv` and
        /// `trace-contacts.csv`; with two grains also their impact (`impact.json`: duration,
        /// peak force, restitution, angles, spins, with Hertz's values). Set the scene's
        /// `numerics.check_every = 1` for a frame every step.
        #[arg(long, value_name = "T")]
        trace_every: Option<f64>,
        /// Write the state at the end of each stage into `<out>/stages/stage-KKK.snap.json`
        /// (K as in the progress line, from 0): the points of a pressure program.
        #[arg(long)]
        stage_snapshots: bool,
    },
    /// Packing metrics of a snapshot: Φ, z, z*, x0, force moments, AR07 (22) / GRC07 (18) checks.
    Analyze {
        /// A grainbench snapshot, or with --from a directory of another code's final dumps.
        snapshot: PathBuf,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Read the final state of another code from a directory: `lammps` (dump custom +
        /// dump local), `liggghts` (dump custom + pair/gran/local), `yade` (text export); formats
        /// in docs/external-formats/. Our decks write a `deck.json` beside them; for dumps of
        /// your own deck give --dimension, --mu, --pressure and --force-unit.
        #[arg(long, value_name = "CODE")]
        from: Option<String>,
        /// With --from: 2 or 3 (overrides deck.json).
        #[arg(long)]
        dimension: Option<usize>,
        /// With --from: μ of the last stage, a number or `inf` (overrides deck.json).
        #[arg(long, value_name = "MU")]
        mu: Option<String>,
        /// With --from: target pressure of the last stage, or `none` for a fixed cell (overrides
        /// deck.json).
        #[arg(long, value_name = "P")]
        pressure: Option<String>,
        /// With --from: the force unit of the dumps, e.g. "P_ref a^2" or F0 (overrides deck.json).
        #[arg(long, value_name = "TEXT")]
        force_unit: Option<String>,
        /// With --from: an adhesive law (pairs within the attraction range are dumped).
        #[arg(long)]
        cohesive: bool,
        /// Also write the state read as a grainbench snapshot.
        #[arg(long, value_name = "FILE")]
        write: Option<PathBuf>,
        /// Also the elastic moduli B, G with their Voigt and Reuss estimates, the energy
        /// concentration of a pressure increment (GRC08 §VI) and the mechanisms and force
        /// indeterminacy of the network (GRC07 App. A), from its stiffness matrix.
        #[arg(long)]
        moduli: bool,
        /// With --moduli: the scene (file or embedded name) whose law gives the contact
        /// stiffnesses (default: the scene the snapshot names).
        #[arg(long, value_name = "SCENE")]
        scene: Option<String>,
        /// Also write the snapshot for ParaView into DIR: particles.vtu (grains with diameter,
        /// velocity, spin, contact count), contacts.vtu (lines with normal and tangential
        /// force) and snapshot.pvd grouping them.
        #[arg(long, value_name = "DIR")]
        vtk: Option<PathBuf>,
        /// Cohesive snapshots: the normal force, in F0, at or below which an interaction counts
        /// as unstressed in GRC07 T.VI's split z = z+ + z− + z0 (default 1e-4, T.VI's
        /// tolerance; GRC07 §IV.C separates loops with RR at 1e-2).
        #[arg(long, value_name = "F")]
        cohesive_tolerance: Option<f64>,
    },
    /// List the embedded scenes.
    Scenes,
    /// What each stage of a scene will do, in absolute reduced units: cell control, law
    /// numbers, time step, criteria, time limit — the plan our engine runs and every code's
    /// deck and the exchange format carry.
    Plan {
        /// Scene file or embedded scene name.
        scene: String,
        /// The plan as JSON.
        #[arg(long)]
        json: bool,
    },
    /// The reference implementation of the exchange format (docs/exchange-format.md): run
    /// `INPUT/exchange.json` with `INPUT/particles.csv` in our engine and write
    /// `OUTPUT/particles.csv`, `contacts.csv` and `status.txt`, as any code in the harness must.
    RunExchange {
        /// Directory holding exchange.json and particles.csv (`grainbench decks SCENE --codes generic`).
        input: PathBuf,
        /// Where the final state goes.
        output: PathBuf,
        /// Threads.
        #[arg(long, short = 'j')]
        threads: Option<usize>,
        #[arg(long, short)]
        quiet: bool,
    },
    /// Write LAMMPS, LIGGGHTS and YADE decks and the exchange format (input + data file of the
    /// same initial configuration) of a scene into `reference-inputs/<scene>/<code>/`.
    Decks {
        /// Scene files or embedded scene names.
        scenes: Vec<String>,
        /// Every embedded scene.
        #[arg(long)]
        all: bool,
        /// Codes, comma-separated: lammps (Debian's 2021), lammps-2025, liggghts, yade, and
        /// `generic`, the neutral exchange format (docs/exchange-format.md) (default: all five).
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
        /// Codes, comma-separated: rust, lammps (Debian's 2021), lammps-2025, liggghts, yade
        /// (default: all), and NAME=PATH.toml for any code with an adapter file
        /// (docs/exchange-format.md).
        #[arg(long, value_delimiter = ',')]
        codes: Vec<String>,
        /// Seeds, comma-separated (default: the scene's). With several, each seed is compared
        /// in `seed-K/` and `compare-seeds.md` gives every code's mean ± s.d., with P(f) per
        /// code over its seeds' band.
        #[arg(long, value_delimiter = ',')]
        seeds: Vec<u64>,
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
    Capabilities {
        scene: Option<String>,
        /// Columns, comma-separated (default: lammps, lammps-2025, liggghts, yade); NAME=PATH.toml
        /// adds a code with an adapter file.
        #[arg(long, value_delimiter = ',')]
        codes: Vec<String>,
    },
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
    /// N,…` times our engine alone on dense packings of growing size (scale.md/csv/json/svg);
    /// `--memory N,…` measures the peak memory per particle of whole runs (memory.md/json).
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
    large_blocks_mapped();
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

/// glibc's allocator: every block of 128 KiB or more (the per-grain and per-pair arrays of
/// any sizeable packing) in a mapping of its own, unmapped when freed and grown by `mremap`.
/// By default glibc raises that threshold after the first large block is freed and then
/// carves large arrays from the heap, which keeps what the preparation, the checks and the
/// output freed resident for the rest of the run, raising the peak memory per particle
/// (docs/performance.md).
fn large_blocks_mapped() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets an allocator parameter; called before any thread starts.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 128 * 1024);
    }
}

fn dispatch(cli: Cli) -> Result<i32> {
    match cli.command.unwrap_or(Command::Compare {
        scene: DEFAULT_COMPARE.into(),
        codes: Vec::new(),
        seeds: Vec::new(),
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
            seeds,
            out,
            time_limit,
            np,
            threads,
            all_metrics,
            quiet,
        } => {
            install_stop_handler();
            on_threads(threads, || {
                compare::compare(&compare::Args {
                    scene,
                    codes,
                    seeds,
                    out,
                    time_limit,
                    np,
                    quiet,
                    all_metrics,
                })
            })
        }
        Command::Accuracy(args) => on_threads(args.threads, || accuracy::accuracy(&args)),
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
            force,
            checkpoint_every,
            seed,
            dump_every,
            trace_every,
            stage_snapshots,
        } => on_threads(threads, || {
            if let Some(t) = trace_every {
                if !(t.is_finite() && t > 0.0) {
                    anyhow::bail!(
                        "--trace-every {t}: give a positive time in the scene's reduced units"
                    );
                }
            }
            if let Some(t) = dump_every {
                if !(t.is_finite() && t > 0.0) {
                    anyhow::bail!(
                        "--dump-every {t}: give a positive time in the scene's reduced units"
                    );
                }
            }
            let flags = RunFlags {
                quiet,
                report: true,
                resume,
                force,
                checkpoint_every,
                dump_every,
                trace_every,
                stage_snapshots,
            };
            run::run_command(scene.as_deref(), out, seed, require_equilibrium, &flags)
        }),
        Command::Analyze {
            snapshot,
            json,
            from,
            dimension,
            mu,
            pressure,
            force_unit,
            cohesive,
            write,
            moduli,
            scene,
            vtk,
            cohesive_tolerance,
        } => analyze::analyze(
            &snapshot,
            json,
            from.as_deref(),
            &analyze::DumpMeta {
                dimension,
                mu,
                pressure,
                force_unit,
                cohesive,
            },
            write.as_deref(),
            &analyze::Extra {
                moduli,
                scene: scene.as_deref(),
                vtk: vtk.as_deref(),
                cohesive_tolerance,
            },
        ),
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
        } => on_threads(threads, || {
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
                    force: false,
                    checkpoint_every,
                    dump_every: None,
                    trace_every: None,
                    stage_snapshots: false,
                },
            })
        }),
        Command::Decks {
            scenes,
            all,
            codes,
            out,
        } => xcode::decks_command(&scenes, all, &codes, out),
        Command::Capabilities { scene, codes } => {
            xcode::capabilities_command(scene.as_deref(), &codes)
        }
        Command::Bench(args) => bench::bench(&args),
        Command::Scenes => common::list_scenes(),
        Command::Plan { scene, json } => plan::plan_command(&scene, json),
        Command::RunExchange {
            input,
            output,
            threads,
            quiet,
        } => on_threads(threads, || exchange::run_exchange(&input, &output, quiet)),
    }
}

/// The scene bare `grainbench` compares across codes.
const DEFAULT_COMPARE: &str = "xcode-smoke";
