//! The stage loop: DEM stages run to their criteria with checks, progress and checkpoints;
//! hard-grain stages (expansion, event-driven mixing, growth).

use super::checkpoint::{self, Checkpoint, Header};
use super::checks::{
    contacts_at_threshold, links_into, measure, settle_view, step_correlation, stopped, unstable,
    Link,
};
use super::checks::{FLIP_CHECKS, FLIP_CORRELATION};
use super::grains::Grains;
use super::options::{CheckpointSpec, DumpSpec, RunOptions};
use super::output::snapshot_of;
use super::quench::Quenched;
use super::relax::{Relaxation, StageWatch};
use super::report::{AtThreshold, Checks, Progress, RunError, StepEnd, StepReport};
use super::setup::{build_system, initial_grains};
use crate::cell::Control;
use crate::contact::ContactLaw;
use crate::geometry::{Dim, VectorOps as _};
use crate::init::maxwell_velocities;
use crate::neighbor::branch;
use crate::network;
use crate::plan::{self, HardStage, Plan, PlanStage, PlanStep, StageKind};
use crate::protocols::event_driven::HardSpheres;
use crate::scene::{Scene, Step};
use crate::snapshot::Snapshot;
use crate::system::{LastGood, State, StateRef, System};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Checkpoint payload: grains at a stage start, or the integrator inside a stage.
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(bound(
    serialize = "H: serde::Serialize",
    deserialize = "H: serde::de::DeserializeOwned"
))]
#[allow(clippy::large_enum_variant)] // one per checkpoint write, short-lived
pub(super) enum Payload<D: Dim, H> {
    AtStart(Grains<D>),
    /// The integrator state and what the stage watches across its checks.
    Inside(State<D, H>, StageWatch<D>),
}

/// [`Payload`] borrowed, as a checkpoint writes it (the same bytes, no copy of the state).
#[derive(serde::Serialize)]
#[serde(bound(serialize = "H: serde::Serialize"))]
pub(super) enum PayloadRef<'a, D: Dim, H> {
    AtStart(&'a Grains<D>),
    Inside(StateRef<'a, D, H>, &'a StageWatch<D>),
}

/// Bookkeeping carried through the stages.
pub(super) struct Ctx<'s, D: Dim> {
    pub(super) scene: &'s Scene,
    /// The scene's stages (pressure programs and κ ramps unrolled): the run's structure,
    /// known before the grains.
    pub(super) stages: Vec<(usize, Step)>,
    /// The resolved protocol, once the grains are known ([`Ctx::plan_for`]).
    plan: Option<Plan>,
    /// The last stage entered (`None` before the first).
    pub(super) current: Option<usize>,
    pub(super) start: Instant,
    pub(super) wall_before: f64,
    pub(super) reports: Vec<StepReport>,
    pub(super) grains: Grains<D>,
    pub(super) neighbor_builds: u64,
    pub(super) last_checkpoint: Instant,
    pub(super) dt: f64,
    pub(super) k_max: f64,
    pub(super) law: String,
    pub(super) at_threshold: AtThreshold,
}

impl<'s, D: Dim> Ctx<'s, D> {
    /// A run of `scene` starting now, with no grains yet.
    pub(super) fn new(scene: &'s Scene) -> Self {
        Ctx {
            scene,
            stages: scene.stages(),
            plan: None,
            current: None,
            start: Instant::now(),
            wall_before: 0.0,
            reports: Vec::new(),
            grains: Grains {
                l: D::V::zero(),
                s: Vec::new(),
                u: Vec::new(),
                w: Vec::new(),
                diameter: Vec::new(),
                time: 0.0,
                step: 0,
            },
            neighbor_builds: 0,
            last_checkpoint: Instant::now(),
            dt: 0.0,
            k_max: 0.0,
            law: String::new(),
            at_threshold: Default::default(),
        }
    }

