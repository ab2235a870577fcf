//! Checks at each check point: the equilibrium measures, clusters, contacts at a threshold,
//! blow-up detection.

use super::output::snapshot_of;
use super::relax::Settling;
use super::report::{AtThreshold, Checks, RunError};
use crate::cell::Control;
use crate::contact::ContactLaw;
use crate::geometry::{Dim, VectorOps as _};
use crate::plan::{Plan, PlanStage, StageKind, Tolerances};
use crate::scene::Mu;
use crate::system::{self, System};

/// An interacting pair as the checks see it (12 bytes instead of a whole
/// [`system::Interaction`]: the list is rebuilt at every check of large packings).
#[derive(Clone, Copy, Debug)]
pub(super) struct Link {
    pub i: u32,
    pub j: u32,
    /// In contact (gap < 0); a distant attraction is not.
    pub touching: bool,
}

impl Link {
    /// The pair as (smaller index, larger index).
    pub fn pair(&self) -> (u32, u32) {
        (self.i.min(self.j), self.i.max(self.j))
    }
}

/// The interacting pairs of `sys` into `out` (cleared first, its allocation reused), in the
/// order of [`System::interactions`].
pub(super) fn links_into<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>, out: &mut Vec<Link>) {
    out.clear();
    sys.for_each_interaction(|c| {
        out.push(Link {
            i: c.i as u32,
            j: c.j as u32,
            touching: c.gap < 0.0,
        })
    });
}

/// Number of clusters of `n` grains linked by interactions (contacts or distant attractions).
pub(super) fn clusters(n: usize, inter: &[Link]) -> usize {
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut count = n;
    for c in inter {
        let (a, b) = (
            root(&mut parent, c.i as usize),
            root(&mut parent, c.j as usize),
        );
        if a != b {
            parent[a] = b;
            count -= 1;
        }
    }
    count
}

/// Consecutive-step correlation of the net forces below which a check counts as flipping.
pub(super) const FLIP_CORRELATION: f64 = -0.5;
/// Consecutive flipping checks (outside equilibrium) that stop a run as unstable.
pub(super) const FLIP_CHECKS: u32 = 5;

/// Correlation Σ a·b / √(Σ|a|² Σ|b|²) of the net forces (or torques) of two consecutive
/// steps: ≈ cos(ω dt) of the dominant mode, near 1 when the time step resolves the motion,
/// negative when the dominant mode has fewer than four steps per period (ω dt > π/2), the
/// signature of a time step past the stability of the leapfrog/velocity-Verlet scheme
/// (ω dt < 2). 1 when there is no force.
pub(super) fn step_correlation<V: crate::geometry::VectorOps>(a: &[V], b: &[V]) -> f64 {
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        ab += x.dot(y);
        aa += x.dot(x);
        bb += y.dot(y);
    }
    if aa > 0.0 && bb > 0.0 {
        ab / (aa * bb).sqrt()
    } else {
        1.0
    }
}

/// The error for a blown-up run of `plan` in `stage`; `sys` is returned to the last good
/// checkpoint to write it.
pub(super) fn unstable<D: Dim, L: ContactLaw<D>>(
    plan: &Plan,
    stage: &PlanStage,
    sys: &mut System<D, L>,
    last_good: &Option<system::LastGood<D, L>>,
    what: String,
) -> RunError {
    let k_max = stage.k_max;
    let cause = format!(
        "{what}. Likely cause: the time step dt = {:.4e} (numerics.dt_fraction = {} of the contact duration for K_max = {:.4e}) is too large for the contacts, or the contacts are too soft (law.kappa) for the applied pressure. Try a smaller numerics.dt_fraction, or a larger numerics.stiffness_force if forces exceed the expected scale",
        sys.dt, plan.dt_fraction, k_max
    );
    stopped(plan, sys, last_good, cause)
}

/// The run stops as [`RunError::Unstable`] for `cause` (the whole message), restoring the
/// last good state for the snapshot it carries.
pub(super) fn stopped<D: Dim, L: ContactLaw<D>>(
    plan: &Plan,
    sys: &mut System<D, L>,
    last_good: &Option<system::LastGood<D, L>>,
    cause: String,
) -> RunError {
    let (step, time) = (sys.step, sys.time);
    if let Some(cp) = last_good {
        sys.restore(cp);
    }
    RunError::Unstable {
        scene: plan.scene.clone(),
        step,
        time,
        cause,
        last_good: Box::new(snapshot_of(
            sys,
            plan,
            "unstable",
            match sys.cell.control {
                Control::Stress { target, .. } => Some(target[0]),
                Control::Fixed => None,
            },
        )),
    }
}

