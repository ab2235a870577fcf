//! The final state a code writes in the exchange format (`docs/exchange-format.md`):
//! `particles.csv`, `contacts.csv` and the one-line `status.txt` of its output directory, and
//! the trace of a few-body run (`trace-grains.csv`, `trace-contacts.csv`).

use super::{ImportError, Meta, Raw, RawContact};
use crate::xcode::decks::generic::{
    OUT_CONTACTS, OUT_PARTICLES, OUT_STATUS, OUT_TRACE_CONTACTS, OUT_TRACE_GRAINS,
};
use std::collections::HashMap;
use std::path::Path;

/// Reads `dir`'s three files.
pub fn read_dir(dir: &Path, meta: &Meta) -> Result<Raw, ImportError> {
    read_final(dir, meta).map(|(raw, _)| raw)
}

/// [`read_dir`], with the row of each grain id.
fn read_final(dir: &Path, meta: &Meta) -> Result<(Raw, HashMap<usize, usize>), ImportError> {
    let d = meta.dimension;
    let status_path = dir.join(OUT_STATUS);
    let status =
        std::fs::read_to_string(&status_path).map_err(|e| ImportError::new(&status_path, e))?;
    let mut raw = Raw {
        status: String::new(),
        ..Raw::default()
    };
    parse_status(&status, d, &mut raw).map_err(|m| ImportError::new(&status_path, m))?;
    let ids = read_particles(&dir.join(OUT_PARTICLES), d, &mut raw)?;
    if raw.position.len() != meta.n {
        return Err(ImportError::new(
            &dir.join(OUT_PARTICLES),
            format!(
                "{} grains, the exchange started {}",
                raw.position.len(),
                meta.n
            ),
        ));
    }
    read_contacts(&dir.join(OUT_CONTACTS), d, &ids, &mut raw, None)?;
    Ok((raw, ids))
}

/// The frames of the trace in `dir` (the code's output directory), in time order: grains from
/// `trace-grains.csv` (sizes and masses from the final `particles.csv` by id), interacting
/// pairs from `trace-contacts.csv` (each row in the frame of its `t`), the cell from
/// `status.txt` (traces are of fixed cells); steps counted in the time step `dt` when known.
pub fn read_trace(dir: &Path, meta: &Meta, dt: Option<f64>) -> Result<Vec<Raw>, ImportError> {
    let d = meta.dimension;
    let (last, ids) = read_final(dir, meta)?;
    let grains = Table::read(&dir.join(OUT_TRACE_GRAINS))?;
    let (ct, cid) = (grains.need("t")?, grains.need("id")?);
    let pos: Vec<usize> = ["x", "y", "z"][..d]
        .iter()
        .map(|a| grains.need(a))
        .collect::<Result<_, _>>()?;
    let vel = grains.vector("v", d).ok_or_else(|| {
        ImportError::new(
            &grains.path,
            format!(
                "no velocity columns v{} in the header",
                ["x", "y", "z"][..d].join(", v")
            ),
        )
    })?;
    let spin = if d == 2 {
        grains.col("w").map(|c| vec![c])
    } else {
        grains.vector("w", d)
    };
    let n = last.position.len();
    let mut frames: Vec<Raw> = Vec::new();
    let mut seen = vec![false; n];
    for r in 0..grains.rows.len() {
        let t = grains.num(r, ct)?;
        if frames.last().is_none_or(|f| f.time != t) {
            if let Some(f) = frames.last() {
                if t < f.time {
                    return Err(ImportError::new(
                        &grains.path,
                        format!(
                            "line {}: t = {t} after t = {}: frames must come in time order",
                            r + 2,
                            f.time
                        ),
                    ));
                }
                check_complete(&grains.path, f.time, &seen)?;
            }
            seen.iter_mut().for_each(|s| *s = false);
            frames.push(Raw {
                lengths: last.lengths.clone(),
                position: vec![Vec::new(); n],
                velocity: vec![Vec::new(); n],
                angular_velocity: if spin.is_some() {
                    vec![Vec::new(); n]
                } else {
                    Vec::new()
                },
                radius: last.radius.clone(),
                mass: last.mass.clone(),
                time: t,
                step: dt.map_or(0, |dt| (t / dt).round() as u64),
                status: "trace".into(),
                ..Raw::default()
            });
        }
        let id = grains.num(r, cid)?;
        let Some(&k) = ids
            .get(&(id as usize))
            .filter(|_| id >= 0.0 && id.fract() == 0.0)
        else {
            return Err(ImportError::new(
                &grains.path,
                format!(
                    "line {}, column `id`: no grain with id {id} in {OUT_PARTICLES}",
                    r + 2
                ),
            ));
        };
        seen[k] = true;
        let f = frames.last_mut().expect("a frame was pushed");
        f.position[k] = pos
            .iter()
            .map(|&c| grains.num(r, c))
            .collect::<Result<_, _>>()?;
        f.velocity[k] = vel
            .iter()
            .map(|&c| grains.num(r, c))
            .collect::<Result<_, _>>()?;
        if let Some(w) = &spin {
            f.angular_velocity[k] = w
                .iter()
                .map(|&c| grains.num(r, c))
                .collect::<Result<_, _>>()?;
        }
    }
    match frames.last() {
        Some(f) => check_complete(&grains.path, f.time, &seen)?,
        None => return Err(ImportError::new(&grains.path, "no frames")),
    }
    let contacts = dir.join(OUT_TRACE_CONTACTS);
    let mut all = Raw::default();
    let times = read_contacts(&contacts, d, &ids, &mut all, Some("t"))?;
    for (c, t) in all.contacts.into_iter().zip(times) {
        // The frame of this time (the two files come from one run: equal to rounding).
        let k = frames.partition_point(|f| f.time < t - 1e-9 * t.abs().max(1.0));
        match frames
            .get_mut(k)
            .filter(|f| (f.time - t).abs() <= 1e-9 * t.abs().max(1.0))
        {
            Some(f) => f.contacts.push(c),
            None => {
                return Err(ImportError::new(
                    &contacts,
                    format!("a contact at t = {t}, where {OUT_TRACE_GRAINS} has no frame"),
                ))
            }
        }
    }
    Ok(frames)
}

