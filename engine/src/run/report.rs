//! What a run reports: progress at each check, how each stage ended, the outcome or why it
//! stopped early.

use crate::snapshot::Snapshot;

/// What the progress callback sees at each check.
#[derive(Clone, Debug, Default)]
pub struct Progress {
    /// Protocol step (0-based) and count.
    pub step_index: usize,
    pub step_count: usize,
    pub step_kind: &'static str,
    /// Time since the start of the protocol step, and its limit.
    pub time: f64,
    pub max_time: f64,
    pub steps: u64,
    pub checks: Checks,
    /// The stage's damped final phase is on (engine/src/run/relax.rs).
    pub relaxing: bool,
    /// The time step.
    pub dt: f64,
    /// At the first check of a stress-controlled stage: the axes the interaction network wraps
    /// ([`crate::network::wrapped_axes`]); `None` at other checks.
    pub wrapped_axes: Option<Vec<bool>>,
}

/// Equilibrium measures at one check, in units of the criteria.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Checks {
    pub packing_fraction: f64,
    /// Mean contact pressure trace(σ_contact)/d.
    pub pressure: f64,
    /// Target pressure (NaN in a fixed cell).
    pub pressure_target: f64,
    /// Largest net force on a grain / (criterion · F_ref).
    pub force_ratio: f64,
    /// Largest net moment / (criterion · F_ref · a) (0 when the law has no moments).
    pub moment_ratio: f64,
    /// Largest |σ_αα − Σ_α| / (criterion · F_ref/a^(d−1)) (0 in a fixed cell).
    pub stress_ratio: f64,
    /// Kinetic energy per grain / (criterion · F_ref · a).
    pub kinetic_ratio: f64,
    /// Kinetic energy per grain, reduced units (translation, and rotation of touching grains).
    pub kinetic_per_grain: f64,
    /// Rotational energy per grain of grains without any contact, not counted above.
    pub free_spin_per_grain: f64,
    /// Largest strain rate max_α |L̇_α/L_α| (1/time unit; 0 in a fixed cell).
    #[serde(default)]
    pub strain_rate: f64,
    /// Interacting pairs.
    pub interactions: usize,
    /// Clusters of interacting grains (`aggregate` stages only, else 0).
    pub clusters: usize,
}

impl Checks {
    /// The force, moment and stress criteria met.
    fn static_criteria(&self) -> bool {
        self.force_ratio < 1.0 && self.moment_ratio < 1.0 && self.stress_ratio < 1.0
    }

    /// All criteria met.
    pub fn equilibrium(&self) -> bool {
        self.static_criteria() && self.kinetic_ratio < 1.0
    }

    /// Every criterion but the kinetic one met, the kinetic one not: when
    /// `criteria.quench` sets the velocities to zero (AR07 §III.A).
    pub fn only_kinetic_fails(&self) -> bool {
        self.static_criteria() && self.kinetic_ratio >= 1.0
    }
}

/// How a protocol step ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StepEnd {
    /// The equilibrium criteria hold.
    Equilibrium,
    /// `aggregate`: all grains form one cluster.
    OneCluster,
    /// A hard-grain stage (expansion, mixing, growth) completed.
    Done,
    TimeLimit,
    Interrupted,
}

impl StepEnd {
    const ALL: [StepEnd; 5] = [
        StepEnd::Equilibrium,
        StepEnd::OneCluster,
        StepEnd::Done,
        StepEnd::TimeLimit,
        StepEnd::Interrupted,
    ];

    /// How a whole run ended: `interrupted` when stopped, `equilibrium` when every stage
    /// reached what it was run for, else `time-limit` (the status of its final snapshot).
    pub fn of_run(stopped: bool, steps: &[StepReport]) -> StepEnd {
        if stopped {
            StepEnd::Interrupted
        } else if steps.iter().all(|r| r.end.ok()) {
            StepEnd::Equilibrium
        } else {
            StepEnd::TimeLimit
        }
    }

