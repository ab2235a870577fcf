//! Reader of the final state of a LIGGGHTS run (`docs/external-formats/liggghts.md`):
//!
//! * `final.atoms`: `dump custom` with columns `id radius mass x y z` (required) and
//!   `vx vy vz omegax omegay omegaz` (optional), box bounds in the frame header;
//! * `final.contacts`: `dump local` of `compute pair/gran/local id force …` (the compute
//!   writes `id1 id2 periodic-flag fx fy fz` first whenever `pos`/`vel` are not requested;
//!   with them, 12 columns come first), the force being the force on grain id1;
//! * `final.status` (optional): `equilibrium` / `time-limit`; `final.time` (optional): time
//!   and step.
//!
//! The last frame of each dump is read; ids become 0-based indices in id order.

use super::{
    last_dump_frame, read_atoms, read_status, unit_normal, DumpSection, ImportError, Meta, Raw,
    RawContact,
};
use std::collections::HashMap;
use std::path::Path;

/// Reads the final files of a LIGGGHTS run in `dir`.
pub fn read_dir(dir: &Path, meta: &Meta) -> Result<Raw, ImportError> {
    let (mut raw, ids) = read_atoms(&dir.join("final.atoms"), meta)?;
    let cpath = dir.join("final.contacts");
    let contacts = last_dump_frame(&cpath)?;
    raw.contacts = read_contacts(&cpath, &contacts, &raw, &ids, meta)?;
    raw.status = read_status(&dir.join("final.status"));
    if let Ok(t) = std::fs::read_to_string(dir.join("final.time")) {
        let v: Vec<f64> = t
            .split_whitespace()
            .filter_map(|x| x.parse().ok())
            .collect();
        if let Some(&time) = v.first() {
            raw.time = time;
        }
    }
    Ok(raw)
}

/// The contacts of one frame of a `pair/gran/local` dump (`final.contacts`, or a frame of the
/// trace's `trace.contacts`) between the grains of `raw` (`ids`: atom id → grain).
pub(super) fn read_contacts(
    path: &Path,
    sec: &DumpSection,
    raw: &Raw,
    ids: &HashMap<i64, usize>,
    meta: &Meta,
) -> Result<Vec<RawContact>, ImportError> {
    let d = meta.dimension;
    // Columns: id1 id2 flag fx fy fz, after pos (6) when the dump has `pos` (12+ columns with
    // positions written first is recognised by named columns only, see the format doc).
    let named = |n: &str| sec.columns.iter().position(|c| c == n);
    let (ci, cj, cf) = match (named("id1"), named("id2"), named("fx")) {
        (Some(i), Some(j), Some(f)) => (i, j, f),
        _ => {
            if sec.columns.len() < 6 {
                return Err(ImportError::new(
                    path,
                    format!(
                        "{} columns; expected `compute pair/gran/local id force`: id1 id2 periodic fx fy fz",
                        sec.columns.len()
                    ),
                ));
            }
            (0, 1, 3)
        }
    };
    let mut out = Vec::with_capacity(sec.rows.len());
    for r in &sec.rows {
        let look = |c: usize| -> Result<usize, ImportError> {
            let id = r[c].round() as i64;
            ids.get(&id).copied().ok_or_else(|| {
                ImportError::new(
                    path,
                    format!("contact names id {id}, absent from the atoms dump"),
                )
            })
        };
        let (i, j) = (look(ci)?, look(cj)?);
        let f_on_i = [r[cf], r[cf + 1], r[cf + 2]];
        let n = unit_normal(raw, i, j, d).ok_or_else(|| {
            ImportError::new(path, format!("contact ({i}, {j}) joins coincident grains"))
        })?;
        // Force on j = −(force on i); normal repulsive positive = (force on j)·n.
        let f_on_j: Vec<f64> = (0..d).map(|a| -f_on_i[a]).collect();
        let normal: f64 = (0..d).map(|a| f_on_j[a] * n[a]).sum();
        // Read even for μ = 0, so that `assemble` can check the deck.json against them.
        let tangential: Vec<f64> = (0..d).map(|a| f_on_j[a] - normal * n[a]).collect();
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
            code: "liggghts".into(),
            dimension: 3,
            pressure_target: Some(1.0),
            cohesive: false,
            mu: Some(0.5),
            force_unit: "P_ref a^2".into(),
            n: 2,
            data: Default::default(),
            trace: None,
        }
    }

    /// A hand-written pair of dumps: grain id 7 at x = 9.8, id 3 at x = 0.6 (images across the
    /// boundary, i → j along −x), force on id1 = 7 pushing it −x, away from id 3 (repulsion), plus a y part.
    #[test]
    fn signs_and_periodic_images() {
        let dir = tempfile::tempdir().unwrap();
        let box_ = "ITEM: BOX BOUNDS pp pp pp\n0 10\n0 10\n0 10\n";
        std::fs::write(
            dir.path().join("final.atoms"),
            format!(
                "ITEM: TIMESTEP\n5\nITEM: NUMBER OF ATOMS\n2\n{box_}ITEM: ATOMS id radius mass x y z vx vy vz omegax omegay omegaz\n\
                 7 0.5 1 9.8 5 5 0 0 0 0 0 1\n3 0.5 1 0.6 5 5 1 0 0 0 0 0\n"
            ),
        )
        .unwrap();
        std::fs::write(
            dir.path().join("final.contacts"),
            format!(
                "ITEM: TIMESTEP\n5\nITEM: NUMBER OF ENTRIES\n1\n{box_}ITEM: ENTRIES c_pgl[1] c_pgl[2] c_pgl[3] c_pgl[4] c_pgl[5] c_pgl[6] c_pgl[7]\n\
                 7 3 1 -2.5 0.25 0 0.2\n"
            ),
        )
        .unwrap();
        std::fs::write(dir.path().join("final.status"), "equilibrium\n").unwrap();
        let raw = read_dir(dir.path(), &meta()).unwrap();
        // ids sorted: 3 → 0, 7 → 1.
        assert_eq!(raw.position[0], vec![0.6, 5.0, 5.0]);
        assert_eq!(raw.velocity[0], vec![1.0, 0.0, 0.0]);
        assert_eq!(raw.angular_velocity[1], vec![0.0, 0.0, 1.0]);
        assert_eq!(raw.step, 5);
        assert_eq!(raw.status, "equilibrium");
        let c = &raw.contacts[0];
        assert_eq!((c.i, c.j), (1, 0));
        // n (7 → 3 through the boundary) = +x; force on j = (2.5, −0.25, 0).
        assert!((c.normal - 2.5).abs() < 1e-12, "{}", c.normal);
        assert!((c.tangential[0]).abs() < 1e-12 && (c.tangential[1] + 0.25).abs() < 1e-12);
    }
}
