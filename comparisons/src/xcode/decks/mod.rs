//! Cross-code decks: input decks and data files for LAMMPS, LIGGGHTS and YADE that start from
//! the configuration our engine starts from and run the same protocol, as far as each code can
//! express it (the laws of AR07 §II and GRC07 §II, the protocols of AR07 §III–IV and GRC07
//! §III; what each code can express: docs/external-codes.md).
//!
//! * [`Start`]: the common start (grains after the scene's leading hard-grain stages, and the
//!   engine's [`Plan`]: the DEM stages with their absolute rate caps, tolerances and time
//!   steps), in reduced units: lengths in a, masses in the mass of a grain of diameter a,
//!   forces in the scene's unit. No generator derives a stage quantity itself.
//! * [`capability`]: the capability matrix, one [`Support`] per [`Feature`] and [`Code`].
//! * [`lammps`], [`liggghts`], [`yade`]: one generator per code (one style, one file).
//! * [`lammps_table`]: GRC07 adhesion as LAMMPS `pair_style table` sections per size class.
//! * [`lammps_bench`]: a bench-only (throughput) LAMMPS deck for adhesive scenes.
//! * [`deck`] ([`by_code`]): the deck of a scene for one code, refusing unsupported features
//!   with what is missing.

pub mod by_code;
pub mod capability;
pub mod feature;
pub mod generic;
pub mod lammps;
pub mod lammps_bench;
pub mod lammps_table;
pub mod liggghts;
pub mod yade;

/// Every deck is for one code.
pub use super::code::{which, Code};
pub use by_code::deck;
pub use capability::features;
pub use feature::{Feature, Support};

pub use grainbench_engine::plan::{Plan, PlanStage, StageKind, Tolerances};

use grainbench_engine::geometry::{Dim, VectorOps as _, D2, D3};
use grainbench_engine::plan::PlanStep;
use grainbench_engine::run::{prepared_grains, Grains};
use grainbench_engine::scene::{Law, Mu, Scene};
use std::fmt;

/// The common start of every code's run of a scene.
#[derive(Clone, Debug)]
pub struct Start {
    pub scene: Scene,
    pub dimension: usize,
    /// Cell side lengths (a).
    pub lengths: Vec<f64>,
    /// Positions in [0, L) (a), velocities, diameters (a), masses (mass of a grain of
    /// diameter a: m = d^dimension), moments of inertia (m d²/10 spheres, m d²/8 disks).
    pub position: Vec<Vec<f64>>,
    pub velocity: Vec<Vec<f64>>,
    /// Spins (one component in 2D, three in 3D) of an explicit-particle start; empty = all
    /// at rest.
    pub spin: Vec<Vec<f64>>,
    pub diameter: Vec<f64>,
    pub mass: Vec<f64>,
    pub inertia: Vec<f64>,
    /// Hard-grain stages run by grainbench before the deck starts (kinds).
    pub prelude: Vec<String>,
    /// Hard-grain stages between DEM stages (no external code can run them: refused).
    pub interlude: Vec<String>,
    /// The DEM stages of the engine's [`Plan`], in order: the stages every deck runs, with the
    /// engine's numbers.
    pub stages: Vec<PlanStage>,
    /// Steps between frames of the trace (`output.trace_every` in the first stage's time
    /// steps, at least 1), if the scene asks for one.
    pub trace_steps: Option<u64>,
}

/// Why a scene cannot be written for a code.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    pub code: Code,
    pub scene: String,
    pub missing: Vec<(Feature, String)>,
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(
            f,
            "scene {}: {} cannot run it: ",
            self.scene,
            self.code.name()
        )?;
        for (k, (feat, why)) in self.missing.iter().enumerate() {
            if k > 0 {
                f.write_str("; ")?;
            }
            write!(f, "{} unsupported ({why})", feat.key())?;
        }
        write!(
            f,
            ". See `grainbench capabilities`; pick a scene without these features."
        )
    }
}

impl std::error::Error for Refusal {}

/// A generated deck: files to write into its directory and how to run it.
#[derive(Clone, Debug, PartialEq)]
pub struct Deck {
    pub code: Code,
    /// (file name, contents); the first is the input script.
    pub files: Vec<(String, String)>,
    /// The approximate features this deck uses, each with its deviation (also listed in the
    /// input's header comment).
    pub deviations: Vec<String>,
    /// Arguments after the binary (the input script's name among them).
    pub args: Vec<String>,
}

impl Start {
    /// The common start of `scene`: runs its leading hard-grain stages with our event-driven
    /// code, then lists the DEM stages that follow.
    pub fn of(scene: &Scene) -> Result<Start, String> {
        match scene.dimension {
            2 => start_dim::<D2>(scene),
            _ => start_dim::<D3>(scene),
        }
    }

    pub fn n(&self) -> usize {
        self.diameter.len()
    }

    /// The same grains under `scene`'s protocol (which must keep the hard-grain prelude): the
    /// plan resolved again.
    pub fn with_scene(mut self, scene: Scene) -> Result<Start, String> {
        let plan = Plan::new(&scene, &self.diameter)?;
        (self.stages, self.interlude) = after_prelude(&plan, self.prelude.len());
        self.scene = scene;
        Ok(self)
    }

    /// Does any grain start spinning?
    pub fn spinning(&self) -> bool {
        self.spin.iter().flatten().any(|&w| w != 0.0)
    }

    /// The spin of grain `i` as a 3D vector (a disk spins about z).
    pub fn spin3(&self, i: usize) -> [f64; 3] {
        match self.spin.get(i).map(Vec::as_slice) {
            Some(&[w]) => [0.0, 0.0, w],
            Some(&[x, y, z]) => [x, y, z],
            _ => [0.0; 3],
        }
    }

