//! How the run of one code ended, as the records of `compare` ([`CodeResult`]), `bench` and
//! `accuracy` carry it. Written as the kebab-case strings of the JSON, CSV and Markdown
//! outputs (`ran`, `missing`, `timeout`, …); the final state of a run that ended is said
//! apart, by the snapshot's status (`equilibrium`, `time-limit`).
//!
//! [`CodeResult`]: crate::xcode::crosscode::CodeResult

use serde::{Deserialize, Serialize};
use std::fmt;

/// How the run of one code ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Outcome {
    /// Ran to its end; the final state says how (`equilibrium`, `time-limit`).
    Ran,
    /// Not run: the values recorded in `golden/<scene>/<code>.json`.
    Recorded,
    /// The code's binary is not on `PATH`.
    Missing,
    /// The code cannot express the scene (capability matrix).
    Refused,
    /// Killed at the wall-time limit (`--time-limit`).
    Timeout,
    /// Stopped by Ctrl-C.
    Interrupted,
    /// Exited with an error, or its final state could not be read.
    Failed,
    /// Blew up: the time step is past stability (our instability error, LAMMPS `Lost atoms`).
    Unstable,
    /// Refused by the scene validation (e.g. `dt_fraction` > 0.5).
    Invalid,
}

impl Outcome {
    pub const ALL: [Outcome; 9] = [
        Outcome::Ran,
        Outcome::Recorded,
        Outcome::Missing,
        Outcome::Refused,
        Outcome::Timeout,
        Outcome::Interrupted,
        Outcome::Failed,
        Outcome::Unstable,
        Outcome::Invalid,
    ];

    /// The word of the outputs.
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Ran => "ran",
            Outcome::Recorded => "recorded",
            Outcome::Missing => "missing",
            Outcome::Refused => "refused",
            Outcome::Timeout => "timeout",
            Outcome::Interrupted => "interrupted",
            Outcome::Failed => "failed",
            Outcome::Unstable => "unstable",
            Outcome::Invalid => "invalid",
        }
    }

    pub fn parse(s: &str) -> Option<Outcome> {
        Outcome::ALL.into_iter().find(|o| o.as_str() == s)
    }
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl PartialEq<str> for Outcome {
    fn eq(&self, other: &str) -> bool {
        self.as_str() == other
    }
}

impl PartialEq<&str> for Outcome {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_round_trip_through_serde() {
        for o in Outcome::ALL {
            let json = serde_json::to_string(&o).unwrap();
            assert_eq!(json, format!("\"{o}\""));
            assert_eq!(serde_json::from_str::<Outcome>(&json).unwrap(), o);
            assert_eq!(Outcome::parse(o.as_str()), Some(o));
        }
        assert_eq!(Outcome::parse("equilibrium"), None);
    }
}
