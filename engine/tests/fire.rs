//! FIRE as the final relaxation of a frictionless stage (`relax.method = "fire"`,
//! engine/src/run/fire.rs) on `ar07-frictionless-small` (N = 500, μ = 0, κ = 1e4): the stage
//! ends on the AR07 criteria in fewer steps than the law's own dynamics, at the packing
//! fraction of that dynamics (AR07 §III.A: frictionless equilibria are
//! enthalpy minima, reached by any descent).

use grainbench_engine::library::SCENES;
use grainbench_engine::run::{run_scene, RunOptions, StepEnd};
use grainbench_engine::Scene;
use std::path::Path;

fn small_text() -> &'static str {
    SCENES
        .iter()
        .find(|(n, _)| *n == "ar07-frictionless-small")
        .unwrap()
        .1
}

fn small(relax: &str) -> Scene {
    let text = small_text();
    let criteria = "criteria = { preset = \"ar07\" }";
    assert!(text.contains(criteria));
    let text = text.replace(criteria, &format!("{criteria}\n{relax}"));
    Scene::from_toml(&text, Path::new("ar07-frictionless-small.toml")).unwrap()
}

#[test]
fn fire_reaches_the_criteria_sooner_at_the_same_packing() {
    let md = run_scene(&small(""), &mut RunOptions::default()).unwrap();
    let fire = run_scene(
        &small("relax = { method = \"fire\", settle_time = 0.0, settle_factor = 1e3 }"),
        &mut RunOptions::default(),
    )
    .unwrap();
    let (m, f) = (md.steps.last().unwrap(), fire.steps.last().unwrap());
    assert_eq!(m.end, StepEnd::Equilibrium);
    assert_eq!(f.end, StepEnd::Equilibrium);
    assert!(m.relaxation.is_none());
    let r = f.relaxation.as_ref().expect("the FIRE phase started");
    let stats = r.fire.as_ref().expect("FIRE's report");
    // FIRE ran, zeroed the velocities where the power turned negative, and lengthened its
    // step (up to its cap of 10× the stage's).
    assert!(stats.steps > 0 && stats.resets >= 1, "{stats:?}");
    assert!(
        stats.peak_dt > 2.0 && stats.peak_dt <= 10.0 + 1e-12,
        "{stats:?}"
    );
    assert_eq!(r.damping, 0.0);
    // Both runs are the same up to the switch; from there the law's dynamics needs many
    // times FIRE's steps to the criteria (14× when this was written).
    let before = f.steps - stats.steps;
    assert!(
        4 * stats.steps < m.steps - before,
        "from the switch: FIRE {} steps against {} without",
        stats.steps,
        m.steps - before
    );
    // Same state as the law's own dynamics to well within the seed-to-seed spread of such
    // packings (AR07 T.IV: Φ ± 0.0015 over samples of 4000).
    let (pm, pf) = (m.checks.packing_fraction, f.checks.packing_fraction);
    assert!((pm - pf).abs() < 2e-3, "Φ {pf} with FIRE, {pm} without");
    assert!((f.checks.pressure - 1.0).abs() < 1e-4, "{:?}", f.checks);
}

#[test]
fn fire_is_refused_with_friction_or_damping_settings() {
    let text = small_text();
    let fire = "criteria = { preset = \"ar07\" }\nrelax = { method = \"fire\", settle_time = 0.0 }";
    let with = |law: &str, relax: &str| {
        let t = text
            .replace("criteria = { preset = \"ar07\" }", relax)
            .replace("mu = 0.0", law);
        Scene::from_toml(&t, Path::new("s.toml"))
    };
    let e = with("mu = 0.3", fire).unwrap_err();
    assert_eq!(e.field, "protocol[0].relax.method", "{e}");
    assert!(e.to_string().contains("frictionless"), "{e}");
    let e = with(
        "mu = 0.0",
        &fire.replace("settle_time = 0.0", "settle_time = 0.0, damping = 1.0"),
    )
    .unwrap_err();
    assert_eq!(e.field, "protocol[0].relax.method", "{e}");
    assert!(with("mu = 0.0", fire).is_ok());
}
