//! Two spheres in a big periodic box run by `lmp` from a deck of `decks::lammps`, read back
//! by `import::lammps`, compared with our Hertz–Mindlin law (normal force, damping force,
//! tangential stiffness), for each LAMMPS version (`lammps`: Debian's 2021 build; `lammps-2025`:
//! the current release in its virtual environment). Skipped when a version is missing (fails
//! when `CI` is set).

mod common;
use common::rel;

use grainbench_comparisons::xcode::decks::{self, Start, Tolerances};
use grainbench_comparisons::xcode::import::{self, last_dump_frame, Meta};
use grainbench_comparisons::xcode::Code;
use grainbench_engine::contact::hertz_mindlin::HertzMindlin;
use grainbench_engine::scene::{Mu, Scene};
use std::path::Path;
use std::process::Command;

const KAPPA: f64 = 1e4;
const ZETA: f64 = 0.98;
const NU: f64 = 0.3;
const MU: f64 = 0.3;

fn scene() -> Scene {
    let text = format!(
        r#"
name = "lammps-two-particle"
description = "two spheres"
dimension = 3
seed = 1
[particles]
count = 2
[initial]
packing_fraction = 0.01
[law]
kind = "hertz-mindlin"
kappa = {KAPPA}
mu = {MU}
zeta = {ZETA}
poisson = {NU}
[[protocol]]
kind = "compress"
pressure = 1.0
inertia_cap = 0.01
max_time = 10.0
criteria = {{ preset = "ar07" }}
"#
    );
    Scene::from_toml(&text, Path::new("lammps-two-particle.toml")).expect("scene")
}

/// Two unit spheres along x at overlap `h`, velocities `v1`, `v2`, masses `m`, `steps` steps
/// of `dt` in a fixed 20³ cell.
fn start(h: f64, v1: [f64; 3], v2: [f64; 3], m: f64, steps: u64, dt: f64) -> Start {
    let stages = vec![common::fixed_stage(
        true,
        Mu::Finite(MU),
        KAPPA,
        dt,
        steps,
        10,
        Tolerances {
            force: 1e-4,
            moment: 1e-4,
            stress: 1e-4,
            kinetic_per_grain: 1e-8,
        },
    )];
    Start {
        scene: scene(),
        dimension: 3,
        lengths: vec![20.0; 3],
        position: vec![vec![9.0, 10.0, 10.0], vec![10.0 - h, 10.0, 10.0]],
        velocity: vec![v1.to_vec(), v2.to_vec()],
        spin: Vec::new(),
        diameter: vec![1.0, 1.0],
        mass: vec![m, m],
        inertia: vec![0.1 * m, 0.1 * m],
        prelude: Vec::new(),
        interlude: Vec::new(),
        trace_steps: None,
        stages,
    }
}

/// Runs the deck with `code`; returns the imported contact (normal, tangential on atom 2) and the net
/// force on atom 2 as LAMMPS wrote it minus N·n (n from atom 1 to 2): the tangential force on
/// atom 2 seen by LAMMPS itself.
fn run(start: &Start, code: Code) -> (f64, Vec<f64>, Vec<f64>) {
    let (n, t, f, _) = run_h(start, code);
    (n, t, f)
}

/// Writes the deck of `start` for `code` into a temporary directory, runs it, and reads its
/// final state back: (directory, what the reader found, the LAMMPS log).
fn run_deck(start: &Start, code: Code) -> (tempfile::TempDir, import::Raw, String) {
    run_edited_deck(start, code, |_| {})
}

/// [`run_deck`] with the deck's files edited first (what a [`Start`] cannot say: spins).
fn run_edited_deck(
    start: &Start,
    code: Code,
    edit: impl Fn(&mut Vec<(String, String)>),
) -> (tempfile::TempDir, import::Raw, String) {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut deck = decks::deck(start, code).expect("deck");
    edit(&mut deck.files);
    for (name, text) in &deck.files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let out = Command::new(code.find().expect("checked by common::present"))
        .args(&deck.args)
        .args(["-screen", "none"])
        .current_dir(dir.path())
        .output()
        .expect("lmp runs");
    let log = std::fs::read_to_string(dir.path().join("log.lammps")).unwrap_or_default();
    assert!(out.status.success(), "lmp failed:\n{log}");
    let meta = Meta::read(dir.path()).unwrap();
    let raw = import::lammps::read_dir(dir.path(), &meta).expect("read");
    (dir, raw, log)
}

