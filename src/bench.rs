//! `grainbench bench SCENE --codes …`: runs the same scene from the same start in each code,
//! alternating the codes run by run, and reports throughput (particle-steps/s), wall time and
//! steps to equilibrium (or for `--steps S` a fixed number of steps), peak resident memory per
//! child process and the ratio to our engine. `--scale N1,N2,…` times our engine alone on
//! dense packings of growing size ([`crate::scale`]).

use crate::compare::{self, Finished};
use crate::STOP;
use anyhow::{bail, Context, Result};
use grainbench_comparisons::crosscode::CodeResult;
use grainbench_comparisons::decks::{lammps_table, Code, Deck, StageKind, Start, Tolerances};
use grainbench_engine::geometry::{D2, D3};
use grainbench_engine::run::initial_grains;
use grainbench_engine::scene::{Criteria, Scene, Step};
use grainbench_engine::snapshot::write_atomic;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::Ordering;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file or embedded scene name (not with --scale).
    pub scene: Option<String>,
    /// Codes, comma-separated (default: rust,lammps,liggghts,yade).
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
pub fn bench(a: &Args) -> Result<i32> {
    if a.threads.is_empty() || a.threads.contains(&0) {
        bail!("--threads: give thread counts ≥ 1, e.g. --threads 1,2");
    }
    if a.child_run {
        return child_run(a);
    }
    if let Some(n) = a.child_scale {
        return crate::scale::child(
            n,
            a.steps.unwrap_or(crate::scale::DEFAULT_STEPS),
            a.threads[0],
        );
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
        return crate::scale::sweep(a);
    }
    let Some(spec) = &a.scene else {
        bail!("give a scene (`grainbench bench xcode-smoke`) or --scale N,…");
    };
    bench_scene(a, spec)
}

/// The rust child: `run` without the metrics report or periodic checkpoints; a plain progress
/// line every 5 s on stderr (its log).
fn child_run(a: &Args) -> Result<i32> {
    let (Some(scene), Some(out)) = (&a.scene, &a.out) else {
        bail!("--child-run needs a scene file and --out");
    };
    crate::set_threads(Some(a.threads[0]))?;
    let scene = crate::load_scene(scene)?;
    let flags = crate::RunFlags {
        quiet: false,
        report: false,
        resume: false,
        checkpoint_every: 1e12,
    };
    Ok(crate::run(&scene, out, &flags)?.0)
}

/// How the runs stop.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "mode")]
pub enum Mode {
    /// The full protocol with its equilibrium criteria.
    Equilibrium,
    /// `steps` MD steps of the first DEM stage, criteria off.
    Steps { steps: u64 },
}

impl Mode {
    fn describe(&self) -> String {
        match self {
            Mode::Equilibrium => "to equilibrium (full protocol, equilibrium criteria)".into(),
            Mode::Steps { steps } => format!(
                "fixed steps: {steps} MD steps of the first DEM stage, criteria evaluated but never met"
            ),
        }
    }
}

