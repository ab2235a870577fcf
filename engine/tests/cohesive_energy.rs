//! Exact verification that the adhesive linear law of GRC07 §II.A–B is integrated without
//! error.
//!
//! With no normal dashpot (ζ = 0), no tangential or rolling dashpot (ζ_t = 0) and sliders that
//! never reach their thresholds, the law is conservative. Per contact (h < 0) it stores
//!
//! - ½ K_N h² (elastic normal force N_e = −K_N h),
//! - the potential of the constant attraction −F0 of GRC07 (5): F0 h − F0 D0/2, continuous at
//!   h = 0 with the potential −F0 (D0 − h)²/(2 D0) of GRC07 (4) for 0 ≤ h ≤ D0 (zero beyond
//!   D0),
//! - |T|²/(2 K_T) and Γ²/(2 K_r): the tangential spring and the rolling spring, read from the
//!   contact history (`ContactLaw::stored`, via `System::interactions`).
//!
//! The total energy E = Σ m u²/2 + Σ I ω²/2 (I = m r²/2 for a disk, computed here and not taken
//! from the engine) + Σ_contacts of the above is then conserved by the exact dynamics. The
//! engine's velocity-Verlet scheme updates the springs with the half-step velocities (the
//! slip v_{n+½} dt is the exact increment of a position-like variable), so it is a symplectic
//! scheme for this system and E must show (a) no secular drift and (b) a bounded fluctuation
//! of second order in dt.
//!
//! **Fluctuation bound.** For a linear system M ẍ = −K x, velocity Verlet with velocities at
//! whole steps conserves exactly, mode by mode, H̃_k = ½ ẋ_k² + ½ ω_k² x_k² (1 − (ω_k dt)²/4).
//! Hence E − Σ H̃_k = Σ ω_k⁴ dt² x_k²/8 lies in [0, (ω_max dt)²/4 · E_vib], where E_vib is the
//! energy above the equilibrium state (every contact at h0 = −F0/K_N, springs relaxed):
//! E_eq = n_c (−F0²/(2 K_N) − F0 D0/2). The fluctuation of E (and so |E_n − E_0| at any step,
//! the end included) is at most (ω_max dt)² E_vib/4. Our motions are small (h − h0 ≲ 0.3 h0,
//! rotations ≲ 1e-2 rad), so the system is linear to a few per cent; we allow a factor 2.
//!
//! **Highest frequency.** One contact couples the normal, tangential and rolling motions of
//! its two disks through rank-one stiffnesses k b bᵀ. The normal one (b: translations along
//! n) has ω² = K_N/m* (m* = m_i m_j/(m_i+m_j)); the tangential one (b: translations along t,
//! and spins with arms r_i, r_j) has ω² = K_T (1/m_i + 1/m_j + r_i²/I_i + r_j²/I_j) =
//! 3 K_T/m*, and is M⁻¹-orthogonal to the normal one; the rolling one adds at most
//! K_r (1/I_i + 1/I_j). So ω_c² ≤ max(K_N, 3 K_T)/m* + K_r (1/I_i + 1/I_j). Contacts acting on
//! disjoint grains (a matching) do not couple, so if the contacts split into χ matchings,
//! ω_max² ≤ χ max_c ω_c² (Weyl's inequality); χ = 1 for a pair, 2 for a chain and for a loop of
//! four. The time step is dt = 2π/(40 ω_max), i.e. (ω_max dt)²/4 = 6.2e-3.
//!
//! **Rounding.** Gaps are differences of reduced positions ≈ 0.5 with ulp 1.1e-16, times
//! L = 16: ~2e-15 a, i.e. 2e-10 h0. The energy is a sum of terms of order F0 D0 = 1e-3; its
//! rounding (~1e-19) and the random walk of position rounding over 2e6 steps
//! (~√(2e6) · F0 · 1e-15 ≈ 1e-12 F0 a, far smaller in practice since the net forces are
//! ≪ F0) are both far below the fluctuation bound (~1e-9 F0 a), so they do not enter it.
//!
//! Parameters (GRC07 T.I): F0 = 1, a = 1 (largest diameter), κ = K_N a/F0 = 1e5, K_T = K_N,
//! D0 = 1e-3 a, K_r = 1e-4 K_N a², μ = 0.5, μ_r = 1 a (large: rolling never yields; the test
//! asserts that neither slider ever reaches its threshold, so the run is conservative).
//! Masses are the engine's, m = (d/a)², with unequal diameters in [a/2, a].
//!
//! **Sensitivity** (mutations of the engine tried when these tests were written, then
//! reverted): the rolling moment applied with the wrong sign (an anti-restoring spring) opens
//! a contact within the first steps in all four dynamic tests; dropping the spins' opening
//! half kick makes |E − E0| 30× the bound in the three energy tests, with a fluctuation ratio
//! ≈ 1 for dt/2 (first order); the tangential spring left in the fixed frame (no transport)
//! fails `rigid_rotation_transports_stored_springs` (T·n = 1.3 F0) and the chain's
//! window-mean drift (34× its allowance); the pair and the loop, whose T oscillates about 0,
//! do not see it.
//!
//! Tests run in a one-thread rayon pool: the systems have 2–4 grains, where thread hand-offs
//! would cost more than the work, and the machine is shared.

