//! Scene files: one TOML file per scene (`reference-inputs/scenes/*.toml`).
//!
//! Everything is dimensionless, in reduced units: lengths in units of
//! the largest diameter `a`, masses in units of the mass of a grain of diameter `a`, forces in
//! units of `F0` (cohesive laws) or of `P_ref·a^(d-1)` (cohesionless laws), so that pressures
//! in the protocol are `P/P_ref` or `P* = P a/F0` (GRC07 (12)).
//!
//! Parsing rejects unknown keys; [`Scene::validate`] checks every value and names the file,
//! the field and what is allowed.

mod error;
mod validate;

pub use error::SceneError;
pub use validate::max_random_packing_fraction;

use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::PathBuf;

/// A whole scene.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name, used for output files.
    pub name: String,
    /// One line saying what the scene is and which paper section it follows.
    #[serde(default)]
    pub description: String,
    /// The published state this scene reproduces (a key of golden/paper-values.toml, e.g.
    /// `ar07-D-10kPa`); `grainbench reproduce` compares with it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub paper_state: Option<String>,
    /// 2 (disks) or 3 (spheres).
    pub dimension: usize,
    /// Seed of the random initial state.
    #[serde(default = "default_seed")]
    pub seed: u64,
    pub particles: Particles,
    pub law: Law,
    pub initial: Initial,
    #[serde(default)]
    pub numerics: Numerics,
    /// Steps run in order.
    pub protocol: Vec<Step>,
    #[serde(default)]
    pub output: Output,
}

/// Where the grains start.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Arrangement {
    #[default]
    Random,
    Fcc,
}

/// How the initial Maxwell velocities depend on grain mass.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Maxwell {
    /// Each component Gaussian with variance ∝ 1/m: one temperature, equal mean kinetic energy.
    #[default]
    Equipartition,
    /// One Gaussian for every grain, whatever its mass (GRC07 §III.B's "random velocities
    /// drawn according to a Maxwell distribution, with mean quadratic velocity V0" read as one
    /// velocity distribution): large grains move faster than under equipartition.
    MassIndependent,
    /// One Gaussian for every grain with `rms_velocity` as the standard deviation of each
    /// Cartesian component, so the mean of |v|² is d·rms² (V0 read as a per-component spread,
    /// as `v = V0·(g1, g2)` draws it).
    PerComponent,
}

impl Maxwell {
    fn is_default(&self) -> bool {
        *self == Maxwell::Equipartition
    }
}

fn default_seed() -> u64 {
    1
}

/// Number of grains and their size distribution.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Particles {
    pub count: usize,
    /// Smallest diameter in units of the largest one, `a` (GRC07: 0.5; monodisperse: 1).
    #[serde(default = "one")]
    pub min_diameter: f64,
    /// Diameter classes: `K` ≥ 2 equally spaced diameters from `min_diameter` to 1, each grain
    /// drawn uniformly among them (absent: uniform in [min_diameter, 1]). LAMMPS 2021 writes the
    /// GRC07 attraction as one `pair_style table` per pair of atom types, exact only when the
    /// diameters come in classes (docs/external-codes.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub classes: Option<usize>,
}

fn one() -> f64 {
    1.0
}

/// Friction coefficient: a number, or `"inf"` for contacts that never slide.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mu {
    Finite(f64),
    Infinite,
}

impl Mu {
    pub fn value(self) -> f64 {
        match self {
            Mu::Finite(x) => x,
            Mu::Infinite => f64::INFINITY,
        }
    }
}

impl Serialize for Mu {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Mu::Finite(x) => s.serialize_f64(*x),
            Mu::Infinite => s.serialize_str("inf"),
        }
    }
}

