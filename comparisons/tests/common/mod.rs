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
