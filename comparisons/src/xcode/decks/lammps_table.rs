//! GRC07 attraction (−F0 in contact, −F0(1 − g/D0) over a gap g < D0) as LAMMPS
//! `pair_style table` sections, one per pair of diameter classes (atom types): `pair_style
//! table` sees only r and the types, so the law is exact only when the diameters come in
//! classes (`particles.classes`). The tables are laid out so that LAMMPS's `linear`
//! interpolation is exact to ~1e-7 F0 ([`tables`]).
//!
//! Users: the LAMMPS 2021 deck of an adhesive class scene ([`super::lammps`], with [`Classes::of`])
//! and the bench-only deck of [`super::lammps_bench`].

use super::{num, Start};
use std::fmt::Write as _;

/// Points of each table (`pair_style table linear POINTS`: the same for every table).
pub const POINTS: usize = 10001;
/// Intervals of each table across the attraction range [σ, σ + D0] (the rest covers overlaps).
const RAMP_INTERVALS: usize = 64;
/// Most classes a scene may have for the per-class-pair tables (K(K+1)/2 tables).
pub const MAX_CLASSES: usize = 16;
/// The table file of an exact (class scene) deck.
pub const TABLE: &str = "cohesion.table";

/// Diameter classes of a start: the class diameters, ascending, and each grain's class.
#[derive(Clone, Debug, PartialEq)]
pub struct Classes {
    pub diameter: Vec<f64>,
    pub of: Vec<usize>,
}

impl Classes {
    /// The start's own diameters as classes, when it has at most [`MAX_CLASSES`] distinct ones.
    pub fn of(start: &Start) -> Option<Classes> {
        let mut diameter: Vec<f64> = Vec::new();
        for &d in &start.diameter {
            if !diameter.contains(&d) {
                if diameter.len() == MAX_CLASSES {
                    return None;
                }
                diameter.push(d);
            }
        }
        diameter.sort_by(f64::total_cmp);
        let of = start
            .diameter
            .iter()
            .map(|d| diameter.iter().position(|x| x == d).expect("listed"))
            .collect();
        Some(Classes { diameter, of })
    }

    pub fn len(&self) -> usize {
        self.diameter.len()
    }

    pub fn is_empty(&self) -> bool {
        self.diameter.is_empty()
    }

    /// Contact distance σ = (d_i + d_j)/2 of classes `i`, `j`.
    pub fn sigma(&self, i: usize, j: usize) -> f64 {
        0.5 * (self.diameter[i] + self.diameter[j])
    }
}

/// Table section name of classes `i` ≤ `j` (0-based).
fn section(i: usize, j: usize) -> String {
    format!("C_{}_{}", i + 1, j + 1)
}

/// (r_lo, r_hi) of the table of contact distance `sigma`, as LAMMPS reads them back: r_hi =
/// σ + D0 (the cut-off: no force beyond); r² uniform with [`RAMP_INTERVALS`] steps across
/// [σ², (σ + D0)²], so that both kinks of the law are table points, and the other
/// POINTS − 1 − RAMP_INTERVALS steps below σ² (overlaps up to ~6 % of σ at D0 = 1e-3), r_lo
/// at least σ/2.
fn grid(sigma: f64, d0: f64) -> (f64, f64) {
    let hi = sigma + d0;
    let ramp = hi * hi - sigma * sigma;
    let below = (POINTS - 1 - RAMP_INTERVALS) as f64 * ramp / RAMP_INTERVALS as f64;
    let lo = (sigma * sigma - below).max(0.25 * sigma * sigma).sqrt();
    // Through the deck's text, as LAMMPS parses them.
    let text = |x: f64| num(x).parse::<f64>().expect("num() reads back");
    (text(lo), text(hi))
}

/// Pair cut-off of classes `i`, `j` (the table's r_hi, equal as LAMMPS requires to use the
/// table's points as they are).
pub fn cutoff(classes: &Classes, i: usize, j: usize, d0: f64) -> f64 {
    grid(classes.sigma(i, j), d0).1
}

/// GRC07 attraction at centre distance `r` for contact distance `sigma`: (force along the
/// separation, positive repulsive; energy, zero at σ + D0), F0 = 1.
pub fn attraction(r: f64, sigma: f64, d0: f64) -> (f64, f64) {
    let g = sigma + d0 - r;
    if g >= d0 {
        (-1.0, -0.5 * d0 - (g - d0))
    } else if g > 0.0 {
        (-g / d0, -0.5 * g * g / d0)
    } else {
        (0.0, 0.0)
    }
}

/// r of point `p` of a table on [lo, hi], as LAMMPS recomputes it for `RSQ` tables.
fn point(lo: f64, hi: f64, p: usize) -> f64 {
    (lo * lo + (hi * hi - lo * lo) * p as f64 / (POINTS - 1) as f64).sqrt()
}