/// Every grain listed in the frame at `t`.
fn check_complete(path: &Path, t: f64, seen: &[bool]) -> Result<(), ImportError> {
    match seen.iter().position(|s| !s) {
        None => Ok(()),
        Some(k) => Err(ImportError::new(
            path,
            format!(
                "the frame at t = {t} lists {} of the {} grains (the grain in row {} of {OUT_PARTICLES} is missing)",
                seen.iter().filter(|s| **s).count(),
                seen.len(),
                k + 2
            ),
        )),
    }
}

/// A value of `status.txt` in `dir` (`version`, `loop_time`, …), if the code wrote it.
pub fn status_value(dir: &Path, key: &str) -> Option<String> {
    let text = std::fs::read_to_string(dir.join(OUT_STATUS)).ok()?;
    let line = text.lines().find(|l| !l.trim().is_empty())?;
    tokens(line)
        .ok()?
        .into_iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v)
}

/// `status=equilibrium cell=20.1,20.1 steps=123 time=4.5 version="mydem 2.1"`.
fn parse_status(text: &str, d: usize, raw: &mut Raw) -> Result<(), String> {
    let line = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("");
    for (key, value) in tokens(line)? {
        match key.as_str() {
            "status" => raw.status = value,
            "cell" => {
                raw.lengths = value
                    .split(',')
                    .map(|x| x.trim().parse::<f64>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| format!("`cell={value}`: expected {d} comma-separated lengths"))?;
            }
            "steps" => {
                raw.step = value
                    .parse()
                    .map_err(|_| format!("`steps={value}`: expected a whole number"))?
            }
            "time" => {
                raw.time = value
                    .parse()
                    .map_err(|_| format!("`time={value}`: expected a number"))?
            }
            _ => {}
        }
    }
    if raw.status.is_empty() {
        return Err(format!(
            "no `status=` on its first line \"{line}\" (equilibrium, time-limit or failed)"
        ));
    }
    if raw.lengths.len() != d || raw.lengths.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
        return Err(format!(
            "`cell=` must give the {d} positive side lengths of the final cell, got {:?}",
            raw.lengths
        ));
    }
    Ok(())
}

