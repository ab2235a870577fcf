//! What one run of one point and seed gave, as cached in `runs/<code>/<settings>/seed-S.json`,
//! and the measures taken on its final packing.

use grainbench_comparisons::metrics::{analyze, Options};
use grainbench_comparisons::outcome::Outcome;
use grainbench_comparisons::xcode::decks::Code;
use grainbench_engine::run::StepEnd;
use grainbench_engine::snapshot::Snapshot;
use serde_json::{json, Value};

/// What one run of one point and seed gave.
#[derive(Clone, Debug)]
pub struct Record {
    pub code: Code,
    pub seed: u64,
    /// `ran` (its final state in `state`), `unstable`, `invalid` (refused by the scene
    /// validation), `failed`, or why an external code did not run.
    pub outcome: Outcome,
    /// The final state of a run that ran: `equilibrium`, `time-limit`.
    pub state: Option<StepEnd>,
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
    /// Did the run end with a packing to measure (`equilibrium` or `time-limit`)?
    pub fn packing(&self) -> bool {
        self.outcome == Outcome::Ran
            && matches!(self.state, Some(StepEnd::Equilibrium | StepEnd::TimeLimit))
    }

    /// Did the run end at equilibrium?
    pub fn equilibrated(&self) -> bool {
        self.outcome == Outcome::Ran && self.state == Some(StepEnd::Equilibrium)
    }

    /// The final state of a run that ran, else its outcome (`unstable`, `failed`, …).
    pub fn status(&self) -> &str {
        match (self.outcome, &self.state) {
            (Outcome::Ran, Some(s)) => s.as_str(),
            (o, _) => o.as_str(),
        }
    }

    /// The cache file's document; `scene_json` tells whether a later sweep ran the same scene.
    pub fn to_json(&self, scene_json: &str) -> Value {
        json!({
            "code": self.code,
            "seed": self.seed,
            "status": self.status(),
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

    /// Reads a cached record back.
    pub fn from_json(v: &Value) -> Option<Record> {
        let f = |k: &str| v.get(k).and_then(Value::as_f64);
        let status = v.get("status")?.as_str()?;
        let (outcome, state) = match Outcome::parse(status) {
            Some(o) if o != Outcome::Ran => (o, None),
            _ => (Outcome::Ran, Some(StepEnd::parse(status)?)),
        };
        Some(Record {
            code: Code::parse(v.get("code")?.as_str()?)?,
            seed: v.get("seed")?.as_u64()?,
            outcome,
            state,
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
pub fn measure(snap: &Snapshot) -> (Option<f64>, Option<f64>, Option<f64>, Vec<f64>) {
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

/// The message of an unstable point up to its advice.
pub fn short_message(m: &str) -> &str {
    m.split(". Try ").next().unwrap_or(m)
}
