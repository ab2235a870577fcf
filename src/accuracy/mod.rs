//! `grainbench accuracy SCENE`: speed against error.
//!
//! Sweeps the numerical knobs that trade wall time for accuracy, one at a time from the
//! scene's settings, over several seeds:
//!
//! * `dt`: the time step as a fraction of the binary contact duration (`numerics.dt_fraction`);
//!   values past the stable step are expected to stop with the engine's instability error,
//!   and are tabled as `unstable: <message>` with no error;
//! * `inertia`: the strain-rate cap of the stress-controlled stages, AR07 (23)
//!   `I = ε̇√(m/(aP))` (GRC08 `I_a = ε̇_max T0` with cohesion); every stage's cap is scaled by the
//!   same factor, so the value given is the cap of the first capped stage;
//! * `tolerance`: a factor on every equilibrium criterion of every stage (AR07 §III, GRC07
//!   §II.D: force, moment, stress and kinetic-energy thresholds);
//! * `kappa`: the contact stiffness κ (AR07 (21) `κ = (Ẽ/P)^{2/3}`, GRC07 `κ = K_N a/F0`); the
//!   papers' rigid limit needs κ ≳ 1e4 (AR07 §IV.A, GRC07 §II.C), so κ is a physical
//!   parameter as much as a numerical one: its "error" is the distance to the stiffest κ swept.
//!
//! The reference is the run with the tightest value of every knob at once (smallest dt, I and
//! tolerance factor, largest κ), same seeds. The error of a point is the mean over seeds of
//! |metric − reference of the same seed| for Φ, z* and x0, and the mean over seeds of the
//! two-sample Kolmogorov–Smirnov distance between its forces f = N/⟨N⟩ and the pooled
//! reference forces. The reference's seed-to-seed spread is reported beside, to tell error
//! from sample noise; where the scene reproduces a published state (`paper_state`), the
//! distance of the seed mean to the paper's value (comparisons/src/paper.rs) is reported too.
//!
//! External codes expose fewer knobs: the LAMMPS deck takes our time step (`timestep`, from
//! the same `dt_fraction`), so `--codes lammps` adds a LAMMPS curve for the `dt` knob, its error
//! taken against the LAMMPS run at the smallest dt. LAMMPS has no strain-rate cap of our kind
//! (fix press/berendsen), no equilibrium criteria of ours (it runs the deck's fixed number of
//! steps) and its κ is our κ converted to a modulus, fixed by the deck: only `dt` is swept there.

use crate::common::{install_stop_handler, load_scene, on_threads, STOP};
use crate::external;
use anyhow::{bail, Context, Result};
use grainbench_comparisons::outcome::Outcome;
use grainbench_comparisons::xcode::crosscode::CodeResult;
use grainbench_comparisons::xcode::decks::{Code, Start};
use grainbench_engine::run::{RunError, RunOptions, StepEnd};
use grainbench_engine::snapshot::write_atomic;
use grainbench_engine::Scene;
use knobs::{apply, normalize, Knob, Point, Settings};
use output::write_outputs;
use record::{measure, short_message, Record};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::Instant;
use table::build_table;

mod knobs;
mod output;
mod record;
mod table;

/// Command-line arguments.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file or embedded scene name.
    pub scene: String,
    /// Seeds, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,2,3")]
    pub seeds: Vec<u64>,
    /// Knobs to sweep, comma-separated: dt, inertia, tolerance, kappa (default: all).
    #[arg(long, value_delimiter = ',')]
    pub knobs: Vec<String>,
    /// Codes: rust (all knobs), lammps (dt only). Default: rust.
    #[arg(long, value_delimiter = ',')]
    pub codes: Vec<String>,
    /// Output directory (default: `runs/accuracy/<scene>`).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// dt_fraction values instead of 0.005,0.01,0.02,0.04,0.08,0.16,0.3,0.5,1.
    #[arg(long, value_delimiter = ',')]
    pub dt: Vec<f64>,
    /// Strain-rate caps I instead of 1e-3,3e-3,1e-2,3e-2,1e-1.
    #[arg(long, value_delimiter = ',')]
    pub inertia: Vec<f64>,
    /// Factors on the equilibrium criteria instead of 0.3,1,3,10.
    #[arg(long, value_delimiter = ',')]
    pub tolerance: Vec<f64>,
    /// κ values instead of 1e4,39000,181000 (Hertz) or 1e4,1e5 (linear).
    #[arg(long, value_delimiter = ',')]
    pub kappa: Vec<f64>,
    /// Cap on the time of every DEM stage, reduced units (short sweeps).
    #[arg(long, value_name = "T")]
    pub max_time: Option<f64>,
    /// Wall-time limit of each external run, seconds.
    #[arg(long, default_value_t = 3600.0, value_name = "SECS")]
    pub time_limit: f64,
    /// Rerun points already in the output directory.
    #[arg(long)]
    pub fresh: bool,
    /// Worker threads of our engine.
    #[arg(long, short = 'j')]
    pub threads: Option<usize>,
    /// No progress lines.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `grainbench accuracy`.
pub fn command(a: Args) -> Result<i32> {
    on_threads(a.threads, || accuracy(&a))
}

