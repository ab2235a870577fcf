//! Dense packings shared by the step benchmark (`benches/step.rs`) and the memory example
//! (`examples/memory.rs`): scenes, laws, and the preparation by fast compression.

use grainbench_engine::contact::hertz_mindlin::HertzMindlin;
use grainbench_engine::contact::linear::{Adhesion, Linear};
use grainbench_engine::contact::slider::{Coulomb, RollingSpring};
use grainbench_engine::contact::ContactLaw;
use grainbench_engine::geometry::Dim;
use grainbench_engine::run::{
    adhesion, compress_until, hertz_mindlin_law, linear_law, rolling_spring,
};
use grainbench_engine::scene::Scene;
use grainbench_engine::system::System;
use std::path::Path;
use std::time::Instant;

/// 3D Hertz–Mindlin scene: gas at Φ = 0.36 compressed at P = 1, inertia cap 0.1.
pub fn scene_3d(n: usize) -> Scene {
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

/// 2D adhesive disks with rolling resistance (GRC07 T.I parameters), compressed at P* = 1,
/// inertia cap 0.05.
pub fn scene_2d(n: usize) -> Scene {
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
max_time = 6.0
criteria = {{ preset = "grc07" }}
"#
    );
    Scene::from_toml(&text, Path::new("bench-adh2d.toml")).expect("2D bench scene")
}

/// The Hertz–Mindlin law of a scene, with the friction kind `f` (as `run::dispatch_law`).
pub fn law_3d<F>(scene: &Scene, f: F) -> HertzMindlin<F> {
    hertz_mindlin_law(&scene.law, f)
}

pub fn law_2d(scene: &Scene) -> Linear<Adhesion, Coulomb, RollingSpring> {
    let law = &scene.law;
    let mu = law.mu().value();
    let cohesion = adhesion(&law.cohesion().expect("cohesive bench scene"));
    let rolling = rolling_spring(law).expect("bench scene with rolling resistance");
    linear_law(law, cohesion, Coulomb { mu }, rolling)
}

/// Overlapping pairs.
pub fn contacts<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>) -> usize {
    sys.interactions().iter().filter(|c| c.gap < 0.0).count()
}

pub fn report<D: Dim, L: ContactLaw<D>>(what: &str, sys: &System<D, L>) {
    let z = contacts(sys);
    eprintln!(
        "{what}: N = {}, Φ = {:.4}, contacts = {z} (z = {:.2}), listed pairs = {}, dt = {:.3e}",
        sys.len(),
        sys.packing_fraction(),
        2.0 * z as f64 / sys.len() as f64,
        sys.nlist.pairs(),
        sys.dt
    );
}

/// Compresses the gas of `scene` until Φ ≥ `phi_stop` (or the step's max_time). The cell
/// stays stress-controlled: at a fixed volume the unequilibrated packing, still below its
/// jamming density, would lose most of its contacts within a few hundred steps.
pub fn prepare<D: Dim, L: ContactLaw<D>>(scene: &Scene, law: L, phi_stop: f64) -> System<D, L> {
    let start = Instant::now();
    let sys = compress_until::<D, L>(scene, law, phi_stop).expect("preparation run");
    report(
        &format!(
            "prepared {} in {} steps, {:.1} s",
            scene.name,
            sys.step,
            start.elapsed().as_secs_f64()
        ),
        &sys,
    );
    sys
}
