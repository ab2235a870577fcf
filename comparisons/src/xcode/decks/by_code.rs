//! The deck of a common start for one code: the capability matrix consulted, the code's
//! generator called, the metadata file added.

use super::capability::{features, support};
use super::feature::{Feature, Support};
use super::{fnv1a, generic, lammps, liggghts, yade, Deck, Refusal, Start};
use crate::xcode::code::Code;
use crate::xcode::import::{Meta, TraceMeta};
use grainbench_engine::plan::StageKind;
use grainbench_engine::scene::{Law, Mu};

/// The deck of `scene` for `code`, or why it cannot be written.
pub fn deck(start: &Start, code: Code) -> Result<Deck, Refusal> {
    let feats = features(start);
    let mut missing: Vec<(Feature, String)> = feats
        .iter()
        .filter_map(|f| match support(code, *f) {
            Support::Unsupported(why) => Some((*f, why.to_string())),
            _ => None,
        })
        .collect();
    // A code without adhesion (rolling resistance) need not also be told about continuous sizes.
    for (base, sizes) in [
        (Feature::Adhesion, Feature::AdhesionContinuousSizes),
        (Feature::Rolling, Feature::RollingContinuousSizes),
    ] {
        if missing.iter().any(|(f, _)| *f == base) {
            missing.retain(|(f, _)| *f != sizes);
        }
    }
    if !missing.is_empty() {
        return Err(Refusal {
            code,
            scene: start.scene.name.clone(),
            missing,
        });
    }
    // LAMMPS decks with a servo (adhesive, or the scene's servo_gain) describe their stress
    // control and box change as such.
    let servo = start.cohesive() || start.scene.numerics.servo_gain.is_some();
    let adhesive_lammps = servo && matches!(code, Code::Lammps | Code::Lammps2025);
    let deviations: Vec<String> = feats
        .iter()
        .filter_map(|f| match support(code, *f) {
            Support::Approximate(_)
                if *f == Feature::HertzDamping && damping_exact(code, start.law()) =>
            {
                None
            }
            Support::Approximate(why) if adhesive_lammps => {
                Some(lammps::adhesive_deviation(*f, why, code))
            }
            Support::Approximate(why) => Some(format!("{}: {why}", f.key())),
            _ => None,
        })
        .collect();
    let mut deck = match code {
        Code::Lammps | Code::Lammps2025 => lammps::deck(start, code, &deviations),
        Code::Liggghts => liggghts::deck(start, &deviations),
        Code::Yade => yade::deck(start, &deviations),
        // An adapter's code reads the exchange format; `external` adds its command.
        Code::Generic | Code::Adapter(_) => generic::deck(start),
        Code::Rust => unreachable!("grainbench runs scenes, not decks"),
    };
    deck.code = code;
    deck.deviations = deviations;
    let mut meta = start.meta(code);
    for (name, text) in deck.files.iter().skip(1) {
        meta.data
            .insert(name.clone(), format!("{:016x}", fnv1a(text.as_bytes())));
    }
    deck.files.push((
        Meta::FILE.into(),
        serde_json::to_string_pretty(&meta).expect("meta encodes") + "\n",
    ));
    Ok(deck)
}

/// Is the matrix's `hertz-damping` deviation void for this law? LIGGGHTS's restitution cap does
/// not bite at ζ ≤ 0.63; with DMT adhesion YADE does not clip the normal force, and the rest of
/// its damping is our law (engine/src/contact/dmt.rs).
fn damping_exact(code: Code, law: &Law) -> bool {
    match (code, law) {
        (Code::Liggghts, Law::HertzMindlin { zeta, .. }) => liggghts::damping_exact(*zeta),
        (Code::Yade, Law::HertzMindlin { dmt, .. }) => dmt.is_some(),
        _ => false,
    }
}

impl Start {
    /// What the final dumps of `code` do not say (written as `deck.json` beside the deck).
    pub fn meta(&self, code: Code) -> Meta {
        let last = self.stages.last();
        let pressure_target = self.stages.iter().rev().find_map(|s| match s.kind {
            StageKind::Compress { pressure } => Some(pressure),
            _ => None,
        });
        Meta {
            scene: self.scene.name.clone(),
            code: code.name().into(),
            dimension: self.dimension,
            pressure_target,
            cohesive: self.scene.law.attractive(),
            mu: match last.map(|s| s.mu) {
                Some(Mu::Infinite) => None,
                Some(Mu::Finite(x)) => Some(x),
                None => Some(0.0),
            },
            force_unit: if self.cohesive() {
                "F0".into()
            } else {
                format!("P_ref a^{}", self.dimension - 1)
            },
            n: self.n(),
            data: Default::default(),
            // LIGGGHTS writes no time: its trace needs one time step throughout.
            trace: self
                .trace_steps
                .filter(|_| code != Code::Liggghts || self.uniform_dt().is_some())
                .map(|every| TraceMeta {
                    file: match code {
                        Code::Yade => "trace.txt".into(),
                        Code::Generic | Code::Adapter(_) => {
                            format!("{}/{}", generic::OUTPUT_DIR, generic::OUT_TRACE_GRAINS)
                        }
                        _ => "trace.atoms".into(),
                    },
                    every,
                    dt: self.uniform_dt(),
                    contacts: matches!(code, Code::Lammps | Code::Lammps2025 | Code::Liggghts)
                        .then(|| "trace.contacts".into()),
                }),
        }
    }
}
