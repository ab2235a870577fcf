//! `grainbench analyze`: the packing metrics of a snapshot, or of another code's final dumps.

use crate::common::load_scene;
use anyhow::{anyhow, bail, Context, Result};
use grainbench_comparisons::metrics::{analyze as measure, stiffness::ContactStiffness, Options};
use grainbench_comparisons::xcode::{import, Code};
use grainbench_engine::Snapshot;
use std::path::{Path, PathBuf};

/// The arguments of `grainbench analyze`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A grainbench snapshot, or with --from a directory of another code's final dumps.
    pub snapshot: PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Read the final state of another code from a directory: `lammps` (dump custom +
    /// dump local), `liggghts` (dump custom + pair/gran/local), `yade` (text export); formats
    /// in docs/external-formats/. Our decks write a `deck.json` beside them; for dumps of
    /// your own deck give --dimension, --mu, --pressure and --force-unit.
    #[arg(long, value_name = "CODE")]
    pub from: Option<String>,
    /// With --from: 2 or 3 (overrides deck.json).
    #[arg(long)]
    pub dimension: Option<usize>,
    /// With --from: μ of the last stage, a number or `inf` (overrides deck.json).
    #[arg(long, value_name = "MU")]
    pub mu: Option<String>,
    /// With --from: target pressure of the last stage, or `none` for a fixed cell (overrides
    /// deck.json).
    #[arg(long, value_name = "P")]
    pub pressure: Option<String>,
    /// With --from: the force unit of the dumps, e.g. "P_ref a^2" or F0 (overrides deck.json).
    #[arg(long, value_name = "TEXT")]
    pub force_unit: Option<String>,
    /// With --from: an adhesive law (pairs within the attraction range are dumped).
    #[arg(long)]
    pub cohesive: bool,
    /// Also write the state read as a grainbench snapshot.
    #[arg(long, value_name = "FILE")]
    pub write: Option<PathBuf>,
    /// Also the elastic moduli B, G with their Voigt and Reuss estimates, the energy
    /// concentration of a pressure increment (GRC08 §VI) and the mechanisms and force
    /// indeterminacy of the network (GRC07 App. A), from its stiffness matrix.
    #[arg(long)]
    pub moduli: bool,
    /// With --moduli: the scene (file or embedded name) whose law gives the contact
    /// stiffnesses (default: the scene the snapshot names).
    #[arg(long, value_name = "SCENE")]
    pub scene: Option<String>,
    /// Also write the snapshot for ParaView into DIR: particles.vtu (grains with diameter,
    /// velocity, spin, contact count), contacts.vtu (lines with normal and tangential
    /// force) and snapshot.pvd grouping them.
    #[arg(long, value_name = "DIR")]
    pub vtk: Option<PathBuf>,
    /// Cohesive snapshots: the normal force, in F0, at or below which an interaction counts
    /// as unstressed in GRC07 T.VI's split z = z+ + z− + z0 (default 1e-4, T.VI's
    /// tolerance; GRC07 §IV.C separates loops with RR at 1e-2).
    #[arg(long, value_name = "F")]
    pub cohesive_tolerance: Option<f64>,
}

/// `grainbench analyze`.
pub fn command(a: Args) -> Result<i32> {
    analyze(
        &a.snapshot,
        a.json,
        a.from.as_deref(),
        &DumpMeta {
            dimension: a.dimension,
            mu: a.mu,
            pressure: a.pressure,
            force_unit: a.force_unit,
            cohesive: a.cohesive,
        },
        a.write.as_deref(),
        &Extra {
            moduli: a.moduli,
            scene: a.scene.as_deref(),
            vtk: a.vtk.as_deref(),
            cohesive_tolerance: a.cohesive_tolerance,
        },
    )
}

/// What a user's own dumps do not say (`analyze --from` without a `deck.json`), or overrides
/// of it.
#[derive(Default)]
pub struct DumpMeta {
    pub dimension: Option<usize>,
    /// μ of the last stage: a number or `inf`.
    pub mu: Option<String>,
    /// Target pressure of the last stage, or `none` (fixed cell).
    pub pressure: Option<String>,
    pub force_unit: Option<String>,
    /// Adhesive law: pairs dumped within the attraction range (LAMMPS rows without force are
    /// dropped).
    pub cohesive: bool,
}

impl DumpMeta {
    fn given(&self) -> bool {
        self.dimension.is_some()
            || self.mu.is_some()
            || self.pressure.is_some()
            || self.force_unit.is_some()
            || self.cohesive
    }

