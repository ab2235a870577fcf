//! Explicit-particle starts: the grains of a scene listed in a CSV file
//! (`initial.particles`, `initial.cell`), for two- and few-body tests and for starts
//! written by other programs (the exchange format's `particles.csv`).

use super::grains::Grains;
use crate::geometry::{Dim, VectorOps as _};
use std::path::Path;

/// Reads the grains of `path` into a cell of side lengths `cell`: columns `x`, `y`, (`z`,)
/// `diameter` and optionally velocities `vx`, `vy`, (`vz`) and spins `w` (2D) or `wx`, `wy`,
/// `wz` (3D), by header name; errors name the file, the row and the column.
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
    let mut names: std::collections::BTreeSet<String> =
        grains.iter().flat_map(|g| g.keys().cloned()).collect();
    // A velocity or 3D spin listed in part: the components not listed are 0 (in 2D a `wx`
    // … is left for `spin_columns` to refuse by its own name).
    let spin3: &[&str] = if D::D == 3 { &SPIN[1..] } else { &[] };
    for group in [&VELOCITY[..D::D], spin3] {
        if group.iter().any(|c| names.contains(*c)) {
            names.extend(group.iter().map(|c| c.to_string()));
        }
    }
    let names: Vec<String> = names.into_iter().collect();
    let mut text = names
        .iter()
        .map(|s| s.as_str())
        .collect::<Vec<_>>()
        .join(",")
        + "\n";
    for g in grains {
        let row: Vec<String> = names
            .iter()
            .map(|k| match g.get(k) {
                Some(x) => format!("{x:?}"),
                // A grain without a velocity or spin listed is at rest.
                None if VELOCITY.contains(&k.as_str()) || SPIN.contains(&k.as_str()) => "0".into(),
                None => String::new(),
            })
            .collect();
        text += &(row.join(",") + "\n");
    }
    let rd = csv::ReaderBuilder::new().from_reader(text.as_bytes());
    parse(rd, "initial.grains", cell, n)
}

const VELOCITY: [&str; 3] = ["vx", "vy", "vz"];
const SPIN: [&str; 4] = ["w", "wx", "wy", "wz"];