/// [`run`], and the final overlap.
fn run_h(start: &Start, code: Code) -> (f64, Vec<f64>, Vec<f64>, f64) {
    let (dir, raw, log) = run_deck(start, code);
    assert_eq!(raw.contacts.len(), 1, "one contact:\n{log}");
    let c = &raw.contacts[0];
    let (n, t) = if (c.i, c.j) == (0, 1) {
        (c.normal, c.tangential.clone())
    } else {
        // The reader's tangential is on j: swap to have it on atom 2.
        (c.normal, c.tangential.iter().map(|x| -x).collect())
    };
    let atoms = last_dump_frame(&dir.path().join("final.atoms")).unwrap();
    let p = dir.path().join("final.atoms");
    let (cid, cf) = (atoms.col(&p, "id").unwrap(), atoms.col(&p, "fx").unwrap());
    let cx = atoms.col(&p, "x").unwrap();
    let row = |id: f64| atoms.rows.iter().find(|r| r[cid] == id).unwrap();
    let (r1, r2) = (row(1.0), row(2.0));
    let b: Vec<f64> = (0..3).map(|a| r2[cx + a] - r1[cx + a]).collect();
    let len = b.iter().map(|x| x * x).sum::<f64>().sqrt();
    let f2t: Vec<f64> = (0..3).map(|a| r2[cf + a] - n * b[a] / len).collect();
    if std::env::var_os("GB_KEEP").is_some() {
        eprintln!("kept {}", dir.keep().display());
    }
    (n, t, f2t, 1.0 - len)
}

fn law() -> HertzMindlin<()> {
    HertzMindlin::new(KAPPA.powf(1.5), NU, ZETA, ())
}

#[test]
fn lammps_two_particle_hertz_mindlin() {
    hertz_mindlin(Code::Lammps);
}

#[test]
fn lammps_2025_two_particle_hertz_mindlin() {
    hertz_mindlin(Code::Lammps2025);
}

