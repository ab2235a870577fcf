//! End-to-end tests of the `grainbench` command line.

use assert_cmd::Command;
use predicates::prelude::*;
use serde_json::Value;
use std::path::Path;

fn grainbench() -> Command {
    Command::cargo_bin("grainbench").unwrap()
}

/// Writes `text` as a scene file in `dir`.
fn scene_file(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const SMALL_3D: &str = r#"
name = "small3d"
dimension = 3
seed = 3
[particles]
count = 250
[law]
kind = "hertz-mindlin"
kappa = 1e4
mu = 0.3
zeta = 0.98
[initial]
packing_fraction = 0.3
[[protocol]]
kind = "compress"
pressure = 1.0
inertia_cap = 0.05
max_time = 4.0
"#;

fn analyze_json(snap: &Path) -> Value {
    analyze_json_with(snap, &[])
}

fn analyze_json_with(snap: &Path, extra: &[&str]) -> Value {
    let out = grainbench()
        .args(["analyze", "--json"])
        .args(extra)
        .arg(snap)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    serde_json::from_slice(&out).unwrap()
}

#[test]
fn scenes_lists_the_embedded_scenes() {
    grainbench()
        .arg("scenes")
        .assert()
        .success()
        .stdout(predicate::str::contains("default"))
        .stdout(predicate::str::contains("grc07-cohesive-small"));
}

#[test]
fn bad_scene_names_file_and_field_and_leaves_results_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    let snap = out.join("final.snap.json");
    std::fs::write(&snap, "previous result").unwrap();
    let bad = scene_file(
        dir.path(),
        "bad.toml",
        &SMALL_3D.replace("kappa = 1e4", "kappa = -3.0"),
    );
    grainbench()
        .arg("run")
        .arg(&bad)
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("bad.toml"))
        .stderr(predicate::str::contains("law.kappa"))
        .stderr(predicate::str::contains("must lie in [10, 1e12]"));
    assert_eq!(std::fs::read_to_string(&snap).unwrap(), "previous result");

    let unknown = scene_file(
        dir.path(),
        "unknown.toml",
        &SMALL_3D.replace("zeta = 0.98", "zeta = 0.98\nstifness = 2"),
    );
    grainbench()
        .arg("run")
        .arg(&unknown)
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("unknown.toml"))
        .stderr(predicate::str::contains("stifness"));

    let dense = scene_file(
        dir.path(),
        "dense.toml",
        &SMALL_3D.replace("packing_fraction = 0.3", "packing_fraction = 0.5"),
    );
    grainbench()
        .arg("run")
        .arg(&dense)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("initial.packing_fraction"));

    grainbench()
        .args(["analyze", "--cohesive-tolerance", "0"])
        .arg(&snap)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--cohesive-tolerance 0"));

    let not_snap = scene_file(dir.path(), "x.json", "{\"format\": \"other\"}");
    grainbench()
        .arg("analyze")
        .arg(&not_snap)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("x.json"))
        .stderr(predicate::str::contains("not a grainbench snapshot"));

    grainbench()
        .args(["run", "no-such-scene"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("grainbench scenes"));
}

#[test]
fn same_seed_gives_identical_results_for_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path(), "s.toml", SMALL_3D);
    let mut files = Vec::new();
    for t in ["1", "2"] {
        let out = dir.path().join(format!("t{t}"));
        grainbench()
            .arg("run")
            .arg(&scene)
            .args(["-q", "-j", t, "-o"])
            .arg(&out)
            .assert()
            .success();
        files.push(std::fs::read(out.join("final.snap.json")).unwrap());
    }
    // GRC07 T.VI's split has no meaning for a cohesionless packing.
    grainbench()
        .args(["analyze", "--cohesive-tolerance", "1e-2"])
        .arg(dir.path().join("t1/final.snap.json"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("cohesionless"));
    let snap: Value = serde_json::from_slice(&files[0]).unwrap();
    assert!(
        snap["contacts"].as_array().unwrap().len() > 100,
        "the run must be past the gas stage for the comparison to mean something"
    );
    assert!(
        files[0] == files[1],
        "snapshots differ between 1 and 2 threads"
    );
}

