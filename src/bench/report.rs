//! The records of `bench` and their tables: each run, the rows (median [min–max] over the
//! repeats, ratio to our engine), bench.json, bench.md and bench.csv.

use super::setup::Mode;
use grainbench_comparisons::outcome::Outcome;
use grainbench_comparisons::report::format::sci3;
use grainbench_comparisons::stats::Stat;
use grainbench_comparisons::xcode::crosscode::CodeResult;
use grainbench_comparisons::xcode::decks::Code;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// One run of one code.
#[derive(Clone, Debug, Serialize)]
pub struct Run {
    /// Position in the run order (1-based).
    pub order: usize,
    pub code: Code,
    pub threads: usize,
    /// Repeat index (1-based).
    pub repeat: usize,
    /// `ran`, `failed`, `timeout`, `interrupted`.
    pub outcome: Outcome,
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

/// One row of the table: a code at a thread count.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub code: Code,
    pub threads: usize,
    /// Runs that ended normally / runs made.
    pub ran: usize,
    pub runs: usize,
    /// `ran`, or why it did not run (`missing`, `refused`, …) with the message.
    pub outcome: Outcome,
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

/// The notes under the table: what the columns measure and how the runs were made.
pub fn notes(mode: &Mode, start: Option<&Path>) -> Vec<String> {
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

/// The progress line of one finished run.
pub fn run_line(r: &Run) -> String {
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

/// The rows of the table: one per code (with its column of results) and thread count.
pub fn rows_of(columns: &[(Code, &CodeResult)], threads: &[usize], runs: &[Run]) -> Vec<Row> {
    let mut rows = Vec::new();
    for (code, r) in columns {
        for &t in threads {
            let mine: Vec<&Run> = runs
                .iter()
                .filter(|x| x.code == *code && x.threads == t)
                .collect();
            let ok: Vec<&Run> = mine
                .iter()
                .copied()
                .filter(|x| x.outcome == Outcome::Ran)
                .collect();
            let stat = |f: &dyn Fn(&Run) -> Option<f64>| {
                Stat::of(&ok.iter().filter_map(|x| f(x)).collect::<Vec<_>>())
            };
            let ratio = |f: &dyn Fn(&Run) -> Option<f64>| {
                let v: Vec<f64> = ok
                    .iter()
                    .filter_map(|x| {
                        let ours = runs.iter().find(|y| {
                            y.code == Code::Rust
                                && y.threads == t
                                && y.repeat == x.repeat
                                && y.outcome == Outcome::Ran
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
                (r.outcome, r.message.clone())
            } else if ok.len() == mine.len() {
                (Outcome::Ran, None)
            } else {
                let bad = mine
                    .iter()
                    .find(|x| x.outcome != Outcome::Ran)
                    .expect("some failed");
                (bad.outcome, bad.message.clone())
            };
            rows.push(Row {
                code: *code,
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

/// `median [min–max]`, or the median alone when they agree.
fn stat_text(s: Option<Stat>, fmt: impl Fn(f64) -> String) -> String {
    match s {
        None => "—".into(),
        Some(s) if s.min == s.max => fmt(s.median),
        Some(s) => format!("{} [{}–{}]", fmt(s.median), fmt(s.min), fmt(s.max)),
    }
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
        let status = if row.outcome == Outcome::Ran {
            row.statuses.join(", ")
        } else {
            row.outcome.to_string()
        };
        s += &format!(
            "| {} | {} | {}/{} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            row.code,
            row.threads,
            row.ran,
            row.runs,
            status,
            stat_text(row.steps, fixed(0)),
            stat_text(row.wall_seconds, fixed(2)),
            stat_text(row.loop_seconds, fixed(2)),
            stat_text(row.particle_steps_per_second, sci3),
            stat_text(row.loop_particle_steps_per_second, sci3),
            stat_text(row.peak_rss_mib, fixed(1)),
            stat_text(row.rate_ratio, fixed(3)),
            stat_text(row.wall_ratio, fixed(3)),
        );
    }
    s += "\n";
    for row in r.rows.iter().filter(|x| x.outcome != Outcome::Ran) {
        if let Some(m) = &row.message {
            s += &format!("- {} -j{}: {}: {m}\n", row.code, row.threads, row.outcome);
        }
    }
    let mut seen = Vec::new();
    for row in &r.rows {
        if let Some(v) = &row.version {
            if !seen.contains(&row.code) {
                seen.push(row.code);
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
