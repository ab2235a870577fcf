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
    position: &[impl std::ops::Deref<Target = [f64]>],
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
    let fit = fit_from_peak(&scattering);
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

/// I(k) averaged over several samples and its fit by GRC07 (28): GRC07 §V.D fits "FFT
/// calculations … averaged over different characteristic density maps", where one 1400-disk
/// sample is too small to fix ξ (README, GRC07 §V).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeanScattering {
    /// Mean I(k) over the samples and its standard error (sample s.d./√n) in shells of the
    /// widest sample spacing 2π/L (the smallest cell), k the mean |k| of the shell.
    pub scattering: Scattering,
    pub samples: usize,
    /// GRC07 (28) fitted from the maximum of the mean up to 2π/a.
    pub fit: Option<FractalFit>,
}

/// The mean of the samples' I(k) on a common set of shells, kept where every sample has
/// wavevectors; `None` for fewer than two samples.
pub fn mean_scattering(samples: &[&DensityCorrelations]) -> Option<MeanScattering> {
    if samples.len() < 2 {
        return None;
    }
    let two_pi = 2.0 * std::f64::consts::PI;
    // Each sample's shells are 2π/L wide (L its longer side); the common ones, the widest.
    let dk = samples
        .iter()
        .map(|d| two_pi / (d.nodes[0] as f64 * d.spacing[0]).max(d.nodes[1] as f64 * d.spacing[1]))
        .fold(0.0, f64::max);
    let shells = (K_MAX / dk).floor() as usize + 1;
    // Per sample and common shell: Σ count·k, Σ count·I, Σ count.
    let mut per: Vec<Vec<(f64, f64, usize)>> = vec![vec![(0.0, 0.0, 0); shells]; samples.len()];
    for (acc, d) in per.iter_mut().zip(samples) {
        let s = &d.scattering;
        for q in 0..s.k.len() {
            let b = (s.k[q] / dk).round() as usize;
            if let Some(cell) = acc.get_mut(b) {
                let c = s.count[q];
                cell.0 += c as f64 * s.k[q];
                cell.1 += c as f64 * s.intensity[q];
                cell.2 += c;
            }
        }
    }
    let n = samples.len() as f64;
    let mut mean = Scattering {
        k: Vec::new(),
        intensity: Vec::new(),
        error: Vec::new(),
        count: Vec::new(),
    };
    for b in 0..shells {
        if per.iter().any(|acc| acc[b].2 == 0) {
            continue;
        }
        let ks: Vec<f64> = per.iter().map(|acc| acc[b].0 / acc[b].2 as f64).collect();
        let is: Vec<f64> = per.iter().map(|acc| acc[b].1 / acc[b].2 as f64).collect();
        let i_mean = is.iter().sum::<f64>() / n;
        let sd = crate::stats::sample_sd(&is).unwrap_or(0.0);
        mean.k.push(ks.iter().sum::<f64>() / n);
        mean.intensity.push(i_mean);
        mean.error.push(sd / n.sqrt());
        mean.count.push(per.iter().map(|acc| acc[b].2).sum());
    }
    let fit = fit_from_peak(&mean);
    Some(MeanScattering {
        scattering: mean,
        samples: samples.len(),
        fit,
    })
}

/// GRC07 (28) decreases monotonically; a measured I(k) rises to a maximum first (the steric
/// "bump" GRC07 §V.D sees at 2π/k ≈ 10a), so the fit starts at that maximum.
fn fit_from_peak(s: &Scattering) -> Option<FractalFit> {
    let peak = (0..s.k.len())
        .filter(|&q| s.k[q] <= K_FIT_MAX)
        .max_by(|&a, &b| s.intensity[a].total_cmp(&s.intensity[b]));
    let k_min = peak.map_or(0.0, |q| s.k[q]);
    fit(&s.k, &s.intensity, k_min, K_FIT_MAX)
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

    #[test]
    fn the_mean_of_equal_samples_is_the_sample() {
        let (l, pos) = fractal_percolation(6.0 / 9.0, 4, 2, 3);
        let c = density_correlations(&[l, l], &pos, &vec![0.5; pos.len()], 1.0, 0.1, 0.1).unwrap();
        assert!(mean_scattering(&[&c]).is_none(), "one sample has no mean");
        let m = mean_scattering(&[&c, &c, &c]).expect("three samples");
        assert_eq!(m.samples, 3);
        let s = &c.scattering;
        let kept: Vec<usize> = (0..s.k.len()).filter(|&q| s.count[q] > 0).collect();
        assert_eq!(m.scattering.k.len(), kept.len());
        for (j, &q) in kept.iter().enumerate() {
            assert!((m.scattering.k[j] - s.k[q]).abs() < 1e-12 * s.k[q]);
            assert!((m.scattering.intensity[j] - s.intensity[q]).abs() < 1e-12 * s.intensity[q]);
            assert!(m.scattering.error[j] < 1e-12 * s.intensity[q]);
            assert_eq!(m.scattering.count[j], 3 * s.count[q]);
        }
        // The same fit, to the minimiser's tolerance.
        let (a, b) = (m.fit.unwrap().model, c.fit.unwrap().model);
        assert!(
            (a.d_f - b.d_f).abs() < 1e-6 && (a.xi - b.xi).abs() < 1e-6 * b.xi,
            "{a:?} {b:?}"
        );
    }

    /// Samples in cells of 324 a and 243 a: the mean lies on the shells of the smaller cell
    /// (2π/243 wide) and keeps the set's dimension (1.631; each sample alone: 1.568, above).
    #[test]
    fn samples_of_different_sizes_average_on_the_widest_shells() {
        let keep: f64 = 6.0 / 9.0;
        let exact = (9.0 * keep).ln() / 3f64.ln();
        let samples: Vec<DensityCorrelations> = [(4, 5), (3, 6), (4, 7)]
            .into_iter()
            .map(|(blocks, seed)| {
                let (l, pos) = fractal_percolation(keep, 4, blocks, seed);
                density_correlations(&[l, l], &pos, &vec![0.5; pos.len()], 1.0, 0.1, 0.1).unwrap()
            })
            .collect();
        let refs: Vec<&DensityCorrelations> = samples.iter().collect();
        let m = mean_scattering(&refs).expect("mean");
        let dk = 2.0 * std::f64::consts::PI / 243.0;
        for (&k, &i) in m.scattering.k.iter().zip(&m.scattering.intensity) {
            let centre = (k / dk).round() * dk;
            assert!((k - centre).abs() <= 0.5 * dk, "k = {k} off its shell");
            assert!(i > 0.0);
        }
        assert!(m.scattering.error.iter().any(|&e| e > 0.0));
        let f = m.fit.expect("fit");
        assert!(
            (f.model.d_f - exact).abs() < 0.1,
            "d_F {} vs {exact}",
            f.model.d_f
        );
        assert!(f.model.xi > 1.0 && f.model.xi < 81.0, "ξ = {}", f.model.xi);
    }
}