/// `run --dump-every T` writes a ParaView frame at the first check past each multiple of T
/// (here T = 1 over 4 time units: t ≈ 0, 1, 2, 3) and `vtk/run.pvd` listing them in time order;
/// the run itself is untouched (the final snapshot is bit-identical to one without frames).
#[test]
fn dump_every_writes_a_paraview_series_without_changing_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path(), "s.toml", SMALL_3D);
    let mut finals = Vec::new();
    for (name, extra) in [("plain", &[][..]), ("dumped", &["--dump-every", "1.0"][..])] {
        let out = dir.path().join(name);
        grainbench()
            .arg("run")
            .arg(&scene)
            .args(["-q", "-j", "1"])
            .args(extra)
            .arg("-o")
            .arg(&out)
            .assert()
            .success();
        finals.push(std::fs::read(out.join("final.snap.json")).unwrap());
    }
    assert!(finals[0] == finals[1], "frames changed the run");
    let vtk = dir.path().join("dumped/vtk");
    let pvd = std::fs::read_to_string(vtk.join("run.pvd")).unwrap();
    let times: Vec<f64> = pvd
        .lines()
        .filter(|l| l.contains("part=\"0\""))
        .map(|l| l.split('"').nth(1).unwrap().parse().unwrap())
        .collect();
    assert!((4..=5).contains(&times.len()), "{pvd}");
    for (k, t) in times.iter().enumerate() {
        assert!(
            *t >= k as f64 && *t < k as f64 + 0.5,
            "frame {k} at t = {t}"
        );
    }
    for line in pvd.lines().filter(|l| l.contains("file=")) {
        let file = line
            .split("file=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        assert!(vtk.join(file).is_file(), "{file}");
    }
    grainbench()
        .arg("run")
        .arg(&scene)
        .args(["-q", "--dump-every", "0", "-o"])
        .arg(dir.path().join("bad"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--dump-every 0"));
}

/// `run --stage-snapshots` writes the state at the end of each stage: for a pressure program
/// (unrolled into one stage per level) one snapshot per level, under that level's pressure, in
/// the order of the summary's stage reports; the last is the final state.
#[test]
fn stage_snapshots_write_each_level_of_a_pressure_program() {
    let dir = tempfile::tempdir().unwrap();
    let text = SMALL_3D.replace(
        "kind = \"compress\"\npressure = 1.0\ninertia_cap = 0.05\nmax_time = 4.0",
        "kind = \"pressure-program\"\nfrom = 1.0\nto = 4.0\nfactor = 2.0\ninertia_cap = 0.05\nmax_time = 1.5",
    );
    assert!(text.contains("pressure-program"));
    let scene = scene_file(dir.path(), "program.toml", &text);
    let out = dir.path().join("out");
    grainbench()
        .arg("run")
        .arg(&scene)
        .args(["-q", "-j", "1", "--stage-snapshots", "-o"])
        .arg(&out)
        .assert()
        .success();
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let reports = summary["steps"].as_array().expect("stage reports");
    assert_eq!(reports.len(), 3, "{summary}");
    let mut states = Vec::new();
    for (k, (level, report)) in [1.0, 2.0, 4.0].iter().zip(reports).enumerate() {
        let path = out.join(format!("stages/stage-{k:03}.snap.json"));
        let snap: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(f(&snap, &["pressure_target"]), *level, "{}", path.display());
        let start = states.last().copied().unwrap_or(0.0);
        assert!((f(&snap, &["time"]) - start - f(report, &["time"])).abs() < 1e-9);
        states.push(f(&snap, &["time"]));
        let a = analyze_json(&path);
        assert_eq!(
            f(&a, &["packing_fraction"]),
            f(report, &["checks", "packing_fraction"]),
            "stage {k}"
        );
    }
    let last: Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("stages/stage-002.snap.json")).unwrap(),
    )
    .unwrap();
    let fin: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("final.snap.json")).unwrap())
            .unwrap();
    assert_eq!(last["particles"], fin["particles"]);
    assert!(!out.join("stages/stage-003.snap.json").exists());
}

#[test]
fn too_large_time_step_is_detected_and_last_good_state_kept() {
    let dir = tempfile::tempdir().unwrap();
    let text = SMALL_3D.replace("[initial]", "[numerics]\ndt_fraction = 0.5\n[initial]");
    let scene = scene_file(dir.path(), "unstable.toml", &text);
    let out = dir.path().join("out");
    grainbench()
        .arg("run")
        .arg(&scene)
        .args(["-q", "-o"])
        .arg(&out)
        .assert()
        .code(4)
        .stderr(predicate::str::contains("unstable at step"))
        .stderr(predicate::str::contains("time step"))
        .stderr(predicate::str::contains("numerics.dt_fraction"));
    let last = out.join("last-good.snap.json");
    let a = analyze_json(&last);
    assert_eq!(a["status"], "unstable");
    assert!(!out.join("final.snap.json").exists());
}

/// Runs an embedded scene to equilibrium and returns its analysis.
fn equilibrated(scene: &str) -> Value {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    grainbench()
        .args(["run", scene, "-q", "--require-equilibrium", "-o"])
        .arg(&out)
        .assert()
        .success()
        .stdout(predicate::str::contains("ended at equilibrium"));
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "equilibrium");
    analyze_json_with(&out.join("final.snap.json"), &["--moduli"])
}

