//! Pair structure: the pair correlation function g(r) and the gap-dependent coordination
//! number z(h) (AR07 §III.D, Figs. 5, 6, 8–12), as data series.
//!
//! Lengths are in units of `a`, the largest grain diameter (the diameter for equal spheres,
//! the length unit of GRC07 for polydisperse disks): g is a function of the centre distance
//! r/a, z of the surface gap h/a with `h_ij = |r_ij| − R_i − R_j` (negative: overlap).
//!
//! Rattlers (AR07 §III.C): z(h) comes in three variants, I (all grains where the snapshot
//! has them), II (rattlers first fixed onto the backbone, [`super::fixed_rattlers`]) and III
//! (rattlers discarded: only backbone grains and pairs, so that z^III(0) = z*).

use super::neighbors::{for_each_pair, points, valid_cell};
use super::series::Series;
use serde::Serialize;
use std::f64::consts::PI;

/// Pair correlation and z(h) of one snapshot (see the module documentation).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Structure {
    /// The length unit a of the series (largest diameter); `None` without grains.
    pub unit: Option<f64>,
    /// g(r) against r/a, on the snapshot positions (AR07 g^I).
    pub pair_correlation: Option<Series>,
    /// z^I(h) against h/a: all grains as they are.
    pub gap_coordination_i: Option<Series>,
    /// z^II(h): rattlers fixed onto the backbone (`None` if not computed or no backbone).
    pub gap_coordination_ii: Option<Series>,
    /// z^III(h): backbone grains only, z^III(0) = z*.
    pub gap_coordination_iii: Option<Series>,
}

/// The length unit a: the largest diameter, `None` unless positive and finite.
pub fn unit_length(radius: &[f64]) -> Option<f64> {
    let a = 2.0 * radius.iter().copied().fold(0.0, f64::max);
    (a > 0.0 && a.is_finite()).then_some(a)
}

/// g(r) in the periodic orthorhombic cell of any dimension (2 or 3), normalised so that an
/// ideal gas gives 1: `g(r) = 2 N_pairs(shell) Ω / (n (n − 1) V_shell)`. Bins of width
/// `bin_width·a` from 0 to `r_max·a`, `r_max` clipped to half the smallest cell length (so that
/// every shell lies inside the nearest-image domain). Returns bin centres r/a and g.
/// `None` for fewer than 2 grains, a bad cell, `a` or bin width.
pub fn pair_correlation(
    lengths: &[f64],
    position: &[impl std::ops::Deref<Target = [f64]>],
    a: f64,
    bin_width: f64,
    r_max: f64,
) -> Option<Series> {
    let n = position.len();
    if n < 2 || !valid_cell(lengths) || !(a > 0.0 && a.is_finite()) {
        return None;
    }
    if !(bin_width > 0.0 && bin_width.is_finite() && r_max > 0.0) {
        return None;
    }
    let d = lengths.len();
    let w = bin_width * a;
    let half = lengths.iter().copied().fold(f64::INFINITY, f64::min) / 2.0;
    let reach = (r_max * a).min(half);
    let bins = (reach / w).floor() as usize;
    if bins == 0 || bins > 10_000_000 {
        return None;
    }
    let mut count = vec![0u64; bins];
    let pts = points(d, position);
    for_each_pair(lengths, &pts, bins as f64 * w, |_, _, _, r2| {
        let k = (r2.sqrt() / w) as usize;
        if k < bins {
            count[k] += 1;
        }
    });
    let volume: f64 = lengths.iter().product();
    let ball = |r: f64| {
        if d == 2 {
            PI * r * r
        } else {
            4.0 / 3.0 * PI * r * r * r
        }
    };
    let pairs = n as f64 * (n as f64 - 1.0) / 2.0;
    let y = count
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            let shell = ball((k + 1) as f64 * w) - ball(k as f64 * w);
            c as f64 * volume / (pairs * shell)
        })
        .collect();
    Some(Series {
        x: (0..bins).map(|k| (k as f64 + 0.5) * bin_width).collect(),
        y,
    })
}

/// Default grid of h/a for z(h): 0, then 10 points per decade from 1e-5 up to `h_max`
/// (which closes the grid).
pub fn default_gap_grid(h_max: f64) -> Vec<f64> {
    let mut h = vec![0.0];
    if !(h_max > 0.0 && h_max.is_finite()) {
        return h;
    }
    let mut k = 0;
    loop {
        let x = 10f64.powf(-5.0 + k as f64 / 10.0);
        if x >= h_max * (1.0 - 1e-12) {
            break;
        }
        h.push(x);
        k += 1;
    }
    h.push(h_max);
    h
}

