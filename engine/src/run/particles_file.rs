//! Explicit-particle starts (issue 19): the grains of a scene listed in a CSV file
//! (`initial.particles`, `initial.cell`), for two- and few-body tests and for starts
//! written by other programs (the exchange format's `particles.csv`).

use super::setup::Grains;
use crate::geometry::{Dim, VectorOps as _};
use std::path::Path;

/// Reads the grains of `path` into a cell of side lengths `cell`: columns `x`, `y`, (`z`,)
/// `diameter` and optionally `vx`, `vy`, (`vz`), by header name; errors name the file, the
/// row and the column.
pub fn read<D: Dim>(path: &Path, cell: &[f64], n: usize) -> Result<Grains<D>, String> {
    let rd = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(path)
        .map_err(|e| format!("initial.particles {}: {e}", path.display()))?;
    parse(
        rd,
        &format!("initial.particles {}", path.display()),
        cell,
        n,
    )
}

/// The grains of a scene's `initial.grains` (one map of column → value per grain).
pub fn inline<D: Dim>(
    grains: &[std::collections::BTreeMap<String, f64>],
    cell: &[f64],
    n: usize,
) -> Result<Grains<D>, String> {
    let names: std::collections::BTreeSet<&String> = grains.iter().flat_map(|g| g.keys()).collect();
    let names: Vec<&String> = names.into_iter().collect();
    let mut text = names
        .iter()
        .map(|s| s.as_str())
        .collect::<Vec<_>>()
        .join(",")
        + "\n";
    for g in grains {
        let row: Vec<String> = names
            .iter()
            .map(|k| match g.get(*k) {
                Some(x) => format!("{x:?}"),
                // A grain without a velocity listed is at rest.
                None if ["vx", "vy", "vz"].contains(&k.as_str()) => "0".into(),
                None => String::new(),
            })
            .collect();
        text += &(row.join(",") + "\n");
    }
    let rd = csv::ReaderBuilder::new().from_reader(text.as_bytes());
    parse(rd, "initial.grains", cell, n)
}

fn parse<D: Dim, R: std::io::Read>(
    mut rd: csv::Reader<R>,
    file: &str,
    cell: &[f64],
    n: usize,
) -> Result<Grains<D>, String> {
    if cell.len() != D::D || cell.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
        return Err(format!(
            "initial.cell: a `particles` or `grains` start needs the {} side lengths of the periodic cell, positive (e.g. cell = [{}]), got {cell:?}",
            D::D,
            vec!["20.0"; D::D].join(", ")
        ));
    }
    let header = rd.headers().map_err(|e| format!("{file}: {e}"))?.clone();
    let column = |name: &str| header.iter().position(|h| h == name);
    let axes = ["x", "y", "z"];
    let mut pos_cols = Vec::new();
    for a in axes.iter().take(D::D) {
        pos_cols.push(column(a).ok_or_else(|| {
            format!(
                "{file}: no column `{a}` in the header (need x, y{}, diameter)",
                if D::D == 3 { ", z" } else { "" }
            )
        })?);
    }
    let d_col =
        column("diameter").ok_or_else(|| format!("{file}: no column `diameter` in the header"))?;
    let vel_cols: Option<Vec<usize>> = ["vx", "vy", "vz"]
        .iter()
        .take(D::D)
        .map(|a| column(a))
        .collect();
    let l = D::from_slice(cell);
    let (mut s, mut u, mut diameter) = (Vec::new(), Vec::new(), Vec::new());
    for (k, row) in rd.records().enumerate() {
        let row = row.map_err(|e| format!("{file}: {e}"))?;
        let line = k + 2;
        let num = |c: usize| -> Result<f64, String> {
            let text = row.get(c).unwrap_or("");
            text.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    format!(
                        "{file}: line {line}, column `{}`: expected a finite number, got \"{text}\"",
                        &header[c]
                    )
                })
        };
        let mut x = D::V::zero();
        for (a, &c) in pos_cols.iter().enumerate() {
            x[a] = (num(c)? / l[a]).rem_euclid(1.0);
        }
        let d = num(d_col)?;
        if !(d > 0.0 && d <= 1.0) {
            return Err(format!(
                "{file}: line {line}, column `diameter`: must lie in (0, 1] (lengths in units of the largest diameter a), got {d}"
            ));
        }
        let mut v = D::V::zero();
        if let Some(cols) = &vel_cols {
            for (a, &c) in cols.iter().enumerate() {
                v[a] = num(c)?;
            }
        }
        s.push(x);
        u.push(v);
        diameter.push(d);
    }
    if s.len() != n {
        return Err(format!(
            "{file}: lists {} grains, the scene wants {n} (particles.count)",
            s.len()
        ));
    }
    Ok(Grains {
        l,
        s,
        u,
        diameter,
        time: 0.0,
        step: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::D2;

    fn write(text: &str) -> tempfile::NamedTempFile {
        let f = tempfile::NamedTempFile::new().unwrap();
        std::fs::write(f.path(), text).unwrap();
        f
    }

    #[test]
    fn reads_columns_by_name_and_wraps_positions() {
        let f = write("id,diameter,y,x,vx,vy\n0,1.0,2.5,1.0,0.5,0\n1,0.5,-1.0,11.0,0,-0.25\n");
        let g = read::<D2>(f.path(), &[10.0, 5.0], 2).unwrap();
        assert_eq!(g.diameter, vec![1.0, 0.5]);
        assert!((g.s[0][0] - 0.1).abs() < 1e-15 && (g.s[0][1] - 0.5).abs() < 1e-15);
        // x = 11 wraps to 1, y = −1 to 4.
        assert!((g.s[1][0] - 0.1).abs() < 1e-15 && (g.s[1][1] - 0.8).abs() < 1e-15);
        assert_eq!(g.u[1][1], -0.25);
    }

    #[test]
    fn errors_name_the_line_and_the_column() {
        let f = write("x,y,diameter\n1,2,1\n1,oops,1\n");
        let e = read::<D2>(f.path(), &[10.0, 10.0], 2).unwrap_err();
        assert!(
            e.contains("line 3") && e.contains("`y`") && e.contains("oops"),
            "{e}"
        );
        let e = read::<D2>(f.path(), &[10.0], 2).unwrap_err();
        assert!(e.contains("initial.cell"), "{e}");
        let f = write("x,y,diameter\n1,2,1\n");
        let e = read::<D2>(f.path(), &[10.0, 10.0], 3).unwrap_err();
        assert!(
            e.contains("lists 1 grains") && e.contains("particles.count"),
            "{e}"
        );
        let f = write("x,y\n1,2\n");
        let e = read::<D2>(f.path(), &[10.0, 10.0], 1).unwrap_err();
        assert!(e.contains("`diameter`"), "{e}");
    }
}