impl<'de> Deserialize<'de> for Mu {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Mu;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("`mu` as a non-negative number or \"inf\"")
            }
            fn visit_f64<E: serde::de::Error>(self, x: f64) -> Result<Mu, E> {
                if x.is_infinite() && x > 0.0 {
                    Ok(Mu::Infinite)
                } else {
                    Ok(Mu::Finite(x))
                }
            }
            fn visit_i64<E: serde::de::Error>(self, x: i64) -> Result<Mu, E> {
                Ok(Mu::Finite(x as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, x: u64) -> Result<Mu, E> {
                Ok(Mu::Finite(x as f64))
            }
            fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<Mu, E> {
                match s {
                    "inf" | "infinity" | "Infinity" => Ok(Mu::Infinite),
                    _ => Err(E::custom(format!(
                        "`mu` must be a non-negative number or \"inf\", found \"{s}\""
                    ))),
                }
            }
        }
        d.deserialize_any(V)
    }
}

/// Contact law and its dimensionless parameters.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Law {
    /// Hertz–Mindlin spheres (AR07 §II.A, App. A, App. B).
    HertzMindlin {
        /// κ = (Ẽ/P_ref)^(2/3) (AR07 (21)).
        kappa: f64,
        /// Friction coefficient μ (0, finite or "inf").
        mu: Mu,
        /// Normal damping as a fraction of critical (AR07 (5)).
        zeta: f64,
        /// Poisson ratio ν, giving K_T/K_N = (2-2ν)/(2-ν) (AR07 (3)).
        #[serde(default = "default_poisson")]
        poisson: f64,
        /// LIGGGHTS 3.8's `cohesion sjkr`: an attraction k·πa² in contact (πa²: area of the
        /// circle where the two spheres intersect), k in units of P_ref
        /// (`engine/src/contact/sjkr.rs`). Absent: no cohesion.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        sjkr: Option<f64>,
        /// YADE's DMT adhesion (`Law2_ScGeom_MindlinPhys_Mindlin(includeAdhesion=True)`): a
        /// constant pull 4πR*γ in contact, γ in units of P_ref·a (`engine/src/contact/dmt.rs`).
        /// Absent: no adhesion.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        dmt: Option<f64>,
    },
    /// Linear spring–dashpot–Coulomb disks or spheres with optional short-range adhesion and
    /// rolling resistance (GRC07 §II.B).
    Linear {
        /// κ = K_N a/F0 with cohesion, K_N/P_ref without (GRC07 §II.C).
        kappa: f64,
        /// Friction coefficient μ.
        mu: Mu,
        /// Normal damping as a fraction of critical (GRC07 (6)).
        zeta: f64,
        /// K_T/K_N.
        #[serde(default = "one")]
        kt_over_kn: f64,
        /// Viscous damping of the tangential and rolling relative motion in contacts, as a
        /// fraction of critical. GRC07 §II.B has none ("we chose not to implement any
        /// tangential viscous force"): 0 is the paper's law; a positive value is a deviation,
        /// reported as such, that damps the oscillations of grains held by a single contact.
        #[serde(default)]
        tangential_damping: f64,
        /// Adhesion: contact pull −F0 and linear attraction over the gap range D0 (GRC07 (4)–(5)).
        #[serde(default)]
        cohesion: Option<Cohesion>,
        /// Rolling resistance (GRC07 (9)–(10)).
        #[serde(default)]
        rolling: Option<Rolling>,
    },
}

