//! The run's protocol resolved once into absolute reduced units: what each stage does to the
//! cell, with which law numbers, time step, criteria and time limit. Built from the scene and
//! the grains (the time step depends on the lightest grain and the largest radius), validated
//! once, and read by every consumer — the stage loop, the cross-code decks, the exchange format
//! and `grainbench plan` — so that no consumer derives a stage quantity itself (as rapier hands
//! its `IntegrationParameters` to the pipeline).
//!
//! Units: lengths in a (the largest diameter), masses in the mass of a grain of diameter a,
//! forces in the scene's force unit (P_ref a^(d−1), AR07 (21); F0 with cohesion, GRC07 (12)),
//! times in the matching unit.

use crate::contact::from_scene::{hertz_mindlin_law, linear_law};
use crate::contact::hertz_mindlin::HertzMindlin;
use crate::contact::linear::{Linear, NoCohesion};
use crate::contact::slider::{Frictionless, NoRolling};
use crate::contact::ContactLaw;
use crate::geometry::{Dim, D2, D3};
use crate::scene::{Criteria, ForceScale, Law, Mu, Relax, Scene, Step};
use serde::{Deserialize, Serialize};

/// One stage of the protocol: a DEM stage with its numerics, or a hard-grain stage.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[allow(clippy::large_enum_variant)] // a few dozen steps, built once per run: Copy is worth more
pub enum PlanStep {
    Dem(PlanStage),
    Hard(HardStage),
}

/// A hard-grain stage (event-driven dynamics, no contact law): run by grainbench before or
/// between the DEM stages.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum HardStage {
    /// Every length of the cell × `factor` (AR07 §IV.B: 1.005 before the hard-sphere mix).
    Expand { factor: f64 },
    /// Event-driven elastic collisions, `collisions_per_grain` on average (AR07 §III.A).
    HardSphereMix { collisions_per_grain: f64 },
    /// Lubachevsky–Stillinger growth to `packing_fraction` at growth `rate` (AR07 §IV.A).
    Grow { packing_fraction: f64, rate: f64 },
}

/// What a DEM stage does to the cell and how it ends.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum StageKind {
    /// Isotropic stress control to `pressure` (force unit / a^(d−1)), AR07 (6)–(8).
    Compress { pressure: f64 },
    /// Fixed cell; `full_time`: the stage runs its whole time even when the criteria hold.
    FixedVolume { full_time: bool },
    /// Fixed cell until the grains form one cluster (GRC07 §III.B, method 2).
    Aggregate,
}

/// Equilibrium criteria in absolute units (AR07 §III, GRC07 §II.D): largest net force and net
/// moment on a grain, largest deviation of a diagonal contact stress from the target, kinetic
/// energy per grain.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tolerances {
    pub force: f64,
    pub moment: f64,
    pub stress: f64,
    pub kinetic_per_grain: f64,
}

/// A DEM stage in absolute reduced units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanStage {
    pub kind: StageKind,
    /// Largest strain rate of each cell axis, 1/time (AR07 (23) I·√(P/m)/a; GRC08 I_a/T0);
    /// 0 for a fixed cell.
    pub max_strain_rate: f64,
    /// The first-order servo gain of the stress control (`numerics.servo_gain`), instead of
    /// AR07 (7)'s cell mass, if the scene sets one.
    pub servo_gain: Option<f64>,
    /// The pressure last prescribed at or before this stage (`None` before any `compress`):
    /// the force scale of the criteria and the target snapshots report.
    pub pressure: Option<f64>,
    /// Friction coefficient, and the rolling threshold μ_r of a law with rolling resistance.
    pub mu: Mu,
    pub mu_r: Option<f64>,
    /// κ of the stage (the law's unless the stage overrides it; contacts and history are kept)
    /// and κ_stage/κ_law, the factor the engine scales its law by.
    pub kappa: f64,
    pub kappa_factor: f64,
    /// Time step (`numerics.dt_fraction` of the binary contact duration of the stiffest
    /// contact, [`time_step`]) and that stiffness K_max. A final relaxation by FIRE changes
    /// the step while it runs (engine/src/run/fire.rs).
    pub dt: f64,
    pub k_max: f64,
    /// Time limit, and the same in steps of `dt`.
    pub max_time: f64,
    pub max_steps: u64,
    /// The criteria as the scene writes them (relative to the force scale, with the window)
    /// and in absolute units; `f_ref` is the force scale.
    pub criteria: Criteria,
    pub tolerances: Tolerances,
    pub f_ref: f64,
    /// Time over which every check must meet the criteria before the stage ends (0: one check).
    pub window: f64,
    /// Velocities set to zero at a check where only the kinetic criterion fails (AR07 §III.A);
    /// false in stages that end otherwise than on the criteria.
    pub quench: bool,
    /// Steps between checks of the criteria; overlap (fraction of the smaller radius) that
    /// stops the run as unstable.
    pub check_every: u64,
    pub max_overlap: f64,
    /// The stage's final relaxation, if any (engine/src/run/relax.rs).
    pub relax: Option<Relax>,
}

