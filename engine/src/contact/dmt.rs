//! Hertz–Mindlin spheres with YADE's DMT adhesion (`Law2_ScGeom_MindlinPhys_Mindlin` with
//! `includeAdhesion=True`, `Ip2_FrictMat_FrictMat_MindlinPhys(gamma=γ)`): in contact a constant
//! pull F_a = 4πR*γ (the Derjaguin–Muller–Toporov pull-off force, R* = R_i R_j/(R_i+R_j)),
//! nothing apart (YADE erases the interaction at first separation).
//!
//! The law YADE runs, term by term: N = (2/3)Ẽ√R* h^{3/2} − F_a − α v_n with the dashpot α of
//! [`HertzMindlin`] (on the plain normal relative velocity: YADE's (R_i+R_j)/r scaling reaches
//! only its tangential slip, comparisons/tests/yade_two_particle.rs), a dashpot that may not
//! pull harder than F_a while the total force is tensile, and the Coulomb cap μ(|N| + F_a). The
//! tangential spring is ours (incremental, Walton-rescaled; YADE's keeps T when N drops):
//! frictionless scenes are identical in both codes.

use super::hertz_mindlin::HertzMindlin;
use super::slider::Friction;
use super::{ContactLaw, Pair, PairForce};
use crate::geometry::{Dim, VectorOps};

/// Hertz–Mindlin plus YADE's DMT pull 4πR*γ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dmt<F> {
    pub hertz: HertzMindlin<F>,
    /// Surface energy γ (force per length).
    pub gamma: f64,
}

impl<D: Dim, F: Friction> ContactLaw<D> for Dmt<F> {
    type History = F::State<D>;
    const MOMENTS: bool = F::ACTIVE;
    const ROLLING: bool = false;

    #[inline(always)]
    fn range(&self) -> f64 {
        0.0
    }

    #[inline(always)]
    fn interact(&self, p: &Pair<D>, hist: &mut Self::History, dt: f64) -> PairForce<D> {
        // YADE keeps the interaction at penetrationDepth = 0 (it erases it below 0).
        if p.gap > 0.0 {
            *hist = Default::default();
            return PairForce::default();
        }
        let h = -p.gap;
        let kn = self.hertz.normal_stiffness(h, p.r_eff);
        let ne = 2.0 / 3.0 * kn * h;
        let pull = 4.0 * std::f64::consts::PI * p.r_eff * self.gamma;
        let vn = p.v_contact.dot(&p.n);
        let alpha = 2.0 * self.hertz.zeta * (p.m_eff * kn).sqrt();
        let mut viscous = alpha * vn;
        // A tensile total may not owe more than F_a to the dashpot.
        if ne - pull - viscous < 0.0 && viscous.abs() > pull {
            viscous = pull.copysign(viscous);
        }
        let normal = ne - pull - viscous;
        let tangential = if F::ACTIVE {
            let slip = (p.v_contact - p.n * vn) * dt;
            let pivot = 0.5 * D::pivot_rate(p.w_i + p.w_j, p.n) * dt;
            // YADE's cap with adhesion (Thornton 1991): μ(|N| + F_a).
            self.hertz.friction.update::<D>(
                hist,
                p.n,
                pivot,
                slip,
                self.hertz.kt_ratio * kn,
                normal.abs() + pull,
            )
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
        // As Hertz–Mindlin (the decks' time step is the Hertz one): the pull deepens overlaps
        // by F_a's worth, which `numerics.stiffness_force` (10 P a² by default) must cover.
        <HertzMindlin<F> as ContactLaw<D>>::max_stiffness(&self.hertz, force, r_eff_max)
    }

    fn with_kappa_scaled(&self, factor: f64) -> Self {
        Dmt {
            hertz: <HertzMindlin<F> as ContactLaw<D>>::with_kappa_scaled(&self.hertz, factor),
            gamma: self.gamma,
        }
    }

    fn describe(&self) -> String {
        format!(
            "{} dmt γ={}",
            <HertzMindlin<F> as ContactLaw<D>>::describe(&self.hertz),
            self.gamma
        )
    }

    fn stored(&self, hist: &Self::History) -> (D::V, D::Ang) {
        (F::force::<D>(hist), D::Ang::zero())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::slider::Frictionless;
    use crate::geometry::D3;
    use nalgebra::Vector3 as V3;

    fn pair(h: f64, vn: f64) -> Pair<D3> {
        Pair {
            n: V3::new(1.0, 0.0, 0.0),
            gap: -h,
            v_contact: V3::new(vn, 0.0, 0.0),
            w_i: V3::zeros(),
            w_j: V3::zeros(),
            r_eff: 0.25,
            m_eff: 0.5,
            r_sum: 1.0,
        }
    }

    #[test]
    fn constant_pull_in_contact_and_a_capped_dashpot() {
        let hertz = HertzMindlin::new(1e6, 0.3, 0.5, Frictionless);
        let law = Dmt { hertz, gamma: 0.1 };
        let pull = 4.0 * std::f64::consts::PI * 0.25 * 0.1;
        let at = |h: f64, v: f64| ContactLaw::<D3>::interact(&law, &pair(h, v), &mut (), 0.0);
        // At rest: Hertz minus the pull, from first touch on.
        for h in [0.0, 1e-5, 1e-3] {
            let want = hertz.normal_force(h, 0.25) - pull;
            assert!((at(h, 0.0).normal - want).abs() < 1e-12, "{h}");
        }
        // Apart: nothing.
        let mut p = pair(0.0, 0.0);
        p.gap = 1e-9;
        assert_eq!(
            ContactLaw::<D3>::interact(&law, &p, &mut (), 0.0).normal,
            0.0
        );
        // Receding fast at a small overlap: the dashpot's pull is capped at F_a, total −2F_a.
        assert!(
            (at(1e-7, 10.0).normal - (hertz.normal_force(1e-7, 0.25) - 2.0 * pull)).abs() < 1e-9
        );
        // Slowly: the plain dashpot.
        let (h, v) = (1e-4, 1e-3);
        let kn = hertz.normal_stiffness(h, 0.25);
        let visc = 2.0 * 0.5 * (0.5 * kn).sqrt() * v;
        assert!((at(h, v).normal - (hertz.normal_force(h, 0.25) - pull - visc)).abs() < 1e-12);
    }
}
