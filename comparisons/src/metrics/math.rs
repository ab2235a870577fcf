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

/// Central-difference Jacobian of `residuals` (`rows` of them) at the four parameters `x`,
/// step 1e-6·max(|x_c|, 1e-3); `None` if any entry is not finite. For the
/// Levenberg–Marquardt fits of smooth models (GRC07 (28), GRC08 (9)).
pub(crate) fn central_jacobian4(
    x: &nalgebra::Vector4<f64>,
    rows: usize,
    residuals: impl Fn(&nalgebra::Vector4<f64>) -> nalgebra::DVector<f64>,
) -> Option<nalgebra::OMatrix<f64, nalgebra::Dyn, nalgebra::U4>> {
    let mut j = nalgebra::OMatrix::<f64, nalgebra::Dyn, nalgebra::U4>::zeros(rows);
    for c in 0..4 {
        let h = 1e-6 * x[c].abs().max(1e-3);
        let (mut lo, mut hi) = (*x, *x);
        lo[c] -= h;
        hi[c] += h;
        let d = (residuals(&hi) - residuals(&lo)) / (2.0 * h);
        j.set_column(c, &d);
    }
    j.iter().all(|v| v.is_finite()).then_some(j)
}
