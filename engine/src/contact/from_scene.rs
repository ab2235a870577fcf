//! Contact laws of a scene's `[law]` table, in reduced units: [`with_law`] chooses the law's
//! type and its numbers, in one place; the constructors below give the numbers of each family.

use crate::contact::dmt::Dmt;
use crate::contact::hertz_mindlin::{HertzCohesion, HertzMindlin, NoCohesion as HertzNoCohesion};
use crate::contact::linear::{Adhesion, CohesionModel, Linear, NoCohesion};
use crate::contact::sjkr::Sjkr;
use crate::contact::slider::{Coulomb, Friction, Frictionless, NoRolling, NoSlip, RollingSpring};
use crate::contact::ContactLaw;
use crate::geometry::Dim;
use crate::scene::{Law, Mu};

/// What runs with a law once its type is known: a function generic over the law, so that each
/// combination of sub-models gets its own monomorphized kernel.
pub trait WithLaw<D: Dim> {
    type Output;
    fn with<L: ContactLaw<D>>(self, law: L) -> Self::Output;
}

/// Hands `w` the law of `law` with the friction `mu` (a stage's μ: AR07 C and GRC07 change it
/// between stages): the cohesion model, the friction kind (μ = 0, finite, ∞) and the rolling
/// resistance each become a type, and a scene pays only for the physics it uses.
pub fn with_law<D: Dim, W: WithLaw<D>>(law: &Law, mu: Mu, w: W) -> W::Output {
    match law {
        Law::HertzMindlin { sjkr: Some(k), .. } => hertz(law, Sjkr { k: *k }, mu, w),
        Law::HertzMindlin { dmt: Some(g), .. } => hertz(law, Dmt { gamma: *g }, mu, w),
        Law::HertzMindlin { .. } => hertz(law, HertzNoCohesion, mu, w),
        Law::Linear {
            cohesion: Some(c), ..
        } => linear(law, adhesion(c), mu, w),
        Law::Linear { .. } => linear(law, NoCohesion, mu, w),
    }
}

fn hertz<D: Dim, C: HertzCohesion, W: WithLaw<D>>(law: &Law, c: C, mu: Mu, w: W) -> W::Output {
    match mu {
        Mu::Finite(0.0) => w.with(hertz_mindlin_law(law, Frictionless).with_cohesion(c)),
        Mu::Finite(m) => w.with(hertz_mindlin_law(law, Coulomb { mu: m }).with_cohesion(c)),
        Mu::Infinite => w.with(hertz_mindlin_law(law, NoSlip).with_cohesion(c)),
    }
}

fn linear<D: Dim, C: CohesionModel, W: WithLaw<D>>(law: &Law, c: C, mu: Mu, w: W) -> W::Output {
    match mu {
        Mu::Finite(0.0) => linear_rolling(law, c, Frictionless, w),
        Mu::Finite(m) => linear_rolling(law, c, Coulomb { mu: m }, w),
        Mu::Infinite => linear_rolling(law, c, NoSlip, w),
    }
}

fn linear_rolling<D: Dim, C: CohesionModel, F: Friction, W: WithLaw<D>>(
    law: &Law,
    c: C,
    f: F,
    w: W,
) -> W::Output {
    match rolling_spring(law) {
        Some(r) => w.with(linear_law(law, c, f, r)),
        None => w.with(linear_law(law, c, f, NoRolling)),
    }
}

/// The Hertz–Mindlin law of a scene in reduced units: κ = (Ẽ/P_ref)^(2/3) with P_ref = 1
/// (AR07 (21)), so Ẽ = κ^(3/2). Panics if `law` is not Hertz–Mindlin.
pub fn hertz_mindlin_law<F>(law: &Law, friction: F) -> HertzMindlin<F> {
    let Law::HertzMindlin {
        kappa,
        zeta,
        poisson,
        ..
    } = law
    else {
        panic!("hertz_mindlin_law needs a Hertz–Mindlin law")
    };
    HertzMindlin::new(kappa.powf(1.5), *poisson, *zeta, friction)
}

/// The Hertz–Mindlin law of a scene with its SJKR cohesion (LIGGGHTS `cohesion sjkr`), k in
/// units of P_ref. Panics if `law` is not Hertz–Mindlin with `sjkr`.
pub fn sjkr_law<F>(law: &Law, friction: F) -> HertzMindlin<F, Sjkr> {
    let Law::HertzMindlin { sjkr: Some(k), .. } = law else {
        panic!("sjkr_law needs a Hertz–Mindlin law with sjkr")
    };
    hertz_mindlin_law(law, friction).with_cohesion(Sjkr { k: *k })
}

/// The Hertz–Mindlin law of a scene with YADE's DMT adhesion, γ in units of P_ref·a. Panics if
/// `law` is not Hertz–Mindlin with `dmt`.
pub fn dmt_law<F>(law: &Law, friction: F) -> HertzMindlin<F, Dmt> {
    let Law::HertzMindlin { dmt: Some(g), .. } = law else {
        panic!("dmt_law needs a Hertz–Mindlin law with dmt")
    };
    hertz_mindlin_law(law, friction).with_cohesion(Dmt { gamma: *g })
}

/// The linear law of a scene in reduced units (K_N = κ, K_T = κ·kt_over_kn) with the given
/// cohesion, friction and rolling parts. Panics if `law` is not linear.
pub fn linear_law<C, F, R>(law: &Law, cohesion: C, friction: F, rolling: R) -> Linear<C, F, R> {
    let Law::Linear {
        kappa,
        zeta,
        kt_over_kn,
        tangential_damping,
        ..
    } = law
    else {
        panic!("linear_law needs a linear law")
    };
    Linear {
        kn: *kappa,
        kt: kappa * kt_over_kn,
        zeta: *zeta,
        zeta_t: *tangential_damping,
        cohesion,
        friction,
        rolling,
    }
}

/// GRC07 adhesion in reduced units: F0 is the force unit.
pub fn adhesion(c: &crate::scene::Cohesion) -> Adhesion {
    Adhesion { f0: 1.0, d0: c.d0 }
}

/// The rolling spring of a linear law, K_r = kr·K_N a² (GRC07 T.I), if it has one.
pub fn rolling_spring(law: &Law) -> Option<RollingSpring> {
    match law {
        Law::Linear {
            kappa,
            rolling: Some(r),
            ..
        } => Some(RollingSpring {
            kr: r.kr * kappa,
            mu_r: r.mu_r,
        }),
        _ => None,
    }
}