fn default_poisson() -> f64 {
    0.3
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Cohesion {
    /// Attraction range D0/a (GRC07 T.I: 1e-3).
    pub d0: f64,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Rolling {
    /// K_r/(K_N a²) (GRC07 T.I: 1e-4).
    pub kr: f64,
    /// μ_r/a (GRC07 T.I: 0.005 with μ = 0.5).
    pub mu_r: f64,
}

/// Initial state: a random non-overlapping gas, or an FCC lattice (AR07 §III).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Initial {
    /// `random` (sequential random placement, GRC07 §III.A) or `fcc` (n = 4k³ spheres on an
    /// FCC lattice, AR07 §III).
    #[serde(default)]
    pub arrangement: Arrangement,
    /// Solid fraction Φ_I of the initial state.
    pub packing_fraction: f64,
    /// Root-mean-square speed of Maxwell velocities (reduced units); 0 = grains at rest.
    #[serde(default)]
    pub rms_velocity: f64,
    /// How those velocities depend on mass (`equipartition`, the default, or
    /// `mass-independent`; either way the mean of v² over the grains is `rms_velocity`²), or
    /// `per-component` (mass-independent, mean v² = d·`rms_velocity`²).
    #[serde(default, skip_serializing_if = "Maxwell::is_default")]
    pub maxwell: Maxwell,
    /// Start instead from the grains of this snapshot (positions, diameters, cell lengths),
    /// at rest; `particles.count` and `dimension` must match it; a relative path is taken from
    /// the working directory (as LAMMPS `read_data`). Used by `grainbench bench
    /// --start` to time every code on the same dense packing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub snapshot: Option<PathBuf>,
    /// Start instead from the grains listed in this CSV file (explicit-particle scenes: two-
    /// and few-body tests, starts written by other programs): a header naming the columns
    /// `x`, `y`, (`z`,) `diameter`, optionally velocities `vx`, `vy`, (`vz`,) and spins `w`
    /// (2D) or `wx`, `wy`, `wz` (3D), in any order, other columns ignored; one row per grain,
    /// positions in [0, L) (wrapped if not), lengths in a. Needs `cell`; `particles.count` and
    /// `dimension` must match it; a relative path is taken from the working directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub particles: Option<PathBuf>,
    /// The same grains listed in the scene itself, one table per grain with the columns of a
    /// `particles` file as keys: `grains = [{ x = 5.0, y = 5.0, z = 5.0, diameter = 1.0 }, …]`
    /// (few-body scenes: impacts, chains). Needs `cell`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grains: Option<Vec<std::collections::BTreeMap<String, f64>>>,
    /// Side lengths of the periodic cell (a) of a `particles` or `grains` start.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cell: Option<Vec<f64>>,
}

/// Numerical settings; the defaults suit the papers' scenes.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Numerics {
    /// Time step as a fraction of the shortest binary contact duration π√(m_eff/K_max).
    pub dt_fraction: f64,
    /// For Hertz contacts: the normal force, in units of the force scale, at which K_max is
    /// evaluated.
    pub stiffness_force: f64,
    /// Verlet skin in units of a: speed only, no bit of a run depends on it (engine/tests/skin.rs);
    /// the LAMMPS and LIGGGHTS decks get the same.
    pub skin: f64,
    /// Generalized mass of the cell as a fraction of the total grain mass (AR07 §II.B: ~1;
    /// GRC07 §II.A: 3/10).
    pub cell_mass: f64,
    /// Divide the cell mass by the cell length L/a (GRC07 §II.A's wording: "a fraction of the
    /// sum of grain masses (3/10 in most calculations), divided by a linear size L of the
    /// cell"). L is taken when the soft-contact stages start. The GRC07 scenes leave it off:
    /// with 2D stresses (force per length) in GRC07 (3), M ε̈ = σ^I − σ^M, M is a mass, and
    /// the 42–70 × lighter cell this gives makes z miss T.III by 5–10 % (README, GRC07).
    pub cell_mass_per_length: bool,
    /// Stress control by a first-order servo with no cell mass instead of AR07 (7): each
    /// axis' strain rate is g·(σ_αα − P)/P on the contact stress, at most the stage's cap
    /// (`cell_mass` unused). The LAMMPS adhesive decks' control (deform/pressure in 2025, a
    /// fix deform servo in 2021), which then use this g. Needs P > 0 in every `compress`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub servo_gain: Option<f64>,
    /// Grain and contact velocities see the cell's strain rate (AR07 (6): u̇ = F/m + ε̇·u,
    /// contact velocity Δu + ε̇·r, so the normal dashpot resists the affine compression).
    /// `false` is LAMMPS's (and LIGGGHTS's) `remap x`: positions follow the cell,
    /// velocities do not. Without it our engine's servo loop goes unstable (README).
    pub affine_velocity: bool,
    /// Steps between equilibrium checks and progress reports (1 to 10 000).
    pub check_every: u64,
    /// The run stops as unstable when an overlap exceeds this fraction of the smaller radius.
    pub max_overlap: f64,
}

