//! Two spheres through a generated LIGGGHTS deck, read back by our reader, against our
//! Hertz–Mindlin law (`engine/src/contact/hertz_mindlin.rs`): normal elastic force, normal
//! damping at the clamped ζ, tangential stiffness K_T and tangential damping; and against our
//! SJKR law (`engine/src/contact/sjkr.rs`): the cohesive normal force of unequal spheres and
//! the overlap at which an attracted pair comes to rest.
//!
//! The final dump is written by a `run 0`, whose force evaluation uses the dumped positions
//! and velocities and the stored tangential displacement (not incremented in a setup), so the
//! force can be recomputed from the dumped state; the tangential displacement is u·t with t
//! short against the contact period ((ωt)² ≈ 1e-5).

mod common;
use common::rel;

use grainbench_comparisons::xcode::decks::{self, liggghts, Start, Tolerances};
use grainbench_comparisons::xcode::import::{self, Meta};
use grainbench_comparisons::xcode::Code;
use grainbench_engine::contact::{ContactLaw, Pair};
use grainbench_engine::geometry::{Dim, D3};
use grainbench_engine::run::sjkr_law;
use grainbench_engine::scene::{Mu, Scene};
use std::path::Path;
use std::process::Command;

const KAPPA: f64 = 1e4;
const POISSON: f64 = 0.3;

fn scene(zeta: f64) -> Scene {
    scene_with(zeta, "mu = \"inf\"")
}

/// The two-sphere scene with law lines `law` (μ, cohesion) in place of μ = ∞.
fn scene_with(zeta: f64, law: &str) -> Scene {
    let text = format!(
        r#"name = "two-particle-liggghts"
description = "two spheres"
dimension = 3
seed = 1
[particles]
count = 2
[initial]
arrangement = "random"
packing_fraction = 0.1
[law]
kind = "hertz-mindlin"
kappa = {KAPPA}
{law}
zeta = {zeta}
poisson = {POISSON}
[[protocol]]
kind = "fixed-volume"
max_time = 1.0
"#
    );
    Scene::from_toml(&text, Path::new("two.toml")).expect("scene parses")
}

/// Sphere 1 at rest at x = 4.5, sphere 2 overlapping by `h0` along x with velocity `v2`.
fn start(zeta: f64, h0: f64, v2: [f64; 3], steps: u64, dt: f64) -> Start {
    let stages = vec![common::fixed_stage(
        false,
        Mu::Infinite,
        KAPPA,
        dt,
        steps,
        steps,
        Tolerances {
            force: 0.0,
            moment: 0.0,
            stress: 0.0,
            kinetic_per_grain: 0.0,
        },
    )];
    Start {
        scene: scene(zeta),
        dimension: 3,
        lengths: vec![10.0; 3],
        position: vec![vec![4.5, 5.0, 5.0], vec![5.5 - h0, 5.0, 5.0]],
        velocity: vec![vec![0.0; 3], v2.to_vec()],
        spin: Vec::new(),
        diameter: vec![1.0, 1.0],
        mass: vec![1.0, 1.0],
        inertia: vec![0.1, 0.1],
        prelude: Vec::new(),
        interlude: Vec::new(),
        trace_steps: None,
        stages,
    }
}

/// Runs the deck of `start`; returns the snapshot of its final state.
fn run(start: &Start) -> grainbench_engine::snapshot::Snapshot {
    let deck = decks::deck(start, Code::Liggghts).expect("liggghts deck");
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in &deck.files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let out = Command::new("liggghts")
        .args(&deck.args)
        .current_dir(dir.path())
        .output()
        .expect("liggghts runs");
    assert!(
        out.status.success() && dir.path().join("final.contacts").exists(),
        "liggghts failed:\n{}",
        String::from_utf8_lossy(&out.stdout)
    );
    let meta = Meta::read(dir.path()).unwrap();
    import::read(Code::Liggghts, dir.path(), &meta).expect("reader")
}

struct Expected {
    normal: f64,
    normal_elastic: f64,
    tangential: [f64; 3],
}