/// What the relaxation's settling test sees at one check: the interaction list, and whether
/// the assembly is at rest — the kinetic criterion and, under stress control, the stress
/// criterion hold, to `factor` (`relax.settle_factor`; a gas at rest before a slow compression
/// has an unchanged, empty list: it must not be taken for a settled packing). With `free_rollers` (GRC07 §III.A, no rolling
/// resistance), grains with exactly one interaction roll freely on their partner: their pairs
/// and their kinetic energy are left out (the energy per grain still divided by all N, as in
/// the criterion).
pub(super) fn settle_view<D: Dim, L: ContactLaw<D>>(
    sys: &System<D, L>,
    stage: &PlanStage,
    inter: &[Link],
    checks: &Checks,
    free_rollers: bool,
    factor: f64,
) -> Settling {
    let pressure_deviation = if checks.pressure_target.is_nan() {
        0.0
    } else {
        (checks.pressure - checks.pressure_target) / stage.tolerances.stress
    };
    if !free_rollers {
        return Settling {
            pairs: None,
            at_rest: checks.kinetic_ratio < factor && checks.stress_ratio < factor,
            kinetic_at_rest: checks.kinetic_ratio < factor,
            pressure_deviation,
            rollers: 0,
        };
    }
    let touching = touching(sys.len(), inter);
    let mut degree = vec![0u32; sys.len()];
    for c in inter {
        degree[c.i as usize] += 1;
        degree[c.j as usize] += 1;
    }
    let roller = |i: usize| degree[i] == 1;
    let pairs = inter
        .iter()
        .filter(|c| !roller(c.i as usize) && !roller(c.j as usize))
        .map(Link::pair)
        .collect();
    let ke: f64 = (0..sys.len())
        .filter(|&i| !roller(i))
        .map(|i| {
            let (t, r) = kinetic_parts(sys, i);
            if touching[i] {
                t + r
            } else {
                t
            }
        })
        .sum();
    let kinetic_at_rest = ke / sys.len() as f64 / stage.tolerances.kinetic_per_grain < factor;
    Settling {
        pairs: Some(pairs),
        at_rest: kinetic_at_rest && checks.stress_ratio < factor,
        kinetic_at_rest,
        pressure_deviation,
        rollers: degree.iter().filter(|&&d| d == 1).count(),
    }
}

/// Grains in contact with another one (gap < 0; a distant attraction does not count).
fn touching(n: usize, inter: &[Link]) -> Vec<bool> {
    let mut touching = vec![false; n];
    for c in inter.iter().filter(|c| c.touching) {
        touching[c.i as usize] = true;
        touching[c.j as usize] = true;
    }
    touching
}

/// Translational and rotational kinetic energy of grain `i` (rotation 0 without moments).
fn kinetic_parts<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>, i: usize) -> (f64, f64) {
    let t = 0.5 * sys.mass[i] * sys.u[i].norm_squared();
    let r = if L::MOMENTS {
        0.5 * sys.w[i].norm_squared() / sys.inv_inertia[i]
    } else {
        0.0
    };
    (t, r)
}

/// Equilibrium measures in units of the criteria of the stage, from the state and its
/// interactions `inter` ([`links_into`], computed once per check by the caller).
pub(super) fn measure<D: Dim, L: ContactLaw<D>>(
    sys: &System<D, L>,
    stage: &PlanStage,
    inter: &[Link],
) -> Checks {
    let tol = &stage.tolerances;
    let n = sys.len() as f64;
    let (fmax, tmax) = sys.max_unbalanced();
    // Kinetic energy: all translations, and the rotations of grains that touch another one. A
    // grain with no contact spinning on itself (a rattler, typically) keeps its spin forever
    // since no force can reach it; it has no bearing on the equilibrium of the packing, so
    // its spin is reported apart (`free_spin_per_grain`) instead of blocking the criterion.
    let touching = touching(sys.len(), inter);
    let mut ke_t = 0.0;
    let mut ke_r = 0.0;
    let mut ke_free = 0.0;
    for (i, &touch) in touching.iter().enumerate() {
        let (t, r) = kinetic_parts(sys, i);
        ke_t += t;
        if touch {
            ke_r += r;
        } else {
            ke_free += r;
        }
    }
    let ke = (ke_t + ke_r) / n;
    let sc = sys.contact_stress();
    let p = (0..D::D).map(|a| sc[a][a]).sum::<f64>() / D::D as f64;
    let compress = matches!(stage.kind, StageKind::Compress { .. });
    let (target, stress_ratio) = match (compress, sys.cell.control) {
        (true, Control::Stress { target, .. }) => {
            let dev = (0..D::D)
                .map(|a| (sc[a][a] - target[a]).abs())
                .fold(0.0, f64::max);
            (target[0], dev / tol.stress)
        }
        _ => (f64::NAN, 0.0),
    };
    Checks {
        packing_fraction: sys.packing_fraction(),
        pressure: p,
        pressure_target: target,
        force_ratio: fmax / tol.force,
        moment_ratio: if L::MOMENTS { tmax / tol.moment } else { 0.0 },
        stress_ratio,
        kinetic_ratio: ke / tol.kinetic_per_grain,
        kinetic_per_grain: ke,
        free_spin_per_grain: ke_free / n,
        strain_rate: (0..D::D)
            .map(|a| (sys.cell.ldot[a] / sys.cell.l[a]).abs())
            .fold(0.0, f64::max),
        interactions: inter.len(),
        clusters: if stage.kind == StageKind::Aggregate {
            clusters(sys.len(), inter)
        } else {
            0
        },
    }
}

