//! `grainbench analyze`: the packing metrics of a snapshot, or of another code's final dumps.

use crate::common::{contact_stiffness, load_scene};
use anyhow::{anyhow, bail, Context, Result};
use grainbench_comparisons::metrics::{analyze as measure, stiffness::ContactStiffness, Options};
use grainbench_comparisons::xcode::{import, Code};
use grainbench_engine::Snapshot;
use std::path::Path;

/// What `analyze` measures besides the defaults.
pub struct Extra<'a> {
    /// Elastic moduli and rigidity (GRC08 §VI, GRC07 App. A).
    pub moduli: bool,
    /// The scene whose law gives the contact stiffnesses (default: the snapshot's scene).
    pub scene: Option<&'a str>,
    /// Directory for the ParaView files of the snapshot.
    pub vtk: Option<&'a Path>,
}

/// `grainbench analyze SNAPSHOT [--from CODE] [--write FILE] [--json] [--moduli [--scene S]] [--vtk DIR]`.
pub fn analyze(
    path: &Path,
    json: bool,
    from: Option<&str>,
    write: Option<&Path>,
    extra: &Extra,
) -> Result<i32> {
    let snap = match from {
        None => Snapshot::read(path)?,
        Some(name) => {
            let code = match Code::parse(name) {
                Some(Code::Rust) | None => {
                    bail!("--from: expected lammps, liggghts or yade, got `{name}`")
                }
                Some(c) => c,
            };
            if !path.is_dir() {
                bail!(
                    "--from {name}: {} is not a directory (give the directory holding the final dumps and deck.json)",
                    path.display()
                );
            }
            let meta = import::Meta::read(path)?;
            import::read(code, path, &meta)?
        }
    };
    if let Some(w) = write {
        snap.write(w)?;
    }
    let mut opts = Options::default();
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
    contact_stiffness(&sc, snap).map_err(|e| anyhow!("--scene {spec}: {e}"))
}
