//! Orthorhombic periodic cell with variable lengths and the stress control of AR07 (6)–(8).

use crate::geometry::{Dim, Tensor, VectorOps};

/// How the cell lengths evolve.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
pub enum Control<D: Dim> {
    /// Fixed volume and shape.
    Fixed,
    /// Prescribed diagonal stresses Σ_α (compressive positive), with |L̇_α/L_α| capped.
    /// `servo: None`: AR07 (7), the cell has a mass. `Some(g)`: first-order servo with no
    /// cell mass, ε̇_α = g·(σ_αα − Σ_α)/Σ_α on the contact stress (the LAMMPS adhesive decks'
    /// deform/pressure; `numerics.servo_gain`).
    Stress {
        target: D::V,
        rate_cap: f64,
        #[serde(default)]
        servo: Option<f64>,
    },
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
    /// Whether grain and contact velocities see the cell's strain rate (AR07 (6): u̇ = F/m +
    /// ε̇·u, contact velocity Δu + ε̇·r). `false` is LAMMPS's `remap x`: positions follow
    /// the cell, velocities do not (`numerics.affine_velocity`).
    #[serde(default = "yes")]
    pub affine_velocity: bool,
}

fn yes() -> bool {
    true
}

impl<D: Dim> Cell<D> {
    pub fn new(l: D::V, mass: f64) -> Self {
        Cell {
            l,
            ldot: D::V::zero(),
            mass,
            control: Control::Fixed,
            affine_velocity: true,
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

    /// The strain rate as the grain and contact velocities see it: ε̇, or zero without
    /// [`Cell::affine_velocity`].
    #[inline]
    pub fn velocity_strain_rate(&self) -> D::V {
        if self.affine_velocity {
            self.strain_rate()
        } else {
            D::V::zero()
        }
    }

    /// Kick of the cell rates by AR07 (7): M L̈_α = (Ω/L_α)(σ_αα − Σ_α), then the cap on
    /// the strain rate. `stress` is the measured stress (AR07 (8)), `contact` its contact
    /// part (what the servo reads, as LAMMPS's virial). Called once per step with the full
    /// `dt` (leapfrog: the stored rates are half-step rates).
    pub fn kick(&mut self, stress: &Tensor, contact: &Tensor, dt: f64) {
        match self.control {
            Control::Fixed => self.ldot = D::V::zero(),
            Control::Stress {
                target,
                rate_cap,
                servo: Some(g),
            } => {
                for a in 0..D::D {
                    let rate = capped(g * (contact[a][a] - target[a]) / target[a], rate_cap);
                    self.ldot[a] = rate * self.l[a];
                }
            }
            Control::Stress {
                target,
                rate_cap,
                servo: None,
            } => {
                let omega = self.volume();
                for a in 0..D::D {
                    let acc = omega / (self.mass * self.l[a]) * (stress[a][a] - target[a]);
                    let cap = rate_cap * self.l[a];
                    self.ldot[a] = capped(self.ldot[a] + dt * acc, cap);
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

/// `x` limited to [−cap, cap]; NaN when the cap is NaN or negative (a cell length gone
/// non-finite or negative), so that the run's stability check stops it with its message
/// instead of `f64::clamp` panicking (`pressure = 1e20` blows the cell up; docs/reliability.md).
#[inline]
fn capped(x: f64, cap: f64) -> f64 {
    if cap >= 0.0 {
        x.clamp(-cap, cap)
    } else {
        f64::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::D2;
    use nalgebra::Vector2;

    fn stressed(servo: Option<f64>) -> Cell<D2> {
        let mut c = Cell::<D2>::new(Vector2::new(10.0, 20.0), 1.0);
        c.control = Control::Stress {
            target: Vector2::new(0.01, 0.01),
            rate_cap: 2e-3,
            servo,
        };
        c
    }

    /// The servo's rate is g·(σ_αα − P)/P on the contact stress, at most the cap, whatever
    /// the rate before (no cell mass); AR07 (7) instead accelerates the cell from its rate.
    /// A cell length gone NaN or negative leaves NaN rates for the stability check to report,
    /// not a panic in `f64::clamp` (docs/reliability.md).
    #[test]
    fn kick_on_a_broken_cell_gives_nan_not_a_panic() {
        let total = [[1.0; 3]; 3];
        for l in [f64::NAN, -1.0] {
            let mut c = stressed(None);
            c.l[0] = l;
            c.kick(&total, &total, 0.1);
            assert!(c.ldot[0].is_nan(), "L = {l}: {}", c.ldot[0]);
        }
    }

    #[test]
    fn servo_sets_the_rate_from_the_contact_stress_and_caps_it() {
        let mut total = [[0.0; 3]; 3];
        total[0][0] = 1.0;
        total[1][1] = 1.0;
        let mut contact = [[0.0; 3]; 3];
        contact[0][0] = 0.011; // 10 % above P: rate 0.1 g, expansion
        contact[1][1] = 0.0; // far below: the cap, contraction
        let mut c = stressed(Some(0.004));
        c.ldot = Vector2::new(5.0, 5.0);
        c.kick(&total, &contact, 0.1);
        assert!((c.strain_rate()[0] - 0.1 * 0.004).abs() < 1e-15);
        assert_eq!(c.strain_rate()[1], -2e-3);
        // Without the servo, the same contact stress and total stress 1.0 drive it by AR07 (7).
        let mut m = stressed(None);
        m.kick(&total, &contact, 0.1);
        assert_eq!(m.strain_rate()[0], 2e-3);
    }

    /// `affine_velocity = false` (LAMMPS `remap x`): the cell still deforms, the velocities
    /// see no strain rate.
    #[test]
    fn remap_without_affine_velocity_hides_the_strain_rate_from_velocities() {
        let mut c = stressed(None);
        c.ldot = Vector2::new(0.01, -0.04);
        assert_eq!(c.velocity_strain_rate(), c.strain_rate());
        c.affine_velocity = false;
        assert_eq!(c.velocity_strain_rate(), Vector2::zeros());
        assert_eq!(c.strain_rate(), Vector2::new(0.01 / 10.0, -0.04 / 20.0));
    }
}
