//! Speed against error: a time step past stability stops with the instability error (exit
//! status 4, a message naming the time step) instead of a packing, and `grainbench accuracy`
//! tables a tiny sweep with its unstable point flagged.

use assert_cmd::Command;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn grainbench() -> Command {
    Command::cargo_bin("grainbench").unwrap()
}

/// xcode-smoke (n = 256 Hertz–Mindlin spheres, κ = 1e4, μ = 0.3) with another time step.
fn smoke_with_dt(dir: &Path, dt_fraction: f64) -> PathBuf {
    let text = grainbench_engine::library::scene_text("xcode-smoke").unwrap();
    let text = format!("{text}\n[numerics]\ndt_fraction = {dt_fraction}\n");
    let p = dir.join(format!("smoke-dt{dt_fraction}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

/// Runs a scene whose time step is past stability and checks that it ends as unstable.
fn assert_unstable(dt_fraction: f64, cause: &str) {
    let dir = tempfile::tempdir().unwrap();
    let scene = smoke_with_dt(dir.path(), dt_fraction);
    let out = dir.path().join("out");
    let a = grainbench()
        .args(["run", "-q", "-j", "1"])
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .timeout(std::time::Duration::from_secs(60))
        .assert()
        .code(4);
    let stderr = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(stderr.contains("unstable at step"), "{stderr}");
    assert!(stderr.contains(cause), "{stderr}");
    assert!(stderr.contains("the time step dt ="), "{stderr}");
    assert!(
        stderr.contains(&format!("numerics.dt_fraction = {dt_fraction}")),
        "{stderr}"
    );
    assert!(
        !out.join("final.snap.json").exists(),
        "an unstable run must not write a packing"
    );
    assert!(out.join("last-good.snap.json").exists());
}

/// dt = 0.5 of the contact duration: an overlap blows past numerics.max_overlap.
#[test]
fn time_step_far_past_stability_stops_on_the_overlap_check() {
    assert_unstable(0.5, "times the smaller radius");
}

/// dt = 0.16: nothing blows up, the contacts oscillate at the Nyquist frequency for ever
/// (before the step-correlation check, this ran to its time limit and wrote a packing with
/// Φ = 0.624 instead of ≈ 0.60). The check stops it within a few checks.
#[test]
fn time_step_just_past_stability_stops_on_the_step_correlation_check() {
    assert_unstable(0.16, "reverse at every time step");
}

#[test]
fn accuracy_sweep_tables_points_errors_and_the_unstable_point() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("acc");
    grainbench()
        .args([
            "accuracy",
            "xcode-smoke",
            "--knobs",
            "dt",
            "--dt",
            "0.02,0.04,0.5,1.0",
            "--seeds",
            "1",
            "--max-time",
            "20",
            "-j",
            "1",
            "-q",
            "-o",
        ])
        .arg(&out)
        .timeout(std::time::Duration::from_secs(120))
        .assert()
        .success();
    for f in ["accuracy.md", "accuracy.csv", "accuracy.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let doc: Value =
        serde_json::from_slice(&std::fs::read(out.join("accuracy.json")).unwrap()).unwrap();
    let rows = doc["rows"].as_array().unwrap();
    let dt_rows: Vec<&Value> = rows.iter().filter(|r| r["knob"] == "dt").collect();
    assert_eq!(dt_rows.len(), 4, "{rows:#?}");
    let by_value = |x: f64| {
        dt_rows
            .iter()
            .find(|r| (r["value"].as_f64().unwrap() - x).abs() < 1e-12)
            .copied()
            .unwrap_or_else(|| panic!("no row for dt {x}"))
    };
    // Stable points: every error present and ≥ 0; a Pareto flag on every row.
    for x in [0.02, 0.04] {
        let r = by_value(x);
        assert_eq!(r["stable"], true, "{r:#?}");
        for m in ["phi", "z_star", "x0", "ks"] {
            let e = r["errors"][m]
                .as_f64()
                .unwrap_or_else(|| panic!("{m}: {r:#?}"));
            assert!(e >= 0.0 && e.is_finite(), "{m} = {e}");
        }
        assert!(r["wall_seconds"].as_f64().unwrap() > 0.0);
    }
    // The reference is the smallest dt: its own errors vanish (KS against itself too).
    assert_eq!(by_value(0.02)["errors"]["phi"].as_f64(), Some(0.0));
    assert_eq!(by_value(0.02)["errors"]["ks"].as_f64(), Some(0.0));
    // Past stability: flagged, no error value.
    let u = by_value(0.5);
    assert!(
        u["status"].as_str().unwrap().starts_with("unstable: "),
        "{u:#?}"
    );
    assert!(u["status"].as_str().unwrap().contains("dt_fraction = 0.5"));
    assert_eq!(u["stable"], false);
    assert!(u["errors"].as_object().unwrap().is_empty());
    assert_eq!(u["pareto"], false);
    // Refused by the scene validation (dt_fraction ≤ 0.5): flagged, not run.
    let v = by_value(1.0);
    assert!(
        v["status"].as_str().unwrap().starts_with("invalid: "),
        "{v:#?}"
    );
    assert!(v["status"]
        .as_str()
        .unwrap()
        .contains("numerics.dt_fraction"));
    assert!(rows.iter().all(|r| r["pareto"].is_boolean()));
    assert!(rows.iter().any(|r| r["pareto"] == true));
    let md = std::fs::read_to_string(out.join("accuracy.md")).unwrap();
    assert!(md.contains("unstable: "), "{md}");
    let csv = std::fs::read_to_string(out.join("accuracy.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + rows.len());
    // The KS error of dt 0.04 is positive: its plot exists.
    assert!(out.join("accuracy-ks.svg").is_file());
    assert!(out.join("accuracy-ks.png").is_file());
    // A second run reuses the finished points.
    grainbench()
        .args([
            "accuracy",
            "xcode-smoke",
            "--knobs",
            "dt",
            "--dt",
            "0.02,0.04,0.5,1.0",
            "--seeds",
            "1",
            "--max-time",
            "20",
            "-q",
            "-o",
        ])
        .arg(&out)
        .timeout(std::time::Duration::from_secs(20))
        .assert()
        .success();
}