/// The elastic moduli of an equilibrated packing (`analyze --moduli`) lie between the Reuss
/// and Voigt bounds (GRC08 (12)–(14): B^R ≤ B ≤ B^V, G ≤ G^V), and the network has `k`
/// mechanisms with the cell fixed. Returns the moduli.
fn check_moduli(a: &Value, k: u64) -> &Value {
    let m = &a["moduli"]["Ok"];
    let (b, g) = (f(m, &["bulk"]), f(m, &["shear"]));
    assert!(b > 0.0 && g > 0.0, "{m}");
    assert!(
        f(m, &["reuss_bulk"]) <= b && b <= f(m, &["voigt_bulk"]),
        "{m}"
    );
    assert!(g <= f(m, &["voigt_shear"]), "{m}");
    assert_eq!(m["rigidity"]["mechanisms"], k, "{m}");
    m
}

fn f(v: &Value, path: &[&str]) -> f64 {
    let mut x = v;
    for k in path {
        x = &x[*k];
    }
    x.as_f64()
        .unwrap_or_else(|| panic!("{path:?} missing in {v}"))
}

/// 3D frictionless Hertz packing, N = 500, κ = 1e4, compressed from a random gas at
/// I ≤ 1e-2 until the AR07 §III criteria hold.
///
/// Bands: AR07 T.IV state A (n = 4000, κ = 39000) has Φ = 0.6370 ± 0.0002, z* = 6.074,
/// x0 = 1.3 %. At κ = 1e4 contacts are 4 times deeper, so the excess z* − 6 (∝ κ^(−1/2) near
/// jamming, AR07 §III.B) roughly doubles (≈ 6.15) and Φ gains ≈ 1e-3; with n = 500 the
/// sample-to-sample spread is √8 ≈ 3 times that of n = 4000, and the random-gas start with a
/// faster compression than the paper's melt gives RCP-like Φ in 0.630–0.642 (AR07 §III.A,
/// OSLN, DTS). Hence Φ ∈ [0.628, 0.645], z* ∈ [6.03, 6.30], x0 ≤ 4 %.
#[test]
fn frictionless_3d_packing_reaches_ar07_criteria() {
    let a = equilibrated("ar07-frictionless-small");
    let phi = f(&a, &["packing_fraction"]);
    let zs = f(&a, &["z_backbone"]);
    let x0 = f(&a, &["rattler_fraction"]);
    assert!((0.628..=0.645).contains(&phi), "Φ = {phi}");
    assert!((6.03..=6.30).contains(&zs), "z* = {zs}");
    assert!(x0 <= 0.04, "x0 = {x0}");
    // Exact at equilibrium: the contact stress is Σ N ℓ/(dΩ) and, for equal spheres, AR07 (22)
    // P = zΦ⟨N⟩/(πa²) up to the contact deflections (h/a ~ 1/κ).
    let p = f(&a, &["pressure", "measured"]);
    assert!((p - 1.0).abs() < 1e-4, "P = {p}");
    assert!(f(&a, &["pressure", "exact_rel_diff"]).abs() < 1e-6);
    let eq22 = f(&a, &["pressure", "ar07_22", "rel_diff"]);
    assert!(eq22.abs() < 1e-3, "AR07 (22) off by {eq22}");
    // AR07 §II.C: the backbone has no mechanism but the 3 global translations (rotations of
    // frictionless spheres are not degrees of freedom).
    check_moduli(&a, 3);
}

/// 2D cohesionless linear disks (diameters in [a/2, a]), N = 400, μ = 0.5, Φ_I = 0.36,
/// κ = K_N/P = 1e4, compressed at I ≤ 0.05 until the criteria hold.
///
/// Bands: GRC07 T.II (N = 1400, κ = 1e5) gives Φ = 0.811 ± 0.001 and z = 2.65 ± 0.02 for
/// this Φ_I and μ. Ten times softer contacts add contacts (z up by ~0.1–0.2, GRC07 §II.C: "a
/// significant number of additional contacts appear" for soft grains), N = 400 widens the
/// spread by √3.5 ≈ 2, and a faster compression loosens the packing by up to ~0.01 (GRC07
/// §III.A). Hence Φ ∈ [0.79, 0.82], z ∈ [2.55, 2.95].
#[test]
fn cohesionless_2d_packing_reaches_criteria() {
    let a = equilibrated("grc07-cohesionless-phi036-mu05-ci");
    let phi = f(&a, &["packing_fraction"]);
    let z = f(&a, &["z"]);
    assert!((0.79..=0.82).contains(&phi), "Φ = {phi}");
    assert!((2.55..=2.95).contains(&z), "z = {z}");
    let p = f(&a, &["pressure", "measured"]);
    assert!((p - 1.0).abs() < 1e-4, "P = {p}");
    assert!(f(&a, &["pressure", "exact_rel_diff"]).abs() < 1e-6);
    // GRC07 (18) neglects size–force correlations; the paper finds it "remarkably accurate".
    // With N = 400 we measure a 2–3 % excess (bigger grains carry bigger forces).
    let eq18 = f(&a, &["pressure", "grc07_18", "rel_diff"]);
    assert!(eq18.abs() < 0.05, "GRC07 (18) off by {eq18}");
    // A rigid backbone: only the 2 global translations are free.
    check_moduli(&a, 2);
}

