//! Sample statistics shared by the reports over seeds and repeats (`reproduce`, `bench`,
//! `accuracy`): mean, sample s.d., median with min and max, the two-sample
//! Kolmogorov–Smirnov distance, the Pareto front of (cost, error) points.

use serde::{Deserialize, Serialize};

/// Arithmetic mean; `None` for an empty sample.
pub fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// Sample standard deviation (n − 1 in the denominator); `None` below two values.
pub fn sample_sd(v: &[f64]) -> Option<f64> {
    let m = mean(v)?;
    (v.len() >= 2)
        .then(|| (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt())
}

/// Median, min and max of a quantity over repeats.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Stat {
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Stat {
    /// Of the finite values (the mean of the middle two for an even count); `None` if there
    /// is none.
    pub fn of(values: &[f64]) -> Option<Stat> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let m = v.len();
        let median = if m % 2 == 1 {
            v[m / 2]
        } else {
            0.5 * (v[m / 2 - 1] + v[m / 2])
        };
        Some(Stat {
            median,
            min: v[0],
            max: v[m - 1],
        })
    }
}

/// Two-sample Kolmogorov–Smirnov distance sup_f |F_a(f) − F_b(f)| of two samples; `None`
/// when one is empty.
pub fn ks_distance(a: &[f64], b: &[f64]) -> Option<f64> {
    if a.is_empty() || b.is_empty() {
        return None;
    }
    let mut a = a.to_vec();
    let mut b = b.to_vec();
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    let (na, nb) = (a.len() as f64, b.len() as f64);
    let (mut i, mut j, mut d) = (0usize, 0usize, 0.0f64);
    while i < a.len() && j < b.len() {
        let x = a[i].min(b[j]);
        while i < a.len() && a[i] <= x {
            i += 1;
        }
        while j < b.len() && b[j] <= x {
            j += 1;
        }
        d = d.max((i as f64 / na - j as f64 / nb).abs());
    }
    Some(d)
}

/// Points not dominated in (cost, error): no other point is at most as costly and at most as
/// wrong, and strictly better in one. Returns one flag per point; `None` entries are never on
/// the front.
pub fn pareto(points: &[Option<(f64, f64)>]) -> Vec<bool> {
    points
        .iter()
        .map(|p| {
            let Some((c, e)) = *p else { return false };
            !points
                .iter()
                .flatten()
                .any(|&(c2, e2)| c2 <= c && e2 <= e && (c2 < c || e2 < e))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_sample_sd() {
        assert_eq!(mean(&[]), None);
        assert_eq!(mean(&[1.0, 2.0, 6.0]), Some(3.0));
        assert_eq!(sample_sd(&[1.0]), None);
        assert!((sample_sd(&[1.0, 2.0, 3.0, 4.0]).unwrap() - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn median_min_max() {
        let s = Stat::of(&[3.0, 1.0, 2.0, f64::NAN]).unwrap();
        assert_eq!((s.median, s.min, s.max), (2.0, 1.0, 3.0));
        assert_eq!(Stat::of(&[1.0, 2.0]).unwrap().median, 1.5);
        assert!(Stat::of(&[]).is_none());
    }

    #[test]
    fn ks_distance_of_samples() {
        assert_eq!(ks_distance(&[1.0, 2.0], &[1.0, 2.0]), Some(0.0));
        assert_eq!(ks_distance(&[1.0, 2.0], &[3.0, 4.0]), Some(1.0));
        let d = ks_distance(&[1.0, 2.0, 3.0, 4.0], &[2.5]).unwrap();
        assert!((d - 0.5).abs() < 1e-12);
        assert_eq!(ks_distance(&[], &[1.0]), None);
    }

    #[test]
    fn pareto_front_keeps_undominated_points() {
        let p = [
            Some((1.0, 5.0)),
            Some((2.0, 1.0)),
            Some((3.0, 2.0)), // dominated by (2, 1)
            None,
            Some((0.5, 9.0)),
            Some((2.0, 1.0)), // equal to a front point: on it too
        ];
        assert_eq!(pareto(&p), vec![true, true, false, false, true, true]);
    }
}