use grainbench_engine::cell::Cell;
use grainbench_engine::contact::linear::{Adhesion, Linear};
use grainbench_engine::contact::slider::{Coulomb, RollingSpring};
use grainbench_engine::geometry::D2;
use grainbench_engine::neighbor::min_image;
use grainbench_engine::system::System;
use nalgebra::Vector2;
use std::f64::consts::PI;

type Law = Linear<Adhesion, Coulomb, RollingSpring>;
type Sys = System<D2, Law>;
type V = Vector2<f64>;

/// Cell side: large, a power of two (as in verification.rs).
const SIDE: f64 = 16.0;
const F0: f64 = 1.0;
const KAPPA: f64 = 1e5;
const KN: f64 = KAPPA * F0;
const KT: f64 = KN;
const KR: f64 = 1e-4 * KN;
const D0: f64 = 1e-3;
const MU: f64 = 0.5;
const MU_R: f64 = 1.0;
/// Pair equilibrium overlap F0/K_N (the gap is −H0).
const H0: f64 = F0 / KN;

fn law(mu: f64) -> Law {
    Linear {
        kn: KN,
        kt: KT,
        zeta: 0.0,
        zeta_t: 0.0,
        cohesion: Adhesion { f0: F0, d0: D0 },
        friction: Coulomb { mu },
        rolling: RollingSpring { kr: KR, mu_r: MU_R },
    }
}

/// Runs `f` on a one-thread rayon pool.
fn single_thread<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(f)
}

/// Disks of diameters `diam` at physical positions `pos` (centred in a fixed cell).
fn build(law: Law, pos: &[V], diam: &[f64]) -> Sys {
    let c = pos.iter().fold(V::zeros(), |a, p| a + p) / pos.len() as f64;
    let s = pos
        .iter()
        .map(|p| (p - c) / SIDE + V::new(0.5, 0.5))
        .collect();
    let cell = Cell::new(V::new(SIDE, SIDE), 1.0);
    let sys = System::new(law, cell, s, diam, 0.1);
    sys.check_cell().unwrap();
    sys
}

/// Branch vector r_j − r_i (nearest image).
fn branch(sys: &Sys, i: usize, j: usize) -> V {
    let mut ds = sys.s[j] - sys.s[i];
    min_image::<D2>(&mut ds);
    ds.component_mul(&sys.cell.l)
}

/// Moment of inertia of a disk, I = m r²/2 (independent of the engine's `inv_inertia`).
fn inertia(sys: &Sys, i: usize) -> f64 {
    0.5 * sys.mass[i] * sys.radius[i] * sys.radius[i]
}

fn m_eff(sys: &Sys, i: usize, j: usize) -> f64 {
    sys.mass[i] * sys.mass[j] / (sys.mass[i] + sys.mass[j])
}

/// Potential energy of one interaction at gap h with stored T and Γ.
fn pair_potential(h: f64, t: V, g: f64) -> f64 {
    if h < 0.0 {
        0.5 * KN * h * h + F0 * h - 0.5 * F0 * D0
            + t.norm_squared() / (2.0 * KT)
            + g * g / (2.0 * KR)
    } else if h <= D0 {
        -F0 * (D0 - h) * (D0 - h) / (2.0 * D0)
    } else {
        0.0
    }
}

/// Energy of one contact at rest at the pair equilibrium h = −h0.
const E_EQ: f64 = -F0 * F0 / (2.0 * KN) - 0.5 * F0 * D0;