/// The whole protocol of a scene, resolved.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub scene: String,
    pub dimension: usize,
    /// The law has GRC07 adhesion (force unit F0, time unit T0); the law attracts (GRC07
    /// adhesion or SJKR: contacts are counted by the cohesive rule).
    pub cohesive: bool,
    pub attractive: bool,
    /// The law's own μ, μ_r, κ, and the time step and K_max at that κ (a new system's step,
    /// before any stage).
    pub mu: Mu,
    pub mu_r: Option<f64>,
    pub kappa: f64,
    pub dt: f64,
    pub k_max: f64,
    /// `numerics.dt_fraction`, and the normal force at which K_max is evaluated:
    /// `numerics.stiffness_force` × the largest pressure of the protocol (at least the force
    /// unit).
    pub dt_fraction: f64,
    pub stiffness_force: f64,
    /// The stages, in order (pressure programs and κ ramps unrolled into their levels).
    pub steps: Vec<PlanStep>,
}

/// The time step for grains of masses `mass` and radii `radius` under `law`:
/// `dt_fraction` of the binary contact duration π√(m_eff/K_max) of the two lightest grains,
/// K_max the law's stiffness at normal force `force` between the two largest grains.
/// Returns (dt, K_max).
pub fn time_step<D: Dim, L: ContactLaw<D>>(
    law: &L,
    mass: &[f64],
    radius: &[f64],
    dt_fraction: f64,
    force: f64,
) -> (f64, f64) {
    let m_min = mass.iter().cloned().fold(f64::INFINITY, f64::min);
    let r_max = radius.iter().cloned().fold(0.0, f64::max);
    let k_max = law.max_stiffness(force, 0.5 * r_max);
    let t_c = std::f64::consts::PI * (0.5 * m_min / k_max).sqrt();
    (dt_fraction * t_c, k_max)
}

/// The time unit in which a stage's strain-rate cap is written: AR07 (23)
/// I = ε̇√(m/(aP)), so √(m/(aP)) = 1/√P for P > 0 without cohesion; GRC08's I_a = ε̇ T0 with
/// T0 = √(m a/F0) = 1 with cohesion.
pub fn rate_time_unit(pressure: f64, cohesive: bool) -> f64 {
    if cohesive {
        1.0
    } else {
        1.0 / pressure.sqrt()
    }
}

/// The force scale of the criteria: the pressure last prescribed (1 before any), or with
/// [`ForceScale::Cohesion`] F0 = 1 unless that pressure exceeds it.
pub fn force_scale(scale: ForceScale, pressure: Option<f64>) -> f64 {
    match scale {
        ForceScale::Pressure => pressure.unwrap_or(1.0),
        ForceScale::Cohesion => pressure.unwrap_or(0.0).max(1.0),
    }
}

