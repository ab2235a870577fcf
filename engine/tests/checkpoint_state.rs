//! The checkpoint writes the integrator state borrowed from the running system
//! ([`System::state_ref`]) instead of a copy ([`System::state`]): both must encode to the same
//! bytes, or a resumed run would not continue bit for bit.

use grainbench_engine::contact::slider::Coulomb;
use grainbench_engine::geometry::D3;
use grainbench_engine::system::System;

#[path = "../benches/common/packings.rs"]
#[allow(dead_code)]
mod packings;

#[test]
fn the_borrowed_state_encodes_as_the_copy() {
    let scene = packings::scene_3d(300);
    let mut sys: System<D3, _> =
        packings::prepare(&scene, packings::law_3d(&scene, Coulomb { mu: 0.3 }), 0.55);
    for _ in 0..50 {
        sys.step();
    }
    assert!(
        sys.nlist.history.iter().any(|h| h.kt > 0.0),
        "springs in the state"
    );
    let copy = bincode::serialize(&sys.state()).unwrap();
    let borrowed = bincode::serialize(&sys.state_ref()).unwrap();
    assert_eq!(copy.len(), borrowed.len());
    assert!(copy == borrowed, "the borrowed state encodes differently");
}
