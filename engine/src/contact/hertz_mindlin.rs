//! Hertz–Mindlin spheres (AR07 §II.A, App. A, App. B), with an optional contact cohesion model
//! from another code ([`HertzCohesion`]: [`super::sjkr::Sjkr`], [`super::dmt::Dmt`]).

use super::batch::{ChunkSum, PairChunk};
use super::hertz_mindlin_avx::{self, Coefficients};
use super::slider::{Friction, Spring};
use super::{ContactLaw, Pair, PairForce};
use crate::geometry::{ByDim, Dim, VectorOps};
use std::marker::PhantomData;

/// A cohesion model acting in contact on top of the Hertz force: the total normal force and the
/// force the Coulomb cap multiplies (AR07: the elastic part alone).
pub trait HertzCohesion: Copy + Send + Sync + std::fmt::Debug + PartialEq + 'static {
    const ACTIVE: bool;
    /// (N, Coulomb normal force) from the elastic part `ne`, the dashpot `viscous` (α v_n) and
    /// the overlap of `p`.
    fn normal<D: Dim>(&self, ne: f64, viscous: f64, p: &Pair<D>) -> (f64, f64);
    /// ` name=value` for [`ContactLaw::describe`].
    fn describe(&self) -> String;
}

/// No cohesion: N = N_e − α v_n, the Coulomb cap on N_e (AR07 (4)).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoCohesion;

impl HertzCohesion for NoCohesion {
    const ACTIVE: bool = false;
    #[inline(always)]
    fn normal<D: Dim>(&self, ne: f64, viscous: f64, _p: &Pair<D>) -> (f64, f64) {
        (ne - viscous, ne)
    }
    fn describe(&self) -> String {
        String::new()
    }
}

/// Hertz normal force with Mindlin tangential stiffness, Walton rescaling on unloading and
/// viscous normal damping at a fraction ζ of critical. `F` selects the friction kind
/// ([`super::slider::Frictionless`], [`super::slider::Coulomb`], [`super::slider::NoSlip`]),
/// `C` the cohesion ([`NoCohesion`] in AR07).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HertzMindlin<F, C = NoCohesion> {
    /// Ẽ = E/(1−ν²).
    pub e_tilde: f64,
    /// K_T/K_N = (2−2ν)/(2−ν) (AR07 (3)).
    pub kt_ratio: f64,
    /// ζ: fraction of critical damping (AR07 (5)).
    pub zeta: f64,
    pub friction: F,
    pub cohesion: C,
}

impl<F> HertzMindlin<F> {
    pub fn new(e_tilde: f64, poisson: f64, zeta: f64, friction: F) -> Self {
        HertzMindlin {
            e_tilde,
            kt_ratio: (2.0 - 2.0 * poisson) / (2.0 - poisson),
            zeta,
            friction,
            cohesion: NoCohesion,
        }
    }

    /// The same law with the cohesion model `cohesion`.
    pub fn with_cohesion<C: HertzCohesion>(self, cohesion: C) -> HertzMindlin<F, C> {
        HertzMindlin {
            e_tilde: self.e_tilde,
            kt_ratio: self.kt_ratio,
            zeta: self.zeta,
            friction: self.friction,
            cohesion,
        }
    }
}

impl<F, C> HertzMindlin<F, C> {
    /// Elastic normal force for overlap `h` and reduced radius `r_eff`: AR07 (1), written
    /// N = (2/3) Ẽ √R* h^{3/2}, which is (Ẽ√a/3) h^{3/2} for equal spheres (R* = a/4).
    #[inline(always)]
    pub fn normal_force(&self, h: f64, r_eff: f64) -> f64 {
        2.0 / 3.0 * self.e_tilde * (r_eff * h).sqrt() * h
    }

    /// K_N = dN/dh = Ẽ √(R* h) (AR07 (2)).
    #[inline(always)]
    pub fn normal_stiffness(&self, h: f64, r_eff: f64) -> f64 {
        self.e_tilde * (r_eff * h).sqrt()
    }
}

