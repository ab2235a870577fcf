//! The neutral exchange format (`docs/exchange-format.md`): the start, the cell, the law, the
//! protocol and the criteria of a scene in plain JSON and CSV, for any DEM code.
//! `exchange.json` (everything but the grains) and `particles.csv` (one row per grain). Its
//! stages are written from the engine's plan ([`super::Plan`]), field for field.

use super::{num, Deck, PlanStage, StageKind, Start};
use grainbench_engine::scene::{Criteria, Law, Mu, Numerics, Relax};
use serde::{Deserialize, Serialize};

/// `exchange.json`'s `format` and `version`.
pub const FORMAT: &str = "grainbench-exchange";
pub const VERSION: u32 = 1;
pub const EXCHANGE: &str = "exchange.json";
pub const PARTICLES: &str = "particles.csv";

/// `exchange.json`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Exchange {
    pub format: String,
    pub version: u32,
    pub scene: String,
    pub description: String,
    /// 2 (disks, in the x–y plane) or 3 (spheres).
    pub dimension: usize,
    pub units: Units,
    pub cell: ExchangeCell,
    /// The grains: `particles.csv`.
    pub particles: ParticlesFile,
    /// The contact law with its parameters in reduced units (`kind`: `hertz-mindlin` or
    /// `linear`; fields as in a scene's `[law]`, README "Scenes").
    pub law: Law,
    /// grainbench's numerical settings: `cell_mass` (AR07 (7), × total grain mass),
    /// `cell_mass_per_length`, `servo_gain`, `affine_velocity` are physics of the protocol;
    /// `dt_fraction`, `skin`, `check_every`, `max_overlap` are ours, for reference.
    pub numerics: Numerics,
    /// Hard-grain stages grainbench ran before `particles.csv` (already done).
    pub prelude: Vec<String>,
    /// The DEM stages, in order, each run to its criteria or its time limit.
    pub stages: Vec<ExchangeStage>,
    /// What the code writes into its output directory.
    pub output: OutputFiles,
    /// The time series of a few-body run (scene `output.trace_every`), if asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trace: Option<ExchangeTrace>,
}

/// A trace: every `every` time units (every step when below the time step), a frame of every
/// grain (`grains`: `t,id,x,y[,z],vx,vy[,vz],w` or `wx,wy,wz`) and of every interacting pair
/// (`contacts`: `t,i,j,fn,ft_x,ft_y[,ft_z]`, as `contacts.csv`), from t = 0 to the end.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ExchangeTrace {
    pub every: f64,
    pub grains: String,
    pub contacts: String,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Units {
    pub length: String,
    pub mass: String,
    pub force: String,
    pub time: String,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ExchangeCell {
    /// Periodic along every axis, `[0, L)`.
    pub periodic: bool,
    pub lengths: Vec<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ParticlesFile {
    pub file: String,
    pub count: usize,
    pub columns: Vec<String>,
}

/// One DEM stage, in absolute reduced units.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ExchangeStage {
    /// `compress` (isotropic stress control to `pressure`), `fixed-volume`, or `aggregate`
    /// (fixed cell until all grains form one cluster of interacting grains).
    pub kind: ExchangeKind,
    /// Target pressure of `compress` (force unit / a^(d−1)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure: Option<f64>,
    /// Largest strain rate of each cell axis, 1/time (0: fixed cell).
    pub max_strain_rate: f64,
    pub max_time: f64,
    /// Time step grainbench uses, and the time limit in those steps.
    pub dt: f64,
    pub max_steps: u64,
    /// Friction coefficient; `"inf"`: contacts never slide.
    pub mu: Mu,
    /// κ of the stage (the law's unless the stage changes it; history is kept).
    pub kappa: f64,
    /// Run the whole `max_time` even when the criteria hold (fixed-volume).
    #[serde(default)]
    pub full_time: bool,
    /// The criteria in absolute units: largest net force and moment on a grain, largest
    /// deviation of a diagonal contact stress from `pressure`, kinetic energy per grain.
    pub tolerances: AbsoluteTolerances,
    /// The same as the scene writes them (relative to the force scale, with the window).
    pub criteria: Criteria,
    /// Steps between checks of the criteria.
    pub check_every: u64,
    /// Final relaxation (background damping once the interaction list has settled), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relax: Option<Relax>,
}

/// An exchange stage's `kind`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum ExchangeKind {
    Compress,
    FixedVolume,
    Aggregate,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AbsoluteTolerances {
    pub force: f64,
    pub moment: f64,
    pub stress: f64,
    pub kinetic_per_grain: f64,
}

/// Files the code writes (names relative to its output directory).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OutputFiles {
    pub particles: String,
    pub contacts: String,
    pub status: String,
}

/// The code's output directory, inside the exchange directory.
pub const OUTPUT_DIR: &str = "final";
/// Output file names.
pub const OUT_PARTICLES: &str = "particles.csv";
pub const OUT_CONTACTS: &str = "contacts.csv";
pub const OUT_STATUS: &str = "status.txt";
/// Trace file names (in the output directory too).
pub const OUT_TRACE_GRAINS: &str = "trace-grains.csv";
pub const OUT_TRACE_CONTACTS: &str = "trace-contacts.csv";

