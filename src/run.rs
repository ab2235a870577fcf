//! `grainbench run`: one scene into an output directory (snapshot, summary, checkpoints),
//! with a progress bar and the metrics table of the final state.

use crate::common::{analysis_of, install_stop_handler, load_scene, on_threads, STOP};
use anyhow::{bail, Context, Result};
use grainbench_comparisons::report::vtk;
use grainbench_engine::checkpoint::Checkpoint;
use grainbench_engine::run::layout::{stage_file, CHECKPOINT, LAST_GOOD, LOCK, STAGES, SUMMARY};
use grainbench_engine::run::{
    CheckpointSpec, Checks, DumpSpec, Outcome, Progress, RunError, RunOptions, StageEndHook,
    StepEnd, StepReport,
};
use grainbench_engine::scene::MAX_TRACE_GRAINS;
use grainbench_engine::{snapshot, Scene};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

/// The arguments of `grainbench run`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file or embedded scene name.
    pub scene: Option<String>,
    /// Output directory (default: `runs/<scene name>`).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long, short = 'j')]
    pub threads: Option<usize>,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
    /// Exit with status 3 unless every protocol step ends at equilibrium.
    #[arg(long)]
    pub require_equilibrium: bool,
    /// Continue the interrupted run whose checkpoint is in the output directory; the
    /// result is bit-identical to an uninterrupted run.
    #[arg(long)]
    pub resume: bool,
    /// Start over even if the output directory holds the checkpoint of an unfinished run
    /// (which is then deleted); without it such a run is refused.
    #[arg(long, conflicts_with = "resume")]
    pub force: bool,
    /// Seconds of wall time between checkpoints (`<out>/checkpoint.bin`); 0 = at every
    /// check. The checkpoint is removed when the run completes.
    #[arg(long, default_value_t = 60.0, value_name = "SECS")]
    pub checkpoint_every: f64,
    /// Seed of the initial state instead of the scene's.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Write a ParaView frame (grains and contacts, `.vtu`) every T of simulated time (the
    /// first check at or after each multiple of T) into `<out>/vtk/`, listed in
    /// `<out>/vtk/run.pvd`; a resumed run extends the series.
    #[arg(long, value_name = "T")]
    pub dump_every: Option<f64>,
    /// Few-body runs (≤ 1000 grains): record every grain and contact at the first check
    /// at or after each multiple of T into `<out>/trace-grains.csv` and
    /// `trace-contacts.csv`; with two grains also their impact (`impact.json`: duration,
    /// peak force, restitution, angles, spins, with Hertz's values). Set the scene's
    /// `numerics.check_every = 1` for a frame every step.
    #[arg(long, value_name = "T")]
    pub trace_every: Option<f64>,
    /// Write the state at the end of each stage into `<out>/stages/stage-KKK.snap.json`
    /// (K as in the progress line, from 0): the points of a pressure program.
    #[arg(long)]
    pub stage_snapshots: bool,
}

/// `grainbench run`.
pub fn command(a: Args) -> Result<i32> {
    on_threads(a.threads, || {
        for (flag, t) in [
            ("--trace-every", a.trace_every),
            ("--dump-every", a.dump_every),
        ] {
            if let Some(t) = t {
                if !(t.is_finite() && t > 0.0) {
                    bail!("{flag} {t}: give a positive time in the scene's reduced units");
                }
            }
        }
        let flags = RunFlags {
            quiet: a.quiet,
            report: true,
            resume: a.resume,
            force: a.force,
            checkpoint_every: a.checkpoint_every,
            dump_every: a.dump_every,
            trace_every: a.trace_every,
            stage_snapshots: a.stage_snapshots,
        };
        run_command(
            a.scene.as_deref(),
            a.out,
            a.seed,
            a.require_equilibrium,
            &flags,
        )
    })
}

/// Above this many steps to the time limits, a scene with warnings is told so once the time
/// step is known.
const LONG_RUN_STEPS: f64 = 1e7;