/// The scene cut to its hard-grain prelude and first DEM stage, run for exactly `steps` steps
/// (criteria that never hold, still evaluated every check period), and its common start.
/// `steps` is rounded up to a multiple of the check period (LIGGGHTS and our engine run whole
/// check periods).
pub fn fixed_steps(scene: &Scene, steps: u64) -> Result<(Scene, Start, u64)> {
    let stages = scene.stages();
    let Some(k) = stages.iter().position(|(_, s)| s.is_dem()) else {
        bail!(
            "scene {}: --steps needs a DEM stage (compress, fixed-volume, …) in [[protocol]]",
            scene.name
        );
    };
    let every = scene.numerics.check_every.max(1);
    let steps = steps.div_ceil(every) * every;
    // Never met: positive (the scene validator wants that) and far below any measure.
    let never = Criteria {
        force: 1e-200,
        moment: 1e-200,
        pressure: 1e-200,
        kinetic: 1e-200,
        ..stages[k].1.criteria()
    };
    let mut stage = stages[k].1.clone();
    match &mut stage {
        // Throughput of the paper's law: no damped final phase either.
        Step::Compress {
            criteria, relax, ..
        } => {
            *criteria = never.clone();
            *relax = None;
        }
        Step::FixedVolume {
            criteria,
            full_time,
            relax,
            ..
        } => {
            *criteria = never.clone();
            *full_time = true;
            *relax = None;
        }
        // A fixed cell for S steps: no cluster count to stop on.
        Step::Aggregate {
            max_time,
            mu,
            kappa,
        } => {
            stage = Step::FixedVolume {
                max_time: *max_time,
                criteria: never.clone(),
                full_time: true,
                mu: *mu,
                kappa: *kappa,
                relax: None,
            }
        }
        other => unreachable!("stages() unrolls {}", other.kind()),
    }
    let mut cut = scene.clone();
    cut.protocol = stages[..k].iter().map(|(_, s)| s.clone()).collect();
    cut.protocol.push(stage);
    let mut start = Start::of(&cut).map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
    let dt = start.stages[0].dt;
    // Half a step below S·dt: the time after S steps passes it whatever the rounding.
    let max_time = (steps as f64 - 0.5) * dt;
    match cut.protocol.last_mut() {
        Some(Step::Compress { max_time: t, .. } | Step::FixedVolume { max_time: t, .. }) => {
            *t = max_time
        }
        _ => unreachable!(),
    }
    let st = &mut start.stages[0];
    st.max_time = max_time;
    st.max_steps = steps;
    let pressure = match st.kind {
        StageKind::Compress { pressure } => Some(pressure),
        _ => None,
    };
    st.tolerances = Tolerances::of(&never, pressure);
    if let StageKind::FixedVolume { full_time } = &mut st.kind {
        *full_time = true;
    }
    start.scene = cut.clone();
    Ok((cut, start, steps))
}

/// The scene started from the grains of `snap` (at rest) without its hard-grain prelude.
pub fn from_snapshot(scene: &Scene, snap: &Path) -> Result<Scene> {
    if !snap.is_file() {
        bail!(
            "--start {}: no such snapshot file (give a final.snap.json written by `grainbench run` or `analyze --write`)",
            snap.display()
        );
    }
    let mut s = scene.clone();
    s.initial.snapshot = Some(std::path::absolute(snap)?);
    s.protocol = scene
        .stages()
        .into_iter()
        .map(|(_, st)| st)
        .skip_while(|st| !st.is_dem())
        .collect();
    if s.protocol.is_empty() {
        bail!(
            "scene {}: --start needs a DEM stage in [[protocol]]",
            scene.name
        );
    }
    // Read it now: a wrong file or grain count is an error before any run.
    let read = match s.dimension {
        2 => initial_grains::<D2>(&s).map(|_| ()),
        _ => initial_grains::<D3>(&s).map(|_| ()),
    };
    read.map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
    Ok(s)
}

/// One run of one code.
#[derive(Clone, Debug, Serialize)]
pub struct Run {
    /// Position in the run order (1-based).
    pub order: usize,
    pub code: String,
    pub threads: usize,
    /// Repeat index (1-based).
    pub repeat: usize,
    /// `ran`, `failed`, `timeout`, `interrupted`.
    pub outcome: String,
    /// Final status (`equilibrium`, `time-limit`).
    pub status: Option<String>,
    pub message: Option<String>,
    /// MD steps of the DEM stages.
    pub steps: Option<u64>,
    /// Wall time of the child process (rust: less its hard-grain prelude, which the external
    /// decks receive done in their data file).
    pub wall_seconds: Option<f64>,
    /// Rust only: wall time of the whole child process, prelude included.
    pub process_seconds: Option<f64>,
    /// Time-stepping loop as the code logs it (LAMMPS/LIGGGHTS `Loop time`, YADE's script
    /// timer, our DEM stages).
    pub loop_seconds: Option<f64>,
    pub particle_steps_per_second: Option<f64>,
    pub loop_particle_steps_per_second: Option<f64>,
    /// max(`wait4` ru_maxrss, sampled sum over the process group), KiB.
    pub peak_rss_kib: Option<u64>,
    pub dir: PathBuf,
}

