//! Running a scene: from the scene file to a typed system (one monomorphized kernel per
//! combination of dimension and law features), then the protocol steps with the equilibrium
//! criteria (AR07 §III, GRC07 §II.D, GRC08 §II.D.1), blow-up detection and snapshots.

use crate::cell::{Cell, Control};
use crate::checkpoint::{self, Checkpoint, Header};
use crate::contact::hertz_mindlin::HertzMindlin;
use crate::contact::linear::{Adhesion, Cohesion, Linear, NoCohesion};
use crate::contact::slider::{Coulomb, Friction, Frictionless, NoRolling, NoSlip, RollingSpring};
use crate::contact::ContactLaw;
use crate::geometry::{Dim, Linear as _, D2, D3};
use crate::init::{maxwell_velocities, random_gas};
use crate::protocols::event_driven::HardSpheres;
use crate::protocols::lattice;
use crate::relax::{Relaxation, StageWatch};
use crate::scene::{Arrangement, Criteria, ForceScale, Law, Mu, Scene, Step};
use crate::snapshot::{self, Snapshot};
use crate::system::{self as system, State, System};
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
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
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
    /// Largest strain rate max_α |L̇_α/L_α| (1/time unit; 0 in a fixed cell).
    #[serde(default)]
    pub strain_rate: f64,
    /// Interacting pairs.
    pub interactions: usize,
    /// Clusters of interacting grains (`aggregate` stages only, else 0).
    pub clusters: usize,
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
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StepEnd {
    /// The equilibrium criteria hold.
    Equilibrium,
    /// `aggregate`: all grains form one cluster.
    OneCluster,
    /// A hard-grain stage (expansion, mixing, growth) completed.
    Done,
    TimeLimit,
    Interrupted,
}

impl StepEnd {
    pub fn as_str(self) -> &'static str {
        match self {
            StepEnd::Equilibrium => "equilibrium",
            StepEnd::OneCluster => "one-cluster",
            StepEnd::Done => "done",
            StepEnd::TimeLimit => "time-limit",
            StepEnd::Interrupted => "interrupted",
        }
    }
    /// Did the stage reach what it was run for?
    pub fn ok(self) -> bool {
        matches!(
            self,
            StepEnd::Equilibrium | StepEnd::OneCluster | StepEnd::Done
        )
    }
}

/// Report of one protocol stage.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct StepReport {
    /// Stage index in [`Scene::stages`].
    pub index: usize,
    pub kind: String,
    pub end: StepEnd,
    /// Time spent in the stage (hard-grain stages: their own event-driven time).
    pub time: f64,
    /// Time steps (hard-grain stages: pair collisions).
    pub steps: u64,
    pub wall_seconds: f64,
    pub checks: Checks,
    /// Largest strain rate |L̇_α/L_α| seen at a check of the stage (1/time unit).
    #[serde(default)]
    pub peak_strain_rate: f64,
    /// What the damped final phase changed, for a stage with `relax` that reached it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relaxation: Option<Relaxation>,
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
        self.steps.iter().all(|s| s.end.ok())
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

/// Periodic checkpoints on disk.
#[derive(Clone, Debug)]
pub struct CheckpointSpec {
    pub path: std::path::PathBuf,
    /// Wall-clock seconds between checkpoints (one is also written at each stage start that
    /// runs hard-sphere dynamics, and when the run is stopped).
    pub every: f64,
}

/// Options of a run.
#[derive(Default)]
pub struct RunOptions<'a> {
    /// Called at every check (every `numerics.check_every` steps).
    pub progress: Option<&'a mut (dyn FnMut(&Progress) + Send)>,
    /// Set to stop the run cleanly at the next check (Ctrl-C).
    pub stop: Option<&'a AtomicBool>,
    /// Write checkpoints.
    pub checkpoint: Option<CheckpointSpec>,
    /// Continue from a checkpoint of the same scene.
    pub resume: Option<Checkpoint>,
}

/// Grains between protocol stages, independent of the contact law: what hard-sphere stages
/// read and write, and what a new contact law starts from.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
pub struct Grains<D: Dim> {
    pub l: D::V,
    pub s: Vec<D::V>,
    pub u: Vec<D::V>,
    pub diameter: Vec<f64>,
    pub time: f64,
    pub step: u64,
}

/// Checkpoint payload: grains at a stage start, or the integrator inside a stage.
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(bound(
    serialize = "H: serde::Serialize",
    deserialize = "H: serde::de::DeserializeOwned"
))]
#[allow(clippy::large_enum_variant)] // one per checkpoint write, short-lived
enum Payload<D: Dim, H> {
    AtStart(Grains<D>),
    /// The integrator state and the stage's progress towards its end.
    Inside(State<D, H>, StageWatch<D>),
}

