//! The knobs `accuracy` sweeps (time step, strain-rate cap, equilibrium tolerance, κ), the
//! settings of one run, and the scene with those settings applied.

use anyhow::{Context, Result};
use grainbench_comparisons::xcode::decks::Code;
use grainbench_engine::scene::{Criteria, Law, Step};
use grainbench_engine::Scene;
use serde_json::{json, Value};

/// A knob that trades time for accuracy.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Knob {
    Dt,
    Inertia,
    Tolerance,
    Kappa,
}

impl Knob {
    pub const ALL: [Knob; 4] = [Knob::Dt, Knob::Inertia, Knob::Tolerance, Knob::Kappa];

    pub fn name(self) -> &'static str {
        match self {
            Knob::Dt => "dt",
            Knob::Inertia => "inertia",
            Knob::Tolerance => "tolerance",
            Knob::Kappa => "kappa",
        }
    }

    pub fn parse(s: &str) -> Result<Knob> {
        Knob::ALL
            .into_iter()
            .find(|k| k.name() == s.trim())
            .with_context(|| {
                format!("--knobs: unknown knob {s:?}; expected dt, inertia, tolerance or kappa")
            })
    }

    /// Which way is "tighter" (more accurate, more expensive): the smallest value, except κ.
    pub fn tighter(self, a: f64, b: f64) -> bool {
        match self {
            Knob::Kappa => a > b,
            _ => a < b,
        }
    }

    /// The built-in values of the sweep for `scene` (always including the scene's own).
    pub fn default_values(self, scene: &Scene, base: &Settings) -> Vec<f64> {
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
pub fn normalize(mut v: Vec<f64>) -> Vec<f64> {
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
    pub fn of(scene: &Scene) -> Settings {
        Settings {
            dt: scene.numerics.dt_fraction,
            inertia: first_inertia_cap(scene),
            tolerance: 1.0,
            kappa: scene.law.kappa(),
        }
    }

    pub fn get(&self, k: Knob) -> f64 {
        match k {
            Knob::Dt => self.dt,
            Knob::Inertia => self.inertia.unwrap_or(f64::NAN),
            Knob::Tolerance => self.tolerance,
            Knob::Kappa => self.kappa,
        }
    }

    pub fn with(mut self, k: Knob, x: f64) -> Settings {
        match k {
            Knob::Dt => self.dt = x,
            Knob::Inertia => self.inertia = Some(x),
            Knob::Tolerance => self.tolerance = x,
            Knob::Kappa => self.kappa = x,
        }
        self
    }

    /// A directory name for the cache of this point.
    pub fn label(&self) -> String {
        let i = self
            .inertia
            .map_or("none".to_string(), |x| format!("{x:e}"));
        format!(
            "dt{:e}_I{i}_tol{:e}_kappa{:e}",
            self.dt, self.tolerance, self.kappa
        )
    }

    pub fn key(&self) -> String {
        self.label()
    }

    pub fn to_json(self) -> Value {
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

fn scale_criteria(c: &mut Criteria, f: f64) {
    c.force *= f;
    c.moment *= f;
    c.pressure *= f;
    c.kinetic *= f;
}

/// One swept point: a code, a knob and its value.
#[derive(Clone, Debug)]
pub struct Point {
    pub code: Code,
    /// `None`: the reference.
    pub knob: Option<Knob>,
    pub settings: Settings,
    /// The scene's own value of this knob.
    pub is_default: bool,
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

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