/// Median, min and max of a quantity over the repeats.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Stat {
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Stat {
    pub fn of(values: &[f64]) -> Option<Stat> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let m = v.len();
        let median = if m % 2 == 1 {
            v[m / 2]
        } else {
            0.5 * (v[m / 2 - 1] + v[m / 2])
        };
        Some(Stat {
            median,
            min: v[0],
            max: v[m - 1],
        })
    }
    fn text(s: Option<Stat>, fmt: impl Fn(f64) -> String) -> String {
        match s {
            None => "—".into(),
            Some(s) if s.min == s.max => fmt(s.median),
            Some(s) => format!("{} [{}–{}]", fmt(s.median), fmt(s.min), fmt(s.max)),
        }
    }
}

/// One row of the table: a code at a thread count.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub code: String,
    pub threads: usize,
    /// Runs that ended normally / runs made.
    pub ran: usize,
    pub runs: usize,
    /// `ran`, or why it did not run (`missing`, `refused`, …) with the message.
    pub outcome: String,
    pub message: Option<String>,
    pub version: Option<String>,
    pub deviations: Vec<String>,
    /// Final statuses seen (`equilibrium`, `time-limit`).
    pub statuses: Vec<String>,
    pub steps: Option<Stat>,
    pub wall_seconds: Option<Stat>,
    pub loop_seconds: Option<Stat>,
    pub particle_steps_per_second: Option<Stat>,
    pub loop_particle_steps_per_second: Option<Stat>,
    pub peak_rss_mib: Option<Stat>,
    /// Rate over our engine's rate in the same repeat and thread count (> 1: faster).
    pub rate_ratio: Option<Stat>,
    /// Wall time over our engine's in the same repeat and thread count.
    pub wall_ratio: Option<Stat>,
}

/// bench.json.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub scene: String,
    pub n: usize,
    pub mode: Mode,
    pub repeat: usize,
    pub threads: Vec<usize>,
    pub command: String,
    pub notes: Vec<String>,
    /// `code/-jT/#k` in the order run.
    pub run_order: Vec<String>,
    pub rows: Vec<Row>,
    pub runs: Vec<Run>,
}

/// A code, its column of results, and its binary and deck (external codes that can run).
type Setup = (Code, CodeResult, Option<(PathBuf, Deck)>);

