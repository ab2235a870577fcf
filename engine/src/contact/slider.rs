//! Elastic springs with a plastic threshold ("sliders"): the elastic part of the relative
//! tangential displacement (Coulomb, AR07 (3), GRC07 (8)) and of the relative rolling rotation
//! (GRC07 (10)). Each kind is a type, so an absent feature has no state and no cost.

use super::batch::PairChunk;
use super::PairState;
use crate::geometry::{keep_norm_in_plane_with, Dim, VectorOps};

/// Sliding friction between grains.
pub trait Friction: Copy + Send + Sync + std::fmt::Debug + 'static {
    type State<D: Dim>: PairState;
    const ACTIVE: bool;
    /// Updates the elastic tangential force (exerted by i on j) and returns it.
    ///
    /// Order of operations: transport with the contact (AR07 (B3)–(B5): onto the new tangent
    /// plane keeping its magnitude, then spun by the mean pivoting rotation `pivot`), Walton
    /// rescaling by `kt/kt_prev` when the stiffness drops (AR07 App. A), increment by
    /// `−kt·slip`, then projection back onto the Coulomb circle of radius μ·`limit`.
    fn update<D: Dim>(
        &self,
        st: &mut Self::State<D>,
        n: D::V,
        pivot: f64,
        slip: D::V,
        kt: f64,
        limit: f64,
    ) -> D::V;
    fn force<D: Dim>(st: &Self::State<D>) -> D::V;
    fn mu(&self) -> f64;
    /// `chunk` with its histories seen as tangential springs, where this kind keeps one (the
    /// batch kernels' view of them); `None` for μ = 0.
    fn springs<'x, 'y, D: Dim>(
        _chunk: &'x mut PairChunk<'y, D, Self::State<D>>,
    ) -> Option<&'x mut PairChunk<'y, D, Spring<D::V>>> {
        None
    }
}

/// μ = 0: no tangential force, no state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Frictionless;

/// Coulomb friction with a finite μ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coulomb {
    pub mu: f64,
}

/// μ = ∞: contacts never slide.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoSlip;

/// Tangential spring state: the elastic force and the stiffness it was built with.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Spring<V> {
    pub t: V,
    pub kt: f64,
}

impl Friction for Frictionless {
    type State<D: Dim> = ();
    const ACTIVE: bool = false;
    #[inline(always)]
    fn update<D: Dim>(&self, _: &mut (), _: D::V, _: f64, _: D::V, _: f64, _: f64) -> D::V {
        D::V::zero()
    }
    #[inline(always)]
    fn force<D: Dim>(_: &()) -> D::V {
        D::V::zero()
    }
    fn mu(&self) -> f64 {
        0.0
    }
}

#[inline(always)]
fn elastic_update<D: Dim>(st: &mut Spring<D::V>, n: D::V, pivot: f64, slip: D::V, kt: f64) {
    // The two divisions by stored quantities first: they do not wait for the geometry.
    let before = st.t.norm_squared();
    let inv_before = 1.0 / before;
    let inv_kt = 1.0 / st.kt;
    let mut t = keep_norm_in_plane_with(st.t, n, before, inv_before);
    t = D::pivot(t, n, pivot);
    // AR07 App. A: scaled down, never up, with the stiffness. Branch-free: whether K_T
    // rises or falls flips from step to step and would defeat the branch predictor. A new
    // spring has kt = 0 and t = 0, where the ratio is +∞ and the factor 1.
    t = t * (kt * inv_kt).min(1.0);
    st.kt = kt;
    st.t = t - slip * kt;
}

impl Friction for Coulomb {
    type State<D: Dim> = Spring<D::V>;
    const ACTIVE: bool = true;
    fn springs<'x, 'y, D: Dim>(
        chunk: &'x mut PairChunk<'y, D, Spring<D::V>>,
    ) -> Option<&'x mut PairChunk<'y, D, Spring<D::V>>> {
        Some(chunk)
    }
    #[inline(always)]
    fn update<D: Dim>(
        &self,
        st: &mut Spring<D::V>,
        n: D::V,
        pivot: f64,
        slip: D::V,
        kt: f64,
        limit: f64,
    ) -> D::V {
        elastic_update::<D>(st, n, pivot, slip, kt);
        let cap = self.mu * limit.max(0.0);
        let t2 = st.t.norm_squared();
        if t2 > cap * cap {
            st.t = if t2 > 0.0 {
                st.t * (cap / t2.sqrt())
            } else {
                D::V::zero()
            };
        }
        st.t
    }
    #[inline(always)]
    fn force<D: Dim>(st: &Spring<D::V>) -> D::V {
        st.t
    }
    fn mu(&self) -> f64 {
        self.mu
    }
}