/// Contacts whose tangential force or rolling moment sits at its threshold μ, μ_r, split by
/// the equilibrium tolerances `tol`.
pub(super) fn contacts_at_threshold<D: Dim, L: ContactLaw<D>>(
    sys: &System<D, L>,
    mu: Mu,
    mu_r: f64,
    tol: &Tolerances,
) -> AtThreshold {
    let mu = mu.value();
    let (force_tolerance, moment_tolerance) = (tol.force, tol.moment);
    let mut count = AtThreshold::default();
    sys.for_each_interaction(|c| {
        if c.gap >= 0.0 {
            return;
        }
        let ne = c.normal_elastic;
        let sliding = mu.is_finite() && mu > 0.0 && c.tangential.norm() >= mu * ne * (1.0 - 1e-9);
        let rolling = mu_r.is_finite() && c.rolling.norm() >= mu_r * ne * (1.0 - 1e-9);
        if sliding || rolling {
            count.all += 1;
            let unresolved = (!sliding || mu * ne < force_tolerance)
                && (!rolling || mu_r * ne < moment_tolerance);
            count.below_tolerance += usize::from(unresolved);
        }
    });
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cell::Cell;
    use crate::contact::linear::{Linear, NoCohesion};
    use crate::contact::slider::{Coulomb, NoRolling};
    use crate::geometry::D2;
    use nalgebra::Vector2;

    type Law = Linear<NoCohesion, Coulomb, NoRolling>;

    /// Two unit disks overlapping by 1e-3 (N = K_N h = 1) along x; `slide` gives them
    /// opposite velocities along y, which takes the tangential spring to its Coulomb cap.
    fn pair(slide: bool) -> System<D2, Law> {
        let law = Linear {
            kn: 1000.0,
            kt: 1000.0,
            zeta: 0.0,
            zeta_t: 0.0,
            cohesion: NoCohesion,
            friction: Coulomb { mu: 0.5 },
            rolling: NoRolling,
        };
        let side = 10.0;
        let s = vec![
            Vector2::new(0.5 - 0.4995 / side, 0.5),
            Vector2::new(0.5 + 0.4995 / side, 0.5),
        ];
        let mut sys = System::new(
            law,
            Cell::new(Vector2::new(side, side), 1.0),
            s,
            &[1.0, 1.0],
            0.1,
        );
        sys.dt = 1e-4;
        if slide {
            sys.u[0] = Vector2::new(0.0, -1.0);
            sys.u[1] = Vector2::new(0.0, 1.0);
        }
        sys.init_forces();
        for _ in 0..5 {
            sys.step();
        }
        sys
    }

    fn at_threshold(sys: &System<D2, Law>, force_tolerance: f64) -> AtThreshold {
        let tol = Tolerances {
            force: force_tolerance,
            moment: 1e-4,
            stress: 1e-4,
            kinetic_per_grain: 1e-8,
        };
        contacts_at_threshold(sys, Mu::Finite(0.5), f64::INFINITY, &tol)
    }

    /// GRC07 §II.D asks for strict Coulomb inequalities; a sliding contact whose Coulomb
    /// bound μN is below the force tolerance is counted apart.
    #[test]
    fn contacts_at_threshold_are_split_by_the_force_tolerance() {
        let sliding = pair(true);
        let mut n = 0.0;
        sliding.for_each_interaction(|c| n = c.normal_elastic);
        assert!((n - 1.0).abs() < 0.01, "N = {n}");
        let loaded = at_threshold(&sliding, 1e-4);
        assert_eq!(
            (loaded.all, loaded.below_tolerance, loaded.loaded()),
            (1, 0, 1)
        );
        let ignored = at_threshold(&sliding, 2.0);
        assert_eq!(
            (ignored.all, ignored.below_tolerance, ignored.loaded()),
            (1, 1, 0)
        );
        // At rest the contact is inside the cone.
        let resting = at_threshold(&pair(false), 1e-4);
        assert_eq!(resting, AtThreshold::default());
    }
}
