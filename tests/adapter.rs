//! Any DEM code through the exchange format and an adapter file (see
//! docs/exchange-format.md): the reference adapter end to end in `compare`, refusals from an
//! adapter's `supports`, a failing code, the generic deck, and the capability column.

use assert_cmd::Command;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn grainbench() -> Command {
    let mut c = Command::cargo_bin("grainbench").unwrap();
    // The reference adapter runs `grainbench` from PATH: this build's.
    let bin = assert_cmd::cargo::cargo_bin("grainbench");
    let path = std::env::var_os("PATH").unwrap_or_default();
    let mut dirs = vec![bin.parent().unwrap().to_path_buf()];
    dirs.extend(std::env::split_paths(&path));
    c.env("PATH", std::env::join_paths(dirs).unwrap());
    c
}

fn reference_adapter() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("reference-inputs/adapters/grainbench.toml")
}

fn compare_json(dir: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(dir.join("compare.json")).unwrap()).unwrap()
}

fn code<'a>(cmp: &'a Value, name: &str) -> &'a Value {
    cmp["codes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["code"] == name)
        .unwrap_or_else(|| panic!("no {name} in {cmp}"))
}

#[test]
fn the_reference_adapter_runs_the_exchange_and_lands_in_the_bands() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cmp");
    let codes = format!("rust,ref={}", reference_adapter().display());
    let assert = grainbench()
        .args(["compare", "xcode-smoke", "--quiet", "--codes", &codes, "-o"])
        .arg(&out)
        .assert();
    let o = assert.get_output();
    assert!(
        o.status.success(),
        "every band check passes: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    let cmp = compare_json(&out);
    let r = code(&cmp, "ref");
    assert_eq!(r["outcome"], "ran", "{r}");
    assert_eq!(r["status"], "equilibrium", "{r}");
    assert!(
        r["version"]
            .as_str()
            .unwrap()
            .contains("exchange reference"),
        "the version line comes from status.txt: {r}"
    );
    // The code read only exchange.json and particles.csv and wrote the three output files.
    let run = out.join("ref");
    for f in [
        "exchange.json",
        "particles.csv",
        "final/particles.csv",
        "final/contacts.csv",
        "final/status.txt",
    ] {
        assert!(run.join(f).is_file(), "{f}");
    }
    let ours = code(&cmp, "rust")["metrics"]["phi"].as_f64().unwrap();
    let theirs = r["metrics"]["phi"].as_f64().unwrap();
    // Same start, same law and protocol, another trajectory (round-off): the seed spread of Φ
    // at n = 256 is ~0.002.
    assert!((ours - theirs).abs() < 0.005, "Φ {ours} vs {theirs}");
    assert_eq!(r["metrics"]["pressure"].as_f64().unwrap().round(), 1.0);
    let md = std::fs::read_to_string(out.join("compare.md")).unwrap();
    assert!(md.contains("| ref |"), "{md}");
    // report.html, as a browser sees it: the tables and the inlined P(f) and g(r).
    if let Some(dom) = render(&out.join("report.html")) {
        assert!(
            dom.matches("<table>").count() >= 2,
            "the outcome and metric tables: {dom}"
        );
        assert!(dom.contains("<td>ref</td>"), "the adapter's row");
        assert_eq!(dom.matches("<svg").count(), 2, "P(f) and g(r) inlined");
        assert!(dom.contains("Normal force distribution") && dom.contains("Pair correlation"));
    }
}

/// The DOM headless Chromium builds from `html` (Debian's `chromium`, installed by
/// ci/setup.sh); `None` where it is not installed, outside CI.
fn render(html: &Path) -> Option<String> {
    let Some(chromium) = ["chromium", "chromium-browser"]
        .iter()
        .find_map(|b| grainbench_comparisons::xcode::which(b))
    else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI: headless Chromium is needed to check report.html (apt-get install -y --no-install-recommends chromium; ci/setup.sh does)"
        );
        eprintln!("skipping the browser check of report.html: chromium not installed");
        return None;
    };
    let profile = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(chromium)
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--dump-dom"])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg(format!("file://{}", html.display()))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "chromium: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(String::from_utf8_lossy(&out.stdout).into_owned())
}

