//! Running a scene: from the scene file to a typed system (one monomorphized kernel per
//! combination of dimension and law features), then the protocol steps with the equilibrium
//! criteria (AR07 §III, GRC07 §II.D, GRC08 §II.D.1), blow-up detection and snapshots.
//!
//! [`setup`] builds the grains and the system, [`stages`] runs the protocol as the
//! [`crate::plan`] resolves it, [`checks`] measures equilibrium and detects
//! blow-ups, [`relax`] and [`quench`] are the optional final phases of a stage (GRC07 damping,
//! AR07's velocity quench), [`output`] writes snapshots, [`report`] holds what a run reports,
//! [`options`] how it is driven, [`checkpoint`] the resumable state on disk, [`layout`] the
//! names of the files a run writes.

pub mod checkpoint;
pub(crate) mod checks;
pub(crate) mod fire;
pub(crate) mod grains;
pub mod layout;
pub(crate) mod options;
pub(crate) mod output;
pub(crate) mod particles_file;
pub(crate) mod quench;
pub(crate) mod reference;
pub(crate) mod relax;
pub(crate) mod report;
pub(crate) mod setup;
pub(crate) mod stages;

pub use crate::contact::from_scene::{
    adhesion, dmt_law, hertz_mindlin_law, linear_law, rolling_spring, sjkr_law,
};
pub use fire::FireStats;
pub use grains::Grains;
pub use options::{CheckpointSpec, DumpSpec, RunOptions, StageEndHook};
pub use output::snapshot_of;
pub use quench::Quenched;
pub use relax::Relaxation;
pub use report::{AtThreshold, Checks, Outcome, Progress, RunError, StepEnd, StepReport};
pub use setup::{build_system, cell_mass, initial_grains, system_of, time_step};
pub use stages::{compress_until, prepared_grains, run_protocol};

use crate::contact::from_scene::{with_law, WithLaw};
use crate::contact::ContactLaw;
use crate::geometry::{Dim, D2, D3};
use crate::scene::{Mu, Scene, Step};
use crate::snapshot::Snapshot;
use crate::system::System;
use checkpoint::Header;
use stages::{hard_stage, run_stages, write_checkpoint, Ctx, Payload, PayloadRef};

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

