//! ParaView output of a snapshot from any code: VTK XML unstructured grids (`.vtu`, ASCII) and a
//! `.pvd` collection that groups them.
//!
//! - `particles.vtu`: one vertex per grain; point data `diameter`, `mass`, `velocity`, `spin`
//!   (angular velocity; 2D spins on z), `contacts` (interactions of the grain). Render with
//!   ParaView's Glyph filter (sphere, scale by `diameter`).
//! - `contacts.vtu`: one line per listed interaction, from the centre of i to the centre of j's
//!   nearest periodic image (`r_i + branch`, so lines across the boundary stay short); cell data
//!   `normal_force` (N, repulsive positive), `tangential_force` (vector), `rolling_moment`
//!   (2D on z; zero without rolling resistance), `gap`.
//! - `snapshot.pvd`: both parts at the snapshot's time.
//!
//! A run's time series (`run --dump-every`) writes each frame as `step-<step>-particles.vtu` and
//! `step-<step>-contacts.vtu` ([`write_frame`]) and `run.pvd` listing them all in time order
//! ([`write_series`], which reads each frame's time back from its `TimeValue` field, so a
//! resumed run extends the series). 2D positions get z = 0. Every file is written atomically.

use grainbench_engine::snapshot::{write_atomic, Snapshot};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The files [`write_vtk`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct VtkFiles {
    pub particles: PathBuf,
    pub contacts: PathBuf,
    pub collection: PathBuf,
}

/// Writes `particles.vtu`, `contacts.vtu` and `snapshot.pvd` into `dir` (created if needed).
pub fn write_vtk(snap: &Snapshot, dir: &Path) -> std::io::Result<VtkFiles> {
    let (particles, contacts) = write_frame(snap, dir, "")?;
    let collection = dir.join("snapshot.pvd");
    write_atomic(
        &collection,
        collection_xml(&[(snap.time, "particles.vtu".into(), "contacts.vtu".into())]).as_bytes(),
    )?;
    Ok(VtkFiles {
        particles,
        contacts,
        collection,
    })
}

/// Writes `<prefix>particles.vtu` and `<prefix>contacts.vtu` into `dir`.
pub fn write_frame(
    snap: &Snapshot,
    dir: &Path,
    prefix: &str,
) -> std::io::Result<(PathBuf, PathBuf)> {
    let particles = dir.join(format!("{prefix}particles.vtu"));
    let contacts = dir.join(format!("{prefix}contacts.vtu"));
    write_atomic(&particles, particles_vtu(snap).as_bytes())?;
    write_atomic(&contacts, contacts_vtu(snap).as_bytes())?;
    Ok((particles, contacts))
}

/// The prefix of a run's frame at `step`.
pub fn frame_prefix(step: u64) -> String {
    format!("step-{step:012}-")
}

/// Writes `dir/<name>` listing every `step-*-particles.vtu` frame in `dir` (and its contacts
/// file) at the time stored in the frame, in time order. Returns the number of frames.
pub fn write_series(dir: &Path, name: &str) -> std::io::Result<usize> {
    let mut frames = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let file = entry?.file_name().to_string_lossy().into_owned();
        let Some(prefix) = file
            .strip_suffix("particles.vtu")
            .filter(|p| p.starts_with("step-"))
        else {
            continue;
        };
        let text = std::fs::read_to_string(dir.join(&file))?;
        if let Some(t) = time_value(&text) {
            frames.push((t, file.clone(), format!("{prefix}contacts.vtu")));
        }
    }
    frames.sort_by(|a, b| a.0.total_cmp(&b.0).then_with(|| a.1.cmp(&b.1)));
    write_atomic(&dir.join(name), collection_xml(&frames).as_bytes())?;
    Ok(frames.len())
}

/// The `TimeValue` field of a `.vtu` written here.
fn time_value(vtu: &str) -> Option<f64> {
    let at = vtu.find("Name=\"TimeValue\"")?;
    let body = &vtu[at..];
    let open = body.find('>')? + 1;
    let close = body.find("</DataArray>")?;
    body[open..close].trim().parse().ok()
}

/// A `.pvd` collection: (time, particles file, contacts file) per frame, as parts 0 and 1.
fn collection_xml(frames: &[(f64, String, String)]) -> String {
    let mut out = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n",
    );
    for (t, p, c) in frames {
        let _ = writeln!(
            out,
            "    <DataSet timestep=\"{t:e}\" part=\"0\" file=\"{p}\"/>\n    <DataSet timestep=\"{t:e}\" part=\"1\" file=\"{c}\"/>"
        );
    }
    out.push_str("  </Collection>\n</VTKFile>\n");
    out
}

