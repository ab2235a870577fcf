//! The SIMD force kernel (`contact::hertz_mindlin_avx`) against the scalar reference path:
//! two copies of one dense Hertz–Mindlin packing, one with `System::simd` off, stepped side by
//! side, must stay equal bit for bit (forces, springs, virial, positions, cell), at rest and
//! stirred hard enough to take the kernel's rare branches (springs turned by more than 3 mrad
//! in a step, pivot angles above 1e-3 rad, Coulomb sliding).

use grainbench_engine::contact::batch;
use grainbench_engine::contact::hertz_mindlin::HertzMindlin;
use grainbench_engine::contact::slider::{Coulomb, Friction, NoSlip};
use grainbench_engine::contact::ContactLaw;
use grainbench_engine::geometry::D3;
use grainbench_engine::system::System;
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};

#[path = "../benches/common/packings.rs"]
#[allow(dead_code)]
mod packings;

/// The `step`/`kernels` benches' dense packing (3D Hertz–Mindlin, κ = 39000, compressed at
/// P = 1 to Φ = 0.58), at N = 500 and with the friction kind `friction`.
fn packing<F: Friction>(friction: F) -> System<D3, HertzMindlin<F>>
where
    HertzMindlin<F>: ContactLaw<D3>,
{
    let scene = packings::scene_3d(500);
    let law = packings::law_3d(&scene, friction);
    packings::prepare(&scene, law, 0.58)
}

/// Steps the SIMD and the scalar copy of `sys` together, comparing everything each step;
/// returns the springs in contact at the end and the list builds on the way.
fn lockstep<
    L: ContactLaw<D3, History = grainbench_engine::contact::slider::Spring<Vector3<f64>>>,
>(
    sys: &System<D3, L>,
    steps: usize,
) -> (usize, u64) {
    let mut simd = sys.clone();
    simd.simd = true;
    let mut scalar = sys.clone();
    scalar.simd = false;
    let builds = simd.nlist.builds;
    let mut touching = 0;
    for step in 0..steps {
        simd.step();
        scalar.step();
        let at = |what: &str| format!("{what} differs at step {step}");
        assert_eq!(
            simd.contact_virial,
            scalar.contact_virial,
            "{}",
            at("virial")
        );
        assert_eq!(
            simd.max_overlap,
            scalar.max_overlap,
            "{}",
            at("largest overlap")
        );
        assert_eq!(simd.cell.l, scalar.cell.l, "{}", at("cell"));
        assert_eq!(simd.force, scalar.force, "{}", at("net force"));
        assert_eq!(simd.torque, scalar.torque, "{}", at("net moment"));
        assert_eq!(simd.s, scalar.s, "{}", at("position"));
        assert_eq!(simd.u, scalar.u, "{}", at("velocity"));
        assert_eq!(simd.w, scalar.w, "{}", at("spin"));
        for (a, b) in simd.nlist.history.iter().zip(&scalar.nlist.history) {
            assert!(a.t == b.t && a.kt == b.kt, "{}", at("spring"));
        }
        touching = simd.nlist.history.iter().filter(|h| h.kt > 0.0).count();
    }
    (touching, simd.nlist.builds - builds)
}

fn require_avx() -> bool {
    if batch::available() {
        return true;
    }
    eprintln!("this CPU has no AVX: only the scalar path runs, nothing to compare");
    false
}

#[test]
fn simd_kernel_is_the_scalar_path_bit_for_bit_at_rest() {
    if !require_avx() {
        return;
    }
    let sys = packing(Coulomb { mu: 0.3 });
    let (touching, _) = lockstep(&sys, 300);
    assert!(
        touching > sys.len(),
        "a dense packing (z > 2): {touching} springs"
    );
}

#[test]
fn simd_kernel_is_the_scalar_path_bit_for_bit_stirred() {
    if !require_avx() {
        return;
    }
    // Stirred, the list is rebuilt on the way: pairs change places in it, and those the
    // kernel leaves untouched out of reach must hold zeros there too.
    for mu in [0.3, 0.02] {
        let mut sys = packing(Coulomb { mu });
        stir(&mut sys);
        let (_, builds) = lockstep(&sys, 200);
        assert!(builds > 0, "μ = {mu}: no list build while stirred");
    }
    let mut sys = packing(NoSlip);
    stir(&mut sys);
    assert!(lockstep(&sys, 200).1 > 0);
}

/// Spins of ~0.1 rad per step and velocities of a tenth of a diameter per 100 steps: pivot
/// angles far above 1e-3 rad, springs dragged round their contacts and sliding.
fn stir<L: ContactLaw<D3>>(sys: &mut System<D3, L>) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let spin = 0.1 / sys.dt;
    let speed = 1e-3 / sys.dt;
    for (u, w) in sys.u.iter_mut().zip(sys.w.iter_mut()) {
        *u = Vector3::from_fn(|_, _| rng.gen_range(-speed..speed));
        *w = Vector3::from_fn(|_, _| rng.gen_range(-spin..spin));
    }
}
