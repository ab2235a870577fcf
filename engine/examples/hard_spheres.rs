//! Timings of the event-driven hard-sphere protocols (AR07 §III, §III.A) with n = 4000:
//! melting the FCC lattice at Φ = 0.45 (50 collisions per grain), then LS growth
//! 0.45 → 0.49 → 0.58 → 0.61 at rate 1e-2, with the collisions per grain of each interval.
//!
//! ```text
//! cargo run --release -p grainbench-engine --example hard_spheres [K] [RATE] [SEED] [jam]
//! ```
//! (n = 4K³, default K = 10; with `jam`, also times the refusal of an impossible target,
//! Φ = 0.75, which runs the packing into jamming.) Collisions per grain are 2 × pair
//! collisions / n.

use grainbench_engine::geometry::D3;
use grainbench_engine::protocols::event_driven::HardSpheres;
use grainbench_engine::protocols::lattice::{fcc, fcc_order_parameter};
use nalgebra::Vector3;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let k: usize = args.get(1).map_or(10, |a| a.parse().expect("K"));
    let rate: f64 = args.get(2).map_or(1e-2, |a| a.parse().expect("RATE"));
    let seed: u64 = args.get(3).map_or(1, |a| a.parse().expect("SEED"));
    let (side, s) = fcc(k, 0.45);
    let n = s.len();
    let mass = vec![1.0; n];
    let vel = grainbench_engine::init::maxwell_velocities::<D3>(&mass, 1.0, seed);
    let mut hs = HardSpheres::<D3>::new(Vector3::repeat(side), s, vec![0.5; n], mass, vel).unwrap();
    println!("n = {n}, Φ = {:.4}, rate = {rate}", hs.packing_fraction());

    let clock = Instant::now();
    let st = hs.run_collisions(50.0);
    let dt = clock.elapsed().as_secs_f64();
    println!(
        "melt: {:.1} collisions/grain, {} crossings, in {dt:.3} s ({:.2} µs/collision); Z = {:.3}; FCC order = {:.3}",
        st.collisions_per_grain,
        st.cell_crossings,
        dt / st.collisions as f64 * 1e6,
        st.z,
        fcc_order_parameter(&hs.s, k)
    );

    let total = Instant::now();
    for target in [0.49, 0.58, 0.61] {
        let from = hs.packing_fraction();
        let clock = Instant::now();
        match hs.grow(target, rate) {
            Ok(st) => println!(
                "grow {from:.2} → {target:.2}: {:.1} collisions/grain, {} rescalings, in {:.3} s, Z = {:.2}",
                st.collisions_per_grain,
                st.rescalings,
                clock.elapsed().as_secs_f64(),
                st.z
            ),
            Err(e) => {
                println!("grow {from:.2} → {target:.2}: {e}");
                return;
            }
        }
    }
    println!(
        "grow 0.45 → 0.61 in {:.3} s; max overlap {:.2e}",
        total.elapsed().as_secs_f64(),
        hs.max_overlap().unwrap().2
    );
    if args.get(4).map(String::as_str) != Some("jam") {
        return;
    }
    let clock = Instant::now();
    match hs.grow(0.75, rate) {
        Ok(_) => println!("grow to 0.75 succeeded?!"),
        Err(e) => println!("grow to 0.75 ({:.3} s): {e}", clock.elapsed().as_secs_f64()),
    }
}
