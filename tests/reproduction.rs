//! The reduced (CI) versions of the paper states land in the bands of golden/ci-bands.toml,
//! through the `reproduce` command that makes the paper-size tables.

use assert_cmd::Command;
use grainbench_comparisons::report::paper::paper_values;
use serde_json::Value;

const BANDS: &str = include_str!("../golden/ci-bands.toml");

struct Band {
    metric: String,
    lo: f64,
    hi: f64,
}

/// The bands of one CI scene: paper ± (3 sd √(n_paper/n) + systematic), checked against the
/// published values file.
fn bands(scene: &str) -> (String, Vec<Band>) {
    let all: toml::Table = toml::from_str(BANDS).unwrap();
    let s = all[scene].as_table().unwrap();
    let state = s["paper_state"].as_str().unwrap().to_string();
    let ratio =
        (s["n_paper"].as_integer().unwrap() as f64 / s["n"].as_integer().unwrap() as f64).sqrt();
    let published = paper_values(&state).unwrap_or_else(|| panic!("no paper state {state}"));
    let mut out = Vec::new();
    for (metric, b) in s["bands"].as_table().unwrap() {
        let paper = b["paper"].as_float().unwrap();
        let sd = b.get("sd").and_then(|x| x.as_float()).unwrap_or(0.0);
        let pv = &published.values[metric];
        assert_eq!(
            paper, pv.value,
            "{scene}.{metric}: band and paper-values.toml disagree"
        );
        assert_eq!(
            Some(sd).filter(|s| *s > 0.0),
            pv.sd,
            "{scene}.{metric}: s.d. differs"
        );
        let allowance = 3.0 * sd * ratio + b["systematic"].as_float().unwrap();
        out.push(Band {
            metric: metric.clone(),
            lo: paper - allowance,
            hi: paper + allowance,
        });
    }
    (state, out)
}

fn check_ci_scene(scene: &str) {
    let (_, bands) = bands(scene);
    let name = scene.strip_suffix("-ci").unwrap();
    let (paper, state) = name.split_once('-').unwrap();
    let dir = tempfile::tempdir().unwrap();
    Command::cargo_bin("grainbench")
        .unwrap()
        .args(["reproduce", paper, "--state", state, "--ci", "--seeds", "1"])
        .args(["-q", "-j", "2", "-o"])
        .arg(dir.path())
        .assert()
        .success();
    let summary: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("seed-1/summary.json")).unwrap())
            .unwrap();
    assert_eq!(
        summary["status"], "equilibrium",
        "{scene} did not equilibrate"
    );
    let report: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("report.json")).unwrap()).unwrap();
    assert!(dir.path().join("pf.svg").exists() && dir.path().join("gr.png").exists());
    let mut failures = Vec::new();
    for b in &bands {
        let row = report["rows"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["metric"] == b.metric.as_str())
            .unwrap_or_else(|| panic!("{scene}: no row {}", b.metric));
        let ours = row["ours"]["mean"].as_f64().unwrap();
        eprintln!("{scene} {}: {ours} in [{}, {}]?", b.metric, b.lo, b.hi);
        if !(b.lo..=b.hi).contains(&ours) {
            failures.push(format!(
                "{} = {ours} outside [{}, {}]",
                b.metric, b.lo, b.hi
            ));
        }
    }
    assert!(failures.is_empty(), "{scene}: {}", failures.join("; "));
}

#[test]
fn ar07_a_ci_lands_in_its_bands() {
    check_ci_scene("ar07-A-ci");
}

#[test]
fn ar07_d_ci_lands_in_its_bands() {
    check_ci_scene("ar07-D-ci");
}

#[test]
fn grc07_cohesionless_ci_lands_in_its_bands() {
    check_ci_scene("grc07-cohesionless-phi036-mu05-ci");
}
