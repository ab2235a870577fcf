//! The numerics of one DEM stage, resolved once from the scene and the stage and handed to
//! the time step, the checks and the output instead of the scene (as rapier hands its
//! `IntegrationParameters` to the pipeline).

use crate::contact::ContactLaw;
use crate::geometry::Dim;
use crate::scene::{Criteria, ForceScale, Law, Mu, Relax, Scene, Step};
use crate::system::System;

/// What a DEM stage reads from the scene: time step, check cadence, blow-up limit, equilibrium
/// criteria with their force unit, and the law's thresholds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StageNumerics {
    /// `numerics.dt_fraction`: the time step as a fraction of the binary contact duration.
    pub dt_fraction: f64,
    /// Normal force at which K_max is evaluated: `numerics.stiffness_force` × the largest
    /// pressure of the protocol (at least the force unit).
    pub stiffness_force: f64,
    /// `numerics.check_every`: steps between checks.
    pub check_every: u64,
    /// `numerics.max_overlap`: overlap (fraction of the smaller radius) that stops the run.
    pub max_overlap: f64,
    /// Stiffness of the stage over the law's: κ_stage/κ (1 without a κ override).
    pub kappa_factor: f64,
    /// Equilibrium criteria of the stage (AR07 §III, GRC07 §II.D, [`Criteria`]): largest
    /// net force, net moment, stress deviation and kinetic energy per grain, in units of the
    /// force scale `f_ref` (F_ref, F_ref·a, F_ref/a^(d−1), F_ref·a).
    pub force: f64,
    pub moment: f64,
    pub stress: f64,
    pub kinetic: f64,
    pub f_ref: f64,
    /// `compress`: the stress criterion applies. `aggregate`: the stage ends at one cluster.
    /// `full_time`: a fixed-volume stage runs its whole time.
    pub compress: bool,
    pub aggregate: bool,
    pub full_time: bool,
    /// Time limit of the stage, and the time over which every check must meet the criteria
    /// before it ends (`criteria.window`, 0: the first check that meets them).
    pub max_time: f64,
    pub window: f64,
    /// `criteria.quench`: velocities set to zero at a check where only the kinetic criterion
    /// fails (AR07 §III.A, engine/src/run/quench.rs).
    pub quench: bool,
    /// The stage's final relaxation, if any (engine/src/run/relax.rs).
    pub relax: Option<Relax>,
    /// The law has GRC07 adhesion (force unit F0, time unit T0).
    pub cohesive: bool,
    /// The law attracts (GRC07 adhesion or SJKR): snapshots count contacts by the cohesive rule.
    pub attractive: bool,
    /// The law's friction coefficient and rolling threshold μ_r (∞ without rolling
    /// resistance), for the snapshot and the contacts at a threshold.
    pub mu: Mu,
    pub mu_r: f64,
    /// `numerics.servo_gain`: stress control by the first-order servo, not AR07 (7).
    pub servo_gain: Option<f64>,
}

impl StageNumerics {
    /// The numerics outside any stage (the time step of a new system, snapshots): κ of the
    /// law, AR07 criteria, F_ref = 1.
    pub fn of_scene(scene: &Scene) -> Self {
        let n = &scene.numerics;
        let ar07 = Criteria::ar07();
        StageNumerics {
            dt_fraction: n.dt_fraction,
            stiffness_force: n.stiffness_force * force_scale(scene),
            check_every: n.check_every,
            max_overlap: n.max_overlap,
            kappa_factor: 1.0,
            force: ar07.force,
            moment: ar07.moment,
            stress: ar07.pressure,
            kinetic: ar07.kinetic,
            f_ref: 1.0,
            compress: false,
            aggregate: false,
            full_time: false,
            max_time: 0.0,
            window: 0.0,
            quench: false,
            relax: None,
            cohesive: scene.law.cohesion().is_some(),
            attractive: scene.law.attractive(),
            mu: scene.law.mu(),
            mu_r: match &scene.law {
                Law::Linear {
                    rolling: Some(r), ..
                } => r.mu_r,
                _ => f64::INFINITY,
            },
            servo_gain: n.servo_gain,
        }
    }

    /// The numerics of DEM stage `step`, after the pressure `pressure` was last prescribed
    /// (`None` before any `compress` stage).
    pub fn of_stage(scene: &Scene, step: &Step, pressure: Option<f64>) -> Self {
        let pressure = match step {
            Step::Compress { pressure, .. } => Some(*pressure),
            _ => pressure,
        };
        let criteria = step.criteria();
        StageNumerics {
            // κ of the stage (GRC07 §III.B.2 ramps), always scaled from the scene's law so
            // that a resumed run has the same law bit for bit.
            kappa_factor: step.kappa().map_or(1.0, |k| k / scene.law.kappa()),
            f_ref: match criteria.scale {
                ForceScale::Pressure => pressure.unwrap_or(1.0),
                ForceScale::Cohesion => pressure.unwrap_or(0.0).max(1.0),
            },
            force: criteria.force,
            moment: criteria.moment,
            stress: criteria.pressure,
            kinetic: criteria.kinetic,
            compress: matches!(step, Step::Compress { .. }),
            aggregate: matches!(step, Step::Aggregate { .. }),
            full_time: matches!(
                step,
                Step::FixedVolume {
                    full_time: true,
                    ..
                }
            ),
            max_time: step.max_time(),
            window: criteria.window,
            quench: criteria.quench,
            relax: step.relax(),
            ..Self::of_scene(scene)
        }
    }

    /// Time step from the stiffest contact: `dt_fraction` of the binary contact duration
    /// π√(m_eff/K_max) of the two lightest grains. Returns (dt, K_max).
    pub fn time_step<D: Dim, L: ContactLaw<D>>(&self, sys: &System<D, L>) -> (f64, f64) {
        let m_min = sys.mass.iter().cloned().fold(f64::INFINITY, f64::min);
        let r_max = sys.radius.iter().cloned().fold(0.0, f64::max);
        let k_max = sys.law.max_stiffness(self.stiffness_force, 0.5 * r_max);
        let t_c = std::f64::consts::PI * (0.5 * m_min / k_max).sqrt();
        (self.dt_fraction * t_c, k_max)
    }
}

/// Largest pressure any step asks for (at least the force unit).
fn force_scale(scene: &Scene) -> f64 {
    scene
        .stages()
        .iter()
        .filter_map(|(_, s)| match s {
            Step::Compress { pressure, .. } => Some(*pressure),
            _ => None,
        })
        .fold(1.0, f64::max)
}
