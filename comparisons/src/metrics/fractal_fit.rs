//! The fractal-blob model of the density correlations, GRC07 (27)–(28), and its
//! Levenberg–Marquardt fit to a measured I(k) (GRC07 §V.D): fractal dimension d_F and blob
//! size ξ.

use super::math::Fit4;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Vector4};
use serde::Serialize;

/// GRC07 (28) without its constant: the 2D Fourier transform of C(r) − Φ² = Φ (r/ℓ)^{d_F−2}
/// e^{−r/ξ} (GRC07 (27)) is `Φ 2π ℓ² Γ(d_F) (ξ/ℓ)^{d_F} shape(ξk, d_F)`, with
/// `shape(x, d) = ₂F₁[(1+d)/2, d/2; 1; −x²] = (1+x²)^{−d/2} P_{d−1}(1/√(1+x²))`
/// (the Laplace–Hankel transform of t^{d−1} e^{−t}, Gradshteyn–Ryzhik 6.621.1), which
/// converges for every x where the ₂F₁ series needs |x| < 1.
pub fn shape(x: f64, d: f64) -> f64 {
    let s = 1.0 + x * x;
    s.powf(-0.5 * d) * legendre_p(d - 1.0, 1.0 / s.sqrt())
}

/// Legendre function P_ν(t) for 0 ≤ t ≤ 1: ₂F₁(−ν, ν+1; 1; (1−t)/2), a series of ratio at
/// most 1/2.
fn legendre_p(nu: f64, t: f64) -> f64 {
    let z = 0.5 * (1.0 - t);
    let (mut term, mut sum) = (1.0, 1.0);
    for n in 0..400 {
        let n = n as f64;
        term *= (n - nu) * (n + nu + 1.0) / ((n + 1.0) * (n + 1.0)) * z;
        sum += term;
        if term.abs() <= 1e-17 * sum.abs() {
            break;
        }
    }
    sum
}

/// Γ(x) for x > 0 (Lanczos, g = 7, 9 terms; relative error ~1e-15).
pub fn gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return std::f64::consts::PI / ((std::f64::consts::PI * x).sin() * gamma(1.0 - x));
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    (2.0 * std::f64::consts::PI).sqrt() * t.powf(x + 0.5) * (-t).exp() * a
}

/// Parameters of GRC07 (28): `I(k) = constant + amplitude · shape(ξk, d_F)`, amplitude =
/// I(0) − constant = Φ 2π ℓ² Γ(d_F) (ξ/ℓ)^{d_F}.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FractalModel {
    pub constant: f64,
    pub amplitude: f64,
    pub d_f: f64,
    pub xi: f64,
}

impl FractalModel {
    pub fn eval(&self, k: f64) -> f64 {
        self.constant + self.amplitude * shape(self.xi * k, self.d_f)
    }

    /// ℓ of GRC07 (27) for solid fraction Φ (undefined at d_F = 2, where ℓ drops out).
    pub fn ell(&self, phi: f64) -> Option<f64> {
        let e = 2.0 - self.d_f;
        let l = (self.amplitude / (phi * 2.0 * std::f64::consts::PI * gamma(self.d_f))
            * self.xi.powf(-self.d_f))
        .powf(1.0 / e);
        (e.abs() > 1e-6 && l.is_finite()).then_some(l)
    }
}

/// Result of [`fit`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FractalFit {
    pub model: FractalModel,
    /// Standard errors of d_F and ξ from the fit's covariance (GRC07 T.VII: "± from the fit").
    pub d_f_error: f64,
    pub xi_error: f64,
    /// Range of k fitted and number of points.
    pub k_min: f64,
    pub k_max: f64,
    pub points: usize,
    /// Root-mean-square of ln(model/I) over the fitted points.
    pub rms_log_residual: f64,
}

impl FractalFit {
    /// Whether the fit describes a fractal range a ≪ 2π/k ≪ ξ at all (GRC07 (26), GRC08 §IV):
    /// ξ above the grain size and 1 < d_F < 2. A dense, homogeneous packing's flat, low I(k)
    /// (GRC08 Fig. 15, P* = 1) still fits the model, with ξ below a or d_F above 2.
    pub fn has_fractal_range(&self) -> bool {
        let m = &self.model;
        m.xi > 1.0 && m.d_f > 1.0 && m.d_f < 2.0
    }