/// Options of one run.
#[derive(Clone)]
pub struct RunFlags {
    pub quiet: bool,
    /// Print the metrics table of the final state.
    pub report: bool,
    pub resume: bool,
    /// Start over even if the output directory holds the checkpoint of an unfinished run.
    pub force: bool,
    pub checkpoint_every: f64,
    /// Write a ParaView frame every so much simulated time into `<out>/vtk/` (`--dump-every`).
    pub dump_every: Option<f64>,
    /// Record every grain and contact every so much simulated time (`--trace-every`).
    pub trace_every: Option<f64>,
    /// Write the state at the end of each stage into `<out>/stages/` (`--stage-snapshots`).
    pub stage_snapshots: bool,
}

/// `grainbench run`: exit status 3 with `require_equilibrium` unless every step ended at
/// equilibrium.
fn run_command(
    spec: Option<&str>,
    out: Option<PathBuf>,
    seed: Option<u64>,
    require_equilibrium: bool,
    flags: &RunFlags,
) -> Result<i32> {
    let (mut scene, out) = scene_and_out(spec, out, flags.resume)?;
    if let Some(s) = seed {
        if flags.resume && spec.is_none() && scene.seed != s {
            bail!(
                "--resume continues the run in {} started with seed {}; --seed {s} cannot change it: drop --seed, or start a new run without --resume",
                out.display(),
                scene.seed
            );
        }
        scene.seed = s;
    }
    let (code, outcome) = run(&scene, &out, flags)?;
    if let Some(o) = outcome {
        if code == 0 && require_equilibrium && !o.equilibrated() {
            eprintln!("not every step reached equilibrium (--require-equilibrium)");
            return Ok(3);
        }
    }
    Ok(code)
}

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
pub fn run(scene: &Scene, out: &Path, flags: &RunFlags) -> Result<(i32, Option<Outcome>)> {
    let quiet = flags.quiet;
    let cp_path = out.join(CHECKPOINT);
    let (_lock, resume) = prepare(scene, out, flags)?;
    install_stop_handler();
    let stop = &STOP;
    let threads = rayon::current_num_threads();
    eprintln!(
        "grainbench {}: scene {} ({}D, N = {}, {threads} thread{}) → {}",
        env!("CARGO_PKG_VERSION"),
        scene.name,
        scene.dimension,
        scene.particles.count,
        if threads == 1 { "" } else { "s" },
        out.display()
    );
    let warnings = scene.warnings();
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let bar = progress_bar(quiet);
    let mut on_progress = progress_lines(scene, &bar, quiet, warnings.is_empty());
    if let Some(cp) = &resume {
        eprintln!(
            "resuming from {} (stage {} of {})",
            cp_path.display(),
            cp.header.stage + 1,
            scene.stages().len()
        );
    }
    // ParaView frames: written as they come, the series file rewritten after each.
    let vtk_dir = out.join("vtk");
    let mut dump_failed = false;
    let mut frames = 0usize;
    // The command line's interval, else the scene's (`output.trace_every`).
    let trace_every = flags.trace_every.or(scene.output.trace_every);
    if trace_every.is_some() && scene.particles.count > MAX_TRACE_GRAINS {
        bail!(
            "--trace-every keeps every frame in memory: for few-body scenes (at most {} grains), this one has {}; use --dump-every for ParaView frames",
            MAX_TRACE_GRAINS,
            scene.particles.count
        );
    }
    let mut trace: Vec<snapshot::Snapshot> = Vec::new();
    let mut last_vtk: Option<u64> = None;
    let mut on_dump = |snap: &snapshot::Snapshot| {
        if trace_every.is_some() {
            trace.push(snap.clone());
        }
        // With a trace the frames come every trace interval: ParaView's at its own.
        let Some(every) = flags.dump_every else {
            return;
        };
        let k = (snap.time / every).floor() as u64;
        if dump_failed || last_vtk == Some(k) {
            return;
        }
        last_vtk = Some(k);
        let prefix = vtk::frame_prefix(snap.step);
        let written = vtk::write_frame(snap, &vtk_dir, &prefix)
            .and_then(|_| vtk::write_series(&vtk_dir, "run.pvd"));
        match written {
            Ok(n) => frames = n,
            Err(e) => {
                dump_failed = true;
                eprintln!(
                    "warning: --dump-every: writing into {} failed ({e}); no more frames are written",
                    vtk_dir.display()
                );
            }
        }
    };
    let mut on_stage_end = stage_writer(out);
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
            dump: trace_every.or(flags.dump_every).map(|every| DumpSpec {
                every,
                sink: &mut on_dump,
                last: None,
            }),
            stage_end: flags
                .stage_snapshots
                .then_some(&mut on_stage_end as &mut StageEndHook),
        },
    );
    if flags.dump_every.is_some() && frames > 0 {
        eprintln!(
            "frames     {frames} in {} (ParaView: open run.pvd)",
            vtk_dir.display()
        );
    }
    bar.finish_and_clear();
    let outcome = match result {
        Ok(o) => o,
        Err(e @ RunError::Unstable { .. }) => {
            let RunError::Unstable { last_good, .. } = &e else {
                unreachable!()
            };
            let path = out.join(LAST_GOOD);
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
    if trace_every.is_some() {
        // The final state closes the series (the last frame may be a check earlier).
        if trace.last().is_none_or(|f| f.step != outcome.snapshot.step) {
            trace.push(outcome.snapshot.clone());
        }
        if let Some(r) = crate::trace::write(out, scene, &trace)? {
            eprint!("{}", crate::trace::describe(&r));
        }
        eprintln!(
            "trace      {} frames in {}/trace-grains.csv, trace-contacts.csv",
            trace.len(),
            out.display()
        );
    }
    write_summary(scene, &outcome, out, &snap_path)?;
    print_outcome(scene, &outcome, flags.report);
    println!("snapshot   {}", snap_path.display());
    println!("wall time  {:.1} s", outcome.wall_seconds);
    if outcome.status == StepEnd::Interrupted {
        eprintln!(
            "interrupted: the state at the stop is in {}; continue with `grainbench run --resume --out {}`",
            snap_path.display(),
            out.display()
        );
        return Ok((130, Some(outcome)));
    }
    Ok((0, Some(outcome)))
}

/// Readies the output directory of a run: checks the flags against what it holds, takes its
/// lock (held while the returned file lives) and reads the checkpoint to resume, if asked.
fn prepare(
    scene: &Scene,
    out: &Path,
    flags: &RunFlags,
) -> Result<(std::fs::File, Option<Checkpoint>)> {
    let cp_path = out.join(CHECKPOINT);
    if !(flags.checkpoint_every.is_finite() && flags.checkpoint_every >= 0.0) {
        bail!("--checkpoint-every must be a number of seconds ≥ 0");
    }
    if out.exists() && !out.is_dir() {
        bail!(
            "--out {}: is a file, not a directory; give a directory (it is created if missing)",
            out.display()
        );
    }
    std::fs::create_dir_all(out)
        .with_context(|| format!("creating the output directory {}", out.display()))?;
    // Held until the run returns; also proves the directory writable before any work.
    let lock = lock_output(out)?;
    if !flags.resume && !flags.force && cp_path.exists() {
        bail!(
            "{} holds the checkpoint of an unfinished run ({}): continue it with --resume, or start over with --force (which deletes it)",
            out.display(),
            cp_path.display()
        );
    }
    if flags.force && !flags.resume && cp_path.exists() {
        // Gone now, so that a crash before this run's first checkpoint cannot resume it.
        std::fs::remove_file(&cp_path)
            .with_context(|| format!("deleting the old checkpoint {}", cp_path.display()))?;
    }
    let resume = if flags.resume {
        let cp = Checkpoint::read(&cp_path).map_err(|e| {
            anyhow::anyhow!("{e}\n(--resume continues a run from {}; there is nothing to resume without it: run without --resume)", cp_path.display())
        })?;
        let saved = cp.scene().map_err(anyhow::Error::msg)?;
        if !saved.same_run(scene) {
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
    Ok((lock, resume))
}

/// The progress bar of a run (hidden with `quiet`).
fn progress_bar(quiet: bool) -> ProgressBar {
    if quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(1000);
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {prefix} {bar:30} {msg}")
                .expect("valid template"),
        );
        b
    }
}

/// What a run shows as it goes: the bar's stage, position and numbers; without a terminal (CI
/// logs) a plain line every few seconds; once the time step is known, a note when the stages'
/// time limits allow a very long run (unless the scene already warned); warnings of the
/// checks.
fn progress_lines<'a>(
    scene: &Scene,
    bar: &'a ProgressBar,
    quiet: bool,
    warned_nothing: bool,
) -> impl FnMut(&Progress) + 'a {
    // The stages' time limits in steps, said once the time step is known.
    let time_limits: f64 = scene.stages().iter().map(|(_, s)| s.max_time()).sum();
    let mut told_steps = warned_nothing;
    // Without a terminal (CI logs), a plain line every few seconds instead of the bar.
    let plain = !quiet && !std::io::IsTerminal::is_terminal(&std::io::stderr());
    let mut last_line = std::time::Instant::now();
    move |p: &Progress| {
        let c = &p.checks;
        if !told_steps && p.dt > 0.0 {
            told_steps = true;
            let steps = time_limits / p.dt;
            if steps.is_finite() && steps > LONG_RUN_STEPS {
                bar.suspend(|| {
                    eprintln!(
                        "note: dt = {:.3e}: the stages' time limits ({time_limits:.3e}) allow up to {steps:.2e} steps",
                        p.dt
                    )
                });
            }
        }
        if let Some(w) = unwrapped_warning(p) {
            bar.suspend(|| eprintln!("warning: {w}"));
        }
        if plain && last_line.elapsed().as_secs_f64() >= 5.0 {
            last_line = std::time::Instant::now();
            eprintln!(
                "  stage {}/{} {} t={:.4e}/{:.1e} Φ={:.4} {} Ek/grain={:.2e} force/crit={:.2e} stress/crit={:.2e} Ek/crit={:.2e} contacts={}{}{}",
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
                clusters_text(c),
                if p.relaxing { " relaxing" } else { "" }
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
    }
}

/// `--stage-snapshots`: writes each stage's end state into `<out>/stages/`, atomically as the
/// stage ends, so that a resumed run keeps those of the stages before it; after a failed
/// write, a warning and no more.
fn stage_writer(out: &Path) -> impl FnMut(&StepReport, &snapshot::Snapshot) {
    let stage_dir = out.join(STAGES);
    let mut stage_failed = false;
    move |r: &StepReport, snap: &snapshot::Snapshot| {
        if stage_failed {
            return;
        }
        let path = stage_dir.join(stage_file(r.index));
        let written = std::fs::create_dir_all(&stage_dir)
            .map_err(anyhow::Error::from)
            .and_then(|_| snap.write(&path).map_err(anyhow::Error::from));
        if let Err(e) = written {
            stage_failed = true;
            eprintln!(
                "warning: --stage-snapshots: writing {} failed ({e}); no more stage states are written",
                path.display()
            );
        }
    }
}

/// `summary.json`: the scene, the law and time step, the stage reports and how the run ended.
fn write_summary(scene: &Scene, outcome: &Outcome, out: &Path, snap_path: &Path) -> Result<()> {
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
        "contacts_at_threshold": outcome.contacts_at_threshold.all,
        "contacts_at_threshold_below_tolerance": outcome.contacts_at_threshold.below_tolerance,
        "status": outcome.status.as_str(),
        "steps": outcome.steps,
        "snapshot": snap_path,
    });
    snapshot::write_atomic(
        &out.join(SUMMARY),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    Ok(())
}

