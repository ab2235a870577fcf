//! Linear spring–dashpot–Coulomb law with optional short-range adhesion and rolling
//! resistance (GRC07 §II.B, GRC08 §II.B). Without adhesion it is the classic cohesionless
//! linear law.

use super::slider::{Friction, RollingResistance};
use super::{ContactLaw, Pair, PairForce};
use crate::geometry::{Dim, VectorOps as _};

/// Adhesion or its absence.
pub trait CohesionModel: Copy + Send + Sync + std::fmt::Debug + 'static {
    const ACTIVE: bool;
    /// Pull-off force F0.
    fn f0(&self) -> f64;
    /// Attraction range D0.
    fn d0(&self) -> f64;
}

/// No adhesion.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoCohesion;

/// GRC07 (4)–(5): −F0 in contact, −F0(1 − h/D0) for gaps 0 ≤ h ≤ D0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adhesion {
    pub f0: f64,
    pub d0: f64,
}

impl CohesionModel for NoCohesion {
    const ACTIVE: bool = false;
    #[inline(always)]
    fn f0(&self) -> f64 {
        0.0
    }
    #[inline(always)]
    fn d0(&self) -> f64 {
        0.0
    }
}

impl CohesionModel for Adhesion {
    const ACTIVE: bool = true;
    #[inline(always)]
    fn f0(&self) -> f64 {
        self.f0
    }
    #[inline(always)]
    fn d0(&self) -> f64 {
        self.d0
    }
}

/// The GRC07 interaction law with constant stiffnesses K_N, K_T.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Linear<C, F, R> {
    pub kn: f64,
    pub kt: f64,
    /// ζ: fraction of critical damping, η = ζ√(4 K_N m_i m_j/(m_i+m_j)) (GRC07 (6)).
    pub zeta: f64,
    /// Tangential and rolling viscous damping, fraction of critical (0 in GRC07).
    pub zeta_t: f64,
    pub cohesion: C,
    pub friction: F,
    pub rolling: R,
}

/// Per-pair history: tangential spring and rolling spring (each `()` when absent).
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct LinearHistory<T, G> {
    pub tangential: T,
    pub rolling: G,
}

impl<D: Dim, C: CohesionModel, F: Friction, R: RollingResistance> ContactLaw<D>
    for Linear<C, F, R>
{
    type History = LinearHistory<F::State<D>, R::State<D>>;
    const MOMENTS: bool = F::ACTIVE || R::ACTIVE;
    const ROLLING: bool = R::ACTIVE;

    #[inline(always)]
    fn range(&self) -> f64 {
        self.cohesion.d0()
    }

    #[inline(always)]
    fn interact(&self, p: &Pair<D>, hist: &mut Self::History, dt: f64) -> PairForce<D> {
        if p.gap >= 0.0 {
            *hist = Default::default();
            if C::ACTIVE && p.gap <= self.cohesion.d0() {
                // GRC07 (4): distant attraction, no tangential force, no viscosity.
                let normal = -self.cohesion.f0() * (1.0 - p.gap / self.cohesion.d0());
                return PairForce {
                    normal,
                    ..Default::default()
                };
            }
            return PairForce::default();
        }
        let ne = -self.kn * p.gap;
        let vn = p.v_contact.dot(&p.n);
        let eta = 2.0 * self.zeta * (self.kn * p.m_eff).sqrt();
        // GRC07 (5): N = N_e + N_v − F0.
        let normal = ne - eta * vn - self.cohesion.f0();
        let tangential = if F::ACTIVE {
            let vt = p.v_contact - p.n * vn;
            let pivot = 0.5 * D::pivot_rate(p.w_i + p.w_j, p.n) * dt;
            // GRC07 (8): the Coulomb cap uses the elastic repulsive part only.
            let t =
                self.friction
                    .update::<D>(&mut hist.tangential, p.n, pivot, vt * dt, self.kt, ne);
            if self.zeta_t > 0.0 {
                // Optional tangential dashpot (not in GRC07), outside the Coulomb cap.
                t - vt * (2.0 * self.zeta_t * (self.kt * p.m_eff).sqrt())
            } else {
                t
            }
        } else {
            D::V::zero()
        };
        let rolling = if R::ACTIVE {
            let wr = D::rolling_part(p.w_j - p.w_i, p.n);
            let g = self
                .rolling
                .update::<D>(&mut hist.rolling, p.n, wr * dt, ne);
            if self.zeta_t > 0.0 {
                // Optional rolling dashpot, η_r = 2ζ_t √(K_r m_eff r_eff²).
                g - wr * (2.0 * self.zeta_t * (self.rolling.stiffness() * p.m_eff).sqrt() * p.r_eff)
            } else {
                g
            }
        } else {
            D::Ang::zero()
        };
        PairForce {
            normal,
            normal_elastic: ne,
            tangential,
            rolling,
        }
    }

    fn max_stiffness(&self, _force: f64, _r_eff_max: f64) -> f64 {
        self.kn
    }

    fn with_kappa_scaled(&self, factor: f64) -> Self {
        // κ = K_N a/F0; K_T/K_N and K_r/(K_N a²) are kept (GRC07 T.I).
        Linear {
            kn: self.kn * factor,
            kt: self.kt * factor,
            rolling: self.rolling.with_stiffness_scaled(factor),
            ..*self
        }
    }

    fn with_tangential_damping(&self, zeta_t: f64) -> Self {
        Linear { zeta_t, ..*self }
    }

    fn without_normal_damping(&self) -> Self {
        Linear { zeta: 0.0, ..*self }
    }

    fn describe(&self) -> String {
        let mut s = format!(
            "linear K_N={:.4e} K_T={:.4e} ζ={} μ={}",
            self.kn,
            self.kt,
            self.zeta,
            self.friction.mu()
        );
        if C::ACTIVE {
            s += &format!(" F0={} D0={}", self.cohesion.f0(), self.cohesion.d0());
        }
        if R::ACTIVE {
            s += " rolling-resistance";
        }
        s
    }

    fn stored(&self, hist: &Self::History) -> (D::V, D::Ang) {
        (
            F::force::<D>(&hist.tangential),
            R::moment::<D>(&hist.rolling),
        )
    }
}