fn adapter_file(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("adapter.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn an_adapter_without_a_feature_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let a = adapter_file(
        dir.path(),
        "run = [\"true\", \"{output}\"]\nsupports = [\"hertz-normal\", \"coulomb\"]\n",
    );
    let out = dir.path().join("cmp");
    grainbench()
        .args(["compare", "xcode-smoke", "--quiet", "--codes"])
        .arg(format!("narrow={}", a.display()))
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let cmp = compare_json(&out);
    let r = code(&cmp, "narrow");
    assert_eq!(r["outcome"], "refused", "{r}");
    let m = r["message"].as_str().unwrap();
    assert!(
        m.contains("stress-control") && m.contains("supports"),
        "{m}"
    );
    assert!(!m.contains("coulomb unsupported"), "{m}");
    // The same in the capability matrix, beside a built-in code.
    let o = grainbench()
        .args(["capabilities", "xcode-smoke", "--codes"])
        .arg(format!("lammps,narrow={}", a.display()))
        .assert()
        .success();
    let text = String::from_utf8_lossy(&o.get_output().stdout).to_string();
    assert!(text.contains("| feature | lammps | narrow |"), "{text}");
    assert!(
        text.contains("| `stress-control` |")
            && text.contains("not in the adapter's `supports` list"),
        "{text}"
    );
}

#[test]
fn a_failing_code_is_reported_with_its_output() {
    let dir = tempfile::tempdir().unwrap();
    let a = adapter_file(
        dir.path(),
        "run = [\"sh\", \"-c\", \"echo cannot read the law >&2; exit 3\", \"{output}\"]\nsupports = [\"hertz-normal\", \"mindlin-tangential\", \"mindlin-unloading\", \"hertz-damping\", \"coulomb\", \"stress-control\", \"affine-velocity\", \"equilibrium-criteria\", \"contact-dump\"]\n",
    );
    let out = dir.path().join("cmp");
    grainbench()
        .args(["compare", "xcode-smoke", "--quiet", "--codes"])
        .arg(format!("broken={}", a.display()))
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let r = code(&compare_json(&out), "broken").clone();
    assert_eq!(r["outcome"], "failed", "{r}");
    let m = r["message"].as_str().unwrap();
    assert!(
        m.contains("exit status: 3") && m.contains("cannot read the law"),
        "{m}"
    );
}

#[test]
fn bad_adapter_names_and_files_are_errors_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let a = adapter_file(dir.path(), "run = [\"x\"]\nsupports = []\n");
    grainbench()
        .args(["compare", "xcode-smoke", "--codes"])
        .arg(format!("mine={}", a.display()))
        .assert()
        .failure()
        .stderr(predicates::str::contains("field `run`"))
        .stderr(predicates::str::contains("adapter.toml"));
    grainbench()
        .args(["compare", "xcode-smoke", "--codes"])
        .arg(format!("yade={}", reference_adapter().display()))
        .assert()
        .failure()
        .stderr(predicates::str::contains("built-in"));
}

#[test]
fn the_generic_deck_holds_the_start_and_the_protocol() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("decks");
    grainbench()
        .args(["decks", "grc07-cohesive-small", "--codes", "generic", "-o"])
        .arg(&out)
        .assert()
        .success();
    let ex: Value =
        serde_json::from_slice(&std::fs::read(out.join("generic/exchange.json")).unwrap()).unwrap();
    assert_eq!(ex["format"], "grainbench-exchange");
    assert_eq!(ex["version"], 1);
    assert_eq!(ex["law"]["kind"], "linear");
    assert!(ex["law"]["cohesion"]["d0"].as_f64().unwrap() > 0.0);
    let n = ex["particles"]["count"].as_u64().unwrap() as usize;
    let csv = std::fs::read_to_string(out.join("generic/particles.csv")).unwrap();
    assert_eq!(csv.lines().count(), n + 1);
    assert!(
        csv.starts_with("id,x,y,diameter,mass,inertia,vx,vy\n"),
        "{csv}"
    );
    let stages = ex["stages"].as_array().unwrap();
    assert!(!stages.is_empty());
    for s in stages {
        assert!(
            s["dt"].as_f64().unwrap() > 0.0 && s["tolerances"]["force"].as_f64().unwrap() > 0.0,
            "{s}"
        );
    }
    // A reader refuses another version, naming it.
    let bad = dir.path().join("bad");
    std::fs::create_dir_all(&bad).unwrap();
    let text = std::fs::read_to_string(out.join("generic/exchange.json"))
        .unwrap()
        .replace("\"version\": 1", "\"version\": 7");
    std::fs::write(bad.join("exchange.json"), text).unwrap();
    grainbench()
        .arg("run-exchange")
        .arg(&bad)
        .arg(dir.path().join("o"))
        .assert()
        .failure()
        .stderr(predicates::str::contains("version 7"));
}

