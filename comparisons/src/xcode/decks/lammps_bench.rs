//! A bench-only LAMMPS deck for adhesive scenes of continuous sizes, for throughput: diameters
//! snapped to a few classes, the cohesionless LAMMPS deck with the GRC07 attraction tables of
//! [`super::lammps_table`] overlaid (`pair_style hybrid/overlay granular table linear N`). It is
//! approximate (the grains are not the scene's) and writes no contact dump (its final state is
//! not compared); the steps come from its log.

use super::lammps_table::{pair_lines, tables, Classes};
use super::{Code, Deck, Start};
use grainbench_engine::scene::Law;
use std::fmt::Write as _;

/// Size classes (atom types) of [`deck`] as `grainbench bench` uses it.
pub const CLASSES: usize = 5;
/// The table file of the bench-only deck: its presence marks a deck as throughput only.
pub const BENCH_TABLE: &str = "cohesion-snapped.table";

/// The bench-only deck, or why not (no adhesion, or the cohesionless deck is refused).
pub fn deck(start: &Start, classes: usize) -> Result<Deck, String> {
    let Some(cohesion) = start.law().cohesion() else {
        return Err("the scene has no adhesion: use the regular LAMMPS deck".into());
    };
    let d0 = cohesion.d0;
    let snapped_classes = snap(start, classes.max(1));
    let classes = snapped_classes.len();
    let mut snapped = start.clone();
    let dim = start.dimension as i32;
    let inertia_factor = if start.dimension == 2 { 0.125 } else { 0.1 };
    for (i, &t) in snapped_classes.of.iter().enumerate() {
        let d = snapped_classes.diameter[t];
        snapped.diameter[i] = d;
        snapped.mass[i] = d.powi(dim);
        snapped.inertia[i] = inertia_factor * snapped.mass[i] * d * d;
    }
    if let Law::Linear { cohesion, .. } = &mut snapped.scene.law {
        *cohesion = None;
    }
    snapped.scene.particles.classes = None;
    let mut deck = super::deck(&snapped, Code::Lammps).map_err(|e| e.to_string())?;
    let note = format!(
        "adhesion: bench-only deck for throughput: diameters snapped to {classes} size classes (atom types), GRC07 attraction by pair_style table per class pair (hybrid/overlay), Coulomb cap without it; final state not comparable"
    );
    deck.deviations.push(note.clone());
    for (name, text) in deck.files.iter_mut() {
        if name == "in.lammps" {
            *text = input(text, &snapped_classes, d0, &note)?;
        } else if name == "data.lammps" {
            *text = data(text, classes, &snapped_classes.of)?;
        }
    }
    deck.files.push((
        BENCH_TABLE.into(),
        tables(&snapped_classes, d0, "grainbench bench-only deck"),
    ));
    Ok(deck)
}

/// `k` classes of equal width over the start's diameters, each at the mean diameter of its
/// grains (empty classes: the bin centre).
fn snap(start: &Start, k: usize) -> Classes {
    let (dmin, dmax) = start
        .diameter
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(a, b), &d| (a.min(d), b.max(d)));
    let width = (dmax - dmin) / k as f64;
    let class_of = |d: f64| -> usize {
        if width <= 0.0 {
            0
        } else {
            (((d - dmin) / width) as usize).min(k - 1)
        }
    };
    let mut sum = vec![0.0; k];
    let mut count = vec![0usize; k];
    for &d in &start.diameter {
        sum[class_of(d)] += d;
        count[class_of(d)] += 1;
    }
    let diameter = (0..k)
        .map(|c| {
            if count[c] > 0 {
                sum[c] / count[c] as f64
            } else {
                dmin + (c as f64 + 0.5) * width
            }
        })
        .collect();
    Classes {
        diameter,
        of: start.diameter.iter().map(|&d| class_of(d)).collect(),
    }
}

fn input(text: &str, classes: &Classes, d0: f64, note: &str) -> Result<String, String> {
    let mut out = String::new();
    let _ = writeln!(out, "# BENCH-ONLY (throughput): {note}");
    let mut skipping = false;
    let mut overlaid = false;
    for line in text.lines() {
        if line.starts_with("pair_style granular") {
            continue;
        }
        if let Some(rest) = line.strip_prefix("pair_coeff * * ") {
            if !overlaid {
                out.push_str(&pair_lines(classes, d0, BENCH_TABLE));
                overlaid = true;
            }
            let _ = writeln!(out, "pair_coeff * * granular {rest}");
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
    if !overlaid {
        return Err("the LAMMPS deck has no `pair_coeff * *` line to overlay".into());
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