impl Default for Numerics {
    fn default() -> Self {
        Numerics {
            dt_fraction: 0.02,
            stiffness_force: 10.0,
            skin: 0.02,
            cell_mass: 1.0,
            cell_mass_per_length: false,
            servo_gain: None,
            affine_velocity: true,
            check_every: 200,
            max_overlap: 0.1,
        }
    }
}

/// One protocol step.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Step {
    /// Stress-controlled run of the periodic cell towards an isotropic pressure (AR07 (6)–(8)),
    /// with the strain rate capped at `inertia_cap` (AR07 (23) I, or GRC08 I_a = ε̇_max T0).
    Compress {
        pressure: f64,
        inertia_cap: f64,
        max_time: f64,
        #[serde(default)]
        criteria: Criteria,
        /// Friction coefficient for this step instead of `law.mu` (AR07 §IV.B: state C is
        /// assembled without friction, mixed, then compressed with μ = 0.3). A change of μ
        /// between consecutive steps starts the new step without contact history.
        #[serde(default)]
        mu: Option<Mu>,
        /// Stiffness κ for this step instead of `law.kappa` (contacts and history are kept;
        /// the time step follows the stiffness).
        #[serde(default)]
        kappa: Option<f64>,
        /// Final relaxation once the structure has settled (see [`Relax`]).
        #[serde(default)]
        relax: Option<Relax>,
    },
    /// Fixed cell.
    FixedVolume {
        max_time: f64,
        #[serde(default)]
        criteria: Criteria,
        /// Run the full time even when the criteria hold.
        #[serde(default)]
        full_time: bool,
        #[serde(default)]
        mu: Option<Mu>,
        #[serde(default)]
        kappa: Option<f64>,
        /// Final relaxation once the structure has settled (see [`Relax`]).
        #[serde(default)]
        relax: Option<Relax>,
    },
    /// Fixed cell until all grains form one cluster of interacting grains (GRC07 §III.B,
    /// method 2: aggregation of a cohesive gas).
    Aggregate {
        max_time: f64,
        #[serde(default)]
        mu: Option<Mu>,
        #[serde(default)]
        kappa: Option<f64>,
    },
    /// Stepwise stiffness ramp at a fixed pressure: κ = `from`·`factor`^k up to `to`, each
    /// level run to its criteria (GRC07 §III.B.2, series B: aggregation at κ = 1e2, then κ
    /// raised slowly to 1e4).
    KappaRamp {
        from: f64,
        to: f64,
        factor: f64,
        pressure: f64,
        inertia_cap: f64,
        /// Time limit of each level.
        max_time: f64,
        #[serde(default)]
        criteria: Criteria,
        #[serde(default)]
        mu: Option<Mu>,
        /// Final relaxation once the structure has settled (see [`Relax`]).
        #[serde(default)]
        relax: Option<Relax>,
    },
    /// Stepwise pressure program: P = `from`·`factor`^k (or divided, when unloading) up to
    /// `to`, each level a `compress` step run to its criteria (AR07 T.III QS rows; GRC08
    /// §II.D.2: factor 10^(1/8) from P* = 0.01 to 13.33 and back).
    PressureProgram {
        from: f64,
        to: f64,
        factor: f64,
        inertia_cap: f64,
        /// Time limit of each level.
        max_time: f64,
        #[serde(default)]
        criteria: Criteria,
        #[serde(default)]
        mu: Option<Mu>,
        /// Final relaxation once the structure has settled (see [`Relax`]).
        #[serde(default)]
        relax: Option<Relax>,
    },
    /// Event-driven hard-sphere (hard-disk) dynamics in the fixed cell with elastic collisions
    /// until `collisions_per_grain` collisions per grain on average, from Maxwell velocities;
    /// velocities are zero at the end (AR07 §III: melting the FCC lattice; §IV.B: mixing).
    HardSphereMix { collisions_per_grain: f64 },
    /// Lubachevsky–Stillinger growth of all diameters in event-driven dynamics until the solid
    /// fraction reaches `packing_fraction` (AR07 §III.A, state A'); `rate` is the growth rate
    /// of the diameters in units of the rms velocity. Velocities are zero at the end and the
    /// length unit is rescaled so that the largest diameter is again a.
    Grow {
        packing_fraction: f64,
        #[serde(default = "default_growth_rate")]
        rate: f64,
    },
    /// Scales the cell and all coordinates by `factor` (AR07 §IV.B: λ = 1.005 opens the
    /// contacts of a packing before mixing); velocities are set to zero.
    Expand { factor: f64 },
}