/// `python3` for pydem, the independent reference code; `None` where it is missing, outside CI.
fn python3() -> Option<PathBuf> {
    let found = grainbench_comparisons::xcode::which("python3");
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI: python3 is needed to run pydem (reference-inputs/adapters/pydem)"
        );
        eprintln!("skipping pydem: python3 not installed");
    }
    found
}

fn impact_row<'a>(cmp: &'a Value, name: &str) -> &'a Value {
    cmp["impacts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|i| i["code"] == name)
        .unwrap_or_else(|| panic!("no impact of {name} in {cmp}"))
}

/// pydem (reference-inputs/adapters/pydem/pydem.py): a Hertz–Mindlin DEM in pure Python,
/// written from the format and AR07 without our engine, joins `compare` through its adapter
/// and the exchange trace, and finds the impact our engine finds — the same velocity-Verlet
/// scheme, so to round-off — within the analytic tolerances.
#[test]
fn pydem_an_independent_code_runs_the_oblique_impact_as_our_engine() {
    if python3().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cmp");
    let adapter = reference_adapter().with_file_name("pydem.toml");
    let o = grainbench()
        .args(["compare", "impact-oblique", "--quiet", "--codes"])
        .arg(format!("rust,pydem={}", adapter.display()))
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "every impact check passes: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let cmp = compare_json(&out);
    let p = code(&cmp, "pydem");
    assert_eq!(p["outcome"], "ran", "{p}");
    assert!(p["version"].as_str().unwrap().starts_with("pydem"), "{p}");
    for f in ["final/trace-grains.csv", "final/trace-contacts.csv"] {
        assert!(out.join("pydem").join(f).is_file(), "{f}");
    }
    let (ours, theirs) = (
        &impact_row(&cmp, "rust")["report"]["measured"],
        &impact_row(&cmp, "pydem")["report"]["measured"],
    );
    for q in [
        "duration",
        "peak_normal_force",
        "restitution_normal",
        "tangential_speed_after",
    ] {
        let (a, b) = (ours[q].as_f64().unwrap(), theirs[q].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-6 * a.abs(), "{q}: rust {a}, pydem {b}");
    }
    assert!(ours["peak_normal_force"].as_f64().unwrap() > 0.4, "{ours}");
}

/// A stage that changes μ (and κ) in mid-contact starts afresh as docs/exchange-format.md
/// says — no contact history, spins at zero, forces evaluated with the stage's κ — in our
/// engine and in pydem alike; a change of κ alone keeps the history.
#[test]
fn a_mu_change_in_mid_contact_starts_afresh_in_both_codes() {
    if python3().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("reference-inputs/scenes/impact-oblique.toml"),
    )
    .unwrap()
    .replace("name = \"impact-oblique\"", "name = \"impact-mu-change\"")
    .replace(
        "max_time = 5.05\nfull_time = true\n",
        "max_time = 5.012\nfull_time = true\n\n[[protocol]]\nkind = \"fixed-volume\"\nmax_time = 0.04\nfull_time = true\nkappa = 20000.0\nmu = 0.5\n",
    );
    assert!(scene.contains("mu = 0.5"), "{scene}");
    let path = dir.path().join("impact-mu-change.toml");
    std::fs::write(&path, scene).unwrap();
    let out = dir.path().join("cmp");
    let adapter = reference_adapter().with_file_name("pydem.toml");
    grainbench()
        .args(["compare", path.to_str().unwrap(), "--quiet", "--codes"])
        .arg(format!("rust,pydem={}", adapter.display()))
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let cmp = compare_json(&out);
    assert_eq!(code(&cmp, "pydem")["outcome"], "ran", "{cmp}");
    let (ours, theirs) = (
        &impact_row(&cmp, "rust")["report"]["measured"],
        &impact_row(&cmp, "pydem")["report"]["measured"],
    );
    for q in ["peak_normal_force", "tangential_speed_after"] {
        let (a, b) = (ours[q].as_f64().unwrap(), theirs[q].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-6 * a.abs(), "{q}: rust {a}, pydem {b}");
    }
    let (a, b) = (
        ours["spin_after"][1][2].as_f64().unwrap(),
        theirs["spin_after"][1][2].as_f64().unwrap(),
    );
    assert!((a - b).abs() <= 1e-6 * a.abs(), "spin: rust {a}, pydem {b}");
}