    /// Builds the plan for grains of diameters `diameter`, once (the grains are known at the
    /// start of a run, or once a checkpoint taken inside a stage is decoded).
    pub(super) fn plan_for(&mut self, diameter: &[f64]) -> Result<&Plan, RunError> {
        if self.plan.is_none() {
            let plan = Plan::new(self.scene, diameter).map_err(|e| self.setup_error(e))?;
            self.plan = Some(plan);
        }
        Ok(self.plan())
    }

    /// [`Ctx::plan_for`] the grains of `sys`.
    pub(super) fn plan_for_system<L: ContactLaw<D>>(
        &mut self,
        sys: &System<D, L>,
    ) -> Result<&Plan, RunError> {
        let diameter: Vec<f64> = sys.radius.iter().map(|r| 2.0 * r).collect();
        self.plan_for(&diameter)
    }

    /// The plan (built by [`Ctx::plan_for`] before any stage runs).
    pub(super) fn plan(&self) -> &Plan {
        self.plan
            .as_ref()
            .expect("the plan is built before the stages run")
    }

    /// The pressure last prescribed, as of the last stage entered.
    pub(super) fn pressure(&self) -> Option<f64> {
        self.current.and_then(|k| self.plan().pressure_at(k))
    }

    /// Contacts at a threshold, judged at the end of the run by the law's μ and μ_r and the
    /// tolerances of the last DEM stage.
    pub(super) fn contacts_at_threshold<L: ContactLaw<D>>(
        &self,
        sys: &System<D, L>,
    ) -> AtThreshold {
        let plan = self.plan();
        match plan.dem_stages().last() {
            Some(s) => contacts_at_threshold(
                sys,
                plan.mu,
                plan.mu_r.unwrap_or(f64::INFINITY),
                &s.tolerances,
            ),
            None => Default::default(),
        }
    }

    pub(super) fn header(
        &self,
        stage: usize,
        inside: bool,
        t0: f64,
        steps0: u64,
        stage_wall: f64,
    ) -> Header {
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
            pressure: self.pressure(),
            neighbor_builds: self.neighbor_builds,
        }
    }

    pub(super) fn setup_error(&self, message: String) -> RunError {
        RunError::Setup {
            scene: self.scene.name.clone(),
            message,
        }
    }
}

pub(super) fn write_checkpoint<D: Dim>(
    ctx: &Ctx<D>,
    spec: &CheckpointSpec,
    header: &Header,
    payload: &impl serde::Serialize,
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
pub(super) fn hard_stage<D: Dim>(ctx: &mut Ctx<D>, k: usize) -> Result<(), RunError> {
    let step = match ctx.plan().steps[k] {
        PlanStep::Hard(h) => h,
        PlanStep::Dem(_) => unreachable!("DEM stage in hard_stage"),
    };
    ctx.current = Some(k);
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
            format!("{} stage {}: {e}. Grains must not overlap before hard-sphere dynamics: add an `expand` step first (AR07 §IV.B uses factor = 1.005)", step.name(), k + 1)
        })
    };
    let (time, collisions) = match step {
        HardStage::Expand { factor } => {
            g.l = g.l * factor;
            (0.0, 0)
        }
        HardStage::HardSphereMix {
            collisions_per_grain,
        } => {
            let mut hs = hard(g).map_err(setup)?;
            let st = hs.run_collisions(collisions_per_grain);
            g.s = hs.s;
            (st.time, st.collisions)
        }
        HardStage::Grow {
            packing_fraction,
            rate,
        } => {
            let mut hs = hard(g).map_err(setup)?;
            let st = hs
                .grow(packing_fraction, rate)
                .map_err(|e| setup(format!("grow stage {}: {e}", k + 1)))?;
            // Back to the length unit a: the grains keep their diameters, the cell shrinks.
            let factor = hs.radius[0] / radius[0];
            g.l = hs.l * (1.0 / factor);
            g.s = hs.s;
            (st.time, st.collisions)
        }
    };
    g.u = vec![D::V::zero(); n];
    g.w = Vec::new();
    let phi: f64 = g.diameter.iter().map(|d| D::grain_volume(*d)).sum::<f64>() / D::product(g.l);
    ctx.reports.push(StepReport {
        index: k,
        kind: step.name().into(),
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
        quench: None,
    });
    Ok(())
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
) -> Result<(Vec<StepReport>, Snapshot, AtThreshold), RunError> {
    sys.init_forces();
    let mut ctx = Ctx::<D>::new(scene);
    ctx.plan_for_system(sys)?;
    let n = ctx.stages.len();
    let stopped = run_stages(&mut ctx, sys, 0..n, None, opts)?;
    let status = if stopped {
        StepEnd::Interrupted
    } else {
        StepEnd::Equilibrium
    };
    let snap = snapshot_of(sys, ctx.plan(), status.as_str(), ctx.pressure());
    let at_threshold = ctx.contacts_at_threshold(sys);
    Ok((ctx.reports, snap, at_threshold))
}