fn bench_scene(a: &Args, spec: &str) -> Result<i32> {
    let mut scene = crate::load_scene(spec)?;
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
    crate::install_stop_handler();
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
    // Decks and binaries once; codes that cannot run are rows without runs.
    let mut setups: Vec<Setup> = Vec::new();
    for &code in &codes {
        let mut r = CodeResult::new(code.name(), "ran");
        let ready = match (code, &start) {
            (Code::Rust, _) => {
                r.version = Some(format!("grainbench {}", env!("CARGO_PKG_VERSION")));
                None
            }
            (_, Some(st)) => compare::prepare_external(st, code, &mut r),
            (_, None) => unreachable!("a start is made when external codes run"),
        };
        let ready = match (ready, code, mode, &start) {
            // Adhesion: the bench-only LAMMPS deck (throughput only).
            (None, Code::Lammps, Mode::Steps { .. }, Some(st))
                if r.outcome == "refused" && st.cohesive() =>
            {
                match (
                    Code::Lammps.find(),
                    lammps_table::deck(st, lammps_table::CLASSES),
                ) {
                    (Some(bin), Ok(deck)) => {
                        r.outcome = "ran".into();
                        r.message = None;
                        r.deviations = deck.deviations.clone();
                        eprintln!(
                            "lammps    bench-only deck: diameters in {} size classes, GRC07 attraction by pair_style table (approximate, throughput only)",
                            lammps_table::CLASSES
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
            && grainbench_comparisons::decks::which("mpirun").is_none()
            && ready.is_some()
        {
            r.outcome = "missing".into();
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
                    code: code.name().into(),
                    threads: t,
                    repeat: rep,
                    outcome: "ran".into(),
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
    let rows = rows_of(&setups, &a.threads, &runs);
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
    eprintln!("wrote {0}/bench.md, bench.csv, bench.json", out.display());
    Ok(if STOP.load(Ordering::SeqCst) { 130 } else { 0 })
}

fn notes(mode: &Mode, start: Option<&Path>) -> Vec<String> {
    let mut v = vec![
        format!("mode: {}", mode.describe()),
        "particle-steps/s = N × steps / wall; wall is the child process's, so it includes start-up, reading the start and writing the final state; `loop` is the time-stepping loop as each code logs it (LAMMPS/LIGGGHTS `Loop time`, YADE's script timer, our DEM stages)".into(),
        "rust: its wall time leaves out the hard-grain prelude (event-driven melting) it runs itself, which the external decks receive done in their data file".into(),
        "codes run alternately (A B C A B C …) so that drift of the machine hits all alike; ratios pair each run with our engine's run of the same repeat and thread count (rate/rust > 1: faster than ours)".into(),
        "peak RSS: max of wait4 ru_maxrss of the child (its own, or its largest descendant, e.g. one MPI rank) and the sum over its process group sampled every 0.25 s".into(),
        "threads: rust -j T; LAMMPS/LIGGGHTS run directly for T = 1, under mpirun -np T otherwise; YADE -j T".into(),
    ];
    if let Some(snap) = start {
        v.push(format!(
            "start: the grains of {} at rest, in every code (hard-grain prelude skipped)",
            snap.display()
        ));
    }
    if let Mode::Steps { .. } = mode {
        v.push("fixed steps: the run is the scene's first DEM stage only, with equilibrium criteria set to 1e-200 so that no code stops early; the checks still run every check period, as in a real run".into());
        if start.is_none() {
            v.push("fixed steps start from the scene's start, often a gas: the rates are those of that state, not of a dense packing (`--start SNAP`, the equilibrium mode and `--scale` time dense ones)".into());
        }
    }
    v
}

fn run_line(r: &Run) -> String {
    let mut s = format!("{} -j{} #{}: {}", r.code, r.threads, r.repeat, r.outcome);
    if let Some(st) = &r.status {
        s += &format!(" ({st})");
    }
    if let (Some(w), Some(steps)) = (r.wall_seconds, r.steps) {
        s += &format!(", {steps} steps in {w:.2} s");
    }
    if let Some(p) = r.particle_steps_per_second {
        s += &format!(", {:.3e} particle-steps/s", p);
    }
    if let Some(m) = r.peak_rss_kib {
        s += &format!(", peak RSS {:.1} MiB", m as f64 / 1024.0);
    }
    if let Some(m) = &r.message {
        s += &format!(": {m}");
    }
    s
}

fn peak(done: &Finished) -> u64 {
    done.max_rss_kib.max(done.group_rss_kib)
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
    let done = compare::supervise(
        &mut cmd,
        dir,
        "rust",
        a.time_limit,
        a.quiet,
        Some("stderr.log"),
    )?;
    run.peak_rss_kib = Some(peak(&done));
    run.process_seconds = Some(done.wall_seconds);
    match done.status {
        None => {
            run.outcome = if STOP.load(Ordering::SeqCst) {
                "interrupted"
            } else {
                "timeout"
            }
            .into();
            run.message = Some(format!(
                "stopped at the time limit of {} s (--time-limit); logs in {}",
                a.time_limit,
                dir.display()
            ));
            return Ok(());
        }
        Some(s) if !s.success() => {
            run.outcome = "failed".into();
            run.message = Some(format!(
                "exited with {s}: {:?}; logs in {}",
                compare::failure_line(&dir.join("stderr.log")),
                dir.display()
            ));
            return Ok(());
        }
        Some(_) => {}
    }
    let path = dir.join("summary.json");
    let summary: serde_json::Value = serde_json::from_slice(
        &std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?,
    )
    .with_context(|| format!("parsing {}", path.display()))?;
    let (mut steps, mut loop_s, mut prelude) = (0u64, 0.0, 0.0);
    for s in summary["steps"].as_array().into_iter().flatten() {
        let wall = s["wall_seconds"].as_f64().unwrap_or(0.0);
        if s["end"] == "done" {
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
    compare::write_fresh_deck(deck, dir)?;
    let np = (threads > 1).then_some(threads);
    let mut cmd = compare::external_command(code, binary, deck, np, Some(threads))?;
    let done = compare::supervise(
        &mut cmd,
        dir,
        code.name(),
        a.time_limit,
        a.quiet,
        Some("stdout.log"),
    )?;
    run.peak_rss_kib = Some(peak(&done));
    run.wall_seconds = Some(done.wall_seconds);
    let throughput_only = deck.files.iter().any(|(n, _)| n == lammps_table::TABLE);
    if throughput_only && done.status.is_some_and(|s| s.success()) {
        // No final state to read back: steps and status from the log.
        if r.version.is_none() {
            r.version = compare::version_line(code, &dir.join("stdout.log"));
        }
        run.status = Some(grainbench_comparisons::import::read_status(
            &dir.join("final.status"),
        ));
        run.steps = log_steps(dir);
        run.loop_seconds = loop_time(code, dir);
        if run.steps.is_none() {
            run.outcome = "failed".into();
            run.message = Some(format!(
                "no `Loop time` line in {}/stdout.log",
                dir.display()
            ));
            run.wall_seconds = None;
        }
        return Ok(());
    }
    let mut res = CodeResult::new(code.name(), "ran");
    let snap = compare::finish_external(code, dir, &done, a.time_limit, &mut res)?;
    if r.version.is_none() {
        r.version = res.version.clone();
    }
    run.outcome = res.outcome;
    run.message = res.message;
    if let Some(snap) = snap {
        run.status = Some(snap.status.clone());
        run.steps = Some(snap.step);
        run.loop_seconds = loop_time(code, dir);
    } else {
        run.wall_seconds = None;
    }
    Ok(())
}

/// Steps of a LAMMPS/LIGGGHTS run: the sum of its `Loop time of … for S steps` lines.
fn log_steps(dir: &Path) -> Option<u64> {
    let text = std::fs::read_to_string(dir.join("stdout.log")).ok()?;
    let steps: Vec<u64> = text
        .lines()
        .filter(|l| l.starts_with("Loop time of "))
        .filter_map(|l| {
            l.split(" for ")
                .nth(1)?
                .split_whitespace()
                .next()?
                .parse()
                .ok()
        })
        .collect();
    (!steps.is_empty()).then(|| steps.iter().sum())
}

/// Time-stepping loop time from a code's log: the sum of LAMMPS/LIGGGHTS `Loop time of X on
/// P procs for S steps` lines, or YADE's `done: … after S steps, T s`.
pub fn loop_time(code: Code, dir: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(dir.join("stdout.log")).ok()?;
    match code {
        Code::Lammps | Code::Liggghts => {
            let times: Vec<f64> = text
                .lines()
                .filter_map(|l| l.strip_prefix("Loop time of "))
                .filter_map(|l| l.split_whitespace().next()?.parse().ok())
                .collect();
            (!times.is_empty()).then(|| times.iter().sum())
        }
        Code::Yade => text
            .lines()
            .rev()
            .find_map(|l| l.strip_prefix("done: "))
            .and_then(|l| l.rsplit(", ").next())
            .and_then(|t| t.trim().trim_end_matches('s').trim().parse().ok())
            // Printed to 0.1 s: shorter loops are unknown.
            .filter(|&t: &f64| t >= 0.1),
        Code::Rust => None,
    }
}

fn rows_of(setups: &[Setup], threads: &[usize], runs: &[Run]) -> Vec<Row> {
    let mut rows = Vec::new();
    for (code, r, _) in setups {
        for &t in threads {
            let mine: Vec<&Run> = runs
                .iter()
                .filter(|x| x.code == code.name() && x.threads == t)
                .collect();
            let ok: Vec<&Run> = mine
                .iter()
                .copied()
                .filter(|x| x.outcome == "ran")
                .collect();
            let stat = |f: &dyn Fn(&Run) -> Option<f64>| {
                Stat::of(&ok.iter().filter_map(|x| f(x)).collect::<Vec<_>>())
            };
            let ratio = |f: &dyn Fn(&Run) -> Option<f64>| {
                let v: Vec<f64> = ok
                    .iter()
                    .filter_map(|x| {
                        let ours = runs.iter().find(|y| {
                            y.code == "rust"
                                && y.threads == t
                                && y.repeat == x.repeat
                                && y.outcome == "ran"
                        })?;
                        Some(f(x)? / f(ours)?)
                    })
                    .collect();
                Stat::of(&v)
            };
            let mut statuses: Vec<String> = ok.iter().filter_map(|x| x.status.clone()).collect();
            statuses.sort();
            statuses.dedup();
            let (outcome, message) = if mine.is_empty() {
                (r.outcome.clone(), r.message.clone())
            } else if ok.len() == mine.len() {
                ("ran".to_string(), None)
            } else {
                let bad = mine
                    .iter()
                    .find(|x| x.outcome != "ran")
                    .expect("some failed");
                (bad.outcome.clone(), bad.message.clone())
            };
            rows.push(Row {
                code: code.name().into(),
                threads: t,
                ran: ok.len(),
                runs: mine.len(),
                outcome,
                message,
                version: r.version.clone(),
                deviations: r.deviations.clone(),
                statuses,
                steps: stat(&|x| x.steps.map(|s| s as f64)),
                wall_seconds: stat(&|x| x.wall_seconds),
                loop_seconds: stat(&|x| x.loop_seconds),
                particle_steps_per_second: stat(&|x| x.particle_steps_per_second),
                loop_particle_steps_per_second: stat(&|x| x.loop_particle_steps_per_second),
                peak_rss_mib: stat(&|x| x.peak_rss_kib.map(|k| k as f64 / 1024.0)),
                rate_ratio: ratio(&|x| x.particle_steps_per_second),
                wall_ratio: ratio(&|x| x.wall_seconds),
            });
        }
    }
    rows
}

fn sig(x: f64) -> String {
    format!("{x:.3e}")
}

fn fixed(d: usize) -> impl Fn(f64) -> String {
    move |x| format!("{x:.d$}")
}

/// The Markdown table with its notes.
pub fn to_markdown(r: &Report) -> String {
    let mut s = format!(
        "## grainbench bench: {} (N = {}), {}\n\n",
        r.scene,
        r.n,
        r.mode.describe()
    );
    s += &format!(
        "Medians over {} repeat(s), [min–max] where they differ.\n\n",
        r.repeat
    );
    s += "| code | threads | runs | status | steps | wall s | loop s | particle-steps/s (wall) | particle-steps/s (loop) | peak RSS MiB | rate / rust | wall / rust |\n";
    s += "| --- | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
    for row in &r.rows {
        let status = if row.outcome == "ran" {
            row.statuses.join(", ")
        } else {
            row.outcome.clone()
        };
        s += &format!(
            "| {} | {} | {}/{} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            row.code,
            row.threads,
            row.ran,
            row.runs,
            status,
            Stat::text(row.steps, fixed(0)),
            Stat::text(row.wall_seconds, fixed(2)),
            Stat::text(row.loop_seconds, fixed(2)),
            Stat::text(row.particle_steps_per_second, sig),
            Stat::text(row.loop_particle_steps_per_second, sig),
            Stat::text(row.peak_rss_mib, fixed(1)),
            Stat::text(row.rate_ratio, fixed(3)),
            Stat::text(row.wall_ratio, fixed(3)),
        );
    }
    s += "\n";
    for row in r.rows.iter().filter(|x| x.outcome != "ran") {
        if let Some(m) = &row.message {
            s += &format!("- {} -j{}: {}: {m}\n", row.code, row.threads, row.outcome);
        }
    }
    let mut seen = Vec::new();
    for row in &r.rows {
        if let Some(v) = &row.version {
            if !seen.contains(&row.code) {
                seen.push(row.code.clone());
                s += &format!("- {}: {v}", row.code);
                if !row.deviations.is_empty() {
                    // The feature keys; bench.json has the deviations in full.
                    let keys: Vec<&str> = row
                        .deviations
                        .iter()
                        .map(|d| d.split(':').next().unwrap_or(d))
                        .collect();
                    s += &format!(" (approximate: {})", keys.join(", "));
                }
                s += "\n";
            }
        }
    }
    for n in &r.notes {
        s += &format!("- {n}\n");
    }
    s += &format!("- run order: {}\n", r.run_order.join(" "));
    s
}

/// bench.csv: one line per code and thread count, median/min/max columns.
pub fn to_csv(r: &Report) -> String {
    let quantities = [
        "steps",
        "wall_seconds",
        "loop_seconds",
        "particle_steps_per_second",
        "loop_particle_steps_per_second",
        "peak_rss_mib",
        "rate_ratio",
        "wall_ratio",
    ];
    let mut s = String::from("scene,n,mode,code,threads,runs,ran,outcome,status");
    for q in quantities {
        s += &format!(",{q}_median,{q}_min,{q}_max");
    }
    s += "\n";
    let mode = match r.mode {
        Mode::Equilibrium => "equilibrium".to_string(),
        Mode::Steps { steps } => format!("steps={steps}"),
    };
    for row in &r.rows {
        s += &format!(
            "{},{},{mode},{},{},{},{},{},{}",
            r.scene,
            r.n,
            row.code,
            row.threads,
            row.runs,
            row.ran,
            row.outcome,
            row.statuses.join(";")
        );
        for st in [
            row.steps,
            row.wall_seconds,
            row.loop_seconds,
            row.particle_steps_per_second,
            row.loop_particle_steps_per_second,
            row.peak_rss_mib,
            row.rate_ratio,
            row.wall_ratio,
        ] {
            match st {
                Some(x) => s += &format!(",{},{},{}", x.median, x.min, x.max),
                None => s += ",,,",
            }
        }
        s += "\n";
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_min_max() {
        let s = Stat::of(&[3.0, 1.0, 2.0, f64::NAN]).unwrap();
        assert_eq!((s.median, s.min, s.max), (2.0, 1.0, 3.0));
        assert_eq!(Stat::of(&[1.0, 2.0]).unwrap().median, 1.5);
        assert!(Stat::of(&[]).is_none());
    }

    #[test]
    fn loop_times_from_logs() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("stdout.log"),
            "Loop time of 1.5 on 1 procs for 200 steps with 256 atoms\n\nLoop time of 0.25 on 1 procs for 0 steps with 256 atoms\n",
        )
        .unwrap();
        assert_eq!(loop_time(Code::Lammps, dir.path()), Some(1.75));
        std::fs::write(
            dir.path().join("stdout.log"),
            "stage 0 …\ndone: time-limit after 400 steps, 3.2 s\n",
        )
        .unwrap();
        assert_eq!(loop_time(Code::Yade, dir.path()), Some(3.2));
    }

    #[test]
    fn fixed_steps_cuts_to_the_first_dem_stage_and_rounds_up() {
        let scene = crate::load_scene("xcode-smoke").unwrap();
        let (cut, start, steps) = fixed_steps(&scene, 250).unwrap();
        assert_eq!(steps, 400);
        assert_eq!(start.stages.len(), 1);
        assert_eq!(start.stages[0].max_steps, 400);
        assert_eq!(cut.protocol.len(), 2);
        let text = toml::to_string(&cut).unwrap();
        let back = Scene::from_toml(&text, Path::new("x.toml")).unwrap();
        assert_eq!(back, cut);
    }
}
