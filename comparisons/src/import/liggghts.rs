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

use super::{last_dump_frame, read_status, DumpSection, ImportError, Meta, Raw, RawContact};
use std::collections::HashMap;
use std::path::Path;

/// Reads the final files of a LIGGGHTS run in `dir`.
pub fn read_dir(dir: &Path, meta: &Meta) -> Result<Raw, ImportError> {
    let apath = dir.join("final.atoms");
    let atoms = last_dump_frame(&apath)?;
    let mut raw = read_atoms(&apath, &atoms, meta)?;
    let cpath = dir.join("final.contacts");
    let contacts = last_dump_frame(&cpath)?;
    raw.contacts = read_contacts(&cpath, &contacts, &raw, meta)?;
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

fn read_atoms(path: &Path, sec: &DumpSection, meta: &Meta) -> Result<Raw, ImportError> {
    if sec.bounds.len() < 3 {
        return Err(ImportError::new(path, "no box bounds in the last frame"));
    }
    let id = sec.col(path, "id")?;
    let rad = sec.col(path, "radius")?;
    let mass = sec.col(path, "mass")?;
    let x = [
        sec.col(path, "x")?,
        sec.col(path, "y")?,
        sec.col(path, "z")?,
    ];
    let opt = |names: [&str; 3]| -> Option<[usize; 3]> {
        let c: Vec<usize> = names
            .iter()
            .filter_map(|n| sec.columns.iter().position(|c| c == n))
            .collect();
        (c.len() == 3).then(|| [c[0], c[1], c[2]])
    };
    let v = opt(["vx", "vy", "vz"]);
    let w = opt(["omegax", "omegay", "omegaz"]);
    let d = meta.dimension;
    let mut rows: Vec<&Vec<f64>> = sec.rows.iter().collect();
    rows.sort_by(|a, b| a[id].total_cmp(&b[id]));
    if meta.n != 0 && rows.len() != meta.n {
        return Err(ImportError::new(
            path,
            format!("{} atoms, deck.json says {}", rows.len(), meta.n),
        ));
    }
    let mut raw = Raw {
        lengths: sec.bounds.iter().map(|(lo, hi)| hi - lo).collect(),
        origin: sec.bounds.iter().map(|(lo, _)| *lo).collect(),
        step: sec.timestep,
        ..Raw::default()
    };
    for r in rows {
        raw.position.push(x[..d].iter().map(|&c| r[c]).collect());
        raw.radius.push(r[rad]);
        raw.mass.push(r[mass]);
        raw.velocity
            .push(v.map_or(vec![0.0; d], |c| c[..d].iter().map(|&k| r[k]).collect()));
        if let Some(c) = w {
            // 2D: the spin is about z.
            raw.angular_velocity.push(if d == 2 {
                vec![r[c[2]]]
            } else {
                c.iter().map(|&k| r[k]).collect()
            });
        }
    }
    Ok(raw)
}

fn read_contacts(
    path: &Path,
    sec: &DumpSection,
    raw: &Raw,
    meta: &Meta,
) -> Result<Vec<RawContact>, ImportError> {
    let d = meta.dimension;
    // Index of grain ids: the atoms dump's ids, sorted, as read.
    let apath = path.with_file_name("final.atoms");
    let ids = {
        let atoms = last_dump_frame(&apath)?;
        let c = atoms.col(&apath, "id")?;
        let mut v: Vec<i64> = atoms.rows.iter().map(|r| r[c].round() as i64).collect();
        v.sort_unstable();
        v.into_iter()
            .enumerate()
            .map(|(k, id)| (id, k))
            .collect::<HashMap<i64, usize>>()
    };
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
                    format!("contact names id {id}, absent from final.atoms"),
                )
            })
        };
        let (i, j) = (look(ci)?, look(cj)?);
        let f_on_i = [r[cf], r[cf + 1], r[cf + 2]];
        // Unit vector i → j by the nearest image.
        let mut n: Vec<f64> = (0..d)
            .map(|a| {
                let x = raw.position[j][a] - raw.position[i][a];
                let l = raw.lengths[a];
                x - l * (x / l).round()
            })
            .collect();
        let dist = n.iter().map(|x| x * x).sum::<f64>().sqrt();
        if dist == 0.0 {
            return Err(ImportError::new(
                path,
                format!("contact ({i}, {j}) joins coincident grains"),
            ));
        }
        n.iter_mut().for_each(|x| *x /= dist);
        // Force on j = −(force on i); normal repulsive positive = (force on j)·n.
        let f_on_j: Vec<f64> = (0..d).map(|a| -f_on_i[a]).collect();
        let normal: f64 = (0..d).map(|a| f_on_j[a] * n[a]).sum();
        let tangential: Vec<f64> = if meta.mu == Some(0.0) {
            Vec::new()
        } else {
            (0..d).map(|a| f_on_j[a] - normal * n[a]).collect()
        };
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
