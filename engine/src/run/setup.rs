//! From a scene to a system: the initial grains, the cell mass, the time step.

use super::grains::Grains;
use crate::cell::Cell;
use crate::contact::ContactLaw;
use crate::geometry::{Dim, VectorOps as _};
use crate::init::{maxwell_velocities_spread, random_gas};
use crate::plan;
use crate::protocols::lattice;
use crate::scene::{Arrangement, Maxwell, Scene};
use crate::snapshot::Snapshot;
use crate::system::System;

/// The initial grains of a scene: random gas (GRC07 §III.A) or FCC lattice (AR07 §III).
pub fn initial_grains<D: Dim>(scene: &Scene) -> Result<Grains<D>, String> {
    let n = scene.particles.count;
    if let Some(path) = &scene.initial.snapshot {
        return snapshot_grains(path, n);
    }
    let cell = scene.initial.cell.as_deref().unwrap_or_default();
    if let Some(path) = &scene.initial.particles {
        return super::particles_file::read::<D>(path, cell, n);
    }
    if let Some(grains) = &scene.initial.grains {
        return super::particles_file::inline::<D>(grains, cell, n);
    }
    let (l, s, diameter) = match scene.initial.arrangement {
        Arrangement::Random => {
            let gas = random_gas::<D>(
                n,
                scene.particles.min_diameter,
                scene.particles.classes,
                scene.initial.packing_fraction,
                scene.seed,
            )?;
            (gas.l, gas.s, gas.diameter)
        }
        Arrangement::Fcc => {
            let k = lattice::fcc_cells_for(n).ok_or("FCC needs 4k³ grains")?;
            let (side, pos) = lattice::fcc(k, scene.initial.packing_fraction);
            let mut l = D::V::zero();
            for a in 0..D::D {
                l[a] = side;
            }
            let s = pos.iter().map(|p| D::from_slice(p.as_slice())).collect();
            (l, s, vec![1.0; n])
        }
    };
    let mass: Vec<f64> = diameter.iter().map(|d| d.powi(D::D as i32)).collect();
    let u = if scene.initial.rms_velocity > 0.0 {
        let rms = scene.initial.rms_velocity;
        let (rms, equipartition) = match scene.initial.maxwell {
            Maxwell::Equipartition => (rms, true),
            Maxwell::MassIndependent => (rms, false),
            Maxwell::PerComponent => (rms * (D::D as f64).sqrt(), false),
        };
        maxwell_velocities_spread::<D>(&mass, rms, scene.seed, equipartition)
    } else {
        vec![D::V::zero(); n]
    };
    Ok(Grains {
        l,
        s,
        u,
        w: Vec::new(),
        diameter,
        time: 0.0,
        step: 0,
    })
}

/// The grains of a snapshot file, at rest (`initial.snapshot`).
fn snapshot_grains<D: Dim>(path: &std::path::Path, n: usize) -> Result<Grains<D>, String> {
    let snap = Snapshot::read(path).map_err(|e| format!("initial.snapshot: {e}"))?;
    let p = &snap.particles;
    if snap.dimension != D::D || p.radius.len() != n {
        return Err(format!(
            "initial.snapshot {}: holds {} grains in {}D, the scene wants {n} in {}D (particles.count, dimension)",
            path.display(),
            p.radius.len(),
            snap.dimension,
            D::D
        ));
    }
    let mut l = D::V::zero();
    for a in 0..D::D {
        l[a] = snap.cell.lengths[a];
    }
    let s = p
        .position
        .iter()
        .map(|r| {
            let mut x = D::V::zero();
            for a in 0..D::D {
                x[a] = (r[a] / l[a]).rem_euclid(1.0);
            }
            x
        })
        .collect();
    Ok(Grains {
        l,
        s,
        u: vec![D::V::zero(); n],
        w: Vec::new(),
        diameter: p.radius.iter().map(|r| 2.0 * r).collect(),
        time: 0.0,
        step: 0,
    })
}

/// Generalized mass of the cell, AR07 (7): `numerics.cell_mass` × the total grain mass,
/// divided by the cell's linear size when `cell_mass_per_length` (GRC07 §II.A).
pub fn cell_mass(numerics: &crate::scene::Numerics, total_mass: f64, volume: f64, d: usize) -> f64 {
    let m = numerics.cell_mass * total_mass;
    if numerics.cell_mass_per_length {
        m / volume.powf(1.0 / d as f64)
    } else {
        m
    }
}

