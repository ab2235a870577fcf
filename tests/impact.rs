//! The two-sphere impact tests of the DEM validation literature from the command line:
//! `run --trace-every` on the explicit-particle scenes `impact-normal` and
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

/// Every built-in code.
const EVERY_CODE: &str = "rust,lammps,lammps-2025,liggghts,yade";

/// `compare SCENE` in every code (into `<tempdir>/cmp`), which must pass: the directory, the
/// printed report and compare.json.
fn compare_in_every_code(scene: &str) -> (tempfile::TempDir, String, Value) {
    compare_in(scene, EVERY_CODE)
}

/// `compare SCENE --codes CODES`, as [`compare_in_every_code`].
fn compare_in(scene: &str, codes: &str) -> (tempfile::TempDir, String, Value) {
    let dir = tempfile::tempdir().unwrap();
    let run = Command::cargo_bin("grainbench")
        .unwrap()
        .args(["compare", scene, "--codes", codes, "-q", "-o"])
        .arg(dir.path().join("cmp"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&run.stdout).into_owned();
    println!("{text}");
    assert!(run.status.success(), "{text}");
    let cmp = serde_json::from_slice(&std::fs::read(dir.path().join("cmp/compare.json")).unwrap())
        .unwrap();
    (dir, text, cmp)
}

/// The codes that ran; under CI (CI=true) every code must be installed and run.
fn ran(cmp: &Value) -> Vec<&str> {
    let ran: Vec<&str> = cmp["codes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["outcome"] == "ran")
        .map(|c| c["code"].as_str().unwrap())
        .collect();
    if std::env::var_os("CI").is_some() {
        for code in EVERY_CODE.split(',') {
            assert!(ran.contains(&code), "every code must run under CI: {ran:?}");
        }
    }
    ran
}

/// The same impact in every installed code, read from its trace (`output.trace_every`):
/// `compare` checks each against Hertz and the sliding balance and fails otherwise. Under CI
/// (CI=true) every code must be installed and have measured an impact.
#[test]
fn oblique_impact_in_every_code_matches_the_analytic_values() {
    let (dir, text, cmp) = compare_in_every_code("impact-oblique");
    let out = dir.path().join("cmp");
    let ran = ran(&cmp);
    let impacts = cmp["impacts"].as_array().unwrap();
    assert_eq!(impacts.len(), ran.len(), "an impact per code that ran");
    for i in impacts {
        let m = &i["report"]["measured"];
        assert!(
            (f(&m["incidence_angle"]) - 5f64.atan().to_degrees()).abs() < 0.01,
            "{i}"
        );
        // Each code's trace was written as ours is.
        let code = i["code"].as_str().unwrap();
        assert!(out.join(code).join("trace-contacts.csv").exists(), "{code}");
    }
    assert!(text.contains("### Two-body impact"), "{text}");
}

/// Peak normal force of each pair in a `trace-contacts.csv`, by (i, j).
fn peaks(path: &std::path::Path) -> std::collections::BTreeMap<(usize, usize), f64> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (ci, cj, cn) = (col("i"), col("j"), col("fn"));
    let mut out = std::collections::BTreeMap::new();
    for l in lines {
        let v: Vec<&str> = l.split(',').collect();
        let key = (v[ci].parse().unwrap(), v[cj].parse().unwrap());
        let f: f64 = v[cn].parse().unwrap();
        let e = out.entry(key).or_insert(f64::NEG_INFINITY);
        *e = f.max(*e);
    }
    out
}

/// A few-body trace in every code: Newton's cradle of three Hertz spheres. Every
/// code's trace carries both contacts (LAMMPS and LIGGGHTS dump them each frame, YADE lists
/// them in trace.txt), with the peak force of each within 0.1 % of ours; our run conserves
/// momentum and energy (ζ = 0). Under CI every code must run.
#[test]
fn chain_impact_in_every_code_traces_both_contacts() {
    let (dir, text, cmp) = compare_in_every_code("impact-chain");
    let out = dir.path().join("cmp");
    let ran = ran(&cmp);
    let ours = peaks(&out.join("rust/trace-contacts.csv"));
    for pair in [(0, 1), (1, 2)] {
        assert!(ours[&pair] > 0.4, "{pair:?}: {ours:?}");
    }
    for code in &ran {
        let theirs = peaks(&out.join(code).join("trace-contacts.csv"));
        for pair in [(0, 1), (1, 2)] {
            let (a, b) = (ours[&pair], theirs.get(&pair).copied().unwrap_or(0.0));
            assert!(
                (b / a - 1.0).abs() < 1e-3,
                "{code} {pair:?}: {b} vs ours {a}"
            );
        }
    }
    // The same, as compare reports it: a pair table per code, checked against ours.
    let pairs = cmp["pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), ran.len(), "{cmp}");
    assert!(
        pairs
            .iter()
            .all(|c| c["pairs"].as_array().unwrap().len() == 2),
        "{cmp}"
    );
    assert!(
        text.contains("### Few-body contacts") && text.contains("| 1–2 peak force |"),
        "{text}"
    );
    // Ours: the last frame's velocities keep the momentum and the energy of the striker.
    let grains = std::fs::read_to_string(out.join("rust/trace-grains.csv")).unwrap();
    let last: Vec<Vec<f64>> = grains
        .lines()
        .rev()
        .take(3)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    // t,id,x,y,z,vx,…: vx is column 5; m = 1 each.
    let p: f64 = last.iter().map(|r| r[5]).sum();
    let e: f64 = last.iter().map(|r| 0.5 * r[5] * r[5]).sum();
    assert!((p - 0.01).abs() < 1e-9, "momentum {p}");
    assert!((e / 5e-5 - 1.0).abs() < 1e-3, "energy {e}");
}

/// Grains that start spinning (explicit-particle scenes): `impact-spin` hits head-on
/// two spheres spinning about z and y, so the contact points slip at 5 v_n. Every code (and
/// pydem, through the exchange format) starts from the scene's spins and ends with each spin
/// changed by the sliding impulse balance, μ J_n R/I = 0.015 — to 1e-3 here, as the line of
/// centres stays fixed. Under CI every built-in code must run.
#[test]
fn spinning_impact_in_every_code_changes_the_spins_by_the_impulse_balance() {
    let codes = format!("{EVERY_CODE},pydem=reference-inputs/adapters/pydem.toml");
    let (_dir, text, cmp) = compare_in("impact-spin", &codes);
    let ran = ran(&cmp);
    assert!(ran.contains(&"pydem"), "{ran:?}");
    let impacts = cmp["impacts"].as_array().unwrap();
    assert_eq!(impacts.len(), ran.len(), "an impact per code that ran");
    let spins_before = serde_json::json!([[0.0, 0.0, 0.08], [0.0, 0.06, 0.0]]);
    for i in impacts {
        let code = i["code"].as_str().unwrap();
        let m = &i["report"]["measured"];
        let before = &m["spin_before"];
        for (k, w) in spins_before.as_array().unwrap().iter().enumerate() {
            for a in 0..3 {
                let (got, want) = (f(&before[k][a]), f(&w[a]));
                assert!(
                    (got - want).abs() < 1e-12,
                    "{code}: spin {k} before {before}"
                );
            }
        }
        assert!(
            (f(&m["tangential_speed_before"]) - 0.05).abs() < 1e-9,
            "{code}: {m}"
        );
        for k in 0..2 {
            let after: Vec<f64> = (0..3).map(|a| f(&m["spin_after"][k][a])).collect();
            let before: Vec<f64> = (0..3).map(|a| f(&before[k][a])).collect();
            let dw = after
                .iter()
                .zip(&before)
                .map(|(x, y)| (x - y).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(
                (dw / 0.015 - 1.0).abs() < 1e-3,
                "{code}: spin {k} changed by {dw}"
            );
        }
        let vt = f(&m["tangential_speed_after"]) / 0.029;
        assert!((vt - 1.0).abs() < 1e-3, "{code}: v_t after ratio {vt}");
    }
    assert!(text.contains("| spin 1 gained |"), "{text}");
}
