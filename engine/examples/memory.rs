//! Memory use of the dense packings of `benches/step.rs`: peak resident memory (VmHWM) and
//! the steady-state heap of the system, per particle.
//!
//! ```text
//! cargo run --release -p grainbench-engine --example memory [N3D] [N2D]
//! ```
//!
//! Prepares the dense 3D Hertz–Mindlin packing (μ = 0.3, κ = 39000, ζ = 0.98) with `N3D`
//! spheres (default 4000) and the 2D adhesive disk packing with rolling resistance with `N2D`
//! disks (default 1400), exactly as the benchmark does, runs 100 steps on each and prints
//! bytes per particle. Each case runs in a child process of its own so that the high-water
//! marks do not mix.

use grainbench_engine::contact::slider::Coulomb;
use grainbench_engine::contact::ContactLaw;
use grainbench_engine::geometry::{Dim, D2, D3};
use grainbench_engine::scene::Scene;
use grainbench_engine::system::System;
use std::mem::size_of;
use std::process::Command;

// ---- Preparation: the same as in benches/step.rs (keep in sync). ----

#[path = "../benches/common/packings.rs"]
mod packings;
use packings::*;

// ---- Memory. ----

/// A field of /proc/self/status (kB there), in bytes.
fn proc_status(field: &str) -> Option<usize> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = text.lines().find(|l| l.starts_with(field))?;
    let kb: usize = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Resets VmHWM to the current RSS (Linux ≥ 4.0); false where not permitted.
fn reset_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Hands the memory the allocator keeps after `free` back to the system, so that the RSS
/// shows the live data (glibc only); false where not available.
fn trim_heap() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn malloc_trim(pad: usize) -> i32;
        }
        // SAFETY: glibc's malloc_trim takes no pointers and may be called at any time.
        unsafe { malloc_trim(0) };
        true
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    false
}

fn bytes<T>(v: &Vec<T>) -> usize {
    v.capacity() * size_of::<T>()
}

/// Heap held by the system between steps, from the vector capacities.
fn heap<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>) -> Vec<(&'static str, usize)> {
    let nl = &sys.nlist;
    // The per-pair force arrays are private: pairs × element size (a lower bound, `resize`
    // may have left spare capacity).
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
            "grains: s, u, w, force, torque, disp",
            bytes(&sys.s)
                + bytes(&sys.u)
                + bytes(&sys.w)
                + bytes(&sys.force)
                + bytes(&sys.torque)
                + bytes(&sys.disp),
        ),
        (
            "grains: radius, mass, inv_mass, inv_inertia",
            bytes(&sys.radius) + bytes(&sys.mass) + bytes(&sys.inv_mass) + bytes(&sys.inv_inertia),
        ),
        (
            "list: row_start, partner, col_start, col_pair",
            bytes(&nl.row_start)
                + bytes(&nl.partner)
                + bytes(&nl.col_start)
                + bytes(&nl.col_pair)
                + bytes(&nl.l_build),
        ),
        ("list: contact history", bytes(&nl.history)),
        ("pair forces/moments (pairs × size)", pair_arrays),
    ]
}

fn measure<D: Dim, L: ContactLaw<D>>(label: &str, scene: &Scene, law: L, phi_stop: f64) {
    let start_rss = proc_status("VmRSS:").unwrap_or(0);
    let mut sys = prepare::<D, L>(scene, law, phi_stop);
    let n = sys.len();
    let peak_prep = proc_status("VmHWM:").unwrap_or(0);
    let rss_prepared = proc_status("VmRSS:").unwrap_or(0);
    // Drop what the preparation freed (gas placement grid, the run's last-good copy, the
    // snapshot) but the allocator kept, so that the peak over the steps shows the live data
    // and the transients of a step.
    let trimmed = trim_heap();
    let rss_trimmed = proc_status("VmRSS:").unwrap_or(0);
    let reset = reset_peak();
    let builds = sys.nlist.builds;
    for _ in 0..100 {
        sys.step();
    }
    let peak_steps = proc_status("VmHWM:").unwrap_or(0);
    let rebuilds = sys.nlist.builds - builds;
    // Transient of one neighbour-list rebuild on its own (old and new lists coexist).
    trim_heap();
    let rss_before_rebuild = proc_status("VmRSS:").unwrap_or(0);
    reset_peak();
    sys.rebuild();
    let peak_rebuild = proc_status("VmHWM:").unwrap_or(0);
    let peak_all = peak_steps.max(peak_prep);
    let per = |b: usize| b as f64 / n as f64;
    let above = |b: usize| per(b.saturating_sub(start_rss));
    println!(
        "== {label}: N = {n}, Φ = {:.4}, listed pairs = {} ({:.2} per grain), contacts = {}",
        sys.packing_fraction(),
        sys.nlist.pairs(),
        per(sys.nlist.pairs()),
        contacts(&sys)
    );
    println!("  RSS at start (runtime, before the system):  {start_rss:>10} B");
    println!(
        "  peak RSS (VmHWM), preparation + 100 steps:  {peak_all:>10} B = {:>6.0} B/particle, {:>6.0} B/particle above the start",
        per(peak_all),
        above(peak_all)
    );
    println!(
        "  RSS once prepared:                          {rss_prepared:>10} B = {:>6.0} B/particle, {:>6.0} B/particle above the start",
        per(rss_prepared),
        above(rss_prepared)
    );
    if trimmed {
        println!(
            "  RSS once prepared, after malloc_trim:       {rss_trimmed:>10} B = {:>6.0} B/particle, {:>6.0} B/particle above the start",
            per(rss_trimmed),
            above(rss_trimmed)
        );
    }
    if reset {
        println!(
            "  peak RSS during the 100 steps alone:        {peak_steps:>10} B = {:>6.0} B/particle, {:>6.0} B/particle above the start",
            per(peak_steps),
            above(peak_steps)
        );
        println!(
            "    ({rebuilds} list rebuilds in the 100 steps; one forced rebuild raises the RSS by {:.0} B/particle)",
            per(peak_rebuild.saturating_sub(rss_before_rebuild))
        );
    } else {
        println!("  (/proc/self/clear_refs not writable: no separate peak for the steps)");
    }
    let parts = heap(&sys);
    let total: usize = parts.iter().map(|p| p.1).sum();
    println!(
        "  steady-state heap of the System:            {total:>10} B = {:>6.0} B/particle",
        per(total)
    );
    for (name, b) in &parts {
        println!("    {name:<44} {:>6.1} B/particle", per(*b));
    }
    println!(
        "  element sizes: V = {} B, Ang = {} B, History = {} B",
        size_of::<D::V>(),
        size_of::<D::Ang>(),
        size_of::<L::History>()
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() >= 4 && args[1] == "--case" {
        let n: usize = args[3].parse().expect("N");
        if args[2] == "3d" {
            let mut scene = scene_3d(n);
            if n > 8000 {
                // Random sequential addition stalls at Φ_I = 0.36 for large N.
                scene.initial.packing_fraction = 0.33;
                eprintln!("N = {n} > 8000: initial packing fraction 0.33 instead of 0.36");
            }
            let law = law_3d(&scene, Coulomb { mu: 0.3 });
            measure::<D3, _>("hm3d_mu0.3", &scene, law, 0.58);
        } else {
            let scene = scene_2d(n);
            measure::<D2, _>("adh2d_rr", &scene, law_2d(&scene), 0.76);
        }
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
