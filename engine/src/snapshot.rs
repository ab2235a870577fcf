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
    pub position: Vec<Vec<f64>>,
    pub velocity: Vec<Vec<f64>>,
    /// One value per grain in 2D, three in 3D; empty when the law has no moments.
    #[serde(default)]
    pub angular_velocity: Vec<Vec<f64>>,
}

/// One interacting pair (in contact, or within the attraction range).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Contact {
    pub i: usize,
    pub j: usize,
    /// r_j − r_i, nearest periodic image.
    pub branch: Vec<f64>,
    /// Total normal force N (repulsive positive): elastic + viscous − adhesion.
    pub normal: f64,
    /// Elastic repulsive part N_e (the part the Coulomb and rolling thresholds use).
    pub normal_elastic: f64,
    /// Tangential force exerted by i on j.
    #[serde(default)]
    pub tangential: Vec<f64>,
    /// Rolling moment exerted by i on j (empty without rolling resistance).
    #[serde(default)]
    pub rolling: Vec<f64>,
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
        let text = std::fs::read_to_string(path).map_err(|error| SnapshotError::Io {
            path: p.clone(),
            error,
        })?;
        let snap: Snapshot = serde_json::from_str(&text).map_err(|e| SnapshotError::Parse {
            path: p.clone(),
            message: e.to_string(),
        })?;
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
        }
        Ok(())
    }

    /// Writes the snapshot atomically (temporary file in the same directory, then rename), so
    /// an interrupted write never leaves a truncated file in place of a good one.
    pub fn write(&self, path: &Path) -> Result<(), SnapshotError> {
        let text = serde_json::to_string(self).map_err(|e| SnapshotError::Invalid {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        write_atomic(path, text.as_bytes()).map_err(|error| SnapshotError::Io {
            path: path.display().to_string(),
            error,
        })
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

/// Writes `bytes` to `path` atomically: temporary file beside it, flushed, then renamed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => std::path::PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir)?;
    let mut tmp = tempfile::NamedTempFile::new_in(&dir)?;
    tmp.write_all(bytes)?;
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
