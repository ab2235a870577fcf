//! YADE's DMT adhesion (`Law2_ScGeom_MindlinPhys_Mindlin` with `includeAdhesion=True`,
//! `Ip2_FrictMat_FrictMat_MindlinPhys(gamma=γ)`) as a cohesion model of
//! [`HertzMindlin`](super::hertz_mindlin::HertzMindlin): in contact a constant pull
//! F_a = 4πR*γ (the Derjaguin–Muller–Toporov pull-off force, R* = R_i R_j/(R_i+R_j)), nothing
//! apart (YADE erases the interaction at separation).
//!
//! The law YADE runs, term by term: N = (2/3)Ẽ√R* h^{3/2} − F_a − α v_n with the Hertz dashpot α
//! on the plain normal relative velocity (YADE's (R_i+R_j)/r scaling reaches only its tangential
//! slip, comparisons/tests/yade_two_particle.rs), a dashpot that may not pull harder than F_a
//! while the total force is tensile, and the Coulomb cap μ(|N| + F_a) (Thornton 1991). The
//! tangential spring is ours (incremental, Walton-rescaled; YADE's keeps T when N drops):
//! frictionless scenes are identical in both codes.

use super::hertz_mindlin::HertzCohesion;
use super::Pair;
use crate::geometry::Dim;

/// YADE's DMT pull 4πR*γ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dmt {
    /// Surface energy γ (force per length).
    pub gamma: f64,
}

impl HertzCohesion for Dmt {
    const ACTIVE: bool = true;

    #[inline(always)]
    fn normal<D: Dim>(&self, ne: f64, viscous: f64, p: &Pair<D>) -> (f64, f64) {
        let pull = 4.0 * std::f64::consts::PI * p.r_eff * self.gamma;
        // A tensile total may not owe more than F_a to the dashpot.
        let viscous = if ne - pull - viscous < 0.0 && viscous.abs() > pull {
            pull.copysign(viscous)
        } else {
            viscous
        };
        let n = ne - pull - viscous;
        (n, n.abs() + pull)
    }

    fn describe(&self) -> String {
        format!(" dmt γ={}", self.gamma)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::hertz_mindlin::HertzMindlin;
    use crate::contact::slider::Frictionless;
    use crate::contact::ContactLaw;
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
        let law = hertz.with_cohesion(Dmt { gamma: 0.1 });
        let pull = 4.0 * std::f64::consts::PI * 0.25 * 0.1;
        let at = |h: f64, v: f64| ContactLaw::<D3>::interact(&law, &pair(h, v), &mut (), 0.0);
        // At rest: Hertz minus the pull.
        for h in [1e-9, 1e-5, 1e-3] {
            let want = hertz.normal_force(h, 0.25) - pull;
            assert!((at(h, 0.0).normal - want).abs() < 1e-12, "{h}");
        }
        // Apart or just touching: nothing.
        for gap in [0.0, 1e-9] {
            let mut p = pair(0.0, 0.0);
            p.gap = gap;
            assert_eq!(
                ContactLaw::<D3>::interact(&law, &p, &mut (), 0.0).normal,
                0.0
            );
        }
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