/// What one evaluation of the state gives.
struct Measure {
    energy: f64,
    kinetic: f64,
    /// Tangential force component T·t̂ (t̂ = ẑ × n) and rolling moment per contact.
    tau: Vec<f64>,
    gamma: Vec<f64>,
    /// Largest |T|/(μ N_e) and |Γ|/(μ_r N_e) over the contacts.
    slide: f64,
    roll: f64,
}

/// Energy and contact state. Asserts that exactly `contacts` pairs interact and that each is
/// in contact (h < 0: no contact opened, so no spring was reset).
fn measure(sys: &Sys, contacts: &[(usize, usize)], mu: f64) -> Measure {
    let mut kinetic = 0.0;
    for i in 0..sys.len() {
        kinetic += 0.5 * sys.mass[i] * sys.u[i].norm_squared();
        kinetic += 0.5 * inertia(sys, i) * sys.w[i] * sys.w[i];
    }
    let it = sys.interactions();
    assert_eq!(it.len(), contacts.len(), "interactions changed: {it:?}");
    let mut m = Measure {
        energy: kinetic,
        kinetic,
        tau: Vec::new(),
        gamma: Vec::new(),
        slide: 0.0,
        roll: 0.0,
    };
    for c in &it {
        assert!(
            contacts.contains(&(c.i, c.j)) || contacts.contains(&(c.j, c.i)),
            "unexpected pair {} {}",
            c.i,
            c.j
        );
        assert!(c.gap < 0.0, "contact {} {} opened: h = {}", c.i, c.j, c.gap);
        m.energy += pair_potential(c.gap, c.tangential, c.rolling);
        let n = c.branch / c.branch.norm();
        m.tau.push(n.x * c.tangential.y - n.y * c.tangential.x);
        m.gamma.push(c.rolling);
        m.slide = m.slide.max(c.tangential.norm() / (mu * c.normal_elastic));
        m.roll = m.roll.max(c.rolling.abs() / (MU_R * c.normal_elastic));
    }
    m
}

/// ω_max bound of the module doc with `chi` matchings.
fn omega_max(sys: &Sys, contacts: &[(usize, usize)], chi: f64) -> f64 {
    contacts
        .iter()
        .map(|&(i, j)| {
            let w2 = KN.max(3.0 * KT) / m_eff(sys, i, j)
                + KR * (1.0 / inertia(sys, i) + 1.0 / inertia(sys, j));
            (chi * w2).sqrt()
        })
        .fold(0.0, f64::max)
}

/// Removes the total momentum (so the group stays near the cell centre).
fn zero_momentum(sys: &mut Sys) {
    let mtot: f64 = sys.mass.iter().sum();
    let p = (0..sys.len()).fold(V::zeros(), |a, i| a + sys.u[i] * sys.mass[i]);
    for u in sys.u.iter_mut() {
        *u -= p / mtot;
    }
}

/// Result of [`conservation`].
struct Report {
    e_vib: f64,
    bound: f64,
    max_dev: f64,
    end_dev: f64,
    window_mean_shift: f64,
    fluct_dt: f64,
    fluct_half: f64,
    amp_tau: (f64, f64),
    amp_gamma: (f64, f64),
    kin: (f64, f64),
    slide: f64,
    roll: f64,
}

/// Window statistics: Σ τ², Σ Γ², Σ kinetic, count.
#[derive(Default)]
struct Window {
    tau2: f64,
    gamma2: f64,
    kin: f64,
    e: f64,
    n: f64,
}

impl Window {
    fn add(&mut self, m: &Measure) {
        self.tau2 += m.tau.iter().map(|x| x * x).sum::<f64>() / m.tau.len() as f64;
        self.gamma2 += m.gamma.iter().map(|x| x * x).sum::<f64>() / m.gamma.len() as f64;
        self.kin += m.kinetic;
        self.e += m.energy;
        self.n += 1.0;
    }
    fn rms_tau(&self) -> f64 {
        (self.tau2 / self.n).sqrt()
    }
    fn rms_gamma(&self) -> f64 {
        (self.gamma2 / self.n).sqrt()
    }
    fn mean_kin(&self) -> f64 {
        self.kin / self.n
    }
    fn mean_e(&self) -> f64 {
        self.e / self.n
    }
}

/// Largest minus smallest energy over `steps` steps of `sys` (from its initial state).
fn fluctuation(mut sys: Sys, dt: f64, steps: usize, contacts: &[(usize, usize)]) -> f64 {
    sys.dt = dt;
    sys.init_forces();
    let e0 = measure(&sys, contacts, MU).energy;
    let (mut lo, mut hi) = (e0, e0);
    for _ in 0..steps {
        sys.step();
        let e = measure(&sys, contacts, MU).energy;
        lo = lo.min(e);
        hi = hi.max(e);
    }
    hi - lo
}

