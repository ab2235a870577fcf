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

use crate::common::{install_stop_handler, load_scene, STOP};
use crate::external;
use anyhow::{bail, Context, Result};
use grainbench_comparisons::decks::{Code, Start};
use grainbench_comparisons::metrics::{analyze, Options};
use grainbench_comparisons::stats::{ks_distance, mean, pareto, sample_sd};
use grainbench_comparisons::{crosscode::CodeResult, paper, plots};
use grainbench_engine::run::{RunError, RunOptions, StepEnd};
use grainbench_engine::scene::{Law, Step};
use grainbench_engine::snapshot::{write_atomic, Snapshot};
use grainbench_engine::Scene;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::Instant;

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

/// A knob that trades time for accuracy.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Knob {
    Dt,
    Inertia,
    Tolerance,
    Kappa,
}

impl Knob {
    const ALL: [Knob; 4] = [Knob::Dt, Knob::Inertia, Knob::Tolerance, Knob::Kappa];

    fn name(self) -> &'static str {
        match self {
            Knob::Dt => "dt",
            Knob::Inertia => "inertia",
            Knob::Tolerance => "tolerance",
            Knob::Kappa => "kappa",
        }
    }

    fn parse(s: &str) -> Result<Knob> {
        Knob::ALL
            .into_iter()
            .find(|k| k.name() == s.trim())
            .with_context(|| {
                format!("--knobs: unknown knob {s:?}; expected dt, inertia, tolerance or kappa")
            })
    }

    /// Which way is "tighter" (more accurate, more expensive): the smallest value, except κ.
    fn tighter(self, a: f64, b: f64) -> bool {
        match self {
            Knob::Kappa => a > b,
            _ => a < b,
        }
    }

    /// The built-in values of the sweep for `scene` (always including the scene's own).
    fn default_values(self, scene: &Scene, base: &Settings) -> Vec<f64> {
        let mut v = match self {
            // Past the stable step on purpose: 0.3 and 0.5 must stop with the instability
            // error; 1.0 is refused by the scene validation (dt_fraction ≤ 0.5).
            Knob::Dt => vec![0.005, 0.01, 0.02, 0.04, 0.08, 0.16, 0.3, 0.5, 1.0],
            Knob::Inertia => vec![1e-3, 3e-3, 1e-2, 3e-2, 1e-1],
            Knob::Tolerance => vec![0.3, 1.0, 3.0, 10.0],
            // AR07 §II.A: κ ≈ 39 000 at 10 kPa, 181 000 at 1 kPa (rigid limit for κ ≳ 1e4);
            // GRC07 T.I: 1e4 and 1e5.
            Knob::Kappa => match scene.law {
                Law::HertzMindlin { .. } => vec![1e4, 39_000.0, 181_000.0],
                Law::Linear { .. } => vec![1e4, 1e5],
            },
        };
        v.push(base.get(self));
        normalize(v)
    }
}

/// Sorted, deduplicated, finite values.
fn normalize(mut v: Vec<f64>) -> Vec<f64> {
    v.retain(|x| x.is_finite());
    v.sort_by(f64::total_cmp);
    v.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs().max(1e-300));
    v
}

/// The value of every knob of one run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    pub dt: f64,
    pub inertia: Option<f64>,
    pub tolerance: f64,
    pub kappa: f64,
}

impl Settings {
    /// The scene's own settings (tolerance factor 1).
    fn of(scene: &Scene) -> Settings {
        Settings {
            dt: scene.numerics.dt_fraction,
            inertia: first_inertia_cap(scene),
            tolerance: 1.0,
            kappa: scene.law.kappa(),
        }
    }

    fn get(&self, k: Knob) -> f64 {
        match k {
            Knob::Dt => self.dt,
            Knob::Inertia => self.inertia.unwrap_or(f64::NAN),
            Knob::Tolerance => self.tolerance,
            Knob::Kappa => self.kappa,
        }
    }

    fn with(mut self, k: Knob, x: f64) -> Settings {
        match k {
            Knob::Dt => self.dt = x,
            Knob::Inertia => self.inertia = Some(x),
            Knob::Tolerance => self.tolerance = x,
            Knob::Kappa => self.kappa = x,
        }
        self
    }