fn default_growth_rate() -> f64 {
    1e-2
}

impl Step {
    /// Soft-contact (DEM) steps run the contact law; the others move hard grains.
    pub fn is_dem(&self) -> bool {
        matches!(
            self,
            Step::Compress { .. }
                | Step::FixedVolume { .. }
                | Step::Aggregate { .. }
                | Step::PressureProgram { .. }
                | Step::KappaRamp { .. }
        )
    }
    pub fn kind(&self) -> &'static str {
        match self {
            Step::Compress { .. } => "compress",
            Step::FixedVolume { .. } => "fixed-volume",
            Step::Aggregate { .. } => "aggregate",
            Step::PressureProgram { .. } => "pressure-program",
            Step::KappaRamp { .. } => "kappa-ramp",
            Step::HardSphereMix { .. } => "hard-sphere-mix",
            Step::Grow { .. } => "grow",
            Step::Expand { .. } => "expand",
        }
    }
    /// Time limit of a DEM step (of each level of a pressure program).
    pub fn max_time(&self) -> f64 {
        match self {
            Step::Compress { max_time, .. }
            | Step::FixedVolume { max_time, .. }
            | Step::Aggregate { max_time, .. }
            | Step::PressureProgram { max_time, .. }
            | Step::KappaRamp { max_time, .. } => *max_time,
            _ => 0.0,
        }
    }
    pub fn criteria(&self) -> Criteria {
        match self {
            Step::Compress { criteria, .. }
            | Step::FixedVolume { criteria, .. }
            | Step::PressureProgram { criteria, .. }
            | Step::KappaRamp { criteria, .. } => *criteria,
            _ => Criteria::default(),
        }
    }
    /// The μ override of a DEM step.
    pub fn mu(&self) -> Option<Mu> {
        match self {
            Step::Compress { mu, .. }
            | Step::FixedVolume { mu, .. }
            | Step::Aggregate { mu, .. }
            | Step::PressureProgram { mu, .. }
            | Step::KappaRamp { mu, .. } => *mu,
            _ => None,
        }
    }
    /// The κ override of a DEM stage.
    pub fn kappa(&self) -> Option<f64> {
        match self {
            Step::Compress { kappa, .. }
            | Step::FixedVolume { kappa, .. }
            | Step::Aggregate { kappa, .. } => *kappa,
            _ => None,
        }
    }
    /// The final relaxation of a DEM stage.
    pub fn relax(&self) -> Option<Relax> {
        match self {
            Step::Compress { relax, .. }
            | Step::FixedVolume { relax, .. }
            | Step::PressureProgram { relax, .. }
            | Step::KappaRamp { relax, .. } => *relax,
            _ => None,
        }
    }
    /// Pressure levels of a pressure program, `from` to `to` inclusive.
    pub fn pressure_levels(from: f64, to: f64, factor: f64) -> Vec<f64> {
        let mut levels = vec![from];
        let up = to >= from;
        let mut p = from;
        loop {
            p = if up { p * factor } else { p / factor };
            // A level within 0.1 % of the end is the end.
            if (up && p >= to * (1.0 - 1e-3)) || (!up && p <= to * (1.0 + 1e-3)) {
                if levels.last() != Some(&to) {
                    levels.push(to);
                }
                return levels;
            }
            levels.push(p);
        }
    }
}