/// Our law at the dumped state: N = (2/3)Ẽ√(R*h)h + 2ζ√(m*K_N)·ḣ, tangential force on j
/// −K_T·δ − 2ζ√(m*K_T)·v_t with δ = `slip` (ζ: LIGGGHTS's effective one, K_T = (2−2ν)/(2−ν)K_N).
fn expected(snap: &grainbench_engine::snapshot::Snapshot, zeta: f64, slip: [f64; 3]) -> Expected {
    let p = &snap.particles;
    let e_tilde = KAPPA.powf(1.5);
    let (r_eff, m_eff) = (0.25, 0.5);
    let b: Vec<f64> = (0..3)
        .map(|a| p.position[1][a] - p.position[0][a])
        .collect();
    let dist = b.iter().map(|x| x * x).sum::<f64>().sqrt();
    let n: Vec<f64> = b.iter().map(|x| x / dist).collect();
    let h = 1.0 - dist;
    let kn = e_tilde * (r_eff * h).sqrt();
    let kt = (2.0 - 2.0 * POISSON) / (2.0 - POISSON) * kn;
    let w = |i: usize| p.angular_velocity[i].clone();
    // Velocity of j relative to i at the contact point.
    let mut vc = [0.0; 3];
    let (wi, wj) = (w(0), w(1));
    let ws: Vec<f64> = (0..3).map(|a| 0.5 * (wi[a] + wj[a])).collect();
    let cross = [
        ws[1] * n[2] - ws[2] * n[1],
        ws[2] * n[0] - ws[0] * n[2],
        ws[0] * n[1] - ws[1] * n[0],
    ];
    for a in 0..3 {
        vc[a] = p.velocity[1][a] - p.velocity[0][a] - cross[a];
    }
    let vn: f64 = (0..3).map(|a| vc[a] * n[a]).sum();
    let ne = 2.0 / 3.0 * kn * h;
    let normal = ne - 2.0 * zeta * (m_eff * kn).sqrt() * vn;
    let gt = 2.0 * zeta * (m_eff * kt).sqrt();
    let mut t = [0.0; 3];
    for a in 0..3 {
        t[a] = -kt * slip[a] - gt * (vc[a] - vn * n[a]);
    }
    Expected {
        normal,
        normal_elastic: ne,
        tangential: t,
    }
}

#[test]
fn normal_elastic_force() {
    if !common::present(Code::Liggghts) {
        return;
    }
    // ζ = 0: e = 1, no damping; approaching spheres, so h and v both matter.
    let s = start(0.0, 1e-3, [-0.05, 0.0, 0.0], 10, 1e-5);
    let snap = run(&s);
    assert_eq!(snap.contacts.len(), 1);
    // Zero tolerances: the stage ends at its step limit, after 10 steps of 1e-5.
    assert_eq!(snap.status, "time-limit");
    assert_eq!(snap.step, 10);
    assert!((snap.time - 1e-4).abs() < 1e-12, "{}", snap.time);
    let c = &snap.contacts[0];
    let ex = expected(&snap, 0.0, [0.0; 3]);
    let err = rel(c.normal, ex.normal);
    eprintln!(
        "normal elastic: liggghts {} ours {} rel {err:.2e}",
        c.normal, ex.normal
    );
    assert!(err <= 1e-3, "normal force rel. error {err}");
    // Our identical-sphere form N = (Ẽ√a/3)h^{3/2}.
    let h = -c.gap;
    assert!(rel(ex.normal_elastic, KAPPA.powf(1.5) / 3.0 * h.powf(1.5)) < 1e-12);
    // Frictionless: no tangential force.
    let t: f64 = c.tangential.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!(t < 1e-9 * c.normal, "{t}");
}

#[test]
fn normal_damping_at_clamped_zeta() {
    if !common::present(Code::Liggghts) {
        return;
    }
    // ζ = 0.98 is clamped: e = 0.0501, effective ζ ≈ 0.63.
    let (e, zeta_eff) = liggghts::restitution(0.98);
    assert_eq!(e, liggghts::MIN_RESTITUTION);
    let s = start(0.98, 1e-3, [-0.1, 0.0, 0.0], 10, 1e-5);
    let snap = run(&s);
    let c = &snap.contacts[0];
    let ex = expected(&snap, zeta_eff, [0.0; 3]);
    let err = rel(c.normal, ex.normal);
    eprintln!(
        "normal damped: liggghts {} ours(ζ={zeta_eff:.4}) {} (elastic {}) rel {err:.2e}; ours at ζ = 0.98: {}",
        c.normal,
        ex.normal,
        ex.normal_elastic,
        expected(&snap, 0.98, [0.0; 3]).normal
    );
    assert!(ex.normal - ex.normal_elastic > 0.3 * ex.normal_elastic);
    assert!(err <= 1e-3, "damped normal force rel. error {err}");
}

