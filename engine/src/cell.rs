//! Orthorhombic periodic cell with variable lengths and the stress control of AR07 (6)–(8).

use crate::geometry::{Dim, Tensor, VectorOps};

/// How the cell lengths evolve.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
pub enum Control<D: Dim> {
    /// Fixed volume and shape.
    Fixed,
    /// Prescribed diagonal stresses Σ_α (compressive positive), with |L̇_α/L_α| capped.
    Stress { target: D::V, rate_cap: f64 },
}

/// The periodic cell `[0, L_1) × … × [0, L_d)`; positions are stored reduced, r = L·s.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
pub struct Cell<D: Dim> {
    /// Lengths L_α.
    pub l: D::V,
    /// Rates L̇_α.
    pub ldot: D::V,
    /// Generalized mass M of AR07 (7).
    pub mass: f64,
    pub control: Control<D>,
}

impl<D: Dim> Cell<D> {
    pub fn new(l: D::V, mass: f64) -> Self {
        Cell {
            l,
            ldot: D::V::zero(),
            mass,
            control: Control::Fixed,
        }
    }

    /// Ω = Π L_α (area in 2D).
    #[inline]
    pub fn volume(&self) -> f64 {
        D::product(self.l)
    }

    /// Strain rates ε̇_α = L̇_α/L_α (positive for expansion).
    #[inline]
    pub fn strain_rate(&self) -> D::V {
        D::div(self.ldot, self.l)
    }

    /// Kick of the cell rates by AR07 (7): M L̈_α = (Ω/L_α)(σ_αα − Σ_α), then the cap on
    /// the strain rate. `stress` is the measured stress (AR07 (8)). Called once per step with
    /// the full `dt` (leapfrog: the stored rates are half-step rates).
    pub fn kick(&mut self, stress: &Tensor, dt: f64) {
        match self.control {
            Control::Fixed => self.ldot = D::V::zero(),
            Control::Stress { target, rate_cap } => {
                let omega = self.volume();
                for a in 0..D::D {
                    let acc = omega / (self.mass * self.l[a]) * (stress[a][a] - target[a]);
                    let cap = rate_cap * self.l[a];
                    self.ldot[a] = (self.ldot[a] + dt * acc).clamp(-cap, cap);
                }
            }
        }
    }

    /// Drift of the lengths.
    pub fn drift(&mut self, dt: f64) {
        if let Control::Stress { .. } = self.control {
            self.l += self.ldot * dt;
        }
    }
}
