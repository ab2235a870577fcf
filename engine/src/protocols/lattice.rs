//! Crystal lattices for initial states: monodisperse spheres of diameter a = 1 on an FCC
//! lattice at a given packing fraction, to be melted by event-driven dynamics (AR07 §III).

use nalgebra::Vector3;
use std::f64::consts::PI;

/// FCC lattice of `k = cells_per_side` conventional cubic cells per side in a cubic periodic
/// box: returns the box side L and the reduced positions (in [0,1)³) of the n = 4k³ sites,
/// for spheres of diameter 1 at `packing_fraction` Φ, so that n π/6 = Φ L³. The lattice is
/// shifted by a quarter of a conventional cell, so no site lies on the box faces.
pub fn fcc(cells_per_side: usize, packing_fraction: f64) -> (f64, Vec<Vector3<f64>>) {
    let k = cells_per_side;
    let side = k as f64 * fcc_cell_side(packing_fraction);
    let basis = [
        [0.0, 0.0, 0.0],
        [0.5, 0.5, 0.0],
        [0.5, 0.0, 0.5],
        [0.0, 0.5, 0.5],
    ];
    let mut s = Vec::with_capacity(4 * k * k * k);
    for z in 0..k {
        for y in 0..k {
            for x in 0..k {
                for b in &basis {
                    let site = |i: usize, o: f64| (i as f64 + o + 0.25) / k as f64;
                    s.push(Vector3::new(site(x, b[0]), site(y, b[1]), site(z, b[2])));
                }
            }
        }
    }
    (side, s)
}

/// `Some(k)` when n = 4k³ (an FCC lattice of k cells per side holds n sites), else `None`.
pub fn fcc_cells_for(n: usize) -> Option<usize> {
    let k = ((n as f64 / 4.0).cbrt().round() as usize).max(1);
    (4 * k * k * k == n).then_some(k)
}

/// Side of the conventional cubic FCC cell (4 spheres of diameter 1) at packing fraction Φ:
/// a_c³ = 4 (π/6) / Φ.
pub fn fcc_cell_side(packing_fraction: f64) -> f64 {
    (2.0 * PI / (3.0 * packing_fraction)).cbrt()
}

/// Nearest-neighbour distance a_c/√2 of the FCC lattice at packing fraction Φ (1 at the close
/// packing Φ = π/(3√2)).
pub fn fcc_nearest_neighbour(packing_fraction: f64) -> f64 {
    fcc_cell_side(packing_fraction) / 2f64.sqrt()
}

/// Translational order parameter of the FCC lattice built by [`fcc`] with `cells_per_side`
/// cells (Verlet's melting indicator): the mean over the three axes of |⟨exp(i k·r)⟩| for the
/// reciprocal lattice vectors k = (4π/a_c) e_α. It is 1 on the lattice, about 1/√n in a
/// fluid.
pub fn fcc_order_parameter(s: &[Vector3<f64>], cells_per_side: usize) -> f64 {
    if s.is_empty() {
        return 0.0;
    }
    let q = 4.0 * PI * cells_per_side as f64;
    let mut total = 0.0;
    for a in 0..3 {
        let (mut c, mut sn) = (0.0, 0.0);
        for x in s {
            let (si, co) = (q * x[a]).sin_cos();
            c += co;
            sn += si;
        }
        total += (c * c + sn * sn).sqrt() / s.len() as f64;
    }
    total / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fcc_counts_spacing_and_fraction() {
        for k in 1..=4 {
            let n = 4 * k * k * k;
            assert_eq!(fcc_cells_for(n), Some(k));
            assert_eq!(fcc_cells_for(n + 1), None);
            let phi = 0.45;
            let (side, s) = fcc(k, phi);
            assert_eq!(s.len(), n);
            let fraction = n as f64 * PI / 6.0 / side.powi(3);
            assert!((fraction - phi).abs() < 1e-14, "{fraction}");
            assert!(s.iter().all(|x| x.iter().all(|&c| (0.0..1.0).contains(&c))));
            // Nearest-neighbour distance, minimum image, all pairs: 12 neighbours each.
            let nn = fcc_nearest_neighbour(phi);
            let mut dmin = f64::INFINITY;
            let mut count = vec![0usize; n];
            for i in 0..n {
                for j in i + 1..n {
                    let mut d = s[j] - s[i];
                    d.iter_mut().for_each(|c| *c -= c.round());
                    let r = d.norm() * side;
                    dmin = dmin.min(r);
                    if (r - nn).abs() < 1e-9 {
                        count[i] += 1;
                        count[j] += 1;
                    }
                }
            }
            assert!((dmin - nn).abs() < 1e-12, "k = {k}: {dmin} vs {nn}");
            if k >= 2 {
                assert!(count.iter().all(|&c| c == 12), "k = {k}");
            }
            assert!((fcc_order_parameter(&s, k) - 1.0).abs() < 1e-9);
        }
        assert_eq!(fcc_cells_for(0), None);
        // Close packing: touching spheres.
        assert!((fcc_nearest_neighbour(PI / (3.0 * 2f64.sqrt())) - 1.0).abs() < 1e-15);
    }
}