/// The stages `range` on one system; returns whether the run was stopped.
pub(super) fn run_stages<D: Dim, L: ContactLaw<D>>(
    ctx: &mut Ctx<D>,
    sys: &mut System<D, L>,
    range: std::ops::Range<usize>,
    mut resume_at: Option<(f64, u64, f64, StageWatch<D>)>,
    opts: &mut RunOptions,
) -> Result<bool, RunError> {
    let plan = ctx.plan().clone();
    let base_law = sys.law;
    let n = sys.len() as f64;
    let ke0 = sys.kinetic_energy() / n;
    let mut last_good = None;
    sys.save(&mut last_good);
    // The interacting pairs of the current check, one buffer for the whole run (a fresh list
    // at every check would be allocated and faulted in again each time).
    let mut inter = Vec::new();
    let stage_count = plan.steps.len();
    for k in range {
        let stage: PlanStage = *plan.steps[k].dem().expect("run_stages runs DEM stages");
        let kind = stage.kind.name();
        ctx.current = Some(k);
        configure(sys, base_law, &stage, &plan);
        ctx.dt = stage.dt;
        ctx.k_max = stage.k_max;
        let full_time = stage.kind == StageKind::FixedVolume { full_time: true };
        let max_time = stage.max_time;
        let (t0, steps0, wall0, mut watch) = match resume_at.take() {
            Some(r) => r,
            None => (
                sys.time,
                sys.step,
                0.0,
                StageWatch::new(stage.relax, sys.time),
            ),
        };
        if let Some(z) = watch.tangential_zeta() {
            sys.law = sys.law.with_tangential_damping(z);
        }
        let step_start = Instant::now();
        let end;
        let mut checks;
        let mut prev_force: Vec<D::V> = Vec::new();
        let mut prev_torque: Vec<D::Ang> = Vec::new();
        let mut flips = 0u32;
        let mut first_check = true;
        loop {
            let damping = watch.damping_factor(sys.dt);
            if let Some(f) = &watch.fire {
                // Also after a resume inside the FIRE phase.
                sys.dt = f.dt();
                sys.law = sys.law.without_normal_damping();
            }
            for m in 0..stage.check_every {
                if m + 1 == stage.check_every {
                    prev_force.clear();
                    prev_force.extend_from_slice(&sys.force);
                    prev_torque.clear();
                    prev_torque.extend_from_slice(&sys.torque);
                }
                sys.step();
                if let Some(f) = damping {
                    sys.damp(f);
                }
                if let Some(f) = watch.fire.as_mut() {
                    f.after_step(sys);
                }
                let (ov, ..) = sys.max_overlap;
                if ov.is_nan() || ov > stage.max_overlap {
                    return Err(overlap_error(&plan, &stage, sys, &last_good));
                }
            }
            links_into(sys, &mut inter);
            checks = measure(sys, &stage, &inter);
            if let Some(cb) = opts.progress.as_mut() {
                let stressed = matches!(sys.cell.control, Control::Stress { .. });
                let wrapped_axes = (first_check && stressed).then(|| wrapped_axes(sys, &inter));
                first_check = false;
                cb(&Progress {
                    step_index: k,
                    step_count: stage_count,
                    step_kind: kind,
                    time: sys.time - t0,
                    max_time,
                    steps: sys.step - steps0,
                    checks: checks.clone(),
                    relaxing: watch.damping_on(),
                    dt: sys.dt,
                    wrapped_axes,
                });
            }
            if let Some(d) = opts.dump.as_mut() {
                dump_frame(d, sys, &plan, &stage);
            }
            guard(
                &plan,
                &stage,
                sys,
                &mut last_good,
                &checks,
                (&prev_force, &prev_torque),
                &mut flips,
                ke0,
            )?;
            watch_phases(sys, &stage, &mut watch, &inter, &checks);
            let held = watch.held(sys.time, checks.equilibrium(), stage.window);
            let stop = opts.stop.is_some_and(|s| s.load(Ordering::Relaxed));
            if let Some(e) = ends_now(stage.kind, &checks, held, sys.time - t0 >= max_time, stop) {
                end = e;
                break;
            }
            if let Some(spec) = &opts.checkpoint {
                if ctx.last_checkpoint.elapsed().as_secs_f64() >= spec.every {
                    let wall = wall0 + step_start.elapsed().as_secs_f64();
                    checkpoint_inside(ctx, spec, sys, &watch, (k, t0, steps0, wall))?;
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
                checkpoint_inside(ctx, spec, sys, &watch, (k, t0, steps0, wall))?;
            }
        }
        // The final pairs are listed once, and only when a report compares with them.
        let (relaxation, quench) = phase_reports(sys, &mut watch, t0);
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
            quench,
        });
        if end == StepEnd::Interrupted {
            return Ok(true);
        }
        if let Some(hook) = opts.stage_end.as_mut() {
            let report = ctx.reports.last().expect("pushed above");
            // The state a stage that reached its end leaves is an equilibrium state.
            let status = if end.ok() { StepEnd::Equilibrium } else { end };
            hook(
                report,
                &snapshot_of(sys, &plan, status.as_str(), stage.pressure),
            );
        }
    }
    Ok(false)
}

