//! Data series for plots: a curve `y(x)` ([`Series`]) and a density histogram ([`Histogram`]).

use serde::Serialize;

/// Most bins a histogram gets; a wider bin is used if the range asks for more.
pub const MAX_BINS: usize = 10_000;

/// A curve `y(x)`, `x` increasing.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Series {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
}

/// A histogram normalised as a probability density: `x` are the bin centres, `y` the
/// densities, so that `Σ y · bin_width = 1` over the `samples` values binned.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Histogram {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub bin_width: f64,
    /// Number of values binned.
    pub samples: usize,
}

impl Histogram {
    /// Bins the finite `values` into bins `[start + k w, start + (k+1) w)`, `k < bins`
    /// (values beyond the last edge go to the last bin, before the first to the first).
    /// `None` without finite values, or for a bad width or range.
    pub fn density(values: &[f64], start: f64, width: f64, bins: usize) -> Option<Histogram> {
        let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
        if finite.is_empty() || !(width > 0.0 && width.is_finite() && start.is_finite()) {
            return None;
        }
        let bins = bins.clamp(1, MAX_BINS);
        let mut count = vec![0usize; bins];
        for v in &finite {
            let k = ((v - start) / width).floor();
            let k = if k < 0.0 {
                0
            } else {
                (k as usize).min(bins - 1)
            };
            count[k] += 1;
        }
        let norm = 1.0 / (finite.len() as f64 * width);
        Some(Histogram {
            x: (0..bins)
                .map(|k| start + (k as f64 + 0.5) * width)
                .collect(),
            y: count.iter().map(|&c| c as f64 * norm).collect(),
            bin_width: width,
            samples: finite.len(),
        })
    }

    /// Bins of width `width` covering the range of the finite `values`, starting at a multiple
    /// of `width` (at 0 when no value is negative). The width is enlarged if the range would
    /// need more than [`MAX_BINS`] bins.
    pub fn density_auto(values: &[f64], width: f64) -> Option<Histogram> {
        let (lo, hi) = values
            .iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        if lo > hi || lo.is_nan() || !(width > 0.0 && width.is_finite()) {
            return None;
        }
        let mut w = width;
        if (hi - lo) / w > (MAX_BINS - 2) as f64 {
            w = (hi - lo) / (MAX_BINS - 2) as f64;
        }
        let start = if lo >= 0.0 { 0.0 } else { (lo / w).floor() * w };
        let bins = (((hi - start) / w).floor() as usize + 1).min(MAX_BINS);
        Histogram::density(values, start, w, bins)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn density_is_normalised_and_binned() {
        let h = Histogram::density(&[0.05, 0.15, 0.16, 0.95, f64::NAN], 0.0, 0.1, 10).unwrap();
        assert_eq!(h.samples, 4);
        assert_eq!(h.x.len(), 10);
        assert!((h.x[0] - 0.05).abs() < 1e-15);
        assert!((h.y[0] - 1.0 / (4.0 * 0.1)).abs() < 1e-12);
        assert!((h.y[1] - 2.0 / (4.0 * 0.1)).abs() < 1e-12);
        assert!((h.y[9] - 1.0 / (4.0 * 0.1)).abs() < 1e-12);
        let total: f64 = h.y.iter().sum::<f64>() * h.bin_width;
        assert!((total - 1.0).abs() < 1e-12);
        assert!(Histogram::density(&[], 0.0, 0.1, 3).is_none());
        assert!(Histogram::density(&[1.0], 0.0, 0.0, 3).is_none());
    }

    #[test]
    fn auto_range_starts_at_zero_or_below_the_minimum() {
        let h = Histogram::density_auto(&[0.3, 2.05], 0.5).unwrap();
        assert_eq!(h.x, vec![0.25, 0.75, 1.25, 1.75, 2.25]);
        let h = Histogram::density_auto(&[-0.7, 0.2], 0.5).unwrap();
        assert_eq!(h.x, vec![-0.75, -0.25, 0.25]);
        // A huge range does not allocate a huge histogram.
        let h = Histogram::density_auto(&[0.0, 1e300], 1e-3).unwrap();
        assert!(h.x.len() <= MAX_BINS);
        assert!(Histogram::density_auto(&[f64::NAN], 1.0).is_none());
    }
}
