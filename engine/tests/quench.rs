//! `criteria.quench` (AR07 §III.A, engine/src/run/quench.rs) on the cross-code smoke scene
//! (N = 256, μ = 0.3, κ = 1e4): the velocities are zeroed where only the kinetic criterion
//! fails, the packing does not regain kinetic energy, and nothing in it moves.

use grainbench_engine::library::SCENES;
use grainbench_engine::run::{run_scene, RunOptions, StepEnd};
use grainbench_engine::Scene;
use std::path::Path;

fn smoke(criteria: &str, max_time: &str) -> Scene {
    let text = SCENES.iter().find(|(n, _)| *n == "xcode-smoke").unwrap().1;
    let text = text
        .replace(
            "criteria = { preset = \"ar07\" }",
            &format!("criteria = {criteria}"),
        )
        .replace("max_time = 3000.0", &format!("max_time = {max_time}"));
    Scene::from_toml(&text, Path::new("xcode-smoke.toml")).unwrap()
}

#[test]
fn a_quench_ends_the_stage_without_changing_the_packing() {
    let quenched = run_scene(
        &smoke("{ preset = \"ar07\", quench = true }", "3000.0"),
        &mut RunOptions::default(),
    )
    .unwrap();
    let stage = quenched.steps.last().unwrap();
    assert_eq!(stage.end, StepEnd::Equilibrium);
    let q = stage.quench.as_ref().expect("the stage quenched");
    assert!(q.count >= 1);
    // What was removed was above the kinetic criterion (1e-8 P a³ per grain, P = 1)...
    assert!(q.kinetic_removed_per_grain > 1e-8, "{q:?}");
    // ...and carried by motions that change nothing in the packing.
    assert_eq!((q.pairs_gained, q.pairs_lost), (0, 0), "{q:?}");
    assert!(q.delta_phi.abs() < 1e-6, "{q:?}");
    assert!(q.max_displacement < 1e-3, "{q:?}");

    // The same run without the quench, stopped one time unit after the first quench: it has
    // not met the criteria (the quench is what ended the stage), and until the quench both
    // runs are the same, so its Φ is the quenched run's.
    let plain = run_scene(
        &smoke("{ preset = \"ar07\" }", &format!("{}", q.first_time + 1.0)),
        &mut RunOptions::default(),
    )
    .unwrap();
    let p = plain.steps.last().unwrap();
    assert_eq!(p.end, StepEnd::TimeLimit);
    assert!(p.quench.is_none());
    assert!(p.checks.kinetic_ratio >= 1.0, "{:?}", p.checks);
    assert!(
        (p.checks.packing_fraction - stage.checks.packing_fraction).abs() < 1e-6,
        "{} against {}",
        p.checks.packing_fraction,
        stage.checks.packing_fraction
    );
}
