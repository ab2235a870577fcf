//! Initial states: a random non-overlapping granular gas at solid fraction Φ_I (GRC07 §III.A,
//! AR07 §IV.A), by random sequential addition with a cell grid, largest grains first.

use crate::geometry::{Dim, VectorOps};
use crate::neighbor::branch;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Random gas: reduced positions, diameters and cell lengths.
pub struct Gas<D: Dim> {
    pub s: Vec<D::V>,
    pub diameter: Vec<f64>,
    pub l: D::V,
}

/// Diameters uniform in [d_min, 1] (GRC07 §II.A with d_min = 1/2; monodisperse when 1), or,
/// with `classes = Some(K)`, uniform among the K diameters d_min + (1 − d_min) k/(K − 1).
pub fn diameters(n: usize, d_min: f64, classes: Option<usize>, rng: &mut ChaCha8Rng) -> Vec<f64> {
    (0..n)
        .map(|_| match classes {
            _ if d_min >= 1.0 => 1.0,
            Some(k) if k >= 2 => class_diameter(rng.gen_range(0..k), k, d_min),
            _ => rng.gen_range(d_min..=1.0),
        })
        .collect()
}

/// Diameter of class `c` of `k` spanning [d_min, 1].
pub fn class_diameter(c: usize, k: usize, d_min: f64) -> f64 {
    d_min + (1.0 - d_min) * c as f64 / (k - 1) as f64
}

/// Places `n` grains at random, without overlap, in a cubic (square) cell of solid fraction
/// `phi`. Fails with a message if the placement stalls.
pub fn random_gas<D: Dim>(
    n: usize,
    d_min: f64,
    classes: Option<usize>,
    phi: f64,
    seed: u64,
) -> Result<Gas<D>, String> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut diameter = diameters(n, d_min, classes, &mut rng);
    // Largest first: they are the hardest to place.
    diameter.sort_by(|a, b| b.total_cmp(a));
    let solid: f64 = diameter.iter().map(|&d| D::grain_volume(d)).sum();
    let side = (solid / phi).powf(1.0 / D::D as f64);
    let mut l = D::V::zero();
    for a in 0..D::D {
        l[a] = side;
    }
    // Grid of cells of side ≥ 1 (the largest diameter), at most ~4 cells a grain: a dilute
    // gas (a tiny `phi`) gets larger cells, not a grid beyond memory (or an overflow).
    let m_max = ((4 * n) as f64).powf(1.0 / D::D as f64).floor().max(1.0);
    let m = side.floor().clamp(1.0, m_max) as usize;
    let total = m.pow(D::D as u32);
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); total];
    let cell_index = |s: &D::V| -> [usize; 3] {
        let mut c = [0usize; 3];
        for a in 0..D::D {
            c[a] = ((s[a] * m as f64) as usize).min(m - 1);
        }
        c
    };
    let flat = |c: [usize; 3]| -> usize {
        let mut k = 0;
        for a in (0..D::D).rev() {
            k = k * m + c[a];
        }
        k
    };
    let mut s: Vec<D::V> = Vec::with_capacity(n);
    let max_tries = 200_000;
    for (k, &d) in diameter.iter().enumerate() {
        let mut placed = false;
        for _ in 0..max_tries {
            let mut x = D::V::zero();
            for a in 0..D::D {
                x[a] = rng.gen::<f64>();
            }
            let c = cell_index(&x);
            let reach: i64 = if m >= 3 { 1 } else { 0 };
            let mut ok = true;
            'search: for dz in -reach..=reach {
                if D::D == 2 && dz != 0 {
                    continue;
                }
                for dy in -reach..=reach {
                    for dx in -reach..=reach {
                        let mut cc = c;
                        for (a, off) in [dx, dy, dz].iter().enumerate().take(D::D) {
                            cc[a] = ((c[a] as i64 + off).rem_euclid(m as i64)) as usize;
                        }
                        let bucket = if m >= 3 {
                            &grid[flat(cc)]
                        } else {
                            // Small cells: compare with everything placed so far.
                            &grid[0]
                        };
                        for &j in bucket {
                            let j = j as usize;
                            let r = branch::<D>(&x, &s[j], &l);
                            let contact = 0.5 * (d + diameter[j]);
                            if r.norm_squared() < contact * contact {
                                ok = false;
                                break 'search;
                            }
                        }
                    }
                }
            }
            if ok {
                let slot = if m >= 3 { flat(c) } else { 0 };
                grid[slot].push(k as u32);
                s.push(x);
                placed = true;
                break;
            }
        }
        if !placed {
            return Err(format!(
                "random placement stalled at grain {} of {n} (diameter {d:.3}) after {max_tries} tries: Φ_I = {phi} is too dense for random sequential addition; lower initial.packing_fraction",
                k + 1
            ));
        }
    }
    // Label the grains along a Morton curve so that neighbours in space are near in memory
    // (the force and gather passes then read partners from cache, most of all at large N).
    let order = crate::neighbor::morton_order::<D>(&s);
    let s = order.iter().map(|&k| s[k as usize]).collect();
    let diameter = order.iter().map(|&k| diameter[k as usize]).collect();
    Ok(Gas { s, diameter, l })
}

