//! `grainbench plan SCENE`: what each stage of a scene will do, in absolute reduced units —
//! the engine's resolved plan, which every code's deck and the exchange format carry.

use crate::common::load_scene;
use anyhow::Result;
use grainbench_engine::plan::{HardStage, Plan, PlanStage, PlanStep, StageKind};
use grainbench_engine::scene::{Mu, Relax, RelaxMethod};

/// The arguments of `grainbench plan`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file or embedded scene name.
    pub scene: String,
    /// The plan as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `grainbench plan`.
pub fn command(a: Args) -> Result<i32> {
    plan_command(&a.scene, a.json)
}

/// `grainbench plan`.
fn plan_command(spec: &str, json: bool) -> Result<i32> {
    let scene = load_scene(spec)?;
    let plan = grainbench_engine::run::plan_of(&scene)
        .map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
    if json {
        println!("{}", serde_json::to_string_pretty(&plan)?);
    } else {
        print!("{}", text(&plan));
    }
    Ok(0)
}

fn mu(m: Mu) -> String {
    match m {
        Mu::Finite(x) => format!("{x}"),
        Mu::Infinite => "∞".into(),
    }
}

/// The plan as text: one block per stage.
pub fn text(plan: &Plan) -> String {
    let unit = if plan.cohesive {
        "F0 (time T0)"
    } else {
        "P_ref a^(d-1)"
    };
    let mut out = format!(
        "plan of scene `{}` ({}D; force unit {unit}): law μ = {}, κ = {}, dt = {:.4e} (K_max = {:.4e} at N = {:.4e}, dt_fraction = {})\n",
        plan.scene,
        plan.dimension,
        mu(plan.mu),
        plan.kappa,
        plan.dt,
        plan.k_max,
        plan.stiffness_force,
        plan.dt_fraction
    );
    for (k, step) in plan.steps.iter().enumerate() {
        out += &format!("\n{}. {}\n", k + 1, step.name());
        match step {
            PlanStep::Hard(h) => out += &format!("   {}\n", hard(h)),
            PlanStep::Dem(s) => out += &dem(s),
        }
    }
    out
}

fn hard(h: &HardStage) -> String {
    match *h {
        HardStage::Expand { factor } => format!("cell lengths × {factor} (hard grains)"),
        HardStage::HardSphereMix {
            collisions_per_grain,
        } => format!("event-driven hard grains, {collisions_per_grain} collisions per grain"),
        HardStage::Grow {
            packing_fraction,
            rate,
        } => format!("Lubachevsky–Stillinger growth to Φ = {packing_fraction} at rate {rate}"),
    }
}

fn dem(s: &PlanStage) -> String {
    let cell = match s.kind {
        StageKind::Compress { pressure } => format!(
            "stress control to P = {pressure}, strain rate ≤ {:.4e}{}",
            s.max_strain_rate,
            s.servo_gain
                .map_or(String::new(), |g| format!(", servo gain {g}"))
        ),
        StageKind::FixedVolume { full_time: true } => "fixed cell, runs its full time".into(),
        StageKind::FixedVolume { full_time: false } => "fixed cell".into(),
        StageKind::Aggregate => "fixed cell until one cluster".into(),
    };
    let t = &s.tolerances;
    let mut out = format!(
        "   cell:      {cell}\n   law:       μ = {}, μ_r = {}, κ = {} (× {} of the law's)\n   time:      dt = {:.4e} (K_max = {:.4e}), max time {} = {} steps, checks every {} steps\n   criteria:  force {:.3e}, moment {:.3e}, stress {:.3e}, kinetic/grain {:.3e} (force scale {}){}{}\n",
        mu(s.mu),
        s.mu_r.map_or("∞ (no rolling resistance)".into(), |m| format!("{m}")),
        s.kappa,
        s.kappa_factor,
        s.dt,
        s.k_max,
        s.max_time,
        s.max_steps,
        s.check_every,
        t.force,
        t.moment,
        t.stress,
        t.kinetic_per_grain,
        s.f_ref,
        if s.window > 0.0 { format!(", held for {}", s.window) } else { String::new() },
        if s.quench { ", velocities quenched when only the kinetic criterion fails" } else { "" },
    );
    if let Some(r) = &s.relax {
        out += &format!("   relax:     {}\n", relax(r));
    }
    out
}

/// A final relaxation in words: how, and when it starts.
fn relax(r: &Relax) -> String {
    let how = match r.method {
        RelaxMethod::Fire => "FIRE on the grains and the cell".to_string(),
        RelaxMethod::Damping if r.tangential_zeta > 0.0 => format!(
            "background damping {} with tangential and rolling dashpots ζ_t = {}",
            r.damping, r.tangential_zeta
        ),
        RelaxMethod::Damping => format!("background damping {}", r.damping),
    };
    let mut when = format!(
        "once the interaction list has held for {} (at rest to {} × the criteria",
        r.settle_time, r.settle_factor
    );
    if r.free_rollers {
        when += ", free rollers left out";
    }
    if r.mean_stress {
        when += ", the stress judged on its mean over that time";
    }
    format!("{how}, {when})")
}
