//! Reader of the trace a deck writes when its scene sets `output.trace_every`: every
//! so many steps each grain's position, velocity, spin and net force —
//!
//! * LAMMPS and LIGGGHTS: `trace.atoms`, a multi-frame `dump custom` with columns `id radius
//!   mass x y z vx vy vz omegax omegay omegaz fx fy fz` (LAMMPS adds `ITEM: TIME`; else the
//!   time is the step × the deck's one time step, `deck.json` `trace.dt`);
//! * YADE: `trace.txt`, `frame ITER TIME LX LY LZ` lines, each followed by one line per body
//!   `id radius mass x y z vx vy vz wx wy wz fx fy fz`.
//!
//! * a code of the exchange format: `trace-grains.csv` and `trace-contacts.csv` in its output
//!   directory (`docs/exchange-format.md`), contacts included.
//!
//! The other codes write no per-contact history, so the contact of a **two-grain** trace is
//! rebuilt from the net force on grain 1 (the only force on it): in contact while the grains
//! overlap, normal force f₁·n with n from grain 0 to 1, tangential force f₁ − (f₁·n)n. A trace
//! of more grains from them keeps the grains only.

use super::{
    assemble, atoms_of, branch, dump_frames, DumpSection, ImportError, Meta, Raw, RawContact,
};
use crate::xcode::code::Code;
use grainbench_engine::snapshot::Snapshot;
use std::collections::HashMap;
use std::path::Path;

/// A frame's grains, the net force on each, and whether the code listed its contacts.
type Frame = (Raw, Vec<Vec<f64>>, bool);

/// The frames of the trace in `dir`, in time order; `None` if the deck wrote none.
pub fn read(code: Code, dir: &Path, meta: &Meta) -> Result<Option<Vec<Snapshot>>, ImportError> {
    let Some(t) = &meta.trace else {
        return Ok(None);
    };
    let path = dir.join(&t.file);
    let frames: Vec<Frame> = match code {
        Code::Lammps | Code::Lammps2025 | Code::Liggghts => {
            // The contact dump's frames by step (decks written before it existed have none).
            let cpath = t.contacts.as_ref().map(|c| dir.join(c));
            let mut pairs: HashMap<u64, DumpSection> = match &cpath {
                Some(p) if p.exists() => dump_frames(p)?
                    .into_iter()
                    .map(|f| (f.timestep, f))
                    .collect(),
                _ => HashMap::new(),
            };
            let mut out = Vec::new();
            for sec in dump_frames(&path)? {
                let (mut raw, index) = atoms_of(&path, &sec, meta)?;
                raw.time = match (sec.time, t.dt) {
                    (Some(time), _) => time,
                    (None, Some(dt)) => sec.timestep as f64 * dt,
                    (None, None) => {
                        return Err(ImportError::new(
                            &path,
                            "frames without `ITEM: TIME`, and deck.json gives no single time step (trace.dt) to time them by",
                        ))
                    }
                };
                let f = ["fx", "fy", "fz"]
                    .iter()
                    .map(|c| sec.col(&path, c))
                    .collect::<Result<Vec<_>, _>>()?;
                // In the order of `raw` (by id), as `atoms_of` put the grains.
                let id = sec.col(&path, "id")?;
                let mut forces = vec![Vec::new(); sec.rows.len()];
                for r in &sec.rows {
                    forces[index[&(r[id].round() as i64)]] =
                        f[..meta.dimension].iter().map(|&c| r[c]).collect();
                }
                let listed = match (pairs.remove(&sec.timestep), &cpath) {
                    (Some(p), Some(cp)) => {
                        raw.contacts = if code == Code::Liggghts {
                            super::liggghts::read_contacts(cp, &p, &raw, &index, meta)?
                        } else {
                            super::lammps::contacts(cp, &p, &raw, &index, meta)?
                        };
                        true
                    }
                    _ => false,
                };
                out.push((raw, forces, listed));
            }
            out
        }
        Code::Yade => yade_frames(&path, meta)?,
        // The exchange format's trace carries its contacts, for any number of grains.
        Code::Generic | Code::Adapter(_) => {
            let out = path.parent().unwrap_or(dir);
            return super::generic::read_trace(out, meta, t.dt)?
                .into_iter()
                .map(|raw| assemble(raw, meta).map_err(|m| ImportError::new(out, m)))
                .collect::<Result<Vec<_>, _>>()
                .map(Some);
        }
        other => {
            return Err(ImportError::new(
                &path,
                format!("{other} writes no trace this reader knows"),
            ))
        }
    };
    let mut snaps = Vec::with_capacity(frames.len());
    for (mut raw, forces, listed) in frames {
        raw.status = "trace".into();
        if !listed && raw.position.len() == 2 {
            raw.contacts = two_grain_contact(&raw, &forces[1], meta.dimension);
        }
        snaps.push(assemble(raw, meta).map_err(|m| ImportError::new(&path, m))?);
    }
    Ok(Some(snaps))
}

