//! The thread count changes only how a step's passes are cut among threads
//! (engine/src/parallel.rs), never the result: one dense packing stepped in pools of 1, 2 and
//! 3 threads stays equal bit for bit (forces, virial, positions, velocities, springs, cell).
//! N = 2300 gives 9 chunks of rows and grains: 2 threads get pieces of unequal size.

use grainbench_engine::contact::slider::Coulomb;
use grainbench_engine::geometry::D3;
use grainbench_engine::system::System;

#[path = "../benches/common/packings.rs"]
#[allow(dead_code)]
mod packings;

fn stepped<L: grainbench_engine::contact::ContactLaw<D3>>(
    sys: &System<D3, L>,
    threads: usize,
    steps: usize,
) -> System<D3, L> {
    let mut s = sys.clone();
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
        .install(|| {
            for _ in 0..steps {
                s.step();
            }
        });
    s
}

#[test]
fn one_two_and_three_threads_step_bit_for_bit_alike() {
    let scene = packings::scene_3d(2300);
    let sys = packings::prepare(&scene, packings::law_3d(&scene, Coulomb { mu: 0.3 }), 0.58);
    let one = stepped(&sys, 1, 300);
    let touching = one.nlist.history.iter().filter(|h| h.kt > 0.0).count();
    assert!(
        touching > one.len(),
        "a dense packing (z > 2): {touching} springs"
    );
    for threads in [2, 3] {
        let other = stepped(&sys, threads, 300);
        let at = |what: &str| format!("{what} differs between 1 and {threads} threads");
        assert_eq!(one.contact_virial, other.contact_virial, "{}", at("virial"));
        assert_eq!(one.force, other.force, "{}", at("net force"));
        assert_eq!(one.torque, other.torque, "{}", at("net moment"));
        assert_eq!(one.s, other.s, "{}", at("position"));
        assert_eq!(one.u, other.u, "{}", at("velocity"));
        assert_eq!(one.w, other.w, "{}", at("spin"));
        assert_eq!(one.cell.l, other.cell.l, "{}", at("cell"));
        assert!(
            one.nlist
                .history
                .iter()
                .zip(&other.nlist.history)
                .all(|(a, b)| a.t == b.t && a.kt == b.kt),
            "{}",
            at("spring")
        );
    }
}
