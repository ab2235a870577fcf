//! AR07 §III.A velocity quench (`criteria.quench`).
//!
//! AR07 stops its compressions on three criteria and adds: "On setting all velocities to zero,
//! it is observed that the sample does not regain kinetic energy beyond that value, while the
//! unbalanced force level does not increase." Divalent grains rolling on their two contacts
//! (AR07 App. E, fig. 14(b)) keep their kinetic energy: the contact forces do no work in that
//! motion and no dashpot of the law acts on it, so a packing can hold every criterion but the
//! kinetic one for thousands of time units (docs/performance.md, N = 1372). With `quench`, a
//! check where only the kinetic criterion fails sets every grain's velocity and spin and the
//! cell's rate to zero; the dynamics then goes on unchanged and the next check judges the
//! criteria again. [`Quenched`] reports how often, the energy removed, and what the packing did
//! from the first quench to the end of the stage.

use super::reference::Reference;
use crate::geometry::Dim;
use serde::{Deserialize, Serialize};

/// What the quenches of a stage removed and changed (in the stage report).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quenched {
    /// Stage time of the first quench, and how many checks quenched.
    pub first_time: f64,
    pub count: u32,
    /// Kinetic energy per grain set to zero, summed over the quenches (all translations and
    /// spins, reduced units).
    pub kinetic_removed_per_grain: f64,
    /// Interacting pairs at the first quench, and those gained and lost since.
    pub pairs: usize,
    pub pairs_gained: usize,
    pub pairs_lost: usize,
    /// Φ(end) − Φ(first quench).
    pub delta_phi: f64,
    /// Largest displacement of a grain centre relative to the cell since the first quench
    /// (nearest image, scaled by the cell lengths at the end), in a.
    pub max_displacement: f64,
}

/// The quenches of one stage so far (saved in checkpoints).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct QuenchLog<D: Dim> {
    first: Option<Reference<D>>,
    count: u32,
    removed: f64,
}

impl<D: Dim> QuenchLog<D> {
    /// Records a quench at stage time `time` removing `kinetic_per_grain`; the first one keeps
    /// the interacting pairs (i < j, any order), Φ and the reduced positions.
    pub fn record(
        &mut self,
        time: f64,
        kinetic_per_grain: f64,
        pairs: impl FnOnce() -> Vec<(u32, u32)>,
        phi: f64,
        s: &[D::V],
    ) {
        if self.first.is_none() {
            self.first = Some(Reference::new(time, pairs(), phi, s));
        }
        self.count += 1;
        self.removed += kinetic_per_grain;
    }

    /// Whether the stage has quenched.
    pub fn any(&self) -> bool {
        self.first.is_some()
    }

    /// The report at the end of the stage (`None` without a quench), from its final pairs,
    /// Φ, reduced positions and cell lengths.
    pub fn report(
        &self,
        t0: f64,
        pairs: &mut [(u32, u32)],
        phi: f64,
        s: &[D::V],
        l: D::V,
    ) -> Option<Quenched> {
        let first = self.first.as_ref()?;
        let c = first.change(pairs, phi, s, l);
        Some(Quenched {
            first_time: first.time - t0,
            count: self.count,
            kinetic_removed_per_grain: self.removed,
            pairs: c.pairs,
            pairs_gained: c.gained,
            pairs_lost: c.lost,
            delta_phi: c.delta_phi,
            max_displacement: c.max_displacement,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::D2;
    use nalgebra::Vector2;

    #[test]
    fn report_counts_quenches_and_what_changed_since_the_first() {
        let mut log = QuenchLog::<D2>::default();
        let s0 = vec![Vector2::new(0.1, 0.1), Vector2::new(0.98, 0.5)];
        assert!(log
            .report(0.0, &mut [], 0.5, &s0, Vector2::new(10.0, 10.0))
            .is_none());
        log.record(5.0, 2e-8, || vec![(1, 2), (0, 1)], 0.60, &s0);
        // The second quench does not move the reference state.
        let s1 = vec![Vector2::new(0.1, 0.1), Vector2::new(0.01, 0.5)];
        log.record(6.0, 1e-8, || vec![(0, 3)], 0.61, &s1);
        let r = log
            .report(
                1.0,
                &mut [(2, 3), (0, 1)],
                0.62,
                &s1,
                Vector2::new(10.0, 10.0),
            )
            .unwrap();
        assert_eq!((r.first_time, r.count), (4.0, 2));
        assert!((r.kinetic_removed_per_grain - 3e-8).abs() < 1e-20);
        assert_eq!((r.pairs, r.pairs_gained, r.pairs_lost), (2, 1, 1));
        assert!((r.delta_phi - 0.02).abs() < 1e-12);
        // 0.98 → 0.01 across the periodic boundary: 0.03 of a 10 a cell.
        assert!((r.max_displacement - 0.3).abs() < 1e-9);
    }
}
