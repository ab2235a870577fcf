//! The grains of a run between its stages.

use crate::geometry::Dim;

/// Grains between protocol stages, independent of the contact law: what hard-sphere stages
/// read and write, and what a new contact law starts from.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
pub struct Grains<D: Dim> {
    pub l: D::V,
    pub s: Vec<D::V>,
    pub u: Vec<D::V>,
    /// Spins (explicit-particle starts); empty = all at rest. Not in checkpoints:
    /// a checkpoint holds grains only at the start of a hard-grain stage, which ends with the
    /// grains at rest.
    #[serde(skip)]
    pub w: Vec<D::Ang>,
    pub diameter: Vec<f64>,
    pub time: f64,
    pub step: u64,
}
