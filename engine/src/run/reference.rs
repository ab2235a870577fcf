//! A state of the grains kept to measure what a later phase of a stage changed: the damped
//! phase of a final relaxation ([`super::relax`]) and AR07's quenches ([`super::quench`]).

use crate::geometry::{Dim, VectorOps as _};
use serde::{Deserialize, Serialize};

/// A state kept to measure what a later phase of the stage changed: its time, interacting pairs (sorted), Φ and reduced
/// positions.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub(crate) struct Reference<D: Dim> {
    pub time: f64,
    pairs: Vec<(u32, u32)>,
    phi: f64,
    s: Vec<D::V>,
}

/// What changed from a [`Reference`] to a later state.
pub(crate) struct Change {
    /// Pairs at the reference, and those gained and lost since.
    pub pairs: usize,
    pub gained: usize,
    pub lost: usize,
    /// Φ(later) − Φ(reference).
    pub delta_phi: f64,
    /// Largest nearest-image displacement of a grain centre, scaled by the later cell, in a.
    pub max_displacement: f64,
}

impl<D: Dim> Reference<D> {
    /// The state at `time`: interacting pairs (i < j, any order), Φ, reduced positions.
    pub fn new(time: f64, mut pairs: Vec<(u32, u32)>, phi: f64, s: &[D::V]) -> Self {
        pairs.sort_unstable();
        Reference {
            time,
            pairs,
            phi,
            s: s.to_vec(),
        }
    }

    /// What changed by the state with these pairs, Φ, reduced positions and cell lengths.
    pub fn change(&self, pairs: &mut [(u32, u32)], phi: f64, s: &[D::V], l: D::V) -> Change {
        pairs.sort_unstable();
        let common = count_common(&self.pairs, pairs);
        let max_displacement = self
            .s
            .iter()
            .zip(s)
            .map(|(a, b)| {
                let mut d = *b - *a;
                for k in 0..D::D {
                    d[k] -= d[k].round();
                    d[k] *= l[k];
                }
                d.norm_squared()
            })
            .fold(0.0, f64::max)
            .sqrt();
        Change {
            pairs: self.pairs.len(),
            gained: pairs.len() - common,
            lost: self.pairs.len() - common,
            delta_phi: phi - self.phi,
            max_displacement,
        }
    }
}

/// Pairs present in both sorted lists.
fn count_common(a: &[(u32, u32)], b: &[(u32, u32)]) -> usize {
    let (mut i, mut j, mut n) = (0, 0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                n += 1;
                i += 1;
                j += 1;
            }
        }
    }
    n
}
