//! Bench-only LAMMPS deck for adhesive (GRC07) scenes, for throughput only: the diameters are
//! snapped to a few size classes (atom types), the contact law is the cohesionless LAMMPS deck
//! (`pair_style granular`, `hooke`) and the GRC07 attraction (−F0 in contact, −F0(1 − g/D0)
//! over a gap g < D0) is overlaid by `pair_style table linear` with one table per pair of
//! classes (`pair_style hybrid/overlay granular table linear N`). Approximate: the grains are
//! not the scene's (snapped diameters), and the Coulomb cap leaves the table force out. It
//! writes no contact dump (its final state is not compared); the steps come from its log.

use super::{num, Code, Deck, Start};
use grainbench_engine::scene::Law;
use std::fmt::Write as _;

/// Points of each table.
const POINTS: usize = 5000;
/// Size classes (atom types) of [`deck`] as `grainbench bench` uses it.
pub const CLASSES: usize = 5;
/// The table file: its presence marks a deck as bench-only.
pub const TABLE: &str = "cohesion.table";

/// The deck, or why not (no adhesion, or the cohesionless deck is refused).
pub fn deck(start: &Start, classes: usize) -> Result<Deck, String> {
    let Some(cohesion) = start.law().cohesion() else {
        return Err("the scene has no adhesion: use the regular LAMMPS deck".into());
    };
    let d0 = cohesion.d0;
    let classes = classes.max(1);
    let (dmin, dmax) = start
        .diameter
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(a, b), &d| (a.min(d), b.max(d)));
    let width = (dmax - dmin) / classes as f64;
    let class_of = |d: f64| -> usize {
        if width <= 0.0 {
            0
        } else {
            (((d - dmin) / width) as usize).min(classes - 1)
        }
    };
    // Class diameter: the mean of its grains' diameters (empty classes: the bin centre).
    let mut sum = vec![0.0; classes];
    let mut count = vec![0usize; classes];
    for &d in &start.diameter {
        sum[class_of(d)] += d;
        count[class_of(d)] += 1;
    }
    let class_d: Vec<f64> = (0..classes)
        .map(|k| {
            if count[k] > 0 {
                sum[k] / count[k] as f64
            } else {
                dmin + (k as f64 + 0.5) * width
            }
        })
        .collect();
    let types: Vec<usize> = start.diameter.iter().map(|&d| class_of(d)).collect();
    let mut snapped = start.clone();
    let dim = start.dimension as i32;
    let inertia_factor = if start.dimension == 2 { 0.125 } else { 0.1 };
    for (i, &t) in types.iter().enumerate() {
        let d = class_d[t];
        snapped.diameter[i] = d;
        snapped.mass[i] = d.powi(dim);
        snapped.inertia[i] = inertia_factor * snapped.mass[i] * d * d;
    }
    if let Law::Linear { cohesion, .. } = &mut snapped.scene.law {
        *cohesion = None;
    }
    let mut deck = super::deck(&snapped, Code::Lammps).map_err(|e| e.to_string())?;
    let note = format!(
        "adhesion: bench-only deck for throughput: diameters snapped to {classes} size classes (atom types), GRC07 attraction by pair_style table per class pair (hybrid/overlay), Coulomb cap without it; final state not comparable"
    );
    deck.deviations.push(note.clone());
    for (name, text) in deck.files.iter_mut() {
        if name == "in.lammps" {
            *text = input(text, classes, &class_d, d0, &note)?;
        } else if name == "data.lammps" {
            *text = data(text, classes, &types)?;
        }
    }
    deck.files.push((TABLE.into(), tables(&class_d, d0)));
    Ok(deck)
}

fn input(
    text: &str,
    classes: usize,
    class_d: &[f64],
    d0: f64,
    note: &str,
) -> Result<String, String> {
    let mut out = String::new();
    let _ = writeln!(out, "# BENCH-ONLY (throughput): {note}");
    let mut skipping = false;
    for line in text.lines() {
        if line.starts_with("pair_style granular") {
            let _ = writeln!(
                out,
                "pair_style hybrid/overlay granular table linear {POINTS}"
            );
            continue;
        }
        if let Some(rest) = line.strip_prefix("pair_coeff * * ") {
            let _ = writeln!(out, "pair_coeff * * granular {rest}");
            for i in 0..classes {
                for j in i..classes {
                    let cut = 0.5 * (class_d[i] + class_d[j]) + d0;
                    let _ = writeln!(
                        out,
                        "pair_coeff {} {} table cohesion.table C_{}_{} {}",
                        i + 1,
                        j + 1,
                        i + 1,
                        j + 1,
                        num(cut)
                    );
                }
            }
            continue;
        }
        // No contact dump: pair/local is not needed for throughput.
        if line.starts_with("dump fc ") {
            skipping = true;
        }
        if skipping {
            if line.starts_with("undump fc") {
                skipping = false;
            }
            continue;
        }
        let _ = writeln!(out, "{line}");
    }
    if !out.contains("pair_style hybrid/overlay") {
        return Err("the LAMMPS deck has no `pair_style granular` line to overlay".into());
    }
    Ok(out)
}

fn data(text: &str, classes: usize, types: &[usize]) -> Result<String, String> {
    let mut out = String::new();
    let mut in_atoms = false;
    for line in text.lines() {
        if line == "1 atom types" {
            let _ = writeln!(out, "{classes} atom types");
            continue;
        }
        if line.starts_with("Atoms") {
            in_atoms = true;
        } else if line.starts_with("Velocities") {
            in_atoms = false;
        }
        let mut words = line.split_whitespace();
        if in_atoms {
            if let (Some(id), Some("1")) = (words.next(), words.next()) {
                let k: usize = id.parse().map_err(|_| format!("atom id {id:?}"))?;
                let rest: Vec<&str> = words.collect();
                let _ = writeln!(out, "{id} {} {}", types[k - 1] + 1, rest.join(" "));
                continue;
            }
        }
        let _ = writeln!(out, "{line}");
    }
    Ok(out)
}

/// One table per class pair: F = −F0 for r < σ, −F0(1 − (r − σ)/D0) up to σ + D0 (F0 = 1,
/// the force unit), energy its integral from the cutoff.
fn tables(class_d: &[f64], d0: f64) -> String {
    let mut s = String::from("# GRC07 attraction per class pair (grainbench bench-only deck)\n");
    let k = class_d.len();
    for i in 0..k {
        for j in i..k {
            let sigma = 0.5 * (class_d[i] + class_d[j]);
            let (lo, hi) = (0.5 * sigma, sigma + d0);
            let _ = write!(
                s,
                "\nC_{}_{}\nN {POINTS} R {} {}\n\n",
                i + 1,
                j + 1,
                num(lo),
                num(hi)
            );
            for p in 0..POINTS {
                let r = lo + (hi - lo) * p as f64 / (POINTS - 1) as f64;
                let (e, f) = if r < sigma {
                    (-0.5 * d0 - (sigma - r), -1.0)
                } else {
                    let g = hi - r;
                    (-0.5 * g * g / d0, -g / d0)
                };
                let _ = writeln!(s, "{} {} {} {}", p + 1, num(r), num(e), num(f));
            }
        }
    }
    s
}