/// The conservation checks shared by the three configurations: a long run at dt (energy
/// deviation from the start at every step, window means, amplitudes at start and end,
/// sliders), and the fluctuation over a window of `fluct_time` at dt and dt/2.
fn conservation(
    name: &str,
    sys: Sys,
    contacts: &[(usize, usize)],
    chi: f64,
    steps: usize,
    window: usize,
    fluct_time: f64,
) -> Report {
    let wmax = omega_max(&sys, contacts, chi);
    let dt = 2.0 * PI / (40.0 * wmax);
    let fresh = sys.clone();
    let mut sys = sys;
    sys.dt = dt;
    sys.init_forces();
    let m0 = measure(&sys, contacts, MU);
    let e0 = m0.energy;
    let e_vib = e0 - contacts.len() as f64 * E_EQ;
    assert!(e_vib > 0.0);
    let bound = 2.0 * (wmax * dt).powi(2) / 4.0 * e_vib;
    let (mut first, mut last) = (Window::default(), Window::default());
    let (mut max_dev, mut slide, mut roll) = (0.0f64, m0.slide, m0.roll);
    let mut end_dev = 0.0;
    let start = std::time::Instant::now();
    for n in 0..steps {
        sys.step();
        let m = measure(&sys, contacts, MU);
        let dev = m.energy - e0;
        max_dev = max_dev.max(dev.abs());
        slide = slide.max(m.slide);
        roll = roll.max(m.roll);
        if n < window {
            first.add(&m);
        }
        if n >= steps - window {
            last.add(&m);
        }
        end_dev = dev;
    }
    let secs = start.elapsed().as_secs_f64();
    // Same physical time at dt and dt/2.
    let nf = (fluct_time / dt).round() as usize;
    let fluct_dt = fluctuation(fresh.clone(), dt, nf, contacts);
    let fluct_half = fluctuation(fresh, 0.5 * dt, 2 * nf, contacts);
    let r = Report {
        e_vib,
        bound,
        max_dev,
        end_dev,
        window_mean_shift: last.mean_e() - first.mean_e(),
        fluct_dt,
        fluct_half,
        amp_tau: (first.rms_tau(), last.rms_tau()),
        amp_gamma: (first.rms_gamma(), last.rms_gamma()),
        kin: (first.mean_kin(), last.mean_kin()),
        slide,
        roll,
    };
    eprintln!(
        "{name}: ω_max ≤ {wmax:.1}, dt = {dt:.3e}, {steps} steps = {:.1} T0 in {secs:.1} s; \
         E_vib = {:.3e}; max |E − E0| = {:.3e} (bound {:.3e}), end {:.3e}, \
         window-mean shift {:.3e} ({:.1e} E_vib/T0); fluctuation dt {:.3e}, dt/2 {:.3e}, ratio {:.3}; \
         rms τ {:.4e} → {:.4e}, rms Γ {:.4e} → {:.4e}, ⟨KE⟩ {:.4e} → {:.4e}; \
         max |T|/μN_e {:.3}, |Γ|/μ_rN_e {:.2e}",
        steps as f64 * dt,
        r.e_vib,
        r.max_dev,
        r.bound,
        r.end_dev,
        r.window_mean_shift,
        r.window_mean_shift / r.e_vib / ((steps - window) as f64 * dt),
        r.fluct_dt,
        r.fluct_half,
        r.fluct_dt / r.fluct_half,
        r.amp_tau.0,
        r.amp_tau.1,
        r.amp_gamma.0,
        r.amp_gamma.1,
        r.kin.0,
        r.kin.1,
        r.slide,
        r.roll
    );
    r
}