    /// "GRC07 (28), d_F = …, ξ = … a", a plot's legend for the fit.
    pub fn legend(&self) -> String {
        format!(
            "GRC07 (28), d_F = {:.2}, ξ = {:.2} a",
            self.model.d_f, self.model.xi
        )
    }

    /// The fitted GRC07 (28) at `n + 1` log-spaced k over the fitted range, for a plot.
    pub fn curve(&self, n: usize) -> Vec<(f64, f64)> {
        (0..=n)
            .map(|q| self.k_min * (self.k_max / self.k_min).powf(q as f64 / n as f64))
            .map(|k| (k, self.model.eval(k)))
            .collect()
    }
}

/// Least squares of ln I: parameters (√constant, ln amplitude, d_F, ln ξ), so that the
/// constant and the amplitude stay positive and every decade of I weighs alike.
fn model_of(p: &Vector4<f64>) -> FractalModel {
    FractalModel {
        constant: p[0] * p[0],
        amplitude: p[1].exp(),
        d_f: p[2],
        xi: p[3].exp(),
    }
}

/// Fits GRC07 (28) to the points (k, I) with `k_min ≤ k ≤ k_max` and I > 0. `None` when fewer
/// than 6 points remain or the minimisation fails (d_F must end in (0, 3) and ξ finite).
pub fn fit(k: &[f64], intensity: &[f64], k_min: f64, k_max: f64) -> Option<FractalFit> {
    let (ks, is): (Vec<f64>, Vec<f64>) = k
        .iter()
        .zip(intensity)
        .filter(|(&k, &i)| k >= k_min && k <= k_max && i > 0.0 && i.is_finite())
        .map(|(&k, &i)| (k, i))
        .unzip();
    if ks.len() < 6 {
        return None;
    }
    // Start: the constant at a tenth of the smallest I, I(0) from the first point, d_F = 1.8
    // and ξ at a quarter of the longest wavelength fitted.
    let i_min = is.iter().copied().fold(f64::INFINITY, f64::min);
    let xi0 = 0.25 * 2.0 * std::f64::consts::PI / ks[0];
    let start = Vector4::new((0.1 * i_min).sqrt(), (2.0 * is[0]).ln(), 1.8, xi0.ln());
    let ln_i: Vec<f64> = is.iter().map(|i| i.ln()).collect();
    let problem = Fit4::new(start, |p: &Vector4<f64>| {
        let m = model_of(p);
        DVector::from_iterator(
            ks.len(),
            (0..ks.len()).map(|q| m.eval(ks[q]).ln() - ln_i[q]),
        )
    });
    let (problem, report) = LevenbergMarquardt::new()
        .with_patience(400)
        .minimize(problem);
    if !report.termination.was_successful() {
        return None;
    }
    let model = model_of(&problem.x);
    if !(model.d_f > 0.0 && model.d_f < 3.0 && model.xi.is_finite()) {
        return None;
    }
    let r = problem.residuals()?;
    let j = problem.jacobian()?;
    let dof = (ks.len() - 4).max(1) as f64;
    let s2 = r.norm_squared() / dof;
    // Covariance s²(JᵀJ)⁻¹; when the constant has gone to 0 its column vanishes and the
    // errors come from the other three parameters.
    let jtj = DMatrix::from_iterator(4, 4, (j.transpose() * &j).iter().copied());
    let cov = jtj
        .clone()
        .try_inverse()
        .filter(|m| m.iter().all(|x| x.is_finite()))
        .map(|m| (m * s2, 0))
        .or_else(|| {
            jtj.view((1, 1), (3, 3))
                .clone_owned()
                .try_inverse()
                .map(|m| (m * s2, 1))
        });
    let se = |c: usize| {
        cov.as_ref()
            .map_or(f64::NAN, |(m, off)| m[(c - off, c - off)].max(0.0).sqrt())
    };
    Some(FractalFit {
        model,
        d_f_error: se(2),
        xi_error: model.xi * se(3),
        k_min: ks[0],
        k_max: *ks.last().unwrap_or(&ks[0]),
        points: ks.len(),
        rms_log_residual: (r.norm_squared() / ks.len() as f64).sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hypergeometric_series(a: f64, b: f64, c: f64, z: f64) -> f64 {
        let (mut term, mut sum) = (1.0, 1.0);
        for n in 0..2000 {
            let n = n as f64;
            term *= (a + n) * (b + n) / ((c + n) * (n + 1.0)) * z;
            sum += term;
        }
        sum
    }

    #[test]
    fn gamma_matches_known_values() {
        assert!((gamma(5.0) - 24.0).abs() < 1e-12);
        assert!((gamma(0.5) - std::f64::consts::PI.sqrt()).abs() < 1e-13);
        assert!((gamma(1.5) - 0.5 * std::f64::consts::PI.sqrt()).abs() < 1e-13);
    }

    /// GRC07 (28)'s ₂F₁ by its own series where that converges (ξk < 1).
    #[test]
    fn shape_is_grc07_hypergeometric() {
        for d in [1.3, 1.53, 1.93, 2.4] {
            for x in [0.0, 0.1, 0.4, 0.7, 0.9] {
                let direct = hypergeometric_series(0.5 * (1.0 + d), 0.5 * d, 1.0, -x * x);
                assert!(
                    (shape(x, d) - direct).abs() < 1e-10 * direct.abs().max(1.0),
                    "d = {d}, x = {x}: {} vs {direct}",
                    shape(x, d)
                );
            }
        }
    }

    /// Closed forms: d_F = 2 is C ∝ e^{−r/ξ}, whose transform goes as (1+x²)^{−3/2}; d_F = 1
    /// is C ∝ e^{−r/ξ}/r, (1+x²)^{−1/2}. Far beyond ξ, I ∝ k^{−d_F} (GRC07 (26)); near
    /// d_F = 2 the k^{−d_F} term's weight P_{d_F−1}(0) vanishes and a k^{−d_F−1} term competes
    /// up to ξk ~ 1e3, hence the large x.
    #[test]
    fn shape_closed_forms_and_power_law() {
        for x in [0.5, 2.0, 10.0, 100.0] {
            let s = 1.0 + x * x;
            assert!((shape(x, 2.0) - s.powf(-1.5)).abs() < 1e-12 * s.powf(-1.5) * 10.0);
            assert!((shape(x, 1.0) - s.powf(-0.5)).abs() < 1e-12);
        }
        for d in [1.5, 1.9] {
            let slope = (shape(2e6, d) / shape(1e6, d)).ln() / 2f64.ln();
            assert!((slope + d).abs() < 1e-3, "d = {d}: slope {slope}");
        }
    }

    #[test]
    fn fit_recovers_the_model_parameters() {
        let truth = FractalModel {
            constant: 0.02,
            amplitude: 300.0,
            d_f: 1.6,
            xi: 7.0,
        };
        let k: Vec<f64> = (1..=80).map(|i| 0.08 * i as f64).collect();
        let i: Vec<f64> = k.iter().map(|&k| truth.eval(k)).collect();
        let f = fit(&k, &i, 0.0, 10.0).expect("fit");
        assert!((f.model.d_f - 1.6).abs() < 1e-4, "{f:?}");
        assert!((f.model.xi - 7.0).abs() < 1e-3, "{f:?}");
        assert!(f.rms_log_residual < 1e-6, "{f:?}");
        assert!(f.has_fractal_range());
        let curve = f.curve(10);
        assert_eq!(
            (curve.len(), curve[0].0, curve[10].0),
            (11, f.k_min, f.k_max)
        );
        assert!(curve
            .iter()
            .all(|(k, y)| (y - f.model.eval(*k)).abs() < 1e-12));
        // What a dense CI packing's flat I(k) fitted to (GRC08 Fig. 15, P* = 1): no range.
        let blob_below_a = FractalFit {
            model: FractalModel {
                xi: 0.41,
                d_f: 1.6,
                ..truth
            },
            ..f.clone()
        };
        let beyond_the_plane = FractalFit {
            model: FractalModel { d_f: 2.36, ..truth },
            ..f.clone()
        };
        assert!(!blob_below_a.has_fractal_range() && !beyond_the_plane.has_fractal_range());
        // ℓ inverts the amplitude: Φ 2π ℓ² Γ(d_F) (ξ/ℓ)^{d_F}.
        let l = f.model.ell(0.4).expect("ell");
        let back = 0.4 * 2.0 * std::f64::consts::PI * l * l * gamma(1.6) * (7.0 / l).powf(1.6);
        assert!((back / f.model.amplitude - 1.0).abs() < 1e-6);
    }

    #[test]
    fn fit_refuses_too_few_points() {
        assert!(fit(&[0.1, 0.2, 0.3], &[1.0, 0.5, 0.2], 0.0, 1.0).is_none());
    }
}
