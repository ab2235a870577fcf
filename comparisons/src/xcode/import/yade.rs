//! Reader of the text export written by our YADE decks (format in
//! `docs/external-formats/yade.md`): `final.cell`, `final.bodies`, `final.interactions`,
//! `final.status`.

use super::{read_status, ImportError, Meta, Raw, RawContact};
use std::collections::HashMap;
use std::path::Path;

/// A whitespace table with a `# col col …` header: column names and numeric rows with their
/// line numbers. The file ends with `# rows N`, the count of its rows, so that a file cut short
/// is told from a complete one.
struct Table {
    columns: Vec<String>,
    rows: Vec<(usize, Vec<f64>)>,
}

impl Table {
    fn read(path: &Path, default: &[&str]) -> Result<Table, ImportError> {
        let text = std::fs::read_to_string(path).map_err(|e| ImportError::new(path, e))?;
        let mut columns: Vec<String> = Vec::new();
        let mut rows = Vec::new();
        let mut footer: Option<(usize, &str)> = None;
        for (k, line) in text.lines().enumerate() {
            let line_no = k + 1;
            let t = line.trim();
            if t.is_empty() {
                continue;
            }
            if let Some((at, _)) = footer {
                return Err(ImportError::new(
                    path,
                    format!("line {line_no}: more after the closing `# rows` line {at}: {t:?}"),
                ));
            }
            if let Some(h) = t.strip_prefix('#') {
                let mut w = h.split_whitespace();
                if w.next() == Some("rows") && (!columns.is_empty() || !rows.is_empty()) {
                    footer = Some((line_no, w.next().unwrap_or("")));
                } else if columns.is_empty() && rows.is_empty() {
                    columns = h.split_whitespace().map(str::to_string).collect();
                }
                continue;
            }
            if columns.is_empty() {
                columns = default.iter().map(|s| s.to_string()).collect();
            }
            let v: Vec<f64> = t
                .split_whitespace()
                .map(|x| x.parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|e| ImportError::new(path, format!("line {line_no}: {e}: {t:?}")))?;
            if v.len() != columns.len() {
                return Err(ImportError::new(
                    path,
                    format!(
                        "line {line_no}: {} values for the {} columns `{}`",
                        v.len(),
                        columns.len(),
                        columns.join(" ")
                    ),
                ));
            }
            if let Some(c) = v.iter().position(|x| !x.is_finite()) {
                return Err(ImportError::new(
                    path,
                    format!(
                        "line {line_no}: column `{}` is {}: the code that wrote it failed (a non-finite position or force cannot be analysed)",
                        columns[c], v[c]
                    ),
                ));
            }
            rows.push((line_no, v));
        }
        match footer {
            None => Err(ImportError::new(
                path,
                format!(
                    "no closing `# rows N` line after its {} rows: the file was cut short, or written by an export without it (docs/external-formats/yade.md)",
                    rows.len()
                ),
            )),
            Some((at, count)) if count.parse::<usize>() != Ok(rows.len()) => Err(ImportError::new(
                path,
                format!(
                    "line {at}: `# rows {count}` promises {count} rows, but the file holds {}",
                    rows.len()
                ),
            )),
            Some(_) => Ok(Table { columns, rows }),
        }
    }

    fn col(&self, path: &Path, name: &str) -> Result<usize, ImportError> {
        self.columns.iter().position(|c| c == name).ok_or_else(|| {
            ImportError::new(
                path,
                format!(
                    "no column `{name}` in the header `# {}`",
                    self.columns.join(" ")
                ),
            )
        })
    }

    fn opt(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }
}

const BODY_COLUMNS: [&str; 12] = [
    "id", "radius", "mass", "x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz",
];
const INTERACTION_COLUMNS: [&str; 7] = ["id1", "id2", "fn", "fn_elastic", "tx", "ty", "tz"];