    /// A directory name for the cache of this point.
    fn label(&self) -> String {
        let i = self
            .inertia
            .map_or("none".to_string(), |x| format!("{x:e}"));
        format!(
            "dt{:e}_I{i}_tol{:e}_kappa{:e}",
            self.dt, self.tolerance, self.kappa
        )
    }

    fn key(&self) -> String {
        self.label()
    }

    fn to_json(self) -> Value {
        json!({
            "dt_fraction": self.dt,
            "inertia_cap": self.inertia,
            "tolerance_factor": self.tolerance,
            "kappa": self.kappa,
        })
    }
}

/// The strain-rate cap of the first stress-controlled stage.
fn first_inertia_cap(scene: &Scene) -> Option<f64> {
    scene.protocol.iter().find_map(|s| match s {
        Step::Compress { inertia_cap, .. }
        | Step::PressureProgram { inertia_cap, .. }
        | Step::KappaRamp { inertia_cap, .. } => Some(*inertia_cap),
        _ => None,
    })
}

/// `base` with the knobs of `s` (relative to `b`, the base scene's own settings).
pub fn apply(base: &Scene, b: &Settings, s: &Settings) -> Scene {
    let mut scene = base.clone();
    scene.numerics.dt_fraction = s.dt;
    let i_factor = match (s.inertia, b.inertia) {
        (Some(x), Some(y)) => x / y,
        _ => 1.0,
    };
    let k_factor = s.kappa / b.kappa;
    match &mut scene.law {
        Law::HertzMindlin { kappa, .. } | Law::Linear { kappa, .. } => *kappa = s.kappa,
    }
    for step in &mut scene.protocol {
        match step {
            Step::Compress {
                inertia_cap,
                criteria,
                kappa,
                ..
            } => {
                *inertia_cap *= i_factor;
                scale_criteria(criteria, s.tolerance);
                if let Some(k) = kappa {
                    *k *= k_factor;
                }
            }
            Step::PressureProgram {
                inertia_cap,
                criteria,
                ..
            } => {
                *inertia_cap *= i_factor;
                scale_criteria(criteria, s.tolerance);
            }
            Step::KappaRamp {
                inertia_cap,
                criteria,
                from,
                to,
                ..
            } => {
                *inertia_cap *= i_factor;
                scale_criteria(criteria, s.tolerance);
                *from *= k_factor;
                *to *= k_factor;
            }
            Step::FixedVolume {
                criteria, kappa, ..
            } => {
                scale_criteria(criteria, s.tolerance);
                if let Some(k) = kappa {
                    *k *= k_factor;
                }
            }
            Step::Aggregate { kappa: Some(k), .. } => *k *= k_factor,
            _ => {}
        }
    }
    scene
}

fn scale_criteria(c: &mut grainbench_engine::scene::Criteria, f: f64) {
    c.force *= f;
    c.moment *= f;
    c.pressure *= f;
    c.kinetic *= f;
}

/// What one run of one point and seed gave.
#[derive(Clone, Debug)]
pub struct Record {
    pub code: String,
    pub seed: u64,
    /// `equilibrium`, `time-limit`, `unstable`, `invalid` (refused by the scene validation)
    /// or `failed`.
    pub status: String,
    pub message: Option<String>,
    pub wall_seconds: f64,
    /// DEM time steps (hard-sphere collisions not counted).
    pub steps: u64,
    pub phi: Option<f64>,
    pub z_star: Option<f64>,
    pub x0: Option<f64>,
    /// f = N/⟨N⟩ over the counted contacts (N in F0 for cohesive packings, GRC07 Fig. 9).
    pub forces: Vec<f64>,
}

impl Record {
    fn packing(&self) -> bool {
        matches!(self.status.as_str(), "equilibrium" | "time-limit")
    }

    fn to_json(&self, scene_json: &str) -> Value {
        json!({
            "code": self.code,
            "seed": self.seed,
            "status": self.status,
            "message": self.message,
            "wall_seconds": self.wall_seconds,
            "steps": self.steps,
            "phi": self.phi,
            "z_star": self.z_star,
            "x0": self.x0,
            "forces": self.forces,
            "scene": scene_json,
        })
    }