#[test]
fn tangential_stiffness_and_damping() {
    if !common::present(Code::Liggghts) {
        return;
    }
    let (steps, dt, u) = (5u64, 1e-5, 0.2);
    let t = steps as f64 * dt;
    for zeta in [0.0, 0.3] {
        // Sphere 2 slides along +y; μ = ∞: no sliding.
        let s = start(zeta, 1e-3, [0.0, u, 0.0], steps, dt);
        let snap = run(&s);
        let c = &snap.contacts[0];
        let (_, zeta_eff) = liggghts::restitution(zeta);
        let ex = expected(&snap, zeta_eff, [0.0, u * t, 0.0]);
        let err = rel(c.tangential[1], ex.tangential[1]);
        eprintln!(
            "tangential ζ={zeta}: liggghts T_y {} ours {} rel {err:.2e}; normal {} vs {}",
            c.tangential[1], ex.tangential[1], c.normal, ex.normal
        );
        assert!(c.tangential[1] < 0.0, "the spring pulls j back");
        assert!(err <= 1e-3, "tangential force rel. error {err}");
        assert!(rel(c.normal, ex.normal) <= 1e-3);
    }
}

/// Cohesion energy density of the SJKR tests (units of P_ref, as in `xcode-sjkr-smoke`).
const SJKR_K: f64 = 5000.0;

type Vector3 = <D3 as Dim>::V;

/// Frictionless spheres of diameters 1 and `d2` with SJKR cohesion, overlapping by `h0`.
fn sjkr_start(d2: f64, h0: f64, v2: [f64; 3], steps: u64, dt: f64) -> Start {
    let zeta = 0.5;
    let mut s = start(zeta, h0, v2, steps, dt);
    s.scene = scene_with(zeta, &format!("mu = 0.0\nsjkr = {SJKR_K}"));
    s.stages[0].mu = Mu::Finite(0.0);
    s.diameter[1] = d2;
    s.mass[1] = d2.powi(3);
    s.inertia[1] = 0.1 * d2.powi(5);
    s.position[1][0] = 4.5 + 0.5 * (1.0 + d2) - h0;
    s
}

/// Our SJKR pair of a dumped two-sphere state (j = grain 1 relative to grain 0).
fn sjkr_pair(snap: &grainbench_engine::snapshot::Snapshot) -> Pair<D3> {
    let p = &snap.particles;
    let v3 = |x: &[f64]| Vector3::new(x[0], x[1], x[2]);
    let b = v3(&p.position[1]) - v3(&p.position[0]);
    let dist = b.norm();
    let (ri, rj) = (p.radius[0], p.radius[1]);
    let (mi, mj) = (p.mass[0], p.mass[1]);
    Pair {
        n: b / dist,
        gap: dist - ri - rj,
        v_contact: v3(&p.velocity[1]) - v3(&p.velocity[0]),
        w_i: Vector3::zeros(),
        w_j: Vector3::zeros(),
        r_eff: ri * rj / (ri + rj),
        m_eff: mi * mj / (mi + mj),
        r_sum: ri + rj,
    }
}