/// After the steps of a check, the signs that the run blew up, each an error carrying the last
/// state that passed them; else the state becomes the last good one. `prev` holds the forces
/// and torques of the step before the check's last, `flips` the checks in a row whose
/// consecutive forces reverse.
#[allow(clippy::too_many_arguments)]
fn guard<D: Dim, L: ContactLaw<D>>(
    plan: &Plan,
    stage: &PlanStage,
    sys: &mut System<D, L>,
    last_good: &mut Option<LastGood<D, L>>,
    checks: &Checks,
    prev: (&[D::V], &[D::Ang]),
    flips: &mut u32,
    ke0: f64,
) -> Result<(), RunError> {
    // Time step past stability: the fastest modes flip sign at every step (the
    // integrator's amplification is real and negative) and, held by the nonlinear
    // contacts, oscillate for ever instead of blowing up: a packing that never
    // equilibrates, denser than it should be.
    let flip = step_correlation(prev.0, &sys.force).min(step_correlation(prev.1, &sys.torque));
    *flips = if flip < FLIP_CORRELATION && !checks.equilibrium() {
        *flips + 1
    } else {
        0
    };
    if *flips >= FLIP_CHECKS {
        return Err(unstable(
            plan,
            stage,
            sys,
            last_good,
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
            plan,
            stage,
            sys,
            last_good,
            "non-finite velocities, forces or cell lengths".into(),
        ));
    }
    // The cell may shrink below the minimum-image limit while compressing (with
    // `count = 8` a pair touching through two images was counted once).
    if let Err(e) = sys.check_cell() {
        return Err(stopped(
            plan,
            sys,
            last_good,
            format!("the cell shrank during the stage: {e} (particles.count): a pair would interact through two periodic images, which the minimum-image convention counts once"),
        ));
    }
    if checks.kinetic_per_grain > 1e4 * (stage.f_ref + ke0) {
        return Err(unstable(
            plan,
            stage,
            sys,
            last_good,
            format!(
                "kinetic energy per grain exploded to {:.3e} (force unit × a)",
                checks.kinetic_per_grain
            ),
        ));
    }
    sys.save(last_good);
    Ok(())
}