/// GRC07 §II.D on an adhesive packing: the reduced type-1 state with rolling
/// resistance (N = 400, Φ_I = 0.36, μ = 0.5, P* = 0.01) never met the force criterion under the
/// paper's law alone (undamped rolling and tangential modes). With `relax` it ends at
/// equilibrium, the criteria held over a 2 T0 window; the damped phase changed no interaction
/// and moved no grain by more than the vibration amplitude; no contact sits at its Coulomb or
/// rolling threshold (GRC07 §II.D: strict inequalities). The run is then killed and resumed
/// from its checkpoint, which carries the stage's watch (settling clock, damped phase): the
/// result is bit-identical.
#[test]
fn cohesive_2d_packing_relaxes_to_grc07_criteria_and_resumes_bit_identical() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("straight");
    grainbench()
        .args([
            "run",
            "grc07-cohesive-small",
            "-q",
            "-j",
            "2",
            "--require-equilibrium",
            "-o",
        ])
        .arg(&out)
        .assert()
        .success()
        .stdout(predicate::str::contains("relaxation from t ="));
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "equilibrium");
    assert_eq!(summary["contacts_at_threshold"], 0);
    let stage = &summary["steps"][0];
    assert_eq!(stage["end"], "equilibrium");
    let r = &stage["relaxation"];
    assert!(r["pairs"].as_u64().unwrap() > 400, "{r}");
    assert_eq!(r["pairs_gained"], 0, "{r}");
    assert_eq!(r["pairs_lost"], 0, "{r}");
    assert!(f(r, &["delta_phi"]).abs() < 1e-5, "{r}");
    assert!(f(r, &["max_displacement"]) < 0.01, "{r}");
    // Relaxation starts after the list has been unchanged for settle_time = 10 T0, and the
    // criteria then hold over the 2 T0 window before the stage ends.
    assert!(
        f(stage, &["time"]) >= f(r, &["start_time"]) + 2.0,
        "{stage}"
    );
    // GRC07 §IV.C: with RR every connected cluster is rigid (GRC07 App. A, checked there on
    // the stiffness matrix); GRC08 §VI.C: loose cohesive moduli far below the Voigt estimate.
    let a = analyze_json_with(&out.join("final.snap.json"), &["--moduli"]);
    let m = check_moduli(&a, 2);
    assert!(f(m, &["voigt_bulk"]) > 3.0 * f(m, &["bulk"]), "{m}");
    // GRC07 T.VI's split at GRC07 §IV.C's wider tolerance (1e-2 F0): the interactions that
    // carry between 1e-4 and 1e-2 F0 move to z0, none changes sign, z stays.
    let wide = analyze_json_with(
        &out.join("final.snap.json"),
        &["--cohesive-tolerance", "1e-2"],
    );
    assert_eq!(f(&wide, &["force_threshold"]), 1e-2);
    assert_eq!(f(&wide, &["z"]), f(&a, &["z"]));
    let split = |a: &Value, k: &str| f(a, &["cohesive_split", k]);
    assert!(split(&wide, "z_zero") > split(&a, "z_zero"), "{wide}");
    for k in ["z_plus", "z_minus"] {
        assert!(split(&wide, k) <= split(&a, k), "{k}: {wide}");
    }
    for s in [&a, &wide] {
        let sum = split(s, "z_plus") + split(s, "z_minus") + split(s, "z_zero");
        assert!((sum - f(s, &["z"])).abs() < 1e-12, "{s}");
    }
    let straight = std::fs::read_to_string(out.join("final.snap.json")).unwrap();
    let scene = dir.path().join("cohesive.toml");
    std::fs::write(
        &scene,
        grainbench_engine::library::scene_text("grc07-cohesive-small").unwrap(),
    )
    .unwrap();
    let resumed = interrupted_then_resumed(dir.path(), &scene, "-KILL");
    assert!(
        straight == resumed,
        "resumed run differs from the uninterrupted one"
    );
}