/// Bookkeeping carried through the stages.
struct Ctx<'s, D: Dim> {
    scene: &'s Scene,
    stages: Vec<(usize, Step)>,
    start: Instant,
    wall_before: f64,
    reports: Vec<StepReport>,
    pressure: Option<f64>,
    grains: Grains<D>,
    neighbor_builds: u64,
    last_checkpoint: Instant,
    dt: f64,
    k_max: f64,
    law: String,
    at_threshold: usize,
}

impl<'s, D: Dim> Ctx<'s, D> {
    /// A run of `scene` starting now, with no grains yet.
    fn new(scene: &'s Scene) -> Self {
        Ctx {
            scene,
            stages: scene.stages(),
            start: Instant::now(),
            wall_before: 0.0,
            reports: Vec::new(),
            pressure: None,
            grains: Grains {
                l: D::V::zero(),
                s: Vec::new(),
                u: Vec::new(),
                diameter: Vec::new(),
                time: 0.0,
                step: 0,
            },
            neighbor_builds: 0,
            last_checkpoint: Instant::now(),
            dt: 0.0,
            k_max: 0.0,
            law: String::new(),
            at_threshold: 0,
        }
    }

    fn header(&self, stage: usize, inside: bool, t0: f64, steps0: u64, stage_wall: f64) -> Header {
        Header {
            format: checkpoint::FORMAT.into(),
            version: checkpoint::VERSION,
            code: checkpoint::code(),
            scene_json: serde_json::to_string(self.scene).expect("scene encodes"),
            stage,
            inside,
            stage_time0: t0,
            stage_steps0: steps0,
            stage_wall,
            wall_seconds: self.wall_before + self.start.elapsed().as_secs_f64(),
            reports: self.reports.clone(),
            pressure: self.pressure,
            neighbor_builds: self.neighbor_builds,
        }
    }

    fn setup_error(&self, message: String) -> RunError {
        RunError::Setup {
            scene: self.scene.name.clone(),
            message,
        }
    }
}

/// Runs a validated scene to the end of its protocol (or from a checkpoint to the end).
///
/// The run executes on a worker of rayon's global pool, so the parallel loops of each step
/// fork from a worker (cheap) instead of being injected from outside at every step.
pub fn run_scene(scene: &Scene, opts: &mut RunOptions) -> Result<Outcome, RunError> {
    rayon::scope(|_| match scene.dimension {
        2 => run_dim::<D2>(scene, opts),
        _ => run_dim::<D3>(scene, opts),
    })
}

/// The initial grains of a scene: random gas (GRC07 §III.A) or FCC lattice (AR07 §III).
pub fn initial_grains<D: Dim>(scene: &Scene) -> Result<Grains<D>, String> {
    let n = scene.particles.count;
    if let Some(path) = &scene.initial.snapshot {
        return snapshot_grains(path, n);
    }
    let (l, s, diameter) = match scene.initial.arrangement {
        Arrangement::Random => {
            let gas = random_gas::<D>(
                n,
                scene.particles.min_diameter,
                scene.initial.packing_fraction,
                scene.seed,
            )?;
            (gas.l, gas.s, gas.diameter)
        }
        Arrangement::Fcc => {
            let k = lattice::fcc_cells_for(n).ok_or("FCC needs 4k³ grains")?;
            let (side, pos) = lattice::fcc(k, scene.initial.packing_fraction);
            let mut l = D::V::zero();
            for a in 0..D::D {
                l[a] = side;
            }
            let s = pos.iter().map(|p| D::from_slice(p.as_slice())).collect();
            (l, s, vec![1.0; n])
        }
    };
    let mass: Vec<f64> = diameter.iter().map(|d| d.powi(D::D as i32)).collect();
    let u = if scene.initial.rms_velocity > 0.0 {
        maxwell_velocities::<D>(&mass, scene.initial.rms_velocity, scene.seed)
    } else {
        vec![D::V::zero(); n]
    };
    Ok(Grains {
        l,
        s,
        u,
        diameter,
        time: 0.0,
        step: 0,
    })
}

