//! Memory use of a dense packing: peak resident memory (VmHWM) and the steady-state heap of
//! the system, per particle.
//!
//! ```text
//! cargo run --release -p grainbench-engine --example memory [N3D] [N2D]
//! ```
//!
//! Prepares the dense 3D Hertz–Mindlin packing of `benches/step.rs` (μ = 0.3, κ = 39000,
//! ζ = 0.98) with `N3D` spheres (default 4000) and the 2D adhesive disk packing with rolling
//! resistance with `N2D` disks (default 1400), runs 100 steps on each, and prints bytes per
//! particle. Each case runs in a child process of its own so that the high-water marks do not
//! mix.

use grainbench_engine::cell::Control;
use grainbench_engine::contact::hertz_mindlin::HertzMindlin;
use grainbench_engine::contact::linear::{Adhesion, Linear};
use grainbench_engine::contact::slider::{Coulomb, RollingSpring};
use grainbench_engine::contact::ContactLaw;
use grainbench_engine::geometry::{Dim, Linear as _, D2, D3};
use grainbench_engine::run::{build_system, run_protocol, RunOptions};
use grainbench_engine::scene::Scene;
use grainbench_engine::system::System;
use std::mem::size_of;
use std::path::Path;
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

type Hm = HertzMindlin<Coulomb>;
type Adh = Linear<Adhesion, Coulomb, RollingSpring>;

/// 3D Hertz–Mindlin scene: gas at Φ = 0.36 compressed at P = 1 with a large inertia cap.
fn scene_3d(n: usize) -> Scene {
    let text = format!(
        r#"
name = "bench-hm3d"
dimension = 3
seed = 7
[particles]
count = {n}
[law]
kind = "hertz-mindlin"
kappa = 39000.0
mu = 0.3
zeta = 0.98
[initial]
packing_fraction = 0.36
[numerics]
cell_mass = 0.01
[[protocol]]
kind = "compress"
pressure = 1.0
inertia_cap = 0.1
max_time = 5.0
"#
    );
    Scene::from_toml(&text, Path::new("bench-hm3d.toml")).expect("3D bench scene")
}

/// 2D adhesive disks with rolling resistance (GRC07 T.I parameters), compressed at P* = 1.
fn scene_2d(n: usize) -> Scene {
    let text = format!(
        r#"
name = "bench-adh2d"
dimension = 2
seed = 7
[particles]
count = {n}
min_diameter = 0.5
[law]
kind = "linear"
kappa = 1e5
mu = 0.5
zeta = 0.8
cohesion = {{ d0 = 1e-3 }}
rolling = {{ kr = 1e-4, mu_r = 0.005 }}
[initial]
packing_fraction = 0.5
[numerics]
cell_mass = 0.01
[[protocol]]
kind = "compress"
pressure = 1.0
inertia_cap = 0.05
max_time = 40.0
criteria = {{ preset = "grc07" }}
"#
    );
    Scene::from_toml(&text, Path::new("bench-adh2d.toml")).expect("2D bench scene")
}

fn law_3d(scene: &Scene) -> Hm {
    let grainbench_engine::scene::Law::HertzMindlin {
        kappa,
        mu,
        zeta,
        poisson,
    } = scene.law
    else {
        unreachable!()
    };
    HertzMindlin::new(kappa.powf(1.5), poisson, zeta, Coulomb { mu: mu.value() })
}

fn law_2d(scene: &Scene) -> Adh {
    let grainbench_engine::scene::Law::Linear {
        kappa,
        mu,
        zeta,
        kt_over_kn,
        cohesion,
        rolling,
    } = scene.law
    else {
        unreachable!()
    };
    let (c, r) = (cohesion.unwrap(), rolling.unwrap());
    Linear {
        kn: kappa,
        kt: kappa * kt_over_kn,
        zeta,
        cohesion: Adhesion { f0: 1.0, d0: c.d0 },
        friction: Coulomb { mu: mu.value() },
        rolling: RollingSpring {
            kr: r.kr * kappa,
            mu_r: r.mu_r,
        },
    }
}

/// Contacts (overlapping pairs).
fn contacts<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>) -> usize {
    sys.interactions().iter().filter(|c| c.gap < 0.0).count()
}

/// Compresses the gas of `scene` until Φ ≥ `phi_stop` (or the scene's max_time), then fixes
/// the cell.
fn prepare<D: Dim, L: ContactLaw<D>>(scene: &Scene, law: L, phi_stop: f64) -> System<D, L> {
    let start = Instant::now();
    let mut sys = build_system::<D, L>(scene, law).expect("build_system");
    let stop = AtomicBool::new(false);
    let mut progress = |p: &grainbench_engine::run::Progress| {
        if std::env::var_os("VERBOSE").is_some() {
            eprintln!(
                "t={:.3} steps={} phi={:.4} P={:.3e} inter={} ke={:.3e}",
                p.time,
                p.steps,
                p.checks.packing_fraction,
                p.checks.pressure,
                p.checks.interactions,
                p.checks.kinetic_per_grain
            );
        }
        if p.checks.packing_fraction >= phi_stop {
            stop.store(true, Ordering::Relaxed);
        }
    };
    let mut opts = RunOptions {
        progress: Some(&mut progress),
        stop: Some(&stop),
    };
    run_protocol(scene, &mut sys, &mut opts).expect("preparation run");
    sys.cell.control = Control::Fixed;
    sys.cell.ldot = D::V::zero();
    eprintln!(
        "prepared {}: N = {}, Φ = {:.4}, contacts = {} (z = {:.2}), {} steps, {:.1} s",
        scene.name,
        sys.len(),
        sys.packing_fraction(),
        contacts(&sys),
        2.0 * contacts(&sys) as f64 / sys.len() as f64,
        sys.step,
        start.elapsed().as_secs_f64()
    );
    sys
}

