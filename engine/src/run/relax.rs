//! Final relaxation of a DEM stage and the windowed equilibrium test.
//!
//! GRC07's adhesive law damps only the normal relative velocity of touching grains, so the
//! rolling and tangential modes of one-contact grains, chains and loops (uncoupled from the
//! normal gap at first order at h0 = F0/K_N) keep vibrating with e-folding times of 10³–10⁵ T0
//! after the structure has stopped changing: the net-force criterion of GRC07 §II.D is never
//! met. A stage with `relax` runs GRC07's law exactly until the interaction list has been
//! unchanged for `settle_time` with the kinetic and stress criteria met, then switches on background
//! damping of the peculiar velocities and spins (and, optionally, tangential and rolling
//! dashpots) until the criteria hold over a window. [`Relaxation`] reports what the damped
//! phase changed: pairs gained and lost, ΔΦ and the largest grain displacement. With
//! `relax.method = "fire"` (frictionless stages) FIRE acts after the switch instead of the
//! damping ([`super::fire`]).

use super::fire::{Fire, FireStats};
use super::reference::Reference;
use crate::geometry::Dim;
use crate::scene::{Relax, RelaxMethod};
use serde::{Deserialize, Serialize};

/// What the damped phase of a stage changed (in the stage report).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Relaxation {
    /// Stage time at which the damping was switched on.
    pub start_time: f64,
    /// Background damping rate γ and tangential/rolling dashpot ζ_t that were applied.
    pub damping: f64,
    pub tangential_zeta: f64,
    /// Interacting pairs at the switch, and those gained and lost since.
    pub pairs: usize,
    pub pairs_gained: usize,
    pub pairs_lost: usize,
    /// Φ(end) − Φ(switch).
    pub delta_phi: f64,
    /// Largest displacement of a grain centre relative to the cell since the switch (nearest
    /// image of the reduced displacement, scaled by the cell lengths at the end), in a.
    pub max_displacement: f64,
    /// Free rollers (one-interaction grains, `relax.free_rollers`) left out of the settling
    /// test and stopped by the damping where they were (0 without `free_rollers`).
    #[serde(default)]
    pub free_rollers: usize,
    /// What FIRE did, when it was the method (`relax.method = "fire"`; damping is then 0).
    /// Always written, `null` otherwise: the step reports travel in checkpoint headers, which
    /// are bincode and cannot skip a field (skipped, every relaxation without FIRE made the
    /// checkpoint unreadable).
    #[serde(default)]
    pub fire: Option<FireStats>,
}

/// The state at the switch, kept to measure what the damped phase changes.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
struct Switch<D: Dim> {
    at: Reference<D>,
    rollers: usize,
}

/// What a stage watches across its checks: settling of the interaction list, the damped
/// phase, how long the criteria have held, the peak strain rate. Saved in checkpoints so that
/// a resumed run ends bit-identical to an uninterrupted one.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct StageWatch<D: Dim> {
    relax: Option<Relax>,
    /// Hash of the sorted interaction list at the last check, and since when it is unchanged.
    pairs_hash: u64,
    unchanged_since: f64,
    switch: Option<Switch<D>>,
    /// Stage time since which every check met the criteria.
    held_since: Option<f64>,
    /// Largest strain rate max_α |L̇_α/L_α| seen at a check.
    pub peak_strain_rate: f64,
    /// (time, signed pressure deviation in criterion units) of the checks within the last
    /// `settle_time`, for `relax.mean_stress`.
    #[serde(default)]
    deviations: std::collections::VecDeque<(f64, f64)>,
    /// The velocity quenches of `criteria.quench` (AR07 §III.A).
    pub quench: super::quench::QuenchLog<D>,
    /// FIRE after the switch (`relax.method = "fire"`).
    pub fire: Option<Fire>,
}

impl<D: Dim> StageWatch<D> {
    pub fn new(relax: Option<Relax>, time: f64) -> Self {
        StageWatch {
            relax,
            pairs_hash: 0,
            unchanged_since: time,
            switch: None,
            held_since: None,
            peak_strain_rate: 0.0,
            deviations: Default::default(),
            quench: Default::default(),
            fire: None,
        }
    }

    /// Whether the interaction list is still being watched for the switch.
    pub fn watching(&self) -> bool {
        self.relax.is_some() && self.switch.is_none()
    }

    /// Whether the settling test leaves free rollers out (GRC07 §III.A, `relax.free_rollers`).
    pub fn free_rollers(&self) -> bool {
        self.relax.is_some_and(|r| r.free_rollers)
    }