    /// The end [`Self::as_str`] names (`None` for any other text).
    pub fn parse(text: &str) -> Option<StepEnd> {
        Self::ALL.into_iter().find(|e| e.as_str() == text)
    }

    pub fn as_str(self) -> &'static str {
        match self {
            StepEnd::Equilibrium => "equilibrium",
            StepEnd::OneCluster => "one-cluster",
            StepEnd::Done => "done",
            StepEnd::TimeLimit => "time-limit",
            StepEnd::Interrupted => "interrupted",
        }
    }
    /// Did the stage reach what it was run for?
    pub fn ok(self) -> bool {
        matches!(
            self,
            StepEnd::Equilibrium | StepEnd::OneCluster | StepEnd::Done
        )
    }
}

/// Report of one protocol stage.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct StepReport {
    /// Stage index in [`Scene::stages`](crate::scene::Scene::stages).
    pub index: usize,
    pub kind: String,
    pub end: StepEnd,
    /// Time spent in the stage (hard-grain stages: their own event-driven time).
    pub time: f64,
    /// Time steps (hard-grain stages: pair collisions).
    pub steps: u64,
    pub wall_seconds: f64,
    pub checks: Checks,
    /// Largest strain rate |L̇_α/L_α| seen at a check of the stage (1/time unit).
    #[serde(default)]
    pub peak_strain_rate: f64,
    /// What the damped final phase changed, for a stage with `relax` that reached it (always
    /// written, `null` otherwise: checkpoint headers are bincode, which cannot skip fields).
    #[serde(default)]
    pub relaxation: Option<super::relax::Relaxation>,
    /// The velocity quenches of `criteria.quench`, when there were any (always written,
    /// `null` otherwise, as `relaxation`).
    #[serde(default)]
    pub quench: Option<super::quench::Quenched>,
}

/// Result of a whole run.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// How the run ended ([`StepEnd::of_run`]; the snapshot's status names it).
    pub status: StepEnd,
    pub snapshot: Snapshot,
    pub steps: Vec<StepReport>,
    /// Time step and the stiffness it was derived from.
    pub dt: f64,
    pub k_max: f64,
    pub law: String,
    pub wall_seconds: f64,
    pub neighbor_builds: u64,
    /// Contacts at the Coulomb or rolling threshold at the end (GRC07 §II.D: none at
    /// equilibrium, the thresholds hold as strict inequalities).
    pub contacts_at_threshold: AtThreshold,
}

impl Outcome {
    /// Did every step end at equilibrium?
    pub fn equilibrated(&self) -> bool {
        self.steps.iter().all(|s| s.end.ok())
    }
}

/// Why a run stopped early.
#[derive(Debug)]
pub enum RunError {
    /// The scene cannot start (placement, cell too small).
    Setup { scene: String, message: String },
    /// The integration blew up; `last_good` is the last state that passed the checks.
    Unstable {
        scene: String,
        step: u64,
        time: f64,
        cause: String,
        last_good: Box<Snapshot>,
    },
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            RunError::Setup { scene, message } => write!(f, "scene {scene}: {message}"),
            RunError::Unstable {
                scene,
                step,
                time,
                cause,
                ..
            } => write!(
                f,
                "scene {scene}: unstable at step {step} (t = {time:.6e}): {cause}"
            ),
        }
    }
}

impl std::error::Error for RunError {}

/// Contacts whose tangential force or rolling moment sits at its threshold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AtThreshold {
    /// Every such contact.
    pub all: usize,
    /// Those whose threshold itself, μN^e (or μ_r N^e for the rolling moment), is below the
    /// equilibrium tolerance on the net force (moment): at that accuracy the contact cannot be
    /// told from one strictly inside its cone (GRC07 §III.A likewise ignores contacts whose
    /// forces are below the tolerance). GRC07 §II.D's strict inequalities concern the rest.
    pub below_tolerance: usize,
}

impl AtThreshold {
    /// Contacts at a threshold larger than the equilibrium tolerance.
    pub fn loaded(&self) -> usize {
        self.all - self.below_tolerance
    }
}
