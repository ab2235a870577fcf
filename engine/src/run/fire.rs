//! FIRE, the fast inertial relaxation engine (Bitzek, Koskinen, Gähler, Moseler and Gumbsch,
//! Phys. Rev. Lett. 97, 170201 (2006)), as the final phase of a frictionless stage
//! (`relax = { method = "fire", … }`), to shorten the time to the criteria
//! (docs/performance.md).
//!
//! AR07 §III.A: "configurations of rigid, frictionless, non-adhesive spherical particles in
//! stable equilibrium under an isotropic confining pressure are those that realize a local
//! minimum of volume", and with deformable contacts a minimum of the elastic energy plus PΩ
//! (AR07 (25)). Any dynamics that descends to the nearest minimum reaches the same kind of
//! state; FIRE does it in fewer steps than the damped Newtonian dynamics of the law. After
//! each velocity-Verlet step with power P = Σ F·u + Σ_α F^cell_α L̇_α (F^cell_α =
//! (Ω/L_α)(σ_αα − Σ_α), AR07 (7)):
//! - P > 0: u ← (1 − α)u + α|u|F̂ over the grains; after `N_MIN` such steps in a row the
//!   time step grows by `F_INC` (up to `DT_MAX` times the stage's) and α shrinks by `F_ALPHA`;
//! - P ≤ 0: every velocity and spin and the cell's rate are set to zero, the time step is
//!   halved (not below the stage's) and α is reset to `ALPHA_START`.
//!
//! The normal dashpot is switched off in this phase: the resets dissipate, a dashpot exerts no
//! force at rest (the equilibria are the law's), and at ζ = 0.98 it would make ten times the
//! stage's step unstable (explicit velocity Verlet is stable to 0.27 of the contact duration at
//! ζ = 0.98, 0.64 without damping). The contact law is otherwise unchanged, and so is the
//! stress control; the stage still ends on its criteria. The step never drops below the
//! stage's own; ten times it is a fifth of the stiffest contact's duration at the default
//! `numerics.dt_fraction`.

use crate::contact::ContactLaw;
use crate::geometry::{Dim, VectorOps};
use crate::system::System;
use serde::{Deserialize, Serialize};

/// Bitzek et al.'s parameters.
const N_MIN: u32 = 5;
const F_INC: f64 = 1.1;
const F_DEC: f64 = 0.5;
const ALPHA_START: f64 = 0.1;
const F_ALPHA: f64 = 0.99;
/// Largest time step, in units of the stage's.
pub const DT_MAX: f64 = 10.0;

/// FIRE's state (saved in checkpoints with the stage watch).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fire {
    /// The stage's time step, and FIRE's current one.
    dt0: f64,
    dt: f64,
    alpha: f64,
    /// Steps in a row with P > 0 (moving down the enthalpy).
    downhill: u32,
    /// Steps taken, and how many had P ≤ 0 (velocities zeroed).
    pub steps: u64,
    pub resets: u64,
    /// Largest time step reached, in units of the stage's.
    pub peak_dt: f64,
}

/// What FIRE did in a stage (in the relaxation report).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FireStats {
    pub steps: u64,
    /// Steps with P ≤ 0, where the velocities were zeroed.
    pub resets: u64,
    /// Largest time step reached / the stage's.
    pub peak_dt: f64,
}

impl Fire {
    /// FIRE from a stage whose time step is `dt`.
    pub fn new(dt: f64) -> Self {
        Fire {
            dt0: dt,
            dt,
            alpha: ALPHA_START,
            downhill: 0,
            steps: 0,
            resets: 0,
            peak_dt: 1.0,
        }
    }

    /// The time step of the next step.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    pub fn stats(&self) -> FireStats {
        FireStats {
            steps: self.steps,
            resets: self.resets,
            peak_dt: self.peak_dt,
        }
    }

    /// Mixes or zeroes the velocities after one step of `sys` and sets its next time step.
    pub fn after_step<D: Dim, L: ContactLaw<D>>(&mut self, sys: &mut System<D, L>) {
        self.steps += 1;
        let (mut power, mut uu, mut ff) = (0.0, 0.0, 0.0);
        for (u, f) in sys.u.iter().zip(&sys.force) {
            power += f.dot(u);
            uu += u.norm_squared();
            ff += f.norm_squared();
        }
        power += cell_power(sys);
        if power > 0.0 {
            if ff > 0.0 {
                let (a, b) = (1.0 - self.alpha, self.alpha * (uu / ff).sqrt());
                for (u, f) in sys.u.iter_mut().zip(&sys.force) {
                    *u = *u * a + *f * b;
                }
            }
            self.downhill += 1;
            if self.downhill > N_MIN {
                self.dt = (self.dt * F_INC).min(DT_MAX * self.dt0);
                self.alpha *= F_ALPHA;
            }
        } else {
            self.resets += 1;
            self.downhill = 0;
            self.dt = (self.dt * F_DEC).max(self.dt0);
            self.alpha = ALPHA_START;
            sys.quench();
        }
        self.peak_dt = self.peak_dt.max(self.dt / self.dt0);
        sys.dt = self.dt;
    }
}

/// Σ_α F^cell_α L̇_α with F^cell_α = (Ω/L_α)(σ_αα − Σ_α) (AR07 (7)); 0 in a fixed cell.
fn cell_power<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>) -> f64 {
    let crate::cell::Control::Stress { target, .. } = sys.cell.control else {
        return 0.0;
    };
    let (stress, omega) = (sys.stress(), sys.cell.volume());
    (0..D::D)
        .map(|a| omega / sys.cell.l[a] * (stress[a][a] - target[a]) * sys.cell.ldot[a])
        .sum()
}
