//! Reader of the final state of a LAMMPS run (our decks or any run writing the same dumps,
//! `docs/external-formats/lammps.md`):
//!
//! * `final.atoms`: `dump custom` with columns `id radius mass x y z` (required; `vx vy vz`,
//!   `omegax omegay omegaz` optional, others ignored), `ITEM: TIME` optional (`dump_modify time
//!   yes`; else the time is 0 and only the step is known);
//! * `final.contacts`: `dump local` whose first nine columns are, in this order,
//!   `patom1 patom2` (`compute property/local`) and `dist fx fy fz p1 p2 p3`
//!   (`compute pair/local … cutoff radius` of `pair_style granular`), whatever their names.
//!   Adhesive decks (`hybrid/overlay granular lepton/sphere`) dump every pair within the
//!   cut-off; rows whose six force columns are all zero (no interaction) are dropped.
//!   `fx fy fz` is the normal force on atom 1 (along x1 − x2, its sign the repulsive one), `p1 p2 p3`
//!   the tangential force on atom 1;
//! * `final.status`: one word (`equilibrium`, `time-limit`), optional.

use super::{
    last_dump_frame, read_atoms, read_status, unit_normal, ImportError, Meta, Raw, RawContact,
};
use std::path::Path;

/// Reads the final files of a LAMMPS run in `dir`.
pub fn read_dir(dir: &Path, meta: &Meta) -> Result<Raw, ImportError> {
    let d = meta.dimension;
    let (mut raw, index) = read_atoms(&dir.join("final.atoms"), meta)?;
    raw.status = read_status(&dir.join("final.status"));
    let cpath = dir.join("final.contacts");
    let pairs = last_dump_frame(&cpath)?;
    if pairs.columns.len() < 9 {
        return Err(ImportError::new(
            &cpath,
            format!(
                "{} columns; want patom1 patom2 dist fx fy fz p1 p2 p3 first",
                pairs.columns.len()
            ),
        ));
    }
    for r in &pairs.rows {
        // Adhesive decks dump every pair within the cut-off: keep those that carry a force.
        if meta.cohesive && r[3..9].iter().all(|&x| x == 0.0) {
            continue;
        }
        let atom = |k: usize| {
            index.get(&(r[k].round() as i64)).copied().ok_or_else(|| {
                ImportError::new(
                    &cpath,
                    format!("contact names atom {} not in final.atoms", r[k]),
                )
            })
        };
        let (i, j) = (atom(0)?, atom(1)?);
        let n = unit_normal(&raw, i, j, d)
            .ok_or_else(|| ImportError::new(&cpath, format!("atoms {i}, {j} coincide")))?;
        // fx fy fz: normal force on i, along x_i − x_j when repulsive.
        let normal = -(0..d).map(|a| r[3 + a] * n[a]).sum::<f64>();
        // p1 p2 p3: tangential force on i; on j it is the opposite.
        let tangential = if meta.mu == Some(0.0) {
            Vec::new()
        } else {
            (0..d).map(|a| -r[6 + a]).collect()
        };
        raw.contacts.push(RawContact {
            i,
            j,
            normal,
            normal_elastic: None,
            tangential,
            rolling: Vec::new(),
        });
    }
    Ok(raw)
}