/// The assertions on a [`Report`].
///
/// - Sliders: |T| < 0.9 μ N_e and |Γ| < 0.9 μ_r N_e at every step (never at the threshold,
///   so no plastic slip and the law is conservative).
/// - (a) No drift: |E_n − E_0| ≤ bound at every step, the last included. A drift per step δ
///   would have to satisfy steps·δ < bound; the window means (first and last `window` steps,
///   1e5 steps ≈ 10–15 T0, i.e. thousands of periods of the fast modes that carry the
///   fluctuation and ~50 of the slowest rolling mode) must also agree to 1e-3 bound: the
///   mean of the bounded fluctuation over such a window is steady to ~1/(ω W) ≲ 1e-4 of it,
///   and a drift would shift it.
/// - (b) Second order: halving dt divides the fluctuation by 4 (3.6–4.4; the higher-order
///   terms are (ω dt)² ≈ 2.5 % and the sampled maxima of a few modes at most a few % off).
/// - The fluctuation is itself within the bound and not vanishingly small compared to it
///   (≥ 1 %: the check measures something).
/// - Amplitudes: the rms of τ and Γ and the mean kinetic energy over the first and last
///   windows agree to 0.5 % (no damping appears: an amplitude damping rate γ would lower them
///   by e^{−γ t} over the ≈ 200–300 T0 between the windows, so γ < 2e-5/T0 is excluded; the
///   rms over ~50 periods of the slowest mode is steady to ≲ 1/(Δω W) ~ 3e-3, and measured
///   to 1e-3).
fn check(r: &Report) {
    let amp_tol = 5e-3;
    assert!(r.slide < 0.9, "Coulomb threshold approached: {}", r.slide);
    assert!(r.roll < 0.9, "rolling threshold approached: {}", r.roll);
    assert!(
        r.max_dev <= r.bound,
        "energy deviation {:.3e} above bound {:.3e}",
        r.max_dev,
        r.bound
    );
    assert!(r.end_dev.abs() <= r.bound);
    assert!(
        r.window_mean_shift.abs() <= 1e-3 * r.bound,
        "window mean moved by {:.3e} (bound {:.3e})",
        r.window_mean_shift,
        r.bound
    );
    assert!(r.fluct_dt <= r.bound && r.fluct_dt >= 0.01 * r.bound);
    let ratio = r.fluct_dt / r.fluct_half;
    assert!(
        (3.6..=4.4).contains(&ratio),
        "fluctuation ratio for dt/2 is {ratio}, not ≈ 4"
    );
    for (what, (a, b)) in [
        ("rms τ", r.amp_tau),
        ("rms Γ", r.amp_gamma),
        ("⟨KE⟩", r.kin),
    ] {
        assert!(a > 0.0);
        assert!(
            ((b - a) / a).abs() <= amp_tol,
            "{what} changed from {a:.4e} to {b:.4e}"
        );
    }
}

/// Places grain positions so that each listed pair is at gap −h0 (overlap F0/K_N).
fn contact_distance(d: &[f64], i: usize, j: usize) -> f64 {
    0.5 * (d[i] + d[j]) - H0
}

// ---------------------------------------------------------------------------------------------
// 1. One adhesive pair of unequal disks
// ---------------------------------------------------------------------------------------------

const PAIR_D: [f64; 2] = [1.0, 0.6];

fn pair_at(gap: f64) -> Sys {
    let l = 0.5 * (PAIR_D[0] + PAIR_D[1]) + gap;
    build(law(MU), &[V::new(0.0, 0.0), V::new(l, 0.0)], &PAIR_D)
}

/// Pair at h0 with a tangential relative velocity 1e-3 √(F0 a/m) (the pair orbits and the
/// contact slips) and a relative spin (2e-3/T0, plus a common spin), no normal velocity: the
/// tangential and rolling motions GRC07's dashpot does not damp. 2e6 steps (≈ 300 T0).
#[test]
fn adhesive_pair_conserves_energy() {
    let r = single_thread(|| {
        let mut sys = pair_at(-H0);
        let (m0, m1) = (sys.mass[0], sys.mass[1]);
        let vt = 1e-3;
        sys.u[0] = V::new(0.0, -vt * m1 / (m0 + m1));
        sys.u[1] = V::new(0.0, vt * m0 / (m0 + m1));
        sys.w[0] = -1e-3 + 3e-4;
        sys.w[1] = 1e-3 + 3e-4;
        conservation("pair", sys, &[(0, 1)], 1.0, 2_000_000, 100_000, 2.0)
    });
    check(&r);
}

/// Bent chain of three unequal disks (angle 110° at the middle one), both contacts at h0,
/// small pseudo-random velocities and spins of all kinds (zero total momentum).
#[test]
fn adhesive_bent_chain_conserves_energy() {
    let d = [0.8, 1.0, 0.6];
    let a = 110f64.to_radians();
    let p1 = V::new(0.0, 0.0);
    let p0 = p1 + V::new(-1.0, 0.0) * contact_distance(&d, 0, 1);
    let p2 = p1 + V::new(-a.cos(), a.sin()) * contact_distance(&d, 1, 2);
    let contacts = [(0, 1), (1, 2)];
    let r = single_thread(|| {
        let mut sys = build(law(MU), &[p0, p1, p2], &d);
        assert!(branch(&sys, 0, 2).norm() > 0.5 * (d[0] + d[2]) + 2.0 * D0);
        kick(&mut sys);
        conservation("chain", sys, &contacts, 2.0, 2_000_000, 100_000, 2.0)
    });
    check(&r);
}