/// LIGGGHTS's `cohesion sjkr` against ours on unequal spheres: overlaps below, near and beyond
/// the one where the attraction balances the Hertz repulsion, approaching and receding.
#[test]
fn sjkr_cohesive_normal_force() {
    if !common::present(Code::Liggghts) {
        return;
    }
    let (e, zeta_eff) = liggghts::restitution(0.5);
    assert!(e > liggghts::MIN_RESTITUTION && (zeta_eff - 0.5).abs() < 1e-12);
    for (h0, v) in [(2e-5, 0.0), (2e-4, -0.05), (6e-4, 0.0), (2e-3, 0.05)] {
        let s = sjkr_start(0.7, h0, [v, 0.0, 0.0], 10, 1e-5);
        let law = sjkr_law(s.law(), grainbench_engine::contact::slider::Frictionless);
        let snap = run(&s);
        assert_eq!(snap.contacts.len(), 1);
        let c = &snap.contacts[0];
        let p = sjkr_pair(&snap);
        let ours = ContactLaw::<D3>::interact(&law, &p, &mut (), 0.0);
        let pull =
            SJKR_K * grainbench_engine::contact::sjkr::contact_area(-p.gap, p.r_eff, p.r_sum);
        let err = (c.normal - ours.normal).abs() / pull;
        eprintln!(
            "sjkr h = {:.3e}: liggghts N = {:.9e}, ours {:.9e} (attraction {pull:.6e}), error {err:.2e} of the attraction",
            -p.gap, c.normal, ours.normal
        );
        assert!(
            err <= 1e-6,
            "cohesive normal force off by {err} of the attraction"
        );
        // The attraction is there: without it N would be the Hertz force alone.
        assert!(pull > 1e-3 * ours.normal_elastic.abs().max(1e-12));
        let t: f64 = c.tangential.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(t <= 1e-12 * pull, "frictionless: T = {t}");
    }
}

/// Two spheres set down at a small overlap are pulled in and come to rest where our law's
/// normal force vanishes (found by bisection), which LIGGGHTS must reproduce.
#[test]
fn sjkr_pair_rests_at_the_zero_force_overlap() {
    if !common::present(Code::Liggghts) {
        return;
    }
    let s = sjkr_start(0.7, 1e-5, [0.0; 3], 60_000, 1e-5);
    let law = sjkr_law(s.law(), grainbench_engine::contact::slider::Frictionless);
    let snap = run(&s);
    let p = sjkr_pair(&snap);
    let at = |h: f64| {
        let mut q = p;
        q.gap = -h;
        q.v_contact = Vector3::zeros();
        ContactLaw::<D3>::interact(&law, &q, &mut (), 0.0).normal
    };
    // Attractive at small overlaps, repulsive at large ones: one root in between.
    let (mut lo, mut hi) = (1e-7, 1e-2);
    assert!(at(lo) < 0.0 && at(hi) > 0.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if at(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let h_rest = 0.5 * (lo + hi);
    let h = -p.gap;
    let speed = p.v_contact.norm();
    eprintln!("sjkr rest: liggghts h = {h:.9e}, ours {h_rest:.9e}, |v| = {speed:.2e}");
    assert!(speed < 1e-6, "still moving: {speed}");
    assert!(
        (h - h_rest).abs() <= 1e-6 * h_rest,
        "rest overlap {h} vs {h_rest}"
    );
}

/// Import and analysis of a finished LIGGGHTS run (the `xcode-smoke` deck, say):
/// `LIGGGHTS_RUN_DIR=/tmp/lig-smoke/liggghts cargo test --release --test liggghts_two_particle
/// -- --ignored --nocapture`. Writes `imported.json` (our snapshot format) beside the dumps.
#[test]
#[ignore = "needs a finished LIGGGHTS run in LIGGGHTS_RUN_DIR"]
fn import_and_analyze_run() {
    let dir = std::path::PathBuf::from(
        std::env::var_os("LIGGGHTS_RUN_DIR").expect("set LIGGGHTS_RUN_DIR"),
    );
    let meta = Meta::read(&dir).unwrap();
    let snap = import::read(Code::Liggghts, &dir, &meta).unwrap();
    snap.write(&dir.join("imported.json")).unwrap();
    let a = grainbench_comparisons::analyze(&snap, &Default::default());
    let s = &snap.cell.contact_stress;
    eprintln!(
        "status {} step {} time {:.3}: Φ = {:.6}, z = {:.4}, z* = {:?}, rattlers {} ({:.3}), \
         contact stress diag {:.6} {:.6} {:.6}, P = {:.6}",
        snap.status,
        snap.step,
        snap.time,
        a.packing_fraction,
        a.z,
        a.z_backbone,
        a.rattlers,
        a.rattler_fraction,
        s[0][0],
        s[1][1],
        s[2][2],
        (s[0][0] + s[1][1] + s[2][2]) / 3.0
    );
}