    /// The scene's law, in reduced units.
    pub fn law(&self) -> &Law {
        &self.scene.law
    }

    /// Solid fraction of the start.
    pub fn packing_fraction(&self) -> f64 {
        let d = self.dimension;
        let solid: f64 = self
            .diameter
            .iter()
            .map(|&x| {
                if d == 2 {
                    std::f64::consts::PI * x * x / 4.0
                } else {
                    std::f64::consts::PI * x * x * x / 6.0
                }
            })
            .sum();
        solid / self.lengths.iter().product::<f64>()
    }

    /// Does the scene's law carry attraction?
    pub fn cohesive(&self) -> bool {
        self.scene.law.cohesion().is_some()
    }

    /// Mass density giving m = d^dimension: 6/π per volume (spheres), 4/π per area (disks).
    pub fn density(&self) -> f64 {
        if self.dimension == 2 {
            4.0 / std::f64::consts::PI
        } else {
            6.0 / std::f64::consts::PI
        }
    }
}

/// The DEM stages of `plan` from stage `first_dem` on, and the hard-grain stages among them
/// (refused through the matrix: `hard-grain-interlude`).
fn after_prelude(plan: &Plan, first_dem: usize) -> (Vec<PlanStage>, Vec<String>) {
    let mut stages = Vec::new();
    let mut interlude = Vec::new();
    for step in &plan.steps[first_dem..] {
        match step {
            PlanStep::Dem(s) => stages.push(*s),
            PlanStep::Hard(h) => interlude.push(h.name().to_string()),
        }
    }
    (stages, interlude)
}

fn start_dim<D: Dim>(scene: &Scene) -> Result<Start, String> {
    let (grains, plan, first_dem): (Grains<D>, Plan, usize) = prepared_grains::<D>(scene)?;
    let prelude = plan.steps[..first_dem]
        .iter()
        .map(|s| s.name().to_string())
        .collect();
    let (stages, interlude) = after_prelude(&plan, first_dem);
    let n = grains.s.len();
    let mass: Vec<f64> = grains
        .diameter
        .iter()
        .map(|d| d.powi(D::D as i32))
        .collect();
    let inertia_factor = if D::D == 2 { 0.125 } else { 0.1 };
    Ok(Start {
        scene: scene.clone(),
        dimension: D::D,
        lengths: grains.l.to_vec(),
        position: (0..n)
            .map(|i| D::mul(grains.s[i], grains.l).to_vec())
            .collect(),
        velocity: grains.u.iter().map(|u| u.to_vec()).collect(),
        spin: grains.w.iter().map(|w| w.to_vec()).collect(),
        inertia: mass
            .iter()
            .zip(&grains.diameter)
            .map(|(m, d)| inertia_factor * m * d * d)
            .collect(),
        mass,
        diameter: grains.diameter.clone(),
        prelude,
        interlude,
        trace_steps: scene
            .output
            .trace_every
            .zip(stages.first())
            .map(|(t, s)| ((t / s.dt).round() as u64).max(1)),
        stages,
    })
}

impl Start {
    /// The time step of every DEM stage, if they share one (a step count is then a time).
    pub fn uniform_dt(&self) -> Option<f64> {
        let dt = self.stages.first()?.dt;
        self.stages.iter().all(|s| s.dt == dt).then_some(dt)
    }
}

/// Header lines common to every deck (each code prefixes its comment marker).
pub fn header_lines(start: &Start, code: Code, deviations: &[String]) -> Vec<String> {
    let s = &start.scene;
    let mut h = vec![
        format!(
            "grainbench deck for scene `{}` ({}), generated by grainbench {} — do not edit; rerun `grainbench decks {}`",
            s.name,
            code.name(),
            env!("CARGO_PKG_VERSION"),
            s.name
        ),
        s.description.clone(),
        format!(
            "N = {}, dimension {}, seed {}, start Φ = {:.6}, reduced units (a = 1, m(a) = 1, force unit {})",
            start.n(),
            start.dimension,
            s.seed,
            start.packing_fraction(),
            if start.cohesive() { "F0" } else { "P_ref a^(d-1)" }
        ),
    ];
    if !start.prelude.is_empty() {
        h.push(format!(
            "The data file holds the grains after the hard-grain stages run by grainbench: {}",
            start.prelude.join(", ")
        ));
    }
    if deviations.is_empty() {
        h.push("Deviations from the grainbench law and protocol: none".into());
    } else {
        h.push("Deviations from the grainbench law and protocol:".into());
        for d in deviations {
            h.push(format!("  - {d}"));
        }
    }
    h
}

/// FNV-1a, 64 bits: a stable checksum of the generated data files.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf29ce484222325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x100000001b3)
    })
}

/// Is `name` a generated data file (not committed; its checksum is in `deck.json`)?
pub fn is_data_file(deck: &Deck, name: &str) -> bool {
    deck.files.iter().skip(1).any(|(n, _)| n == name) && name != super::import::Meta::FILE
}

/// μ as a number for codes without an infinite friction coefficient: ∞ → 1e300.
pub fn mu_number(mu: Mu) -> f64 {
    match mu {
        Mu::Finite(x) => x,
        Mu::Infinite => 1e300,
    }
}

/// [`mu_number`] as deck text.
pub fn mu_text(mu: Mu) -> String {
    num(mu_number(mu))
}

/// Formats a float so that it reads back to the same value (shortest round-trip form).
pub fn num(x: f64) -> String {
    if x.is_infinite() {
        return if x > 0.0 {
            "1e300".into()
        } else {
            "-1e300".into()
        };
    }
    let s = format!("{x:e}");
    // `1e0` → `1`, keep mantissa/exponent otherwise.
    s.strip_suffix("e0").map(str::to_string).unwrap_or(s)
}
