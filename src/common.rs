//! What several commands share: the stop flag and its signal handler, the worker-thread
//! count, scene lookup, and the packing analysis of a snapshot.

use anyhow::{bail, Context, Result};
use grainbench_comparisons::metrics::{analyze, stiffness::ContactStiffness, Analysis, Options};
use grainbench_engine::{library, Scene, Snapshot};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set by the first Ctrl-C (or SIGTERM): runs stop cleanly at their next check.
pub static STOP: AtomicBool = AtomicBool::new(false);

/// Ctrl-C / SIGTERM: the first stops runs cleanly at their next check (external codes are
/// killed, logs kept); a second one exits at once.
pub fn install_stop_handler() {
    static HANDLER: std::sync::Once = std::sync::Once::new();
    HANDLER.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            if STOP.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
        });
    });
}

/// Sizes the global rayon pool (default: all cores, or `RAYON_NUM_THREADS`), its threads
/// with the main thread's 8 MiB stacks.
pub fn set_threads(threads: Option<usize>) -> Result<()> {
    if threads == Some(0) {
        bail!("-j 0: give a thread count ≥ 1, or omit -j to use every core");
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .stack_size(8 << 20)
        .build_global()
        .context("setting the thread count")?;
    Ok(())
}

/// Sizes the global pool ([`set_threads`]) and runs `work` on one of its threads, so that
/// each parallel pass of a step starts on a worker: with one thread it runs in place, with
/// more only the other workers are woken. Run from the main thread, every pass was handed to
/// the pool and back, a sleep and a wake-up each way, several times a step; the wake-up of a
/// halted virtual CPU can take as long as a worker's piece (docs/performance.md).
pub fn on_threads<R: Send>(
    threads: Option<usize>,
    work: impl FnOnce() -> Result<R> + Send,
) -> Result<R> {
    set_threads(threads)?;
    rayon::scope(|_| work())
}

/// Loads a scene from a file, or an embedded one by name.
pub fn load_scene(spec: &str) -> Result<Scene> {
    let path = Path::new(spec);
    if path.is_file() || (path.exists() && library::scene_text(spec).is_none()) {
        return Ok(Scene::from_file(path)?);
    }
    if let Some(scene) = library::scene(spec) {
        return Ok(scene?);
    }
    let names: Vec<&str> = library::SCENES.iter().map(|(n, _)| *n).collect();
    bail!(
        "no scene file {spec:?} and no embedded scene of that name (embedded: {}; `grainbench scenes` lists them)",
        names.join(", ")
    )
}

/// `grainbench scenes`: the embedded scenes, one line each.
pub fn list_scenes() -> Result<i32> {
    for (name, text) in library::SCENES {
        let scene = Scene::from_toml(text, Path::new(name))?;
        println!(
            "{name:<24} {}D N={:<6} {}",
            scene.dimension, scene.particles.count, scene.description
        );
    }
    Ok(0)
}

/// The packing metrics of a snapshot with the default options (as `analyze` prints them).
pub fn analysis_of(snap: &Snapshot) -> Analysis {
    analyze(snap, &Default::default())
}

/// The packing metrics of a snapshot with the elastic moduli of `scene`'s law (`compare`:
/// every code's final state under the one law).
pub fn analysis_with_moduli(snap: &Snapshot, scene: &Scene) -> Analysis {
    match ContactStiffness::of_scene(scene, snap) {
        Ok(k) => analyze(
            snap,
            &Options {
                moduli: Some(k),
                ..Default::default()
            },
        ),
        Err(e) => Analysis {
            moduli: Some(Err(e)),
            ..analysis_of(snap)
        },
    }
}

/// Seeds as a command line lists them: `1,2,3`.
pub fn seed_list(seeds: &[u64]) -> String {
    seeds
        .iter()
        .map(|s| s.to_string())
        .collect::<Vec<_>>()
        .join(",")
}