/// The terminal report of a finished run: the law, the time step, each stage's end with its
/// relaxation and quench, the contacts at a threshold, and (with `report`) the metrics table.
fn print_outcome(scene: &Scene, outcome: &Outcome, report: bool) {
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
        if s.end == StepEnd::Done {
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
            if s.peak_strain_rate > 0.0 {
                println!(
                    "           peak strain rate |L̇/L| = {:.4e}",
                    s.peak_strain_rate
                );
            }
            if let Some(r) = &s.relaxation {
                let how = match &r.fire {
                    Some(f) => format!(
                        "FIRE: {} steps, {} velocity resets, time step up to {:.1}× the stage's",
                        f.steps, f.resets, f.peak_dt
                    ),
                    None => format!("damping γ = {}, ζ_t = {}", r.damping, r.tangential_zeta),
                };
                println!(
                    "           relaxation from t = {:.4e} ({how}): {} pairs, {} gained, {} lost, ΔΦ = {:.2e}, largest displacement {:.2e} a",
                    r.start_time,
                    r.pairs,
                    r.pairs_gained,
                    r.pairs_lost,
                    r.delta_phi,
                    r.max_displacement
                );
                if r.free_rollers > 0 {
                    println!(
                        "           {} free rollers (one interaction, no rolling resistance) stopped where they were, as GRC07 §III.A stops",
                        r.free_rollers
                    );
                }
            }
            if let Some(q) = &s.quench {
                println!(
                    "           {} velocity quench(es) from t = {:.4e} (AR07 §III.A), {:.3e} kinetic energy per grain removed: {} pairs, {} gained, {} lost, ΔΦ = {:.2e}, largest displacement {:.2e} a",
                    q.count,
                    q.first_time,
                    q.kinetic_removed_per_grain,
                    q.pairs,
                    q.pairs_gained,
                    q.pairs_lost,
                    q.delta_phi,
                    q.max_displacement
                );
            }
        }
    }
    let at = outcome.contacts_at_threshold;
    if at.loaded() > 0 {
        println!(
            "warning    {} contacts sit at a Coulomb or rolling threshold above the equilibrium tolerance (GRC07 §II.D expects none at equilibrium)",
            at.loaded()
        );
    }
    if at.below_tolerance > 0 {
        println!(
            "note       {} contacts sit at a threshold (μN or μ_r N) below the equilibrium tolerance, which cannot tell them from contacts inside it",
            at.below_tolerance
        );
    }
    if report {
        print!(
            "{}",
            grainbench_comparisons::report::to_markdown(&analysis_of(&outcome.snapshot))
        );
    }
}

