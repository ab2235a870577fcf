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
//!   cut-off; rows whose normal force columns are all zero (no interaction) are dropped (with
//!   `rolling sds`, LAMMPS 2025 leaves the tangential columns of such a row at the previous
//!   row's values).
//!   `fx fy fz` is the normal force on atom 1 (along x1 − x2, its sign the repulsive one), `p1 p2 p3`
//!   the tangential force on atom 1;
//! * `final.status`: one word (`equilibrium`, `time-limit`), optional.

use super::{
    last_dump_frame, read_atoms, read_status, unit_normal, DumpSection, ImportError, Meta, Raw,
    RawContact,
};
use std::collections::HashMap;
use std::path::Path;

/// Reads the final files of a LAMMPS run in `dir`.
pub fn read_dir(dir: &Path, meta: &Meta) -> Result<Raw, ImportError> {
    let (mut raw, index) = read_atoms(&dir.join("final.atoms"), meta)?;
    raw.status = read_status(&dir.join("final.status"));
    let cpath = dir.join("final.contacts");
    let pairs = last_dump_frame(&cpath)?;
    raw.contacts = contacts(&cpath, &pairs, &raw, &index, meta)?;
    Ok(raw)
}

/// The contacts of one frame of a contact dump (`final.contacts`, or a frame of the trace's
/// `trace.contacts`) between the grains of `raw` (`index`: atom id → grain).
pub(super) fn contacts(
    cpath: &Path,
    pairs: &DumpSection,
    raw: &Raw,
    index: &HashMap<i64, usize>,
    meta: &Meta,
) -> Result<Vec<RawContact>, ImportError> {
    let d = meta.dimension;
    let mut out = Vec::with_capacity(pairs.rows.len());
    if pairs.columns.len() < 9 {
        return Err(ImportError::new(
            cpath,
            format!(
                "{} columns; want patom1 patom2 dist fx fy fz p1 p2 p3 first",
                pairs.columns.len()
            ),
        ));
    }
    for r in &pairs.rows {
        // Adhesive decks dump every pair within the cut-off: keep those that carry a normal
        // force (a pair out of range has none; its tangential columns may be stale).
        if meta.cohesive && r[3..6].iter().all(|&x| x == 0.0) {
            continue;
        }
        let atom = |k: usize| {
            index.get(&(r[k].round() as i64)).copied().ok_or_else(|| {
                ImportError::new(
                    cpath,
                    format!("contact names atom {}, absent from the atoms dump", r[k]),
                )
            })
        };
        let (i, j) = (atom(0)?, atom(1)?);
        let n = unit_normal(raw, i, j, d)
            .ok_or_else(|| ImportError::new(cpath, format!("atoms {i}, {j} coincide")))?;
        // fx fy fz: normal force on i, along x_i − x_j when repulsive.
        let normal = -(0..d).map(|a| r[3 + a] * n[a]).sum::<f64>();
        // p1 p2 p3: tangential force on i; on j it is the opposite.
        // Read even for μ = 0, so that `assemble` can check the deck.json against them.
        let tangential = (0..d).map(|a| -r[6 + a]).collect();
        out.push(RawContact {
            i,
            j,
            normal,
            normal_elastic: None,
            tangential,
            rolling: Vec::new(),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn meta() -> Meta {
        Meta {
            scene: "t".into(),
            code: "lammps-2025".into(),
            dimension: 2,
            pressure_target: Some(0.01),
            cohesive: true,
            mu: Some(0.5),
            force_unit: "F0".into(),
            n: 3,
            data: Default::default(),
            trace: None,
        }
    }

    /// An adhesive deck's dump lists every pair within the cut-off. Row 2 (ids 1 and 3, 1.5 a
    /// apart) carries no force, but its tangential columns repeat row 1's, as LAMMPS 2025 writes
    /// them with `rolling sds`: it is dropped, and the real contact keeps its forces.
    #[test]
    fn out_of_range_pairs_are_dropped_even_with_stale_tangential_columns() {
        let dir = tempfile::tempdir().unwrap();
        let box_ = "ITEM: BOX BOUNDS pp pp pp\n0 10\n0 10\n-0.5 0.5\n";
        std::fs::write(
            dir.path().join("final.atoms"),
            format!(
                "ITEM: TIMESTEP\n9\nITEM: NUMBER OF ATOMS\n3\n{box_}ITEM: ATOMS id radius mass x y z\n\
                 1 0.5 1 2 5 0\n2 0.5 1 2.999 5 0\n3 0.5 1 3.5 5 0\n"
            ),
        )
        .unwrap();
        std::fs::write(
            dir.path().join("final.contacts"),
            format!(
                "ITEM: TIMESTEP\n9\nITEM: NUMBER OF ENTRIES\n2\n{box_}ITEM: ENTRIES c_prl[1] c_prl[2] c_pl[1] c_pl[2] c_pl[3] c_pl[4] c_pl[5] c_pl[6] c_pl[7]\n\
                 1 2 0.999 0.9 0 0 0 0.02 0\n\
                 1 3 1.5 -0 0 -0 0 0.02 0\n"
            ),
        )
        .unwrap();
        let raw = read_dir(dir.path(), &meta()).unwrap();
        assert_eq!(raw.contacts.len(), 1);
        let c = &raw.contacts[0];
        assert_eq!((c.i, c.j), (0, 1));
        // Force on atom 1 along +x, toward atom 2: attraction (N < 0).
        assert!((c.normal + 0.9).abs() < 1e-12, "{}", c.normal);
        assert!((c.tangential[1] + 0.02).abs() < 1e-12, "{:?}", c.tangential);
    }
}
