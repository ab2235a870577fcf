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

/// A fixed-cell DEM stage of `steps` steps of `dt` (the two-particle tests run one), checked
/// every `check_every` steps against `tolerances`.
#[allow(dead_code)] // not every test file uses it
pub fn fixed_stage(
    full_time: bool,
    mu: grainbench_engine::scene::Mu,
    kappa: f64,
    dt: f64,
    steps: u64,
    check_every: u64,
    tolerances: grainbench_engine::plan::Tolerances,
) -> grainbench_engine::plan::PlanStage {
    grainbench_engine::plan::PlanStage {
        kind: grainbench_engine::plan::StageKind::FixedVolume { full_time },
        max_strain_rate: 0.0,
        servo_gain: None,
        pressure: None,
        mu,
        mu_r: None,
        kappa,
        kappa_factor: 1.0,
        dt,
        k_max: f64::NAN,
        max_time: steps as f64 * dt,
        max_steps: steps,
        criteria: Default::default(),
        tolerances,
        f_ref: 1.0,
        window: 0.0,
        quench: false,
        check_every,
        max_overlap: 1.0,
        relax: None,
    }
}