fn hertz_mindlin(code: Code) {
    if !common::present(code) {
        return;
    }
    let law = law();
    let r_eff = 0.25;
    let h = 1e-3;

    // Normal force at rest (0 steps): N = (2/3)Ẽ√(R*h)h; on atom 2 along +x.
    let (n, t, f2) = run(&start(h, [0.0; 3], [0.0; 3], 1.0, 0, 1e-4), code);
    let want = law.normal_force(h, r_eff);
    eprintln!("{code} normal: {n}, ours {want}, rel {:.2e}", rel(n, want));
    assert!(rel(n, want) < 1e-3);
    assert!(
        f2.iter().chain(&t).all(|x| x.abs() < 1e-9 * want),
        "{f2:?} {t:?}"
    );

    // Damping: approaching at v (m = 1, m* = 1/2): N = N_e + 2ζ√(m* K_N)·v.
    let v = 0.05;
    let (n, _, _) = run(
        &start(h, [v / 2.0, 0.0, 0.0], [-v / 2.0, 0.0, 0.0], 1.0, 0, 1e-4),
        code,
    );
    let damp = 2.0 * ZETA * (0.5 * law.normal_stiffness(h, r_eff)).sqrt() * v;
    let want = law.normal_force(h, r_eff) + damp;
    eprintln!(
        "{code} damped normal: {n}, ours {want} (viscous {damp}), rel {:.2e}",
        rel(n, want)
    );
    assert!(rel(n, want) < 1e-3);

    // Unequal masses (1 and 3, m* = 3/4), the same relative velocity, no net momentum: the
    // dashpot scales with √m* (AR07 (5)).
    let mut st = start(h, [0.75 * v, 0.0, 0.0], [-0.25 * v, 0.0, 0.0], 1.0, 0, 1e-4);
    st.mass = vec![1.0, 3.0];
    st.inertia = vec![0.1, 0.3];
    let (n, _, _) = run(&st, code);
    let damp = 2.0 * ZETA * (0.75 * law.normal_stiffness(h, r_eff)).sqrt() * v;
    let want = law.normal_force(h, r_eff) + damp;
    eprintln!(
        "{code} damped normal, masses 1 and 3: {n}, ours {want} (viscous {damp}), rel {:.2e}",
        rel(n, want)
    );
    assert!(rel(n, want) < 1e-3);

    // Tangential stiffness: heavy grains (m = 1e4: negligible acceleration, viscous force ~1e-3 N), relative tangential velocity u
    // along y for k steps: T on atom 2 = −K_T·u·k·dt, K_T = (2−2ν)/(2−ν) Ẽ√(R*h).
    let (u, k, dt) = (1e-2, 100, 1e-4);
    let (n, t, f2) = run(
        &start(h, [0.0, -u / 2.0, 0.0], [0.0, u / 2.0, 0.0], 1e4, k, dt),
        code,
    );
    let kt = law.kt_ratio * law.normal_stiffness(h, r_eff);
    let delta = u * k as f64 * dt;
    let want = -kt * delta;
    eprintln!(
        "{code} tangential: {:?}, ours {want} (K_T {kt}), rel {:.2e}; N {n}; f2 {f2:?}",
        t,
        rel(t[1], want)
    );
    assert!(want.abs() < MU * n, "test must stay below sliding");
    assert!(rel(t[1], want) < 1e-3, "T {t:?} vs {want}");
    // The reader's sign convention agrees with the net force LAMMPS applied to atom 2.
    assert!(
        (0..3).all(|a| (f2[a] - t[a]).abs() < 1e-9),
        "{f2:?} vs {t:?}"
    );

    // Unloading (AR07 App. A): the same tangential motion while the grains separate at w, μ = ∞,
    // very heavy grains (the viscous pull stays harmless). Rescaling T by K_T(h')/K_T(h) at each
    // decrease, then adding K_T(h')·u·dt, gives T = K_T(h_end)·u·t; without the rescale T would be
    // Σ K_T(h_k) u dt, about 15 % more here (h: 1e-3 → 5e-4).
    let w = 5e-2;
    let mut st = start(
        h,
        [-w / 2.0, -u / 2.0, 0.0],
        [w / 2.0, u / 2.0, 0.0],
        1e8,
        k,
        dt,
    );
    st.stages[0].mu = Mu::Infinite;
    let (_, t, _, h_end) = run_h(&st, code);
    let want = -law.kt_ratio * law.normal_stiffness(h_end, r_eff) * delta;
    eprintln!(
        "{code} unloading: h_end {h_end:.6e}, T {:?}, ours {want}, rel {:.2e}",
        t,
        rel(t[1], want)
    );
    assert!(h_end < 0.6 * h);
    assert!(rel(t[1], want) < 2e-3, "T {t:?} vs {want}");
}

/// Converts a finished LAMMPS deck directory (env `GB_LAMMPS_DIR`, with its `deck.json`) into
/// our snapshot `final.json` in the same directory, for `grainbench analyze`:
/// `GB_LAMMPS_DIR=/tmp/lmp-smoke/lammps cargo test --release --test lammps_two_particle -- --ignored`.
#[test]
#[ignore]
fn lammps_convert_dir() {
    let Some(dir) = std::env::var_os("GB_LAMMPS_DIR") else {
        eprintln!("set GB_LAMMPS_DIR");
        return;
    };
    let dir = Path::new(&dir);
    let meta = Meta::read(dir).expect("deck.json");
    let snap = import::read(Code::Lammps, dir, &meta).expect("import");
    eprintln!(
        "{}: step {}, time {}, status {}, {} contacts",
        dir.display(),
        snap.step,
        snap.time,
        snap.status,
        snap.contacts.len()
    );
    snap.write(&dir.join("final.json"))
        .expect("write final.json");
}