/// Final relaxation of a DEM stage (engine/src/run/relax.rs): once the interaction list
/// has been unchanged for `settle_time` with the kinetic and stress criteria met (to
/// `settle_factor`), the peculiar velocities
/// and spins are damped at rate `damping` (v ← v e^{−γ dt} each step) and, when
/// `tangential_zeta` > 0, tangential and rolling dashpots of that fraction of critical act in
/// the contacts, until the criteria hold. Before the switch the law is the paper's, exactly.
///
/// With `method = "fire"` the phase after the switch is FIRE (engine/src/run/fire.rs) in place
/// of the damping: for frictionless, non-adhesive laws only, whose equilibrium states are the
/// local minima of the enthalpy (AR07 §III.A).
///
/// In a scene: `relax = { damping = 1.0, tangential_zeta = 0.5, settle_time = 10.0 }`, or
/// `relax = { method = "fire", settle_time = 0.0, settle_factor = 1e3 }`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Relax {
    /// What acts after the switch. Always written: the stage watch keeps this struct in
    /// binary checkpoints, where a skipped field would misalign what follows.
    #[serde(default)]
    pub method: RelaxMethod,
    /// Background damping rate γ, per time unit (T0 with cohesion); `damping` method only.
    #[serde(default)]
    pub damping: f64,
    /// Tangential and rolling dashpot, fraction of critical (linear law only).
    #[serde(default)]
    pub tangential_zeta: f64,
    /// Time the interaction list must stay unchanged before the damping starts.
    pub settle_time: f64,
    /// GRC07 §III.A stopping rule without rolling resistance: a grain with one interaction
    /// rolls freely on its partner (nothing damps that motion) and the paper stops "when the
    /// kinetic energy is below a set tolerance", not waiting "until all freely rolling disks
    /// reach their final position". With `free_rollers` the settling test leaves such grains
    /// out (their pairs and their kinetic energy); the damping then stops them where they are.
    /// Needs a cohesive law without rolling resistance.
    #[serde(default)]
    pub free_rollers: bool,
    /// The switch needs the kinetic and stress criteria met to this factor (≥ 1, default 1):
    /// for soft scenes (κ ≈ 1e4) whose undamped rolling modes keep the kinetic energy a few
    /// times above GRC07's tolerance while the interaction list stays unchanged. The stage
    /// still ends on the criteria themselves.
    #[serde(default = "one")]
    pub settle_factor: f64,
    /// The switch tests the stress criterion on the pressure averaged over the last
    /// `settle_time` instead of at the check: under GRC08's pressure steps the cell of a loose
    /// packing rings about its target (only the grains' normal dashpots damp its breathing)
    /// with a stress error 10²–10³ times the criterion while the interaction list and the
    /// kinetic energy have settled; on the mean the switch comes once the ringing is centred
    /// on the target. The stage still ends on the criteria themselves.
    #[serde(default)]
    pub mean_stress: bool,
}

/// What a final relaxation applies after its switch ([`Relax::method`]).
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum RelaxMethod {
    /// Background damping of velocities and spins (and optional tangential/rolling dashpots).
    #[default]
    Damping,
    /// FIRE (Bitzek et al. 2006) on the grains and the cell, from the stage's time step up to
    /// ten times it: a descent to the nearest minimum of the enthalpy (AR07 §III.A).
    Fire,
}

/// Equilibrium criteria (AR07 §III, GRC07 §II.D, GRC08 §II.D.1), in units of a force scale
/// `F_ref`: `a^(d-1)·P` for `scale = "pressure"` (AR07), `F1 = max(F0, P a^(d-1))` for
/// `scale = "cohesion"` (GRC07).
///
/// In a scene: `criteria = { preset = "grc07" }`, optionally with fields overriding the preset
/// (`criteria = { preset = "ar07", force = 1e-5 }`).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(try_from = "CriteriaTable")]
pub struct Criteria {
    pub scale: ForceScale,
    /// Largest net force on a grain, in F_ref.
    pub force: f64,
    /// Largest net moment on a grain, in F_ref·a (not used when the law has no moments).
    pub moment: f64,
    /// Largest deviation of a diagonal contact stress from its target, in F_ref/a^(d-1).
    pub pressure: f64,
    /// Kinetic energy per grain, in F_ref·a.
    pub kinetic: f64,
    /// Time over which every check must meet the criteria before the stage ends (0: the first
    /// check that meets them). A window of about one period of the slowest rolling mode
    /// (~2 T0) keeps a vibrating packing from passing at a lucky instant.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub window: f64,
    /// AR07 §III.A: "on setting all velocities to zero, it is observed that the sample does
    /// not regain kinetic energy". At a check where every criterion but the kinetic one holds,
    /// the grains' velocities and spins and the cell's rate are set to zero, and the stage goes
    /// on to be judged at the next check (engine/src/run/quench.rs). For packings whose
    /// divalent grains keep rolling on two contacts (AR07 App. E), a motion no dashpot of the
    /// law damps; the stage report says how often and what it changed. Ignored by stages that
    /// do not end on the criteria (`aggregate`, full-time `fixed-volume`).
    #[serde(default, skip_serializing_if = "is_false")]
    pub quench: bool,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn is_false(x: &bool) -> bool {
    !*x
}

/// Scene form of [`Criteria`]: a preset and overrides.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CriteriaTable {
    preset: Option<String>,
    scale: Option<ForceScale>,
    force: Option<f64>,
    moment: Option<f64>,
    pressure: Option<f64>,
    kinetic: Option<f64>,
    window: Option<f64>,
    quench: Option<bool>,
}

