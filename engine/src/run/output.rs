//! The snapshot of a system: what a run writes.

use super::checkpoint;
use crate::contact::ContactLaw;
use crate::geometry::{Dim, VectorOps as _};
use crate::plan::Plan;
use crate::scene::Mu;
use crate::snapshot::{self, Snapshot, Vector};
use crate::system::System;

/// The snapshot of the current state of a run of `plan` (the law's force unit, μ and
/// attraction; `pressure_target`, the pressure last prescribed).
pub fn snapshot_of<D: Dim, L: ContactLaw<D>>(
    sys: &System<D, L>,
    plan: &Plan,
    status: &str,
    pressure_target: Option<f64>,
) -> Snapshot {
    let n = sys.len();
    let cohesive = plan.cohesive;
    let mu = match plan.mu {
        Mu::Finite(x) => Some(x),
        Mu::Infinite => None,
    };
    let omega = sys.cell.volume();
    let tensor = |t: &crate::geometry::Tensor| -> Vec<Vec<f64>> {
        (0..D::D)
            .map(|a| (0..D::D).map(|b| t[a][b] / omega).collect())
            .collect()
    };
    // Straight into the snapshot's list, without an intermediate list of interactions: the
    // peak memory of large packings.
    let mut contacts = Vec::new();
    sys.for_each_interaction(|c| {
        contacts.push(snapshot::Contact {
            i: c.i,
            j: c.j,
            branch: c.branch.components(),
            normal: c.normal,
            normal_elastic: c.normal_elastic,
            tangential: if L::MOMENTS {
                c.tangential.components()
            } else {
                Vector::new()
            },
            rolling: if L::ROLLING {
                c.rolling.components()
            } else {
                Vector::new()
            },
            gap: c.gap,
        })
    });
    Snapshot {
        format: snapshot::FORMAT.into(),
        version: snapshot::VERSION,
        code: checkpoint::code(),
        scene: plan.scene.clone(),
        dimension: D::D,
        time: sys.time,
        step: sys.step,
        status: status.into(),
        force_unit: if cohesive {
            "F0".into()
        } else {
            format!("P_ref a^{}", D::D - 1)
        },
        pressure_target,
        cohesive: plan.attractive,
        mu,
        cell: snapshot::Cell {
            lengths: sys.cell.l.to_vec(),
            contact_stress: tensor(&sys.contact_virial),
            kinetic_stress: tensor(&sys.kinetic_virial),
        },
        particles: snapshot::Particles {
            radius: sys.radius.clone(),
            mass: sys.mass.clone(),
            position: (0..n).map(|i| sys.position(i).components()).collect(),
            velocity: sys.u.iter().map(|v| v.components()).collect(),
            angular_velocity: if L::MOMENTS {
                sys.w.iter().map(|w| w.components()).collect()
            } else {
                Vec::new()
            },
        },
        contacts,
    }
}