/// Three components of a 2D or 3D vector (z = 0 in 2D).
fn xyz(v: &[f64]) -> [f64; 3] {
    [
        v.first().copied().unwrap_or(0.0),
        v.get(1).copied().unwrap_or(0.0),
        v.get(2).copied().unwrap_or(0.0),
    ]
}

/// An angular quantity as a 3-vector: a 2D scalar goes on z.
fn axial(v: &[f64]) -> [f64; 3] {
    match v.len() {
        1 => [0.0, 0.0, v[0]],
        _ => xyz(v),
    }
}

/// One `<DataArray>` of `components` numbers per entry.
fn array(out: &mut String, name: &str, components: usize, values: impl Iterator<Item = f64>) {
    let _ = write!(
        out,
        "        <DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{components}\" format=\"ascii\">\n         "
    );
    for (k, x) in values.enumerate() {
        if k > 0 && k % (6 * components) == 0 {
            out.push_str("\n         ");
        }
        let _ = write!(out, " {x:e}");
    }
    out.push_str("\n        </DataArray>\n");
}

fn header(out: &mut String, time: f64, points: usize, cells: usize) {
    let _ = write!(
        out,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n  \
         <UnstructuredGrid>\n    <FieldData>\n      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{time:e}</DataArray>\n    </FieldData>\n    \
         <Piece NumberOfPoints=\"{points}\" NumberOfCells=\"{cells}\">\n"
    );
}

/// Cells of `size` consecutive points each, of VTK type `kind` (1 vertex, 3 line).
fn cells(out: &mut String, count: usize, size: usize, kind: u8) {
    out.push_str("      <Cells>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n         ");
    for p in 0..count * size {
        let _ = write!(out, " {p}");
    }
    out.push_str("\n        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n         ");
    for c in 1..=count {
        let _ = write!(out, " {}", c * size);
    }
    out.push_str("\n        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n         ");
    for _ in 0..count {
        let _ = write!(out, " {kind}");
    }
    out.push_str("\n        </DataArray>\n      </Cells>\n");
}

const FOOTER: &str = "    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";

fn particles_vtu(snap: &Snapshot) -> String {
    let p = &snap.particles;
    let n = p.radius.len();
    let mut count = vec![0usize; n];
    for c in &snap.contacts {
        count[c.i] += 1;
        count[c.j] += 1;
    }
    let mut out = String::new();
    header(&mut out, snap.time, n, n);
    out.push_str("      <Points>\n");
    array(
        &mut out,
        "position",
        3,
        p.position.iter().flat_map(|x| xyz(x)),
    );
    out.push_str("      </Points>\n");
    cells(&mut out, n, 1, 1);
    out.push_str("      <PointData Scalars=\"diameter\" Vectors=\"velocity\">\n");
    array(&mut out, "diameter", 1, p.radius.iter().map(|r| 2.0 * r));
    array(&mut out, "mass", 1, p.mass.iter().copied());
    array(
        &mut out,
        "velocity",
        3,
        p.velocity.iter().flat_map(|v| xyz(v)),
    );
    let spin: Vec<[f64; 3]> = (0..n)
        .map(|i| p.angular_velocity.get(i).map_or([0.0; 3], |w| axial(w)))
        .collect();
    array(&mut out, "spin", 3, spin.iter().flatten().copied());
    array(&mut out, "contacts", 1, count.iter().map(|&k| k as f64));
    out.push_str("      </PointData>\n");
    out.push_str(FOOTER);
    out
}