/// Reads `final.cell`: `lengths Lx Ly Lz`, `iteration n`, `time t` (any order).
fn read_cell(path: &Path) -> Result<(Vec<f64>, u64, f64), ImportError> {
    let text = std::fs::read_to_string(path).map_err(|e| ImportError::new(path, e))?;
    let mut lengths = None;
    let mut step = 0;
    let mut time = 0.0;
    for (k, line) in text.lines().enumerate() {
        let line_no = k + 1;
        let mut w = line.split_whitespace();
        let key = match w.next() {
            Some(key) if !key.starts_with('#') => key,
            _ => continue,
        };
        let bad = |e: &dyn std::fmt::Display| {
            ImportError::new(path, format!("line {line_no}: {e}: {line:?}"))
        };
        let vals: Vec<&str> = w.collect();
        match key {
            "lengths" if lengths.is_some() => return Err(bad(&"a second `lengths` line")),
            "lengths" => {
                let v: Vec<f64> = vals
                    .iter()
                    .map(|x| x.parse::<f64>())
                    .collect::<Result<_, _>>()
                    .map_err(|e| bad(&e))?;
                if v.len() != 3 || v.iter().any(|x| x.is_nan() || *x <= 0.0) {
                    return Err(bad(&"expected three positive lengths"));
                }
                lengths = Some(v);
            }
            "iteration" => {
                step = vals
                    .first()
                    .ok_or_else(|| bad(&"missing value"))?
                    .parse()
                    .map_err(|e| bad(&e))?
            }
            "time" => {
                time = vals
                    .first()
                    .ok_or_else(|| bad(&"missing value"))?
                    .parse()
                    .map_err(|e| bad(&e))?
            }
            other => return Err(bad(&format!("unknown key `{other}`"))),
        }
    }
    let lengths = lengths.ok_or_else(|| ImportError::new(path, "no `lengths Lx Ly Lz` line"))?;
    Ok((lengths, step, time))
}