/// Writes the LAMMPS deck of the scene file `GB_SCENE` into `GB_OUT` (development helper, like
/// `grainbench decks` without rebuilding the binary).
#[test]
#[ignore]
fn lammps_write_deck() {
    let (Some(scene), Some(out)) = (std::env::var_os("GB_SCENE"), std::env::var_os("GB_OUT"))
    else {
        eprintln!("set GB_SCENE and GB_OUT");
        return;
    };
    let scene = Scene::from_file(Path::new(&scene)).expect("scene");
    let start = Start::of(&scene).expect("start");
    let deck = decks::deck(&start, Code::Lammps).expect("deck");
    let out = Path::new(&out);
    std::fs::create_dir_all(out).unwrap();
    for (name, text) in &deck.files {
        std::fs::write(out.join(name), text).unwrap();
    }
}

/// 2D linear law (GRC07): two disks, K_N h + 2ζ√(m* K_N)·v normal force, K_T·u·t tangential.
#[test]
fn lammps_two_particle_linear_disks() {
    linear_disks(Code::Lammps);
}

#[test]
fn lammps_2025_two_particle_linear_disks() {
    linear_disks(Code::Lammps2025);
}

fn linear_disks(code: Code) {
    if !common::present(code) {
        return;
    }
    let (kn, zeta, mu) = (1e4, 0.8, 0.5);
    let text = format!(
        r#"
name = "lammps-two-disks"
description = "two disks"
dimension = 2
seed = 1
[particles]
count = 2
[initial]
packing_fraction = 0.01
[law]
kind = "linear"
kappa = {kn}
mu = {mu}
zeta = {zeta}
[[protocol]]
kind = "compress"
pressure = 1.0
inertia_cap = 0.01
max_time = 10.0
criteria = {{ preset = "ar07" }}
"#
    );
    let scene = Scene::from_toml(&text, Path::new("lammps-two-disks.toml")).expect("scene");
    let disks = |h: f64, v1: [f64; 2], v2: [f64; 2], m: f64, steps: u64, dt: f64| {
        let mut st = start(h, [0.0; 3], [0.0; 3], m, steps, dt);
        st.scene = scene.clone();
        st.dimension = 2;
        st.lengths.truncate(2);
        st.position = vec![vec![9.0, 10.0], vec![10.0 - h, 10.0]];
        st.velocity = vec![v1.to_vec(), v2.to_vec()];
        st.inertia = vec![0.125 * m, 0.125 * m];
        st.stages[0].kappa = kn;
        st.stages[0].mu = Mu::Finite(mu);
        st
    };
    let h = 1e-3;
    let v = 0.05;
    let (n, _, _) = run(
        &disks(h, [v / 2.0, 0.0], [-v / 2.0, 0.0], 1.0, 0, 1e-4),
        code,
    );
    let want = kn * h + 2.0 * zeta * (0.5 * kn).sqrt() * v;
    eprintln!(
        "{code} disks normal: {n}, ours {want}, rel {:.2e}",
        rel(n, want)
    );
    assert!(rel(n, want) < 1e-3);
    let (u, k, dt) = (1e-2, 100, 1e-4);
    let (n, t, _) = run(&disks(h, [0.0, -u / 2.0], [0.0, u / 2.0], 1e4, k, dt), code);
    let want = -kn * u * k as f64 * dt;
    eprintln!(
        "{code} disks tangential: {t:?}, ours {want}, rel {:.2e}; N {n}",
        rel(t[1], want)
    );
    assert!(want.abs() < mu * n);
    assert!(rel(t[1], want) < 1e-3);
}

