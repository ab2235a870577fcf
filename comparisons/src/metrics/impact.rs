//! Two-body impacts (the classic DEM validation tests): from a time series of
//! snapshots of two grains, the contact duration, the peak normal force, the normal and
//! tangential coefficients of restitution, the incidence and rebound angles and the spins;
//! and the analytic values they are checked against — Hertz's elastic impact and the impulse
//! balance of an impact that slides throughout.

use grainbench_engine::scene::{Law, Mu, Scene};
use grainbench_engine::snapshot::Snapshot;
use serde::{Deserialize, Serialize};

/// Measured impact of grains 0 and 1.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Impact {
    /// First and last frame with the pair in contact (positive normal force or overlap).
    pub contact_start: f64,
    pub contact_end: f64,
    /// `contact_end − contact_start` plus one frame interval (the frames bracket the contact).
    pub duration: f64,
    /// Time between the frames around the contact's start.
    pub frame_interval: f64,
    pub peak_normal_force: f64,
    /// Approach speed along the line of centres at the first frame (> 0), and the separation
    /// speed along it at the last frame (> 0).
    pub normal_speed_before: f64,
    pub normal_speed_after: f64,
    /// Tangential speed of the contact points (translation and spin) before and after.
    pub tangential_speed_before: f64,
    pub tangential_speed_after: f64,
    /// e_n = v_n'/v_n.
    pub restitution_normal: f64,
    /// e_t = v_t'/v_t (signed along the incoming tangential direction; `None` head-on).
    pub restitution_tangential: Option<f64>,
    /// Angles of the contact-point relative velocity to the normal, degrees.
    pub incidence_angle: f64,
    pub rebound_angle: f64,
    /// Angular velocity of each grain at the first frame (1 component in 2D, 3 in 3D; empty
    /// in impact.json files written before spinning starts were possible: at rest).
    #[serde(default)]
    pub spin_before: Vec<Vec<f64>>,
    /// Angular velocity of each grain at the last frame.
    pub spin_after: Vec<Vec<f64>>,
}