/// Reads the final files of a yade run in `dir`.
pub fn read_dir(dir: &Path, meta: &Meta) -> Result<Raw, ImportError> {
    let cell_path = dir.join("final.cell");
    let (lengths, step, time) = read_cell(&cell_path)?;

    let bpath = dir.join("final.bodies");
    let bodies = Table::read(&bpath, &BODY_COLUMNS)?;
    let c = |name| bodies.col(&bpath, name);
    let (cid, cr, cm) = (c("id")?, c("radius")?, c("mass")?);
    let cx = [c("x")?, c("y")?, c("z")?];
    let cv = [c("vx")?, c("vy")?, c("vz")?];
    let cw = match (bodies.opt("wx"), bodies.opt("wy"), bodies.opt("wz")) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    let d = meta.dimension;
    let mut raw = Raw {
        lengths,
        origin: vec![0.0; 3],
        time,
        step,
        status: read_status(&dir.join("final.status")),
        ..Raw::default()
    };
    let mut index: HashMap<i64, usize> = HashMap::new();
    for (line_no, r) in &bodies.rows {
        let id = r[cid];
        if id.fract() != 0.0 || index.insert(id as i64, raw.position.len()).is_some() {
            return Err(ImportError::new(
                &bpath,
                format!("line {line_no}: id {id} is not a new integer id"),
            ));
        }
        raw.radius.push(r[cr]);
        raw.mass.push(r[cm]);
        raw.position.push(cx.iter().map(|&k| r[k]).collect());
        raw.velocity.push(cv.iter().map(|&k| r[k]).collect());
        if let Some(cw) = cw {
            // Spheres: three components in 3D; a 2D emulation keeps ω_z.
            raw.angular_velocity.push(if d == 2 {
                vec![r[cw[2]]]
            } else {
                cw.iter().map(|&k| r[k]).collect()
            });
        }
    }
    if meta.n != 0 && raw.position.len() != meta.n {
        return Err(ImportError::new(
            &bpath,
            format!(
                "{} bodies, deck.json says n = {}",
                raw.position.len(),
                meta.n
            ),
        ));
    }

    let ipath = dir.join("final.interactions");
    let inter = Table::read(&ipath, &INTERACTION_COLUMNS)?;
    let c = |name| inter.col(&ipath, name);
    let (c1, c2, cn) = (c("id1")?, c("id2")?, c("fn")?);
    let ce = inter.opt("fn_elastic");
    let ct = [c("tx")?, c("ty")?, c("tz")?];
    for (line_no, r) in &inter.rows {
        let look = |x: f64| {
            index.get(&(x as i64)).copied().ok_or_else(|| {
                ImportError::new(
                    &ipath,
                    format!("line {line_no}: body id {x} not in final.bodies"),
                )
            })
        };
        let (i, j) = (look(r[c1])?, look(r[c2])?);
        raw.contacts.push(RawContact {
            i,
            j,
            normal: r[cn],
            normal_elastic: ce.map(|k| r[k]),
            tangential: if meta.mu == Some(0.0) {
                Vec::new()
            } else {
                ct.iter().map(|&k| r[k]).collect()
            },
            rolling: Vec::new(),
        });
    }
    Ok(raw)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn meta() -> Meta {
        Meta {
            scene: "t".into(),
            code: "yade".into(),
            dimension: 3,
            pressure_target: Some(1.0),
            cohesive: false,
            mu: Some(0.3),
            force_unit: "P_ref a^2".into(),
            n: 2,
            data: Default::default(),
            trace: None,
        }
    }

    #[test]
    fn reads_export_and_reports_bad_lines() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        std::fs::write(
            p.join("final.cell"),
            "lengths 4 4 4\niteration 10\ntime 0.5\n",
        )
        .unwrap();
        std::fs::write(
            p.join("final.bodies"),
            "# id radius mass x y z vx vy vz wx wy wz\n\
             0 0.5 1 1 1 1 0 0 0 0 0 0\n\
             1 0.5 1 1.9 1 1 0 0 0 0 0 0\n\
             # rows 2\n",
        )
        .unwrap();
        std::fs::write(
            p.join("final.interactions"),
            "# id1 id2 fn fn_elastic tx ty tz\n0 1 2 1.5 0 0.1 0\n# rows 1\n",
        )
        .unwrap();
        std::fs::write(p.join("final.status"), "equilibrium\n").unwrap();
        let raw = read_dir(p, &meta()).unwrap();
        assert_eq!(raw.step, 10);
        assert_eq!(raw.status, "equilibrium");
        assert_eq!(raw.contacts.len(), 1);
        assert_eq!(raw.contacts[0].normal_elastic, Some(1.5));
        assert_eq!(raw.contacts[0].tangential, vec![0.0, 0.1, 0.0]);
        let snap = super::super::assemble(raw, &meta()).unwrap();
        assert!((snap.contacts[0].gap + 0.1).abs() < 1e-12);

        std::fs::write(
            p.join("final.interactions"),
            "# id1 id2 fn fn_elastic tx ty tz\n0 1 2 1.5 0 0.1\n# rows 1\n",
        )
        .unwrap();
        let e = read_dir(p, &meta()).unwrap_err().to_string();
        assert!(
            e.contains("final.interactions") && e.contains("line 2"),
            "{e}"
        );
        std::fs::write(
            p.join("final.interactions"),
            "0 7 2 1.5 0 0.1 0\n# rows 1\n",
        )
        .unwrap();
        let e = read_dir(p, &meta()).unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("id 7"), "{e}");
    }

    /// A file cut at a line end, or one whose footer disagrees, is refused.
    #[test]
    fn a_table_cut_short_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("final.interactions");
        let head = "# id1 id2 fn fn_elastic tx ty tz\n0 1 2 1.5 0 0.1 0\n1 2 1 1 0 0 0\n";
        for (text, expect) in [
            (
                head.to_string(),
                "no closing `# rows N` line after its 2 rows",
            ),
            (
                format!("{head}# rows 3\n"),
                "promises 3 rows, but the file holds 2",
            ),
            (format!("{head}# rows two\n"), "promises two rows"),
            (
                format!("{head}# rows 2\n2 3 1 1 0 0 0\n"),
                "more after the closing",
            ),
        ] {
            std::fs::write(&path, text).unwrap();
            let e = Table::read(&path, &INTERACTION_COLUMNS)
                .err()
                .expect("refused")
                .to_string();
            assert!(
                e.contains(expect) && e.contains("final.interactions"),
                "{e}"
            );
        }
        std::fs::write(&path, format!("{head}# rows 2\n")).unwrap();
        assert_eq!(
            Table::read(&path, &INTERACTION_COLUMNS).unwrap().rows.len(),
            2
        );
    }
}
