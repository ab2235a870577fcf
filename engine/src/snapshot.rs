//! Snapshot files: one configuration of a periodic packing, from grainbench or any other code.
//!
//! Format `grainbench-snapshot`, version 1, is JSON (documented in `docs/snapshot-format.md`).
//! All quantities are in the reduced units of the scene (lengths in a, masses in the mass of a
//! grain of diameter a, forces in the scene's force unit). Files are written atomically: a
//! temporary file in the same directory, renamed over the target.

use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;

pub const FORMAT: &str = "grainbench-snapshot";
pub const VERSION: u32 = 1;

/// A whole configuration.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Snapshot {
    /// Always [`FORMAT`].
    pub format: String,
    /// Format version, [`VERSION`] for this reader.
    pub version: u32,
    /// Program that wrote it (`grainbench 0.1.0`, `lammps 29Sep2021`, …).
    pub code: String,
    /// Scene name.
    pub scene: String,
    /// 2 or 3.
    pub dimension: usize,
    /// Physical time (reduced units) and step count.
    pub time: f64,
    pub step: u64,
    /// How the run that wrote it ended: `equilibrium`, `time-limit`, `unstable`, `interrupted`,
    /// or `imported`.
    pub status: String,
    /// Force unit: `F0` or `P_ref a^(d-1)`; `pressure_target` is in force unit / a^(d-1)
    /// (`null` when no pressure was prescribed: a fixed cell from the start).
    pub force_unit: String,
    pub pressure_target: Option<f64>,
    /// Does the law carry attraction (cohesion)? Decides the contact-counting rule.
    pub cohesive: bool,
    /// Friction coefficient (`null` for μ = ∞).
    pub mu: Option<f64>,
    pub cell: Cell,
    pub particles: Particles,
    pub contacts: Vec<Contact>,
}

/// A small vector of a snapshot (a position, a velocity, a branch vector, a force, a moment):
/// d ≤ 3 components stored inline (32 B instead of a 24-byte header and a separate heap
/// block for each; on large packings that halves the size of a snapshot in memory). Serialized
/// as a JSON array, as `Vec<f64>` was.
pub type Vector = smallvec::SmallVec<[f64; 3]>;

/// Orthorhombic periodic cell `[0, L_1) × … × [0, L_d)`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Cell {
    pub lengths: Vec<f64>,
    /// Measured stress σ_αβ (AR07 (8)), compressive positive, `d × d`, contact part only.
    pub contact_stress: Vec<Vec<f64>>,
    /// Kinetic part Σ m v_α v_β / Ω.
    pub kinetic_stress: Vec<Vec<f64>>,
}

/// Per-grain columns.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct Particles {
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub position: Vec<Vector>,
    pub velocity: Vec<Vector>,
    /// One value per grain in 2D, three in 3D; empty when the law has no moments.
    #[serde(default)]
    pub angular_velocity: Vec<Vector>,
}

/// One interacting pair (in contact, or within the attraction range).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Contact {
    pub i: usize,
    pub j: usize,
    /// r_j − r_i, nearest periodic image.
    pub branch: Vector,
    /// Total normal force N (repulsive positive): elastic + viscous − adhesion.
    pub normal: f64,
    /// Elastic repulsive part N_e (the part the Coulomb and rolling thresholds use).
    pub normal_elastic: f64,
    /// Tangential force exerted by i on j.
    #[serde(default)]
    pub tangential: Vector,
    /// Rolling moment exerted by i on j (empty without rolling resistance).
    #[serde(default)]
    pub rolling: Vector,
    /// Surface gap h (negative: overlap).
    pub gap: f64,
}

/// Errors reading or writing snapshots.
#[derive(Debug, thiserror::Error)]
pub enum SnapshotError {
    #[error("snapshot {path}: {error}")]
    Io { path: String, error: std::io::Error },
    #[error("snapshot {path}: not a grainbench snapshot: {message}")]
    Parse { path: String, message: String },
    #[error("snapshot {path}: {message}")]
    Invalid { path: String, message: String },
}

