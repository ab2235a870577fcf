//! The pressure programs of a scene (GRC08 §II.D.2 cycles; the stepped loading of GRC07
//! series B; AR07's quasi-static compression): which stages end a level, at what pressure.

use grainbench_engine::scene::Step;
use grainbench_engine::Scene;

/// Whether a scene runs pressure programs (GRC08 §II.D.2 cycles; the stepped loading of
/// GRC07 series B; AR07's quasi-static compression).
pub fn has_program(scene: &Scene) -> bool {
    scene
        .protocol
        .iter()
        .any(|s| matches!(s, Step::PressureProgram { .. }))
}

/// The levels of the scene's pressure programs: (stage, whether its program loads, pressure).
pub(super) fn program_levels(scene: &Scene) -> Vec<(usize, bool, f64)> {
    scene
        .stages()
        .into_iter()
        .enumerate()
        .filter_map(|(stage, (k, step))| {
            let Step::PressureProgram { from, to, .. } = &scene.protocol[k] else {
                return None;
            };
            let Step::Compress { pressure, .. } = step else {
                return None;
            };
            Some((stage, to > from, pressure))
        })
        .collect()
}

/// The stage that ends the first program level at `pressure` (relative tolerance 1e-9), if
/// the scene has one.
pub fn program_stage(scene: &Scene, pressure: f64) -> Option<usize> {
    program_levels(scene)
        .into_iter()
        .find(|&(_, _, p)| (p - pressure).abs() <= 1e-9 * pressure.abs())
        .map(|(stage, _, _)| stage)
}