impl Impact {
    /// |ω_after − ω_before| of grain `k`.
    pub fn spin_change(&self, k: usize) -> f64 {
        let after = self
            .spin_after
            .get(k)
            .map(Vec::as_slice)
            .unwrap_or_default();
        let before = self
            .spin_before
            .get(k)
            .map(Vec::as_slice)
            .unwrap_or_default();
        let at = |w: &[f64], a: usize| w.get(a).copied().unwrap_or(0.0);
        (0..after.len().max(before.len()))
            .map(|a| (at(after, a) - at(before, a)).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

/// Hertz's elastic impact (no damping): N = K h^{3/2}, K = (2/3) Ẽ √R* (AR07 (1)).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Hertz {
    pub max_overlap: f64,
    pub peak_normal_force: f64,
    pub duration: f64,
}

/// 2 ∫₀¹ dx/√(1 − x^{5/2}): t_c = this × h_max / v.
pub const HERTZ_DURATION_FACTOR: f64 = 2.943_275_6;

impl Hertz {
    /// For effective mass `m_eff`, stiffness `k` = (2/3) Ẽ √R* and approach speed `v`.
    pub fn new(m_eff: f64, k: f64, v: f64) -> Hertz {
        // ½ m* v² = (2/5) K h_max^{5/2}.
        let h = (5.0 * m_eff * v * v / (4.0 * k)).powf(0.4);
        Hertz {
            max_overlap: h,
            peak_normal_force: k * h.powf(1.5),
            duration: HERTZ_DURATION_FACTOR * h / v,
        }
    }
}

/// Tangential speed of the contact points after an impact that slides throughout with
/// friction μ: the tangential impulse is μ times the normal one, m*(1 + e) v_n, and changes the
/// contact-point speed by it times (1/m₀ + 1/m₁ + R₀²/I₀ + R₁²/I₁) (Maw, Barber & Fawcett;
/// valid while the result stays above 0). Also the spin each grain gains, |Δω| = μ J_n R/I
/// (the contact-point speed includes the spins the grains come in with).
pub fn sliding_throughout(
    masses: [f64; 2],
    radii: [f64; 2],
    inertia: [f64; 2],
    mu: f64,
    e: f64,
    v_n: f64,
    v_t: f64,
) -> (f64, [f64; 2]) {
    let m_eff = masses[0] * masses[1] / (masses[0] + masses[1]);
    let j_n = m_eff * (1.0 + e) * v_n;
    let compliance = 1.0 / masses[0]
        + 1.0 / masses[1]
        + radii[0] * radii[0] / inertia[0]
        + radii[1] * radii[1] / inertia[1];
    (
        v_t - mu * j_n * compliance,
        [
            mu * j_n * radii[0] / inertia[0],
            mu * j_n * radii[1] / inertia[1],
        ],
    )
}

struct Kinematics {
    v_n: f64,
    v_t: Vec<f64>,
}

/// Relative motion of grain 1 seen from grain 0 with the velocities of frame `s` and the
/// line of centres of frame `at` (the first or last frame in contact: in free flight the
/// velocities do not change, the line of centres does): along the unit normal from 0 to 1 (nearest
/// image), the approach speed and the tangential contact-point velocity.
fn kinematics(s: &Snapshot, at: &Snapshot) -> Kinematics {
    let p = &s.particles;
    let d = s.dimension;
    let l = &at.cell.lengths;
    let q = &at.particles;
    let mut n: Vec<f64> = (0..d)
        .map(|a| {
            let x = q.position[1][a] - q.position[0][a];
            x - l[a] * (x / l[a]).round()
        })
        .collect();
    let len = n.iter().map(|x| x * x).sum::<f64>().sqrt();
    n.iter_mut().for_each(|x| *x /= len);
    let (r0, r1) = (p.radius[0], p.radius[1]);
    // Contact-point velocities: v + ω × r, r = R n from grain 0, −R n from grain 1.
    let spin = |i: usize, arm: &[f64]| -> Vec<f64> {
        let w = p.angular_velocity.get(i).cloned().unwrap_or_default();
        if d == 2 {
            let wz = w.first().copied().unwrap_or(0.0);
            vec![-wz * arm[1], wz * arm[0]]
        } else {
            let w = [0, 1, 2].map(|k| w.get(k).copied().unwrap_or(0.0));
            vec![
                w[1] * arm[2] - w[2] * arm[1],
                w[2] * arm[0] - w[0] * arm[2],
                w[0] * arm[1] - w[1] * arm[0],
            ]
        }
    };
    let arm0: Vec<f64> = n.iter().map(|x| r0 * x).collect();
    let arm1: Vec<f64> = n.iter().map(|x| -r1 * x).collect();
    let (s0, s1) = (spin(0, &arm0), spin(1, &arm1));
    let rel: Vec<f64> = (0..d)
        .map(|a| p.velocity[1][a] + s1[a] - p.velocity[0][a] - s0[a])
        .collect();
    let along: f64 = rel.iter().zip(&n).map(|(v, n)| v * n).sum();
    Kinematics {
        v_n: -along,
        v_t: (0..d).map(|a| rel[a] - along * n[a]).collect(),
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The impact of grains 0 and 1 in `frames` (in time order, the first before contact, the last
/// after separation); `None` without a contact, or with the pair still in contact at the end.
pub fn measure(frames: &[Snapshot]) -> Option<Impact> {
    let in_contact = |s: &Snapshot| {
        s.contacts.iter().any(|c| {
            ((c.i, c.j) == (0, 1) || (c.i, c.j) == (1, 0)) && (c.gap < 0.0 || c.normal != 0.0)
        })
    };
    let first = frames.iter().position(in_contact)?;
    let last = frames.iter().rposition(in_contact)?;
    if last + 1 >= frames.len() || first == 0 || frames[0].particles.radius.len() < 2 {
        return None;
    }
    let peak = frames[first..=last]
        .iter()
        .flat_map(|s| s.contacts.iter().map(|c| c.normal))
        .fold(f64::NEG_INFINITY, f64::max);
    let before = kinematics(&frames[0], &frames[first]);
    let after = kinematics(&frames[frames.len() - 1], &frames[last]);
    // Tangential directions: the incoming one; after, its component along it.
    let t_in = norm(&before.v_t);
    let e_t = (t_in > 1e-12 * before.v_n.abs()).then(|| {
        after
            .v_t
            .iter()
            .zip(&before.v_t)
            .map(|(a, b)| a * b)
            .sum::<f64>()
            / (t_in * t_in)
    });
    let step = frames[first].time - frames[first - 1].time;
    Some(Impact {
        contact_start: frames[first].time,
        contact_end: frames[last].time,
        duration: frames[last].time - frames[first].time + step,
        frame_interval: step,
        peak_normal_force: peak,
        normal_speed_before: before.v_n,
        normal_speed_after: -after.v_n,
        tangential_speed_before: t_in,
        tangential_speed_after: norm(&after.v_t),
        restitution_normal: -after.v_n / before.v_n,
        restitution_tangential: e_t,
        incidence_angle: t_in.atan2(before.v_n).to_degrees(),
        rebound_angle: norm(&after.v_t).atan2(-after.v_n).to_degrees(),
        spin_before: spins(&frames[0]),
        spin_after: spins(&frames[frames.len() - 1]),
    })
}

/// Angular velocity of each grain of a frame.
fn spins(frame: &Snapshot) -> Vec<Vec<f64>> {
    frame
        .particles
        .angular_velocity
        .iter()
        .map(|w| w.to_vec())
        .collect()
}

/// What `impact.json` holds.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ImpactReport {
    pub measured: Impact,
    /// Hertz's elastic impact (ζ = 0) for the measured approach speed.
    pub hertz: Option<Hertz>,
    /// Tangential contact-point speed and spins after an impact that slides throughout (ζ = 0,
    /// finite μ), when the impulse balance says it does.
    pub sliding: Option<Sliding>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Sliding {
    pub tangential_speed_after: f64,
    pub spin_gained: [f64; 2],
}

/// `measured` beside the analytic values of an undamped Hertz–Mindlin pair (`first`: a frame
/// before the contact, for the masses and radii).
pub fn against_theory(scene: &Scene, s: &Snapshot, measured: Impact) -> ImpactReport {
    let (kappa, mu) = match &scene.law {
        Law::HertzMindlin {
            kappa,
            mu,
            zeta,
            sjkr: None,
            dmt: None,
            ..
        } if *zeta == 0.0 && s.dimension == 3 => (kappa, mu),
        _ => {
            return ImpactReport {
                measured,
                hertz: None,
                sliding: None,
            }
        }
    };
    let p = &s.particles;
    let (m, r) = ([p.mass[0], p.mass[1]], [p.radius[0], p.radius[1]]);
    let m_eff = m[0] * m[1] / (m[0] + m[1]);
    let r_eff = r[0] * r[1] / (r[0] + r[1]);
    // AR07 (1): N = (2/3) Ẽ √R* h^{3/2}, Ẽ = κ^{3/2} in reduced units.
    let k = 2.0 / 3.0 * kappa.powf(1.5) * r_eff.sqrt();
    let v_n = measured.normal_speed_before;
    let hertz = Some(Hertz::new(m_eff, k, v_n));
    let sliding = match mu {
        Mu::Finite(mu) if *mu > 0.0 && measured.tangential_speed_before > 0.0 => {
            let inertia = [0.4 * m[0] * r[0] * r[0], 0.4 * m[1] * r[1] * r[1]];
            let (vt, dw) = sliding_throughout(
                m,
                r,
                inertia,
                *mu,
                1.0,
                v_n,
                measured.tangential_speed_before,
            );
            (vt > 0.0).then_some(Sliding {
                tangential_speed_after: vt,
                spin_gained: dw,
            })
        }
        _ => None,
    };
    ImpactReport {
        measured,
        hertz,
        sliding,
    }
}

/// One measured quantity of an impact against its analytic value.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Check {
    pub quantity: String,
    pub measured: f64,
    pub expected: f64,
    /// Allowed |measured/expected − 1|.
    pub tolerance: f64,
}

impl Check {
    pub fn deviation(&self) -> f64 {
        self.measured / self.expected - 1.0
    }

    pub fn passed(&self) -> bool {
        self.deviation().abs() <= self.tolerance
    }
}

/// Allowed relative deviations from the analytic values, set before any code was run against
/// them: the peak force and e_n to 1 % (an O(dt²) integrator with ~100 steps in contact does
/// far better); the duration to 1 % plus one frame interval (the frames bracket the contact);
/// the sliding impulse balance to 2 % (it holds the line of centres fixed, which turns by
/// ~v_t t_c / (R₀ + R₁) during the contact: 0.4 % in `impact-oblique`).
pub const PEAK_TOLERANCE: f64 = 0.01;
pub const RESTITUTION_TOLERANCE: f64 = 0.01;
pub const DURATION_TOLERANCE: f64 = 0.01;
pub const SLIDING_TOLERANCE: f64 = 0.02;

impl ImpactReport {
    /// The measured values against Hertz (and the sliding balance where it applies).
    pub fn checks(&self) -> Vec<Check> {
        let m = &self.measured;
        let mut out = Vec::new();
        let mut push = |q: &str, measured: f64, expected: f64, tolerance: f64| {
            out.push(Check {
                quantity: q.into(),
                measured,
                expected,
                tolerance,
            })
        };
        if let Some(h) = &self.hertz {
            push(
                "duration",
                m.duration,
                h.duration,
                DURATION_TOLERANCE + m.frame_interval / h.duration,
            );
            push(
                "peak normal force",
                m.peak_normal_force,
                h.peak_normal_force,
                PEAK_TOLERANCE,
            );
            push("e_n", m.restitution_normal, 1.0, RESTITUTION_TOLERANCE);
        }
        if let Some(sl) = &self.sliding {
            push(
                "v_t after",
                m.tangential_speed_after,
                sl.tangential_speed_after,
                SLIDING_TOLERANCE,
            );
            for k in 0..m.spin_after.len().min(2) {
                push(
                    &format!("spin {k} gained"),
                    m.spin_change(k),
                    sl.spin_gained[k],
                    SLIDING_TOLERANCE,
                );
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hertz_duration_factor_is_the_integral() {
        // 2 ∫₀¹ dx/√(1 − x^{5/2}) by the substitution x = 1 − u², midpoint rule.
        let n = 200_000;
        let mut s = 0.0;
        for k in 0..n {
            let u = (k as f64 + 0.5) / n as f64;
            let x: f64 = 1.0 - u * u;
            s += 2.0 * u / (1.0 - x.powf(2.5)).sqrt() / n as f64;
        }
        assert!(
            (2.0 * s - HERTZ_DURATION_FACTOR).abs() < 1e-5,
            "{}",
            2.0 * s
        );
        let h = Hertz::new(0.5, 2.0, 0.1);
        assert!((0.5 * 0.5 * 0.01 - 0.4 * 2.0 * h.max_overlap.powf(2.5)).abs() < 1e-15);
    }

    #[test]
    fn sliding_throughout_balances_the_impulses() {
        // Equal spheres, I = (2/5) m R²: Δv_t = 7 μ J_n / m = 3.5 μ (1 + e) v_n.
        let (vt, dw) = sliding_throughout([1.0; 2], [0.5; 2], [0.1; 2], 0.3, 1.0, 1.0, 5.0);
        assert!((vt - (5.0 - 3.5 * 0.3 * 2.0)).abs() < 1e-12);
        assert!((dw[0] - 0.3 * 1.0 * 0.5 / 0.1).abs() < 1e-12);
    }
}