/// The plan of a validated scene: its protocol resolved for its initial grains (the hard-grain
/// stages change neither the diameters nor, so, the time step).
pub fn plan_of(scene: &Scene) -> Result<crate::plan::Plan, String> {
    let diameter = match scene.dimension {
        2 => initial_grains::<D2>(scene)?.diameter,
        _ => initial_grains::<D3>(scene)?.diameter,
    };
    crate::plan::Plan::new(scene, &diameter)
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
            ctx.neighbor_builds = h.neighbor_builds;
            // The last stage entered: this one inside it, the one before at its start.
            ctx.current = if h.inside { Some(k) } else { k.checked_sub(1) };
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
    if inside.is_none() {
        // Inside a stage, the grains (and so the plan) come with the checkpoint's state.
        let diameter = ctx.grains.diameter.clone();
        ctx.plan_for(&diameter)?;
    }
    let mut snapshot = None;
    let mut interrupted = false;
    while k < ctx.stages.len() {
        let step = ctx.stages[k].1.clone();
        if !step.is_dem() {
            if let Some(spec) = &opts.checkpoint {
                let h = ctx.header(k, false, ctx.grains.time, ctx.grains.step, 0.0);
                let payload = PayloadRef::<D, ()>::AtStart(&ctx.grains);
                write_checkpoint(&ctx, spec, &h, &payload)?;
            }
            hard_stage(&mut ctx, k)?;
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
    let status = StepEnd::of_run(interrupted, &ctx.reports);
    debug_assert_eq!(status.as_str(), snapshot.status);
    Ok(Outcome {
        status,
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

/// Runs the DEM stages `range` with the scene's law at friction `mu`, typed by
/// [`with_law`].
fn dispatch_law<D: Dim>(
    ctx: &mut Ctx<D>,
    mu: Mu,
    range: std::ops::Range<usize>,
    inside: Option<(Header, Vec<u8>)>,
    opts: &mut RunOptions,
) -> Result<(Snapshot, bool), RunError> {
    let law = ctx.scene.law.clone();
    let run = RunLaw {
        ctx,
        range,
        inside,
        opts,
    };
    with_law(&law, mu, run)
}

/// [`run_law`]'s arguments other than the law, waiting for its type.
struct RunLaw<'c, 's, 'o, 'h, D: Dim> {
    ctx: &'c mut Ctx<'s, D>,
    range: std::ops::Range<usize>,
    inside: Option<(Header, Vec<u8>)>,
    opts: &'o mut RunOptions<'h>,
}

impl<D: Dim> WithLaw<D> for RunLaw<'_, '_, '_, '_, D> {
    type Output = Result<(Snapshot, bool), RunError>;
    fn with<L: ContactLaw<D>>(self, law: L) -> Self::Output {
        run_law(self.ctx, law, self.range, self.inside, self.opts)
    }
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
            Payload::Inside(st, watch) => {
                let sys = System::from_state(law, st);
                ctx.plan_for_system(&sys)?;
                (
                    sys,
                    Some((h.stage_time0, h.stage_steps0, h.stage_wall, watch)),
                )
            }
            Payload::AtStart(_) => {
                return Err(ctx.setup_error("checkpoint payload does not match its header".into()))
            }
        },
        None => {
            let mut sys = system_of(scene, law, &ctx.grains).map_err(|e| ctx.setup_error(e))?;
            // The first half kick uses forces of the first stage's κ (the run's start, or a
            // μ change; docs/exchange-format.md), the law kept as the base the stages scale.
            // An empty range (a protocol that ended with hard-grain stages) keeps the law's κ.
            let factor = range.clone().next().map_or(1.0, |k| {
                ctx.plan().steps[k].dem().expect("a DEM stage").kappa_factor
            });
            sys.law = law.with_kappa_scaled(factor);
            sys.init_forces();
            sys.law = law;
            (sys, None)
        }
    };
    debug_assert!(resume_at.is_some() || sys.dt == ctx.plan().dt);
    ctx.dt = sys.dt;
    ctx.k_max = ctx.plan().k_max;
    ctx.law = sys.law.describe();
    let builds0 = sys.nlist.builds;
    let stopped = {
        let _awake = crate::parallel::KeepAwake::new();
        run_stages(ctx, &mut sys, range, resume_at, opts)
    }?;
    ctx.neighbor_builds += sys.nlist.builds - builds0;
    ctx.at_threshold = ctx.contacts_at_threshold(&sys);
    let status = StepEnd::of_run(stopped, &ctx.reports);
    sys.shed_step_buffers();
    let snap = snapshot_of(&sys, ctx.plan(), status.as_str(), ctx.pressure());
    ctx.grains = Grains {
        l: sys.cell.l,
        s: sys.s.clone(),
        u: sys.u.clone(),
        // A μ change starts with the grains' spins at zero (docs/exchange-format.md).
        w: Vec::new(),
        diameter: sys.radius.iter().map(|r| 2.0 * r).collect(),
        time: sys.time,
        step: sys.step,
    };
    Ok((snap, stopped))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::slider::Coulomb;
    use std::path::Path;

    /// A small dense 3D packing with springs (μ = 0.3), compressed fast.
    fn dense_3d() -> (
        Scene,
        System<D3, crate::contact::hertz_mindlin::HertzMindlin<Coulomb>>,
    ) {
        let text = r#"
name = "shed"
dimension = 3
seed = 3
[particles]
count = 200
[law]
kind = "hertz-mindlin"
kappa = 39000.0
mu = 0.3
zeta = 0.98
[initial]
packing_fraction = 0.3
[numerics]
cell_mass = 0.01
[[protocol]]
kind = "compress"
pressure = 1.0
inertia_cap = 0.1
max_time = 5.0
"#;
        let scene = Scene::from_toml(text, Path::new("shed.toml")).unwrap();
        let law = hertz_mindlin_law(&scene.law, Coulomb { mu: 0.3 });
        let sys = compress_until::<D3, _>(&scene, law, 0.55).unwrap();
        (scene, sys)
    }

    /// Shedding the step buffers before the final snapshot (for the peak memory) leaves
    /// the interactions and everything the snapshot reads as they were.
    #[test]
    fn shedding_the_step_buffers_keeps_the_snapshot() {
        let (scene, mut sys) = dense_3d();
        let diameter: Vec<f64> = sys.radius.iter().map(|r| 2.0 * r).collect();
        let plan = crate::plan::Plan::new(&scene, &diameter).unwrap();
        let before = snapshot_of(&sys, &plan, "time-limit", Some(1.0));
        assert!(before.contacts.len() > sys.len(), "a dense packing");
        sys.shed_step_buffers();
        let after = snapshot_of(&sys, &plan, "time-limit", Some(1.0));
        assert!(
            before == after,
            "the snapshot changed when the step buffers were shed"
        );
    }

    #[test]
    #[should_panic(expected = "shed_step_buffers")]
    fn a_shed_system_is_not_stepped() {
        let (_, mut sys) = dense_3d();
        sys.shed_step_buffers();
        sys.step();
    }

    /// A protocol of hard-grain stages only ends with a snapshot of the law's contacts (found
    /// by tests/fuzz.rs: the first forces of that snapshot once looked up a stage past the end).
    #[test]
    fn a_protocol_of_hard_grain_stages_only_ends_with_a_snapshot() {
        let text = r#"
name = "hard-only"
dimension = 3
seed = 1
[particles]
count = 32
[initial]
arrangement = "fcc"
packing_fraction = 0.45
[law]
kind = "hertz-mindlin"
kappa = 39000.0
mu = 0.3
zeta = 0.98
[[protocol]]
kind = "hard-sphere-mix"
collisions_per_grain = 5.0
[[protocol]]
kind = "expand"
factor = 1.005
"#;
        let scene = Scene::from_toml(text, Path::new("hard-only.toml")).unwrap();
        let out = run_scene(&scene, &mut RunOptions::default()).unwrap();
        assert_eq!(out.snapshot.particles.radius.len(), 32);
        assert!(out.steps.iter().all(|r| r.end.ok()));
        // A gas at Φ = 0.45 / 1.005³ after hard-sphere collisions: no grain overlaps another.
        assert!(out.snapshot.contacts.is_empty());
    }
}
