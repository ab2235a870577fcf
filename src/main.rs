//! `grainbench`: run DEM scenes, analyze packings.

//!
//! Only the command line and its dispatch live here; each command is a module, and the
//! pieces several commands share are in [`common`] (stop flag, threads, scenes, analysis),
//! [`run`] (one run of our engine) and [`external`] (an external code as a child process).

use anyhow::Result;
use clap::{Parser, Subcommand};

mod accuracy;
mod analyze;
mod bench;
mod common;
mod compare;
mod exchange;
mod external;
mod golden;
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
    Run(run::Args),
    /// Packing metrics of a snapshot: Φ, z, z*, x0, force moments, AR07 (22) / GRC07 (18) checks.
    Analyze(analyze::Args),
    /// List the embedded scenes.
    Scenes,
    /// What each stage of a scene will do, in absolute reduced units: cell control, law
    /// numbers, time step, criteria, time limit — the plan our engine runs and every code's
    /// deck and the exchange format carry.
    Plan(plan::Args),
    /// The reference implementation of the exchange format (docs/exchange-format.md): run
    /// `INPUT/exchange.json` with `INPUT/particles.csv` in our engine and write
    /// `OUTPUT/particles.csv`, `contacts.csv` and `status.txt`, as any code in the harness must.
    RunExchange(exchange::Args),
    /// Write LAMMPS, LIGGGHTS and YADE decks and the exchange format (input + data file of the
    /// same initial configuration) of a scene into `reference-inputs/<scene>/<code>/`.
    Decks(xcode::DecksArgs),
    /// Run a scene in our engine and in LAMMPS, LIGGGHTS and YADE from the same start, and
    /// compare every metric with the paper, the golden values and each other (Markdown table,
    /// CSV, JSON, overlaid P(f) and g(r)). Exit status 1 when a check fails. Bare `grainbench`
    /// runs `compare xcode-smoke`.
    Compare(compare::Args),
    /// Speed against error: sweep the time step (dt), the strain-rate cap (inertia), the
    /// equilibrium tolerance and κ one at a time from the scene's settings over several seeds,
    /// and table wall time against the error of Φ, z*, x0 and P(f) (KS distance) relative to
    /// the tightest settings, with the Pareto front (accuracy.md/csv/json, plots). Time steps
    /// past stability are tabled as `unstable: <message>`.
    Accuracy(accuracy::Args),
    /// Golden values: `grainbench golden update SCENE` records the last `compare` run of the
    /// scene as golden/<scene>/<code>.json (only when asked: nothing else writes them).
    Golden(golden::Args),
    /// Print the capability matrix: how each external code expresses each scene feature
    /// (`exact`, `approximate` with the deviation, `unsupported`); with a scene, only its features.
    Capabilities(xcode::CapabilitiesArgs),
    /// Run a paper's state at paper size over several seeds and compare every metric with the
    /// published values (table in Markdown/CSV/JSON, P(f) and g(r) plots). Interrupted runs
    /// continue where they stopped when the same command is given again.
    Reproduce(reproduce::Args),
    /// Time a scene in our engine and in LAMMPS, LIGGGHTS and YADE from the same start, runs
    /// alternated, each code a child process: particle-steps/s, time and steps to equilibrium
    /// (or `--steps S` fixed steps), peak RSS, ratio to ours (bench.md/csv/json). `--scale
    /// N,…` times our engine alone on dense packings of growing size (scale.md/csv/json/svg);
    /// `--memory N,…` measures the peak memory per particle of whole runs (memory.md/json).
    Bench(bench::Args),
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
    let command = match cli.command {
        Some(c) => c,
        None => match Cli::parse_from(["grainbench", "compare", DEFAULT_COMPARE]).command {
            Some(c) => c,
            None => unreachable!("`compare` is a command"),
        },
    };
    match command {
        Command::Run(a) => run::command(a),
        Command::Analyze(a) => analyze::command(a),
        Command::Scenes => common::list_scenes(),
        Command::Plan(a) => plan::command(a),
        Command::RunExchange(a) => exchange::command(a),
        Command::Decks(a) => xcode::decks(a),
        Command::Compare(a) => compare::command(a),
        Command::Accuracy(a) => accuracy::command(a),
        Command::Golden(a) => golden::command(a),
        Command::Capabilities(a) => xcode::capabilities(a),
        Command::Reproduce(a) => reproduce::command(a),
        Command::Bench(a) => bench::command(a),
    }
}

/// The scene bare `grainbench` compares across codes.
const DEFAULT_COMPARE: &str = "xcode-smoke";
