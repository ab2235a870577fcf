//! Hertz–Mindlin spheres with LIGGGHTS 3.8's `cohesion sjkr` (`cohesion_model_sjkr.h`): in
//! contact, an attraction k·A along the normal, A = πa² the area of the circle in which the
//! two spheres' surfaces intersect, k the cohesion energy density (`cohesionEnergyDensity`);
//! nothing at or beyond first touch (A = 0 there), no range.
//!
//! The law LIGGGHTS runs, term by term: the Hertz normal force and its dashpot
//! ([`HertzMindlin`]), plus −k·A, and a Coulomb cap μ|N| on the *total* normal force (LIGGGHTS
//! adds the cohesion to the normal force before its tangential model reads it). The
//! tangential spring is ours (incremental, Walton-rescaled; LIGGGHTS's `tangential history` is a
//! total-displacement law): frictionless scenes are identical in both codes.

use super::hertz_mindlin::HertzMindlin;
use super::slider::Friction;
use super::{ContactLaw, Pair, PairForce};
use crate::geometry::{Dim, VectorOps};

/// Hertz–Mindlin plus the SJKR attraction k·πa².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sjkr<F> {
    pub hertz: HertzMindlin<F>,
    /// Cohesion energy density k (force per area).
    pub k: f64,
}

/// Area πa² of the circle where two spheres of radii R_i, R_j intersect, for overlap
/// h = R_i + R_j − r ≥ 0: π/4·h(2R_i − h)(2R_j − h)(2(R_i+R_j) − h)/r², written with
/// R_i R_j = r_eff·r_sum and (2R_i − h)(2R_j − h) = 4R_iR_j − h(r + r_sum) so that no
/// difference of near-equal numbers appears (LIGGGHTS writes the same product with r − R_i − R_j).
#[inline(always)]
pub fn contact_area(h: f64, r_eff: f64, r_sum: f64) -> f64 {
    let r = r_sum - h;
    let s = r + r_sum;
    std::f64::consts::FRAC_PI_4 * h * (4.0 * r_eff * r_sum - h * s) * s / (r * r)
}

impl<D: Dim, F: Friction> ContactLaw<D> for Sjkr<F> {
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
        let kn = self.hertz.normal_stiffness(h, p.r_eff);
        let ne = 2.0 / 3.0 * kn * h;
        let vn = p.v_contact.dot(&p.n);
        let alpha = 2.0 * self.hertz.zeta * (p.m_eff * kn).sqrt();
        let normal = ne - alpha * vn - self.k * contact_area(h, p.r_eff, p.r_sum);
        let tangential = if F::ACTIVE {
            let slip = (p.v_contact - p.n * vn) * dt;
            let pivot = 0.5 * D::pivot_rate(p.w_i + p.w_j, p.n) * dt;
            // LIGGGHTS's cap: μ|N| with the attraction and the dashpot in N.
            self.hertz.friction.update::<D>(
                hist,
                p.n,
                pivot,
                slip,
                self.hertz.kt_ratio * kn,
                normal.abs(),
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
        // The attraction softens contacts (dN/dh falls by 2πk R* near first touch).
        <HertzMindlin<F> as ContactLaw<D>>::max_stiffness(&self.hertz, force, r_eff_max)
    }

    fn with_kappa_scaled(&self, factor: f64) -> Self {
        Sjkr {
            hertz: <HertzMindlin<F> as ContactLaw<D>>::with_kappa_scaled(&self.hertz, factor),
            k: self.k,
        }
    }

    fn describe(&self) -> String {
        format!(
            "{} sjkr k={}",
            <HertzMindlin<F> as ContactLaw<D>>::describe(&self.hertz),
            self.k
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

    fn pair(h: f64, ri: f64, rj: f64, vn: f64) -> Pair<D3> {
        Pair {
            n: V3::new(1.0, 0.0, 0.0),
            gap: -h,
            v_contact: V3::new(vn, 0.0, 0.0),
            w_i: V3::zeros(),
            w_j: V3::zeros(),
            r_eff: ri * rj / (ri + rj),
            m_eff: 0.5,
            r_sum: ri + rj,
        }
    }

    /// The contact circle from the two spheres' equations: x² + ρ² = R_i², (x − r)² + ρ² = R_j².
    #[test]
    fn contact_area_is_the_intersection_circle() {
        for (ri, rj, h) in [(0.5, 0.5, 1e-3), (0.25, 0.5, 3e-4), (0.5, 0.3, 0.05)] {
            let r: f64 = ri + rj - h;
            let x = (r * r + ri * ri - rj * rj) / (2.0 * r);
            let rho2 = ri * ri - x * x;
            let a = contact_area(h, ri * rj / (ri + rj), ri + rj);
            assert!(
                (a - std::f64::consts::PI * rho2).abs() < 1e-12 * a,
                "{a} {}",
                std::f64::consts::PI * rho2
            );
        }
        // Small overlaps: πa² → 2πR*h.
        let a = contact_area(1e-9, 0.25, 1.0);
        assert!((a / (2.0 * std::f64::consts::PI * 0.25 * 1e-9) - 1.0).abs() < 1e-8);
    }

    #[test]
    fn attraction_adds_to_hertz_in_contact_only() {
        let hertz = HertzMindlin::new(1e6, 0.3, 0.5, Frictionless);
        let law = Sjkr { hertz, k: 5000.0 };
        let mut hist = ();
        for (h, v) in [(1e-4, 0.0), (5e-4, 0.02), (2e-3, -0.01)] {
            let p = pair(h, 0.5, 0.35, v);
            let ours = ContactLaw::<D3>::interact(&law, &p, &mut hist, 1e-4);
            let plain = ContactLaw::<D3>::interact(&hertz, &p, &mut hist, 1e-4);
            let want = plain.normal - 5000.0 * contact_area(h, p.r_eff, p.r_sum);
            assert!((ours.normal - want).abs() < 1e-12 * want.abs().max(1.0));
            assert_eq!(ours.normal_elastic, plain.normal_elastic);
        }
        // Apart or just touching: nothing.
        for gap in [0.0, 1e-6] {
            let mut p = pair(0.0, 0.5, 0.5, 0.0);
            p.gap = gap;
            assert_eq!(
                ContactLaw::<D3>::interact(&law, &p, &mut hist, 1e-4).normal,
                0.0
            );
        }
    }
}