impl Snapshot {
    /// Reads and checks a snapshot file.
    pub fn read(path: &Path) -> Result<Snapshot, SnapshotError> {
        let p = path.display().to_string();
        let io = |error| SnapshotError::Io {
            path: p.clone(),
            error,
        };
        // Parsed from the file as it is read: the text of a large snapshot (≈ 600 B a grain)
        // is not held beside the parsed one. The text is read only to explain an error.
        let file = std::fs::File::open(path).map_err(io)?;
        let parsed = serde_json::from_reader(std::io::BufReader::with_capacity(1 << 16, file));
        let snap: Snapshot = match parsed {
            Ok(snap) => snap,
            Err(e) if e.is_io() => return Err(io(std::io::Error::other(e))),
            Err(e) => {
                let text = std::fs::read_to_string(path).map_err(io)?;
                return Err(SnapshotError::Parse {
                    path: p.clone(),
                    message: parse_message(&text, &e),
                });
            }
        };
        snap.check()
            .map_err(|message| SnapshotError::Invalid { path: p, message })?;
        Ok(snap)
    }

    /// Consistency checks: format tag, version, array lengths, indices.
    pub fn check(&self) -> Result<(), String> {
        if self.format != FORMAT {
            return Err(format!(
                "field `format` is {:?}, expected {FORMAT:?}",
                self.format
            ));
        }
        if self.version != VERSION {
            return Err(format!(
                "field `version` is {}, this grainbench reads version {VERSION}",
                self.version
            ));
        }
        let d = self.dimension;
        if d != 2 && d != 3 {
            return Err(format!("field `dimension` must be 2 or 3, got {d}"));
        }
        if self.cell.lengths.len() != d {
            return Err(format!("field `cell.lengths` must have {d} entries"));
        }
        let n = self.particles.radius.len();
        let p = &self.particles;
        if p.mass.len() != n || p.position.len() != n || p.velocity.len() != n {
            return Err(format!(
                "particle columns differ in length (radius {n}, mass {}, position {}, velocity {})",
                p.mass.len(),
                p.position.len(),
                p.velocity.len()
            ));
        }
        if p.position.iter().chain(&p.velocity).any(|x| x.len() != d) {
            return Err(format!("every position and velocity needs {d} components"));
        }
        // Values a packing cannot have: each would analyse to a silently wrong result.
        let fix = "(a non-finite value means the run that wrote it failed)";
        if let Some(a) = self
            .cell
            .lengths
            .iter()
            .position(|&l| !(l.is_finite() && l > 0.0))
        {
            return Err(format!(
                "field `cell.lengths[{a}]` is {}, expected a finite length > 0",
                self.cell.lengths[a]
            ));
        }
        let l_min = self
            .cell
            .lengths
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        for (k, &r) in p.radius.iter().enumerate() {
            if !(r.is_finite() && r > 0.0) {
                return Err(format!(
                    "field `particles.radius[{k}]` is {r}, expected a finite radius > 0 {fix}"
                ));
            }
            // Minimum image: with every side at least two diameters, a pair touches through
            // one periodic image only (tests/fuzz.rs: a YADE cell of side 1 for diameters of 1
            // analysed to z^II = 18.8).
            if 4.0 * r > l_min {
                return Err(format!(
                    "field `particles.radius[{k}]` is {r}: the shortest cell side {l_min} is less than two diameters; a periodic packing needs every side ≥ 2 diameters, so that a pair touches through one image only"
                ));
            }
        }
        let volume: f64 = self.cell.lengths.iter().product();
        if !volume.is_finite() {
            return Err(format!(
                "field `cell.lengths` {:?} gives a cell volume of {volume}: no packing fills it",
                self.cell.lengths
            ));
        }
        let phi = self.packing_fraction();
        if phi >= 1.0 {
            return Err(format!(
                "the grains' volumes add up to Φ = {phi:.4} of the cell: `particles.radius` or `cell.lengths` is wrong (a packing has Φ < 1)"
            ));
        }
        if let Some(k) = p.mass.iter().position(|&m| !(m.is_finite() && m > 0.0)) {
            return Err(format!(
                "field `particles.mass[{k}]` is {}, expected a finite mass > 0 {fix}",
                p.mass[k]
            ));
        }
        for (name, col) in [
            ("position", &p.position),
            ("velocity", &p.velocity),
            ("angular_velocity", &p.angular_velocity),
        ] {
            if let Some(k) = col.iter().position(|x| x.iter().any(|v| !v.is_finite())) {
                return Err(format!(
                    "field `particles.{name}[{k}]` is {:?}, expected finite numbers {fix}",
                    col[k]
                ));
            }
        }
        if let Some(mu) = self.mu.filter(|mu| !(mu.is_finite() && *mu >= 0.0)) {
            return Err(format!(
                "field `mu` is {mu}, expected a friction coefficient ≥ 0 (null for μ = ∞)"
            ));
        }
        if let Some(pt) = self.pressure_target.filter(|pt| !pt.is_finite()) {
            return Err(format!(
                "field `pressure_target` is {pt}, expected a finite number or null"
            ));
        }
        let mut seen = std::collections::HashMap::with_capacity(self.contacts.len());
        for (k, c) in self.contacts.iter().enumerate() {
            if c.i >= n || c.j >= n || c.i == c.j {
                return Err(format!(
                    "contacts[{k}] joins grains {} and {} (there are {n} grains)",
                    c.i, c.j
                ));
            }
            if c.branch.len() != d {
                return Err(format!("contacts[{k}].branch needs {d} components"));
            }
            let scalars = [c.normal, c.normal_elastic, c.gap];
            let vectors = c.branch.iter().chain(&c.tangential).chain(&c.rolling);
            if scalars.iter().chain(vectors).any(|v| !v.is_finite()) {
                return Err(format!(
                    "contacts[{k}] (grains {} and {}) holds a non-finite force, branch or gap {fix}",
                    c.i, c.j
                ));
            }
            if let Some(first) = seen.insert((c.i.min(c.j), c.i.max(c.j)), k) {
                return Err(format!(
                    "contacts[{k}] and contacts[{first}] both join grains {} and {}: each pair is listed once (a duplicate would count twice in z)",
                    c.i, c.j
                ));
            }
        }
        Ok(())
    }

