//! `grainbench compare SCENE --codes …`: runs a scene in our engine and in the external codes
//! from the same start, reads every final state into our snapshot format, measures all of
//! them with the same `comparisons/` code, and writes the table (Markdown, CSV, JSON) and the
//! overlaid P(f) and g(r) plots. `grainbench golden update` records the results.

use crate::{run, RunFlags, STOP};
use anyhow::{bail, Context, Result};
use grainbench_comparisons::metrics::Analysis;
use grainbench_comparisons::xcode::crosscode::{self, Bands, CodeResult, Comparison};
use grainbench_comparisons::xcode::decks::{self, StageKind, Start};
use grainbench_comparisons::xcode::import::{self, Meta};
use grainbench_comparisons::xcode::Code;
use grainbench_engine::snapshot::{write_atomic, Snapshot};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

pub struct Args {
    pub scene: String,
    pub codes: Vec<String>,
    pub out: Option<PathBuf>,
    pub time_limit: f64,
    pub np: Option<usize>,
    pub quiet: bool,
    pub all_metrics: bool,
}

pub fn compare(a: &Args) -> Result<i32> {
    let scene = crate::load_scene(&a.scene)?;
    let codes = if a.codes.is_empty() {
        Code::ALL.to_vec()
    } else {
        crate::xcode::parse_codes(&a.codes, true)?
    };
    if a.np == Some(0) {
        bail!("--np must be at least 1");
    }
    if a.time_limit.is_nan() || a.time_limit <= 0.0 {
        bail!("--time-limit must be a positive number of seconds");
    }
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs/compare").join(&scene.name));
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let start = Start::of(&scene).map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
    let (p_target, p_tol) = match start.stages.last() {
        Some(s) => match s.kind {
            StageKind::Compress { pressure } => (Some(pressure), Some(s.tolerances.stress)),
            _ => (None, None),
        },
        None => (None, None),
    };
    eprintln!(
        "compare {} (N = {}): {} → {}",
        scene.name,
        start.n(),
        crate::xcode::code_names(&codes),
        out.display()
    );
    let mut results = Vec::new();
    let mut analyses: Vec<(String, Analysis)> = Vec::new();
    for &code in &codes {
        if STOP.load(Ordering::SeqCst) {
            break;
        }
        let dir = out.join(code.name());
        let mut r = CodeResult {
            golden: crosscode::golden_metrics(Path::new("."), &scene.name, code.name()),
            pressure_target: p_target,
            pressure_tolerance: p_tol,
            ..CodeResult::new(code.name(), "ran")
        };
        let snap = match code {
            Code::Rust => run_rust(&scene, &dir, a.quiet, &mut r)?,
            _ => run_external(&start, code, &dir, a, &mut r)?,
        };
        if let Some(snap) = snap {
            let analysis = crate::analysis_of(&snap);
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
    let cmp = crosscode::build(
        &scene.name,
        start.n(),
        Some(scene.paper_state.as_deref().unwrap_or(&scene.name)),
        results,
        &Bands::embedded(),
    );
    write_outputs(&out, &cmp, analyses, a.all_metrics)?;
    Ok(if cmp.failures.is_empty() { 0 } else { 1 })
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
    crate::reproduce::write_plots(out, &labels, &analyses);
    eprintln!(
        "wrote {0}/compare.md, compare.csv, compare.json, pf.svg/png, gr.svg/png{1}",
        out.display(),
        if cmp.failures.is_empty() {
            String::new()
        } else {
            format!("; {} check(s) failed", cmp.failures.len())
        }
    );
    Ok(())
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
        checkpoint_every: 60.0,
    };
    r.version = Some(format!("grainbench {}", env!("CARGO_PKG_VERSION")));
    let t = Instant::now();
    let (code, outcome) = run(scene, dir, &flags)?;
    r.wall_seconds = Some(t.elapsed().as_secs_f64());
    match outcome {
        Some(o) if code == 0 => Ok(Some(o.snapshot)),
        Some(o) => {
            r.outcome = "interrupted".into();
            Ok(Some(o.snapshot))
        }
        None => {
            r.outcome = "failed".into();
            r.message = Some(format!("grainbench run exited with status {code}"));
            Ok(None)
        }
    }
}

/// An external code in its own work directory, with a progress line and a time limit.
pub(crate) fn run_external(
    start: &Start,
    code: Code,
    dir: &Path,
    a: &Args,
    r: &mut CodeResult,
) -> Result<Option<Snapshot>> {
    let Some((binary, deck)) = prepare_external(start, code, r) else {
        return Ok(None);
    };
    write_fresh_deck(&deck, dir)?;
    let mut cmd = external_command(code, &binary, &deck, a.np, None)?;
    let done = supervise(
        &mut cmd,
        dir,
        code.name(),
        a.time_limit,
        a.quiet,
        Some("stdout.log"),
    )?;
    r.wall_seconds = Some(done.wall_seconds);
    finish_external(code, dir, &done, a.time_limit, r)
}

/// The binary and deck of an external code, or `None` with `r` saying why (missing binary,
/// scene refused).
pub(crate) fn prepare_external(
    start: &Start,
    code: Code,
    r: &mut CodeResult,
) -> Option<(PathBuf, decks::Deck)> {
    let Some(binary) = code.find() else {
        r.outcome = "missing".into();
        r.message = Some(format!(
            "`{}` not found on PATH; install with `{}` (or `bash ci/install-externals.sh`)",
            code.binary(),
            code.install_hint()
        ));
        return None;
    };
    match decks::deck(start, code) {
        Ok(d) => {
            r.deviations = d.deviations.clone();
            Some((binary, d))
        }
        Err(refusal) => {
            r.outcome = "refused".into();
            r.message = Some(refusal.to_string());
            None
        }
    }
}

/// Writes `deck` into a fresh `dir` (old dumps must not be read as this run's).
pub(crate) fn write_fresh_deck(deck: &decks::Deck, dir: &Path) -> Result<()> {
    if dir.exists() {
        std::fs::remove_dir_all(dir).with_context(|| format!("clearing {}", dir.display()))?;
    }
    crate::xcode::write_deck(deck, dir)
}

/// The command running `deck`: LAMMPS and LIGGGHTS under `mpirun -np K` when `np` is given,
/// YADE with `-j threads` when given.
pub(crate) fn external_command(
    code: Code,
    binary: &Path,
    deck: &decks::Deck,
    np: Option<usize>,
    yade_threads: Option<usize>,
) -> Result<Command> {
    let mut cmd = match (np, code) {
        (Some(k), Code::Lammps | Code::Liggghts) => {
            let Some(mpirun) = decks::which("mpirun") else {
                bail!("running {code} on {k} processes needs `mpirun` (Debian: apt-get install -y --no-install-recommends openmpi-bin)");
            };
            let mut c = Command::new(mpirun);
            c.args([
                "--allow-run-as-root",
                "--oversubscribe",
                "-np",
                &k.to_string(),
            ]);
            c.arg(binary);
            c
        }
        _ => Command::new(binary),
    };
    if let (Some(t), Code::Yade) = (yade_threads, code) {
        cmd.args(["-j", &t.to_string()]);
    }
    cmd.args(&deck.args);
    if code == Code::Yade {
        // YADE opens local ports and reads its own environment; keep it headless.
        cmd.env("DISPLAY", "");
    }
    Ok(cmd)
}

/// How a supervised child process ended.
pub(crate) struct Finished {
    /// Exit status; `None` when killed at the time limit or by Ctrl-C.
    pub status: Option<std::process::ExitStatus>,
    /// From the start to the reaping of the process.
    pub wall_seconds: f64,
    /// `ru_maxrss` of the process (`wait4`), KiB: its largest resident set, or that of its
    /// largest waited-for descendant (e.g. one MPI rank under `mpirun`).
    pub max_rss_kib: u64,
    /// Largest sum of the resident sets of its process group, sampled every 0.25 s, KiB.
    pub group_rss_kib: u64,
}

/// Runs `cmd` in `dir` with stdout/stderr in `stdout.log`/`stderr.log`, a progress line from
/// the last line of the log `progress` names (unless `None`), the time limit and Ctrl-C (the process
/// group is terminated). Resource usage comes from `wait4` for this process only.
pub(crate) fn supervise(
    cmd: &mut Command,
    dir: &Path,
    label: &str,
    time_limit: f64,
    quiet: bool,
    progress: Option<&str>,
) -> Result<Finished> {
    use std::os::unix::process::{CommandExt, ExitStatusExt};
    cmd.current_dir(dir).stdin(Stdio::null());
    let stdout = std::fs::File::create(dir.join("stdout.log"))?;
    let stderr = std::fs::File::create(dir.join("stderr.log"))?;
    cmd.stdout(stdout).stderr(stderr);
    // Its own process group: a time-limit kill reaches mpirun's ranks too.
    cmd.process_group(0);
    let t = Instant::now();
    let child = cmd
        .spawn()
        .with_context(|| format!("starting {:?}", cmd.get_program()))?;
    let pid = child.id() as libc::pid_t;
    // Reaped by wait4 in the waiter thread (for its rusage), not by `Child`.
    drop(child);
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut status = 0;
        // SAFETY: an all-zero rusage is a valid value; wait4 only writes into it.
        let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
        let r = loop {
            // SAFETY: plain system call on our own child with valid pointers.
            let r = unsafe { libc::wait4(pid, &mut status, 0, &mut ru) };
            if r >= 0 || std::io::Error::last_os_error().kind() != std::io::ErrorKind::Interrupted {
                break r;
            }
        };
        let wall = t.elapsed().as_secs_f64();
        let _ = tx.send((r, status, wall, ru.ru_maxrss.max(0) as u64));
    });
    let bar = if quiet || progress.is_none() {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new_spinner();
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {prefix} {msg}")
                .expect("template"),
        );
        b.set_prefix(label.to_string());
        b
    };
    let plain =
        progress.is_some() && !quiet && !std::io::IsTerminal::is_terminal(&std::io::stderr());
    let mut last_plain = Instant::now();
    let mut group_rss = 0;
    let mut killed = false;
    let mut term_at: Option<Instant> = None;
    let (r, status, wall, max_rss) = loop {
        match rx.recv_timeout(Duration::from_millis(250)) {
            Ok(v) => break v,
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                bail!("lost the waiter of process {pid}")
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
        }
        group_rss = group_rss.max(process_group_rss_kib(pid));
        let elapsed = t.elapsed().as_secs_f64();
        if !killed && (elapsed > time_limit || STOP.load(Ordering::SeqCst)) {
            killed = true;
            term_at = Some(Instant::now());
            // SAFETY: signals the process group we created (not yet reaped: the waiter has
            // not reported).
            unsafe { libc::kill(-pid, libc::SIGTERM) };
        }
        if term_at.is_some_and(|k| k.elapsed().as_secs_f64() > 5.0) {
            // SAFETY: as above.
            unsafe { libc::kill(-pid, libc::SIGKILL) };
            term_at = None;
        }
        if let Some(log) = progress {
            let line = last_line(&dir.join(log));
            bar.set_message(line.clone());
            bar.tick();
            if plain && last_plain.elapsed().as_secs_f64() >= 10.0 {
                last_plain = Instant::now();
                eprintln!("  {label} [{elapsed:.0} s] {line}");
            }
        }
    };
    bar.finish_and_clear();
    if killed {
        // Ranks left behind by a killed mpirun.
        // SAFETY: the group id is that of our child; a group without members is a no-op.
        unsafe { libc::kill(-pid, libc::SIGKILL) };
    }
    if r < 0 {
        bail!(
            "waiting for process {pid}: {}",
            std::io::Error::last_os_error()
        );
    }
    Ok(Finished {
        status: (!killed).then(|| std::process::ExitStatus::from_raw(status)),
        wall_seconds: wall,
        max_rss_kib: max_rss,
        group_rss_kib: group_rss,
    })
}