/// `key=value` tokens separated by blanks; a value may be double-quoted.
fn tokens(line: &str) -> Result<Vec<(String, String)>, String> {
    let mut out = Vec::new();
    let mut rest = line.trim();
    while !rest.is_empty() {
        let eq = rest
            .find('=')
            .ok_or_else(|| format!("expected key=value, found \"{rest}\""))?;
        let key = rest[..eq].trim().to_string();
        rest = &rest[eq + 1..];
        let value;
        if let Some(q) = rest.strip_prefix('"') {
            let end = q.find('"').ok_or("unterminated quoted value")?;
            value = q[..end].to_string();
            rest = q[end + 1..].trim_start();
        } else {
            let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
            value = rest[..end].to_string();
            rest = rest[end..].trim_start();
        }
        out.push((key, value));
    }
    Ok(out)
}

struct Table {
    path: std::path::PathBuf,
    header: Vec<String>,
    rows: Vec<csv::StringRecord>,
}

impl Table {
    fn read(path: &Path) -> Result<Table, ImportError> {
        let mut rd = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_path(path)
            .map_err(|e| ImportError::new(path, e))?;
        let header = rd
            .headers()
            .map_err(|e| ImportError::new(path, e))?
            .iter()
            .map(String::from)
            .collect();
        let rows = rd
            .records()
            .collect::<Result<_, _>>()
            .map_err(|e| ImportError::new(path, e))?;
        Ok(Table {
            path: path.to_path_buf(),
            header,
            rows,
        })
    }
    fn col(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }
    fn need(&self, name: &str) -> Result<usize, ImportError> {
        self.col(name).ok_or_else(|| {
            ImportError::new(
                &self.path,
                format!("no column `{name}` in the header {:?}", self.header),
            )
        })
    }
    fn num(&self, row: usize, c: usize) -> Result<f64, ImportError> {
        let text = self.rows[row].get(c).unwrap_or("");
        text.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| {
                ImportError::new(
                    &self.path,
                    format!(
                        "line {}, column `{}`: expected a finite number, got \"{text}\"",
                        row + 2,
                        self.header[c]
                    ),
                )
            })
    }
    /// Columns `prefix` + x, y(, z), all or none; a 2D scalar `prefix` alone for `scalar_2d`.
    fn vector(&self, prefix: &str, d: usize) -> Option<Vec<usize>> {
        ["x", "y", "z"][..d]
            .iter()
            .map(|a| self.col(&format!("{prefix}{a}")))
            .collect()
    }
}

/// Grains in file order; returns the row of each id.
fn read_particles(
    path: &Path,
    d: usize,
    raw: &mut Raw,
) -> Result<HashMap<usize, usize>, ImportError> {
    let t = Table::read(path)?;
    let pos: Vec<usize> = ["x", "y", "z"][..d]
        .iter()
        .map(|a| t.need(a))
        .collect::<Result<_, _>>()?;
    let dia = t.need("diameter")?;
    let id = t.col("id");
    let mass = t.col("mass");
    let vel = t.vector("v", d);
    let spin = t.vector("w", d).or_else(|| t.col("w").map(|c| vec![c]));
    let mut ids = HashMap::new();
    for r in 0..t.rows.len() {
        let key = match id {
            Some(c) => {
                let x = t.num(r, c)?;
                if x < 0.0 || x.fract() != 0.0 {
                    return Err(ImportError::new(
                        path,
                        format!(
                            "line {}, column `id`: expected a whole number ≥ 0, got {x}",
                            r + 2
                        ),
                    ));
                }
                x as usize
            }
            None => r,
        };
        if ids.insert(key, r).is_some() {
            return Err(ImportError::new(
                path,
                format!("line {}: id {key} listed twice", r + 2),
            ));
        }
        raw.position
            .push(pos.iter().map(|&c| t.num(r, c)).collect::<Result<_, _>>()?);
        let diameter = t.num(r, dia)?;
        raw.radius.push(diameter / 2.0);
        raw.mass.push(match mass {
            Some(c) => t.num(r, c)?,
            None => diameter.powi(d as i32),
        });
        if let Some(v) = &vel {
            raw.velocity
                .push(v.iter().map(|&c| t.num(r, c)).collect::<Result<_, _>>()?);
        }
        if let Some(w) = &spin {
            raw.angular_velocity
                .push(w.iter().map(|&c| t.num(r, c)).collect::<Result<_, _>>()?);
        }
    }
    Ok(ids)
}