/// Sets `sys` up for `stage`: κ (the time step follows, as the plan resolved it) and the
/// cell's control, a stress target with its rate cap or a fixed cell at rest.
fn configure<D: Dim, L: ContactLaw<D>>(
    sys: &mut System<D, L>,
    base_law: L,
    stage: &PlanStage,
    plan: &Plan,
) {
    sys.law = base_law.with_kappa_scaled(stage.kappa_factor);
    debug_assert_eq!(
        plan::time_step(
            &sys.law,
            &sys.mass,
            &sys.radius,
            plan.dt_fraction,
            plan.stiffness_force
        ),
        (stage.dt, stage.k_max),
        "the plan's time step is the typed law's"
    );
    sys.dt = stage.dt;
    match stage.kind {
        StageKind::Compress { pressure } => {
            let mut target = D::V::zero();
            for a in 0..D::D {
                target[a] = pressure;
            }
            sys.cell.control = Control::Stress {
                target,
                rate_cap: stage.max_strain_rate,
                servo: stage.servo_gain,
            };
        }
        _ => {
            sys.cell.control = Control::Fixed;
            sys.cell.ldot = D::V::zero();
        }
    }
}

/// The axes along which the contact network wraps around the cell
/// ([`network::wrapped_axes`]), from the pairs only: each branch is computed again when the
/// walk reaches it.
fn wrapped_axes<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>, inter: &[Link]) -> Vec<bool> {
    let mut edges = Vec::with_capacity(inter.len());
    sys.for_each_interaction(|c| edges.push((c.i as u32, c.j as u32)));
    network::wrapped_axes(
        &sys.cell.l.to_vec(),
        sys.len(),
        &edges,
        |&(i, j)| (i as usize, j as usize),
        |&(i, j)| branch::<D>(&sys.s[i as usize], &sys.s[j as usize], &sys.cell.l),
    )
}

/// The reports of a stage's relaxation and quenches, against its final pairs (listed once,
/// and only when a report compares with them).
fn phase_reports<D: Dim, L: ContactLaw<D>>(
    sys: &System<D, L>,
    watch: &mut StageWatch<D>,
    t0: f64,
) -> (Option<Relaxation>, Option<Quenched>) {
    if !(watch.damping_on() || watch.quench.any()) {
        return (None, None);
    }
    let pairs = &mut {
        let mut links = Vec::new();
        links_into(sys, &mut links);
        pair_list(&links)
    };
    let (phi, s, l) = (sys.packing_fraction(), &sys.s, sys.cell.l);
    (
        watch.report(t0, pairs, phi, s, l),
        watch.quench.report(t0, pairs, phi, s, l),
    )
}

/// A checkpoint inside stage `at.0` (started at time `at.1` and step `at.2`, `at.3` seconds of
/// wall time so far): the integrator and what the stage watches, resumable from exactly here.
fn checkpoint_inside<D: Dim, L: ContactLaw<D>>(
    ctx: &Ctx<D>,
    spec: &CheckpointSpec,
    sys: &System<D, L>,
    watch: &StageWatch<D>,
    at: (usize, f64, u64, f64),
) -> Result<(), RunError> {
    let (k, t0, steps0, wall) = at;
    let h = ctx.header(k, true, t0, steps0, wall);
    let payload = PayloadRef::Inside(sys.state_ref(), watch);
    write_checkpoint(ctx, spec, &h, &payload)
}

/// The error of a check's step whose largest overlap is not finite or beyond the stage's
/// limit (`numerics.max_overlap`).
fn overlap_error<D: Dim, L: ContactLaw<D>>(
    plan: &Plan,
    stage: &PlanStage,
    sys: &mut System<D, L>,
    last_good: &Option<LastGood<D, L>>,
) -> RunError {
    let (ov, i, j) = sys.max_overlap;
    let what = if ov.is_nan() {
        "non-finite positions or forces".to_string()
    } else {
        format!(
            "overlap of {ov:.3} times the smaller radius between grains {i} and {j} (limit numerics.max_overlap = {})",
            stage.max_overlap
        )
    };
    unstable(plan, stage, sys, last_good, what)
}

