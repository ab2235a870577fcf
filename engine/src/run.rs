//! Running a scene: from the scene file to a typed system (one monomorphized kernel per
//! combination of dimension and law features), then the protocol steps with the equilibrium
//! criteria (AR07 §III, GRC07 §II.D, GRC08 §II.D.1), blow-up detection and snapshots.

use crate::cell::{Cell, Control};
use crate::contact::hertz_mindlin::HertzMindlin;
use crate::contact::linear::{Adhesion, Cohesion, Linear, NoCohesion};
use crate::contact::slider::{Coulomb, Friction, Frictionless, NoRolling, NoSlip, RollingSpring};
use crate::contact::ContactLaw;
use crate::geometry::{Dim, Linear as _, D2, D3};
use crate::init::{maxwell_velocities, random_gas};
use crate::scene::{Criteria, ForceScale, Law, Mu, Scene, Step};
use crate::snapshot::{self, Snapshot};
use crate::system::{Checkpoint, System};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// What the progress callback sees at each check.
#[derive(Clone, Debug, Default)]
pub struct Progress {
    /// Protocol step (0-based) and count.
    pub step_index: usize,
    pub step_count: usize,
    pub step_kind: &'static str,
    /// Time since the start of the protocol step, and its limit.
    pub time: f64,
    pub max_time: f64,
    pub steps: u64,
    pub checks: Checks,
}

/// Equilibrium measures at one check, in units of the criteria.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Checks {
    pub packing_fraction: f64,
    /// Mean contact pressure trace(σ_contact)/d.
    pub pressure: f64,
    /// Target pressure (NaN in a fixed cell).
    pub pressure_target: f64,
    /// Largest net force on a grain / (criterion · F_ref).
    pub force_ratio: f64,
    /// Largest net moment / (criterion · F_ref · a) (0 when the law has no moments).
    pub moment_ratio: f64,
    /// Largest |σ_αα − Σ_α| / (criterion · F_ref/a^(d−1)) (0 in a fixed cell).
    pub stress_ratio: f64,
    /// Kinetic energy per grain / (criterion · F_ref · a).
    pub kinetic_ratio: f64,
    /// Kinetic energy per grain, reduced units (translation, and rotation of touching grains).
    pub kinetic_per_grain: f64,
    /// Rotational energy per grain of grains without any contact, not counted above.
    pub free_spin_per_grain: f64,
    /// Interacting pairs.
    pub interactions: usize,
}

impl Checks {
    /// All criteria met.
    pub fn equilibrium(&self) -> bool {
        self.force_ratio < 1.0
            && self.moment_ratio < 1.0
            && self.stress_ratio < 1.0
            && self.kinetic_ratio < 1.0
    }
}

/// How a protocol step ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StepEnd {
    Equilibrium,
    TimeLimit,
    Interrupted,
}

impl StepEnd {
    pub fn as_str(self) -> &'static str {
        match self {
            StepEnd::Equilibrium => "equilibrium",
            StepEnd::TimeLimit => "time-limit",
            StepEnd::Interrupted => "interrupted",
        }
    }
}

/// Report of one protocol step.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StepReport {
    pub index: usize,
    pub kind: &'static str,
    pub end: StepEnd,
    pub time: f64,
    pub steps: u64,
    pub wall_seconds: f64,
    pub checks: Checks,
}

/// Result of a whole run.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub snapshot: Snapshot,
    pub steps: Vec<StepReport>,
    /// Time step and the stiffness it was derived from.
    pub dt: f64,
    pub k_max: f64,
    pub law: String,
    pub wall_seconds: f64,
    pub neighbor_builds: u64,
    /// Contacts at the Coulomb or rolling threshold at the end (should be 0 at equilibrium:
    /// GRC07 §II.D, the thresholds hold as strict inequalities).
    pub contacts_at_threshold: usize,
}

impl Outcome {
    /// Did every step end at equilibrium?
    pub fn equilibrated(&self) -> bool {
        self.steps.iter().all(|s| s.end == StepEnd::Equilibrium)
    }
}

/// Why a run stopped early.
#[derive(Debug)]
pub enum RunError {
    /// The scene cannot start (placement, cell too small).
    Setup { scene: String, message: String },
    /// The integration blew up; `last_good` is the last state that passed the checks.
    Unstable {
        scene: String,
        step: u64,
        time: f64,
        cause: String,
        last_good: Box<Snapshot>,
    },
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            RunError::Setup { scene, message } => write!(f, "scene {scene}: {message}"),
            RunError::Unstable {
                scene,
                step,
                time,
                cause,
                ..
            } => write!(
                f,
                "scene {scene}: unstable at step {step} (t = {time:.6e}): {cause}"
            ),
        }
    }
}