fn accuracy(a: &Args) -> Result<i32> {
    let base = load_scene(&a.scene)?;
    if a.seeds.is_empty() {
        bail!("--seeds needs at least one seed (e.g. --seeds 1,2,3)");
    }
    let mut base = base;
    if let Some(t) = a.max_time {
        if !(t.is_finite() && t > 0.0) {
            bail!("--max-time must be a positive number of reduced time units, got {t}");
        }
        base.cap_max_time(t);
    }
    let points = points(a, &base)?;
    let b = Settings::of(&base);
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs/accuracy").join(&base.name));
    std::fs::create_dir_all(&out)
        .with_context(|| format!("creating the output directory {}", out.display()))?;
    install_stop_handler();

    // Run every distinct (code, settings, seed) once, cached on disk.
    let mut records: BTreeMap<(Code, String, u64), Record> = BTreeMap::new();
    let total = {
        let mut keys: Vec<(Code, String)> =
            points.iter().map(|p| (p.code, p.settings.key())).collect();
        keys.sort_by(|x, y| (x.0.name(), &x.1).cmp(&(y.0.name(), &y.1)));
        keys.dedup();
        keys.len() * a.seeds.len()
    };
    let mut done = 0;
    for p in &points {
        for &seed in &a.seeds {
            let key = (p.code, p.settings.key(), seed);
            if records.contains_key(&key) {
                continue;
            }
            done += 1;
            let scene = {
                let mut s = apply(&base, &b, &p.settings);
                s.seed = seed;
                s
            };
            let dir = out
                .join("runs")
                .join(p.code.name())
                .join(p.settings.label());
            let r = run_point(&scene, p.code, &dir, seed, a)?;
            if STOP.load(Ordering::SeqCst) {
                eprintln!("interrupted: finished points are kept in {}; run the same command again to continue", out.display());
                return Ok(130);
            }
            if !a.quiet {
                eprintln!(
                    "accuracy [{done}/{total}] {} {} seed {seed}: {} ({:.1} s, {} steps){}",
                    p.code.name(),
                    p.settings.label(),
                    r.status(),
                    r.wall_seconds,
                    r.steps,
                    r.message
                        .as_deref()
                        .map(|m| format!(": {}", short_message(m)))
                        .unwrap_or_default()
                );
            }
            records.insert(key, r);
        }
    }

    let table = build_table(&base, &points, &records, &a.seeds);
    write_outputs(&out, &base, &a.seeds, &table, a.max_time, a.quiet)?;
    Ok(0)
}

/// The points of the sweep: for each code its reference (the tightest value of every swept
/// knob, the scene's value elsewhere) and each knob's values, the others at the scene's.
fn points(a: &Args, base: &Scene) -> Result<Vec<Point>> {
    let knobs: Vec<Knob> = if a.knobs.is_empty() {
        Knob::ALL.to_vec()
    } else {
        let mut k = a
            .knobs
            .iter()
            .map(|s| Knob::parse(s))
            .collect::<Result<Vec<_>>>()?;
        k.sort();
        k.dedup();
        k
    };
    let codes: Vec<Code> = if a.codes.is_empty() {
        vec![Code::Rust]
    } else {
        a.codes
            .iter()
            .map(|c| match Code::parse(c.trim()) {
                Some(code @ (Code::Rust | Code::Lammps)) => Ok(code),
                Some(other) => bail!(
                    "--codes: {} exposes none of the swept knobs in its generated deck; accuracy supports rust and lammps (dt only)",
                    other.name()
                ),
                None => bail!("--codes: unknown code {c:?}; expected rust or lammps"),
            })
            .collect::<Result<Vec<_>>>()?
    };
    let b = Settings::of(base);
    let mut values: BTreeMap<Knob, Vec<f64>> = BTreeMap::new();
    for &k in &knobs {
        if k == Knob::Inertia && b.inertia.is_none() {
            eprintln!(
                "accuracy: scene {} has no stress-controlled stage: the inertia knob is skipped",
                base.name
            );
            continue;
        }
        let given = match k {
            Knob::Dt => &a.dt,
            Knob::Inertia => &a.inertia,
            Knob::Tolerance => &a.tolerance,
            Knob::Kappa => &a.kappa,
        };
        let v = if given.is_empty() {
            k.default_values(base, &b)
        } else {
            normalize(given.clone())
        };
        if let Some(bad) = v.iter().find(|x| **x <= 0.0) {
            bail!("--{}: values must be > 0, got {bad}", k.name());
        }
        values.insert(k, v);
    }
    // The reference: the tightest value of every swept knob, the scene's value elsewhere.
    let mut reference = b;
    for (&k, v) in &values {
        let tight = v
            .iter()
            .copied()
            .fold(b.get(k), |t, x| if k.tighter(x, t) { x } else { t });
        reference = reference.with(k, tight);
    }
    let mut points = Vec::new();
    for &code in &codes {
        let ref_settings = if code == Code::Rust {
            reference
        } else {
            b.with(Knob::Dt, values.get(&Knob::Dt).map_or(b.dt, |v| v[0]))
        };
        points.push(Point {
            code,
            knob: None,
            settings: ref_settings,
            is_default: false,
        });
        for (&k, v) in &values {
            if code == Code::Lammps && k != Knob::Dt {
                continue;
            }
            for &x in v {
                points.push(Point {
                    code,
                    knob: Some(k),
                    settings: b.with(k, x),
                    is_default: (x - b.get(k)).abs() <= 1e-12 * x.abs(),
                });
            }
        }
    }
    Ok(points)
}

