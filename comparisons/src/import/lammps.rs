//! Reader of the final state of a LAMMPS run (our decks or any run writing the same dumps,
//! `docs/external-formats/lammps.md`):
//!
//! * `final.atoms`: `dump custom` with columns `id radius mass x y z` (required; `vx vy vz`,
//!   `omegax omegay omegaz` optional, others ignored), `ITEM: TIME` optional (`dump_modify time
//!   yes`; else the time is 0 and only the step is known);
//! * `final.contacts`: `dump local` whose first nine columns are, in this order,
//!   `patom1 patom2` (`compute property/local`) and `dist fx fy fz p1 p2 p3`
//!   (`compute pair/local … cutoff radius` of `pair_style granular`), whatever their names.
//!   `fx fy fz` is the normal force on atom 1 (along x1 − x2, its sign the repulsive one), `p1 p2 p3`
//!   the tangential force on atom 1;
//! * `final.status`: one word (`equilibrium`, `time-limit`), optional.

use super::{last_dump_frame, read_status, ImportError, Meta, Raw, RawContact};
use std::collections::HashMap;
use std::path::Path;

/// Reads the final files of a LAMMPS run in `dir`.
pub fn read_dir(dir: &Path, meta: &Meta) -> Result<Raw, ImportError> {
    let d = meta.dimension;
    let apath = dir.join("final.atoms");
    let atoms = last_dump_frame(&apath)?;
    if atoms.bounds.len() < d {
        return Err(ImportError::new(&apath, "no box bounds in the last frame"));
    }
    let col = |name: &str| atoms.col(&apath, name);
    let opt = |name: &str| atoms.columns.iter().position(|c| c == name);
    let (cid, cr, cm) = (col("id")?, col("radius")?, col("mass")?);
    let cx = [col("x")?, col("y")?, col("z")?];
    let cv = [opt("vx"), opt("vy"), opt("vz")];
    let cw = [opt("omegax"), opt("omegay"), opt("omegaz")];
    let mut rows: Vec<&Vec<f64>> = atoms.rows.iter().collect();
    rows.sort_by(|a, b| a[cid].total_cmp(&b[cid]));
    let index: HashMap<i64, usize> = rows
        .iter()
        .enumerate()
        .map(|(k, r)| (r[cid] as i64, k))
        .collect();
    if index.len() != rows.len() {
        return Err(ImportError::new(&apath, "repeated atom ids"));
    }
    let pick = |r: &Vec<f64>, c: &[Option<usize>; 3]| -> Vec<f64> {
        c.iter().map(|k| k.map_or(0.0, |k| r[k])).collect()
    };
    let mut raw = Raw {
        lengths: atoms.bounds.iter().map(|(lo, hi)| hi - lo).collect(),
        origin: atoms.bounds.iter().map(|(lo, _)| *lo).collect(),
        position: rows
            .iter()
            .map(|r| cx.iter().map(|&k| r[k]).collect())
            .collect(),
        velocity: rows.iter().map(|r| pick(r, &cv)[..d].to_vec()).collect(),
        angular_velocity: rows
            .iter()
            .map(|r| {
                let w = pick(r, &cw);
                if d == 2 {
                    vec![w[2]]
                } else {
                    w
                }
            })
            .collect(),
        radius: rows.iter().map(|r| r[cr]).collect(),
        mass: rows.iter().map(|r| r[cm]).collect(),
        contacts: Vec::new(),
        time: dump_time(&apath)?.unwrap_or(0.0),
        step: atoms.timestep,
        status: read_status(&dir.join("final.status")),
    };
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
    let l = &raw.lengths;
    for r in &pairs.rows {
        let atom = |k: usize| {
            index.get(&(r[k] as i64)).copied().ok_or_else(|| {
                ImportError::new(
                    &cpath,
                    format!("contact names atom {} not in final.atoms", r[k]),
                )
            })
        };
        let (i, j) = (atom(0)?, atom(1)?);
        // Unit vector i → j by the nearest image.
        let mut n: Vec<f64> = (0..d)
            .map(|a| {
                let x = raw.position[j][a] - raw.position[i][a];
                x - l[a] * (x / l[a]).round()
            })
            .collect();
        let len = n.iter().map(|x| x * x).sum::<f64>().sqrt();
        if len == 0.0 {
            return Err(ImportError::new(&cpath, format!("atoms {i}, {j} coincide")));
        }
        n.iter_mut().for_each(|x| *x /= len);
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

/// The value after the last `ITEM: TIME` of a dump (`dump_modify time yes`), if any.
fn dump_time(path: &Path) -> Result<Option<f64>, ImportError> {
    let text = std::fs::read_to_string(path).map_err(|e| ImportError::new(path, e))?;
    let Some(k) = text.rfind("ITEM: TIME\n") else {
        return Ok(None);
    };
    let v = text[k + "ITEM: TIME\n".len()..]
        .lines()
        .next()
        .unwrap_or("")
        .trim();
    v.parse()
        .map(Some)
        .map_err(|e| ImportError::new(path, format!("time {v:?}: {e}")))
}