/// The grains of a snapshot file, at rest (`initial.snapshot`).
fn snapshot_grains<D: Dim>(path: &std::path::Path, n: usize) -> Result<Grains<D>, String> {
    let snap = Snapshot::read(path).map_err(|e| format!("initial.snapshot: {e}"))?;
    let p = &snap.particles;
    if snap.dimension != D::D || p.radius.len() != n {
        return Err(format!(
            "initial.snapshot {}: holds {} grains in {}D, the scene wants {n} in {}D (particles.count, dimension)",
            path.display(),
            p.radius.len(),
            snap.dimension,
            D::D
        ));
    }
    let mut l = D::V::zero();
    for a in 0..D::D {
        l[a] = snap.cell.lengths[a];
    }
    let s = p
        .position
        .iter()
        .map(|r| {
            let mut x = D::V::zero();
            for a in 0..D::D {
                x[a] = (r[a] / l[a]).rem_euclid(1.0);
            }
            x
        })
        .collect();
    Ok(Grains {
        l,
        s,
        u: vec![D::V::zero(); n],
        diameter: p.radius.iter().map(|r| 2.0 * r).collect(),
        time: 0.0,
        step: 0,
    })
}

fn run_dim<D: Dim>(scene: &Scene, opts: &mut RunOptions) -> Result<Outcome, RunError> {
    let resume = opts.resume.take();
    let mut ctx = Ctx::<D>::new(scene);
    let mut k = 0;
    let mut inside: Option<(Header, Vec<u8>)> = None;
    match resume {
        Some(cp) => {
            let h = &cp.header;
            k = h.stage;
            ctx.wall_before = h.wall_seconds;
            ctx.reports = h.reports.clone();
            ctx.pressure = h.pressure;
            ctx.neighbor_builds = h.neighbor_builds;
            if h.inside {
                inside = Some((cp.header, cp.payload));
            } else {
                match checkpoint::decode::<Payload<D, ()>>(&cp.payload)
                    .map_err(|e| ctx.setup_error(e))?
                {
                    Payload::AtStart(g) => ctx.grains = g,
                    Payload::Inside(..) => {
                        return Err(
                            ctx.setup_error("checkpoint payload does not match its header".into())
                        )
                    }
                }
            }
        }
        None => ctx.grains = initial_grains::<D>(scene).map_err(|e| ctx.setup_error(e))?,
    }
    let mut snapshot = None;
    let mut interrupted = false;
    while k < ctx.stages.len() {
        let step = ctx.stages[k].1.clone();
        if !step.is_dem() {
            if let Some(spec) = &opts.checkpoint {
                let h = ctx.header(k, false, ctx.grains.time, ctx.grains.step, 0.0);
                let payload = checkpoint::encode(&Payload::<D, ()>::AtStart(ctx.grains.clone()));
                write_checkpoint(&ctx, spec, &h, &payload)?;
            }
            hard_stage(&mut ctx, k, &step)?;
            snapshot = None;
            k += 1;
            continue;
        }
        let mu = scene.mu_of(&step);
        let mut end = k + 1;
        while end < ctx.stages.len()
            && ctx.stages[end].1.is_dem()
            && scene.mu_of(&ctx.stages[end].1) == mu
        {
            end += 1;
        }
        let (snap, stopped) = dispatch_law::<D>(&mut ctx, mu, k..end, inside.take(), opts)?;
        snapshot = Some(snap);
        if stopped {
            interrupted = true;
            break;
        }
        k = end;
    }
    let snapshot = match snapshot {
        Some(s) => s,
        // The protocol ended with hard-grain stages: a snapshot without contacts.
        None => {
            let mu = scene.mu_of(&Step::Expand { factor: 1.0 });
            let n = ctx.stages.len();
            dispatch_law::<D>(&mut ctx, mu, n..n, None, opts)?.0
        }
    };
    if !interrupted {
        if let Some(spec) = &opts.checkpoint {
            // The run is complete: its checkpoint would only resume into a finished run.
            let _ = std::fs::remove_file(&spec.path);
        }
    }
    Ok(Outcome {
        snapshot,
        steps: ctx.reports,
        dt: ctx.dt,
        k_max: ctx.k_max,
        law: ctx.law,
        wall_seconds: ctx.wall_before + ctx.start.elapsed().as_secs_f64(),
        neighbor_builds: ctx.neighbor_builds,
        contacts_at_threshold: ctx.at_threshold,
    })
}

fn write_checkpoint<D: Dim>(
    ctx: &Ctx<D>,
    spec: &CheckpointSpec,
    header: &Header,
    payload: &[u8],
) -> Result<(), RunError> {
    Checkpoint::write(&spec.path, header, payload).map_err(|e| {
        ctx.setup_error(format!(
            "cannot write the checkpoint {}: {e}",
            spec.path.display()
        ))
    })
}

/// A deterministic seed for stage `k` of a scene.
fn stage_seed(seed: u64, k: usize) -> u64 {
    seed ^ (0x9E37_79B9_7F4A_7C15u64.wrapping_mul(k as u64 + 1))
}