/// The cluster count of aggregation stages (empty elsewhere).
fn clusters_text(c: &Checks) -> String {
    if c.clusters > 0 {
        format!(" clusters={}", c.clusters)
    } else {
        String::new()
    }
}

/// The warning for a stage that frees the cell at zero pressure while the grains still move,
/// around a network that does not wrap it along some axis: no contact holds the cell there.
fn unwrapped_warning(p: &Progress) -> Option<String> {
    let wrapped = p.wrapped_axes.as_ref()?;
    let c = &p.checks;
    if c.pressure_target != 0.0 || c.kinetic_ratio <= 1.0 || wrapped.iter().all(|&w| w) {
        return None;
    }
    let axes: Vec<&str> = wrapped
        .iter()
        .zip(["x", "y", "z"])
        .filter(|(w, _)| !**w)
        .map(|(_, a)| a)
        .collect();
    Some(format!(
        "stage {} ({}) frees the cell at zero pressure with the grains still moving (kinetic energy {:.1e}× its criterion) around a network that does not wrap the cell along {}: no contact holds the cell length there, and it drifts open with the grains' kinetic stress; bring the grains to rest in the fixed cell first (a `fixed-volume` stage with `relax`, as GRC07 §III.B.1 frees the cell only once the aggregate is at rest)",
        p.step_index + 1,
        p.step_kind,
        c.kinetic_ratio,
        axes.join(" and ")
    ))
}