/// A field of /proc/self/status, in bytes.
fn proc_status(field: &str) -> Option<usize> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = text.lines().find(|l| l.starts_with(field))?;
    let kb: usize = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Resets VmHWM to the current RSS (Linux ≥ 4.0); false when not permitted.
fn reset_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

fn bytes<T>(v: &Vec<T>) -> usize {
    v.capacity() * size_of::<T>()
}

/// Heap held by the system between steps, from the vector capacities.
fn heap<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>) -> Vec<(&'static str, usize)> {
    let nl = &sys.nlist;
    let np = nl.pairs();
    let mut pair_arrays = np * size_of::<D::V>();
    if L::MOMENTS {
        pair_arrays += np * size_of::<D::Ang>();
    }
    if L::ROLLING {
        pair_arrays += np * size_of::<D::Ang>();
    }
    vec![
        (
            "per grain: s, u, w, force, torque, disp",
            bytes(&sys.s)
                + bytes(&sys.u)
                + bytes(&sys.w)
                + bytes(&sys.force)
                + bytes(&sys.torque)
                + bytes(&sys.disp),
        ),
        (
            "per grain: radius, mass, inv_mass, inv_inertia",
            bytes(&sys.radius) + bytes(&sys.mass) + bytes(&sys.inv_mass) + bytes(&sys.inv_inertia),
        ),
        (
            "neighbour list: row_start, partner, col_start, col_pair",
            bytes(&nl.row_start)
                + bytes(&nl.partner)
                + bytes(&nl.col_start)
                + bytes(&nl.col_pair)
                + bytes(&nl.l_build),
        ),
        ("neighbour list: contact history", bytes(&nl.history)),
        (
            "per-pair forces (private; pairs × element size)",
            pair_arrays,
        ),
    ]
}

fn measure<D: Dim, L: ContactLaw<D>>(label: &str, scene: &Scene, law: L, phi_stop: f64) {
    let baseline = proc_status("VmRSS:").unwrap_or(0);
    let mut sys = prepare::<D, L>(scene, law, phi_stop);
    let n = sys.len();
    let peak_prep = proc_status("VmHWM:").unwrap_or(0);
    let reset = reset_peak();
    for _ in 0..100 {
        sys.step();
    }
    let peak_all = proc_status("VmHWM:").unwrap_or(0).max(peak_prep);
    let peak_steps = proc_status("VmHWM:").unwrap_or(0);
    let rss = proc_status("VmRSS:").unwrap_or(0);
    let per = |b: usize| b as f64 / n as f64;
    println!(
        "== {label}: N = {n}, listed pairs = {} ({:.2} per grain), contacts = {}, Φ = {:.4}",
        sys.nlist.pairs(),
        sys.nlist.pairs() as f64 / n as f64,
        contacts(&sys),
        sys.packing_fraction()
    );
    println!(
        "  RSS at start (runtime, before any allocation): {:>10} B",
        baseline
    );
    println!(
        "  peak RSS (VmHWM), preparation + 100 steps:    {:>10} B = {:>8.0} B/particle ({:.0} B/particle above the start)",
        peak_all,
        per(peak_all),
        per(peak_all.saturating_sub(baseline))
    );
    if reset {
        println!(
            "  peak RSS over the 100 steps alone:            {:>10} B = {:>8.0} B/particle ({:.0} B/particle above the start)",
            peak_steps,
            per(peak_steps),
            per(peak_steps.saturating_sub(baseline))
        );
    } else {
        println!("  (/proc/self/clear_refs not writable: no separate peak for the steps)");
    }
    println!(
        "  RSS after the steps:                          {:>10} B = {:>8.0} B/particle",
        rss,
        per(rss)
    );
    let parts = heap(&sys);
    let total: usize = parts.iter().map(|p| p.1).sum();
    println!(
        "  steady-state heap of the System (capacities): {:>10} B = {:>8.0} B/particle",
        total,
        per(total)
    );
    for (name, b) in &parts {
        println!("    {name:<56} {:>8.1} B/particle", per(*b));
    }
    println!(
        "  sizes: V = {} B, Ang = {} B, History = {} B",
        size_of::<D::V>(),
        size_of::<D::Ang>(),
        size_of::<L::History>()
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() >= 4 && args[1] == "--case" {
        let n: usize = args[3].parse().expect("N");
        // Run on a pool worker, as `run_scene` does.
        rayon::scope(|_| match args[2].as_str() {
            "3d" => {
                let scene = scene_3d(n);
                measure::<D3, Hm>("3D Hertz–Mindlin μ = 0.3", &scene, law_3d(&scene), 0.58)
            }
            _ => {
                let scene = scene_2d(n);
                measure::<D2, Adh>("2D adhesive disks + rolling", &scene, law_2d(&scene), 0.80)
            }
        });
        return;
    }
    let n3: usize = args.get(1).map_or(4000, |a| a.parse().expect("N3D"));
    let n2: usize = args.get(2).map_or(1400, |a| a.parse().expect("N2D"));
    let exe = std::env::current_exe().expect("current_exe");
    for (case, n) in [("3d", n3), ("2d", n2)] {
        let status = Command::new(&exe)
            .args(["--case", case, &n.to_string()])
            .status()
            .expect("child process");
        assert!(status.success(), "case {case} failed");
    }
}