impl TryFrom<CriteriaTable> for Criteria {
    type Error = String;
    fn try_from(t: CriteriaTable) -> Result<Self, String> {
        let base = match t.preset.as_deref() {
            None | Some("ar07") => Criteria::ar07(),
            Some("grc07") => Criteria::grc07(),
            Some("grc08") => Criteria::grc08(),
            Some(other) => {
                return Err(format!(
                    "unknown criteria preset \"{other}\", expected \"ar07\", \"grc07\" or \"grc08\""
                ))
            }
        };
        Ok(Criteria {
            scale: t.scale.unwrap_or(base.scale),
            force: t.force.unwrap_or(base.force),
            moment: t.moment.unwrap_or(base.moment),
            pressure: t.pressure.unwrap_or(base.pressure),
            kinetic: t.kinetic.unwrap_or(base.kinetic),
            window: t.window.unwrap_or(base.window),
            quench: t.quench.unwrap_or(base.quench),
        })
    }
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum ForceScale {
    Pressure,
    Cohesion,
}

impl Criteria {
    /// AR07 §III: force < 1e-4 a²P, stress to 1e-4 P, kinetic energy < 1e-8 P a³.
    pub fn ar07() -> Self {
        Criteria {
            scale: ForceScale::Pressure,
            force: 1e-4,
            moment: 1e-4,
            pressure: 1e-4,
            kinetic: 1e-8,
            window: 0.0,
            quench: false,
        }
    }
    /// GRC07 §II.D.
    pub fn grc07() -> Self {
        Criteria {
            scale: ForceScale::Cohesion,
            force: 1e-4,
            moment: 1e-4,
            pressure: 1e-4,
            kinetic: 5e-8,
            window: 0.0,
            quench: false,
        }
    }
    /// GRC08 §II.D.1: as GRC07 with 1e-5.
    pub fn grc08() -> Self {
        Criteria {
            force: 1e-5,
            moment: 1e-5,
            pressure: 1e-5,
            ..Self::grc07()
        }
    }
}

impl Default for Criteria {
    fn default() -> Self {
        Self::ar07()
    }
}

/// Where the results go (relative to the output directory given on the command line).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// Final snapshot file name.
    pub snapshot: String,
    /// Record every grain (and, for two grains, their impact) at least this often in
    /// simulated time, in our engine (`run` as with `--trace-every`) and in every code's deck
    /// (few-body scenes of at most [`MAX_TRACE_GRAINS`] grains).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trace_every: Option<f64>,
}

/// Most grains a trace keeps (every frame is held in memory).
pub const MAX_TRACE_GRAINS: usize = 1000;

impl Default for Output {
    fn default() -> Self {
        Output {
            snapshot: "final.snap.json".into(),
            trace_every: None,
        }
    }
}

impl Scene {
    /// Whether `other` runs the same trajectory: equal in every setting but the Verlet skin,
    /// which changes no bit of a run (engine/tests/skin.rs). Records, finished seeds and
    /// checkpoints made with another skin stay valid.
    pub fn same_run(&self, other: &Scene) -> bool {
        let mut other = other.clone();
        other.numerics.skin = self.numerics.skin;
        *self == other
    }