    /// Writes the snapshot atomically (temporary file in the same directory, then rename), so
    /// an interrupted write never leaves a truncated file in place of a good one.
    pub fn write(&self, path: &Path) -> Result<(), SnapshotError> {
        // Streamed into the file: the JSON text of a large packing (≈ 1 KB a grain) is never
        // held in memory, where it would add to a run's peak memory (docs/performance.md).
        let mut invalid = None;
        let written = write_atomic_with(path, |w| {
            serde_json::to_writer(&mut *w, self).map_err(|e| {
                if e.is_io() {
                    std::io::Error::other(e)
                } else {
                    invalid = Some(e.to_string());
                    std::io::Error::other("not encodable")
                }
            })
        });
        match (written, invalid) {
            (_, Some(message)) => Err(SnapshotError::Invalid {
                path: path.display().to_string(),
                message,
            }),
            (Err(error), None) => Err(SnapshotError::Io {
                path: path.display().to_string(),
                error,
            }),
            (Ok(()), None) => Ok(()),
        }
    }

    /// Solid fraction Φ.
    pub fn packing_fraction(&self) -> f64 {
        let vol: f64 = self.cell.lengths.iter().product();
        let solid: f64 = self
            .particles
            .radius
            .iter()
            .map(|&r| {
                if self.dimension == 2 {
                    std::f64::consts::PI * r * r
                } else {
                    4.0 / 3.0 * std::f64::consts::PI * r * r * r
                }
            })
            .sum();
        solid / vol
    }
}

/// serde_json's message, with a hint when the value it stopped at is a NaN or an infinity,
/// which JSON cannot hold.
fn parse_message(text: &str, e: &serde_json::Error) -> String {
    let at = text
        .lines()
        .nth(e.line().saturating_sub(1))
        .and_then(|l| l.get(e.column().saturating_sub(1)..))
        .unwrap_or("");
    let non_finite = ["NaN", "nan", "inf", "Inf", "-inf", "-Inf"]
        .iter()
        .any(|t| at.starts_with(t));
    if non_finite {
        format!("{e}: a NaN or infinite number, which JSON does not allow (the run that wrote it failed, or the writer is not JSON-conformant)")
    } else {
        e.to_string()
    }
}