/// A slow compression (a heavy cell: M = 4.2 Σm for 100 grains compresses at the rate of
/// GRC07 (3) with M = 3/10 Σm for 1400) leaves the gas at rest with an unchanged, nearly empty
/// interaction list for longer than `settle_time`: the relaxation must not take that for a
/// settled packing (before it waited for the stress criterion too, it switched on at t = 20
/// with 2 pairs and damped the whole assembly). It starts on the built packing and changes no
/// pair.
#[test]
fn relaxation_waits_for_the_packing_not_for_a_gas_at_rest() {
    let dir = tempfile::tempdir().unwrap();
    let text = grainbench_engine::library::scene_text("grc07-cohesive-small")
        .unwrap()
        .replace("count = 400", "count = 100")
        .replace("cell_mass = 0.3", "cell_mass = 4.2")
        .replace(
            "cell_mass_per_length = true",
            "cell_mass_per_length = false",
        );
    let scene = scene_file(dir.path(), "slow.toml", &text);
    let out = dir.path().join("out");
    grainbench()
        .arg("run")
        .arg(&scene)
        .args(["-q", "-j", "2", "--require-equilibrium", "-o"])
        .arg(&out)
        .assert()
        .success();
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let r = &summary["steps"][0]["relaxation"];
    assert!(
        r["pairs"].as_u64().unwrap() >= 100,
        "switched on a gas: {r}"
    );
    assert_eq!(r["pairs_gained"], 0, "{r}");
    assert!(f(r, &["start_time"]) > 50.0, "{r}");
}

/// A frictional run long enough to be interrupted; the hard-sphere stage exercises the
/// checkpoint taken at a stage start.
const RESUMABLE: &str = r#"
name = "resumable"
dimension = 3
seed = 5
[particles]
count = 256
[law]
kind = "hertz-mindlin"
kappa = 1e4
mu = 0.3
zeta = 0.98
[initial]
packing_fraction = 0.3
[[protocol]]
kind = "hard-sphere-mix"
collisions_per_grain = 5.0
[[protocol]]
kind = "compress"
pressure = 1.0
inertia_cap = 0.05
max_time = 60.0
"#;

/// Starts a run, stops it with `signal` once a checkpoint exists and some steps later, resumes
/// it, and returns the final snapshot text.
fn interrupted_then_resumed(dir: &Path, scene: &Path, signal: &str) -> String {
    let out = dir.join(format!("run-{signal}"));
    let bin = assert_cmd::cargo::cargo_bin("grainbench");
    let mut child = std::process::Command::new(&bin)
        .args(["run", "-q", "-j", "2", "--checkpoint-every", "0", "-o"])
        .arg(&out)
        .arg(scene)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let cp = out.join("checkpoint.bin");
    let t = std::time::Instant::now();
    while !cp.exists() {
        assert!(t.elapsed().as_secs() < 60, "no checkpoint appeared");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(700));
    let status = std::process::Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let rc = child.wait().unwrap();
    assert!(!rc.success(), "the run finished before it was interrupted");
    assert!(!out.join("final.snap.json").exists() || signal == "-INT");
    grainbench()
        .args(["run", "-q", "-j", "2", "--resume", "-o"])
        .arg(&out)
        .assert()
        .success()
        .stderr(predicate::str::contains("resuming from"));
    assert!(!cp.exists(), "a completed run removes its checkpoint");
    std::fs::read_to_string(out.join("final.snap.json")).unwrap()
}

#[test]
fn interrupted_runs_resume_bit_identical() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path(), "resumable.toml", RESUMABLE);
    grainbench()
        .args(["run", "-q", "-j", "2", "-o"])
        .arg(dir.path().join("straight"))
        .arg(&scene)
        .assert()
        .success();
    let straight = std::fs::read_to_string(dir.path().join("straight/final.snap.json")).unwrap();
    // Killed (no chance to clean up): resumes from the last periodic checkpoint.
    assert_eq!(
        interrupted_then_resumed(dir.path(), &scene, "-KILL"),
        straight
    );
    // Ctrl-C: stops at the next check, writes its state and a checkpoint, exit 130.
    assert_eq!(
        interrupted_then_resumed(dir.path(), &scene, "-INT"),
        straight
    );
    // Nothing to resume: a clear error.
    grainbench()
        .args(["run", "--resume", "-o"])
        .arg(dir.path().join("straight"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("checkpoint"));
}