/// Two disks of diameters `d` and masses `heavy`·d² at rest along x with surface gap `gap`
/// (negative: overlap) in a 20² cell, stage stiffness and friction `(kn, mu)`, `steps` steps of `dt`.
fn unequal_disks(
    scene: &Scene,
    d: (f64, f64),
    heavy: f64,
    gap: f64,
    (kn, mu): (f64, f64),
    (steps, dt): (u64, f64),
) -> Start {
    let (d1, d2) = d;
    let mut st = start(0.0, [0.0; 3], [0.0; 3], 1.0, steps, dt);
    st.scene = scene.clone();
    st.dimension = 2;
    st.lengths.truncate(2);
    st.diameter = vec![d1, d2];
    st.mass = vec![heavy * d1 * d1, heavy * d2 * d2];
    st.inertia = vec![0.125 * st.mass[0] * d1 * d1, 0.125 * st.mass[1] * d2 * d2];
    st.velocity = vec![vec![0.0; 2], vec![0.0; 2]];
    st.position = vec![vec![9.0, 10.0], vec![9.0 + 0.5 * (d1 + d2) + gap, 10.0]];
    st.stages[0].kappa = kn;
    st.stages[0].mu = Mu::Finite(mu);
    st
}

/// GRC07 adhesive law (4)–(5) in LAMMPS 2025: `hybrid/overlay granular lepton/sphere`, two
/// unequal disks (d = 1 and 0.6) at rest at overlaps and gaps across the attraction range and
/// approaching at v: the total normal force is ours (K_N δ + 2ζ√(m* K_N)·v − F0 in contact,
/// −F0(1 − h/D0) for 0 ≤ h ≤ D0, nothing beyond), to 1e-9 F0.
#[test]
fn lammps_2025_two_particle_adhesion() {
    adhesion(Code::Lammps2025, 1e-9);
}

/// The same in LAMMPS 2021: `hybrid/overlay granular table`, the two diameters as two atom
/// types with one attraction table per type pair (decks/lammps_table.rs), to 1e-6 F0 (linear
/// interpolation in r² between table points; the kinks are points).
#[test]
fn lammps_two_particle_adhesion_tables() {
    adhesion(Code::Lammps, 1e-6);
}

