//! One code base for 2D disks and 3D spheres: the [`Dim`] trait carries the vector and
//! angular types of a dimension (angular velocity is a scalar in 2D, a vector in 3D) and the
//! few operations that differ between them, in the spirit of rapier/parry.

use nalgebra::{Vector2, Vector3};
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// Arithmetic shared by position vectors and angular quantities.
pub trait VectorOps:
    Copy
    + Debug
    + Default
    + Send
    + Sync
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Neg<Output = Self>
    + Mul<f64, Output = Self>
    + AddAssign
    + SubAssign
    + serde::Serialize
    + serde::de::DeserializeOwned
    + 'static
{
    fn zero() -> Self;
    fn dot(&self, other: &Self) -> f64;
    fn norm_squared(&self) -> f64 {
        self.dot(self)
    }
    fn norm(&self) -> f64 {
        self.norm_squared().sqrt()
    }
    fn is_finite(&self) -> bool;
    /// Components as a `Vec` (cell lengths and other per-axis lists).
    fn to_vec(&self) -> Vec<f64>;
    /// Components stored inline (a snapshot's [`crate::snapshot::Vector`]).
    fn components(&self) -> smallvec::SmallVec<[f64; 3]>;
    /// From its components (as many as [`VectorOps::to_vec`] gives).
    fn from_components(x: &[f64]) -> Self;
}

impl VectorOps for f64 {
    #[inline(always)]
    fn zero() -> Self {
        0.0
    }
    #[inline(always)]
    fn dot(&self, other: &Self) -> f64 {
        self * other
    }
    #[inline(always)]
    fn is_finite(&self) -> bool {
        f64::is_finite(*self)
    }
    fn to_vec(&self) -> Vec<f64> {
        vec![*self]
    }
    fn components(&self) -> smallvec::SmallVec<[f64; 3]> {
        smallvec::smallvec![*self]
    }
    fn from_components(x: &[f64]) -> Self {
        x[0]
    }
}

macro_rules! impl_linear_vec {
    ($t:ty) => {
        impl VectorOps for $t {
            #[inline(always)]
            fn zero() -> Self {
                <$t>::zeros()
            }
            #[inline(always)]
            fn dot(&self, other: &Self) -> f64 {
                <$t>::dot(self, other)
            }
            #[inline(always)]
            fn is_finite(&self) -> bool {
                self.iter().all(|x| x.is_finite())
            }
            fn to_vec(&self) -> Vec<f64> {
                self.iter().copied().collect()
            }
            fn components(&self) -> smallvec::SmallVec<[f64; 3]> {
                smallvec::SmallVec::from_slice(self.as_slice())
            }
            fn from_components(x: &[f64]) -> Self {
                <$t>::from_column_slice(x)
            }
        }
    };
}
impl_linear_vec!(Vector2<f64>);
impl_linear_vec!(Vector3<f64>);

/// A space dimension: 2 (disks) or 3 (spheres).
pub trait Dim: Copy + Clone + Debug + Default + Send + Sync + 'static {
    const D: usize;
    /// Position, velocity and force vectors.
    type V: VectorOps
        + std::ops::Index<usize, Output = f64>
        + std::ops::IndexMut<usize>
        + std::ops::Div<f64, Output = Self::V>;
    /// Angular velocity, moment and rotation (scalar in 2D, vector in 3D).
    type Ang: VectorOps;

    fn from_slice(x: &[f64]) -> Self::V;
    /// Component-wise product.
    fn mul(a: Self::V, b: Self::V) -> Self::V;
    /// Component-wise quotient.
    fn div(a: Self::V, b: Self::V) -> Self::V;
    /// a × b.
    fn cross(a: Self::V, b: Self::V) -> Self::Ang;
    /// ω × r.
    fn ang_cross(w: Self::Ang, r: Self::V) -> Self::V;
    /// Part of an angular quantity perpendicular to the unit normal `n` (rolling part; the whole
    /// of it in 2D).
    fn rolling_part(w: Self::Ang, n: Self::V) -> Self::Ang;
    /// Spin of `w` about `n` (pivoting rate), zero in 2D.
    fn pivot_rate(w: Self::Ang, n: Self::V) -> f64;
    /// Rotate a tangential vector `t` about the unit normal `n` by `angle` (AR07 (B5)); the
    /// identity in 2D where no pivoting exists.
    fn pivot(t: Self::V, n: Self::V, angle: f64) -> Self::V;
    /// Moves an angular quantity attached to a contact onto the new tangent plane, keeping its
    /// magnitude (identity in 2D).
    fn transport_ang(w: Self::Ang, n: Self::V) -> Self::Ang;
    /// Solid "volume" of a grain of diameter `d` (area in 2D).
    fn grain_volume(d: f64) -> f64;
    /// Moment of inertia factor `c` in I = c m d² (1/8 disk, 1/10 sphere).
    const INERTIA_FACTOR: f64;
    /// Mass exponent: a homogeneous grain of diameter d has mass (d/a)^D.
    fn product(v: Self::V) -> f64;
    /// `x` as the 3D member of its family where this dimension is 3D, `None` in 2D: the proof
    /// that `Self` is [`D3`], with which generic code hands its data to a 3D-only kernel
    /// without a cast.
    fn as_3d<T: ByDim>(x: T::Of<Self>) -> Option<T::Of<D3>>;
}