impl std::error::Error for RunError {}

/// Options of a run.
#[derive(Default)]
pub struct RunOptions<'a> {
    /// Called at every check (every `numerics.check_every` steps).
    pub progress: Option<&'a mut (dyn FnMut(&Progress) + Send)>,
    /// Set to stop the run cleanly at the next check (Ctrl-C).
    pub stop: Option<&'a AtomicBool>,
}

/// Runs a validated scene to the end of its protocol.
///
/// The run executes on a worker of rayon's global pool, so the parallel loops of each step
/// fork from a worker (cheap) instead of being injected from outside at every step.
pub fn run_scene(scene: &Scene, opts: &mut RunOptions) -> Result<Outcome, RunError> {
    rayon::scope(|_| match scene.dimension {
        2 => dispatch_law::<D2>(scene, opts),
        _ => dispatch_law::<D3>(scene, opts),
    })
}

fn dispatch_law<D: Dim>(scene: &Scene, opts: &mut RunOptions) -> Result<Outcome, RunError> {
    match &scene.law {
        Law::HertzMindlin { mu, .. } => {
            let law = &scene.law;
            match *mu {
                Mu::Finite(0.0) => {
                    run_law::<D, _>(scene, hertz_mindlin_law(law, Frictionless), opts)
                }
                Mu::Finite(m) => {
                    run_law::<D, _>(scene, hertz_mindlin_law(law, Coulomb { mu: m }), opts)
                }
                Mu::Infinite => run_law::<D, _>(scene, hertz_mindlin_law(law, NoSlip), opts),
            }
        }
        Law::Linear { cohesion, .. } => match cohesion {
            Some(c) => linear_friction::<D, _>(scene, adhesion(c), opts),
            None => linear_friction::<D, _>(scene, NoCohesion, opts),
        },
    }
}

fn linear_friction<D: Dim, C: Cohesion>(
    scene: &Scene,
    c: C,
    opts: &mut RunOptions,
) -> Result<Outcome, RunError> {
    let Law::Linear { mu, .. } = &scene.law else {
        unreachable!()
    };
    match *mu {
        Mu::Finite(0.0) => linear_rolling::<D, C, _>(scene, c, Frictionless, opts),
        Mu::Finite(m) => linear_rolling::<D, C, _>(scene, c, Coulomb { mu: m }, opts),
        Mu::Infinite => linear_rolling::<D, C, _>(scene, c, NoSlip, opts),
    }
}