/// The exchange of `start`, and the text of its `particles.csv`.
pub fn exchange(start: &Start) -> (Exchange, String) {
    let d = start.dimension;
    let axes = &["x", "y", "z"][..d];
    let mut columns = vec!["id".to_string()];
    columns.extend(axes.iter().map(|a| a.to_string()));
    columns.extend(["diameter", "mass", "inertia"].map(String::from));
    columns.extend(axes.iter().map(|a| format!("v{a}")));
    // Spins only for a start with spinning grains (optional columns).
    let spinning = start.spinning();
    if spinning {
        match d {
            2 => columns.push("w".into()),
            _ => columns.extend(axes.iter().map(|a| format!("w{a}"))),
        }
    }
    let mut csv = columns.join(",") + "\n";
    for i in 0..start.n() {
        let mut row = vec![i.to_string()];
        row.extend(start.position[i].iter().map(|&x| num(x)));
        row.push(num(start.diameter[i]));
        row.push(num(start.mass[i]));
        row.push(num(start.inertia[i]));
        row.extend(start.velocity[i].iter().map(|&x| num(x)));
        if spinning {
            // One component in 2D, three in 3D, as the columns.
            row.extend(start.spin[i].iter().map(|&x| num(x)));
        }
        csv += &(row.join(",") + "\n");
    }
    let stages = start.stages.iter().map(stage).collect();
    let cohesive = start.cohesive();
    let ex = Exchange {
        format: FORMAT.into(),
        version: VERSION,
        scene: start.scene.name.clone(),
        description: start.scene.description.clone(),
        dimension: d,
        units: Units {
            length: "a, the largest diameter".into(),
            mass: format!(
                "mass of a grain of diameter a (m = d^{d}; density {})",
                num(start.density())
            ),
            force: if cohesive {
                "F0, the adhesion force (GRC07 (12))".into()
            } else {
                format!("P_ref a^{}, the reference pressure (AR07 (21))", d - 1)
            },
            time: if cohesive {
                "T0 = sqrt(m(a)/F0 · a)".into()
            } else {
                "sqrt(m(a)/(P_ref a^(d-2)))".into()
            },
        },
        cell: ExchangeCell {
            periodic: true,
            lengths: start.lengths.clone(),
        },
        particles: ParticlesFile {
            file: PARTICLES.into(),
            count: start.n(),
            columns,
        },
        law: start.scene.law.clone(),
        numerics: start.scene.numerics.clone(),
        prelude: start.prelude.clone(),
        stages,
        output: OutputFiles {
            particles: OUT_PARTICLES.into(),
            contacts: OUT_CONTACTS.into(),
            status: OUT_STATUS.into(),
        },
        trace: start
            .trace_steps
            .zip(start.stages.first())
            .map(|(k, s)| ExchangeTrace {
                every: k as f64 * s.dt,
                grains: OUT_TRACE_GRAINS.into(),
                contacts: OUT_TRACE_CONTACTS.into(),
            }),
    };
    (ex, csv)
}

fn stage(s: &PlanStage) -> ExchangeStage {
    let (kind, pressure, full_time) = match s.kind {
        StageKind::Compress { pressure } => (ExchangeKind::Compress, Some(pressure), false),
        StageKind::FixedVolume { full_time } => (ExchangeKind::FixedVolume, None, full_time),
        StageKind::Aggregate => (ExchangeKind::Aggregate, None, false),
    };
    ExchangeStage {
        kind,
        pressure,
        max_strain_rate: s.max_strain_rate,
        max_time: s.max_time,
        dt: s.dt,
        max_steps: s.max_steps,
        mu: s.mu,
        kappa: s.kappa,
        full_time,
        tolerances: AbsoluteTolerances {
            force: s.tolerances.force,
            moment: s.tolerances.moment,
            stress: s.tolerances.stress,
            kinetic_per_grain: s.tolerances.kinetic_per_grain,
        },
        criteria: s.criteria,
        check_every: s.check_every,
        relax: s.relax,
    }
}

/// The generic deck: `exchange.json` (the input), `particles.csv` (data, checksummed).
pub fn deck(start: &Start) -> Deck {
    let (ex, csv) = exchange(start);
    Deck {
        code: super::Code::Generic,
        files: vec![
            (
                EXCHANGE.into(),
                serde_json::to_string_pretty(&ex).expect("exchange encodes") + "\n",
            ),
            (PARTICLES.into(), csv),
        ],
        deviations: Vec::new(),
        args: Vec::new(),
    }
}

impl Exchange {
    /// Reads `exchange.json`, refusing another format or version by name.
    pub fn read(path: &std::path::Path) -> Result<Exchange, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let v: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        if v["format"] != FORMAT {
            return Err(format!(
                "{}: not a grainbench exchange file (`format` is {}, expected \"{FORMAT}\")",
                path.display(),
                v["format"]
            ));
        }
        if v["version"] != VERSION {
            return Err(format!(
                "{}: exchange format version {}, this grainbench reads version {VERSION}",
                path.display(),
                v["version"]
            ));
        }
        serde_json::from_value(v).map_err(|e| format!("{}: {e}", path.display()))
    }
}
