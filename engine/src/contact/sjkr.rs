//! LIGGGHTS 3.8's `cohesion sjkr` (`cohesion_model_sjkr.h`) as a cohesion model of
//! [`HertzMindlin`](super::hertz_mindlin::HertzMindlin): in contact, an attraction k·A along the
//! normal, A = πa² the area of the circle in which the two spheres' surfaces intersect, k the
//! cohesion energy density (`cohesionEnergyDensity`); nothing at or beyond first touch (A = 0
//! there), no range.
//!
//! The law LIGGGHTS runs, term by term: the Hertz normal force and its dashpot, plus −k·A, and a
//! Coulomb cap μ|N| on the *total* normal force (LIGGGHTS adds the cohesion to the normal force
//! before its tangential model reads it). The tangential spring is ours (incremental,
//! Walton-rescaled; LIGGGHTS's `tangential history` is a total-displacement law): frictionless
//! scenes are identical in both codes.

use super::hertz_mindlin::HertzCohesion;
use super::Pair;
use crate::geometry::Dim;

/// The SJKR attraction k·πa².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sjkr {
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

impl HertzCohesion for Sjkr {
    const ACTIVE: bool = true;

    #[inline(always)]
    fn normal<D: Dim>(&self, ne: f64, viscous: f64, p: &Pair<D>) -> (f64, f64) {
        let n = ne - viscous - self.k * contact_area(-p.gap, p.r_eff, p.r_sum);
        // LIGGGHTS's cap: μ|N| with the attraction and the dashpot in N.
        (n, n.abs())
    }

    fn describe(&self) -> String {
        format!(" sjkr k={}", self.k)
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
        let law = hertz.with_cohesion(Sjkr { k: 5000.0 });
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
