//! Reading other codes' final states into our snapshot format, so that every metric is
//! computed by the same `comparisons/` code for all codes (formats in
//! `docs/external-formats.md`).
//!
//! * [`lammps`]: `dump custom` of the atoms + `dump local` of `compute pair/local` and
//!   `compute property/local` (written by our LAMMPS decks).
//! * [`liggghts`]: `dump custom` of the atoms + `dump local` of `compute pair/gran/local`.
//! * [`yade`]: the text export our YADE scripts write (bodies, interactions, cell).
//! * [`generic`]: the exchange format's output (`particles.csv`, `contacts.csv`, `status.txt`).
//! * [`logs`]: what the codes' logs say (version, steps, loop time, why a run failed).
//!
//! Each reader returns [`Raw`] grains and contacts; [`assemble`] builds the snapshot (branch
//! vectors and gaps from the positions, contact stress from the forces, AR07 (8)).

pub mod by_code;
pub mod generic;
pub mod lammps;
pub mod liggghts;
pub mod logs;
pub mod trace;
pub mod yade;

pub use by_code::read;
use grainbench_engine::snapshot::{self, Snapshot, Vector};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What a dump does not say: written by `grainbench decks` as `deck.json` beside each deck.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Meta {
    pub scene: String,
    pub code: String,
    pub dimension: usize,
    /// Target pressure of the last stage (`null`: fixed cell).
    pub pressure_target: Option<f64>,
    pub cohesive: bool,
    /// Friction coefficient of the last stage (`null`: μ = ∞).
    pub mu: Option<f64>,
    pub force_unit: String,
    pub n: usize,
    /// FNV-1a 64 checksums of the deck's data files (name → hex), so the committed deck
    /// records the data file it was written with (data files are generated, not committed).
    #[serde(default)]
    pub data: std::collections::BTreeMap<String, String>,
    /// The trace the deck writes (scene `output.trace_every`), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trace: Option<TraceMeta>,
}

/// A deck's trace: every `every` steps, each grain with its force (`trace.rs`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TraceMeta {
    /// File in the run directory.
    pub file: String,
    pub every: u64,
    /// The time step of every stage (time = step × dt where the code writes no time).
    pub dt: Option<f64>,
    /// The contacts of every frame in their own dump (LAMMPS, LIGGGHTS: `trace.contacts`,
    /// frames matched by step); without it, YADE's `trace.txt` lists them in each frame, and a
    /// trace of two grains is closed by their net forces.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contacts: Option<String>,
}

impl Meta {
    pub const FILE: &'static str = "deck.json";

    pub fn read(dir: &Path) -> Result<Meta, ImportError> {
        let path = dir.join(Meta::FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| ImportError::new(&path, e))?;
        serde_json::from_str(&text).map_err(|e| ImportError::new(&path, e))
    }
}

/// A reader's error: the file and what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct ImportError {
    pub path: PathBuf,
    pub message: String,
}

impl ImportError {
    pub fn new(path: &Path, message: impl std::fmt::Display) -> Self {
        ImportError {
            path: path.to_path_buf(),
            message: message.to_string(),
        }
    }
}

/// Grains and contacts as a code wrote them, indices 0-based in the order of `position`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Raw {
    /// Cell side lengths; the cell is `[origin, origin + L)`.
    pub lengths: Vec<f64>,
    pub origin: Vec<f64>,
    pub position: Vec<Vec<f64>>,
    pub velocity: Vec<Vec<f64>>,
    pub angular_velocity: Vec<Vec<f64>>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub contacts: Vec<RawContact>,
    pub time: f64,
    pub step: u64,
    /// `equilibrium`, `time-limit`, … as the deck recorded it (`imported` if unknown).
    pub status: String,
}

/// One contact: i < j or not, the force on j is `normal`·n + `tangential` with n the unit
/// vector from i to j.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RawContact {
    pub i: usize,
    pub j: usize,
    /// Total normal force, repulsive positive.
    pub normal: f64,
    /// Elastic repulsive part, where the code gives it (else `normal` is used).
    pub normal_elastic: Option<f64>,
    /// Tangential force on j (empty: frictionless).
    pub tangential: Vec<f64>,
    /// Rolling moment on j (empty: none).
    pub rolling: Vec<f64>,
}

