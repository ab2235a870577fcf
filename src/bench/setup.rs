//! What `bench` runs: the scene cut to a fixed number of steps, or started from a snapshot.

use anyhow::{bail, Result};
use grainbench_comparisons::xcode::decks::Start;
use grainbench_engine::geometry::{D2, D3};
use grainbench_engine::run::initial_grains;
use grainbench_engine::scene::{Criteria, Scene, Step};
use serde::Serialize;
use std::path::Path;

/// How the runs stop.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "mode")]
pub enum Mode {
    /// The full protocol with its equilibrium criteria.
    Equilibrium,
    /// `steps` MD steps of the first DEM stage, criteria off.
    Steps { steps: u64 },
}

impl Mode {
    pub fn describe(&self) -> String {
        match self {
            Mode::Equilibrium => "to equilibrium (full protocol, equilibrium criteria)".into(),
            Mode::Steps { steps } => format!(
                "fixed steps: {steps} MD steps of the first DEM stage, criteria evaluated but never met"
            ),
        }
    }
}

/// The scene cut to its hard-grain prelude and first DEM stage, run for exactly `steps` steps
/// (criteria that never hold, still evaluated every check period), and its common start.
/// `steps` is rounded up to a multiple of the check period (LIGGGHTS and our engine run whole
/// check periods).
pub fn fixed_steps(scene: &Scene, steps: u64) -> Result<(Scene, Start, u64)> {
    let stages = scene.stages();
    let Some(k) = stages.iter().position(|(_, s)| s.is_dem()) else {
        bail!(
            "scene {}: --steps needs a DEM stage (compress, fixed-volume, …) in [[protocol]]",
            scene.name
        );
    };
    let every = scene.numerics.check_every.max(1);
    let steps = steps.div_ceil(every) * every;
    // Never met: positive (the scene validator wants that) and far below any measure; judged
    // at each check, since a window longer than the S steps would not validate.
    let never = Criteria {
        force: 1e-200,
        moment: 1e-200,
        pressure: 1e-200,
        kinetic: 1e-200,
        window: 0.0,
        quench: false,
        ..stages[k].1.criteria()
    };
    let mut stage = stages[k].1.clone();
    match &mut stage {
        // Throughput of the paper's law: no damped final phase either.
        Step::Compress {
            criteria, relax, ..
        } => {
            *criteria = never;
            *relax = None;
        }
        Step::FixedVolume {
            criteria,
            full_time,
            relax,
            ..
        } => {
            *criteria = never;
            *full_time = true;
            *relax = None;
        }
        // A fixed cell for S steps: no cluster count to stop on.
        Step::Aggregate {
            max_time,
            mu,
            kappa,
        } => {
            stage = Step::FixedVolume {
                max_time: *max_time,
                criteria: never,
                full_time: true,
                mu: *mu,
                kappa: *kappa,
                relax: None,
            }
        }
        other => unreachable!("stages() unrolls {}", other.kind()),
    }
    let mut cut = scene.clone();
    cut.protocol = stages[..k].iter().map(|(_, s)| s.clone()).collect();
    cut.protocol.push(stage);
    let start = Start::of(&cut).map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
    let dt = start.stages[0].dt;
    // Half a step below S·dt: the time after S steps passes it whatever the rounding.
    let max_time = (steps as f64 - 0.5) * dt;
    match cut.protocol.last_mut() {
        Some(Step::Compress { max_time: t, .. } | Step::FixedVolume { max_time: t, .. }) => {
            *t = max_time
        }
        _ => unreachable!(),
    }
    let start = start
        .with_scene(cut.clone())
        .map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
    debug_assert_eq!(start.stages[0].max_steps, steps);
    Ok((cut, start, steps))
}

/// The scene started from the grains of `snap` (at rest) without its hard-grain prelude.
pub fn from_snapshot(scene: &Scene, snap: &Path) -> Result<Scene> {
    if !snap.is_file() {
        bail!(
            "--start {}: no such snapshot file (give a final.snap.json written by `grainbench run` or `analyze --write`)",
            snap.display()
        );
    }
    let mut s = scene.clone();
    s.initial.snapshot = Some(std::path::absolute(snap)?);
    s.protocol = scene
        .stages()
        .into_iter()
        .map(|(_, st)| st)
        .skip_while(|st| !st.is_dem())
        .collect();
    if s.protocol.is_empty() {
        bail!(
            "scene {}: --start needs a DEM stage in [[protocol]]",
            scene.name
        );
    }
    // Read it now: a wrong file or grain count is an error before any run.
    let read = match s.dimension {
        2 => initial_grains::<D2>(&s).map(|_| ()),
        _ => initial_grains::<D3>(&s).map(|_| ()),
    };
    read.map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_steps_cuts_to_the_first_dem_stage_and_rounds_up() {
        let scene = crate::common::load_scene("xcode-smoke").unwrap();
        let (cut, start, steps) = fixed_steps(&scene, 250).unwrap();
        assert_eq!(steps, 400);
        assert_eq!(start.stages.len(), 1);
        assert_eq!(start.stages[0].max_steps, 400);
        assert_eq!(cut.protocol.len(), 2);
        let text = toml::to_string(&cut).unwrap();
        let back = Scene::from_toml(&text, Path::new("x.toml")).unwrap();
        assert_eq!(back, cut);
    }

    #[test]
    fn fixed_steps_of_a_scene_with_a_criteria_window_reads_back() {
        // GRC07 scenes judge their criteria over 2 T0, longer than a short bench run.
        let scene = crate::common::load_scene("grc07-type1-phi052-mu05-rr").unwrap();
        let (cut, _, _) = fixed_steps(&scene, 200).unwrap();
        let text = toml::to_string(&cut).unwrap();
        let back = Scene::from_toml(&text, Path::new("x.toml")).unwrap();
        assert_eq!(back, cut);
    }
}
