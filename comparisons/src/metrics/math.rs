//! Small numeric helpers shared by the metrics.

/// Arithmetic mean, `None` for no values.
pub(crate) fn mean(xs: impl Iterator<Item = f64>) -> Option<f64> {
    let (s, k) = xs.fold((0.0, 0usize), |(s, k), x| (s + x, k + 1));
    (k > 0).then(|| s / k as f64)
}

/// Euclidean norm.
pub(crate) fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Scalar product.
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A least-squares problem in four parameters for the Levenberg–Marquardt fits of smooth
/// models (GRC07 (28), GRC08 (9)): the residuals at `x` from a closure, the Jacobian by
/// central differences (step 1e-6·max(|x_c|, 1e-3)); non-finite values end the minimisation.
pub(crate) struct Fit4<F> {
    pub x: nalgebra::Vector4<f64>,
    residuals_at: F,
}

impl<F: Fn(&nalgebra::Vector4<f64>) -> nalgebra::DVector<f64>> Fit4<F> {
    pub fn new(start: nalgebra::Vector4<f64>, residuals_at: F) -> Self {
        Fit4 {
            x: start,
            residuals_at,
        }
    }
}

impl<F: Fn(&nalgebra::Vector4<f64>) -> nalgebra::DVector<f64>>
    levenberg_marquardt::LeastSquaresProblem<f64, nalgebra::Dyn, nalgebra::U4> for Fit4<F>
{
    type ResidualStorage = nalgebra::storage::Owned<f64, nalgebra::Dyn>;
    type JacobianStorage = nalgebra::storage::Owned<f64, nalgebra::Dyn, nalgebra::U4>;
    type ParameterStorage = nalgebra::storage::Owned<f64, nalgebra::U4>;

    fn set_params(&mut self, x: &nalgebra::Vector4<f64>) {
        self.x = *x;
    }

    fn params(&self) -> nalgebra::Vector4<f64> {
        self.x
    }

    fn residuals(&self) -> Option<nalgebra::DVector<f64>> {
        let r = (self.residuals_at)(&self.x);
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn jacobian(&self) -> Option<nalgebra::OMatrix<f64, nalgebra::Dyn, nalgebra::U4>> {
        let rows = (self.residuals_at)(&self.x).len();
        let mut j = nalgebra::OMatrix::<f64, nalgebra::Dyn, nalgebra::U4>::zeros(rows);
        for c in 0..4 {
            let h = 1e-6 * self.x[c].abs().max(1e-3);
            let (mut lo, mut hi) = (self.x, self.x);
            lo[c] -= h;
            hi[c] += h;
            let d = ((self.residuals_at)(&hi) - (self.residuals_at)(&lo)) / (2.0 * h);
            j.set_column(c, &d);
        }
        j.iter().all(|v| v.is_finite()).then_some(j)
    }
}
