//! Contact laws of a scene's `[law]` table, in reduced units.

use crate::contact::dmt::Dmt;
use crate::contact::hertz_mindlin::HertzMindlin;
use crate::contact::linear::{Adhesion, Linear};
use crate::contact::sjkr::Sjkr;
use crate::contact::slider::RollingSpring;
use crate::scene::Law;

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
