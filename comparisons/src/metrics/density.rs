//! GRC07 §V on a 2D snapshot, lengths in units of a: the scattering function I(k) of the
//! solid, its fit by the fractal-blob model (d_F, ξ; GRC07 (28), T.VII) and the holes
//! (⟨R⟩_w; GRC07 (30)).

use super::density_field::{rasterize, scattering, Scattering};
use super::fractal_fit::{fit, FractalFit};
use super::holes::{holes, Holes};
use serde::Serialize;

/// Mesh spacing, in a. GRC07 §V.C uses "of the order of a/100"; a/50 changes d_F and ξ of a
/// 1400-disk packing by less than their fit errors (README, GRC07 §V) at a quarter of the
/// memory.
pub const DEFAULT_SPACING: f64 = 0.02;

/// I(k) is kept up to 2·(2π/a); the fit runs up to 2π/a (GRC07 (26): k ≪ 2π/a).
const K_MAX: f64 = 4.0 * std::f64::consts::PI;
const K_FIT_MAX: f64 = 2.0 * std::f64::consts::PI;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DensityCorrelations {
    /// Mesh spacing used (in a) and nodes along each axis.
    pub spacing: [f64; 2],
    pub nodes: [usize; 2],
    /// I(k), k in 1/a, I in a².
    pub scattering: Scattering,
    /// GRC07 (28) fitted from the maximum of I(k) up to 2π/a; ξ in a.
    pub fit: Option<FractalFit>,
    /// ℓ of GRC07 (27), in a.
    pub ell: Option<f64>,
    /// Holes, radii in a.
    pub holes: Holes,
}

/// `None` unless the cell is 2D (`a`: the length unit, [`super::structure::unit_length`]).
pub fn density_correlations(
    lengths: &[f64],
    position: &[Vec<f64>],
    radius: &[f64],
    a: f64,
    phi: f64,
    spacing: f64,
) -> Option<DensityCorrelations> {
    if lengths.len() != 2 || a.is_nan() || a <= 0.0 {
        return None;
    }
    let l: Vec<f64> = lengths.iter().map(|x| x / a).collect();
    let p: Vec<Vec<f64>> = position
        .iter()
        .map(|x| x.iter().map(|c| c / a).collect())
        .collect();
    let r: Vec<f64> = radius.iter().map(|x| x / a).collect();
    let mesh = rasterize(&l, &p, &r, spacing)?;
    let scattering = scattering(&mesh, K_MAX);
    // GRC07 (28) decreases monotonically; a measured I(k) rises to a maximum first (the
    // steric "bump" GRC07 §V.D sees at 2π/k ≈ 10a), so the fit starts at that maximum.
    let peak = (0..scattering.k.len())
        .filter(|&q| scattering.k[q] <= K_FIT_MAX)
        .max_by(|&a, &b| scattering.intensity[a].total_cmp(&scattering.intensity[b]));
    let k_min = peak.map_or(0.0, |q| scattering.k[q]);
    let fit = fit(&scattering.k, &scattering.intensity, k_min, K_FIT_MAX);
    let ell = fit.as_ref().and_then(|f| f.model.ell(phi));
    let holes = holes(&mesh);
    Some(DensityCorrelations {
        spacing: [mesh.dx, mesh.dy],
        nodes: [mesh.nx, mesh.ny],
        scattering,
        fit,
        ell,
        holes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mandelbrot's fractal percolation: a square of 3^g cells split into 3 × 3, each part
    /// kept with probability `keep`, recursively; the kept unit cells hold a unit disk. The set
    /// has dimension ln(9·keep)/ln 3 from a up to 3^g a. The cell holds `blocks`² independent
    /// such squares, so that correlations stop at the block size (the "blobs" of GRC07 §V.A).
    fn fractal_percolation(keep: f64, g: u32, blocks: usize, seed: u64) -> (f64, Vec<Vec<f64>>) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let side = 3usize.pow(g);
        let mut out = Vec::new();
        for b in 0..blocks * blocks {
            let mut squares = vec![(0usize, 0usize)];
            for level in (0..g).rev() {
                let s = 3usize.pow(level);
                squares = squares
                    .iter()
                    .flat_map(|&(x, y)| (0..9).map(move |q| (x + (q % 3) * s, y + (q / 3) * s)))
                    .filter(|_| rng.gen::<f64>() < keep)
                    .collect();
            }
            let (ox, oy) = ((b % blocks) * side, (b / blocks) * side);
            out.extend(
                squares
                    .iter()
                    .map(|&(x, y)| vec![(ox + x) as f64 + 0.5, (oy + y) as f64 + 0.5]),
            );
        }
        ((blocks * side) as f64, out)
    }

    /// Measured: d_F = 1.523, 1.568, 1.687 for ln(9·keep)/ln 3 = 1.465, 1.631, 1.771 (two
    /// decades of scale, the unit disks' own form factor at the top of the fitted range).
    #[test]
    fn a_synthetic_fractal_has_its_dimension() {
        let mut last = 0.0;
        for keep in [5.0 / 9.0, 6.0 / 9.0, 7.0 / 9.0] {
            let (l, pos) = fractal_percolation(keep, 4, 4, 11);
            let exact = (9.0 * keep).ln() / 3f64.ln();
            let c = density_correlations(&[l, l], &pos, &vec![0.5; pos.len()], 1.0, 0.1, 0.1)
                .expect("2D");
            let f = c.fit.expect("fit");
            assert!(
                (f.model.d_f - exact).abs() < 0.1,
                "d_F {} vs {exact}",
                f.model.d_f
            );
            assert!(f.model.d_f > last, "d_F grows with the kept fraction");
            last = f.model.d_f;
            // Blobs of 81 a: ξ below that, above a.
            assert!(f.model.xi > 1.0 && f.model.xi < 81.0, "ξ = {}", f.model.xi);
        }
    }

    #[test]
    fn only_2d_cells() {
        assert!(density_correlations(&[5.0; 3], &[vec![1.0; 3]], &[0.5], 1.0, 0.1, 0.1).is_none());
    }
}