fn contacts_vtu(snap: &Snapshot) -> String {
    let p = &snap.particles.position;
    let m = snap.contacts.len();
    let mut out = String::new();
    header(&mut out, snap.time, 2 * m, m);
    out.push_str("      <Points>\n");
    let ends = snap.contacts.iter().flat_map(|c| {
        let a = xyz(&p[c.i]);
        let b = xyz(&c.branch);
        [a, [a[0] + b[0], a[1] + b[1], a[2] + b[2]]]
    });
    array(&mut out, "position", 3, ends.flatten());
    out.push_str("      </Points>\n");
    cells(&mut out, m, 2, 3);
    out.push_str("      <CellData Scalars=\"normal_force\" Vectors=\"tangential_force\">\n");
    array(
        &mut out,
        "normal_force",
        1,
        snap.contacts.iter().map(|c| c.normal),
    );
    array(
        &mut out,
        "tangential_force",
        3,
        snap.contacts.iter().flat_map(|c| xyz(&c.tangential)),
    );
    array(
        &mut out,
        "rolling_moment",
        3,
        snap.contacts.iter().flat_map(|c| axial(&c.rolling)),
    );
    array(&mut out, "gap", 1, snap.contacts.iter().map(|c| c.gap));
    out.push_str("      </CellData>\n");
    out.push_str(FOOTER);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::fixtures::{bond, snapshot};
    use grainbench_engine::snapshot::Vector;

    /// Two disks of diameter 1 overlapping by 0.01 across the x boundary of a 4 × 2 cell.
    fn two_disks() -> Snapshot {
        let mut b = bond(0, 1, 0.5);
        b.tangential = vec![0.0, 0.1];
        let mut s = snapshot(
            vec![4.0, 2.0],
            vec![0.5, 0.5],
            vec![vec![0.2, 1.0], vec![3.21, 1.0]],
            &[b],
            false,
            Some(0.5),
        );
        s.particles.angular_velocity =
            vec![Vector::from_slice(&[0.5]), Vector::from_slice(&[-0.5])];
        s
    }

    /// The numbers of one `<DataArray Name=name>`.
    fn numbers(xml: &str, name: &str) -> Vec<f64> {
        let start = xml
            .find(&format!("Name=\"{name}\""))
            .unwrap_or_else(|| panic!("no array {name}"));
        let body = &xml[start..];
        let open = body.find('>').unwrap() + 1;
        let close = body.find("</DataArray>").unwrap();
        body[open..close]
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect()
    }

    #[test]
    fn two_disks_across_the_boundary() {
        let snap = two_disks();
        let dir = tempfile::tempdir().unwrap();
        let files = write_vtk(&snap, &dir.path().join("vtk")).unwrap();
        let parts = std::fs::read_to_string(&files.particles).unwrap();
        assert!(parts.contains("NumberOfPoints=\"2\" NumberOfCells=\"2\""));
        assert_eq!(
            numbers(&parts, "position"),
            vec![0.2, 1.0, 0.0, 3.21, 1.0, 0.0]
        );
        assert_eq!(numbers(&parts, "diameter"), vec![1.0, 1.0]);
        assert_eq!(numbers(&parts, "spin"), vec![0.0, 0.0, 0.5, 0.0, 0.0, -0.5]);
        assert_eq!(numbers(&parts, "contacts"), vec![1.0, 1.0]);
        assert_eq!(numbers(&parts, "types"), vec![1.0, 1.0]);
        let cont = std::fs::read_to_string(&files.contacts).unwrap();
        // The line goes to j's nearest image, across the boundary: 0.2 − 0.99.
        let ends = numbers(&cont, "position");
        assert_eq!(ends.len(), 6);
        assert!((ends[3] - (0.2 - 0.99)).abs() < 1e-12, "{ends:?}");
        assert_eq!(numbers(&cont, "normal_force"), vec![0.5]);
        assert_eq!(numbers(&cont, "tangential_force"), vec![0.0, 0.1, 0.0]);
        assert_eq!(numbers(&cont, "types"), vec![3.0]);
        assert_eq!(numbers(&cont, "offsets"), vec![2.0]);
        let pvd = std::fs::read_to_string(&files.collection).unwrap();
        assert!(pvd.contains("file=\"particles.vtu\"") && pvd.contains("file=\"contacts.vtu\""));
    }

    /// A series lists its frames in time order, with the times they carry, whatever order
    /// they were written in; other files are ignored.
    #[test]
    fn series_in_time_order() {
        let dir = tempfile::tempdir().unwrap();
        let mut snap = two_disks();
        for (step, t) in [(30, 3.0), (10, 1.0), (20, 2.5)] {
            snap.step = step;
            snap.time = t;
            write_frame(&snap, dir.path(), &frame_prefix(step)).unwrap();
        }
        write_vtk(&snap, dir.path()).unwrap();
        assert_eq!(write_series(dir.path(), "run.pvd").unwrap(), 3);
        let pvd = std::fs::read_to_string(dir.path().join("run.pvd")).unwrap();
        let times: Vec<&str> = pvd
            .lines()
            .filter(|l| l.contains("part=\"0\""))
            .map(|l| l.split('"').nth(1).unwrap())
            .collect();
        assert_eq!(times, ["1e0", "2.5e0", "3e0"]);
        assert!(pvd.contains("step-000000000020-contacts.vtu"));
        assert!(!pvd.contains("\"particles.vtu\""));
    }
}