    fn from_json(v: &Value) -> Option<Record> {
        let f = |k: &str| v.get(k).and_then(Value::as_f64);
        Some(Record {
            code: v.get("code")?.as_str()?.to_string(),
            seed: v.get("seed")?.as_u64()?,
            status: v.get("status")?.as_str()?.to_string(),
            message: v.get("message").and_then(Value::as_str).map(String::from),
            wall_seconds: f("wall_seconds")?,
            steps: v.get("steps")?.as_u64()?,
            phi: f("phi"),
            z_star: f("z_star"),
            x0: f("x0"),
            forces: v
                .get("forces")?
                .as_array()?
                .iter()
                .filter_map(Value::as_f64)
                .collect(),
        })
    }
}

/// Φ, z*, x0 and the normalized forces of a packing (the same analysis as `analyze`).
fn measure(snap: &Snapshot) -> (Option<f64>, Option<f64>, Option<f64>, Vec<f64>) {
    let opts = Options::default();
    let a = analyze(snap, &opts);
    (
        Some(a.packing_fraction),
        a.z_backbone,
        Some(a.rattler_fraction),
        normalized_forces(snap, &opts),
    )
}

/// f = N/⟨N⟩ over the force-carrying contacts (|N| above the analysis threshold), or N/F0
/// for cohesive packings; sorted.
pub fn normalized_forces(snap: &Snapshot, opts: &Options) -> Vec<f64> {
    let all = &snap.contacts;
    let mut n: Vec<f64> = if snap.cohesive {
        all.iter().map(|c| c.normal).collect()
    } else {
        let k = all.len().max(1) as f64;
        let threshold = opts.force_tolerance * all.iter().map(|c| c.normal.abs()).sum::<f64>() / k;
        all.iter()
            .map(|c| c.normal)
            .filter(|x| x.abs() > threshold)
            .collect()
    };
    if !snap.cohesive && !n.is_empty() {
        let mean = n.iter().sum::<f64>() / n.len() as f64;
        if mean > 0.0 {
            n.iter_mut().for_each(|x| *x /= mean);
        }
    }
    n.retain(|x| x.is_finite());
    n.sort_by(f64::total_cmp);
    n
}

/// One swept point: a code, a knob and its value.
#[derive(Clone, Debug)]
struct Point {
    code: Code,
    /// `None`: the reference.
    knob: Option<Knob>,
    settings: Settings,
    /// The scene's own value of this knob.
    is_default: bool,
}

/// The metrics errors are measured on.
const METRICS: [&str; 4] = ["phi", "z_star", "x0", "ks"];

fn metric_of(r: &Record, m: &str) -> Option<f64> {
    match m {
        "phi" => r.phi,
        "z_star" => r.z_star,
        "x0" => r.x0,
        _ => None,
    }
}

/// One row of the table.
#[derive(Clone, Debug)]
struct Row {
    code: Code,
    knob: String,
    value: f64,
    is_default: bool,
    settings: Settings,
    status: String,
    wall_seconds: Option<f64>,
    steps: Option<f64>,
    /// Metric → (mean over seeds of the metric, error against the reference).
    values: BTreeMap<&'static str, f64>,
    errors: BTreeMap<&'static str, f64>,
    /// Metric → |seed mean − paper value|.
    paper_errors: BTreeMap<&'static str, f64>,
    combined: Option<f64>,
    pareto: bool,
}

pub fn accuracy(a: &Args) -> Result<i32> {
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
    let b = Settings::of(&base);
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
            k.default_values(&base, &b)
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
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs/accuracy").join(&base.name));
    std::fs::create_dir_all(&out)
        .with_context(|| format!("creating the output directory {}", out.display()))?;
    install_stop_handler();

    // Run every distinct (code, settings, seed) once, cached on disk.
    let mut records: BTreeMap<(String, String, u64), Record> = BTreeMap::new();
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
            let key = (p.code.name().to_string(), p.settings.key(), seed);
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
                    r.status,
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
    write_outputs(&out, &base, &a.seeds, &table, a)?;
    Ok(0)
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
        code: code.name().into(),
        seed,
        status: String::new(),
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
        r.status = "invalid".into();
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
            r.status = if o.snapshot.status == "equilibrium" {
                "equilibrium".into()
            } else {
                o.snapshot.status.clone()
            };
            let (phi, z, x0, f) = measure(&o.snapshot);
            (r.phi, r.z_star, r.x0, r.forces) = (phi, z, x0, f);
        }
        Err(e @ RunError::Unstable { .. }) => {
            if let RunError::Unstable { step, .. } = &e {
                r.steps = *step;
            }
            r.status = "unstable".into();
            r.message = Some(e.to_string());
        }
        Err(e) => {
            r.status = "failed".into();
            r.message = Some(e.to_string());
        }
    }
    Ok(())
}

