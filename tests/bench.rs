//! `grainbench bench`: fixed-step runs of our engine as child processes (csv/json/md with
//! every run, positive rates, ratio 1 for rust), a missing external binary reported with its
//! install command, an unknown code refused, a bad output directory leaving nothing written,
//! the run order alternating between codes (with LAMMPS when installed), and a tiny scale
//! sweep.

use assert_cmd::Command;
use std::path::Path;

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

fn row<'a>(doc: &'a serde_json::Value, code: &str) -> &'a serde_json::Value {
    doc["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["code"] == code)
        .unwrap_or_else(|| panic!("no row for {code}"))
}

#[test]
fn rust_fixed_steps_writes_every_run_and_unit_ratio() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b");
    let assert = Command::cargo_bin("grainbench")
        .unwrap()
        .args([
            "bench",
            "xcode-smoke",
            "--codes",
            "rust",
            "--steps",
            "200",
            "--repeat",
            "2",
            "-o",
        ])
        .arg(&out)
        .assert()
        .success();
    let stdout = String::from_utf8_lossy(&assert.get_output().stdout);
    assert!(stdout.contains("| rust | 1 | 2/2 |"), "{stdout}");
    assert!(stdout.contains("fixed steps: 200 MD steps"), "{stdout}");
    let doc = json(&out.join("bench.json"));
    assert_eq!(doc["n"], 256);
    assert_eq!(doc["mode"]["mode"], "steps");
    let runs = doc["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    for r in runs {
        assert_eq!(r["outcome"], "ran", "{r}");
        assert_eq!(r["steps"], 200, "exactly the steps asked: {r}");
        assert!(r["particle_steps_per_second"].as_f64().unwrap() > 0.0);
        assert!(r["peak_rss_kib"].as_u64().unwrap() > 1000, "{r}");
        assert!(r["wall_seconds"].as_f64().unwrap() > 0.0);
    }
    let rust = row(&doc, "rust");
    assert_eq!(rust["rate_ratio"]["median"], 1.0);
    assert_eq!(rust["wall_ratio"]["max"], 1.0);
    let csv = std::fs::read_to_string(out.join("bench.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2, "{csv}");
    assert!(csv
        .lines()
        .nth(1)
        .unwrap()
        .starts_with("xcode-smoke,256,steps=200,rust,1,2,2,ran,time-limit"));
    assert!(std::fs::read_to_string(out.join("bench.md"))
        .unwrap()
        .contains("| rust |"));
    // Only the four reports and the run directories: no temporaries left.
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "bench.csv",
            "bench.json",
            "bench.md",
            "report.html",
            "runs",
            "scene.toml"
        ]
    );
}

#[test]
fn missing_external_binary_is_reported_with_its_install_command() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b");
    let assert = Command::cargo_bin("grainbench")
        .unwrap()
        .env("PATH", dir.path()) // no lmp here
        .args([
            "bench",
            "xcode-smoke",
            "--codes",
            "rust,lammps",
            "--steps",
            "200",
            "--repeat",
            "1",
            "-q",
            "-o",
        ])
        .arg(&out)
        .assert()
        .success();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr);
    assert!(
        stderr.contains("apt-get install -y --no-install-recommends lammps"),
        "{stderr}"
    );
    let doc = json(&out.join("bench.json"));
    assert_eq!(row(&doc, "lammps")["outcome"], "missing");
    assert_eq!(row(&doc, "lammps")["runs"], 0);
    assert_eq!(row(&doc, "rust")["ran"], 1);
}

#[test]
fn unknown_code_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    Command::cargo_bin("grainbench")
        .unwrap()
        .current_dir(dir.path())
        .args([
            "bench",
            "xcode-smoke",
            "--codes",
            "rust,gromacs",
            "--steps",
            "200",
        ])
        .assert()
        .code(2)
        .stderr(predicates::str::contains("unknown code `gromacs`"));
    assert!(!dir.path().join("runs").exists());
}

#[test]
fn bad_output_directory_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plain-file");
    std::fs::write(&file, "x").unwrap();
    Command::cargo_bin("grainbench")
        .unwrap()
        .args([
            "bench",
            "xcode-smoke",
            "--codes",
            "rust",
            "--steps",
            "200",
            "-o",
        ])
        .arg(file.join("out"))
        .assert()
        .code(2)
        .stderr(predicates::str::contains("creating the output directory"));
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1, "only the plain file");
}