/// Sum of VmRSS over the processes of process group `pgid`, KiB (0 where /proc is absent).
fn process_group_rss_kib(pgid: libc::pid_t) -> u64 {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return 0;
    };
    let mut sum = 0;
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(pid) = name
            .to_str()
            .filter(|n| n.bytes().all(|b| b.is_ascii_digit()))
        else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
            continue;
        };
        // Fields after the parenthesised command: state ppid pgrp …
        let Some(rest) = stat.rsplit_once(')').map(|(_, r)| r) else {
            continue;
        };
        if rest.split_whitespace().nth(2) != Some(&pgid.to_string()) {
            continue;
        }
        if let Ok(st) = std::fs::read_to_string(format!("/proc/{pid}/status")) {
            if let Some(kb) = st
                .lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<u64>().ok())
            {
                sum += kb;
            }
        }
    }
    sum
}

/// The outcome of a finished external run, and its final state read back.
pub(crate) fn finish_external(
    code: Code,
    dir: &Path,
    done: &Finished,
    time_limit: f64,
    r: &mut CodeResult,
) -> Result<Option<Snapshot>> {
    r.version = version_line(code, &dir.join("stdout.log"));
    let logs = format!("logs in {}", dir.display());
    match done.status {
        None if STOP.load(Ordering::SeqCst) => {
            r.outcome = "interrupted".into();
            r.message = Some(logs);
            return Ok(None);
        }
        None => {
            r.outcome = "timeout".into();
            r.message = Some(format!(
                "killed after the time limit of {time_limit} s (--time-limit); {logs}"
            ));
            return Ok(None);
        }
        Some(s) if !s.success() => {
            r.outcome = "failed".into();
            r.message = Some(format!(
                "exited with {s}; last output: {:?}; {logs}",
                last_line(&dir.join("stderr.log"))
                    .chars()
                    .chain(last_line(&dir.join("stdout.log")).chars())
                    .collect::<String>()
            ));
            return Ok(None);
        }
        Some(_) => {}
    }
    let meta = Meta::read(dir)?;
    match import::read(code, dir, &meta) {
        Ok(snap) => {
            snap.write(&dir.join("final.snap.json"))?;
            Ok(Some(snap))
        }
        Err(e) => {
            r.outcome = "failed".into();
            r.message = Some(format!("reading its final state: {e}; {logs}"));
            Ok(None)
        }
    }
}