/// Builds a snapshot: positions wrapped into `[0, L)`, branch vectors by the nearest image,
/// gaps from the radii, contact stress σ_αβ = Σ f_α ℓ_β / Ω (AR07 (8)), kinetic stress.
pub fn assemble(raw: Raw, meta: &Meta) -> Result<Snapshot, String> {
    let d = meta.dimension;
    let n = raw.position.len();
    if raw.lengths.len() < d {
        return Err(format!(
            "cell has {} lengths, dimension {d}",
            raw.lengths.len()
        ));
    }
    if raw.radius.len() != n || raw.mass.len() != n {
        return Err(format!(
            "{} positions, {} radii, {} masses",
            n,
            raw.radius.len(),
            raw.mass.len()
        ));
    }
    check_against_deck(&raw, meta)?;
    let l: Vec<f64> = raw.lengths[..d].to_vec();
    let origin: Vec<f64> = if raw.origin.len() >= d {
        raw.origin[..d].to_vec()
    } else {
        vec![0.0; d]
    };
    let position: Vec<Vector> = raw
        .position
        .iter()
        .map(|p| {
            (0..d)
                .map(|a| (p[a] - origin[a]).rem_euclid(l[a]))
                .collect()
        })
        .collect();
    let omega: f64 = l.iter().product();
    let mut stress = vec![vec![0.0; d]; d];
    let mut contacts = Vec::with_capacity(raw.contacts.len());
    for c in &raw.contacts {
        if c.i >= n || c.j >= n {
            return Err(format!(
                "contact ({}, {}) names a grain beyond the {n} read",
                c.i, c.j
            ));
        }
        let branch = branch(&position, &l, c.i, c.j, d);
        let dist = branch.iter().map(|x| x * x).sum::<f64>().sqrt();
        if dist == 0.0 {
            return Err(format!(
                "contact ({}, {}) joins coincident grains",
                c.i, c.j
            ));
        }
        // μ = 0: the tangential columns were checked to be ~0 and are left out.
        let tangential: &[f64] = if meta.mu == Some(0.0) {
            &[]
        } else {
            &c.tangential
        };
        let mut force: Vec<f64> = branch.iter().map(|x| c.normal * x / dist).collect();
        for (a, t) in tangential.iter().take(d).enumerate() {
            force[a] += t;
        }
        for a in 0..d {
            for b in 0..d {
                stress[a][b] += force[a] * branch[b] / omega;
            }
        }
        contacts.push(snapshot::Contact {
            i: c.i,
            j: c.j,
            gap: dist - raw.radius[c.i] - raw.radius[c.j],
            branch: Vector::from_slice(&branch),
            normal: c.normal,
            normal_elastic: c.normal_elastic.unwrap_or(c.normal),
            tangential: if tangential.is_empty() {
                Vector::new()
            } else {
                Vector::from_slice(&tangential[..d])
            },
            rolling: Vector::from_slice(&c.rolling),
        });
    }
    let mut kinetic = vec![vec![0.0; d]; d];
    for (v, m) in raw.velocity.iter().zip(&raw.mass) {
        for a in 0..d {
            for b in 0..d {
                kinetic[a][b] += m * v[a] * v[b] / omega;
            }
        }
    }
    let velocity = if raw.velocity.len() == n {
        raw.velocity
            .iter()
            .map(|v| Vector::from_slice(&v[..d]))
            .collect()
    } else {
        vec![Vector::from_elem(0.0, d); n]
    };
    let snap = Snapshot {
        format: snapshot::FORMAT.into(),
        version: snapshot::VERSION,
        code: meta.code.clone(),
        scene: meta.scene.clone(),
        dimension: d,
        time: raw.time,
        step: raw.step,
        status: if raw.status.is_empty() {
            "imported".into()
        } else {
            raw.status
        },
        force_unit: meta.force_unit.clone(),
        pressure_target: meta.pressure_target,
        cohesive: meta.cohesive,
        mu: meta.mu,
        cell: snapshot::Cell {
            lengths: l,
            contact_stress: stress,
            kinetic_stress: kinetic,
        },
        particles: snapshot::Particles {
            radius: raw.radius,
            mass: raw.mass,
            position,
            velocity,
            angular_velocity: raw
                .angular_velocity
                .iter()
                .map(|w| Vector::from_slice(w))
                .collect(),
        },
        contacts,
    };
    snap.check()?;
    Ok(snap)
}