impl Tolerances {
    /// The criteria `c` at force scale `f_ref` (a = 1: F_ref/a^(d−1) = F_ref).
    pub fn of(c: &Criteria, f_ref: f64) -> Tolerances {
        Tolerances {
            force: c.force * f_ref,
            moment: c.moment * f_ref,
            stress: c.pressure * f_ref,
            kinetic_per_grain: c.kinetic * f_ref,
        }
    }
}

impl StageKind {
    /// The scene's name of the stage kind.
    pub fn name(self) -> &'static str {
        match self {
            StageKind::Compress { .. } => "compress",
            StageKind::FixedVolume { .. } => "fixed-volume",
            StageKind::Aggregate => "aggregate",
        }
    }
}

impl HardStage {
    pub fn name(self) -> &'static str {
        match self {
            HardStage::Expand { .. } => "expand",
            HardStage::HardSphereMix { .. } => "hard-sphere-mix",
            HardStage::Grow { .. } => "grow",
        }
    }
}

impl PlanStep {
    pub fn name(&self) -> &'static str {
        match self {
            PlanStep::Dem(s) => s.kind.name(),
            PlanStep::Hard(h) => h.name(),
        }
    }
    pub fn dem(&self) -> Option<&PlanStage> {
        match self {
            PlanStep::Dem(s) => Some(s),
            PlanStep::Hard(_) => None,
        }
    }
}

impl PlanStage {
    /// Does the stage end otherwise than on the criteria (one cluster, or its full time)?
    pub fn ends_otherwise(&self) -> bool {
        matches!(
            self.kind,
            StageKind::Aggregate | StageKind::FixedVolume { full_time: true }
        )
    }
}

impl Plan {
    /// The plan of a validated `scene` for grains of diameters `diameter` (the time step
    /// depends on the lightest grain and the largest radius; hard-grain stages change neither).
    pub fn new(scene: &Scene, diameter: &[f64]) -> Result<Plan, String> {
        match scene.dimension {
            2 => Self::new_dim::<D2>(scene, diameter),
            _ => Self::new_dim::<D3>(scene, diameter),
        }
    }

    fn new_dim<D: Dim>(scene: &Scene, diameter: &[f64]) -> Result<Plan, String> {
        if diameter.is_empty() {
            return Err("a plan needs at least one grain".into());
        }
        let n = &scene.numerics;
        let cohesive = scene.law.cohesion().is_some();
        let mass: Vec<f64> = diameter.iter().map(|d| d.powi(D::D as i32)).collect();
        let radius: Vec<f64> = diameter.iter().map(|d| 0.5 * d).collect();
        let stiffness_force = stiffness_force(scene);
        let step_of = |factor: f64| {
            law_time_step::<D>(
                &scene.law,
                factor,
                &mass,
                &radius,
                n.dt_fraction,
                stiffness_force,
            )
        };
        let (dt, k_max) = step_of(1.0);
        let mu_r = match &scene.law {
            Law::Linear {
                rolling: Some(r), ..
            } => Some(r.mu_r),
            _ => None,
        };
        let mut pressure: Option<f64> = None;
        let mut steps = Vec::new();
        for (_, step) in scene.stages() {
            let (kind, max_strain_rate) = match step {
                Step::Expand { factor } => {
                    steps.push(PlanStep::Hard(HardStage::Expand { factor }));
                    continue;
                }
                Step::HardSphereMix {
                    collisions_per_grain,
                } => {
                    let mix = HardStage::HardSphereMix {
                        collisions_per_grain,
                    };
                    steps.push(PlanStep::Hard(mix));
                    continue;
                }
                Step::Grow {
                    packing_fraction,
                    rate,
                } => {
                    let grow = HardStage::Grow {
                        packing_fraction,
                        rate,
                    };
                    steps.push(PlanStep::Hard(grow));
                    continue;
                }
                Step::Compress {
                    pressure: p,
                    inertia_cap,
                    ..
                } => {
                    pressure = Some(p);
                    let cap = inertia_cap / rate_time_unit(p, cohesive);
                    (StageKind::Compress { pressure: p }, cap)
                }
                Step::FixedVolume { full_time, .. } => (StageKind::FixedVolume { full_time }, 0.0),
                Step::Aggregate { .. } => (StageKind::Aggregate, 0.0),
                Step::PressureProgram { .. } | Step::KappaRamp { .. } => {
                    unreachable!("Scene::stages unrolls {}", step.kind())
                }
            };
            // κ of the stage (GRC07 §III.B.2 ramps), always scaled from the scene's law so
            // that a resumed run has the same law bit for bit.
            let kappa_factor = step.kappa().map_or(1.0, |k| k / scene.law.kappa());
            let (dt, k_max) = step_of(kappa_factor);
            let criteria = step.criteria();
            let f_ref = force_scale(criteria.scale, pressure);
            let max_time = step.max_time();
            let mut stage = PlanStage {
                kind,
                max_strain_rate,
                servo_gain: n.servo_gain,
                pressure,
                mu: scene.mu_of(&step),
                mu_r,
                kappa: step.kappa().unwrap_or(scene.law.kappa()),
                kappa_factor,
                dt,
                k_max,
                max_time,
                max_steps: (max_time / dt).ceil() as u64,
                tolerances: Tolerances::of(&criteria, f_ref),
                f_ref,
                window: criteria.window,
                quench: false,
                criteria,
                check_every: n.check_every,
                max_overlap: n.max_overlap,
                relax: step.relax(),
            };
            stage.quench = stage.criteria.quench && !stage.ends_otherwise();
            steps.push(PlanStep::Dem(stage));
        }
        Ok(Plan {
            scene: scene.name.clone(),
            dimension: D::D,
            cohesive,
            attractive: scene.law.attractive(),
            mu: scene.law.mu(),
            mu_r,
            kappa: scene.law.kappa(),
            dt,
            k_max,
            dt_fraction: n.dt_fraction,
            stiffness_force,
            steps,
        })
    }