/// The line of a log saying why a process failed: a Rust panic's message or an `error:`
/// line, else the last line.
pub(crate) fn failure_line(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    if let Some(k) = lines.iter().position(|l| l.contains("panicked at")) {
        return lines[k..(k + 2).min(lines.len())].join(" ");
    }
    if let Some(l) = lines.iter().rev().find(|l| l.starts_with("error")) {
        return l.to_string();
    }
    last_line(path)
}

/// The last non-empty line of a log (for the progress line and error messages).
pub(crate) fn last_line(path: &Path) -> String {
    let Ok(bytes) = std::fs::read(path) else {
        return String::new();
    };
    let tail = &bytes[bytes.len().saturating_sub(4096)..];
    let text = String::from_utf8_lossy(tail);
    // Prefer a progress line (a thermo row starting with the step, or YADE's `stage …`) over
    // the run summaries LAMMPS and LIGGGHTS print between chunks.
    let progress = |l: &&&str| {
        let first = l.split_whitespace().next().unwrap_or("");
        first.parse::<u64>().is_ok() || first == "stage"
    };
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    lines
        .iter()
        .rev()
        .find(progress)
        .or(lines.last())
        .copied()
        .unwrap_or("")
        .trim()
        .chars()
        .take(120)
        .collect()
}

