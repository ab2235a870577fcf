//! GRC08 §III.D: the intrinsic consolidation curve of a cohesive packing under growing
//! isotropic pressure, 1/Φ(P*) by GRC08 (9), and its fit to the equilibrium states of a
//! pressure program (P0*, Φ0, λ, α, P1*, Φ_max as in GRC08 T.III).

use super::math::Fit4;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DVector, Matrix4, Vector4};
use serde::Serialize;

/// GRC08 (9) with its parameters. Written with the exponent 1/α on the bracket only,
/// 1/Φ = 1/Φ0 − λ [ln(P*/P0*) + (1/α) ln(1 − exp(−(P1*/P*)^α))], the reading under which
/// (9) crosses over from (7) (P* ≪ P1*) to (8) with A = λ P1*^α/(2α) (P* ≫ P1*), as the text
/// says; P1* then sets Φ_max by 1/Φ_max = 1/Φ0 − λ ln(P1*/P0*) (the relation printed after
/// (9) lacks the factor λ: with it T.III's numbers agree, paper-values.toml).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ConsolidationLaw {
    /// Where the data join the intrinsic curve: (P0*, Φ0).
    pub p0: f64,
    pub phi0: f64,
    /// Plasticity index λ, GRC08 (7).
    pub lambda: f64,
    /// Exponent α of the approach to Φ_max, GRC08 (8).
    pub alpha: f64,
    /// Crossover pressure P1*.
    pub p1: f64,
}

impl ConsolidationLaw {
    /// 1/Φ at reduced pressure `p`, GRC08 (9).
    pub fn inverse_phi(&self, p: f64) -> f64 {
        let x = (self.p1 / p).powf(self.alpha);
        // ln(1 − e^(−x)), accurate for small and large x.
        let ln_bracket = if x > 1e-3 {
            (-(-x).exp()).ln_1p()
        } else {
            x.ln() - 0.5 * x
        };
        1.0 / self.phi0 - self.lambda * ((p / self.p0).ln() + ln_bracket / self.alpha)
    }

    /// Φ at reduced pressure `p`.
    pub fn phi(&self, p: f64) -> f64 {
        1.0 / self.inverse_phi(p)
    }

    /// The asymptotic solid fraction, 1/Φ_max = 1/Φ0 − λ ln(P1*/P0*).
    pub fn phi_max(&self) -> f64 {
        1.0 / (1.0 / self.phi0 - self.lambda * (self.p1 / self.p0).ln())
    }
}

/// Result of [`fit`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConsolidationFit {
    pub law: ConsolidationLaw,
    /// Standard errors of λ, α and P1* from the fit's covariance (GRC08 T.III: "± from the
    /// fit").
    pub lambda_error: f64,
    pub alpha_error: f64,
    pub p1_error: f64,
    /// Points fitted (P* ≥ P0*) and the rms of the residuals of 1/Φ over them.
    pub points: usize,
    pub rms_residual: f64,
}