    /// The DEM stages, in order.
    pub fn dem_stages(&self) -> impl Iterator<Item = &PlanStage> + '_ {
        self.steps.iter().filter_map(PlanStep::dem)
    }

    /// The pressure last prescribed at or before stage `k` (`None` before any `compress`).
    pub fn pressure_at(&self, k: usize) -> Option<f64> {
        self.steps[..=k]
            .iter()
            .rev()
            .find_map(|s| s.dem().map(|s| s.pressure))
            .flatten()
    }
}

/// The time step and K_max of `law` with κ × `factor`. The stiffness depends on the normal law
/// alone, so the frictionless, cohesionless member of the law's family stands for every
/// combination of sub-models the engine builds.
fn law_time_step<D: Dim>(
    law: &Law,
    factor: f64,
    mass: &[f64],
    radius: &[f64],
    dt_fraction: f64,
    force: f64,
) -> (f64, f64) {
    match law {
        Law::HertzMindlin { .. } => {
            let l = <HertzMindlin<Frictionless> as ContactLaw<D>>::with_kappa_scaled(
                &hertz_mindlin_law(law, Frictionless),
                factor,
            );
            time_step::<D, _>(&l, mass, radius, dt_fraction, force)
        }
        Law::Linear { .. } => {
            let l =
                <Linear<NoCohesion, Frictionless, NoRolling> as ContactLaw<D>>::with_kappa_scaled(
                    &linear_law(law, NoCohesion, Frictionless, NoRolling),
                    factor,
                );
            time_step::<D, _>(&l, mass, radius, dt_fraction, force)
        }
    }
}

/// The normal force at which a scene's K_max is evaluated: `numerics.stiffness_force` × the
/// largest pressure of the protocol (at least the force unit).
pub fn stiffness_force(scene: &Scene) -> f64 {
    scene.numerics.stiffness_force * largest_pressure(scene)
}

/// Largest pressure any stage asks for (at least the force unit).
fn largest_pressure(scene: &Scene) -> f64 {
    scene
        .stages()
        .iter()
        .filter_map(|(_, s)| match s {
            Step::Compress { pressure, .. } => Some(*pressure),
            _ => None,
        })
        .fold(1.0, f64::max)
}