/// The code's own version line from its output.
pub(crate) fn version_line(code: Code, stdout: &Path) -> Option<String> {
    let text = std::fs::read_to_string(stdout).ok()?;
    let key = match code {
        Code::Lammps => "LAMMPS (",
        Code::Liggghts => "LIGGGHTS (",
        Code::Yade => "Yade ",
        Code::Rust => return None,
    };
    text.lines()
        .find(|l| l.contains(key))
        .map(clean_version)
        .or_else(|| Some(code.binary().to_string()))
}

/// Was `path` written by `reproduce --record` (several seeds and a paper table)?
fn recorded_by_reproduce(path: &Path) -> bool {
    std::fs::read_to_string(path)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .is_some_and(|d| d.get("table").is_some())
}

/// `Welcome to Yade 2023.02a` → `Yade 2023.02a`.
fn clean_version(line: &str) -> String {
    line.trim().trim_start_matches("Welcome to ").to_string()
}

/// `grainbench golden update SCENE`: records the results of the last `compare` run of the
/// scene (from `runs/compare/<scene>/` or `--from`) as `golden/<scene>/<code>.json`.
pub fn golden_update(
    scene: &str,
    codes: &[String],
    from: Option<PathBuf>,
    command: Option<String>,
) -> Result<i32> {
    let scene = crate::load_scene(scene)?;
    let dir = from.unwrap_or_else(|| Path::new("runs/compare").join(&scene.name));
    let path = dir.join("compare.json");
    let text = std::fs::read_to_string(&path).with_context(|| {
        format!(
            "reading {}: run `grainbench compare {}` first (golden update records its results)",
            path.display(),
            scene.name
        )
    })?;
    let cmp: Comparison =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    if cmp.scene != scene.name {
        bail!(
            "{} holds scene {}, not {}",
            path.display(),
            cmp.scene,
            scene.name
        );
    }
    let wanted = if codes.is_empty() {
        Vec::new()
    } else {
        crate::xcode::parse_codes(codes, true)?
    };
    let mut written = 0;
    for c in &cmp.codes {
        if !wanted.is_empty() && !wanted.iter().any(|w| w.name() == c.code) {
            continue;
        }
        if c.outcome != "ran" {
            eprintln!("{}: not recorded ({})", c.code, c.outcome);
            continue;
        }
        let out = Path::new("golden")
            .join(&scene.name)
            .join(format!("{}.json", c.code));
        if recorded_by_reproduce(&out) {
            eprintln!(
                "{}: not recorded: {} holds a `grainbench reproduce --record` result over seeds; rerun that command to change it",
                c.code,
                out.display()
            );
            continue;
        }
        let doc = serde_json::json!({
            "code": c.version.as_deref().map(clean_version),
            "scene": scene.name,
            "n": cmp.n,
            "command": command.clone().unwrap_or_else(|| format!("grainbench compare {} --codes {}", scene.name, c.code)),
            "deviations": c.deviations,
            "seeds": [{
                "seed": scene.seed,
                "status": c.status,
                "wall_seconds": c.wall_seconds,
                "metrics": c.metrics,
            }],
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
            path.display()
        );
    }
    if written > 1 {
        // The overlaid plots of a run that recorded several codes at once.
        for plot in ["pf.svg", "gr.svg"] {
            if let Ok(bytes) = std::fs::read(dir.join(plot)) {
                let to = Path::new("golden").join(&scene.name).join(plot);
                write_atomic(&to, &bytes)?;
                println!("wrote {}", to.display());
            }
        }
    }
    Ok(0)
}

/// `grainbench golden show SCENE`: the recorded values of every code, as the compare table.
pub fn golden_show(scene: &str, all_metrics: bool) -> Result<i32> {
    let scene = crate::load_scene(scene)?;
    let start = Start::of(&scene).ok();
    let mut codes = Vec::new();
    for c in Code::ALL {
        if let Some(r) = crosscode::recorded(Path::new("."), &scene.name, c.name()) {
            codes.push(r);
            continue;
        }
        // Not recorded: say why when the code cannot express the scene.
        if let (Some(st), true) = (&start, c != Code::Rust) {
            if let Err(refusal) = decks::deck(st, c) {
                codes.push(CodeResult {
                    message: Some(refusal.to_string()),
                    ..CodeResult::new(c.name(), "refused")
                });
            }
        }
    }
    if codes.iter().all(|c| c.outcome != "recorded") {
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
    for c in cmp.codes.iter().filter(|c| c.outcome == "recorded") {
        println!("{}: `{}`", c.code, c.message.as_deref().unwrap_or(""));
    }
    Ok(0)
}