    /// Factor on the kinetic and stress criteria for the switch (`relax.settle_factor`).
    pub fn settle_factor(&self) -> f64 {
        self.relax.map_or(1.0, |r| r.settle_factor)
    }

    /// Whether the damped phase is on.
    pub fn damping_on(&self) -> bool {
        self.switch.is_some()
    }

    /// Velocity factor e^{−γ dt} of one step of the damped phase (`None` before it, and
    /// with FIRE).
    pub fn damping_factor(&self, dt: f64) -> Option<f64> {
        match (&self.relax, &self.switch) {
            (Some(r), Some(_)) if r.method == RelaxMethod::Damping => Some((-r.damping * dt).exp()),
            _ => None,
        }
    }

    /// At the switch of a FIRE relaxation, starts FIRE from the stage's time step `dt`.
    pub fn start_fire(&mut self, dt: f64) {
        if self.relax.is_some_and(|r| r.method == RelaxMethod::Fire) {
            self.fire = Some(Fire::new(dt));
        }
    }

    /// ζ_t of the damped phase, when it is on and asks for one.
    pub fn tangential_zeta(&self) -> Option<f64> {
        match (&self.relax, &self.switch) {
            (Some(r), Some(_)) if r.tangential_zeta > 0.0 => Some(r.tangential_zeta),
            _ => None,
        }
    }

    /// Looks at one check: the settling view (`settled`: whether the assembly is at rest and,
    /// when free rollers are left out, the list without them), the whole interaction list
    /// `pairs` (i < j, any order), Φ and the reduced positions. Returns true when the damped
    /// phase starts at this check.
    pub fn observe_structure(
        &mut self,
        time: f64,
        settled: Settling,
        pairs: &mut [(u32, u32)],
        phi: f64,
        s: &[D::V],
    ) -> bool {
        let Some(relax) = self.relax else {
            return false;
        };
        if self.switch.is_some() {
            return false;
        }
        let Settling {
            pairs: settle_pairs,
            at_rest,
            kinetic_at_rest,
            pressure_deviation,
            rollers,
        } = settled;
        let at_rest = if relax.mean_stress {
            self.deviations.push_back((time, pressure_deviation));
            while self
                .deviations
                .front()
                .is_some_and(|&(t, _)| t < time - relax.settle_time)
            {
                self.deviations.pop_front();
            }
            let mean =
                self.deviations.iter().map(|d| d.1).sum::<f64>() / self.deviations.len() as f64;
            kinetic_at_rest && mean.abs() < relax.settle_factor
        } else {
            at_rest
        };
        let hash = match settle_pairs {
            Some(mut p) => {
                p.sort_unstable();
                fnv1a(&p)
            }
            None => {
                pairs.sort_unstable();
                fnv1a(pairs)
            }
        };
        if hash != self.pairs_hash {
            self.pairs_hash = hash;
            self.unchanged_since = time;
        }
        if at_rest && time - self.unchanged_since >= relax.settle_time {
            self.switch = Some(Switch {
                at: Reference::new(time, pairs.to_vec(), phi, s),
                rollers,
            });
            return true;
        }
        false
    }

    /// Records whether the criteria hold at this check; true when they have held at every
    /// check over the last `window` of time (at once when `window` is 0).
    pub fn held(&mut self, time: f64, equilibrium: bool, window: f64) -> bool {
        if !equilibrium {
            self.held_since = None;
            return false;
        }
        let since = *self.held_since.get_or_insert(time);
        time - since >= window
    }

    /// What the damped phase changed, from the state at the end of the stage.
    pub fn report(
        &self,
        t0: f64,
        pairs: &mut [(u32, u32)],
        phi: f64,
        s: &[D::V],
        l: D::V,
    ) -> Option<Relaxation> {
        let (relax, sw) = (self.relax?, self.switch.as_ref()?);
        let c = sw.at.change(pairs, phi, s, l);
        Some(Relaxation {
            start_time: sw.at.time - t0,
            damping: relax.damping,
            tangential_zeta: relax.tangential_zeta,
            pairs: c.pairs,
            pairs_gained: c.gained,
            pairs_lost: c.lost,
            delta_phi: c.delta_phi,
            max_displacement: c.max_displacement,
            free_rollers: sw.rollers,
            fire: self.fire.as_ref().map(Fire::stats),
        })
    }
}