/// Hard-grain stages: expansion, event-driven mixing, Lubachevsky–Stillinger growth.
fn hard_stage<D: Dim>(ctx: &mut Ctx<D>, k: usize, step: &Step) -> Result<(), RunError> {
    let t = Instant::now();
    let scene_name = ctx.scene.name.clone();
    let setup = |message: String| RunError::Setup {
        scene: scene_name.clone(),
        message,
    };
    let g = &mut ctx.grains;
    let n = g.s.len();
    let mass: Vec<f64> = g.diameter.iter().map(|d| d.powi(D::D as i32)).collect();
    let radius: Vec<f64> = g.diameter.iter().map(|d| 0.5 * d).collect();
    let hard = |g: &Grains<D>| {
        let vel = maxwell_velocities::<D>(&mass, 1.0, stage_seed(ctx.scene.seed, k));
        HardSpheres::<D>::new(g.l, g.s.clone(), radius.clone(), mass.clone(), vel).map_err(|e| {
            format!("{} stage {}: {e}. Grains must not overlap before hard-sphere dynamics: add an `expand` step first (AR07 §IV.B uses factor = 1.005)", step.kind(), k + 1)
        })
    };
    let (time, collisions) = match step {
        Step::Expand { factor } => {
            g.l = g.l * *factor;
            (0.0, 0)
        }
        Step::HardSphereMix {
            collisions_per_grain,
        } => {
            let mut hs = hard(g).map_err(setup)?;
            let st = hs.run_collisions(*collisions_per_grain);
            g.s = hs.s;
            (st.time, st.collisions)
        }
        Step::Grow {
            packing_fraction,
            rate,
        } => {
            let mut hs = hard(g).map_err(setup)?;
            let st = hs
                .grow(*packing_fraction, *rate)
                .map_err(|e| setup(format!("grow stage {}: {e}", k + 1)))?;
            // Back to the length unit a: the grains keep their diameters, the cell shrinks.
            let factor = hs.radius[0] / radius[0];
            g.l = hs.l * (1.0 / factor);
            g.s = hs.s;
            (st.time, st.collisions)
        }
        _ => unreachable!("DEM stage in hard_stage"),
    };
    g.u = vec![D::V::zero(); n];
    let phi: f64 = g.diameter.iter().map(|d| D::grain_volume(*d)).sum::<f64>() / D::product(g.l);
    ctx.reports.push(StepReport {
        index: k,
        kind: step.kind().into(),
        end: StepEnd::Done,
        time,
        steps: collisions,
        wall_seconds: t.elapsed().as_secs_f64(),
        checks: Checks {
            packing_fraction: phi,
            pressure_target: f64::NAN,
            ..Default::default()
        },
        peak_strain_rate: 0.0,
        relaxation: None,
    });
    Ok(())
}

fn dispatch_law<D: Dim>(
    ctx: &mut Ctx<D>,
    mu: Mu,
    range: std::ops::Range<usize>,
    inside: Option<(Header, Vec<u8>)>,
    opts: &mut RunOptions,
) -> Result<(Snapshot, bool), RunError> {
    let law = &ctx.scene.law.clone();
    match law {
        Law::HertzMindlin { .. } => match mu {
            Mu::Finite(0.0) => run_law::<D, _>(
                ctx,
                hertz_mindlin_law(law, Frictionless),
                range,
                inside,
                opts,
            ),
            Mu::Finite(m) => run_law::<D, _>(
                ctx,
                hertz_mindlin_law(law, Coulomb { mu: m }),
                range,
                inside,
                opts,
            ),
            Mu::Infinite => {
                run_law::<D, _>(ctx, hertz_mindlin_law(law, NoSlip), range, inside, opts)
            }
        },
        Law::Linear { cohesion, .. } => match cohesion {
            Some(c) => linear_friction::<D, _>(ctx, adhesion(c), mu, range, inside, opts),
            None => linear_friction::<D, _>(ctx, NoCohesion, mu, range, inside, opts),
        },
    }
}

fn linear_friction<D: Dim, C: Cohesion>(
    ctx: &mut Ctx<D>,
    c: C,
    mu: Mu,
    range: std::ops::Range<usize>,
    inside: Option<(Header, Vec<u8>)>,
    opts: &mut RunOptions,
) -> Result<(Snapshot, bool), RunError> {
    match mu {
        Mu::Finite(0.0) => linear_rolling::<D, C, _>(ctx, c, Frictionless, range, inside, opts),
        Mu::Finite(m) => linear_rolling::<D, C, _>(ctx, c, Coulomb { mu: m }, range, inside, opts),
        Mu::Infinite => linear_rolling::<D, C, _>(ctx, c, NoSlip, range, inside, opts),
    }
}