/// What `deck.json` promises against what the dumps hold (a deck.json saying 2D for 3D dumps,
/// or μ = 0 for frictional ones, would silently change the result). The grain count is
/// checked by each reader.
fn check_against_deck(raw: &Raw, meta: &Meta) -> Result<(), String> {
    if meta.dimension == 2 {
        flat(
            raw.position.iter().filter_map(|p| p.get(2).copied()),
            &raw.radius,
        )?;
    }
    if meta.mu == Some(0.0) {
        let n_max = raw
            .contacts
            .iter()
            .map(|c| c.normal.abs())
            .fold(0.0, f64::max);
        let t_max = raw
            .contacts
            .iter()
            .flat_map(|c| c.tangential.iter().map(|t| t.abs()))
            .fold(0.0, f64::max);
        // LIGGGHTS's tangential part is the total force less its projection on the normal
        // from the dumped positions, which leaves ~2e-6 of the forces (xcode-sjkr-smoke);
        // a frictional packing's |T| is of order μN.
        if t_max > 1e-3 * n_max {
            return Err(format!(
                "deck.json says μ = 0, but contacts carry tangential forces up to {t_max:.4e} (normal forces up to {n_max:.4e}): the dumps are frictional; give the deck.json of the run that wrote them"
            ));
        }
    }
    Ok(())
}

/// A 2D deck's grains all lie in one plane z = const (to 1e-6 of the largest radius).
fn flat(z: impl Iterator<Item = f64>, radius: &[f64]) -> Result<(), String> {
    let (lo, hi) = z.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
        (a.min(z), b.max(z))
    });
    let r_max = radius.iter().copied().fold(0.0, f64::max);
    if hi - lo > 1e-6 * r_max {
        return Err(format!(
            "deck.json says dimension 2, but the grains' z coordinates span {:.4e}: the dumps are 3D; give the deck.json of the run that wrote them",
            hi - lo
        ));
    }
    Ok(())
}