/// P/P₀ against a positive target, else P itself (fixed cell, or P* = 0).
fn pressure_text(c: &Checks) -> String {
    if c.pressure_target > 0.0 {
        format!("P/P₀={:.4}", c.pressure / c.pressure_target)
    } else {
        format!("P={:.3e}", c.pressure)
    }
}

/// Takes the advisory lock of an output directory (`flock` on [`LOCK`], released when the
/// file is dropped or the process ends), so two runs never write over each other's checkpoint.
fn lock_output(out: &Path) -> Result<std::fs::File> {
    use std::io::{Read, Seek, Write};
    use std::os::unix::io::AsRawFd;
    let path = out.join(LOCK);
    let mut f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .with_context(|| format!("cannot write in the output directory {}", out.display()))?;
    // SAFETY: flock on a descriptor this function owns.
    if unsafe { libc::flock(f.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
        let mut other = String::new();
        let _ = f.read_to_string(&mut other);
        let other = match other.trim() {
            "" => "pid unknown".to_string(),
            o => o.to_string(),
        };
        bail!(
            "another grainbench run ({other}) is writing to {}: wait for it to end, or give this run another --out",
            out.display()
        );
    }
    f.set_len(0)?;
    f.rewind()?;
    write!(f, "pid {}", std::process::id())?;
    Ok(f)
}