/// Closed loop of four unequal disks (a rolling four-bar linkage), four contacts at h0.
#[test]
fn adhesive_four_loop_conserves_energy() {
    let d = [1.0, 0.7, 0.9, 0.6];
    let (l01, l12, l23, l30) = (
        contact_distance(&d, 0, 1),
        contact_distance(&d, 1, 2),
        contact_distance(&d, 2, 3),
        contact_distance(&d, 3, 0),
    );
    let a = 95f64.to_radians();
    let p0 = V::new(0.0, 0.0);
    let p1 = V::new(l01, 0.0);
    let p3 = V::new(a.cos(), a.sin()) * l30;
    // p2: intersection of the circles (p1, l12) and (p3, l23) away from p0.
    let b = p3 - p1;
    let dist = b.norm();
    let x = (l12 * l12 - l23 * l23 + dist * dist) / (2.0 * dist);
    let y = (l12 * l12 - x * x).sqrt();
    let e = b / dist;
    let perp = V::new(-e.y, e.x);
    let c1 = p1 + e * x + perp * y;
    let c2 = p1 + e * x - perp * y;
    let p2 = if c1.norm() > c2.norm() { c1 } else { c2 };
    let contacts = [(0, 1), (0, 3), (1, 2), (2, 3)];
    let r = single_thread(|| {
        let mut sys = build(law(MU), &[p0, p1, p2, p3], &d);
        for (i, j) in contacts {
            let h = branch(&sys, i, j).norm() - 0.5 * (d[i] + d[j]);
            assert!((h + H0).abs() < 1e-12, "{i}-{j}: {h}");
        }
        assert!(branch(&sys, 0, 2).norm() > 0.5 * (d[0] + d[2]) + 0.05);
        assert!(branch(&sys, 1, 3).norm() > 0.5 * (d[1] + d[3]) + 0.05);
        kick(&mut sys);
        conservation("loop", sys, &contacts, 2.0, 2_000_000, 100_000, 2.0)
    });
    check(&r);
}

/// Small deterministic velocities (5e-4 √(F0 a/m)) and spins (1e-3/T0), zero total momentum:
/// |T| then stays below ½ μ N_e (twice these reach 0.92 μ N_e in the chain).
fn kick(sys: &mut Sys) {
    for k in 0..sys.len() {
        let x = k as f64;
        sys.u[k] = V::new((1.3 * x + 0.2).sin(), (2.1 * x + 0.5).cos()) * 5e-4;
        sys.w[k] = 1e-3 * (0.7 * x + 1.0).sin();
    }
    zero_momentum(sys);
}

// ---------------------------------------------------------------------------------------------
// 2. Rigid rotation
// ---------------------------------------------------------------------------------------------