/// The pairs of `path` into `raw`; with `time` (a trace), also each row's value of that column.
fn read_contacts(
    path: &Path,
    d: usize,
    ids: &HashMap<usize, usize>,
    raw: &mut Raw,
    time: Option<&str>,
) -> Result<Vec<f64>, ImportError> {
    let t = Table::read(path)?;
    let (ci, cj, cn) = (t.need("i")?, t.need("j")?, t.need("fn")?);
    let ct = time.map(|c| t.need(c)).transpose()?;
    let mut times = Vec::new();
    let elastic = t.col("fn_elastic");
    let tangential = t.vector("ft_", d);
    let rolling = if d == 2 {
        t.col("mr").map(|c| vec![c])
    } else {
        t.vector("mr_", d)
    };
    for r in 0..t.rows.len() {
        let grain = |c: usize| -> Result<usize, ImportError> {
            let x = t.num(r, c)?;
            ids.get(&(x as usize))
                .copied()
                .filter(|_| x >= 0.0 && x.fract() == 0.0)
                .ok_or_else(|| {
                    ImportError::new(
                        &t.path,
                        format!(
                            "line {}, column `{}`: no grain with id {x} in {OUT_PARTICLES}",
                            r + 2,
                            t.header[c]
                        ),
                    )
                })
        };
        let vec_of = |cols: &Option<Vec<usize>>| -> Result<Vec<f64>, ImportError> {
            cols.iter().flatten().map(|&c| t.num(r, c)).collect()
        };
        raw.contacts.push(RawContact {
            i: grain(ci)?,
            j: grain(cj)?,
            normal: t.num(r, cn)?,
            normal_elastic: elastic.map(|c| t.num(r, c)).transpose()?,
            tangential: vec_of(&tangential)?,
            rolling: vec_of(&rolling)?,
        });
        if let Some(c) = ct {
            times.push(t.num(r, c)?);
        }
    }
    Ok(times)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn meta(n: usize) -> Meta {
        Meta {
            scene: "s".into(),
            code: "mycode".into(),
            dimension: 2,
            pressure_target: Some(1.0),
            cohesive: false,
            mu: Some(0.3),
            force_unit: "P_ref a^1".into(),
            n,
            data: Default::default(),
            trace: None,
        }
    }

    fn dir(files: &[(&str, &str)]) -> tempfile::TempDir {
        let d = tempfile::tempdir().unwrap();
        for (name, text) in files {
            std::fs::write(d.path().join(name), text).unwrap();
        }
        d
    }

    #[test]
    fn reads_a_two_disk_state_by_ids() {
        let d = dir(&[
            (
                "status.txt",
                "status=equilibrium cell=4,4 steps=10 time=0.5 version=\"my dem 1.0\"\n",
            ),
            (
                "particles.csv",
                "id,x,y,diameter,vx,vy\n7,1,1,1,0,0\n3,1.95,1,1,0,0\n",
            ),
            ("contacts.csv", "i,j,fn,ft_x,ft_y\n7,3,0.5,0,0.1\n"),
        ]);
        let raw = read_dir(d.path(), &meta(2)).unwrap();
        assert_eq!(raw.status, "equilibrium");
        assert_eq!(
            (raw.step, raw.time, raw.lengths.clone()),
            (10, 0.5, vec![4.0, 4.0])
        );
        assert_eq!(raw.mass, vec![1.0, 1.0]);
        let c = &raw.contacts[0];
        assert_eq!((c.i, c.j, c.normal), (0, 1, 0.5));
        assert_eq!(c.tangential, vec![0.0, 0.1]);
        let snap = super::super::assemble(raw, &meta(2)).unwrap();
        assert_eq!(snap.contacts.len(), 1);
        assert!((snap.contacts[0].gap + 0.05).abs() < 1e-12);
    }

    #[test]
    fn errors_name_the_file_line_and_column() {
        let ok_p = "x,y,diameter\n1,1,1\n1.95,1,1\n";
        let d = dir(&[
            ("status.txt", "cell=4,4\n"),
            ("particles.csv", ok_p),
            ("contacts.csv", "i,j,fn\n"),
        ]);
        let e = read_dir(d.path(), &meta(2)).unwrap_err().to_string();
        assert!(e.contains("status.txt") && e.contains("status="), "{e}");
        let d = dir(&[
            ("status.txt", "status=equilibrium cell=4\n"),
            ("particles.csv", ok_p),
            ("contacts.csv", "i,j,fn\n"),
        ]);
        let e = read_dir(d.path(), &meta(2)).unwrap_err().to_string();
        assert!(e.contains("cell="), "{e}");
        let d = dir(&[
            ("status.txt", "status=equilibrium cell=4,4\n"),
            ("particles.csv", ok_p),
            ("contacts.csv", "i,j,fn\n0,5,1\n"),
        ]);
        let e = read_dir(d.path(), &meta(2)).unwrap_err().to_string();
        assert!(
            e.contains("contacts.csv") && e.contains("line 2") && e.contains("id 5"),
            "{e}"
        );
        let d = dir(&[
            ("status.txt", "status=equilibrium cell=4,4\n"),
            ("particles.csv", ok_p),
            ("contacts.csv", "i,j\n"),
        ]);
        let e = read_dir(d.path(), &meta(2)).unwrap_err().to_string();
        assert!(e.contains("`fn`"), "{e}");
        let d = dir(&[
            ("status.txt", "status=equilibrium cell=4,4\n"),
            ("particles.csv", ok_p),
            ("contacts.csv", "i,j,fn\n"),
        ]);
        let e = read_dir(d.path(), &meta(3)).unwrap_err().to_string();
        assert!(e.contains("2 grains") && e.contains("started 3"), "{e}");
    }

    #[test]
    fn reads_a_trace_of_three_disks_with_its_contacts() {
        let final_state = [
            ("status.txt", "status=time-limit cell=6,6 steps=20 time=2\n"),
            (
                "particles.csv",
                "id,x,y,diameter,mass\n5,1,1,1,1\n6,1.95,1,1,1\n7,4,4,0.5,0.125\n",
            ),
            ("contacts.csv", "i,j,fn\n"),
        ];
        let grains = "t,id,x,y,vx,vy,w\n\
                      0,5,1,1,0,0,0\n0,6,2.1,1,-0.1,0,0\n0,7,4,4,0,0,0\n\
                      1,7,4,4,0,0,0\n1,6,1.95,1,0,0,0.5\n1,5,1,1,0,0,0\n";
        let mut files = final_state.to_vec();
        files.push(("trace-grains.csv", grains));
        files.push((
            "trace-contacts.csv",
            "t,i,j,gap,fn,ft_x,ft_y\n1,5,6,-0.05,0.5,0,0.1\n",
        ));
        let d = dir(&files);
        let frames = read_trace(d.path(), &meta(3), Some(0.1)).unwrap();
        assert_eq!(frames.len(), 2);
        assert_eq!(
            (frames[0].time, frames[1].time, frames[1].step),
            (0.0, 1.0, 10)
        );
        assert!(frames[0].contacts.is_empty());
        // Rows by id, in the order of the final particles.csv.
        assert_eq!(frames[1].position[1], vec![1.95, 1.0]);
        assert_eq!(frames[1].angular_velocity[1], vec![0.5]);
        assert_eq!(frames[1].radius[2], 0.25);
        let c = &frames[1].contacts[0];
        assert_eq!(
            (c.i, c.j, c.normal, c.tangential.clone()),
            (0, 1, 0.5, vec![0.0, 0.1])
        );
        let snap = super::super::assemble(frames[1].clone(), &meta(3)).unwrap();
        assert!((snap.contacts[0].gap + 0.05).abs() < 1e-12);

        // A grain missing from a frame, a contact at a time without a frame.
        let mut files = final_state.to_vec();
        files.push((
            "trace-grains.csv",
            "t,id,x,y,vx,vy\n0,5,1,1,0,0\n0,6,2,1,0,0\n",
        ));
        files.push(("trace-contacts.csv", "t,i,j,fn\n"));
        let e = read_trace(dir(&files).path(), &meta(3), None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("trace-grains.csv") && e.contains("2 of the 3 grains"),
            "{e}"
        );
        let mut files = final_state.to_vec();
        files.push(("trace-grains.csv", grains));
        files.push(("trace-contacts.csv", "t,i,j,fn\n0.5,5,6,1\n"));
        let e = read_trace(dir(&files).path(), &meta(3), None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("trace-contacts.csv") && e.contains("t = 0.5"),
            "{e}"
        );
    }
}