    /// The protocol as run: each step, with pressure programs unrolled into one `compress`
    /// step per level; paired with the index of the protocol step it comes from.
    pub fn stages(&self) -> Vec<(usize, Step)> {
        let mut out = Vec::new();
        for (k, step) in self.protocol.iter().enumerate() {
            match step {
                Step::PressureProgram {
                    from,
                    to,
                    factor,
                    inertia_cap,
                    max_time,
                    criteria,
                    mu,
                    relax,
                } => {
                    for p in Step::pressure_levels(*from, *to, *factor) {
                        out.push((
                            k,
                            Step::Compress {
                                pressure: p,
                                inertia_cap: *inertia_cap,
                                max_time: *max_time,
                                criteria: *criteria,
                                mu: *mu,
                                kappa: None,
                                relax: *relax,
                            },
                        ));
                    }
                }
                Step::KappaRamp {
                    from,
                    to,
                    factor,
                    pressure,
                    inertia_cap,
                    max_time,
                    criteria,
                    mu,
                    relax,
                } => {
                    for level in Step::pressure_levels(*from, *to, *factor) {
                        out.push((
                            k,
                            Step::Compress {
                                pressure: *pressure,
                                inertia_cap: *inertia_cap,
                                max_time: *max_time,
                                criteria: *criteria,
                                mu: *mu,
                                kappa: Some(level),
                                relax: *relax,
                            },
                        ));
                    }
                }
                _ => out.push((k, step.clone())),
            }
        }
        out
    }

    /// Lowers every stage's time limit to at most `t`.
    pub fn cap_max_time(&mut self, t: f64) {
        for step in &mut self.protocol {
            match step {
                Step::Compress { max_time, .. }
                | Step::FixedVolume { max_time, .. }
                | Step::Aggregate { max_time, .. }
                | Step::PressureProgram { max_time, .. }
                | Step::KappaRamp { max_time, .. } => *max_time = max_time.min(t),
                _ => {}
            }
        }
    }

    /// Friction coefficient of a DEM step: its override or `law.mu`.
    pub fn mu_of(&self, step: &Step) -> Mu {
        step.mu().unwrap_or(self.law.mu())
    }
}

impl Law {
    /// The stiffness parameter κ.
    pub fn kappa(&self) -> f64 {
        match self {
            Law::HertzMindlin { kappa, .. } | Law::Linear { kappa, .. } => *kappa,
        }
    }
    /// The friction coefficient μ.
    pub fn mu(&self) -> Mu {
        match self {
            Law::HertzMindlin { mu, .. } | Law::Linear { mu, .. } => *mu,
        }
    }
    pub fn cohesion(&self) -> Option<Cohesion> {
        match self {
            Law::Linear { cohesion, .. } => *cohesion,
            Law::HertzMindlin { .. } => None,
        }
    }
    /// Does the law attract (GRC07 adhesion or the SJKR area cohesion)? Such scenes report
    /// tensile forces, z0 and clusters.
    pub fn attractive(&self) -> bool {
        match self {
            Law::Linear { cohesion, .. } => cohesion.is_some(),
            Law::HertzMindlin { sjkr, dmt, .. } => sjkr.is_some() || dmt.is_some(),
        }
    }
    pub fn has_moments(&self) -> bool {
        match self {
            Law::HertzMindlin { mu, .. } => mu.value() > 0.0,
            Law::Linear { mu, rolling, .. } => mu.value() > 0.0 || rolling.is_some(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_run_ignores_the_skin_and_nothing_else() {
        let text = include_str!("../../../reference-inputs/scenes/grc07-cohesive-small.toml");
        let a = Scene::from_toml(text, std::path::Path::new("a.toml")).unwrap();
        let mut b = a.clone();
        b.numerics.skin = 0.3;
        assert!(a != b && a.same_run(&b) && b.same_run(&a));
        let mut c = b.clone();
        c.numerics.dt_fraction *= 2.0;
        assert!(!a.same_run(&c) && !c.same_run(&a));
    }
}