/// The system of a scene's initial grains for a law (as the first stage of a scene that starts
/// with a DEM stage sees it).
pub fn build_system<D: Dim, L: ContactLaw<D>>(
    scene: &Scene,
    law: L,
) -> Result<System<D, L>, String> {
    system_of(scene, law, &initial_grains::<D>(scene)?)
}

/// A system holding `grains`, with the law, cell mass and time step of the scene.
pub fn system_of<D: Dim, L: ContactLaw<D>>(
    scene: &Scene,
    law: L,
    grains: &Grains<D>,
) -> Result<System<D, L>, String> {
    let total_mass: f64 = grains.diameter.iter().map(|d| d.powi(D::D as i32)).sum();
    let cell_mass = cell_mass(&scene.numerics, total_mass, D::product(grains.l), D::D);
    let mut cell = Cell::new(grains.l, cell_mass);
    cell.affine_velocity = scene.numerics.affine_velocity;
    let mut sys = System::new(
        law,
        cell,
        grains.s.clone(),
        &grains.diameter,
        scene.numerics.skin,
    );
    sys.u.clone_from(&grains.u);
    if !grains.w.is_empty() {
        sys.w.clone_from(&grains.w);
    }
    sys.time = grains.time;
    sys.step = grains.step;
    sys.dt = time_step(scene, &sys).0;
    sys.check_cell()?;
    Ok(sys)
}

/// The time step of `sys` with the numerics of `scene` ([`plan::time_step`] at the law's κ,
/// as [`plan::Plan::dt`]). Returns (dt, K_max).
pub fn time_step<D: Dim, L: ContactLaw<D>>(scene: &Scene, sys: &System<D, L>) -> (f64, f64) {
    plan::time_step(
        &sys.law,
        &sys.mass,
        &sys.radius,
        scene.numerics.dt_fraction,
        plan::stiffness_force(scene),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::D2;

    /// `initial.maxwell` reaches the draw: mass-independent speeds the largest grains up,
    /// relative to the smallest, by the ratio of their masses (in mean v²).
    #[test]
    fn the_scene_chooses_the_maxwell_spread() {
        let text = |spread: &str| {
            format!(
                "name = \"m\"\ndimension = 2\n[particles]\ncount = 4000\nmin_diameter = 0.5\n\
                 [law]\nkind = \"linear\"\nkappa = 1e4\nmu = 0.5\nzeta = 0.8\ncohesion = {{ d0 = 1e-3 }}\n\
                 [initial]\npacking_fraction = 0.2\nrms_velocity = 0.3\n{spread}\n\
                 [[protocol]]\nkind = \"aggregate\"\nmax_time = 1.0\n"
            )
        };
        let grains = |spread: &str| {
            let scene = Scene::from_toml(&text(spread), std::path::Path::new("m.toml")).unwrap();
            initial_grains::<D2>(&scene).unwrap()
        };
        // mean v² of the grains with d > 0.9 over those with d < 0.6.
        let ratio = |spread: &str| {
            let g = grains(spread);
            let mean = |keep: &dyn Fn(f64) -> bool| {
                let v: Vec<f64> = (0..g.u.len())
                    .filter(|&i| keep(g.diameter[i]))
                    .map(|i| g.u[i].norm_squared())
                    .collect();
                v.iter().sum::<f64>() / v.len() as f64
            };
            mean(&|d| d > 0.9) / mean(&|d| d < 0.6)
        };
        let equi = ratio("");
        let blind = ratio("maxwell = \"mass-independent\"");
        assert!(equi < 0.45, "equipartition: heavy grains slower, {equi}");
        assert!((blind - 1.0).abs() < 0.15, "mass-independent: {blind}");
        // Per component: mass-independent, and each of the two components spread by 0.3.
        let spread = "maxwell = \"per-component\"";
        assert!((ratio(spread) - 1.0).abs() < 0.15, "per-component");
        for (kind, want) in [("", 0.09), (spread, 0.18)] {
            let g = grains(kind);
            let msq = g.u.iter().map(|v| v.norm_squared()).sum::<f64>() / g.u.len() as f64;
            assert!((msq / want - 1.0).abs() < 1e-12, "{kind:?}: mean v² {msq}");
        }
    }
}
