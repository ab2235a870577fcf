//! External codes (LAMMPS, LIGGGHTS, YADE) and our own engine as child processes: the binary
//! and deck of a code, its command line, the supervised run (time limit, Ctrl-C, peak
//! memory, progress line), the outcome and the final state read back (what their logs say is
//! read by `grainbench_comparisons::xcode::import::logs`). Used by `compare`, `bench` and
//! `accuracy`.

use crate::common::STOP;
use crate::xcode;
use anyhow::{bail, Context, Result};
use grainbench_comparisons::outcome::Outcome;
use grainbench_comparisons::xcode::crosscode::CodeResult;
use grainbench_comparisons::xcode::decks::{self, generic, Code, Start};
use grainbench_comparisons::xcode::import::{self, logs, Meta};
use grainbench_engine::snapshot::Snapshot;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

/// An external code in its own work directory, with a progress line and a time limit.
/// LAMMPS and LIGGGHTS run under `mpirun -np K` when `np` is given.
pub fn run(
    start: &Start,
    code: Code,
    dir: &Path,
    time_limit: f64,
    np: Option<usize>,
    quiet: bool,
    r: &mut CodeResult,
) -> Result<Option<Snapshot>> {
    let Some((binary, deck)) = prepare(start, code, r) else {
        return Ok(None);
    };
    write_fresh_deck(&deck, dir)?;
    let mut cmd = command(code, &binary, &deck, np, None)?;
    let done = supervise(
        &mut cmd,
        dir,
        code.name(),
        time_limit,
        quiet,
        Some("stdout.log"),
    )?;
    r.wall_seconds = Some(done.wall_seconds);
    finish(code, dir, &done, time_limit, r)
}

/// The binary and deck of an external code, or `None` with `r` saying why (missing binary,
/// scene refused).
pub fn prepare(start: &Start, code: Code, r: &mut CodeResult) -> Option<(PathBuf, decks::Deck)> {
    let Some(binary) = code.find() else {
        r.outcome = Outcome::Missing;
        r.message = Some(format!(
            "{}; install with `{}` (or `bash ci/install-externals.sh`)",
            code.not_found(),
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
            r.outcome = Outcome::Refused;
            r.message = Some(refusal.to_string());
            None
        }
    }
}

/// Writes `deck` into a fresh `dir` (old dumps must not be read as this run's).
pub fn write_fresh_deck(deck: &decks::Deck, dir: &Path) -> Result<()> {
    if dir.exists() {
        std::fs::remove_dir_all(dir).with_context(|| format!("clearing {}", dir.display()))?;
    }
    xcode::write_deck(deck, dir)?;
    if let Code::Adapter(_) = deck.code {
        // `{output}` of the exchange format.
        std::fs::create_dir_all(dir.join(generic::OUTPUT_DIR))?;
    }
    Ok(())
}

/// The command running `deck`: LAMMPS and LIGGGHTS under `mpirun -np K` when `np` is given,
/// YADE with `-j threads` when given.
pub fn command(
    code: Code,
    binary: &Path,
    deck: &decks::Deck,
    np: Option<usize>,
    yade_threads: Option<usize>,
) -> Result<Command> {
    if let Code::Adapter(a) = code {
        // `{exchange}`: the run directory; `{output}`: its `final/` (docs/exchange-format.md).
        let args = a.fill(
            &a.run,
            Path::new("."),
            &Path::new(".").join(generic::OUTPUT_DIR),
            np.or(yade_threads).unwrap_or(1),
        );
        let mut c = Command::new(binary);
        c.args(&args[1..]);
        return Ok(c);
    }
    let mut cmd = match (np, code) {
        (Some(k), Code::Lammps | Code::Lammps2025 | Code::Liggghts) => {
            // LAMMPS 2025 links the MPICH of its virtual environment: its own mpirun.
            let venv_mpirun = binary.with_file_name("mpirun");
            if code == Code::Lammps2025 && venv_mpirun.is_file() {
                // MPICH's hydra: no OpenMPI flags.
                let mut c = Command::new(venv_mpirun);
                c.args(["-np", &k.to_string()]).arg(binary);
                c
            } else {
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
pub struct Finished {
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

impl Finished {
    /// max(`wait4` ru_maxrss, sampled sum over the process group), KiB.
    pub fn peak_rss_kib(&self) -> u64 {
        self.max_rss_kib.max(self.group_rss_kib)
    }
}

/// Runs `cmd` in `dir` with stdout/stderr in `stdout.log`/`stderr.log`, a progress line from
/// the last line of the log `progress` names (unless `None`), the time limit and Ctrl-C (the process
/// group is terminated). Resource usage comes from `wait4` for this process only.
pub fn supervise(
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
            let line = logs::last_line(&dir.join(log));
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
pub fn finish(
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
            r.outcome = Outcome::Interrupted;
            r.message = Some(logs);
            return Ok(None);
        }
        None => {
            r.outcome = Outcome::Timeout;
            r.message = Some(format!(
                "killed after the time limit of {time_limit} s (--time-limit); {logs}"
            ));
            return Ok(None);
        }
        Some(s) if !s.success() => {
            r.outcome = Outcome::Failed;
            r.message = Some(format!(
                "exited with {s}; last output: {:?}; {logs}",
                logs::last_line(&dir.join("stderr.log"))
                    .chars()
                    .chain(logs::last_line(&dir.join("stdout.log")).chars())
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
            r.outcome = Outcome::Failed;
            r.message = Some(format!("reading its final state: {e}; {logs}"));
            Ok(None)
        }
    }
}

/// Why a supervised child gave no result: killed at `time_limit`, or its exit status with the
/// failure line of its `stderr.log` in `dir`.
pub fn why_failed(status: Option<std::process::ExitStatus>, dir: &Path, time_limit: f64) -> String {
    match status {
        None => format!("killed after the time limit of {time_limit} s"),
        Some(s) => format!(
            "exited with {s}: {:?}",
            logs::failure_line(&dir.join("stderr.log"))
        ),
    }
}

/// The code's own version: what its run's output says ([`logs::version_line`]), else for an
/// adapter what its `version` command prints, else its program.
pub fn version_line(code: Code, stdout: &Path) -> Option<String> {
    let read = logs::version_line(code, stdout);
    match code {
        Code::Adapter(a) => read
            .or_else(|| adapter_version(a))
            .or_else(|| Some(a.run[0].clone())),
        _ => read,
    }
}

/// The first line an adapter's `version` command prints.
fn adapter_version(a: &grainbench_comparisons::xcode::adapter::Adapter) -> Option<String> {
    let args = a.fill(a.version.as_ref()?, Path::new("."), Path::new("."), 1);
    let out = Command::new(&args[0])
        .args(&args[1..])
        .stdin(Stdio::null())
        .output()
        .ok()?;
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    text.lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .map(String::from)
}