/// FIRE's state (its time step, α, counters) is in the checkpoint: a frictionless compression
/// relaxed by FIRE from its first check (`relax.method = "fire"`), killed inside the FIRE
/// phase and resumed, ends bit-identical to the uninterrupted run.
#[test]
fn fire_relaxation_resumes_bit_identical() {
    let dir = tempfile::tempdir().unwrap();
    let text = RESUMABLE
        .replace("mu = 0.3", "mu = 0.0")
        .replace("count = 256", "count = 500")
        .replace(
        "max_time = 60.0",
        "max_time = 5000.0\ncriteria = { preset = \"ar07\" }\nrelax = { method = \"fire\", settle_time = 0.0, settle_factor = 1e6 }",
    );
    let scene = scene_file(dir.path(), "fire.toml", &text);
    grainbench()
        .args(["run", "-q", "-j", "2", "--require-equilibrium", "-o"])
        .arg(dir.path().join("straight"))
        .arg(&scene)
        .assert()
        .success()
        .stdout(predicate::str::contains("(FIRE:"));
    let straight = std::fs::read_to_string(dir.path().join("straight/final.snap.json")).unwrap();
    assert!(
        interrupted_then_resumed(dir.path(), &scene, "-KILL") == straight,
        "resumed FIRE run differs from the uninterrupted one"
    );
}

/// Every kind of stage in one small 2D run: hard-disk mixing and growth, a frictionless
/// compression, an expansion and remixing, then friction on with a stiffness ramp and a
/// pressure program.
const ALL_STAGES: &str = r#"
name = "all-stages"
dimension = 2
seed = 2
[particles]
count = 120
min_diameter = 0.5
[law]
kind = "linear"
kappa = 1e4
mu = 0.5
zeta = 0.8
[initial]
packing_fraction = 0.3
[[protocol]]
kind = "hard-sphere-mix"
collisions_per_grain = 5.0
[[protocol]]
kind = "grow"
packing_fraction = 0.6
[[protocol]]
kind = "compress"
pressure = 1.0
inertia_cap = 0.05
max_time = 20.0
mu = 0.0
[[protocol]]
kind = "expand"
factor = 1.01
[[protocol]]
kind = "hard-sphere-mix"
collisions_per_grain = 5.0
[[protocol]]
kind = "kappa-ramp"
from = 1e3
to = 1e4
factor = 10.0
pressure = 1.0
inertia_cap = 0.05
max_time = 10.0
[[protocol]]
kind = "pressure-program"
from = 1.0
to = 4.0
factor = 2.0
inertia_cap = 0.05
max_time = 10.0
"#;

#[test]
fn every_stage_kind_runs_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path(), "all.toml", ALL_STAGES);
    grainbench()
        .args(["run", "-q", "-o"])
        .arg(dir.path().join("out"))
        .arg(&scene)
        .assert()
        .success();
    let summary: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out/summary.json")).unwrap())
            .unwrap();
    let kinds: Vec<&str> = summary["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["kind"].as_str().unwrap())
        .collect();
    assert_eq!(
        kinds,
        [
            "hard-sphere-mix",
            "grow",
            "compress",
            "expand",
            "hard-sphere-mix",
            "compress",
            "compress",
            "compress",
            "compress",
            "compress"
        ]
    );
    // Growth ends at Φ = 0.6 exactly; the last level holds P = 4.
    let grown = summary["steps"][1]["checks"]["packing_fraction"]
        .as_f64()
        .unwrap();
    assert!((grown - 0.6).abs() < 1e-9, "{grown}");
    let last = &summary["steps"][9]["checks"];
    assert!(
        (last["pressure"].as_f64().unwrap() / 4.0 - 1.0).abs() < 0.05,
        "{last}"
    );
    let snap: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out/final.snap.json")).unwrap())
            .unwrap();
    assert_eq!(snap["mu"], 0.5);
    assert_eq!(snap["pressure_target"], 4.0);
}

/// Runs `cmd` and checks its exit status and that its stderr contains each of `needles`.
fn fails(cmd: &mut assert_cmd::Command, code: i32, needles: &[&str]) {
    let mut a = cmd.assert().code(code);
    for n in needles {
        a = a.stderr(predicate::str::contains(*n));
    }
}