/// z(h), AR07 §III.D: the mean number of neighbours of a grain separated from it by a gap
/// `h_ij ≤ h` (i.e. a centre distance ≤ R_i + R_j + h), at each `h/a` of `h_over_a`.
/// `include` restricts grains *and* neighbours to a subset (variant III: the backbone);
/// the mean is over the included grains. `None` if no grain is included, or a bad cell or a.
pub fn gap_coordination(
    lengths: &[f64],
    position: &[impl std::ops::Deref<Target = [f64]>],
    radius: &[f64],
    include: Option<&[bool]>,
    a: f64,
    h_over_a: &[f64],
) -> Option<Series> {
    let n = position.len().min(radius.len());
    let inc = |g: usize| match include {
        None => true,
        Some(s) => s.get(g).copied().unwrap_or(false),
    };
    let count = (0..n).filter(|&g| inc(g)).count();
    if count == 0 || !valid_cell(lengths) || !(a > 0.0 && a.is_finite()) {
        return None;
    }
    let h_max = h_over_a
        .iter()
        .copied()
        .filter(|h| h.is_finite())
        .fold(0.0, f64::max)
        * a;
    let r_max = radius[..n].iter().copied().fold(0.0, f64::max);
    let pts = points(lengths.len(), &position[..n]);
    let mut gaps = Vec::new();
    for_each_pair(
        lengths,
        &pts,
        2.0 * r_max + h_max.max(0.0) + 1e-9 * a,
        |i, j, _, r2| {
            if inc(i) && inc(j) {
                let h = r2.sqrt() - radius[i] - radius[j];
                if h <= h_max {
                    gaps.push(h);
                }
            }
        },
    );
    gaps.sort_unstable_by(f64::total_cmp);
    let y = h_over_a
        .iter()
        .map(|&h| 2.0 * gaps.partition_point(|&g| g <= h * a) as f64 / count as f64)
        .collect();
    Some(Series {
        x: h_over_a.to_vec(),
        y,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::fixtures::{lattice, Lcg};

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1.0)
    }

    /// Square lattice of spacing a: g vanishes below a, and the bin holding each shell of
    /// m neighbours at distance r carries exactly m/2 pairs per grain, so
    /// g = m Ω / ((n − 1) π (r2² − r1²)); bins between shells are empty.
    #[test]
    fn square_lattice_pair_correlation_peaks() {
        let k = 10;
        let (l, _, p, _) = lattice(2, k, 1.0, 0.5, 1.0);
        let w = 0.07;
        let g = pair_correlation(&l, &p, 1.0, w, 100.0).unwrap();
        // r_max clipped to L/2 = 5: 71 bins.
        assert_eq!(g.x.len(), 71);
        assert!(close(g.x[0], 0.035, 1e-12));
        let n = (k * k) as f64;
        let shells = [
            (1.0, 4.0),
            (2f64.sqrt(), 4.0),
            (2.0, 4.0),
            (5f64.sqrt(), 8.0),
            (8f64.sqrt(), 4.0),
            (3.0, 4.0),
            (10f64.sqrt(), 8.0),
            (13f64.sqrt(), 8.0),
        ];
        let mut expected = vec![0.0; g.x.len()];
        for (r, m) in shells {
            let b = (r / w) as usize;
            let (r1, r2) = (b as f64 * w, (b + 1) as f64 * w);
            expected[b] += m * 100.0 / ((n - 1.0) * PI * (r2 * r2 - r1 * r1));
        }
        let checked = (13f64.sqrt() / w) as usize + 1;
        for (b, (got, want)) in g.y.iter().zip(&expected).take(checked).enumerate() {
            assert!(close(*got, *want, 1e-12), "bin {b}: {got} vs {want}");
        }
        // In units of a: the same lattice with a = 2 puts the first peak at r/a = 1/2.
        let g2 = pair_correlation(&l, &p, 2.0, w / 2.0, 100.0).unwrap();
        assert_eq!(g2.y, g.y);
    }

    /// Ideal gas (uniform random points) in 3D and 2D: g ≈ 1 within the Poisson noise of
    /// each bin, and the mean over the range is 1 within 1 %.
    #[test]
    fn ideal_gas_pair_correlation_is_one() {
        let mut rng = Lcg(5);
        for (l, n) in [(vec![10.0, 11.0, 12.0], 4000), (vec![40.0, 30.0], 4000)] {
            let p: Vec<Vec<f64>> = (0..n)
                .map(|_| l.iter().map(|x| x * rng.next()).collect())
                .collect();
            let g = pair_correlation(&l, &p, 1.0, 0.1, 4.0).unwrap();
            assert_eq!(g.x.len(), 40);
            let volume: f64 = l.iter().product();
            let pairs = (n * (n - 1) / 2) as f64;
            let mut sum = 0.0;
            for (x, y) in g.x.iter().zip(&g.y).skip(5) {
                let r1 = x - 0.05;
                let shell = if l.len() == 2 {
                    PI * ((r1 + 0.1).powi(2) - r1 * r1)
                } else {
                    4.0 / 3.0 * PI * ((r1 + 0.1).powi(3) - r1.powi(3))
                };
                let expected_pairs = pairs * shell / volume;
                let sigma = 1.0 / expected_pairs.sqrt();
                assert!((y - 1.0).abs() < 5.0 * sigma, "r = {x}: g = {y}");
                sum += y;
            }
            assert!((sum / 35.0 - 1.0).abs() < 0.01);
        }
    }

    #[test]
    fn pair_correlation_rejects_degenerate_input() {
        let p = vec![vec![0.0, 0.0]];
        assert!(pair_correlation(&[2.0, 2.0], &p, 1.0, 0.1, 1.0).is_none());
        let p = vec![vec![0.0, 0.0], vec![0.5, 0.0]];
        assert!(pair_correlation(&[2.0, 2.0], &p, 0.0, 0.1, 1.0).is_none());
        assert!(pair_correlation(&[2.0, 0.0], &p, 1.0, 0.1, 1.0).is_none());
        assert!(pair_correlation(&[2.0, 2.0], &p, 1.0, 0.0, 1.0).is_none());
        assert!(pair_correlation(&[2.0, 2.0], &p, 1.0, 5.0, 1.0).is_none());
    }

    #[test]
    fn gap_grid() {
        let h = default_gap_grid(1.0);
        assert_eq!(h[0], 0.0);
        assert!(close(h[1], 1e-5, 1e-12));
        assert_eq!(h.len(), 52);
        assert_eq!(*h.last().unwrap(), 1.0);
        assert!(h.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(default_gap_grid(0.0), vec![0.0]);
    }

    /// Square lattice of disks of diameter 1 at spacing 0.999 (overlap 0.001): gaps of the
    /// shells are −0.001 (4), √2·0.999 − 1 (4), 2·0.999 − 1 (4), √5·0.999 − 1 (8): z(h) steps
    /// from 4 to 8, 12, 20 exactly there. Variant III with one grain left out: its 4 contacts
    /// go from 4 neighbours each.
    #[test]
    fn square_lattice_gap_coordination_steps() {
        let s = 0.999;
        let (l, r, p, _) = lattice(2, 8, s, 0.5, 1.0);
        let h1 = 2f64.sqrt() * s - 1.0;
        let h2 = 2.0 * s - 1.0;
        let h3 = 5f64.sqrt() * s - 1.0;
        let grid = [
            -0.002,
            -0.0005,
            0.0,
            h1 - 1e-9,
            h1 + 1e-9,
            h2 - 1e-9,
            h2 + 1e-9,
            h3 - 1e-9,
            h3 + 1e-9,
        ];
        let z = gap_coordination(&l, &p, &r, None, 1.0, &grid).unwrap();
        assert_eq!(z.x, grid.to_vec());
        assert_eq!(z.y, vec![0.0, 4.0, 4.0, 4.0, 8.0, 8.0, 12.0, 12.0, 20.0]);
        // Leave grain 0 out: 63 grains, 128 − 4 contacts.
        let mut inc = vec![true; 64];
        inc[0] = false;
        let z3 = gap_coordination(&l, &p, &r, Some(&inc), 1.0, &[0.0]).unwrap();
        assert!(close(z3.y[0], 2.0 * 124.0 / 63.0, 1e-15));
        assert!(gap_coordination(&l, &p, &r, Some(&[false; 64]), 1.0, &[0.0]).is_none());
        // Lengths in units of a: a = 2 halves every h/a.
        let z2 = gap_coordination(&l, &p, &r, None, 2.0, &[h1 / 2.0 + 1e-9]).unwrap();
        assert_eq!(z2.y, vec![8.0]);
    }
}
