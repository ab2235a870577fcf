//! Shared by the two-particle deck tests.

use grainbench_comparisons::xcode::Code;

/// Is `code` installed? Missing: a skip notice, or a failure when `CI` is set (CI installs
/// all three with ci/install-externals.sh).
pub fn present(code: Code) -> bool {
    if code.find().is_some() {
        return true;
    }
    if std::env::var_os("CI").is_some() {
        panic!(
            "{} is not installed (CI is set): {}",
            code.name(),
            code.install_hint()
        );
    }
    eprintln!("skipping: {}", code.not_found());
    false
}

/// Relative difference |a − b|/|b|.
#[allow(dead_code)] // not every test file uses it
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The plan of a hand-made start: `scene`'s, with `stages` as its DEM stages (the two-particle
/// tests run a fixed cell for a given number of steps of a given time step).
#[allow(dead_code)] // not every test file uses it
pub fn plan(
    scene: &grainbench_engine::scene::Scene,
    stages: &[grainbench_engine::plan::PlanStage],
) -> grainbench_engine::plan::Plan {
    use grainbench_engine::plan::{Plan, PlanStep};
    let mut plan = Plan::new(scene, &[1.0]).expect("plan");
    plan.steps = stages.iter().map(|s| PlanStep::Dem(*s)).collect();
    plan
}