/// A ParaView or trace frame at the first check of each new multiple of the dump interval.
fn dump_frame<D: Dim, L: ContactLaw<D>>(
    d: &mut DumpSpec,
    sys: &System<D, L>,
    plan: &Plan,
    stage: &PlanStage,
) {
    let frame = (sys.time / d.every).floor() as u64;
    if d.last != Some(frame) {
        d.last = Some(frame);
        (d.sink)(&snapshot_of(sys, plan, "running", stage.pressure));
    }
}

/// At a check, the final phases of a stage: the relaxation watches the structure (GRC07
/// damping, then FIRE where asked), the peak strain rate is kept, and AR07's quench removes
/// the kinetic energy when it alone fails the criteria (not in stages that end otherwise than
/// on the criteria: one cluster, full time).
fn watch_phases<D: Dim, L: ContactLaw<D>>(
    sys: &mut System<D, L>,
    stage: &PlanStage,
    watch: &mut StageWatch<D>,
    inter: &[Link],
    checks: &Checks,
) {
    let observed = watch.watching()
        && watch.observe_structure(
            sys.time,
            settle_view(
                sys,
                stage,
                inter,
                checks,
                watch.free_rollers(),
                watch.settle_factor(),
            ),
            &mut pair_list(inter),
            checks.packing_fraction,
            &sys.s,
        );
    if observed {
        watch.start_fire(sys.dt);
        if let Some(z) = watch.tangential_zeta() {
            sys.law = sys.law.with_tangential_damping(z);
        }
    }
    watch.peak_strain_rate = watch.peak_strain_rate.max(checks.strain_rate);
    if stage.quench && checks.only_kinetic_fails() {
        let n = sys.len() as f64;
        watch.quench.record(
            sys.time,
            sys.kinetic_energy() / n,
            || pair_list(inter),
            checks.packing_fraction,
            &sys.s,
        );
        sys.quench();
    }
}

/// How a stage ends at this check, if it does, in this order: an aggregation with one
/// cluster; the criteria held (not for aggregation or full-time stages); the time limit; a
/// stop request.
fn ends_now(
    kind: StageKind,
    checks: &Checks,
    held: bool,
    out_of_time: bool,
    stop: bool,
) -> Option<StepEnd> {
    let aggregate = kind == StageKind::Aggregate;
    let full_time = kind == StageKind::FixedVolume { full_time: true };
    if aggregate && checks.clusters == 1 {
        Some(StepEnd::OneCluster)
    } else if !aggregate && !full_time && held {
        Some(StepEnd::Equilibrium)
    } else if out_of_time {
        Some(StepEnd::TimeLimit)
    } else if stop {
        Some(StepEnd::Interrupted)
    } else {
        None
    }
}

/// Interacting pairs (i < j) of a list of interactions.
fn pair_list(inter: &[Link]) -> Vec<(u32, u32)> {
    inter.iter().map(Link::pair).collect()
}

/// The common start of a cross-code comparison: the scene's initial grains with its leading
/// hard-grain stages (melting, growth, expansion) applied, the plan of the run, and the index
/// of the first DEM stage. External codes have no event-driven dynamics, so their decks start
/// here, from the very configuration our DEM stages start from.
pub fn prepared_grains<D: Dim>(scene: &Scene) -> Result<(Grains<D>, Plan, usize), String> {
    let mut ctx = Ctx::<D>::new(scene);
    ctx.grains = initial_grains::<D>(scene)?;
    let diameter = ctx.grains.diameter.clone();
    ctx.plan_for(&diameter).map_err(|e| e.to_string())?;
    let mut k = 0;
    while k < ctx.stages.len() && !ctx.stages[k].1.is_dem() {
        hard_stage(&mut ctx, k).map_err(|e| e.to_string())?;
        k += 1;
    }
    let plan = ctx.plan.take().expect("built above");
    Ok((ctx.grains, plan, k))
}