impl<D: Dim, F: Friction, C: HertzCohesion> ContactLaw<D> for HertzMindlin<F, C> {
    type History = F::State<D>;
    const MOMENTS: bool = F::ACTIVE;
    const ROLLING: bool = false;

    #[inline(always)]
    fn range(&self) -> f64 {
        0.0
    }

    #[inline(always)]
    fn interact(&self, p: &Pair<D>, hist: &mut Self::History, dt: f64) -> PairForce<D> {
        if p.gap >= 0.0 {
            *hist = Default::default();
            return PairForce::default();
        }
        let h = -p.gap;
        let sq = (p.r_eff * h).sqrt();
        let kn = self.e_tilde * sq;
        let ne = 2.0 / 3.0 * kn * h;
        let vn = p.v_contact.dot(&p.n);
        // AR07 (4)–(5): N_v = α ḣ, α = ζ√(2 m K_N) for equal masses m, i.e. 2ζ√(m_eff K_N).
        let alpha = 2.0 * self.zeta * (p.m_eff * kn).sqrt();
        let (normal, cap) = self.cohesion.normal(ne, alpha * vn, p);
        let tangential = if F::ACTIVE {
            let slip = (p.v_contact - p.n * vn) * dt;
            let pivot = 0.5 * D::pivot_rate(p.w_i + p.w_j, p.n) * dt;
            self.friction
                .update::<D>(hist, p.n, pivot, slip, self.kt_ratio * kn, cap)
        } else {
            D::V::zero()
        };
        PairForce {
            normal,
            normal_elastic: ne,
            tangential,
            rolling: D::Ang::zero(),
        }
    }

    fn max_stiffness(&self, force: f64, r_eff_max: f64) -> f64 {
        // Overlap at which N = force, then K_N there (cohesion: the decks' time step is this
        // one too; its extra overlap is inside `numerics.stiffness_force`, 10 P a² by default).
        let h = (1.5 * force / (self.e_tilde * r_eff_max.sqrt())).powf(2.0 / 3.0);
        self.normal_stiffness(h, r_eff_max)
    }

    fn with_kappa_scaled(&self, factor: f64) -> Self {
        // κ = (Ẽ/P)^(2/3) (AR07 (21)).
        HertzMindlin {
            e_tilde: self.e_tilde * factor.powf(1.5),
            ..*self
        }
    }

    fn without_normal_damping(&self) -> Self {
        HertzMindlin { zeta: 0.0, ..*self }
    }

    fn describe(&self) -> String {
        format!(
            "hertz-mindlin Ẽ={:.4e} K_T/K_N={:.4} ζ={} μ={}{}",
            self.e_tilde,
            self.kt_ratio,
            self.zeta,
            self.friction.mu(),
            self.cohesion.describe()
        )
    }

    fn stored(&self, hist: &Self::History) -> (D::V, D::Ang) {
        (F::force::<D>(hist), D::Ang::zero())
    }

    /// The AVX kernel of 3D spheres with springs and no cohesion
    /// ([`hertz_mindlin_avx`]); every other combination runs pair by pair.
    fn force_batch(&self, chunk: &mut PairChunk<'_, D, Self::History>) -> Option<ChunkSum> {
        if C::ACTIVE {
            return None;
        }
        let chunk = D::as_3d::<SpringChunk<'_, '_>>(F::springs::<D>(chunk)?)?;
        let law = Coefficients {
            e_tilde: self.e_tilde,
            kt_ratio: self.kt_ratio,
            zeta: self.zeta,
            mu: self.friction.mu(),
        };
        if law.mu.is_finite() {
            hertz_mindlin_avx::force_chunk::<true>(&law, chunk)
        } else {
            hertz_mindlin_avx::force_chunk::<false>(&law, chunk)
        }
    }
}

/// A chunk of the force pass with tangential springs, in each dimension (for [`Dim::as_3d`]).
struct SpringChunk<'x, 'y>(PhantomData<&'x mut &'y ()>);

impl<'x, 'y: 'x> ByDim for SpringChunk<'x, 'y> {
    type Of<D: Dim> = &'x mut PairChunk<'y, D, Spring<D::V>>;
}