    /// `deck.json` of `dir` with these overrides, or these alone when there is none (all four
    /// needed then, each missing one named).
    fn meta(&self, dir: &Path, code: Code) -> Result<import::Meta> {
        let file = dir.join(import::Meta::FILE);
        let mut meta = if file.exists() {
            import::Meta::read(dir)?
        } else {
            let missing: Vec<&str> = [
                ("--dimension 2|3", self.dimension.is_none()),
                ("--mu X|inf (μ of the last stage)", self.mu.is_none()),
                (
                    "--pressure P|none (target of the last stage; none: fixed cell)",
                    self.pressure.is_none(),
                ),
                (
                    "--force-unit TEXT (e.g. \"P_ref a^2\" or F0)",
                    self.force_unit.is_none(),
                ),
            ]
            .into_iter()
            .filter_map(|(o, m)| m.then_some(o))
            .collect();
            if !missing.is_empty() {
                bail!(
                    "--from {code}: {} has no deck.json (our decks write one); for dumps of your own deck give {}",
                    dir.display(),
                    missing.join(", ")
                );
            }
            import::Meta {
                scene: dir
                    .file_name()
                    .map_or("imported".into(), |n| n.to_string_lossy().into_owned()),
                code: code.name().into(),
                dimension: 0,
                pressure_target: None,
                cohesive: false,
                mu: None,
                force_unit: String::new(),
                n: 0,
                data: Default::default(),
                trace: None,
            }
        };
        if let Some(d) = self.dimension {
            if d != 2 && d != 3 {
                bail!("--dimension {d}: 2 (disks) or 3 (spheres)");
            }
            meta.dimension = d;
        }
        if let Some(mu) = &self.mu {
            meta.mu = match mu.as_str() {
                "inf" | "infinity" => None,
                x => Some(
                    x.parse::<f64>()
                        .ok()
                        .filter(|m| m.is_finite() && *m >= 0.0)
                        .ok_or_else(|| anyhow!("--mu {x}: a number ≥ 0, or inf"))?,
                ),
            };
        }
        if let Some(p) = &self.pressure {
            meta.pressure_target = match p.as_str() {
                "none" => None,
                x => Some(
                    x.parse::<f64>()
                        .ok()
                        .filter(|p| p.is_finite() && *p >= 0.0)
                        .ok_or_else(|| anyhow!("--pressure {x}: a number ≥ 0, or none"))?,
                ),
            };
        }
        if let Some(u) = &self.force_unit {
            meta.force_unit = u.clone();
        }
        meta.cohesive |= self.cohesive;
        Ok(meta)
    }
}

/// What `analyze` measures besides the defaults.
pub struct Extra<'a> {
    /// Elastic moduli and rigidity (GRC08 §VI, GRC07 App. A).
    pub moduli: bool,
    /// The scene whose law gives the contact stiffnesses (default: the snapshot's scene).
    pub scene: Option<&'a str>,
    /// Directory for the ParaView files of the snapshot.
    pub vtk: Option<&'a Path>,
    /// Cohesive snapshots: the tolerance of GRC07 T.VI's split, in F0 (default 1e-4).
    pub cohesive_tolerance: Option<f64>,
}

/// `grainbench analyze SNAPSHOT [--from CODE] [--write FILE] [--json] [--moduli [--scene S]] [--vtk DIR]
/// [--cohesive-tolerance F]`.
fn analyze(
    path: &Path,
    json: bool,
    from: Option<&str>,
    dump: &DumpMeta,
    write: Option<&Path>,
    extra: &Extra,
) -> Result<i32> {
    if let Some(t) = extra.cohesive_tolerance {
        if !(t.is_finite() && t > 0.0) {
            bail!("--cohesive-tolerance {t}: a force in F0 above zero (GRC07 T.VI: 1e-4)");
        }
    }
    if from.is_none() && dump.given() {
        bail!("--dimension, --mu, --pressure, --force-unit and --cohesive describe another code's dumps: add --from lammps|liggghts|yade");
    }
    let snap = match from {
        None => Snapshot::read(path)?,
        Some(name) => {
            let code = match Code::parse(name) {
                Some(Code::Rust | Code::Generic | Code::Adapter(_)) | None => {
                    bail!("--from: expected lammps, lammps-2025, liggghts or yade, got `{name}`")
                }
                Some(c) => c,
            };
            if !path.is_dir() {
                bail!(
                    "--from {name}: {} is not a directory (give the directory holding the final dumps)",
                    path.display()
                );
            }
            let meta = dump.meta(path, code)?;
            import::read(code, path, &meta)?
        }
    };
    if extra.cohesive_tolerance.is_some() && !snap.cohesive {
        bail!(
            "--cohesive-tolerance sets GRC07 T.VI's split of a cohesive packing; {} is cohesionless (its force threshold is relative to ⟨|N|⟩)",
            path.display()
        );
    }
    if let Some(w) = write {
        snap.write(w)?;
    }
    let mut opts = Options::default();
    if let Some(t) = extra.cohesive_tolerance {
        opts.cohesive_tolerance = t;
    }
    if extra.moduli {
        opts.moduli = Some(stiffness_of(&snap, extra.scene)?);
    } else if extra.scene.is_some() {
        bail!("--scene gives the law for --moduli: add --moduli");
    }
    let a = measure(&snap, &opts);
    if let Some(dir) = extra.vtk {
        let files = grainbench_comparisons::report::vtk::write_vtk(&snap, dir)
            .with_context(|| format!("--vtk: writing into {}", dir.display()))?;
        eprintln!(
            "wrote {}, {}, {} (ParaView)",
            files.collection.display(),
            files.particles.display(),
            files.contacts.display()
        );
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&a)?);
    } else {
        print!("{}", grainbench_comparisons::report::to_markdown(&a));
    }
    Ok(0)
}

/// The contact stiffnesses of the snapshot's law: from `scene` (a file or an embedded name),
/// else from the embedded scene the snapshot names.
fn stiffness_of(snap: &Snapshot, scene: Option<&str>) -> Result<ContactStiffness> {
    let spec = scene.unwrap_or(&snap.scene);
    let sc = load_scene(spec).with_context(|| match scene {
        Some(s) => format!("--scene {s}"),
        None => format!(
            "--moduli needs the contact law, which a snapshot does not carry: its scene `{}` is not embedded; give the scene with --scene FILE|NAME",
            snap.scene
        ),
    })?;
    ContactStiffness::of_scene(&sc, snap).map_err(|e| anyhow!("--scene {spec}: {e}"))
}