fn linear_rolling<D: Dim, C: Cohesion, F: Friction>(
    scene: &Scene,
    c: C,
    f: F,
    opts: &mut RunOptions,
) -> Result<Outcome, RunError> {
    let law = &scene.law;
    match rolling_spring(law) {
        Some(r) => run_law::<D, _>(scene, linear_law(law, c, f, r), opts),
        None => run_law::<D, _>(scene, linear_law(law, c, f, NoRolling), opts),
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

/// The linear law of a scene in reduced units (K_N = κ, K_T = κ·kt_over_kn) with the given
/// cohesion, friction and rolling parts. Panics if `law` is not linear.
pub fn linear_law<C, F, R>(law: &Law, cohesion: C, friction: F, rolling: R) -> Linear<C, F, R> {
    let Law::Linear {
        kappa,
        zeta,
        kt_over_kn,
        ..
    } = law
    else {
        panic!("linear_law needs a linear law")
    };
    Linear {
        kn: *kappa,
        kt: kappa * kt_over_kn,
        zeta: *zeta,
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

/// Largest pressure any step asks for (at least the force unit).
fn force_scale(scene: &Scene) -> f64 {
    scene
        .protocol
        .iter()
        .filter_map(|s| match s {
            Step::Compress { pressure, .. } => Some(*pressure),
            _ => None,
        })
        .fold(1.0, f64::max)
}

/// Builds the system of a scene for a law (initial gas, cell, time step).
pub fn build_system<D: Dim, L: ContactLaw<D>>(
    scene: &Scene,
    law: L,
) -> Result<System<D, L>, String> {
    let gas = random_gas::<D>(
        scene.particles.count,
        scene.particles.min_diameter,
        scene.initial.packing_fraction,
        scene.seed,
    )?;
    let total_mass: f64 = gas.diameter.iter().map(|d| d.powi(D::D as i32)).sum();
    let cell = Cell::new(gas.l, scene.numerics.cell_mass * total_mass);
    let mut sys = System::new(law, cell, gas.s, &gas.diameter, scene.numerics.skin);
    if scene.initial.rms_velocity > 0.0 {
        sys.u = maxwell_velocities::<D>(&sys.mass, scene.initial.rms_velocity, scene.seed);
    }
    let (dt, _) = time_step::<D, L>(scene, &sys);
    sys.dt = dt;
    sys.check_cell()?;
    Ok(sys)
}

/// Time step from the stiffest contact: `dt_fraction` of the binary contact duration
/// π√(m_eff/K_max) of the two lightest grains. Returns (dt, K_max).
pub fn time_step<D: Dim, L: ContactLaw<D>>(scene: &Scene, sys: &System<D, L>) -> (f64, f64) {
    let m_min = sys.mass.iter().cloned().fold(f64::INFINITY, f64::min);
    let r_max = sys.radius.iter().cloned().fold(0.0, f64::max);
    let k_max = sys.law.max_stiffness(
        scene.numerics.stiffness_force * force_scale(scene),
        0.5 * r_max,
    );
    let t_c = std::f64::consts::PI * (0.5 * m_min / k_max).sqrt();
    (scene.numerics.dt_fraction * t_c, k_max)
}

fn run_law<D: Dim, L: ContactLaw<D>>(
    scene: &Scene,
    law: L,
    opts: &mut RunOptions,
) -> Result<Outcome, RunError> {
    let start = Instant::now();
    let mut sys = build_system::<D, L>(scene, law).map_err(|message| RunError::Setup {
        scene: scene.name.clone(),
        message,
    })?;
    let (_, k_max) = time_step::<D, L>(scene, &sys);
    run_protocol(scene, &mut sys, opts).map(|(steps, snapshot, at_threshold)| Outcome {
        snapshot,
        steps,
        dt: sys.dt,
        k_max,
        law: sys.law.describe(),
        wall_seconds: start.elapsed().as_secs_f64(),
        neighbor_builds: sys.nlist.builds,
        contacts_at_threshold: at_threshold,
    })
}

/// Runs the protocol of `scene` on a prepared system.
pub fn run_protocol<D: Dim, L: ContactLaw<D>>(
    scene: &Scene,
    sys: &mut System<D, L>,
    opts: &mut RunOptions,
) -> Result<(Vec<StepReport>, Snapshot, usize), RunError> {
    sys.init_forces();
    let n = sys.len() as f64;
    let ke0 = sys.kinetic_energy() / n;
    let mut last_good = None;
    sys.save(&mut last_good);
    let mut reports = Vec::new();
    let mut pressure: Option<f64> = None;
    let cohesive = scene.law.cohesion().is_some();
    let mut status = "equilibrium";
    for (k, step) in scene.protocol.iter().enumerate() {
        let step_start = Instant::now();
        let kind = match step {
            Step::Compress {
                pressure: p,
                inertia_cap,
                ..
            } => {
                pressure = Some(*p);
                // Strain-rate cap: AR07 (23) I = ε̇√(m/(aP)) (time unit √(m/(aP)) for P > 0 without
                // cohesion), GRC08 I_a = ε̇ T0 with T0 = √(m a/F0) = 1 with cohesion.
                let time_unit = if cohesive { 1.0 } else { 1.0 / p.sqrt() };
                let mut target = D::V::zero();
                for a in 0..D::D {
                    target[a] = *p;
                }
                sys.cell.control = Control::Stress {
                    target,
                    rate_cap: inertia_cap / time_unit,
                };
                "compress"
            }
            Step::FixedVolume { .. } => {
                sys.cell.control = Control::Fixed;
                sys.cell.ldot = D::V::zero();
                "fixed-volume"
            }
        };
        let criteria = step.criteria();
        let f_ref = match criteria.scale {
            ForceScale::Pressure => pressure.unwrap_or(1.0),
            ForceScale::Cohesion => pressure.unwrap_or(0.0).max(1.0),
        };
        let full_time = matches!(
            step,
            Step::FixedVolume {
                full_time: true,
                ..
            }
        );
        let t0 = sys.time;
        let steps0 = sys.step;
        let max_time = step.max_time();
        let end;
        let mut checks;
        loop {
            for _ in 0..scene.numerics.check_every {
                sys.step();
                let (ov, i, j) = sys.max_overlap;
                if ov.is_nan() || ov > scene.numerics.max_overlap {
                    return Err(unstable(
                        scene,
                        sys,
                        &last_good,
                        if ov.is_nan() {
                            "non-finite positions or forces".to_string()
                        } else {
                            format!(
                                "overlap of {ov:.3} times the smaller radius between grains {i} and {j} (limit numerics.max_overlap = {})",
                                scene.numerics.max_overlap
                            )
                        },
                    ));
                }
            }
            checks = measure(sys, criteria, f_ref, step);
            if let Some(cb) = opts.progress.as_mut() {
                cb(&Progress {
                    step_index: k,
                    step_count: scene.protocol.len(),
                    step_kind: kind,
                    time: sys.time - t0,
                    max_time,
                    steps: sys.step - steps0,
                    checks: checks.clone(),
                });
            }
            let finite = checks.kinetic_per_grain.is_finite()
                && checks.force_ratio.is_finite()
                && checks.pressure.is_finite()
                && sys.cell.l.is_finite();
            if !finite {
                return Err(unstable(
                    scene,
                    sys,
                    &last_good,
                    "non-finite velocities, forces or cell lengths".into(),
                ));
            }
            if checks.kinetic_per_grain > 1e4 * (f_ref + ke0) {
                return Err(unstable(
                    scene,
                    sys,
                    &last_good,
                    format!(
                        "kinetic energy per grain exploded to {:.3e} (force unit × a)",
                        checks.kinetic_per_grain
                    ),
                ));
            }
            sys.save(&mut last_good);
            if !full_time && checks.equilibrium() {
                end = StepEnd::Equilibrium;
                break;
            }
            if sys.time - t0 >= max_time {
                end = StepEnd::TimeLimit;
                break;
            }
            if opts.stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
                end = StepEnd::Interrupted;
                break;
            }
        }
        // A full-time run that also meets the criteria at its end counts as equilibrated.
        let end = if full_time && end == StepEnd::TimeLimit && checks.equilibrium() {
            StepEnd::Equilibrium
        } else {
            end
        };
        reports.push(StepReport {
            index: k,
            kind,
            end,
            time: sys.time - t0,
            steps: sys.step - steps0,
            wall_seconds: step_start.elapsed().as_secs_f64(),
            checks,
        });
        match end {
            StepEnd::Interrupted => {
                status = "interrupted";
                break;
            }
            StepEnd::TimeLimit => status = "time-limit",
            StepEnd::Equilibrium => {}
        }
    }
    let at_threshold = contacts_at_threshold(sys, scene);
    let snap = snapshot_of(sys, scene, status, pressure);
    Ok((reports, snap, at_threshold))
}

/// The error for a blown-up run; `sys` is returned to the last good checkpoint to write it.
fn unstable<D: Dim, L: ContactLaw<D>>(
    scene: &Scene,
    sys: &mut System<D, L>,
    last_good: &Option<Checkpoint<D, L>>,
    what: String,
) -> RunError {
    let (_, k_max) = time_step::<D, L>(scene, sys);
    let cause = format!(
        "{what}. Likely cause: the time step dt = {:.4e} (numerics.dt_fraction = {} of the contact duration for K_max = {:.4e}) is too large for the contacts, or the contacts are too soft (law.kappa) for the applied pressure. Try a smaller numerics.dt_fraction, or a larger numerics.stiffness_force if forces exceed the expected scale",
        sys.dt, scene.numerics.dt_fraction, k_max
    );
    let (step, time) = (sys.step, sys.time);
    if let Some(cp) = last_good {
        sys.restore(cp);
    }
    RunError::Unstable {
        scene: scene.name.clone(),
        step,
        time,
        cause,
        last_good: Box::new(snapshot_of(
            sys,
            scene,
            "unstable",
            match sys.cell.control {
                Control::Stress { target, .. } => Some(target[0]),
                Control::Fixed => None,
            },
        )),
    }
}

/// Equilibrium measures in units of the criteria.
pub fn measure<D: Dim, L: ContactLaw<D>>(
    sys: &System<D, L>,
    c: &Criteria,
    f_ref: f64,
    step: &Step,
) -> Checks {
    let n = sys.len() as f64;
    let (fmax, tmax) = sys.max_unbalanced();
    let inter = sys.interactions();
    // Kinetic energy: all translations, and the rotations of grains that touch another one. A
    // grain with no contact spinning on itself (a rattler, typically) keeps its spin forever
    // since no force can reach it; it has no bearing on the equilibrium of the packing, so
    // its spin is reported apart (`free_spin_per_grain`) instead of blocking the criterion.
    let mut touching = vec![false; sys.len()];
    for c in &inter {
        if c.gap < 0.0 {
            touching[c.i] = true;
            touching[c.j] = true;
        }
    }
    let mut ke_t = 0.0;
    let mut ke_r = 0.0;
    let mut ke_free = 0.0;
    for (i, &touch) in touching.iter().enumerate() {
        ke_t += 0.5 * sys.mass[i] * sys.u[i].norm_squared();
        if L::MOMENTS {
            let e = 0.5 * sys.w[i].norm_squared() / sys.inv_inertia[i];
            if touch {
                ke_r += e;
            } else {
                ke_free += e;
            }
        }
    }
    let ke = (ke_t + ke_r) / n;
    let sc = sys.contact_stress();
    let p = (0..D::D).map(|a| sc[a][a]).sum::<f64>() / D::D as f64;
    let (target, stress_ratio) = match (step, sys.cell.control) {
        (Step::Compress { .. }, Control::Stress { target, .. }) => {
            let dev = (0..D::D)
                .map(|a| (sc[a][a] - target[a]).abs())
                .fold(0.0, f64::max);
            (target[0], dev / (c.pressure * f_ref))
        }
        _ => (f64::NAN, 0.0),
    };
    Checks {
        packing_fraction: sys.packing_fraction(),
        pressure: p,
        pressure_target: target,
        force_ratio: fmax / (c.force * f_ref),
        moment_ratio: if L::MOMENTS {
            tmax / (c.moment * f_ref)
        } else {
            0.0
        },
        stress_ratio,
        kinetic_ratio: ke / (c.kinetic * f_ref),
        kinetic_per_grain: ke,
        free_spin_per_grain: ke_free / n,
        interactions: inter.len(),
    }
}

/// Contacts whose tangential force or rolling moment sits at its threshold.
fn contacts_at_threshold<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>, scene: &Scene) -> usize {
    let mu = match &scene.law {
        Law::HertzMindlin { mu, .. } | Law::Linear { mu, .. } => mu.value(),
    };
    let mu_r = match &scene.law {
        Law::Linear {
            rolling: Some(r), ..
        } => r.mu_r,
        _ => f64::INFINITY,
    };
    sys.interactions()
        .iter()
        .filter(|c| {
            c.gap < 0.0
                && ((mu.is_finite()
                    && mu > 0.0
                    && c.tangential.norm() >= mu * c.normal_elastic * (1.0 - 1e-9))
                    || (mu_r.is_finite()
                        && c.rolling.norm() >= mu_r * c.normal_elastic * (1.0 - 1e-9)))
        })
        .count()
}

/// The snapshot of the current state.
pub fn snapshot_of<D: Dim, L: ContactLaw<D>>(
    sys: &System<D, L>,
    scene: &Scene,
    status: &str,
    pressure_target: Option<f64>,
) -> Snapshot {
    let n = sys.len();
    let cohesive = scene.law.cohesion().is_some();
    let mu = match &scene.law {
        Law::HertzMindlin { mu, .. } | Law::Linear { mu, .. } => match mu {
            Mu::Finite(x) => Some(*x),
            Mu::Infinite => None,
        },
    };
    let omega = sys.cell.volume();
    let tensor = |t: &crate::geometry::Tensor| -> Vec<Vec<f64>> {
        (0..D::D)
            .map(|a| (0..D::D).map(|b| t[a][b] / omega).collect())
            .collect()
    };
    let contacts = sys
        .interactions()
        .into_iter()
        .map(|c| snapshot::Contact {
            i: c.i,
            j: c.j,
            branch: c.branch.to_vec(),
            normal: c.normal,
            normal_elastic: c.normal_elastic,
            tangential: if L::MOMENTS {
                c.tangential.to_vec()
            } else {
                Vec::new()
            },
            rolling: if L::ROLLING {
                c.rolling.to_vec()
            } else {
                Vec::new()
            },
            gap: c.gap,
        })
        .collect();
    Snapshot {
        format: snapshot::FORMAT.into(),
        version: snapshot::VERSION,
        code: format!("grainbench {}", env!("CARGO_PKG_VERSION")),
        scene: scene.name.clone(),
        dimension: D::D,
        time: sys.time,
        step: sys.step,
        status: status.into(),
        force_unit: if cohesive {
            "F0".into()
        } else {
            format!("P_ref a^{}", D::D - 1)
        },
        pressure_target,
        cohesive,
        mu,
        cell: snapshot::Cell {
            lengths: sys.cell.l.to_vec(),
            contact_stress: tensor(&sys.contact_virial),
            kinetic_stress: tensor(&sys.kinetic_virial),
        },
        particles: snapshot::Particles {
            radius: sys.radius.clone(),
            mass: sys.mass.clone(),
            position: (0..n).map(|i| sys.position(i).to_vec()).collect(),
            velocity: sys.u.iter().map(|v| v.to_vec()).collect(),
            angular_velocity: if L::MOMENTS {
                sys.w.iter().map(|w| w.to_vec()).collect()
            } else {
                Vec::new()
            },
        },
        contacts,
    }
}