/// Hostile inputs that could panic (exit 101) or hang end with a clear error
/// (docs/reliability.md).
#[test]
fn hostile_scene_inputs_neither_panic_nor_hang() {
    let dir = tempfile::tempdir().unwrap();
    // `pressure = 1e20` blew the cell up and panicked in `f64::clamp` (engine/src/cell.rs).
    let crush = scene_file(
        dir.path(),
        "crush.toml",
        &SMALL_3D.replace("pressure = 1.0", "pressure = 1e20"),
    );
    let out = grainbench()
        .arg("run")
        .arg(&crush)
        .args(["-q", "-o"])
        .arg(dir.path().join("crush"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{err}");
    assert!(
        !err.contains("panicked") && err.contains("unstable"),
        "{err}"
    );

    // `count = 8`: the cell shrank below twice the reach while compressing, exit 0.
    let eight = scene_file(
        dir.path(),
        "eight.toml",
        &SMALL_3D.replace("count = 250", "count = 8"),
    );
    fails(
        grainbench()
            .arg("run")
            .arg(&eight)
            .args(["-q", "-o"])
            .arg(dir.path().join("eight")),
        4,
        &["cell shrank", "two periodic images"],
    );

    // A quiet run of `scene` into `dir/<out>` that must succeed: its stderr.
    let run_ok = |scene: &std::path::Path, out: &str| {
        let o = grainbench()
            .arg("run")
            .arg(scene)
            .args(["-q", "-o"])
            .arg(dir.path().join(out))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{err}");
        err
    };

    // `min_diameter = 1e-2` in 3D was accepted without a word on its 1000× steps.
    let tiny = scene_file(
        dir.path(),
        "tiny.toml",
        &SMALL_3D
            .replace("count = 250", "count = 250\nmin_diameter = 0.01")
            .replace("max_time = 4.0", "max_time = 1e-4"),
    );
    let err = run_ok(&tiny, "tiny");
    assert!(
        err.contains("warning: particles.min_diameter = 0.01") && err.contains("1000× the steps"),
        "{err}"
    );

    // A cohesive gas freed at P* = 0: its network wraps no axis and its grains move, so the
    // cell drifts (GRC07 series B drifted from Φ = 0.26 to 0.13 without a word).
    let drift = scene_file(
        dir.path(),
        "drift.toml",
        r#"
name = "drift"
dimension = 2
seed = 1
[particles]
count = 60
min_diameter = 0.5
[law]
kind = "linear"
kappa = 1e3
mu = 0.5
zeta = 0.8
cohesion = { d0 = 1e-3 }
[initial]
packing_fraction = 0.3
rms_velocity = 0.3
[[protocol]]
kind = "compress"
pressure = 0.0
inertia_cap = 0.05
max_time = 1.0
criteria = { preset = "grc07" }
"#,
    );
    let err = run_ok(&drift, "drift");
    assert!(
        err.contains("warning: stage 1 (compress) frees the cell at zero pressure")
            && err.contains("does not wrap the cell along x and y")
            && err.contains("fixed-volume"),
        "{err}"
    );
    // Under a positive pressure a gas that wraps nothing is normal: no warning.
    let squeeze = scene_file(
        dir.path(),
        "squeeze.toml",
        &std::fs::read_to_string(&drift)
            .unwrap()
            .replace("pressure = 0.0", "pressure = 0.01"),
    );
    let err = run_ok(&squeeze, "squeeze");
    assert!(!err.contains("wrap"), "{err}");

    // `mu = "abc"` pointed at `[law]` without naming the field.
    let abc = scene_file(
        dir.path(),
        "abc.toml",
        &SMALL_3D.replace("mu = 0.3", "mu = \"abc\""),
    );
    fails(
        grainbench().arg("run").arg(&abc),
        2,
        &["abc.toml", "`mu` must be a non-negative number"],
    );

    // `-j 0` silently meant every core.
    fails(
        grainbench().args(["run", "-j", "0"]).arg(&eight),
        2,
        &["-j 0"],
    );

    // `--resume --seed 6` blamed "other settings than the scene given" with no scene given.
    let cut = dir.path().join("cut");
    std::fs::create_dir_all(&cut).unwrap();
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("grainbench"))
        .arg("run")
        .arg(scene_file(dir.path(), "r.toml", RESUMABLE))
        .args(["-q", "-j", "1", "--checkpoint-every", "0", "-o"])
        .arg(&cut)
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t = std::time::Instant::now();
    while !cut.join("checkpoint.bin").exists() {
        assert!(t.elapsed().as_secs() < 60, "no checkpoint appeared");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    fails(
        grainbench()
            .args(["run", "--resume", "--seed", "6", "-o"])
            .arg(&cut),
        2,
        &["started with seed", "--seed 6 cannot change it"],
    );

    // `check_every = 1e10` hung a 64-grain run, deaf to SIGTERM.
    let deaf = scene_file(
        dir.path(),
        "deaf.toml",
        &SMALL_3D.replace(
            "[initial]",
            "[numerics]\ncheck_every = 10000000000\n[initial]",
        ),
    );
    fails(
        grainbench().arg("run").arg(&deaf),
        2,
        &["deaf.toml", "numerics.check_every", "10000]"],
    );

    // An initial snapshot with radius 0 panicked in the same clamp.
    let snap_path = dir.path().join("start.json");
    let good = dir.path().join("good");
    grainbench()
        .arg("run")
        .arg(scene_file(dir.path(), "s.toml", SMALL_3D))
        .args(["-q", "-o"])
        .arg(&good)
        .assert()
        .success();
    let mut snap: Value =
        serde_json::from_slice(&std::fs::read(good.join("final.snap.json")).unwrap()).unwrap();
    snap["particles"]["radius"][7] = 0.0.into();
    std::fs::write(&snap_path, serde_json::to_vec(&snap).unwrap()).unwrap();
    let from = scene_file(
        dir.path(),
        "from.toml",
        &SMALL_3D.replace(
            "[initial]\npacking_fraction = 0.3",
            &format!(
                "[initial]\npacking_fraction = 0.3\nsnapshot = {:?}",
                snap_path.display().to_string()
            ),
        ),
    );
    fails(
        grainbench()
            .arg("run")
            .arg(&from)
            .args(["-q", "-o"])
            .arg(dir.path().join("from")),
        2,
        &["start.json", "particles.radius[7]"],
    );
}

/// An output directory is never written by two runs at once, a checkpoint is never
/// overwritten without being asked, and output names cannot collide.
#[test]
fn output_directory_is_protected() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path(), "s.toml", SMALL_3D);
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    let cp = out.join("checkpoint.bin");
    std::fs::write(&cp, "an unfinished run").unwrap();
    fails(
        grainbench()
            .arg("run")
            .arg(&scene)
            .args(["-q", "-o"])
            .arg(&out),
        2,
        &["checkpoint of an unfinished run", "--resume", "--force"],
    );
    assert_eq!(std::fs::read_to_string(&cp).unwrap(), "an unfinished run");
    grainbench()
        .arg("run")
        .arg(&scene)
        .args(["-q", "--force", "-o"])
        .arg(&out)
        .assert()
        .success();
    assert!(!cp.exists() && out.join("final.snap.json").exists());

    let clash = scene_file(
        dir.path(),
        "clash.toml",
        &format!("{SMALL_3D}[output]\nsnapshot = \"summary.json\"\n"),
    );
    fails(
        grainbench().arg("run").arg(&clash),
        2,
        &["output.snapshot", "overwrite"],
    );

    let file = dir.path().join("a-file");
    std::fs::write(&file, "x").unwrap();
    fails(
        grainbench()
            .arg("run")
            .arg(&scene)
            .args(["-q", "-o"])
            .arg(&file),
        2,
        &["is a file, not a directory"],
    );

    // A second run into the directory of a running one is refused, naming it.
    let long = scene_file(
        dir.path(),
        "long.toml",
        &SMALL_3D
            .replace("count = 250", "count = 3000")
            .replace("max_time = 4.0", "max_time = 1000.0"),
    );
    let busy = dir.path().join("busy");
    let mut first = std::process::Command::new(assert_cmd::cargo::cargo_bin("grainbench"))
        .arg("run")
        .arg(&long)
        .args(["-q", "-j", "1", "-o"])
        .arg(&busy)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let lock = busy.join(".grainbench.lock");
    let t = std::time::Instant::now();
    while !std::fs::read_to_string(&lock).is_ok_and(|s| s.starts_with("pid")) {
        assert!(t.elapsed().as_secs() < 60, "the first run took no lock");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let second = grainbench()
        .arg("run")
        .arg(&long)
        .args(["-q", "-o"])
        .arg(&busy)
        .output()
        .unwrap();
    let _ = first.kill();
    let _ = first.wait();
    let err = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!("another grainbench run (pid {})", first.id())),
        "{err}"
    );
}

/// `grainbench plan` prints what each stage does in absolute units; `--json` is the engine's
/// plan itself, the one the decks and the exchange format carry.
#[test]
fn plan_prints_each_stage_in_absolute_units() {
    let out = grainbench().args(["plan", "ar07-C-ci"]).assert().success();
    let text = String::from_utf8(out.get_output().stdout.clone()).unwrap();
    assert!(text.starts_with("plan of scene `ar07-C-ci`"), "{text}");
    for want in [
        "hard-sphere-mix",
        "compress",
        "stress control to P = ",
        "dt = ",
    ] {
        assert!(text.contains(want), "no {want:?} in:\n{text}");
    }
    let out = grainbench()
        .args(["plan", "ar07-C-ci", "--json"])
        .assert()
        .success();
    let printed: grainbench_engine::plan::Plan =
        serde_json::from_slice(&out.get_output().stdout).unwrap();
    let scene = grainbench_engine::library::scene("ar07-C-ci")
        .unwrap()
        .unwrap();
    assert_eq!(printed, grainbench_engine::run::plan_of(&scene).unwrap());
    grainbench()
        .args(["plan", "no-such-scene"])
        .assert()
        .failure()
        .stderr(predicate::str::contains("no scene file"));
}