impl Friction for NoSlip {
    type State<D: Dim> = Spring<D::V>;
    const ACTIVE: bool = true;
    fn springs<'x, 'y, D: Dim>(
        chunk: &'x mut PairChunk<'y, D, Spring<D::V>>,
    ) -> Option<&'x mut PairChunk<'y, D, Spring<D::V>>> {
        Some(chunk)
    }
    #[inline(always)]
    fn update<D: Dim>(
        &self,
        st: &mut Spring<D::V>,
        n: D::V,
        pivot: f64,
        slip: D::V,
        kt: f64,
        _limit: f64,
    ) -> D::V {
        elastic_update::<D>(st, n, pivot, slip, kt);
        st.t
    }
    #[inline(always)]
    fn force<D: Dim>(st: &Spring<D::V>) -> D::V {
        st.t
    }
    fn mu(&self) -> f64 {
        f64::INFINITY
    }
}

/// Rolling resistance between grains (GRC07 (9)–(10)).
pub trait RollingResistance: Copy + Send + Sync + std::fmt::Debug + 'static {
    type State<D: Dim>: PairState;
    const ACTIVE: bool;
    /// Updates the rolling moment exerted by i on j given the relative rolling rotation
    /// increment `dtheta` (ω_j − ω_i, rolling part, times dt) and returns it.
    fn update<D: Dim>(
        &self,
        st: &mut Self::State<D>,
        n: D::V,
        dtheta: D::Ang,
        limit: f64,
    ) -> D::Ang;
    /// The same resistance with its stiffness multiplied by `factor`.
    fn with_stiffness_scaled(&self, factor: f64) -> Self;
    /// Rolling stiffness K_r (0 without rolling resistance).
    fn stiffness(&self) -> f64;
    fn moment<D: Dim>(st: &Self::State<D>) -> D::Ang;
}

/// No rolling resistance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoRolling;

/// Rolling spring K_r with threshold μ_r N_e (GRC07 (10)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RollingSpring {
    pub kr: f64,
    pub mu_r: f64,
}

impl RollingResistance for NoRolling {
    type State<D: Dim> = ();
    const ACTIVE: bool = false;
    fn with_stiffness_scaled(&self, _factor: f64) -> Self {
        NoRolling
    }
    fn stiffness(&self) -> f64 {
        0.0
    }
    #[inline(always)]
    fn update<D: Dim>(&self, _: &mut (), _: D::V, _: D::Ang, _: f64) -> D::Ang {
        D::Ang::zero()
    }
    #[inline(always)]
    fn moment<D: Dim>(_: &()) -> D::Ang {
        D::Ang::zero()
    }
}

impl RollingResistance for RollingSpring {
    type State<D: Dim> = D::Ang;
    const ACTIVE: bool = true;
    fn with_stiffness_scaled(&self, factor: f64) -> Self {
        RollingSpring {
            kr: self.kr * factor,
            ..*self
        }
    }
    fn stiffness(&self) -> f64 {
        self.kr
    }
    #[inline(always)]
    fn update<D: Dim>(&self, st: &mut D::Ang, n: D::V, dtheta: D::Ang, limit: f64) -> D::Ang {
        let mut g = D::transport_ang(*st, n) - dtheta * self.kr;
        let cap = self.mu_r * limit.max(0.0);
        let g2 = g.norm_squared();
        if g2 > cap * cap {
            g = if g2 > 0.0 {
                g * (cap / g2.sqrt())
            } else {
                D::Ang::zero()
            };
        }
        *st = g;
        g
    }
    #[inline(always)]
    fn moment<D: Dim>(st: &D::Ang) -> D::Ang {
        *st
    }
}
