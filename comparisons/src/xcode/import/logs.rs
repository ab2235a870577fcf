//! What the codes' own logs say: their version, the steps and the time of the time-stepping
//! loop (LAMMPS and LIGGGHTS `Loop time of …` lines, YADE's `done: …` line, an adapter's
//! `status.txt`), the progress line and the line that says why a run failed.

use super::generic::status_value;
use crate::xcode::code::Code;
use crate::xcode::decks::generic::OUTPUT_DIR;
use std::path::Path;

/// The line of a log saying why a process failed: a Rust panic's message or an `error:`
/// line, else the last line.
pub fn failure_line(path: &Path) -> String {
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
pub fn last_line(path: &Path) -> String {
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

/// The code's version as its run's output gives it: the banner line in `stdout` (the code's
/// binary name when the banner is missing), or an adapter's `version` in its `status.txt`
/// (`None` when the adapter wrote none: ask the adapter).
pub fn version_line(code: Code, stdout: &Path) -> Option<String> {
    if let Code::Adapter(_) = code {
        return status_value(&stdout.parent()?.join(OUTPUT_DIR), "version");
    }
    let text = std::fs::read_to_string(stdout).ok()?;
    let key = match code {
        Code::Lammps | Code::Lammps2025 => "LAMMPS (",
        Code::Liggghts => "LIGGGHTS (",
        Code::Yade => "Yade ",
        Code::Rust | Code::Generic | Code::Adapter(_) => return None,
    };
    text.lines()
        .find(|l| l.contains(key))
        .map(clean_version)
        .or_else(|| Some(code.binary().to_string()))
}

/// `Welcome to Yade 2023.02a` → `Yade 2023.02a`.
pub fn clean_version(line: &str) -> String {
    line.trim().trim_start_matches("Welcome to ").to_string()
}

/// Steps of a LAMMPS/LIGGGHTS run in `dir`: the sum of its `Loop time of … for S steps` lines.
pub fn log_steps(dir: &Path) -> Option<u64> {
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

/// Time-stepping loop time from a code's log in `dir`: the sum of LAMMPS/LIGGGHTS `Loop time
/// of X on P procs for S steps` lines, or YADE's `done: … after S steps, T s`.
pub fn loop_time(code: Code, dir: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(dir.join("stdout.log")).ok()?;
    match code {
        Code::Lammps | Code::Lammps2025 | Code::Liggghts => {
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
        Code::Adapter(_) => status_value(&dir.join(OUTPUT_DIR), "loop_time")?
            .parse()
            .ok(),
        Code::Rust | Code::Generic => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loop_times_from_logs() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("stdout.log"),
            "Loop time of 1.5 on 1 procs for 200 steps with 256 atoms\n\nLoop time of 0.25 on 1 procs for 0 steps with 256 atoms\n",
        )
        .unwrap();
        assert_eq!(loop_time(Code::Lammps, dir.path()), Some(1.75));
        assert_eq!(log_steps(dir.path()), Some(200));
        std::fs::write(
            dir.path().join("stdout.log"),
            "stage 0 …\ndone: time-limit after 400 steps, 3.2 s\n",
        )
        .unwrap();
        assert_eq!(loop_time(Code::Yade, dir.path()), Some(3.2));
    }
}