/// A pair in rigid rotation: both disks spin at the pair's angular velocity Ω about its centre
/// of mass, at the overlap where −K_N h − F0 supplies the centripetal force m* Ω² |r|
/// (h = (m* Ω² (r_i + r_j) − F0)/(K_N − m* Ω²)). An objective law sees no relative motion
/// but for one term: the law's contact points are at r_i and r_j from the centres, h apart
/// along n, so the slip velocity is Ω h, not 0 (a fraction |h|/(r_i + r_j) ≈ 1e-5 of what a
/// law ignoring the spins would see). The disks respond to that slip rate s = Ω|h| as to an
/// initial velocity mismatch:
///
/// - the tangential mode (ω_t = √(3 K_T/m*), effective mass m_t = m*/3) cancels it with an
///   oscillation of amplitude |T| = K_T s/ω_t = s √(K_T m_t); we allow 2×;
/// - the impulse m_t s it takes spins the disks by −r_k m_t s/I_k, a relative spin
///   ψ̇ = |r_j/I_j − r_i/I_i| m_t s, which loads the rolling spring through the slow rolling
///   mode of the pair (rolling without slip at constant angular momentum; its inertia J_eff is
///   computed below, ω_r = √(K_r/J_eff) ≈ 23/T0): |Γ| ≈ K_r ψ̇/ω_r; we allow 3×.
///
/// Measured: |T| and |Γ| reach 0.5 and 0.35 of these allowances. For comparison, a law that
/// ignored the spins in the slip would have |T| ≈ 1e5 × larger (and slide at once); one that
/// rolled with the absolute spins would have |Γ| = K_r Ω t = K_r θ = 10 F0 a at θ = 1 rad.
/// The branch must turn by Ω t up to the O(|h|/d) exchange of angular momentum between the
/// spins (which settle at Ω (1 − |h|/d)) and the orbit: |φ − Ω t| ≤ 3 (|h|/d) Ω t.
#[test]
fn rigid_rotation_keeps_history_zero() {
    single_thread(|| {
        let omega = 0.05;
        let probe = pair_at(-H0);
        let me = m_eff(&probe, 0, 1);
        let rsum = 0.5 * (PAIR_D[0] + PAIR_D[1]);
        let h = (me * omega * omega * rsum - F0) / (KN - me * omega * omega);
        let mut sys = pair_at(h);
        let (m0, m1) = (sys.mass[0], sys.mass[1]);
        let r = branch(&sys, 0, 1);
        // Centre of mass: r_0 = −m1/(m0+m1) r, r_1 = m0/(m0+m1) r; u = Ω ẑ × (r_k − r_c).
        let zc = |v: V| V::new(-omega * v.y, omega * v.x);
        sys.u[0] = zc(-r * (m1 / (m0 + m1)));
        sys.u[1] = zc(r * (m0 / (m0 + m1)));
        sys.w[0] = omega;
        sys.w[1] = omega;
        let wt = (3.0 * KT / me).sqrt();
        let dt = 2.0 * PI / (40.0 * wt);
        sys.dt = dt;
        sys.init_forces();
        let t_bound = 2.0 * omega * h.abs() * (KT * me / 3.0).sqrt();
        let (r0, r1) = (sys.radius[0], sys.radius[1]);
        let arm = (r1 / inertia(&sys, 1) - r0 / inertia(&sys, 0)).abs();
        // Rolling mode: ψ = θ_1 − θ_0 with no slip (d φ̇ = r_0 θ̇_0 + r_1 θ̇_1) and no change of
        // angular momentum (m* d² φ̇ + I_0 θ̇_0 + I_1 θ̇_1 = 0): with A = m* d r_0 + I_0,
        // B = m* d r_1 + I_1, θ̇_0 = −B ψ̇/(A+B), θ̇_1 = A ψ̇/(A+B), and the kinetic energy is
        // J_eff ψ̇²/2 with J_eff = (m* (r_0 B − r_1 A)² + I_0 B² + I_1 A²)/(A+B)².
        let (i0, i1) = (inertia(&sys, 0), inertia(&sys, 1));
        let d = r0 + r1;
        let (a, b) = (me * d * r0 + i0, me * d * r1 + i1);
        let j_eff = (me * (r0 * b - r1 * a).powi(2) + i0 * b * b + i1 * a * a) / (a + b).powi(2);
        let wr = (KR / j_eff).sqrt();
        let psi_dot = arm * (me / 3.0) * omega * h.abs();
        let g_bound = 3.0 * KR * psi_dot / wr;
        let steps = (1.0 / omega / dt).round() as usize;
        let (mut t_max, mut g_max) = (0.0f64, 0.0f64);
        for _ in 0..steps {
            sys.step();
            let c = sys.interactions();
            assert_eq!(c.len(), 1);
            assert!(c[0].gap < 0.0);
            t_max = t_max.max(c[0].tangential.norm());
            g_max = g_max.max(c[0].rolling.abs());
        }
        let b = branch(&sys, 0, 1);
        let turned = b.y.atan2(b.x);
        let expected = omega * sys.time;
        eprintln!(
            "rigid rotation: θ = {expected:.4} rad, turned {turned:.6}, max |T| = {t_max:.3e} \
             (bound {t_bound:.3e}), max |Γ| = {g_max:.3e} (bound {g_bound:.3e}), spins {:.6} {:.6}",
            sys.w[0], sys.w[1]
        );
        assert!(
            t_max <= t_bound,
            "tangential spring loaded by a rigid rotation"
        );
        assert!(
            g_max <= g_bound,
            "rolling spring loaded by a rigid rotation"
        );
        assert!((turned - expected).abs() <= 3.0 * h.abs() / (r0 + r1) * expected);
        for w in &sys.w {
            assert!((w - omega).abs() < 1e-3 * omega);
        }
    });
}