/// Runs one point for one seed (or reads it from `dir` when an earlier sweep ran the same
/// scene).
fn run_point(scene: &Scene, code: Code, dir: &Path, seed: u64, a: &Args) -> Result<Record> {
    let scene_json = serde_json::to_string(scene)?;
    let file = dir.join(format!("seed-{seed}.json"));
    if !a.fresh {
        if let Some(r) = std::fs::read(&file)
            .ok()
            .and_then(|b| serde_json::from_slice::<Value>(&b).ok())
            .filter(|v| v.get("scene").and_then(Value::as_str) == Some(scene_json.as_str()))
            .and_then(|v| Record::from_json(&v))
        {
            return Ok(r);
        }
    }
    let mut r = Record {
        code,
        seed,
        outcome: Outcome::Ran,
        state: None,
        message: None,
        wall_seconds: 0.0,
        steps: 0,
        phi: None,
        z_star: None,
        x0: None,
        forces: Vec::new(),
    };
    // The scene validation refuses some values (dt_fraction > 0.5): a refused point, not a run.
    if let Err(e) = scene.validate(Path::new(&format!("<accuracy:{}>", scene.name))) {
        r.outcome = Outcome::Invalid;
        r.message = Some(e.to_string());
    } else if code == Code::Rust {
        run_rust(scene, &mut r)?;
    } else {
        run_external(scene, code, dir, a, &mut r)?;
    }
    if STOP.load(Ordering::SeqCst) {
        return Ok(r);
    }
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    write_atomic(
        &file,
        serde_json::to_string(&r.to_json(&scene_json))?.as_bytes(),
    )
    .with_context(|| format!("writing {}", file.display()))?;
    Ok(r)
}

fn run_rust(scene: &Scene, r: &mut Record) -> Result<()> {
    let t = Instant::now();
    let result = grainbench_engine::run_scene(
        scene,
        &mut RunOptions {
            stop: Some(&STOP),
            ..Default::default()
        },
    );
    r.wall_seconds = t.elapsed().as_secs_f64();
    match result {
        Ok(o) => {
            r.steps = o
                .steps
                .iter()
                .filter(|s| s.end != StepEnd::Done)
                .map(|s| s.steps)
                .sum();
            r.state = Some(o.status);
            let (phi, z, x0, f) = measure(&o.snapshot);
            (r.phi, r.z_star, r.x0, r.forces) = (phi, z, x0, f);
        }
        Err(e @ RunError::Unstable { .. }) => {
            if let RunError::Unstable { step, .. } = &e {
                r.steps = *step;
            }
            r.outcome = Outcome::Unstable;
            r.message = Some(e.to_string());
        }
        Err(e) => {
            r.outcome = Outcome::Failed;
            r.message = Some(e.to_string());
        }
    }
    Ok(())
}

/// LAMMPS from the same start (compare's machinery); only the dt knob reaches its deck.
fn run_external(scene: &Scene, code: Code, dir: &Path, a: &Args, r: &mut Record) -> Result<()> {
    let start = Start::of(scene).map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
    let mut cr = CodeResult::new(code, Outcome::Ran);
    let work = dir.join("work");
    let snap = external::run(&start, code, &work, a.time_limit, None, true, &mut cr)?;
    r.wall_seconds = cr.wall_seconds.unwrap_or(0.0);
    match snap {
        Some(s) => {
            r.state = Some(StepEnd::TimeLimit);
            r.message = Some(format!(
                "{} runs the deck's fixed number of steps (no equilibrium criteria)",
                code.name()
            ));
            let (phi, z, x0, f) = measure(&s);
            (r.phi, r.z_star, r.x0, r.forces) = (phi, z, x0, f);
        }
        None => {
            // LAMMPS stops a blown-up run with "ERROR: Lost atoms" (or out-of-range atoms).
            let error = ["stdout.log", "log.lammps"]
                .iter()
                .filter_map(|f| std::fs::read_to_string(work.join(f)).ok())
                .flat_map(|t| {
                    t.lines()
                        .filter(|l| l.starts_with("ERROR"))
                        .map(String::from)
                        .collect::<Vec<_>>()
                })
                .next();
            let blown = error
                .as_deref()
                .is_some_and(|e| e.contains("Lost atoms") || e.contains("Out of range"));
            r.outcome = if blown { Outcome::Unstable } else { cr.outcome };
            r.message = Some(match (error, &cr.message) {
                (Some(e), Some(m)) => format!(
                    "{e} (numerics.dt_fraction = {}); {m}",
                    scene.numerics.dt_fraction
                ),
                (Some(e), None) => e,
                (None, m) => m.clone().unwrap_or_default(),
            });
        }
    }
    Ok(())
}