/// LAMMPS from the same start (compare's machinery); only the dt knob reaches its deck.
fn run_external(scene: &Scene, code: Code, dir: &Path, a: &Args, r: &mut Record) -> Result<()> {
    let start = Start::of(scene).map_err(|e| anyhow::anyhow!("scene {}: {e}", scene.name))?;
    let mut cr = CodeResult::new(code.name(), "ok");
    let work = dir.join("work");
    let snap = external::run(&start, code, &work, a.time_limit, None, true, &mut cr)?;
    r.wall_seconds = cr.wall_seconds.unwrap_or(0.0);
    match snap {
        Some(s) => {
            r.status = "time-limit".into();
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
            r.status = if blown {
                "unstable".into()
            } else {
                cr.outcome.clone()
            };
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

/// The message of an unstable point up to its advice.
fn short_message(m: &str) -> &str {
    m.split(". Try ").next().unwrap_or(m)
}

/// A status for the Markdown table: the cause without the scene name and the advice (the
/// CSV and JSON keep the whole message).
fn md_status(status: &str) -> String {
    let s = status.split(". Likely cause").next().unwrap_or(status);
    match s.split_once(": scene ") {
        Some((head, rest)) => match rest.split_once(": ") {
            Some((_, cause)) => format!("{head}: {cause}"),
            None => s.to_string(),
        },
        None => s.to_string(),
    }
    .replace('|', "/")
}

struct Table {
    rows: Vec<Row>,
    /// Reference (per code): metric → (mean, seed spread).
    reference: BTreeMap<&'static str, ReferenceStats>,
    paper_state: Option<String>,
    /// Metric → (paper value, paper sd).
    paper: BTreeMap<&'static str, (f64, Option<f64>)>,
}

#[derive(Clone, Debug, Default)]
struct ReferenceStats {
    settings: Option<Settings>,
    status: String,
    wall_seconds: Option<f64>,
    mean: BTreeMap<&'static str, f64>,
    /// Sample s.d. over seeds (KS: mean leave-one-out distance of a seed to the others).
    spread: BTreeMap<&'static str, f64>,
}

fn build_table(
    base: &Scene,
    points: &[Point],
    records: &BTreeMap<(String, String, u64), Record>,
    seeds: &[u64],
) -> Table {
    let recs = |p: &Point| -> Vec<&Record> {
        seeds
            .iter()
            .filter_map(|&s| records.get(&(p.code.name().to_string(), p.settings.key(), s)))
            .collect()
    };
    let paper_state = base.paper_state.clone();
    let mut paper_vals = BTreeMap::new();
    if let Some(st) = paper_state.as_deref().and_then(paper::paper_values) {
        for m in ["phi", "z_star", "x0"] {
            if let Some(v) = st.values.get(m) {
                paper_vals.insert(m, (v.value, v.sd));
            }
        }
    }
    let mut reference: BTreeMap<&'static str, ReferenceStats> = BTreeMap::new();
    let mut rows = Vec::new();
    let codes: Vec<Code> = {
        let mut c: Vec<Code> = points.iter().map(|p| p.code).collect();
        c.dedup();
        c
    };
    for code in codes {
        let Some(rp) = points.iter().find(|p| p.code == code && p.knob.is_none()) else {
            continue;
        };
        let ref_recs = recs(rp);
        let ref_ok: BTreeMap<u64, &Record> = ref_recs
            .iter()
            .filter(|r| r.packing())
            .map(|r| (r.seed, *r))
            .collect();
        let pooled: Vec<f64> = ref_ok.values().flat_map(|r| r.forces.clone()).collect();
        let mut rs = ReferenceStats {
            settings: Some(rp.settings),
            status: point_status(&ref_recs, seeds.len()),
            wall_seconds: mean(&ref_recs.iter().map(|r| r.wall_seconds).collect::<Vec<_>>()),
            ..Default::default()
        };
        for m in ["phi", "z_star", "x0"] {
            let v: Vec<f64> = ref_ok.values().filter_map(|r| metric_of(r, m)).collect();
            if let Some(x) = mean(&v) {
                rs.mean.insert(m, x);
            }
            if let Some(s) = sample_sd(&v) {
                rs.spread.insert(m, s);
            }
        }
        if ref_ok.len() >= 2 {
            let loo: Vec<f64> = ref_ok
                .iter()
                .filter_map(|(s, r)| {
                    let others: Vec<f64> = ref_ok
                        .iter()
                        .filter(|(s2, _)| *s2 != s)
                        .flat_map(|(_, r2)| r2.forces.iter().copied())
                        .collect();
                    ks_distance(&r.forces, &others)
                })
                .collect();
            if let Some(x) = mean(&loo) {
                rs.spread.insert("ks", x);
            }
        }
        let mut code_rows = Vec::new();
        for p in points.iter().filter(|p| p.code == code && p.knob.is_some()) {
            let rr = recs(p);
            let status = point_status(&rr, seeds.len());
            let mut row = Row {
                code,
                knob: p.knob.map_or("reference", |k| k.name()).to_string(),
                value: p.knob.map_or(f64::NAN, |k| p.settings.get(k)),
                is_default: p.is_default,
                settings: p.settings,
                status: status.clone(),
                wall_seconds: mean(&rr.iter().map(|r| r.wall_seconds).collect::<Vec<_>>()),
                steps: mean(&rr.iter().map(|r| r.steps as f64).collect::<Vec<_>>()),
                values: BTreeMap::new(),
                errors: BTreeMap::new(),
                paper_errors: BTreeMap::new(),
                combined: None,
                pareto: false,
            };
            let stable = rr.len() == seeds.len() && rr.iter().all(|r| r.packing());
            if stable {
                for m in ["phi", "z_star", "x0"] {
                    let v: Vec<f64> = rr.iter().filter_map(|r| metric_of(r, m)).collect();
                    if let Some(x) = mean(&v) {
                        row.values.insert(m, x);
                        if let Some((pv, _)) = paper_vals.get(m) {
                            row.paper_errors.insert(m, (x - pv).abs());
                        }
                    }
                    let e: Vec<f64> = rr
                        .iter()
                        .filter_map(|r| {
                            Some((metric_of(r, m)? - metric_of(ref_ok.get(&r.seed)?, m)?).abs())
                        })
                        .collect();
                    if let Some(x) = mean(&e) {
                        row.errors.insert(m, x);
                    }
                }
                let ks: Vec<f64> = rr
                    .iter()
                    .filter_map(|r| ks_distance(&r.forces, &pooled))
                    .collect();
                if let Some(x) = mean(&ks) {
                    row.errors.insert("ks", x);
                }
            }
            code_rows.push(row);
        }
        // Combined error: each metric's error in units of the reference's seed spread (or,
        // without one, of the largest error of that metric in the sweep), averaged.
        let scale: BTreeMap<&str, f64> = METRICS
            .iter()
            .map(|&m| {
                let s = rs.spread.get(m).copied().filter(|s| *s > 0.0);
                let max = code_rows
                    .iter()
                    .filter_map(|r| r.errors.get(m))
                    .fold(0.0f64, |a, &b| a.max(b));
                (m, s.unwrap_or(if max > 0.0 { max } else { 1.0 }))
            })
            .collect();
        for row in &mut code_rows {
            if row.errors.len() == METRICS.len() {
                let c: Vec<f64> = METRICS.iter().map(|m| row.errors[m] / scale[m]).collect();
                row.combined = mean(&c);
            }
        }
        // The Pareto front over distinct settings (the scene's own point is in every curve).
        let pts: Vec<Option<(f64, f64)>> = code_rows
            .iter()
            .map(|r| Some((r.wall_seconds?, r.combined?)))
            .collect();
        let front = pareto(&pts);
        for (row, f) in code_rows.iter_mut().zip(front) {
            row.pareto = f;
        }
        reference.insert(code.name(), rs);
        rows.extend(code_rows);
    }
    Table {
        rows,
        reference,
        paper_state,
        paper: paper_vals,
    }
}

/// `equilibrium`, `time-limit`, or `unstable: <message>` when any seed failed.
fn point_status(rr: &[&Record], seeds: usize) -> String {
    if let Some(bad) = rr.iter().find(|r| !r.packing()) {
        let k = rr.iter().filter(|r| !r.packing()).count();
        let of = if seeds > 1 {
            format!(" ({k}/{seeds} seeds)")
        } else {
            String::new()
        };
        return format!(
            "{}{of}: {}",
            bad.status,
            short_message(bad.message.as_deref().unwrap_or("no message"))
        );
    }
    if rr.len() < seeds {
        return "missing".into();
    }
    if rr.iter().all(|r| r.status == "equilibrium") {
        "equilibrium".into()
    } else {
        let k = rr.iter().filter(|r| r.status != "equilibrium").count();
        format!("time-limit ({k}/{seeds} seeds)")
    }
}

fn num(x: Option<f64>) -> String {
    x.map_or(String::new(), |x| format!("{x:.4e}"))
}

/// Three significant figures.
fn short(x: Option<f64>) -> String {
    match x {
        None => "—".into(),
        Some(0.0) => "0".into(),
        Some(x) if !x.is_finite() || x.abs() < 1e-3 || x.abs() >= 1e4 => format!("{x:.2e}"),
        Some(x) => {
            let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
            format!("{x:.decimals$}")
        }
    }
}

fn write_outputs(out: &Path, base: &Scene, seeds: &[u64], t: &Table, a: &Args) -> Result<()> {
    // CSV.
    let mut csv = String::from("code,knob,value,default,status,wall_seconds,steps,phi,z_star,x0,err_phi,err_z_star,err_x0,ks,combined,pareto,paper_err_phi,paper_err_z_star,paper_err_x0,dt_fraction,inertia_cap,tolerance_factor,kappa\n");
    for r in &t.rows {
        let _ = writeln!(
            csv,
            "{},{},{:e},{},\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:e},{},{:e},{:e}",
            r.code.name(),
            r.knob,
            r.value,
            r.is_default,
            r.status.replace('"', "'"),
            num(r.wall_seconds),
            num(r.steps),
            num(r.values.get("phi").copied()),
            num(r.values.get("z_star").copied()),
            num(r.values.get("x0").copied()),
            num(r.errors.get("phi").copied()),
            num(r.errors.get("z_star").copied()),
            num(r.errors.get("x0").copied()),
            num(r.errors.get("ks").copied()),
            num(r.combined),
            r.pareto,
            num(r.paper_errors.get("phi").copied()),
            num(r.paper_errors.get("z_star").copied()),
            num(r.paper_errors.get("x0").copied()),
            r.settings.dt,
            num(r.settings.inertia),
            r.settings.tolerance,
            r.settings.kappa,
        );
    }
    write_atomic(&out.join("accuracy.csv"), csv.as_bytes())?;

    // JSON.
    let rows: Vec<Value> = t
        .rows
        .iter()
        .map(|r| {
            json!({
                "code": r.code.name(),
                "knob": r.knob,
                "value": r.value,
                "default": r.is_default,
                "status": r.status,
                "stable": !r.errors.is_empty(),
                "wall_seconds": r.wall_seconds,
                "steps": r.steps,
                "values": r.values,
                "errors": r.errors,
                "combined_error": r.combined,
                "pareto": r.pareto,
                "paper_errors": r.paper_errors,
                "settings": r.settings.to_json(),
            })
        })
        .collect();
    let reference: BTreeMap<&str, Value> = t
        .reference
        .iter()
        .map(|(c, rs)| {
            (
                *c,
                json!({
                    "settings": rs.settings.map(Settings::to_json),
                    "status": rs.status,
                    "wall_seconds": rs.wall_seconds,
                    "mean": rs.mean,
                    "seed_spread": rs.spread,
                }),
            )
        })
        .collect();
    let paper: BTreeMap<&str, Value> = t
        .paper
        .iter()
        .map(|(m, (v, sd))| (*m, json!({"value": v, "sd": sd})))
        .collect();
    let doc = json!({
        "scene": base.name,
        "seeds": seeds,
        "max_time": a.max_time,
        "threads": rayon::current_num_threads(),
        "engine": env!("CARGO_PKG_VERSION"),
        "paper_state": t.paper_state,
        "paper": paper,
        "reference": reference,
        "error_definition": "mean over seeds of |metric - reference of the same seed| (phi, z_star, x0); ks: mean over seeds of the two-sample Kolmogorov-Smirnov distance of f = N/<N> to the pooled reference forces; combined: mean of the four errors, each in units of the reference seed spread (or of the sweep's largest error of that metric when there is no spread)",
        "rows": rows,
    });
    write_atomic(
        &out.join("accuracy.json"),
        serde_json::to_string_pretty(&doc)?.as_bytes(),
    )?;

    // Markdown.
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Speed against error: {} (seeds {})\n",
        base.name,
        seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    );
    for (c, rs) in &t.reference {
        let s = rs.settings.expect("reference settings");
        let _ = writeln!(
            md,
            "Reference ({c}): dt_fraction = {}, I = {}, tolerance × {}, κ = {} — {}, {} s per seed.  ",
            s.dt,
            short(s.inertia),
            s.tolerance,
            s.kappa,
            rs.status,
            short(rs.wall_seconds)
        );
        let _ = writeln!(
            md,
            "Reference means: Φ = {}, z* = {}, x0 = {}; seed spread (s.d.): Φ {}, z* {}, x0 {}, KS (leave-one-out) {}.\n",
            short(rs.mean.get("phi").copied()),
            short(rs.mean.get("z_star").copied()),
            short(rs.mean.get("x0").copied()),
            short(rs.spread.get("phi").copied()),
            short(rs.spread.get("z_star").copied()),
            short(rs.spread.get("x0").copied()),
            short(rs.spread.get("ks").copied()),
        );
    }
    if let Some(ps) = &t.paper_state {
        let _ = writeln!(
            md,
            "Paper ({ps}): {}.\n",
            t.paper
                .iter()
                .map(|(m, (v, sd))| format!(
                    "{m} = {v}{}",
                    sd.map(|s| format!(" ± {s}")).unwrap_or_default()
                ))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let _ = writeln!(md, "Errors: mean over seeds of |metric − reference of the same seed|; KS = mean Kolmogorov–Smirnov distance of P(f) to the pooled reference forces; comb. = mean of the four errors in units of the reference seed spread (≲ 1: within sample noise); P = on the Pareto front of (wall time, comb.). `*` marks the scene's own value.\n");
    let paper_cols = !t.paper.is_empty();
    let _ = writeln!(
        md,
        "| code | knob | value | status | wall s | steps | Φ | z* | x0 | err Φ | err z* | err x0 | KS | comb. | P |{}",
        if paper_cols {
            " Φ−paper | z*−paper | x0−paper |"
        } else {
            ""
        }
    );
    let _ = writeln!(
        md,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|{}",
        if paper_cols { "---|---|---|" } else { "" }
    );
    for r in &t.rows {
        let g = |m: &BTreeMap<&str, f64>, k: &str| short(m.get(k).copied());
        let _ = write!(
            md,
            "| {} | {} | {}{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.code.name(),
            r.knob,
            format_args!("{:.3e}", r.value),
            if r.is_default { " *" } else { "" },
            md_status(&r.status),
            short(r.wall_seconds),
            r.steps
                .filter(|s| *s > 0.0)
                .map_or("—".into(), |s| format!("{s:.0}")),
            g(&r.values, "phi"),
            g(&r.values, "z_star"),
            g(&r.values, "x0"),
            g(&r.errors, "phi"),
            g(&r.errors, "z_star"),
            g(&r.errors, "x0"),
            g(&r.errors, "ks"),
            short(r.combined),
            if r.pareto { "P" } else { "" },
        );
        if paper_cols {
            let _ = write!(
                md,
                " {} | {} | {} |",
                g(&r.paper_errors, "phi"),
                g(&r.paper_errors, "z_star"),
                g(&r.paper_errors, "x0")
            );
        }
        md.push('\n');
    }
    md.push_str("\nKnobs per code: rust — dt, inertia, tolerance, kappa; lammps — dt only (its deck takes our time step; no strain-rate cap of our kind, no equilibrium criteria, κ fixed by the deck).\n");
    write_atomic(&out.join("accuracy.md"), md.as_bytes())?;

    // Plots: error against wall time, one per metric and the combined one.
    let mut plotted = Vec::new();
    for m in METRICS.iter().copied().chain(["combined"]) {
        let err_of = |r: &Row| {
            if m == "combined" {
                r.combined
            } else {
                r.errors.get(m).copied()
            }
        };
        let mut series_pts: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        let mut all: Vec<Option<(f64, f64)>> = Vec::new();
        let mut curves: BTreeMap<String, Vec<(f64, f64, f64)>> = BTreeMap::new();
        for r in &t.rows {
            let p = r.wall_seconds.zip(err_of(r));
            if r.code == Code::Rust {
                all.push(p);
            }
            if let Some((c, e)) = p {
                curves
                    .entry(format!("{} {}", r.code.name(), r.knob))
                    .or_default()
                    .push((r.value, c, e));
            }
        }
        for (label, mut v) in curves {
            v.sort_by(|x, y| x.0.total_cmp(&y.0));
            series_pts.push((label, v.into_iter().map(|(_, c, e)| (c, e)).collect()));
        }
        let flags = pareto(&all);
        let rust_rows: Vec<&Row> = t.rows.iter().filter(|r| r.code == Code::Rust).collect();
        let mut front: Vec<(f64, f64)> = rust_rows
            .iter()
            .zip(&flags)
            .filter(|(_, f)| **f)
            .filter_map(|(r, _)| r.wall_seconds.zip(err_of(r)))
            .collect();
        front.sort_by(|x, y| x.0.total_cmp(&y.0));
        front.dedup();
        series_pts.push(("Pareto front (rust)".into(), front));
        let series: Vec<plots::Series> = series_pts
            .iter()
            .map(|(l, p)| plots::Series::new(l, p))
            .collect();
        let title = format!("{}: error of {m} against cost", base.name);
        let y_label = match m {
            "combined" => "combined error (units of seed spread)".to_string(),
            "ks" => "KS distance of P(f)".to_string(),
            _ => format!("|{m} - reference|"),
        };
        let mut plot = plots::LinePlot::new(&title, "wall time per seed (s)", &y_label, &series);
        plot.x_axis = plots::Axis::Log;
        plot.y_axis = plots::Axis::Log;
        plot.marks = plots::Marks::LinesAndPoints;
        match plots::line_plot(&out.join(format!("accuracy-{m}")), &plot) {
            Ok(f) => plotted.push(f.svg.display().to_string()),
            Err(e) => eprintln!("accuracy: no plot of {m}: {e}"),
        }
    }
    if !a.quiet {
        print!("{md}");
    }
    println!(
        "wrote {}, {}, {}{}",
        out.join("accuracy.md").display(),
        out.join("accuracy.csv").display(),
        out.join("accuracy.json").display(),
        if plotted.is_empty() {
            String::new()
        } else {
            format!(" and {} plots (SVG + PNG)", plotted.len())
        }
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knobs_apply_to_the_scene() {
        let base = Scene::from_toml(
            grainbench_engine::library::scene_text("xcode-smoke").unwrap(),
            Path::new("xcode-smoke"),
        )
        .unwrap();
        let b = Settings::of(&base);
        assert_eq!(b.inertia, Some(0.01));
        let s = b
            .with(Knob::Dt, 0.04)
            .with(Knob::Inertia, 0.03)
            .with(Knob::Tolerance, 3.0)
            .with(Knob::Kappa, 39_000.0);
        let sc = apply(&base, &b, &s);
        assert_eq!(sc.numerics.dt_fraction, 0.04);
        assert_eq!(sc.law.kappa(), 39_000.0);
        let Step::Compress {
            inertia_cap,
            criteria,
            ..
        } = &sc.protocol[1]
        else {
            panic!("xcode-smoke's second stage compresses")
        };
        assert!((inertia_cap - 0.03).abs() < 1e-15);
        assert!((criteria.force - 3e-4).abs() < 1e-15);
        assert!((criteria.kinetic - 3e-8).abs() < 1e-20);
    }
}