/// The contact of grains 0 and 1 from the net force `f1` on grain 1, if they overlap.
fn two_grain_contact(raw: &Raw, f1: &[f64], d: usize) -> Vec<RawContact> {
    let b = branch(&raw.position, &raw.lengths, 0, 1, d);
    let dist = b.iter().map(|x| x * x).sum::<f64>().sqrt();
    if dist == 0.0 || dist >= raw.radius[0] + raw.radius[1] {
        return Vec::new();
    }
    let n: Vec<f64> = b.iter().map(|x| x / dist).collect();
    let normal: f64 = (0..d).map(|a| f1[a] * n[a]).sum();
    vec![RawContact {
        i: 0,
        j: 1,
        normal,
        normal_elastic: None,
        tangential: (0..d).map(|a| f1[a] - normal * n[a]).collect(),
        rolling: Vec::new(),
    }]
}

/// The frames of YADE's `trace.txt`, each with the force on every body.
fn yade_frames(path: &Path, meta: &Meta) -> Result<Vec<Frame>, ImportError> {
    let text = std::fs::read_to_string(path).map_err(|e| ImportError::new(path, e))?;
    let d = meta.dimension;
    let mut frames: Vec<Frame> = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let at = k + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = |what: String| ImportError::new(path, format!("line {at}: {what}"));
        let num = |x: &str| {
            x.parse::<f64>()
                .map_err(|e| bad(format!("{x:?}: {e}")))
                .and_then(|v| {
                    v.is_finite()
                        .then_some(v)
                        .ok_or_else(|| bad(format!("{x} is not finite: the run failed")))
                })
        };
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields[0] == "frame" {
            if fields.len() != 6 {
                return Err(bad("want `frame ITER TIME LX LY LZ` (6 fields)".to_string()));
            }
            let raw = Raw {
                step: fields[1]
                    .parse()
                    .map_err(|e| bad(format!("iteration {:?}: {e}", fields[1])))?,
                time: num(fields[2])?,
                lengths: fields[3..6]
                    .iter()
                    .map(|x| num(x))
                    .collect::<Result<_, _>>()?,
                ..Raw::default()
            };
            frames.push((raw, Vec::new(), false));
            continue;
        }
        let Some((raw, forces, listed)) = frames.last_mut() else {
            return Err(bad("a body before the first `frame` line".into()));
        };
        if fields[0] == "contact" {
            // `contact id1 id2 fn tx ty tz`, as final.interactions (bodies listed first).
            if fields.len() != 7 {
                return Err(bad(format!(
                    "{} fields; want `contact id1 id2 fn tx ty tz` (7)",
                    fields.len()
                )));
            }
            let body = |x: &str| -> Result<usize, ImportError> {
                x.parse::<usize>()
                    .ok()
                    .filter(|&k| k < raw.position.len())
                    .ok_or_else(|| bad(format!("contact names body {x}, not listed in its frame")))
            };
            let v: Vec<f64> = fields[3..]
                .iter()
                .map(|x| num(x))
                .collect::<Result<_, _>>()?;
            raw.contacts.push(RawContact {
                i: body(fields[1])?,
                j: body(fields[2])?,
                normal: v[0],
                normal_elastic: None,
                tangential: if meta.mu == Some(0.0) {
                    Vec::new()
                } else {
                    v[1..1 + d].to_vec()
                },
                rolling: Vec::new(),
            });
            *listed = true;
            continue;
        }
        if fields.len() != 15 {
            return Err(bad(format!(
                "{} fields; want id radius mass x y z vx vy vz wx wy wz fx fy fz (15)",
                fields.len()
            )));
        }
        let v: Vec<f64> = fields[1..]
            .iter()
            .map(|x| num(x))
            .collect::<Result<_, _>>()?;
        raw.radius.push(v[0]);
        raw.mass.push(v[1]);
        raw.position.push(v[2..2 + d].to_vec());
        raw.velocity.push(v[5..5 + d].to_vec());
        raw.angular_velocity.push(v[8..11].to_vec());
        forces.push(v[11..11 + d].to_vec());
    }
    if frames.is_empty() {
        return Err(ImportError::new(
            path,
            "no `frame` line: no trace was written",
        ));
    }
    // A trace with contact lines lists every frame's contacts, none in some frames.
    if frames.iter().any(|f| f.2) {
        frames.iter_mut().for_each(|f| f.2 = true);
    }
    for (k, (raw, _, _)) in frames.iter().enumerate() {
        if meta.n != 0 && raw.position.len() != meta.n {
            return Err(ImportError::new(
                path,
                format!(
                    "frame {k} (iteration {}) has {} bodies, deck.json says {}: the trace is cut short",
                    raw.step,
                    raw.position.len(),
                    meta.n
                ),
            ));
        }
    }
    Ok(frames)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::xcode::import::TraceMeta;

    fn meta(file: &str) -> Meta {
        Meta {
            scene: "t".into(),
            code: "yade".into(),
            dimension: 3,
            pressure_target: None,
            cohesive: false,
            mu: Some(0.3),
            force_unit: "P_ref a^2".into(),
            n: 2,
            data: Default::default(),
            trace: Some(TraceMeta {
                file: file.into(),
                every: 1,
                dt: Some(0.5),
                contacts: None,
            }),
        }
    }

    /// Two frames: apart, then overlapping by 0.01 with a force on grain 1 of 2 along the line
    /// of centres (repulsive) and 0.3 across it.
    #[test]
    fn yade_frames_rebuild_the_two_grain_contact() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("trace.txt"),
            "# header\nframe 0 0.0 20 20 20\n\
             0 0.5 1 5 5 5 0 0 0 0 0 0 0 0 0\n1 0.5 1 6.2 5 5 -1 0 0 0 0 0 0 0 0\n\
             frame 1 0.1 20 20 20\n\
             0 0.5 1 5 5 5 0 0 0 0 0 1 -2 -0.3 0\n1 0.5 1 5.99 5 5 -1 0 0 0 0 1 2 0.3 0\n",
        )
        .unwrap();
        let frames = read(Code::Yade, dir.path(), &meta("trace.txt"))
            .unwrap()
            .unwrap();
        assert_eq!(frames.len(), 2);
        assert!(frames[0].contacts.is_empty());
        let c = &frames[1].contacts[0];
        assert!(
            (c.normal - 2.0).abs() < 1e-12 && (c.gap + 0.01).abs() < 1e-12,
            "{c:?}"
        );
        assert!((c.tangential[1] - 0.3).abs() < 1e-12, "{c:?}");
        assert_eq!(
            frames[1].particles.angular_velocity[1].as_slice(),
            [0.0, 0.0, 1.0]
        );
        assert_eq!(frames[1].time, 0.1);
    }

    /// A LAMMPS/LIGGGHTS trace without `ITEM: TIME` is timed by step × dt; with it, by it.
    #[test]
    fn dump_frames_are_timed_and_a_cut_trace_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let frame = |step: u64, x1: f64| {
            format!(
                "ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp pp\n0 20\n0 20\n0 20\n\
                 ITEM: ATOMS id radius mass x y z vx vy vz omegax omegay omegaz fx fy fz\n\
                 1 0.5 1 5 5 5 0 0 0 0 0 0 -1 0 0\n2 0.5 1 {x1} 5 5 -1 0 0 0 0 0 1 0 0\n"
            )
        };
        let path = dir.path().join("trace.atoms");
        std::fs::write(&path, frame(0, 6.5) + &frame(4, 5.98)).unwrap();
        let m = meta("trace.atoms");
        let f = read(Code::Liggghts, dir.path(), &m).unwrap().unwrap();
        assert_eq!((f[0].time, f[1].time), (0.0, 2.0));
        assert_eq!(f[1].contacts.len(), 1);
        std::fs::write(
            &path,
            format!(
                "ITEM: TIME\n0.25\n{}ITEM: TIME\n0.75\n{}",
                frame(0, 6.5),
                frame(4, 5.98)
            ),
        )
        .unwrap();
        let f = read(Code::Lammps, dir.path(), &m).unwrap().unwrap();
        assert_eq!((f[0].time, f[1].time), (0.25, 0.75));
        let cut = frame(0, 6.5) + &frame(4, 5.98)[..150];
        std::fs::write(&path, cut).unwrap();
        let e = read(Code::Lammps, dir.path(), &m).unwrap_err();
        assert!(e.to_string().contains("trace.atoms"), "{e}");
    }

    /// Three bodies: YADE lists each frame's contacts (`contact id1 id2 fn tx ty tz`), and a
    /// frame without contact lines has none, even where two grains would overlap.
    #[test]
    fn yade_frames_read_their_contact_lines() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("trace.txt"),
            "frame 0 0.0 20 20 20\n\
             0 0.5 1 5 5 5 0 0 0 0 0 0 0 0 0\n1 0.5 1 5.99 5 5 0 0 0 0 0 0 0 0 0\n\
             2 0.5 1 7 5 5 0 0 0 0 0 0 0 0 0\n\
             frame 1 0.1 20 20 20\n\
             0 0.5 1 5 5 5 0 0 0 0 0 0 -2 0 0\n1 0.5 1 5.99 5 5 0 0 0 0 0 0 1 0 0\n\
             2 0.5 1 6.98 5 5 0 0 0 0 0 0 1 0 0\n\
             contact 0 1 2 0 0.25 0\ncontact 1 2 1 0 0 0\n",
        )
        .unwrap();
        let mut m = meta("trace.txt");
        m.n = 3;
        let f = read(Code::Yade, dir.path(), &m).unwrap().unwrap();
        assert!(f[0].contacts.is_empty(), "{:?}", f[0].contacts);
        assert_eq!(f[1].contacts.len(), 2);
        let c = &f[1].contacts[0];
        assert_eq!((c.i, c.j, c.normal), (0, 1, 2.0));
        assert!((c.tangential[1] - 0.25).abs() < 1e-12 && (c.gap + 0.01).abs() < 1e-12);
        assert_eq!((f[1].contacts[1].i, f[1].contacts[1].j), (1, 2));
        std::fs::write(
            dir.path().join("trace.txt"),
            "frame 0 0 20 20 20\ncontact 0 1 1 0 0 0\n",
        )
        .unwrap();
        let e = read(Code::Yade, dir.path(), &m).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("body 0"), "{e}");
    }
}
