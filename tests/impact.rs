//! The two-sphere impact tests of the DEM validation literature from the command line (issue
//! 19): `run --trace-every` on the explicit-particle scenes `impact-normal` and
//! `impact-oblique`, against Hertz's elastic impact and the impulse balance of an impact that
//! slides throughout.

use assert_cmd::Command;
use serde_json::Value;

fn impact(scene: &str) -> (Value, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    Command::cargo_bin("grainbench")
        .unwrap()
        .args([
            "run",
            scene,
            "-j",
            "1",
            "--quiet",
            "--trace-every",
            "1e-9",
            "-o",
        ])
        .arg(dir.path())
        .assert()
        .success();
    let v =
        serde_json::from_slice(&std::fs::read(dir.path().join("impact.json")).unwrap()).unwrap();
    (v, dir)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn normal_impact_matches_hertz() {
    let (r, dir) = impact("impact-normal");
    let (m, h) = (&r["measured"], &r["hertz"]);
    // ζ = 0: the energy comes back to O(dt²).
    assert!((f(&m["restitution_normal"]) - 1.0).abs() < 1e-4, "{m}");
    let peak = f(&m["peak_normal_force"]) / f(&h["peak_normal_force"]);
    assert!((peak - 1.0).abs() < 5e-3, "peak force ratio {peak}");
    // The frames (every step) bracket the contact: one time step is 0.94 % of it.
    let dur = f(&m["duration"]) / f(&h["duration"]);
    assert!((dur - 1.0).abs() < 0.01, "duration ratio {dur}");
    assert!(f(&m["rebound_angle"]).abs() < 1e-6);
    let contacts = std::fs::read_to_string(dir.path().join("trace-contacts.csv")).unwrap();
    assert!(contacts.starts_with("t,i,j,gap,fn,ft_x,ft_y,ft_z\n"));
    assert!(contacts.lines().count() > 100, "a row per step in contact");
    let grains = std::fs::read_to_string(dir.path().join("trace-grains.csv")).unwrap();
    assert!(grains.starts_with("t,id,x,y,z,vx,vy,vz,wx,wy,wz\n"));
}

#[test]
fn oblique_impact_slides_throughout_as_the_impulses_say() {
    let (r, _dir) = impact("impact-oblique");
    let (m, s) = (&r["measured"], &r["sliding"]);
    assert!((f(&m["incidence_angle"]) - 5f64.atan().to_degrees()).abs() < 0.01);
    // Tangential impulse μ J_n: the contact-point speed and each spin from it, to the
    // rotation of the line of centres during the contact (~0.4 %).
    let vt = f(&m["tangential_speed_after"]) / f(&s["tangential_speed_after"]);
    assert!((vt - 1.0).abs() < 0.01, "tangential speed ratio {vt}");
    for k in 0..2 {
        let w = f(&m["spin_after"][k][2]).abs() / f(&s["spin_gained"][k]);
        assert!((w - 1.0).abs() < 0.01, "spin ratio {w}");
    }
    assert!((f(&m["restitution_normal"]) - 1.0).abs() < 2e-3, "{m}");
    let peak = f(&m["peak_normal_force"]) / f(&r["hertz"]["peak_normal_force"]);
    assert!((peak - 1.0).abs() < 0.01, "peak force ratio {peak}");
}

#[test]
fn a_trace_of_a_large_scene_is_refused() {
    Command::cargo_bin("grainbench")
        .unwrap()
        .args(["run", "ar07-A", "--trace-every", "0.1", "-o"])
        .arg(tempfile::tempdir().unwrap().path())
        .assert()
        .failure()
        .stderr(predicates::str::contains("few-body"));
}