/// Writes `bytes` to `path` atomically: temporary file beside it, flushed, then renamed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// As [`write_atomic`], with the content streamed by `fill` through a buffered writer (large
/// outputs need not be assembled in memory first). Nothing replaces `path` when `fill` fails.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => std::path::PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir)?;
    let tmp = tempfile::NamedTempFile::new_in(&dir)?;
    let mut w = std::io::BufWriter::with_capacity(1 << 16, tmp);
    fill(&mut w)?;
    let tmp = w.into_inner().map_err(|e| e.into_error())?;
    tmp.as_file().sync_all()?;
    // Temporary files are private (0600); results are ordinary files.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))?;
    }
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use smallvec::smallvec;

    /// Two touching disks in a 4 × 4 cell.
    fn valid() -> Snapshot {
        Snapshot {
            format: FORMAT.into(),
            version: VERSION,
            code: "test".into(),
            scene: "test".into(),
            dimension: 2,
            time: 0.0,
            step: 0,
            status: "imported".into(),
            force_unit: "F0".into(),
            pressure_target: Some(0.01),
            cohesive: false,
            mu: Some(0.5),
            cell: Cell {
                lengths: vec![4.0, 4.0],
                contact_stress: vec![vec![0.0; 2]; 2],
                kinetic_stress: vec![vec![0.0; 2]; 2],
            },
            particles: Particles {
                radius: vec![0.5, 0.5],
                mass: vec![1.0, 1.0],
                position: vec![smallvec![1.0, 1.0], smallvec![2.0, 1.0]],
                velocity: vec![smallvec![0.0; 2]; 2],
                angular_velocity: vec![smallvec![0.0]; 2],
            },
            contacts: vec![Contact {
                i: 0,
                j: 1,
                branch: smallvec![1.0, 0.0],
                normal: 1e-3,
                normal_elastic: 1e-3,
                tangential: smallvec![0.0, 0.0],
                rolling: smallvec![],
                gap: 0.0,
            }],
        }
    }

    fn refused(edit: impl FnOnce(&mut Snapshot), field: &str) {
        let mut s = valid();
        edit(&mut s);
        let e = s
            .check()
            .expect_err("an impossible snapshot must be refused");
        assert!(e.contains(field), "{e:?} should name {field:?}");
    }

    /// Values no packing can have are refused, naming the field, instead of analysing to
    /// nonsense (docs/reliability.md).
    #[test]
    fn impossible_values_are_refused_naming_the_field() {
        valid().check().unwrap();
        refused(|s| s.particles.radius[1] = 0.0, "particles.radius[1]");
        refused(|s| s.particles.radius[0] = -0.5, "particles.radius[0]");
        refused(|s| s.particles.radius[0] = 1e300, "particles.radius[0]");
        refused(|s| s.particles.radius[0] = f64::NAN, "particles.radius[0]");
        refused(|s| s.cell.lengths[1] = 0.0, "cell.lengths[1]");
        refused(|s| s.cell.lengths[0] = -4.0, "cell.lengths[0]");
        refused(|s| s.particles.mass[0] = 0.0, "particles.mass[0]");
        // tests/fuzz.rs: a volume overflowing to ∞ gave Φ = 0; grains filling more than the
        // cell give Φ ≥ 1.
        refused(|s| s.cell.lengths = vec![1e200; 2], "cell volume of inf");
        refused(|s| s.cell.lengths = vec![1.5; 2], "less than two diameters");
        refused(
            |s| {
                // Six disks of diameter 1 in a 2 × 2 cell: Φ = 1.18.
                s.cell.lengths = vec![2.0; 2];
                let p = &mut s.particles;
                for k in 0..4 {
                    p.radius.push(0.5);
                    p.mass.push(1.0);
                    p.position.push(smallvec![0.1 * k as f64, 1.0]);
                    p.velocity.push(smallvec![0.0; 2]);
                }
            },
            "Φ =",
        );
        refused(
            |s| s.particles.position[1][0] = f64::NAN,
            "particles.position[1]",
        );
        refused(
            |s| s.particles.velocity[0][1] = f64::INFINITY,
            "particles.velocity[0]",
        );
        refused(|s| s.mu = Some(-0.1), "field `mu`");
        refused(|s| s.contacts[0].normal = f64::NAN, "contacts[0]");
        refused(
            |s| {
                let mut c = s.contacts[0].clone();
                (c.i, c.j) = (1, 0);
                s.contacts.push(c);
            },
            "contacts[1] and contacts[0]",
        );
    }

    /// A NaN written into the JSON text is named as such.
    #[test]
    fn nan_in_json_is_named() {
        let text = serde_json::to_string(&valid())
            .unwrap()
            .replace("\"time\":0.0", "\"time\":NaN");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.json");
        std::fs::write(&path, text).unwrap();
        let e = Snapshot::read(&path).unwrap_err().to_string();
        assert!(e.contains("NaN or infinite"), "{e}");
        assert!(e.contains("s.json"), "{e}");
    }
}