fn adhesion(code: Code, tolerance: f64) {
    use grainbench_engine::contact::linear::{Adhesion, Linear};
    use grainbench_engine::contact::slider::{Coulomb, NoRolling};
    use grainbench_engine::contact::{ContactLaw, Pair};
    use grainbench_engine::geometry::{Dim, D2};
    type V2 = <D2 as Dim>::V;
    if !common::present(code) {
        return;
    }
    let (kn, zeta, mu, d0) = (1e4, 0.8, 0.5, 1e-3);
    let text = format!(
        r#"
name = "lammps-two-adhesive-disks"
description = "two adhesive disks"
dimension = 2
seed = 1
[particles]
count = 2
min_diameter = 0.6
[initial]
packing_fraction = 0.01
[law]
kind = "linear"
kappa = {kn}
mu = {mu}
zeta = {zeta}
cohesion = {{ d0 = {d0} }}
[[protocol]]
kind = "compress"
pressure = 0.01
inertia_cap = 0.01
max_time = 10.0
criteria = {{ preset = "grc07" }}
"#
    );
    let scene = Scene::from_toml(&text, Path::new("lammps-two-adhesive-disks.toml")).unwrap();
    let (d1, d2) = (1.0, 0.6);
    let (m1, m2) = (d1 * d1, d2 * d2);
    let m_eff = m1 * m2 / (m1 + m2);
    let disks = |gap: f64, v: f64| {
        let mut st = unequal_disks(&scene, (d1, d2), 1.0, gap, (kn, mu), (0, 1e-4));
        // Approaching at v with no net momentum.
        st.velocity = vec![
            vec![v * m2 / (m1 + m2), 0.0],
            vec![-v * m1 / (m1 + m2), 0.0],
        ];
        st
    };
    let law: Linear<Adhesion, Coulomb, NoRolling> = Linear {
        kn,
        kt: kn,
        zeta,
        zeta_t: 0.0,
        cohesion: Adhesion { f0: 1.0, d0 },
        friction: Coulomb { mu },
        rolling: NoRolling,
    };
    let ours = |gap: f64, v: f64| {
        let p = Pair::<D2> {
            n: V2::new(1.0, 0.0),
            gap,
            v_contact: V2::new(-v, 0.0),
            w_i: 0.0,
            w_j: 0.0,
            r_eff: (0.5 * d1) * (0.5 * d2) / (0.5 * (d1 + d2)),
            m_eff,
            r_sum: 0.5 * (d1 + d2),
        };
        let mut hist = Default::default();
        ContactLaw::<D2>::interact(&law, &p, &mut hist, 0.0).normal
    };
    let mut seen = 0;
    for (gap, v) in [
        (-1e-3, 0.0),
        (-2e-4, 0.0),
        (-2e-4, 0.05),
        (0.0, 0.0),
        (1e-4, 0.0),
        (3.3e-4, 0.0),
        (5e-4, 0.0),
        (7.77e-4, 0.0),
        (9e-4, 0.0),
        (1.2e-3, 0.0),
    ] {
        let (_dir, raw, _) = run_deck(&disks(gap, v), code);
        let want = ours(gap, v);
        let got = raw.contacts.first().map(|c| c.normal).unwrap_or(0.0);
        eprintln!("{code} adhesion: gap {gap:e}, v {v}: N {got}, ours {want}");
        assert!(raw.contacts.len() <= 1, "{:?}", raw.contacts);
        assert_eq!(raw.contacts.len(), usize::from(gap <= d0), "gap {gap}");
        assert!(
            (got - want).abs() < tolerance,
            "gap {gap}, v {v}: {got} vs {want}"
        );
        seen += 1;
    }
    assert_eq!(seen, 10);

    // Tangential force through the overlay (the dump's p1..p3): heavy disks (×1e4) sliding
    // past each other at u along y for k steps at overlap 5e-4: T on disk 2 = −K_T·u·k·dt.
    let (u, k, dt) = (1e-2, 100u64, 1e-4);
    let mut st = unequal_disks(&scene, (d1, d2), 1e4, -5e-4, (kn, mu), (k, dt));
    st.velocity = vec![vec![0.0, -u / 2.0], vec![0.0, u / 2.0]];
    let (_dir, raw, _) = run_deck(&st, code);
    assert_eq!(raw.contacts.len(), 1, "{:?}", raw.contacts);
    let c = &raw.contacts[0];
    let t2 = if (c.i, c.j) == (0, 1) {
        c.tangential[1]
    } else {
        -c.tangential[1]
    };
    let want = -kn * u * k as f64 * dt;
    eprintln!(
        "{code} adhesion tangential: {t2}, ours {want}, rel {:.2e}",
        rel(t2, want)
    );
    assert!(rel(t2, want) < 1e-3, "T {t2} vs {want}");
}

/// GRC07 rolling resistance (9)–(10) as `rolling sds` per pair of diameter classes, both
/// LAMMPS versions: two heavy disks (d = 1 and 0.6, two atom types) in contact, spun in pure
/// rolling (ω_1 R_1 = −ω_2 R_2: no slip, so no tangential force) for k steps. The moment on disk
/// 2 is our law's, K_r·θ with θ the relative rotation, to 1e-3; with a small μ_r it is capped at
/// μ_r·N (N = K_N h at rest: the total normal force LAMMPS caps with is the elastic one here).
#[test]
fn lammps_two_particle_rolling() {
    rolling(Code::Lammps);
}

#[test]
fn lammps_2025_two_particle_rolling() {
    rolling(Code::Lammps2025);
}