#[test]
fn runs_alternate_between_codes() {
    if grainbench_comparisons::xcode::Code::Lammps.find().is_none() {
        eprintln!("skipped: `lmp` not installed");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b");
    Command::cargo_bin("grainbench")
        .unwrap()
        .args([
            "bench",
            "xcode-smoke",
            "--codes",
            "rust,lammps",
            "--steps",
            "200",
            "--repeat",
            "2",
            "-q",
            "-o",
        ])
        .arg(&out)
        .assert()
        .success();
    let doc = json(&out.join("bench.json"));
    let order: Vec<&str> = doc["run_order"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(
        order,
        [
            "rust/-j1/#1",
            "lammps/-j1/#1",
            "rust/-j1/#2",
            "lammps/-j1/#2"
        ]
    );
    for r in doc["runs"].as_array().unwrap() {
        assert_eq!(r["outcome"], "ran", "{r}");
        assert_eq!(r["steps"], 200, "same steps in both codes: {r}");
    }
    let lammps = row(&doc, "lammps");
    assert!(lammps["rate_ratio"]["median"].as_f64().unwrap() > 0.0);
    assert!(lammps["loop_seconds"]["median"].as_f64().unwrap() > 0.0);
}

#[test]
fn scale_sweep_writes_table_and_plot() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s");
    Command::cargo_bin("grainbench")
        .unwrap()
        .args(["bench", "--scale", "100,300", "--steps", "20", "-q", "-o"])
        .arg(&out)
        .assert()
        .success();
    let doc = json(&out.join("scale.json"));
    let points = doc["points"].as_array().unwrap();
    assert_eq!(points.len(), 2);
    for p in points {
        assert!(p["ns_per_particle_step"].as_f64().unwrap() > 0.0, "{p}");
        assert!(p["bytes_per_particle"].as_f64().unwrap() > 0.0, "{p}");
        let z = p["z_start"].as_f64().unwrap();
        assert!((3.0..7.5).contains(&z), "dense: z = {z}");
    }
    for f in ["scale.csv", "scale.md", "scale.svg", "scale.png"] {
        assert!(out.join(f).exists(), "{f}");
    }
}

/// `--memory`: each size is a whole `grainbench run` from a dense start (checkpoint at every
/// check, final snapshot, report); its peak RSS and the growth per particle between sizes
/// are recorded, and the run itself ended as it should.
#[test]
fn memory_sweep_records_whole_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m");
    Command::cargo_bin("grainbench")
        .unwrap()
        .args(["bench", "--memory", "200,400", "-q", "-o"])
        .arg(&out)
        .assert()
        .success();
    let doc = json(&out.join("memory.json"));
    let points = doc["points"].as_array().unwrap();
    assert_eq!(points.len(), 2);
    assert!(points[0]["slope_bytes_per_particle"].is_null());
    assert!(points[1]["slope_bytes_per_particle"].as_f64().is_some());
    for p in points {
        assert!(p["peak_rss_bytes"].as_u64().unwrap() > 1 << 20, "{p}");
        assert!(p["steps"].as_u64().unwrap() > 0, "{p}");
        let n = p["n"].as_u64().unwrap();
        let run = out.join("runs").join(format!("n{n}")).join("run");
        assert!(
            run.join("final.snap.json").exists(),
            "N = {n}: no final snapshot"
        );
        // The checkpoint of a completed run is removed.
        assert!(!run.join("checkpoint.bin").exists(), "N = {n}");
    }
    assert!(std::fs::read_to_string(out.join("memory.md"))
        .unwrap()
        .contains("above the previous size"));
}