/// What the settling test looks at, at one check ([`StageWatch::observe_structure`]).
pub struct Settling {
    /// Interacting pairs (i < j, any order) without the free rollers' when they are left
    /// out; `None`: the whole list.
    pub pairs: Option<Vec<(u32, u32)>>,
    /// Whether the kinetic criterion (free rollers' energy left out when asked) and, under
    /// stress control, the stress criterion hold.
    pub at_rest: bool,
    /// Whether the kinetic criterion alone holds.
    pub kinetic_at_rest: bool,
    /// Signed deviation of the pressure from its target, in units of the stress criterion
    /// (0 in a fixed cell).
    pub pressure_deviation: f64,
    /// Free rollers left out (0 without `relax.free_rollers`).
    pub rollers: usize,
}

/// FNV-1a of a sorted pair list (a change of the list changes the hash but for collisions
/// of probability 2⁻⁶⁴).
fn fnv1a(pairs: &[(u32, u32)]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &(i, j) in pairs {
        for b in i.to_le_bytes().into_iter().chain(j.to_le_bytes()) {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h ^ pairs.len() as u64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::D2;
    use nalgebra::Vector2;

    fn settling(at_rest: bool) -> Settling {
        Settling {
            pairs: None,
            at_rest,
            kinetic_at_rest: at_rest,
            pressure_deviation: 0.0,
            rollers: 0,
        }
    }

    fn relax() -> Relax {
        Relax {
            method: RelaxMethod::Damping,
            damping: 1.0,
            tangential_zeta: 0.0,
            settle_time: 2.0,
            free_rollers: false,
            settle_factor: 1.0,
            mean_stress: false,
        }
    }

    #[test]
    fn switches_on_after_the_list_settles_with_low_kinetic_energy() {
        let s = vec![Vector2::new(0.1, 0.2), Vector2::new(0.5, 0.5)];
        let mut st = StageWatch::<D2>::new(Some(relax()), 0.0);
        assert!(!st.observe_structure(0.0, settling(true), &mut [(0, 1)], 0.5, &s));
        // The list changes at t = 1: the clock restarts.
        assert!(!st.observe_structure(1.0, settling(true), &mut [(0, 1), (1, 2)], 0.5, &s));
        assert!(!st.observe_structure(2.5, settling(true), &mut [(1, 2), (0, 1)], 0.5, &s));
        // Settled for 2, but kinetic energy too high.
        assert!(!st.observe_structure(3.0, settling(false), &mut [(0, 1), (1, 2)], 0.5, &s));
        assert!(st.damping_factor(0.1).is_none());
        assert!(st.observe_structure(3.1, settling(true), &mut [(0, 1), (1, 2)], 0.5, &s));
        assert!(st.damping_on());
        assert!((st.damping_factor(0.1).unwrap() - (-0.1f64).exp()).abs() < 1e-15);
        // Once on, it stays on.
        assert!(!st.observe_structure(4.0, settling(true), &mut [(0, 1)], 0.5, &s));
        assert!(st.damping_on());
    }

    /// `settle_time = 0` (the frictional D's relaxation, whose rattlers change the list at
    /// every check): the first check at rest switches, whatever the list did.
    #[test]
    fn without_settle_time_the_first_check_at_rest_switches() {
        let s = vec![Vector2::new(0.1, 0.2), Vector2::new(0.5, 0.5)];
        let mut st = StageWatch::<D2>::new(
            Some(Relax {
                settle_time: 0.0,
                ..relax()
            }),
            0.0,
        );
        assert!(!st.observe_structure(0.5, settling(false), &mut [(0, 1)], 0.5, &s));
        assert!(st.observe_structure(0.6, settling(true), &mut [(1, 2)], 0.5, &s));
        assert!(st.damping_on());
    }

    /// A cell ringing about its target (±300 criteria, never within one at a check) with the
    /// list and the kinetic energy settled: the instantaneous test never switches, the mean
    /// over `settle_time` does, once the mean is within the criterion; a ringing off target
    /// does not.
    #[test]
    fn mean_stress_switches_on_a_cell_ringing_about_its_target() {
        let s = vec![Vector2::new(0.1, 0.2), Vector2::new(0.5, 0.5)];
        let ringing = |k: usize, offset: f64| Settling {
            pairs: None,
            at_rest: false,
            kinetic_at_rest: true,
            pressure_deviation: offset + if k.is_multiple_of(2) { 300.0 } else { -300.0 },
            rollers: 0,
        };
        // Checks every 1/8; a settle time of 31/16 holds 16 checks, 8 of each sign.
        let run = |mean_stress: bool, offset: f64| {
            let mut st = StageWatch::<D2>::new(
                Some(Relax {
                    mean_stress,
                    settle_time: 1.9375,
                    ..relax()
                }),
                0.0,
            );
            (0..100).find(|&k| {
                st.observe_structure(0.125 * k as f64, ringing(k, offset), &mut [(0, 1)], 0.5, &s)
            })
        };
        assert_eq!(run(false, 0.0), None);
        // The list has been unchanged for the settle time from check 16 (t = 2) on, when the
        // window holds checks 1–16: mean 0.
        assert_eq!(run(true, 0.0), Some(16));
        assert_eq!(run(true, 5.0), None);
    }

    #[test]
    fn free_rollers_are_left_out_of_the_clock_but_not_out_of_the_report() {
        let s = vec![Vector2::new(0.1, 0.2), Vector2::new(0.5, 0.5)];
        let mut st = StageWatch::<D2>::new(
            Some(Relax {
                free_rollers: true,
                ..relax()
            }),
            0.0,
        );
        assert!(st.free_rollers());
        // Grain 3 rolls from partner 2 to partner 1: the whole list changes, the settling
        // view (its pairs left out) does not, so the clock runs on.
        let view = || Settling {
            pairs: Some(vec![(0, 1), (1, 2)]),
            at_rest: true,
            kinetic_at_rest: true,
            pressure_deviation: 0.0,
            rollers: 1,
        };
        assert!(!st.observe_structure(0.0, view(), &mut [(0, 1), (1, 2), (2, 3)], 0.5, &s));
        assert!(st.observe_structure(2.0, view(), &mut [(0, 1), (1, 2), (1, 3)], 0.5, &s));
        let r = st
            .report(
                0.0,
                &mut [(1, 3), (0, 1), (1, 2)],
                0.5,
                &s,
                Vector2::new(1.0, 1.0),
            )
            .unwrap();
        assert_eq!((r.pairs, r.pairs_gained, r.pairs_lost), (3, 0, 0));
        assert_eq!(r.free_rollers, 1);
    }

    #[test]
    fn without_relax_nothing_switches() {
        let s = vec![Vector2::new(0.1, 0.2)];
        let mut st = StageWatch::<D2>::new(None, 0.0);
        assert!(!st.observe_structure(100.0, settling(true), &mut [], 0.5, &s));
        assert!(st.damping_factor(0.1).is_none());
        assert!(st
            .report(0.0, &mut [], 0.5, &s, Vector2::new(1.0, 1.0))
            .is_none());
    }

    #[test]
    fn window_requires_every_check_to_hold() {
        let mut st = StageWatch::<D2>::new(None, 0.0);
        assert!(
            st.held(0.0, true, 0.0),
            "window 0: the first check that holds ends"
        );
        let mut st = StageWatch::<D2>::new(None, 0.0);
        assert!(!st.held(1.0, true, 2.0));
        assert!(!st.held(2.0, true, 2.0));
        assert!(!st.held(2.5, false, 2.0));
        assert!(!st.held(3.0, true, 2.0));
        assert!(!st.held(4.9, true, 2.0));
        assert!(st.held(5.0, true, 2.0));
    }

    #[test]
    fn report_counts_pairs_and_the_periodic_displacement() {
        let s0 = vec![Vector2::new(0.99, 0.5), Vector2::new(0.5, 0.5)];
        let mut st = StageWatch::<D2>::new(Some(relax()), 10.0);
        st.observe_structure(10.0, settling(true), &mut [(0, 1), (1, 2)], 0.6, &s0);
        st.observe_structure(12.0, settling(true), &mut [(0, 1), (1, 2)], 0.6, &s0);
        assert!(st.damping_on());
        // Grain 0 crosses the boundary: 0.99 → 0.01 is a displacement of 0.02 cell lengths.
        let s1 = vec![Vector2::new(0.01, 0.5), Vector2::new(0.5, 0.5)];
        let r = st
            .report(
                10.0,
                &mut [(1, 2), (2, 3), (3, 4)],
                0.61,
                &s1,
                Vector2::new(10.0, 10.0),
            )
            .unwrap();
        assert_eq!(r.start_time, 2.0);
        assert_eq!((r.pairs, r.pairs_gained, r.pairs_lost), (2, 2, 1));
        assert!((r.delta_phi - 0.01).abs() < 1e-12);
        assert!((r.max_displacement - 0.2).abs() < 1e-12);
    }
}