/// A family of types, one per dimension (`Of<D2>`, `Of<D3>`), for [`Dim::as_3d`].
pub trait ByDim {
    type Of<D: Dim>;
}

/// 2D disks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct D2;
/// 3D spheres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct D3;

impl Dim for D2 {
    const D: usize = 2;
    fn as_3d<T: ByDim>(_: T::Of<D2>) -> Option<T::Of<D3>> {
        None
    }
    type V = Vector2<f64>;
    type Ang = f64;
    const INERTIA_FACTOR: f64 = 1.0 / 8.0;

    fn from_slice(x: &[f64]) -> Self::V {
        Vector2::new(x[0], x[1])
    }
    #[inline(always)]
    fn mul(a: Self::V, b: Self::V) -> Self::V {
        a.component_mul(&b)
    }
    #[inline(always)]
    fn div(a: Self::V, b: Self::V) -> Self::V {
        a.component_div(&b)
    }
    #[inline(always)]
    fn cross(a: Self::V, b: Self::V) -> f64 {
        a.x * b.y - a.y * b.x
    }
    #[inline(always)]
    fn ang_cross(w: f64, r: Self::V) -> Self::V {
        Vector2::new(-w * r.y, w * r.x)
    }
    #[inline(always)]
    fn rolling_part(w: f64, _n: Self::V) -> f64 {
        w
    }
    #[inline(always)]
    fn pivot_rate(_w: f64, _n: Self::V) -> f64 {
        0.0
    }
    #[inline(always)]
    fn pivot(t: Self::V, _n: Self::V, _angle: f64) -> Self::V {
        t
    }
    #[inline(always)]
    fn transport_ang(w: f64, _n: Self::V) -> f64 {
        w
    }
    fn grain_volume(d: f64) -> f64 {
        std::f64::consts::PI * d * d / 4.0
    }
    #[inline(always)]
    fn product(v: Self::V) -> f64 {
        v.x * v.y
    }
}

impl Dim for D3 {
    const D: usize = 3;
    fn as_3d<T: ByDim>(x: T::Of<D3>) -> Option<T::Of<D3>> {
        Some(x)
    }
    type V = Vector3<f64>;
    type Ang = Vector3<f64>;
    const INERTIA_FACTOR: f64 = 1.0 / 10.0;