fn rolling(code: Code) {
    use grainbench_engine::contact::linear::{Linear, NoCohesion};
    use grainbench_engine::contact::slider::{Coulomb, RollingSpring};
    use grainbench_engine::contact::{ContactLaw, Pair};
    use grainbench_engine::geometry::{Dim, D2};
    type V2 = <D2 as Dim>::V;
    if !common::present(code) {
        return;
    }
    let (kn, kr, mu, h) = (1e4, 1e-4, 0.5, 5e-4);
    let (d1, d2) = (1.0, 0.6);
    let heavy = 1e4;
    let (k, dt, w1) = (100u64, 1e-4, 0.01);
    let w2 = -w1 * d1 / d2;
    for mu_r in [5e-3, 1e-5] {
        let text = format!(
            r#"
name = "lammps-two-rolling-disks"
description = "two disks with rolling resistance"
dimension = 2
seed = 1
[particles]
count = 2
min_diameter = 0.6
[initial]
packing_fraction = 0.01
[law]
kind = "linear"
kappa = {kn}
mu = {mu}
zeta = 0.0
rolling = {{ kr = {kr}, mu_r = {mu_r} }}
[[protocol]]
kind = "compress"
pressure = 1.0
inertia_cap = 0.01
max_time = 10.0
criteria = {{ preset = "ar07" }}
"#
        );
        let scene = Scene::from_toml(&text, Path::new("lammps-two-rolling-disks.toml")).unwrap();
        let st = unequal_disks(&scene, (d1, d2), heavy, -h, (kn, mu), (k, dt));
        // Spins in the data file (a Start has none), torques in the final dump.
        let (dir, raw, log) = run_edited_deck(&st, code, |files| {
            for (name, text) in files.iter_mut() {
                if name == "in.lammps" {
                    *text = text.replace(
                        "omegax omegay omegaz fx fy fz ",
                        "omegax omegay omegaz fx fy fz tqx tqy tqz ",
                    );
                } else if name == "data.lammps" {
                    if !text.contains("Velocities") {
                        text.push_str("\nVelocities\n\n1 0 0 0 0 0 0\n2 0 0 0 0 0 0\n");
                    }
                    *text = text
                        .replace("\n1 0 0 0 0 0 0\n", &format!("\n1 0 0 0 0 0 {w1}\n"))
                        .replace("\n2 0 0 0 0 0 0\n", &format!("\n2 0 0 0 0 0 {w2}\n"));
                }
            }
        });
        assert!(log.contains("rolling sds"), "{log}");
        assert_eq!(raw.contacts.len(), 1, "{:?}", raw.contacts);
        let p = dir.path().join("final.atoms");
        let atoms = last_dump_frame(&p).unwrap();
        let (cid, ctq) = (atoms.col(&p, "id").unwrap(), atoms.col(&p, "tqz").unwrap());
        let tq2 = atoms.rows.iter().find(|r| r[cid] == 2.0).unwrap()[ctq];
        // Ours: the law stepped k times (the dump's `run 0` recomputes without updating).
        let law: Linear<NoCohesion, Coulomb, RollingSpring> = Linear {
            kn,
            kt: kn,
            zeta: 0.0,
            zeta_t: 0.0,
            cohesion: NoCohesion,
            friction: Coulomb { mu },
            rolling: RollingSpring { kr: kr * kn, mu_r },
        };
        let (r1, r2) = (0.5 * d1, 0.5 * d2);
        let pair = Pair::<D2> {
            n: V2::new(1.0, 0.0),
            gap: -h,
            v_contact: V2::new(0.0, 0.0),
            w_i: w1,
            w_j: w2,
            r_eff: r1 * r2 / (r1 + r2),
            m_eff: heavy * (d1 * d1 * d2 * d2) / (d1 * d1 + d2 * d2),
            r_sum: r1 + r2,
        };
        let mut hist = Default::default();
        let mut ours = 0.0;
        for _ in 0..k {
            ours = ContactLaw::<D2>::interact(&law, &pair, &mut hist, dt).rolling;
        }
        let capped = (kr * kn * (w2 - w1) * k as f64 * dt).abs() > mu_r * kn * h;
        eprintln!(
            "{code} rolling (μ_r = {mu_r}, capped: {capped}): moment on disk 2 {tq2}, ours {ours}, rel {:.2e}",
            rel(tq2, ours)
        );
        assert!(rel(tq2, ours) < 1e-3, "moment {tq2} vs ours {ours}");
        if capped {
            assert!((ours.abs() - mu_r * kn * h).abs() < 1e-12);
        }
    }
}