impl ConsolidationFit {
    /// Named values as the reproduction tables know them (paper-values.toml keys).
    pub fn values(&self) -> Vec<(String, f64)> {
        [
            ("P0_star", self.law.p0),
            ("phi0", self.law.phi0),
            ("lambda", self.law.lambda),
            ("alpha", self.law.alpha),
            ("P1_star", self.law.p1),
            ("phi_max", self.law.phi_max()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }
}

/// The law of the fit's parameters (1/Φ0, λ, α, ln P1*), P0* held: 1/Φ0 and ln P1* keep Φ0
/// and P1* positive.
fn law_of(p0: f64, x: &Vector4<f64>) -> ConsolidationLaw {
    ConsolidationLaw {
        p0,
        phi0: 1.0 / x[0],
        lambda: x[1],
        alpha: x[2],
        p1: x[3].exp(),
    }
}

/// Fewest points a fit of four parameters is made from.
pub const MIN_POINTS: usize = 6;

/// Fits GRC08 (9) to the loading points (P*, Φ) from `points[anchor]` on, with P0* the
/// anchor's pressure and Φ0, λ, α, P1* free (T.III's Φ0 is the fitted curve's, below the
/// measured Φ at P* = 0.01 of T.II). `None` with fewer than [`MIN_POINTS`] points or when the
/// minimisation fails (Φ0, λ and α must end positive, P1* finite).
pub fn fit_from(points: &[(f64, f64)], anchor: usize) -> Option<ConsolidationFit> {
    let used = points.get(anchor..)?;
    if used.len() < MIN_POINTS {
        return None;
    }
    let p0 = used[0].0;
    let (p, inv_phi): (Vec<f64>, Vec<f64>) = used.iter().map(|&(p, phi)| (p, 1.0 / phi)).unzip();
    // Start: Φ0 measured, λ from the slope of the first half (regime II), α = 1, P1* at a
    // quarter of the last pressure (regime III begins within the range).
    let half = (p.len() / 2).max(2);
    let slope = -(inv_phi[half - 1] - inv_phi[0]) / (p[half - 1] / p[0]).ln();
    let start = Vector4::new(
        inv_phi[0],
        slope.max(1e-3),
        1.0,
        (p[p.len() - 1] / 4.0).ln(),
    );
    let problem = Fit4::new(start, |x: &Vector4<f64>| {
        let law = law_of(p0, x);
        DVector::from_iterator(
            p.len(),
            p.iter()
                .zip(&inv_phi)
                .map(|(&p, &y)| law.inverse_phi(p) - y),
        )
    });
    let (problem, report) = LevenbergMarquardt::new()
        .with_patience(400)
        .minimize(problem);
    if !report.termination.was_successful() {
        return None;
    }
    let law = law_of(p0, &problem.x);
    if !(law.phi0 > 0.0 && law.lambda > 0.0 && law.alpha > 0.0 && law.p1.is_finite()) {
        return None;
    }
    let r = problem.residuals()?;
    let j = problem.jacobian()?;
    let n = p.len();
    let s2 = r.norm_squared() / (n - 4).max(1) as f64;
    let jtj: Matrix4<f64> = j.transpose() * &j;
    let cov = jtj.try_inverse().map(|m| m * s2);
    let se = |c: usize| cov.map_or(f64::NAN, |m| m[(c, c)].max(0.0).sqrt());
    Some(ConsolidationFit {
        law,
        lambda_error: se(1),
        alpha_error: se(2),
        p1_error: law.p1 * se(3),
        points: n,
        rms_residual: (r.norm_squared() / n as f64).sqrt(),
    })
}

/// Largest rise of Φ from the first level that still counts as regime I, GRC08 §III.C: the
/// plateau where the structure resists elastically (GRC08 Figs. 5–8), a fraction of the
/// sample-to-sample s.d. of Φ at P* = 0.01 (0.008, T.II).
pub const PLATEAU_RISE: f64 = 0.005;

/// The last level of regime I: the highest index whose Φ exceeds the first level's by less
/// than [`PLATEAU_RISE`] with every level before it.
pub fn regime_one_end(points: &[(f64, f64)]) -> usize {
    let Some(&(_, phi_start)) = points.first() else {
        return 0;
    };
    points
        .iter()
        .take_while(|&&(_, phi)| phi - phi_start < PLATEAU_RISE)
        .count()
        .saturating_sub(1)
}

/// Fits GRC08 (9) to a loading curve (points in increasing P*), with P0* where, in GRC08
/// §III.D's words, "the system behavior joins the intrinsic consolidation curve": the last
/// level of the regime I plateau ([`regime_one_end`]).
pub fn fit(points: &[(f64, f64)]) -> Option<ConsolidationFit> {
    fit_from(points, regime_one_end(points))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// GRC08 T.III, μ_R = 0.005.
    fn paper_rr() -> ConsolidationLaw {
        ConsolidationLaw {
            p0: 0.0316,
            phi0: 0.515,
            lambda: 0.194,
            alpha: 1.08,
            p1: 0.900,
        }
    }

    #[test]
    fn law_crosses_over_from_eq7_to_eq8() {
        let law = paper_rr();
        // At the anchor, Φ0 (to the e^(−(P1/P0)^α) term, negligible here).
        assert!((law.phi(law.p0) - law.phi0).abs() < 1e-9);
        // P* ≪ P1*: GRC08 (7), slope −λ in ln P*.
        let (a, b) = (0.04, 0.05);
        let slope = (law.inverse_phi(b) - law.inverse_phi(a)) / (b / a).ln();
        assert!((slope + law.lambda).abs() < 1e-3 * law.lambda, "{slope}");
        // P* ≫ P1*: GRC08 (8) with A = λ P1*^α/(2α).
        let p: f64 = 1e4;
        let eq8 = 1.0 / law.phi_max()
            + law.lambda * law.p1.powf(law.alpha) / (2.0 * law.alpha) / p.powf(law.alpha);
        assert!(
            (law.inverse_phi(p) - eq8).abs() < 1e-9,
            "{}",
            law.inverse_phi(p) - eq8
        );
        // T.III's Φ_max from its P1* (with the factor λ, paper-values.toml).
        assert!((law.phi_max() - 0.7745).abs() < 2e-3, "{}", law.phi_max());
        let no_rr = ConsolidationLaw {
            p0: 0.0237,
            phi0: 0.469,
            lambda: 0.349,
            alpha: 0.91,
            p1: 0.271,
        };
        assert!(
            (no_rr.phi_max() - 0.7808).abs() < 2e-3,
            "{}",
            no_rr.phi_max()
        );
    }

    /// A plateau (regime I, Φ barely rising, up to P0*) then the paper's curve at 10^(1/8)
    /// per level with a small deterministic scatter: the fit anchors at the plateau's last
    /// level and recovers Φ0, λ, α and P1* within their errors.
    #[test]
    fn fit_finds_the_anchor_and_recovers_the_parameters() {
        let law = paper_rr();
        let mut points = Vec::new();
        for k in 0..=25 {
            let p = 0.01 * 10f64.powf(k as f64 / 8.0);
            let phi = if p < law.p0 * 0.999 {
                0.512 + 0.001 * (p / 0.01).ln()
            } else {
                let wiggle = 2e-4 * ((k * 7919) % 13) as f64 / 13.0 - 1e-4;
                1.0 / (law.inverse_phi(p) + wiggle)
            };
            points.push((p, phi));
        }
        assert_eq!(regime_one_end(&points), 4);
        let f = fit(&points).expect("fit");
        assert!(
            (f.law.p0 - law.p0).abs() < 1e-3 * law.p0,
            "P0* = {}",
            f.law.p0
        );
        assert!((f.law.phi0 - law.phi0).abs() < 1e-3, "{f:?}");
        assert!(
            (f.law.lambda - law.lambda).abs() < 3.0 * f.lambda_error.max(1e-3),
            "{f:?}"
        );
        assert!(
            (f.law.alpha - law.alpha).abs() < 3.0 * f.alpha_error.max(1e-2),
            "{f:?}"
        );
        assert!(
            (f.law.p1 - law.p1).abs() < 3.0 * f.p1_error.max(1e-2),
            "{f:?}"
        );
        assert!((f.law.phi_max() - law.phi_max()).abs() < 1e-3, "{f:?}");
        assert!(f.rms_residual < 2e-4, "{f:?}");
        let v = f.values();
        assert_eq!(v[0].0, "P0_star");
        assert_eq!(v.len(), 6);
    }

    #[test]
    fn fit_refuses_too_few_points() {
        let law = paper_rr();
        let points: Vec<(f64, f64)> = (0..5)
            .map(|k| {
                let p = 0.04 * 2f64.powi(k);
                (p, law.phi(p))
            })
            .collect();
        assert!(fit(&points).is_none());
        assert!(fit_from(&points, 0).is_none());
    }
}