    fn from_slice(x: &[f64]) -> Self::V {
        Vector3::new(x[0], x[1], x[2])
    }
    #[inline(always)]
    fn mul(a: Self::V, b: Self::V) -> Self::V {
        a.component_mul(&b)
    }
    #[inline(always)]
    fn div(a: Self::V, b: Self::V) -> Self::V {
        a.component_div(&b)
    }
    #[inline(always)]
    fn cross(a: Self::V, b: Self::V) -> Self::Ang {
        a.cross(&b)
    }
    #[inline(always)]
    fn ang_cross(w: Self::Ang, r: Self::V) -> Self::V {
        w.cross(&r)
    }
    #[inline(always)]
    fn rolling_part(w: Self::Ang, n: Self::V) -> Self::Ang {
        w - n * w.dot(&n)
    }
    #[inline(always)]
    fn pivot_rate(w: Self::Ang, n: Self::V) -> f64 {
        w.dot(&n)
    }
    #[inline(always)]
    fn pivot(t: Self::V, n: Self::V, angle: f64) -> Self::V {
        // Rodrigues rotation of t ⟂ n about n; per-step angles are tiny, where the Taylor
        // series is exact to rounding and much cheaper than sin_cos.
        let (s, c) = if angle.abs() < 1e-3 {
            let a2 = angle * angle;
            (angle * (1.0 - a2 / 6.0), 1.0 - 0.5 * a2 * (1.0 - a2 / 12.0))
        } else {
            angle.sin_cos()
        };
        t * c + n.cross(&t) * s
    }
    #[inline(always)]
    fn transport_ang(w: Self::Ang, n: Self::V) -> Self::Ang {
        keep_norm_in_plane(w, n)
    }
    fn grain_volume(d: f64) -> f64 {
        std::f64::consts::PI * d * d * d / 6.0
    }
    #[inline(always)]
    fn product(v: Self::V) -> f64 {
        v.x * v.y * v.z
    }
}

/// Projects `t` onto the plane normal to the unit vector `n`, keeping its magnitude: the
/// rolling part of the transport of a contact force with its contact (AR07 (B3)–(B4)).
#[inline(always)]
pub fn keep_norm_in_plane<V: VectorOps>(t: V, n: V) -> V {
    let before = t.norm_squared();
    keep_norm_in_plane_with(t, n, before, 1.0 / before)
}

/// [`keep_norm_in_plane`] given |t|² and its inverse, which depend on `t` only: the caller
/// computes them before `n` is known, so the division overlaps the contact geometry.
#[inline(always)]
pub fn keep_norm_in_plane_with<V: VectorOps>(t: V, n: V, before: f64, inv_before: f64) -> V {
    if before == 0.0 {
        return t;
    }
    let tn = t.dot(&n);
    let p = t - n * tn;
    // |p|² = |t|²(1 − x) with x = (t·n)²/|t|², which is of order (rotation per step)², so
    // 1/√(1−x) = 1 + x/2 + 3x²/8 + O(x³) is exact to rounding for x < 1e-5.
    let x = tn * tn * inv_before;
    if x < 1e-5 {
        return p * (1.0 + x * (0.5 + 0.375 * x));
    }
    let after = p.norm_squared();
    if after == 0.0 {
        return V::zero();
    }
    p * (before / after).sqrt()
}

/// Symmetric second-order tensor stored as a full 3×3 array (2D uses the upper-left block).
pub type Tensor = [[f64; 3]; 3];

/// Adds `scale · a ⊗ b` to `t`.
#[inline(always)]
pub fn add_outer<D: Dim>(t: &mut Tensor, a: &D::V, b: &D::V) {
    for (r, row) in t.iter_mut().enumerate().take(D::D) {
        for (c, x) in row.iter_mut().enumerate().take(D::D) {
            *x += a[r] * b[c];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cross_products_agree_between_dims() {
        let a = Vector2::new(1.0, 2.0);
        let b = Vector2::new(-3.0, 0.5);
        let c3 = D3::cross(Vector3::new(a.x, a.y, 0.0), Vector3::new(b.x, b.y, 0.0));
        assert_eq!(D2::cross(a, b), c3.z);
        let w = 0.7;
        let r2 = D2::ang_cross(w, a);
        let r3 = D3::ang_cross(Vector3::new(0.0, 0.0, w), Vector3::new(a.x, a.y, 0.0));
        assert!((r2.x - r3.x).abs() < 1e-15 && (r2.y - r3.y).abs() < 1e-15);
    }

    #[test]
    fn pivot_keeps_norm_and_plane() {
        let n = Vector3::new(0.0, 0.0, 1.0);
        let t = Vector3::new(1.0, 0.0, 0.0);
        let r = D3::pivot(t, n, std::f64::consts::FRAC_PI_2);
        assert!((r - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-15);
    }

    #[test]
    fn transport_keeps_magnitude() {
        let n = Vector3::new(0.0, 0.6, 0.8);
        let t = Vector3::new(3.0, 4.0, 0.0);
        let p = keep_norm_in_plane(t, n);
        assert!((p.norm() - 5.0).abs() < 1e-12);
        assert!(p.dot(&n).abs() < 1e-12);
    }
}