/// Whitespace-separated numeric columns of a LAMMPS/LIGGGHTS dump section, located by the
/// `ITEM: <name> <columns…>` header: returns (column names, rows, header values before it).
pub struct DumpSection {
    pub timestep: u64,
    /// `ITEM: TIME` just before the frame (`dump_modify time yes`), if written.
    pub time: Option<f64>,
    /// Box bounds (lo, hi) per axis.
    pub bounds: Vec<(f64, f64)>,
    pub columns: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

/// Parses the last frame of a LAMMPS-style dump (`ITEM: TIMESTEP`, `ITEM: BOX BOUNDS`, then
/// `ITEM: ATOMS …` or `ITEM: ENTRIES …`).
pub fn last_dump_frame(path: &Path) -> Result<DumpSection, ImportError> {
    let text = std::fs::read_to_string(path).map_err(|e| ImportError::new(path, e))?;
    let start = text.rfind("ITEM: TIMESTEP").ok_or_else(|| {
        ImportError::new(path, "no `ITEM: TIMESTEP` line: not a LAMMPS-style dump")
    })?;
    // Lines numbered from 1 in the whole file, for the messages.
    let first_line = text[..start].matches('\n').count() + 1;
    dump_frame(path, &text, 0, start, text.len(), first_line)
}

/// Every frame of a LAMMPS-style dump, in file order (a trace: `dump … N file` without `*`).
pub fn dump_frames(path: &Path) -> Result<Vec<DumpSection>, ImportError> {
    let text = std::fs::read_to_string(path).map_err(|e| ImportError::new(path, e))?;
    let starts: Vec<usize> = text
        .match_indices("ITEM: TIMESTEP")
        .map(|(k, _)| k)
        .collect();
    if starts.is_empty() {
        return Err(ImportError::new(
            path,
            "no `ITEM: TIMESTEP` line: not a LAMMPS-style dump",
        ));
    }
    let (mut from, mut line, mut counted) = (0, 1, 0);
    let mut frames = Vec::with_capacity(starts.len());
    for (k, &start) in starts.iter().enumerate() {
        let next = starts.get(k + 1).copied().unwrap_or(text.len());
        // The next frame's `ITEM: TIME` (`dump_modify time yes`) precedes its TIMESTEP.
        let end = text[start..next]
            .rfind("ITEM: TIME\n")
            .map_or(next, |t| start + t);
        line += text[counted..start].matches('\n').count();
        counted = start;
        frames.push(dump_frame(path, &text, from, start, end, line)?);
        from = end;
    }
    Ok(frames)
}

/// The frame of `text` that starts at `start` (its `ITEM: TIMESTEP`, on line `first_line`) and
/// ends at `end`; its `ITEM: TIME`, if any, lies in `from..start`.
fn dump_frame(
    path: &Path,
    text: &str,
    from: usize,
    start: usize,
    end: usize,
    first_line: usize,
) -> Result<DumpSection, ImportError> {
    let mut lines = text[start..end]
        .lines()
        .enumerate()
        .map(|(k, l)| (first_line + k, l));
    let mut promised: Option<(usize, usize)> = None;
    // `dump_modify time yes` writes `ITEM: TIME` and its value right before `ITEM: TIMESTEP`.
    let time = match text[from..start].rfind("ITEM: TIME\n").map(|k| from + k) {
        Some(k) if text[k..start].lines().count() == 2 => {
            let v = text[k..start].lines().nth(1).unwrap_or("").trim();
            Some(
                v.parse()
                    .map_err(|e| ImportError::new(path, format!("time {v:?}: {e}")))?,
            )
        }
        _ => None,
    };
    let mut sec = DumpSection {
        timestep: 0,
        time,
        bounds: Vec::new(),
        columns: Vec::new(),
        rows: Vec::new(),
    };
    while let Some((_, line)) = lines.next() {
        if line.starts_with("ITEM: TIMESTEP") {
            let (_, v) = lines
                .next()
                .ok_or_else(|| ImportError::new(path, "missing timestep value"))?;
            sec.timestep = v
                .trim()
                .parse()
                .map_err(|e| ImportError::new(path, format!("timestep {v:?}: {e}")))?;
        } else if line.starts_with("ITEM: NUMBER OF") {
            let (at, v) = lines
                .next()
                .ok_or_else(|| ImportError::new(path, format!("missing value after {line:?}")))?;
            let count = v
                .trim()
                .parse()
                .map_err(|e| ImportError::new(path, format!("line {at}: {line} {v:?}: {e}")))?;
            promised = Some((count, at));
        } else if line.starts_with("ITEM: BOX BOUNDS") {
            for _ in 0..3 {
                let (_, b) = lines
                    .next()
                    .ok_or_else(|| ImportError::new(path, "box bounds cut short"))?;
                let v: Vec<f64> = b
                    .split_whitespace()
                    .map(|x| x.parse::<f64>())
                    .collect::<Result<_, _>>()
                    .map_err(|e| ImportError::new(path, format!("box bounds {b:?}: {e}")))?;
                if v.len() < 2 {
                    return Err(ImportError::new(path, format!("box bounds {b:?}")));
                }
                sec.bounds.push((v[0], v[1]));
            }
        } else if let Some(rest) = line
            .strip_prefix("ITEM: ATOMS")
            .or_else(|| line.strip_prefix("ITEM: ENTRIES"))
        {
            sec.columns = rest.split_whitespace().map(str::to_string).collect();
            for (at, row) in lines.by_ref() {
                // The last frame runs to the end of the file: any other item is damage
                // (tests/fuzz.rs: a header line swapped into the rows cut the frame short).
                if row.starts_with("ITEM:") {
                    return Err(ImportError::new(
                        path,
                        format!("line {at}: {row:?} among the rows of the last frame: the dump is damaged; rerun the code or restore the file"),
                    ));
                }
                if row.trim().is_empty() {
                    continue;
                }
                let v: Vec<f64> = row
                    .split_whitespace()
                    .map(|x| x.parse::<f64>())
                    .collect::<Result<_, _>>()
                    .map_err(|e| ImportError::new(path, format!("line {at}: row {row:?}: {e}")))?;
                if v.len() != sec.columns.len() {
                    return Err(ImportError::new(
                        path,
                        format!(
                            "line {at}: row {row:?} has {} values for {} columns",
                            v.len(),
                            sec.columns.len()
                        ),
                    ));
                }
                if let Some(c) = v.iter().position(|x| !x.is_finite()) {
                    return Err(ImportError::new(
                        path,
                        format!(
                            "line {at}: column `{}` is {}: the code that wrote the dump failed (a non-finite position or force cannot be analysed)",
                            sec.columns[c], v[c]
                        ),
                    ));
                }
                sec.rows.push(v);
            }
            // Without this check a dump cut at a line end would import silently (z halved).
            let Some((count, at)) = promised else {
                return Err(ImportError::new(
                    path,
                    "the last frame has no `ITEM: NUMBER OF …` line before its rows (LAMMPS writes one): the dump is damaged",
                ));
            };
            if count != sec.rows.len() {
                return Err(ImportError::new(
                    path,
                    format!(
                        "the last frame promises {count} rows (line {at}, `ITEM: NUMBER OF …`) but holds {}: the dump is cut short or damaged; rerun the code or restore the file",
                        sec.rows.len()
                    ),
                ));
            }
            break;
        }
    }
    if sec.columns.is_empty() {
        return Err(ImportError::new(
            path,
            "no `ITEM: ATOMS` or `ITEM: ENTRIES` section in the last frame",
        ));
    }
    Ok(sec)
}

impl DumpSection {
    /// Index of a column, or an error naming the columns present.
    pub fn col(&self, path: &Path, name: &str) -> Result<usize, ImportError> {
        self.columns.iter().position(|c| c == name).ok_or_else(|| {
            ImportError::new(
                path,
                format!("no column `{name}` (columns: {})", self.columns.join(" ")),
            )
        })
    }
}

/// The atoms of the last frame of a LAMMPS-style `dump custom` (columns `id radius mass x y z`
/// required, `vx vy vz` and `omegax omegay omegaz` optional), in id order, with the map from
/// atom id to index. Box, step and (if written) time come from the frame header.
pub fn read_atoms(
    path: &Path,
    meta: &Meta,
) -> Result<(Raw, std::collections::HashMap<i64, usize>), ImportError> {
    atoms_of(path, &last_dump_frame(path)?, meta)
}

/// The atoms of one frame of a `dump custom` (as [`read_atoms`]).
pub fn atoms_of(
    path: &Path,
    sec: &DumpSection,
    meta: &Meta,
) -> Result<(Raw, std::collections::HashMap<i64, usize>), ImportError> {
    let d = meta.dimension;
    if sec.bounds.len() < d {
        return Err(ImportError::new(path, "no box bounds in the last frame"));
    }
    let (id, rad, mass) = (
        sec.col(path, "id")?,
        sec.col(path, "radius")?,
        sec.col(path, "mass")?,
    );
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
    let mut rows: Vec<&Vec<f64>> = sec.rows.iter().collect();
    rows.sort_by(|a, b| a[id].total_cmp(&b[id]));
    if meta.n != 0 && rows.len() != meta.n {
        return Err(ImportError::new(
            path,
            format!("{} atoms, deck.json says {}", rows.len(), meta.n),
        ));
    }
    let index: std::collections::HashMap<i64, usize> = rows
        .iter()
        .enumerate()
        .map(|(k, r)| (r[id].round() as i64, k))
        .collect();
    if index.len() != rows.len() {
        return Err(ImportError::new(path, "repeated atom ids"));
    }
    if d == 2 {
        let radius: Vec<f64> = rows.iter().map(|r| r[rad]).collect();
        flat(rows.iter().map(|r| r[x[2]]), &radius).map_err(|e| ImportError::new(path, e))?;
    }
    let mut raw = Raw {
        lengths: sec.bounds.iter().map(|(lo, hi)| hi - lo).collect(),
        origin: sec.bounds.iter().map(|(lo, _)| *lo).collect(),
        step: sec.timestep,
        time: sec.time.unwrap_or(0.0),
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
    Ok((raw, index))
}

/// r_j − r_i by the nearest periodic image (first `d` axes).
pub fn branch(
    position: &[impl std::ops::Deref<Target = [f64]>],
    lengths: &[f64],
    i: usize,
    j: usize,
    d: usize,
) -> Vec<f64> {
    (0..d)
        .map(|a| {
            let x = position[j][a] - position[i][a];
            x - lengths[a] * (x / lengths[a]).round()
        })
        .collect()
}

/// The unit vector from grain i to grain j by the nearest image; `None` if they coincide.
pub fn unit_normal(raw: &Raw, i: usize, j: usize, d: usize) -> Option<Vec<f64>> {
    let b = branch(&raw.position, &raw.lengths, i, j, d);
    let len = b.iter().map(|x| x * x).sum::<f64>().sqrt();
    (len > 0.0).then(|| b.iter().map(|x| x / len).collect())
}

/// Reads a one-word status file a deck writes at its end (`equilibrium`, `time-limit`).
pub fn read_status(path: &Path) -> String {
    std::fs::read_to_string(path)
        .map(|s| {
            s.split_whitespace()
                .last()
                .unwrap_or("imported")
                .to_string()
        })
        .unwrap_or_else(|_| "imported".into())
}