fn linear_rolling<D: Dim, C: Cohesion, F: Friction>(
    ctx: &mut Ctx<D>,
    c: C,
    f: F,
    range: std::ops::Range<usize>,
    inside: Option<(Header, Vec<u8>)>,
    opts: &mut RunOptions,
) -> Result<(Snapshot, bool), RunError> {
    let law = &ctx.scene.law.clone();
    match rolling_spring(law) {
        Some(r) => run_law::<D, _>(ctx, linear_law(law, c, f, r), range, inside, opts),
        None => run_law::<D, _>(ctx, linear_law(law, c, f, NoRolling), range, inside, opts),
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

/// Generalized mass of the cell, AR07 (7): `numerics.cell_mass` × the total grain mass,
/// divided by the cell's linear size when `cell_mass_per_length` (GRC07 §II.A).
pub fn cell_mass(numerics: &crate::scene::Numerics, total_mass: f64, volume: f64, d: usize) -> f64 {
    let m = numerics.cell_mass * total_mass;
    if numerics.cell_mass_per_length {
        m / volume.powf(1.0 / d as f64)
    } else {
        m
    }
}

/// The system of a scene's initial grains for a law (as the first stage of a scene that starts
/// with a DEM stage sees it).
pub fn build_system<D: Dim, L: ContactLaw<D>>(
    scene: &Scene,
    law: L,
) -> Result<System<D, L>, String> {
    system_of(scene, law, &initial_grains::<D>(scene)?)
}

/// A system holding `grains`, with the law, cell mass and time step of the scene.
pub fn system_of<D: Dim, L: ContactLaw<D>>(
    scene: &Scene,
    law: L,
    grains: &Grains<D>,
) -> Result<System<D, L>, String> {
    let total_mass: f64 = grains.diameter.iter().map(|d| d.powi(D::D as i32)).sum();
    let cell_mass = cell_mass(&scene.numerics, total_mass, D::product(grains.l), D::D);
    let cell = Cell::new(grains.l, cell_mass);
    let mut sys = System::new(
        law,
        cell,
        grains.s.clone(),
        &grains.diameter,
        scene.numerics.skin,
    );
    sys.u.clone_from(&grains.u);
    sys.time = grains.time;
    sys.step = grains.step;
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

/// Runs the DEM stages `range` with one typed law, from the grains in `ctx` or from a
/// checkpoint taken inside the first of them. Returns the snapshot and whether it stopped.
fn run_law<D: Dim, L: ContactLaw<D>>(
    ctx: &mut Ctx<D>,
    law: L,
    range: std::ops::Range<usize>,
    inside: Option<(Header, Vec<u8>)>,
    opts: &mut RunOptions,
) -> Result<(Snapshot, bool), RunError> {
    let scene = ctx.scene;
    let (mut sys, resume_at) = match inside {
        Some((h, payload)) => match checkpoint::decode::<Payload<D, L::History>>(&payload)
            .map_err(|e| ctx.setup_error(e))?
        {
            Payload::Inside(st, watch) => (
                System::from_state(law, st),
                Some((h.stage_time0, h.stage_steps0, h.stage_wall, watch)),
            ),
            Payload::AtStart(_) => {
                return Err(ctx.setup_error("checkpoint payload does not match its header".into()))
            }
        },
        None => {
            let mut sys = system_of(scene, law, &ctx.grains).map_err(|e| ctx.setup_error(e))?;
            sys.init_forces();
            (sys, None)
        }
    };
    let (dt, k_max) = time_step::<D, L>(scene, &sys);
    debug_assert!(resume_at.is_some() || sys.dt == dt);
    ctx.dt = sys.dt;
    ctx.k_max = k_max;
    ctx.law = sys.law.describe();
    let builds0 = sys.nlist.builds;
    let stopped = run_stages(ctx, &mut sys, range, resume_at, opts)?;
    ctx.neighbor_builds += sys.nlist.builds - builds0;
    ctx.at_threshold = contacts_at_threshold(&sys, scene);
    let status = if stopped {
        "interrupted"
    } else if ctx.reports.iter().all(|r| r.end.ok()) {
        "equilibrium"
    } else {
        "time-limit"
    };
    let snap = snapshot_of(&sys, scene, status, ctx.pressure);
    ctx.grains = Grains {
        l: sys.cell.l,
        s: sys.s.clone(),
        u: sys.u.clone(),
        diameter: sys.radius.iter().map(|r| 2.0 * r).collect(),
        time: sys.time,
        step: sys.step,
    };
    Ok((snap, stopped))
}

/// A system of `scene` with `law`, run through its protocol until the packing fraction
/// reaches `phi_stop` at a check (or the protocol ends): the fast-compressed dense packings of
/// the step benchmarks and `grainbench bench --scale`.
pub fn compress_until<D: Dim, L: ContactLaw<D>>(
    scene: &Scene,
    law: L,
    phi_stop: f64,
) -> Result<System<D, L>, RunError> {
    let mut sys = build_system::<D, L>(scene, law).map_err(|message| RunError::Setup {
        scene: scene.name.clone(),
        message,
    })?;
    let stop = AtomicBool::new(false);
    let mut progress = |p: &Progress| {
        if p.checks.packing_fraction >= phi_stop {
            stop.store(true, Ordering::Relaxed);
        }
    };
    let mut opts = RunOptions {
        progress: Some(&mut progress),
        stop: Some(&stop),
        ..Default::default()
    };
    // On a pool worker, as `run_scene` does.
    rayon::scope(|_| run_protocol(scene, &mut sys, &mut opts))?;
    Ok(sys)
}

/// Runs every DEM stage of `scene` on a prepared system (all with the system's law): the
/// benches' preparation route.
pub fn run_protocol<D: Dim, L: ContactLaw<D>>(
    scene: &Scene,
    sys: &mut System<D, L>,
    opts: &mut RunOptions,
) -> Result<(Vec<StepReport>, Snapshot, usize), RunError> {
    sys.init_forces();
    let mut ctx = Ctx::<D>::new(scene);
    let n = ctx.stages.len();
    let stopped = run_stages(&mut ctx, sys, 0..n, None, opts)?;
    let status = if stopped {
        "interrupted"
    } else {
        "equilibrium"
    };
    let snap = snapshot_of(sys, scene, status, ctx.pressure);
    Ok((ctx.reports, snap, contacts_at_threshold(sys, scene)))
}

/// Number of clusters of `n` grains linked by interactions (contacts or distant attractions).
fn clusters<D: Dim>(n: usize, inter: &[system::Interaction<D>]) -> usize {
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut count = n;
    for c in inter {
        let (a, b) = (root(&mut parent, c.i), root(&mut parent, c.j));
        if a != b {
            parent[a] = b;
            count -= 1;
        }
    }
    count
}

/// The stages `range` on one system; returns whether the run was stopped.
fn run_stages<D: Dim, L: ContactLaw<D>>(
    ctx: &mut Ctx<D>,
    sys: &mut System<D, L>,
    range: std::ops::Range<usize>,
    mut resume_at: Option<(f64, u64, f64, StageWatch<D>)>,
    opts: &mut RunOptions,
) -> Result<bool, RunError> {
    let scene = ctx.scene;
    let base_law = sys.law;
    let n = sys.len() as f64;
    let ke0 = sys.kinetic_energy() / n;
    let mut last_good = None;
    sys.save(&mut last_good);
    let cohesive = scene.law.cohesion().is_some();
    let stage_count = ctx.stages.len();
    for k in range {
        let step = ctx.stages[k].1.clone();
        let kind = step.kind();
        // κ of the stage (GRC07 §III.B.2 ramps), always scaled from the scene's law so that a
        // resumed run has the same law bit for bit; the time step follows.
        let factor = step.kappa().map_or(1.0, |k| k / scene.law.kappa());
        sys.law = base_law.with_kappa_scaled(factor);
        let (dt, k_max) = time_step::<D, L>(scene, sys);
        sys.dt = dt;
        ctx.dt = dt;
        ctx.k_max = k_max;
        match &step {
            Step::Compress {
                pressure: p,
                inertia_cap,
                ..
            } => {
                ctx.pressure = Some(*p);
                // Strain-rate cap: AR07 (23) I = ε̇√(m/(aP)) (time unit √(m/(aP)) for P > 0
                // without cohesion), GRC08 I_a = ε̇ T0 with T0 = √(m a/F0) = 1 with cohesion.
                let time_unit = if cohesive { 1.0 } else { 1.0 / p.sqrt() };
                let mut target = D::V::zero();
                for a in 0..D::D {
                    target[a] = *p;
                }
                sys.cell.control = Control::Stress {
                    target,
                    rate_cap: inertia_cap / time_unit,
                };
            }
            _ => {
                sys.cell.control = Control::Fixed;
                sys.cell.ldot = D::V::zero();
            }
        }
        let criteria = step.criteria();
        let f_ref = match criteria.scale {
            ForceScale::Pressure => ctx.pressure.unwrap_or(1.0),
            ForceScale::Cohesion => ctx.pressure.unwrap_or(0.0).max(1.0),
        };
        let full_time = matches!(
            step,
            Step::FixedVolume {
                full_time: true,
                ..
            }
        );
        let aggregate = matches!(step, Step::Aggregate { .. });
        let (t0, steps0, wall0, mut watch) = match resume_at.take() {
            Some(r) => r,
            None => (sys.time, sys.step, 0.0, StageWatch::new(step.relax(), sys.time)),
        };
        if let Some(z) = watch.tangential_zeta() {
            sys.law = sys.law.with_tangential_damping(z);
        }
        let step_start = Instant::now();
        let max_time = step.max_time();
        let end;
        let mut checks;
        let mut prev_force: Vec<D::V> = Vec::new();
        let mut prev_torque: Vec<D::Ang> = Vec::new();
        let mut flips = 0u32;
        loop {
            let damping = watch.damping_factor(sys.dt);
            for m in 0..scene.numerics.check_every {
                if m + 1 == scene.numerics.check_every {
                    prev_force.clear();
                    prev_force.extend_from_slice(&sys.force);
                    prev_torque.clear();
                    prev_torque.extend_from_slice(&sys.torque);
                }
                sys.step();
                if let Some(f) = damping {
                    sys.damp(f);
                }
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
            checks = measure(sys, &criteria, f_ref, &step);
            if let Some(cb) = opts.progress.as_mut() {
                cb(&Progress {
                    step_index: k,
                    step_count: stage_count,
                    step_kind: kind,
                    time: sys.time - t0,
                    max_time,
                    steps: sys.step - steps0,
                    checks: checks.clone(),
                });
            }
            // Time step past stability: the fastest modes flip sign at every step (the
            // integrator's amplification is real and negative) and, held by the nonlinear
            // contacts, oscillate for ever instead of blowing up: a packing that never
            // equilibrates, denser than it should be.
            let flip = step_correlation(&prev_force, &sys.force)
                .min(step_correlation(&prev_torque, &sys.torque));
            flips = if flip < FLIP_CORRELATION && !checks.equilibrium() {
                flips + 1
            } else {
                0
            };
            if flips >= FLIP_CHECKS {
                return Err(unstable(
                    scene,
                    sys,
                    &last_good,
                    format!(
                        "the net forces on the grains reverse at every time step (correlation of consecutive steps {flip:.2} at {flips} consecutive checks, force/criterion = {:.2e}): the fastest contact vibration has fewer than four time steps per period, the integration no longer follows the dynamics and the packing would be wrong",
                        checks.force_ratio
                    ),
                ));
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
            if watch.watching()
                && watch.observe_structure(
                    sys.time,
                    &mut pair_list(sys),
                    checks.kinetic_ratio < 1.0,
                    checks.packing_fraction,
                    &sys.s,
                )
            {
                if let Some(z) = watch.tangential_zeta() {
                    sys.law = sys.law.with_tangential_damping(z);
                }
            }
            watch.peak_strain_rate = watch.peak_strain_rate.max(checks.strain_rate);
            let held = watch.held(sys.time, checks.equilibrium(), criteria.window);
            if aggregate && checks.clusters == 1 {
                end = StepEnd::OneCluster;
                break;
            }
            if !aggregate && !full_time && held {
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
            if let Some(spec) = &opts.checkpoint {
                if ctx.last_checkpoint.elapsed().as_secs_f64() >= spec.every {
                    let wall = wall0 + step_start.elapsed().as_secs_f64();
                    let h = ctx.header(k, true, t0, steps0, wall);
                    let payload = checkpoint::encode(&Payload::<D, L::History>::Inside(
                        sys.state(),
                        watch.clone(),
                    ));
                    write_checkpoint(ctx, spec, &h, &payload)?;
                    ctx.last_checkpoint = Instant::now();
                }
            }
        }
        // A full-time run that also meets the criteria at its end counts as equilibrated.
        let end = if full_time && end == StepEnd::TimeLimit && checks.equilibrium() {
            StepEnd::Equilibrium
        } else {
            end
        };
        let wall = wall0 + step_start.elapsed().as_secs_f64();
        if end == StepEnd::Interrupted {
            // Resumable from exactly here.
            if let Some(spec) = &opts.checkpoint {
                let h = ctx.header(k, true, t0, steps0, wall);
                let payload = checkpoint::encode(&Payload::<D, L::History>::Inside(
                    sys.state(),
                    watch.clone(),
                ));
                write_checkpoint(ctx, spec, &h, &payload)?;
            }
        }
        let relaxation = if watch.damping_on() {
            watch.report(
                t0,
                &mut pair_list(sys),
                sys.packing_fraction(),
                &sys.s,
                sys.cell.l,
            )
        } else {
            None
        };
        ctx.reports.push(StepReport {
            index: k,
            kind: kind.into(),
            end,
            time: sys.time - t0,
            steps: sys.step - steps0,
            wall_seconds: wall,
            checks,
            peak_strain_rate: watch.peak_strain_rate,
            relaxation,
        });
        if end == StepEnd::Interrupted {
            return Ok(true);
        }
    }
    Ok(false)
}

/// Interacting pairs (i < j) of the current state.
fn pair_list<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>) -> Vec<(u32, u32)> {
    sys.interactions()
        .iter()
        .map(|c| (c.i.min(c.j) as u32, c.i.max(c.j) as u32))
        .collect()
}

/// Consecutive-step correlation of the net forces below which a check counts as flipping.
const FLIP_CORRELATION: f64 = -0.5;
/// Consecutive flipping checks (outside equilibrium) that stop a run as unstable.
const FLIP_CHECKS: u32 = 5;

/// Correlation Σ a·b / √(Σ|a|² Σ|b|²) of the net forces (or torques) of two consecutive
/// steps: ≈ cos(ω dt) of the dominant mode, near 1 when the time step resolves the motion,
/// negative when the dominant mode has fewer than four steps per period (ω dt > π/2), the
/// signature of a time step past the stability of the leapfrog/velocity-Verlet scheme
/// (ω dt < 2). 1 when there is no force.
fn step_correlation<V: crate::geometry::Linear>(a: &[V], b: &[V]) -> f64 {
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        ab += x.dot(y);
        aa += x.dot(x);
        bb += y.dot(y);
    }
    if aa > 0.0 && bb > 0.0 {
        ab / (aa * bb).sqrt()
    } else {
        1.0
    }
}

/// The error for a blown-up run; `sys` is returned to the last good checkpoint to write it.
fn unstable<D: Dim, L: ContactLaw<D>>(
    scene: &Scene,
    sys: &mut System<D, L>,
    last_good: &Option<system::Checkpoint<D, L>>,
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
        strain_rate: (0..D::D)
            .map(|a| (sys.cell.ldot[a] / sys.cell.l[a]).abs())
            .fold(0.0, f64::max),
        interactions: inter.len(),
        clusters: if matches!(step, Step::Aggregate { .. }) {
            clusters(sys.len(), &inter)
        } else {
            0
        },
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
        code: checkpoint::code(),
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

/// The common start of a cross-code comparison: the scene's initial grains with its leading
/// hard-grain stages (melting, growth, expansion) applied, and the index of the first DEM
/// stage. External codes have no event-driven dynamics, so their decks start here, from the
/// very configuration our DEM stages start from.
pub fn prepared_grains<D: Dim>(scene: &Scene) -> Result<(Grains<D>, usize), String> {
    let mut ctx = Ctx::<D>::new(scene);
    ctx.grains = initial_grains::<D>(scene)?;
    let mut k = 0;
    while k < ctx.stages.len() && !ctx.stages[k].1.is_dem() {
        let step = ctx.stages[k].1.clone();
        hard_stage(&mut ctx, k, &step).map_err(|e| e.to_string())?;
        k += 1;
    }
    Ok((ctx.grains, k))
}

/// The time step our engine uses for `grains` at stiffness `kappa` (the scene's law with κ
/// replaced): `dt_fraction` of the binary contact duration with the stiffest contact.
pub fn time_step_for<D: Dim>(scene: &Scene, grains: &Grains<D>, kappa: f64) -> Result<f64, String> {
    let factor = kappa / scene.law.kappa();
    let dt = match &scene.law {
        Law::HertzMindlin { .. } => {
            let law = <HertzMindlin<Frictionless> as ContactLaw<D>>::with_kappa_scaled(
                &hertz_mindlin_law(&scene.law, Frictionless),
                factor,
            );
            time_step::<D, _>(scene, &system_of(scene, law, grains)?).0
        }
        Law::Linear { .. } => {
            let law =
                <Linear<NoCohesion, Frictionless, NoRolling> as ContactLaw<D>>::with_kappa_scaled(
                    &linear_law(&scene.law, NoCohesion, Frictionless, NoRolling),
                    factor,
                );
            time_step::<D, _>(scene, &system_of(scene, law, grains)?).0
        }
    };
    Ok(dt)
}