/// The attraction table file: one `RSQ` section per class pair with [`POINTS`] points
/// (`pair_style table linear POINTS` then uses them as they are, no spline). LAMMPS
/// interpolates F/r linearly in r², which is exact at the points and off by at most
/// (Δ²/8)·max|d²(F/r)/d(r²)|·r between them: with Δ = 2σD0/64 that is ~2e-7 F0 on the ramp
/// at σ = 1/2 ([`tests`]).
pub fn tables(classes: &Classes, d0: f64, title: &str) -> String {
    let mut s = format!("# GRC07 attraction per class pair: {title}\n");
    let k = classes.len();
    for i in 0..k {
        for j in i..k {
            let sigma = classes.sigma(i, j);
            let (lo, hi) = grid(sigma, d0);
            let _ = write!(
                s,
                "\n{}\nN {POINTS} RSQ {} {}\n\n",
                section(i, j),
                num(lo),
                num(hi)
            );
            for p in 0..POINTS {
                let r = point(lo, hi, p);
                let (f, e) = attraction(r, sigma, d0);
                let _ = writeln!(s, "{} {} {} {}", p + 1, num(r), num(e), num(f));
            }
        }
    }
    s
}

/// `pair_style` and the table `pair_coeff` lines of a deck with these classes (the granular
/// `pair_coeff * * granular …` line follows them).
pub fn pair_lines(classes: &Classes, d0: f64, file: &str) -> String {
    let mut s = format!("pair_style hybrid/overlay granular table linear {POINTS}\n");
    let k = classes.len();
    for i in 0..k {
        for j in i..k {
            let _ = writeln!(
                s,
                "pair_coeff {} {} table {file} {} {}",
                i + 1,
                j + 1,
                section(i, j),
                num(cutoff(classes, i, j, d0))
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// LAMMPS `pair_style table linear` on a matching RSQ table: F/r interpolated linearly in
    /// r² between the points (pair_table.cpp, `compute_table` and `compute`).
    fn lammps_force(lo: f64, hi: f64, sigma: f64, d0: f64, r: f64) -> f64 {
        let inner = lo * lo;
        let delta = (hi * hi - inner) / (POINTS - 1) as f64;
        let f_over_r = |p: usize| {
            let r = (inner + p as f64 * delta).sqrt();
            attraction(r, sigma, d0).0 / r
        };
        let rsq = r * r;
        let p = ((rsq - inner) / delta) as usize;
        let frac = (rsq - (inner + p as f64 * delta)) / delta;
        r * (f_over_r(p) + frac * (f_over_r(p + 1) - f_over_r(p)))
    }

    /// Across overlaps, the contact kink, the ramp and its end, the interpolated attraction is
    /// the law to 1e-6 F0 for every pair of the GRC07 size range (d in [a/2, a]).
    #[test]
    fn tables_interpolate_to_a_millionth_of_f0() {
        let d0 = 1e-3;
        let mut worst: f64 = 0.0;
        for sigma in [0.5, 0.6875, 0.8, 1.0] {
            let (lo, hi) = grid(sigma, d0);
            assert!(
                lo <= sigma * 0.95 && lo >= sigma / 2.0,
                "σ = {sigma}: r_lo = {lo}"
            );
            assert_eq!(hi, sigma + d0);
            for k in 0..20_000 {
                let r = sigma - 0.02 * sigma + (0.02 * sigma + d0) * k as f64 / 20_000.0;
                let err = (lammps_force(lo, hi, sigma, d0, r) - attraction(r, sigma, d0).0).abs();
                worst = worst.max(err);
            }
        }
        assert!(worst < 1e-6, "largest error {worst:e} F0");
    }

    #[test]
    fn attraction_is_grc07() {
        let (sigma, d0) = (0.75, 1e-3);
        assert_eq!(attraction(0.7, sigma, d0).0, -1.0);
        assert!((attraction(sigma + 0.25 * d0, sigma, d0).0 + 0.75).abs() < 1e-12);
        assert_eq!(attraction(sigma + 1.5 * d0, sigma, d0), (0.0, 0.0));
        // Energy: −dE/dr = F on the ramp, continuous at contact.
        let (r, h) = (sigma + 0.4 * d0, 1e-9);
        let de = (attraction(r + h, sigma, d0).1 - attraction(r - h, sigma, d0).1) / (2.0 * h);
        assert!((de + attraction(r, sigma, d0).0).abs() < 1e-5);
        assert!(
            (attraction(sigma, sigma, d0).1 - attraction(sigma - 1e-12, sigma, d0).1).abs() < 1e-9
        );
    }
}