/// Maxwell velocities with root-mean-square speed `rms`, zero total momentum: each component
/// Gaussian with variance ∝ 1/m (one temperature for the mixture).
pub fn maxwell_velocities<D: Dim>(mass: &[f64], rms: f64, seed: u64) -> Vec<D::V> {
    maxwell_velocities_spread::<D>(mass, rms, seed, true)
}

/// As [`maxwell_velocities`]; with `equipartition = false` every grain draws from the same
/// Gaussian whatever its mass (the mass-weighted mean velocity is still removed).
pub fn maxwell_velocities_spread<D: Dim>(
    mass: &[f64],
    rms: f64,
    seed: u64,
    equipartition: bool,
) -> Vec<D::V> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x9e37_79b9_7f4a_7c15);
    let n = mass.len();
    let mut u: Vec<D::V> = (0..n)
        .map(|i| {
            let mut v = D::V::zero();
            for a in 0..D::D {
                let g: f64 = StandardNormal.sample(&mut rng);
                v[a] = if equipartition { g / mass[i].sqrt() } else { g };
            }
            v
        })
        .collect();
    let mtot: f64 = mass.iter().sum();
    let mut p = D::V::zero();
    for i in 0..n {
        p += u[i] * mass[i];
    }
    let vcm = p * (1.0 / mtot);
    for v in u.iter_mut() {
        *v -= vcm;
    }
    let msq: f64 = u.iter().map(|v| v.norm_squared()).sum::<f64>() / n as f64;
    if msq > 0.0 {
        let f = rms / msq.sqrt();
        for v in u.iter_mut() {
            *v = *v * f;
        }
    }
    u
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{D2, D3};

    fn no_overlap<D: Dim>(g: &Gas<D>) {
        for i in 0..g.s.len() {
            for j in i + 1..g.s.len() {
                let r = branch::<D>(&g.s[i], &g.s[j], &g.l).norm();
                assert!(r >= 0.5 * (g.diameter[i] + g.diameter[j]) * (1.0 - 1e-12));
            }
        }
    }

    #[test]
    fn gas_reaches_fraction_without_overlap() {
        let g = random_gas::<D2>(400, 0.5, None, 0.5, 7).unwrap();
        no_overlap(&g);
        let solid: f64 = g.diameter.iter().map(|&d| D2::grain_volume(d)).sum();
        assert!((solid / D2::product(g.l) - 0.5).abs() < 1e-12);
        let g3 = random_gas::<D3>(300, 1.0, None, 0.3, 7).unwrap();
        no_overlap(&g3);
    }

    #[test]
    fn classes_give_k_diameters_each_drawn() {
        let g = random_gas::<D2>(2000, 0.5, Some(5), 0.3, 3).unwrap();
        no_overlap(&g);
        for k in 0..5 {
            let d = class_diameter(k, 5, 0.5);
            let count = g.diameter.iter().filter(|&&x| x == d).count();
            // 400 expected per class; 5 binomial s.d. ≈ 90.
            assert!((310..=490).contains(&count), "class {k} (d = {d}): {count}");
        }
        assert_eq!(class_diameter(0, 5, 0.5), 0.5);
        assert_eq!(class_diameter(4, 5, 0.5), 1.0);
    }

    /// A dilute gas (`packing_fraction = 1e-300`, from tests/fuzz.rs) must not overflow
    /// `m.pow(d)` when sizing the grid.
    #[test]
    fn a_dilute_gas_gets_a_small_grid() {
        for phi in [1e-300, 1e-9] {
            let g = random_gas::<D3>(20, 1.0, None, phi, 1).unwrap();
            assert_eq!(g.s.len(), 20);
            no_overlap(&g);
        }
    }

    #[test]
    fn too_dense_gas_is_refused() {
        let e = random_gas::<D3>(200, 1.0, None, 0.6, 1).err().unwrap();
        assert!(e.contains("initial.packing_fraction"), "{e}");
    }

    /// Equipartition gives light and heavy grains the same mean kinetic energy; the
    /// mass-independent draw the same mean v². Both: zero momentum, mean v² = rms².
    #[test]
    fn maxwell_spreads_by_mass_or_not() {
        let n = 20000;
        let mass: Vec<f64> = (0..n)
            .map(|i| if i % 2 == 0 { 0.25 } else { 1.0 })
            .collect();
        for equi in [true, false] {
            let u = maxwell_velocities_spread::<D2>(&mass, 0.3, 5, equi);
            let p = (0..n).fold(<D2 as Dim>::V::zero(), |p, i| p + u[i] * mass[i]);
            assert!(p.norm() < 1e-9, "{p:?}");
            let msq = u.iter().map(|v| v.norm_squared()).sum::<f64>() / n as f64;
            assert!((msq - 0.09).abs() < 1e-12, "{msq}");
            let mean = |k: usize| {
                (k..n).step_by(2).map(|i| u[i].norm_squared()).sum::<f64>() / (n / 2) as f64
            };
            // v² of the light (m = 1/4) over the heavy (m = 1) grains: 4 or 1.
            let ratio = mean(0) / mean(1);
            let want = if equi { 4.0 } else { 1.0 };
            assert!((ratio / want - 1.0).abs() < 0.05, "{equi}: {ratio}");
        }
    }
}