/// GRC07 type 2 (adhesion, no rolling resistance) at N = 100: LAMMPS runs the bench-only
/// table deck (diameters in size classes, attraction by `pair_style table`) for the same
/// fixed steps, marked approximate.
#[test]
fn adhesive_scene_runs_the_bench_only_lammps_deck() {
    if grainbench_comparisons::xcode::Code::Lammps.find().is_none() {
        eprintln!("skipped: `lmp` not installed");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let text = grainbench_engine::library::scene_text("grc07-type2-phi036")
        .unwrap()
        .replace("name = \"grc07-type2-phi036\"", "name = \"grc07-tiny\"")
        .replace("count = 1400", "count = 100");
    let scene = dir.path().join("tiny.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.path().join("b");
    let assert = Command::cargo_bin("grainbench")
        .unwrap()
        .arg("bench")
        .arg(&scene)
        .args([
            "--codes",
            "rust,lammps",
            "--steps",
            "200",
            "--repeat",
            "1",
            "-q",
            "-o",
        ])
        .arg(&out)
        .assert()
        .success();
    let stdout = String::from_utf8_lossy(&assert.get_output().stdout);
    assert!(stdout.contains("adhesion"), "{stdout}");
    let doc = json(&out.join("bench.json"));
    for r in doc["runs"].as_array().unwrap() {
        assert_eq!(r["outcome"], "ran", "{r}");
        assert_eq!(r["steps"], 200, "{r}");
    }
    let lammps = row(&doc, "lammps");
    assert!(lammps["deviations"]
        .as_array()
        .unwrap()
        .iter()
        .any(|d| d.as_str().unwrap().contains("bench-only")));
    let input = std::fs::read_to_string(out.join("runs/lammps-j1-1/in.lammps")).unwrap();
    assert!(input.contains("pair_style hybrid/overlay granular table linear"));
    assert!(input.contains("pair_coeff 1 5 table cohesion-snapped.table C_1_5"));
}

#[test]
fn time_limit_stops_a_run_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b");
    let assert = Command::cargo_bin("grainbench")
        .unwrap()
        .args([
            "bench",
            "xcode-smoke",
            "--codes",
            "rust",
            "--repeat",
            "1",
            "--time-limit",
            "1",
            "-q",
            "-o",
        ])
        .arg(&out)
        .assert()
        .success();
    let stdout = String::from_utf8_lossy(&assert.get_output().stdout);
    assert!(stdout.contains("| rust | 1 | 0/1 | timeout |"), "{stdout}");
    let doc = json(&out.join("bench.json"));
    assert_eq!(doc["mode"]["mode"], "equilibrium");
    assert_eq!(doc["runs"][0]["outcome"], "timeout");
    assert!(doc["runs"][0]["message"]
        .as_str()
        .unwrap()
        .contains("--time-limit"));
}

/// Packing fraction of a snapshot, through `grainbench analyze --json`.
fn phi_of(snap: &Path) -> f64 {
    let out = Command::cargo_bin("grainbench")
        .unwrap()
        .args(["analyze", "--json"])
        .arg(snap)
        .output()
        .unwrap();
    assert!(out.status.success(), "analyze {}", snap.display());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["packing_fraction"].as_f64().unwrap()
}

/// `--start SNAP`: every code starts from the dense packing of the snapshot (Φ ≈ 0.592), not
/// from the scene's melted FCC gas (Φ = 0.45), and keeps it over the timed steps.
#[test]
fn start_snapshot_is_the_start_of_every_code() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let snap = root.join("reference-inputs/starts/ar07-D-10kPa-n1372.snap.json");
    let phi0 = phi_of(&snap);
    let lammps = grainbench_comparisons::xcode::Code::Lammps.find().is_some();
    let codes = if lammps { "rust,lammps" } else { "rust" };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b");
    Command::cargo_bin("grainbench")
        .unwrap()
        .args(["bench", "ar07-D-10kPa-n1372", "--codes", codes])
        .args(["--steps", "200", "--repeat", "1", "-q", "--start"])
        .arg(&snap)
        .arg("-o")
        .arg(&out)
        .assert()
        .success();
    let md = std::fs::read_to_string(out.join("bench.md")).unwrap();
    assert!(md.contains("start: the grains of"), "{md}");
    for code in codes.split(',') {
        let phi = phi_of(&out.join(format!("runs/{code}-j1-1/final.snap.json")));
        assert!((phi - phi0).abs() < 2e-3, "{code}: Φ = {phi}, start {phi0}");
    }
}

/// A start snapshot with another grain count is refused before any run, naming the field.
#[test]
fn start_snapshot_of_another_size_is_an_error() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let snap = root.join("reference-inputs/starts/ar07-D-10kPa-n1372.snap.json");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b");
    let assert = Command::cargo_bin("grainbench")
        .unwrap()
        .args([
            "bench",
            "xcode-smoke",
            "--codes",
            "rust",
            "--steps",
            "200",
            "--start",
        ])
        .arg(&snap)
        .arg("-o")
        .arg(&out)
        .assert()
        .failure();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr);
    assert!(stderr.contains("particles.count"), "{stderr}");
    assert!(!out.join("bench.json").exists());
}
