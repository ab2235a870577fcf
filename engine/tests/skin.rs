//! The Verlet skin is a speed setting only: every pair within reach is listed whatever the
//! skin, each row is sorted by partner, and a pair's history survives rebuilds, so two copies
//! of one scene that differ only in `numerics.skin` follow the same trajectory bit for bit —
//! through the compression of a gas, and stirred hard enough that the small-skin copy
//! rebuilds its list far more often. This is what lets the default skin be tuned for speed
//! without touching a golden record (docs/performance.md).

use grainbench_engine::contact::slider::Coulomb;
use grainbench_engine::contact::ContactLaw;
use grainbench_engine::geometry::{Dim, VectorOps, D2, D3};
use grainbench_engine::scene::Scene;
use grainbench_engine::system::System;
use rand::{Rng, SeedableRng};

#[path = "../benches/common/packings.rs"]
#[allow(dead_code)]
mod packings;

/// Everything that evolves, compared bit for bit.
fn same_state<D: Dim, L: ContactLaw<D>>(a: &System<D, L>, b: &System<D, L>, when: &str) {
    assert_eq!(a.step, b.step, "{when}: step");
    assert_eq!(a.cell.l, b.cell.l, "{when}: cell");
    assert_eq!(a.s, b.s, "{when}: positions");
    assert_eq!(a.u, b.u, "{when}: velocities");
    assert_eq!(a.w, b.w, "{when}: spins");
    assert_eq!(a.force, b.force, "{when}: net forces");
    assert_eq!(a.torque, b.torque, "{when}: net moments");
    assert_eq!(a.contact_virial, b.contact_virial, "{when}: virial");
}

/// Steps both copies `steps` times, comparing every step; returns the list builds of each.
fn lockstep<D: Dim, L: ContactLaw<D>>(
    a: &mut System<D, L>,
    b: &mut System<D, L>,
    steps: usize,
) -> (u64, u64) {
    let (ba, bb) = (a.nlist.builds, b.nlist.builds);
    for k in 0..steps {
        a.step();
        b.step();
        same_state(a, b, &format!("step {k} after the preparation"));
    }
    (a.nlist.builds - ba, b.nlist.builds - bb)
}

/// Random velocities of `speed` diameters per 100 steps and spins of `spin` rad per step.
fn stir<D: Dim, L: ContactLaw<D>>(sys: &mut System<D, L>, speed: f64, spin: f64) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (v, w) = (speed * 1e-2 / sys.dt, spin / sys.dt);
    for u in sys.u.iter_mut() {
        for c in 0..D::D {
            u[c] = rng.gen_range(-v..v);
        }
    }
    for s in sys.w.iter_mut() {
        let k = s.to_vec().len();
        let c: Vec<f64> = (0..k).map(|_| rng.gen_range(-w..w)).collect();
        *s = VectorOps::from_components(&c);
    }
}

/// Prepares `scene` with skins 0.05 a and 0.005 a, requires the two runs equal through the
/// compression to Φ = `phi` and 150 stirred steps, the thin skin rebuilding more often.
fn wide_and_thin<D: Dim, L: ContactLaw<D>>(scene: Scene, law: impl Fn(&Scene) -> L, phi: f64) {
    let mut wide = scene;
    wide.numerics.skin = 0.05;
    let mut thin = wide.clone();
    thin.numerics.skin = 0.005;
    let mut a = packings::prepare::<D, _>(&wide, law(&wide), phi);
    let mut b = packings::prepare::<D, _>(&thin, law(&thin), phi);
    same_state(&a, &b, "after compressing the gas");
    assert!(
        b.nlist.builds > 2 * a.nlist.builds,
        "the thin skin rebuilds more: {} against {}",
        b.nlist.builds,
        a.nlist.builds
    );
    stir(&mut a, 0.1, 0.05);
    stir(&mut b, 0.1, 0.05);
    let (ba, bb) = lockstep(&mut a, &mut b, 150);
    assert!(bb > ba && bb > 3, "stirred: {bb} builds against {ba}");
}

#[test]
fn the_skin_changes_no_bit_of_a_3d_frictional_run() {
    let law = |s: &Scene| packings::law_3d(s, Coulomb { mu: 0.3 });
    wide_and_thin::<D3, _>(packings::scene_3d(300), law, 0.58);
}

#[test]
fn the_skin_changes_no_bit_of_a_2d_adhesive_run_with_rolling_resistance() {
    wide_and_thin::<D2, _>(packings::scene_2d(300), packings::law_2d, 0.75);
}