/// The stored springs ride with the contact. Both disks are held (infinite masses) at overlap
/// h0; a tangential spring τ0 and a rolling spring Γ0 are built by spinning them, then the
/// pair is turned rigidly by π/2 about its midpoint in n steps of Ω dt (centre velocities along
/// the chords, so the positions stay on the circle to rounding; both spins sin(Ω dt)/dt, the
/// rate that is rigid at the discrete level). The stored T must turn with the normal:
/// T·n = 0 (to rounding) and T·t̂ = τ0 + K_T |h| n sin(Ω dt) exactly — the second term is
/// the slip h sin(Ω dt)/dt of the law's contact points (see
/// `rigid_rotation_keeps_history_zero`) summed step by step, ≈ K_T |h| θ; Γ is unchanged
/// (2D: no transport for a scalar). μ is large here so that term, F0 θ, does not slide.
/// A spring left in the fixed frame would have T·n = τ0 sin θ = |τ0| at the end.
#[test]
fn rigid_rotation_transports_stored_springs() {
    single_thread(|| {
        let mut sys = pair_at(-H0);
        sys.law = law(10.0);
        for i in 0..2 {
            sys.inv_mass[i] = 0.0;
            sys.inv_inertia[i] = 0.0;
        }
        let dt = 1e-4;
        sys.dt = dt;
        sys.init_forces();
        // Build the springs: 100 steps with ω_0 = 1e-4, ω_1 = 8.3e-4: a slip
        // −(r_0 ω_0 + r_1 ω_1) 100 dt t̂ = −3e-6 t̂ (T·t̂ = 0.3 F0) and a relative rotation
        // 7.3e-6 (Γ = −7.3e-5 F0 a).
        sys.w[0] = 1e-4;
        sys.w[1] = 8.3e-4;
        for _ in 0..100 {
            sys.step();
        }
        let c = sys.interactions()[0];
        let n = c.branch / c.branch.norm();
        let tau0 = n.x * c.tangential.y - n.y * c.tangential.x;
        let g0 = c.rolling;
        let h = c.gap;
        assert!(tau0.abs() > 0.1 * F0 && g0.abs() > 1e-5, "{tau0} {g0}");
        // Rigid rotation by π/2 in 2000 steps.
        let steps = 2000;
        let omega = 0.5 * PI / (steps as f64 * dt);
        let centre = 0.5 * (sys.position(0) + sys.position(1));
        let start = [sys.position(0) - centre, sys.position(1) - centre];
        let rot = |v: V, th: f64| {
            V::new(
                th.cos() * v.x - th.sin() * v.y,
                th.sin() * v.x + th.cos() * v.y,
            )
        };
        // Spins sin(Ω dt)/dt: the chord displacement of the branch per step is |r| sin(Ω dt)
        // along the new tangent, so these spins make the discrete motion exactly rigid
        // (a spin of Ω would leave a slip |r| Ω (Ω dt)²/6 per unit time, 1e-2 F0 over π/2).
        let w = (omega * dt).sin() / dt;
        sys.w[0] = w;
        sys.w[1] = w;
        for k in 0..steps {
            let (a, b) = (omega * dt * k as f64, omega * dt * (k + 1) as f64);
            for (u, r) in sys.u.iter_mut().zip(start) {
                *u = (rot(r, b) - rot(r, a)) / dt;
            }
            sys.step();
        }
        let c = sys.interactions()[0];
        let n = c.branch / c.branch.norm();
        let tn = c.tangential.dot(&n);
        let tau = n.x * c.tangential.y - n.y * c.tangential.x;
        let expected = tau0 + KT * h.abs() * w * dt * steps as f64;
        eprintln!(
            "transport: n = ({:.3e}, {:.6}), τ0 = {tau0:.6}, τ = {tau:.6} (expected {expected:.6}), \
             T·n = {tn:.2e}, Γ0 = {g0:.6e}, Γ = {:.6e}, h = {:.4e}",
            n.x, n.y, c.rolling, c.gap
        );
        assert!(
            n.x.abs() < 1e-9 && (n.y - 1.0).abs() < 1e-12,
            "pair did not turn by π/2"
        );
        assert!(tn.abs() < 1e-12, "T left the tangent plane: T·n = {tn}");
        assert!((tau - expected).abs() < 1e-6 * F0, "{tau} vs {expected}");
        assert!((c.rolling - g0).abs() < 1e-12 * g0.abs());
    });
}