/// The spin columns of the header in a `D`-dimensional scene: `w` (2D) or all of `wx`, `wy`,
/// `wz` (3D), or none; the other dimension's names are refused.
fn spin_columns<D: Dim>(
    file: &str,
    column: &impl Fn(&str) -> Option<usize>,
) -> Result<Option<Vec<usize>>, String> {
    let (ours, other): (&[&str], &[&str]) = if D::D == 2 {
        (&SPIN[..1], &SPIN[1..])
    } else {
        (&SPIN[1..], &SPIN[..1])
    };
    if let Some(bad) = other.iter().find(|c| column(c).is_some()) {
        return Err(format!(
            "{file}: column `{bad}` is a spin of a {}D grain; spins in {}D are {}",
            5 - D::D,
            D::D,
            ours.iter()
                .map(|c| format!("`{c}`"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    components(file, "spin", ours, &column)
}

/// The columns of a vector quantity (`what`): all of `names`, or none of them.
fn components(
    file: &str,
    what: &str,
    names: &[&str],
    column: &impl Fn(&str) -> Option<usize>,
) -> Result<Option<Vec<usize>>, String> {
    let found: Vec<Option<usize>> = names.iter().map(|c| column(c)).collect();
    if found.iter().all(Option::is_none) {
        return Ok(None);
    }
    match found.iter().position(Option::is_none) {
        Some(k) => Err(format!(
            "{file}: {what} column `{}` missing (give all of {}, or none)",
            names[k],
            names
                .iter()
                .map(|c| format!("`{c}`"))
                .collect::<Vec<_>>()
                .join(", ")
        )),
        None => Ok(Some(found.into_iter().flatten().collect())),
    }
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
    let spin_cols = spin_columns::<D>(file, &column)?;
    let vel_cols = components(file, "velocity", &VELOCITY[..D::D], &column)?;
    let l = D::from_slice(cell);
    let (mut s, mut u, mut w, mut diameter) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
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
        if let Some(cols) = &spin_cols {
            let spin: Vec<f64> = cols.iter().map(|&c| num(c)).collect::<Result<_, _>>()?;
            w.push(D::Ang::from_components(&spin));
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
        w,
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
    fn reads_spins_of_disks_and_spheres() {
        let f = write("x,y,diameter,w\n1,1,1,0.5\n3,3,1,-2\n");
        let g = read::<D2>(f.path(), &[10.0, 10.0], 2).unwrap();
        assert_eq!(g.w, vec![0.5, -2.0]);
        let f = write("x,y,z,diameter,wz,wx,wy\n1,1,1,1,3,1,2\n");
        let g = read::<crate::geometry::D3>(f.path(), &[10.0; 3], 1).unwrap();
        assert_eq!(g.w[0].to_vec(), vec![1.0, 2.0, 3.0]);
        // Without spin columns the grains start at rest (an empty list).
        let f = write("x,y,diameter\n1,1,1\n");
        assert!(read::<D2>(f.path(), &[10.0, 10.0], 1).unwrap().w.is_empty());
        // Inline grains without a spin start at rest.
        let one = |pairs: &[(&str, f64)]| -> std::collections::BTreeMap<String, f64> {
            pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
        };
        let grains = [
            one(&[("x", 1.0), ("y", 1.0), ("diameter", 1.0), ("w", 4.0)]),
            one(&[("x", 3.0), ("y", 3.0), ("diameter", 1.0)]),
        ];
        assert_eq!(
            inline::<D2>(&grains, &[10.0, 10.0], 2).unwrap().w,
            vec![4.0, 0.0]
        );
        // … and the components of a velocity or 3D spin not listed are 0.
        let grains = [one(&[
            ("x", 1.0),
            ("y", 1.0),
            ("z", 1.0),
            ("diameter", 1.0),
            ("vx", -1.0),
            ("wy", 2.0),
        ])];
        let g = inline::<crate::geometry::D3>(&grains, &[10.0; 3], 1).unwrap();
        assert_eq!(
            (g.u[0].to_vec(), g.w[0].to_vec()),
            (vec![-1.0, 0.0, 0.0], vec![0.0, 2.0, 0.0])
        );
    }

    #[test]
    fn spins_of_the_other_dimension_or_incomplete_are_refused() {
        let f = write("x,y,diameter,wz\n1,1,1,0.5\n");
        let e = read::<D2>(f.path(), &[10.0, 10.0], 1).unwrap_err();
        assert!(
            e.contains("`wz`") && e.contains("3D") && e.contains("`w`"),
            "{e}"
        );
        let grains = [[("x", 1.0), ("y", 1.0), ("diameter", 1.0), ("wz", 0.5)]
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect()];
        let e = inline::<D2>(&grains, &[10.0, 10.0], 1).unwrap_err();
        assert!(e.contains("`wz`") && e.contains("`w`"), "{e}");
        let f = write("x,y,z,diameter,w\n1,1,1,1,0.5\n");
        let e = read::<crate::geometry::D3>(f.path(), &[10.0; 3], 1).unwrap_err();
        assert!(e.contains("`w`") && e.contains("`wx`, `wy`, `wz`"), "{e}");
        let f = write("x,y,z,diameter,wx,wz\n1,1,1,1,0.5,1\n");
        let e = read::<crate::geometry::D3>(f.path(), &[10.0; 3], 1).unwrap_err();
        assert!(e.contains("spin column `wy` missing"), "{e}");
        let f = write("x,y,diameter,vx\n1,1,1,0.5\n");
        let e = read::<D2>(f.path(), &[10.0, 10.0], 1).unwrap_err();
        assert!(e.contains("velocity column `vy` missing"), "{e}");
        let f = write("x,y,diameter,w\n1,1,1,fast\n");
        let e = read::<D2>(f.path(), &[10.0, 10.0], 1).unwrap_err();
        assert!(
            e.contains("line 2") && e.contains("`w`") && e.contains("fast"),
            "{e}"
        );
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
