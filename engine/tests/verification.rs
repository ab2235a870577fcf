//! Verification of the contact laws and of the integrator against exact solutions
//! (AR07 §II.A and App. A; GRC07 §II.B).
//!
//! Every test runs the real engine (`System::step`) on two to a few hundred grains in a large,
//! fixed periodic cell and compares with a closed-form or independently integrated reference.
//! Conventions: reduced positions s ∈ [0,1)^d, r = L·s; masses (d/a)^D with a = 1; N > 0 is
//! repulsive; the stored tangential force and rolling moment are those exerted by i on j.
//!
//! "Kinematic driving": setting `inv_mass` / `inv_inertia` of a grain to zero makes it
//! infinitely heavy, so `step` leaves its velocity and angular velocity exactly as set. This
//! is used to impose a relative motion on a contact and read the law's response.

use grainbench_engine::cell::Cell;
use grainbench_engine::contact::hertz_mindlin::HertzMindlin;
use grainbench_engine::contact::linear::{Adhesion, Linear, NoCohesion};
use grainbench_engine::contact::slider::{Coulomb, Frictionless, NoRolling, NoSlip, RollingSpring};
use grainbench_engine::contact::ContactLaw;
use grainbench_engine::geometry::{Dim, VectorOps as _, D2, D3};
use grainbench_engine::init::{maxwell_velocities, random_gas};
use grainbench_engine::neighbor::min_image;
use grainbench_engine::system::System;
use nalgebra::{Vector2, Vector3};

/// Side of the cell used for the two-grain tests: a power of two, so 0.5 ± 1/(2L) and the
/// products L·s are exact and two unit grains can be placed at exactly zero gap.
const SIDE: f64 = 16.0;

/// t_c v / h_max for N = k h^{3/2}: 2 ∫₀¹ dx/√(1 − x^{5/2}) = 2√π Γ(7/5)/Γ(9/10).
/// (Equivalently t_c = 3.218065 (m*/k)^{2/5} v^{-1/5}.) Checked against RK4 below.
const HERTZ_DURATION: f64 = 2.943_275_184_324_706;

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// Two unit spheres (d = 1, m = 1) on the x axis at surface gap `gap`, centred in the cell.
fn two_spheres<L: ContactLaw<D3>>(law: L, gap: f64) -> System<D3, L> {
    let half = 0.5 * (1.0 + gap) / SIDE;
    let s = vec![
        Vector3::new(0.5 - half, 0.5, 0.5),
        Vector3::new(0.5 + half, 0.5, 0.5),
    ];
    let cell = Cell::new(Vector3::new(SIDE, SIDE, SIDE), 1.0);
    let sys = System::new(law, cell, s, &[1.0, 1.0], 0.1);
    sys.check_cell().unwrap();
    sys
}

/// Two unit disks (d = 1, m = 1) on the x axis at surface gap `gap`, centred in the cell.
fn two_disks<L: ContactLaw<D2>>(law: L, gap: f64) -> System<D2, L> {
    let half = 0.5 * (1.0 + gap) / SIDE;
    let s = vec![Vector2::new(0.5 - half, 0.5), Vector2::new(0.5 + half, 0.5)];
    let cell = Cell::new(Vector2::new(SIDE, SIDE), 1.0);
    let sys = System::new(law, cell, s, &[1.0, 1.0], 0.1);
    sys.check_cell().unwrap();
    sys
}

/// Branch vector r_j − r_i (nearest image).
fn branch<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>, i: usize, j: usize) -> D::V {
    let mut ds = sys.s[j] - sys.s[i];
    min_image::<D>(&mut ds);
    D::mul(ds, sys.cell.l)
}

/// Surface gap of grains i, j (negative: overlap).
fn gap<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>, i: usize, j: usize) -> f64 {
    branch(sys, i, j).norm() - sys.radius[i] - sys.radius[j]
}

/// Normal relative velocity (u_j − u_i)·n, positive when receding.
fn receding<D: Dim, L: ContactLaw<D>>(sys: &System<D, L>, i: usize, j: usize) -> f64 {
    let r = branch(sys, i, j);
    (sys.u[j] - sys.u[i]).dot(&r) / r.norm()
}

/// Makes grain i kinematically driven: `step` never changes its velocities.
fn freeze<D: Dim, L: ContactLaw<D>>(sys: &mut System<D, L>, i: usize) {
    sys.inv_mass[i] = 0.0;
    if L::MOMENTS {
        sys.inv_inertia[i] = 0.0;
    }
}

/// Times at which a head-on binary collision starts and ends (gap crossings, linearly
/// interpolated between steps), peak normal force on grain 1, peak overlap, and the
/// normal relative velocity once the grains have separated again.
struct Collision {
    t_in: f64,
    t_out: f64,
    peak_force: f64,
    peak_overlap: f64,
    v_after: f64,
}

fn collide<D: Dim, L: ContactLaw<D>>(sys: &mut System<D, L>, max_steps: usize) -> Collision {
    sys.init_forces();
    let dt = sys.dt;
    let mut prev = gap(sys, 0, 1);
    assert!(prev > 0.0, "start out of contact");
    let (mut t_in, mut t_out) = (None, None);
    let (mut peak_force, mut peak_overlap) = (0.0f64, 0.0f64);
    for _ in 0..max_steps {
        let t0 = sys.time;
        sys.step();
        let g = gap(sys, 0, 1);
        if t_in.is_none() && prev >= 0.0 && g < 0.0 {
            t_in = Some(t0 + dt * prev / (prev - g));
        }
        if t_in.is_some() && prev < 0.0 && g >= 0.0 {
            t_out = Some(t0 + dt * prev / (prev - g));
        }
        peak_force = peak_force.max(sys.force[1].norm());
        peak_overlap = peak_overlap.max(-g);
        prev = g;
        if let Some(t) = t_out {
            if sys.time > t + 5.0 * dt {
                break;
            }
        }
    }
    let (t_in, t_out) = (
        t_in.expect("no contact"),
        t_out.expect("contact never ended"),
    );
    Collision {
        t_in,
        t_out,
        peak_force,
        peak_overlap,
        v_after: receding(sys, 0, 1),
    }
}

/// RK4 solution of m* ḧ = −k h^{3/2} from h = 0, ḣ = v: (duration, peak overlap).
fn hertz_rk4(k_over_m: f64, v: f64, dt: f64) -> (f64, f64) {
    let acc = |h: f64| -k_over_m * h.max(0.0).powf(1.5);
    let (mut h, mut w, mut t, mut hmax) = (0.0f64, v, 0.0, 0.0f64);
    loop {
        let (k1h, k1w) = (w, acc(h));
        let (k2h, k2w) = (w + 0.5 * dt * k1w, acc(h + 0.5 * dt * k1h));
        let (k3h, k3w) = (w + 0.5 * dt * k2w, acc(h + 0.5 * dt * k2h));
        let (k4h, k4w) = (w + dt * k3w, acc(h + dt * k3h));
        let hn = h + dt / 6.0 * (k1h + 2.0 * k2h + 2.0 * k3h + k4h);
        let wn = w + dt / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
        if hn < 0.0 {
            return (t + dt * h / (h - hn), hmax);
        }
        // Peak: quadratic through the velocity zero crossing.
        if w > 0.0 && wn <= 0.0 {
            let tau = dt * w / (w - wn);
            hmax = hmax.max(h + w * tau + 0.5 * (wn - w) / dt * tau * tau);
        }
        hmax = hmax.max(hn);
        h = hn;
        w = wn;
        t += dt;
    }
}

// ---------------------------------------------------------------------------------------------
// 1. Hertz binary collision
// ---------------------------------------------------------------------------------------------

/// Frictionless, undamped Hertz collision of two unit spheres, head on. With m* = 1/2,
/// R* = 1/4 and N = k h^{3/2}, k = (2/3)Ẽ√R* (AR07 (1)):
/// h_max = (5 m* v²/(4k))^{2/5}, N_max = k h_max^{3/2}, t_c = 2.943275 h_max/v, e = 1.
#[test]
fn hertz_collision_matches_hertz_solution() {
    let e_tilde = 1e5;
    let law = HertzMindlin::new(e_tilde, 0.3, 0.0, Frictionless);
    let (m_eff, r_eff): (f64, f64) = (0.5, 0.25);
    let k = 2.0 / 3.0 * e_tilde * r_eff.sqrt();
    assert!(rel(law.normal_force(1e-3, r_eff), k * 1e-3f64.powf(1.5)) < 1e-14);
    let v = 0.1;
    let h_max = (5.0 * m_eff * v * v / (4.0 * k)).powf(0.4);
    let n_max = k * h_max.powf(1.5);
    let t_c = HERTZ_DURATION * h_max / v;
    assert!(rel(t_c, 3.218_065 * (m_eff / k).powf(0.4) * v.powf(-0.2)) < 1e-6);

    // Independent reference: fine RK4 on the 1-D ODE.
    let (t_rk, h_rk) = hertz_rk4(k / m_eff, v, t_c / 20_000.0);
    assert!(rel(t_rk, t_c) < 1e-6, "RK4 duration {t_rk} vs {t_c}");
    assert!(
        rel(h_rk, h_max) < 1e-6,
        "RK4 peak overlap {h_rk} vs {h_max}"
    );

    let mut sys = two_spheres(law, 0.02 * h_max);
    sys.u[0] = Vector3::new(0.5 * v, 0.0, 0.0);
    sys.u[1] = Vector3::new(-0.5 * v, 0.0, 0.0);
    sys.dt = t_c / 2000.0;
    let c = collide(&mut sys, 10_000);
    let duration = c.t_out - c.t_in;
    let e = c.v_after / v;
    eprintln!(
        "hertz: duration err {:.2e}, peak force err {:.2e}, peak overlap err {:.2e}, 1-e {:.2e}",
        rel(duration, t_rk),
        rel(c.peak_force, n_max),
        rel(c.peak_overlap, h_max),
        1.0 - e
    );
    assert!(rel(duration, t_rk) < 1e-3, "duration {duration} vs {t_rk}");
    assert!(
        rel(c.peak_force, n_max) < 1e-3,
        "peak N {} vs {n_max}",
        c.peak_force
    );
    assert!(rel(c.peak_overlap, h_max) < 1e-3);
    assert!((e - 1.0).abs() < 1e-4, "restitution {e}");
}

// ---------------------------------------------------------------------------------------------
// 2. Linear damped collision
// ---------------------------------------------------------------------------------------------

/// Linear spring–dashpot, η = 2ζ√(K_N m*) (GRC07 (6)): in contact m* ḧ = −K_N h − η ḣ, the
/// damped oscillator, which leaves contact (h = 0) after π/ω_d with e = exp(−πζ/√(1−ζ²)).
/// The law does not clip the attractive dashpot force near the end of contact, so that
/// formula is exact for the continuous problem.
#[test]
fn linear_damped_restitution() {
    let kn = 1e5;
    let v = 0.1;
    let m_eff = 0.5;
    for zeta in [0.1, 0.3, 0.5, 0.8] {
        let law = Linear {
            kn,
            kt: kn,
            zeta,
            zeta_t: 0.0,
            cohesion: NoCohesion,
            friction: Frictionless,
            rolling: NoRolling,
        };
        let wd = (kn / m_eff).sqrt() * (1.0 - zeta * zeta).sqrt();
        let t_c = std::f64::consts::PI / wd;
        let mut sys = two_disks(law, 1e-3 * v * t_c);
        sys.u[0] = Vector2::new(0.5 * v, 0.0);
        sys.u[1] = Vector2::new(-0.5 * v, 0.0);
        // The dashpot sees the half-step velocity, a first-order error in the dissipation:
        // measured rel. error ≈ 27 dt/t_c at ζ = 0.8 (9.5e-3, 1.4e-3, 1.4e-4 for t_c/dt =
        // 2e3, 2e4, 2e5), ≲ 1 dt/t_c for ζ ≤ 0.5. t_c/dt = 1e5 keeps it well inside 1e-3.
        sys.dt = t_c / 100_000.0;
        let c = collide(&mut sys, 200_000);
        let e = c.v_after / v;
        let expected = (-std::f64::consts::PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
        eprintln!(
            "linear ζ={zeta}: e = {e:.6e} vs {expected:.6e} (rel err {:.2e}), duration err {:.2e}",
            rel(e, expected),
            rel(c.t_out - c.t_in, t_c)
        );
        assert!(rel(e, expected) < 1e-3, "ζ={zeta}: e = {e} vs {expected}");
        assert!(rel(c.t_out - c.t_in, t_c) < 1e-3);
    }
}

// ---------------------------------------------------------------------------------------------
// 3. Adhesive disks
// ---------------------------------------------------------------------------------------------

fn adhesive(zeta: f64) -> Linear<Adhesion, Frictionless, NoRolling> {
    Linear {
        kn: 1e5,
        kt: 1e5,
        zeta,
        zeta_t: 0.0,
        cohesion: Adhesion { f0: 1.0, d0: 1e-3 },
        friction: Frictionless,
        rolling: NoRolling,
    }
}

/// GRC07 (4)–(5): two disks released at rest at zero gap are pulled into contact by −F0 and
/// settle, by the viscous force, at the overlap h0 = F0/K_N where N = K_N h − F0 = 0.
///
/// Tolerances: the motion is an oscillator with ω0 = √(K_N/m*) = 447 and decay rate
/// ζω0 = 358; after t = 0.2 the initial amplitude (h0) is down by e^{−72}, i.e. gone. What is
/// left is floating-point round-off, and the dominant part is not the resolution of the gap
/// (reduced s ≈ 0.47 has ulp 2^{−54}, ×L = 16 gives ~1e-15 on h, 1e-10 relative to h0) but
/// the velocity below which a drift v·dt/L is smaller than half an ulp of s and is lost:
/// |u_j − u_i| ≲ ulp·L/dt. The pair then stalls at a false rest where the dashpot η·v balances
/// K_N (h − h0), i.e. |h − h0| ≲ η ulp L/(dt K_N) = 3.2e-14 for dt = 1e-4 (3.2e-9 relative;
/// a measured 2.4e-8 at dt = 1e-5 matched this bound). Any code with finite-precision
/// positions has that floor. We allow twice the bound.
#[test]
fn adhesive_pair_settles_at_equilibrium_overlap() {
    let law = adhesive(0.8);
    let h0 = law.cohesion.f0 / law.kn;
    let mut sys = two_disks(law, 0.0);
    assert_eq!(gap(&sys, 0, 1), 0.0);
    sys.dt = 1e-4;
    sys.init_forces();
    // At zero gap the attraction is exactly −F0 (continuous with the in-contact −F0).
    assert!((sys.force[1].x + 1.0).abs() < 1e-12 && (sys.force[0].x - 1.0).abs() < 1e-12);
    for _ in 0..2_000 {
        sys.step();
    }
    let eta = 2.0 * law.zeta * (law.kn * 0.5).sqrt();
    let ulp = f64::EPSILON / 4.0; // spacing of doubles in [0.25, 0.5)
    let bound = eta * ulp * SIDE / sys.dt / law.kn;
    let h = -gap(&sys, 0, 1);
    let it = sys.interactions();
    assert_eq!(it.len(), 1);
    let net = sys.force[0].norm().max(sys.force[1].norm());
    eprintln!(
        "adhesive rest: |h − h0| = {:.2e} (bound {bound:.2e}), N = {:.2e}, net force {net:.2e}",
        (h - h0).abs(),
        it[0].normal,
    );
    assert!(
        (h - h0).abs() <= 2.0 * bound,
        "overlap {h} vs F0/K_N = {h0}"
    );
    assert!((it[0].normal_elastic - law.cohesion.f0).abs() <= 2.0 * law.kn * bound);
    // N (including the dashpot) and the net forces vanish up to K_N × bound = 3e-9 F0.
    assert!(it[0].normal.abs() <= 2.0 * law.kn * bound);
    assert!(net <= 2.0 * law.kn * bound);
    assert!(sys.u[0].norm() <= ulp * SIDE / sys.dt && sys.u[1].norm() <= ulp * SIDE / sys.dt);
}

/// Separation threshold V*√2 (GRC07 (7)). Start at zero gap, receding at v: out of
/// contact the law is purely conservative (no viscosity, GRC07 (4)), so ζ plays no part and
/// energy decides: (1/2) m* v² against the work ∫₀^{D0} F0(1 − h/D0) dh = F0 D0/2, with
/// m* = 1/2 for two unit masses, gives v* = √(2 F0 D0) = V*√2, V* = √(F0 D0/m), exactly.
/// (Starting at the equilibrium overlap h0 would add the elastic energy F0²/(2K_N) and the
/// viscous loss on the way out to the balance; the zero-gap start is where V*√2 is exact.)
/// Above: the grains leave with (u_j − u_i)·n = √(v² − 2F0D0). Below: the gap peaks at
/// D0 (1 − √(1 − (v/v*)²)) and the grains come back into contact.
#[test]
fn adhesive_pair_separation_threshold() {
    let law = adhesive(0.8);
    let (f0, d0) = (law.cohesion.f0, law.cohesion.d0);
    let v_star = (f0 * d0 / 1.0).sqrt();
    let v_thr = v_star * 2f64.sqrt();
    for factor in [1.02, 0.98] {
        let v = factor * v_thr;
        let mut sys = two_disks(law, 0.0);
        sys.u[0] = Vector2::new(-0.5 * v, 0.0);
        sys.u[1] = Vector2::new(0.5 * v, 0.0);
        sys.dt = 1e-5;
        sys.init_forces();
        let mut max_gap = 0.0f64;
        let mut back_in_contact = false;
        for _ in 0..30_000 {
            sys.step();
            let g = gap(&sys, 0, 1);
            max_gap = max_gap.max(g);
            if g < 0.0 {
                back_in_contact = true;
                break;
            }
        }
        if factor > 1.0 {
            let v_final = receding(&sys, 0, 1);
            let expected = (v * v - 2.0 * f0 * d0).sqrt();
            eprintln!(
                "separation ×{factor}: final gap {:.3e}, v_final err {:.2e}",
                gap(&sys, 0, 1),
                rel(v_final, expected)
            );
            assert!(!back_in_contact);
            assert!(gap(&sys, 0, 1) > 2.0 * d0, "the pair separated");
            assert!(rel(v_final, expected) < 1e-3, "{v_final} vs {expected}");
            assert!(sys.force[0].norm() == 0.0 && sys.force[1].norm() == 0.0);
        } else {
            let expected = d0 * (1.0 - (1.0 - factor * factor).sqrt());
            eprintln!(
                "separation ×{factor}: max gap err {:.2e}",
                rel(max_gap, expected)
            );
            assert!(back_in_contact, "the pair must not separate below V*√2");
            assert!(rel(max_gap, expected) < 1e-3, "{max_gap} vs {expected}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 4. Coulomb slider and Walton rescaling
// ---------------------------------------------------------------------------------------------

/// Statistics of an oblique impact of two unit spheres (linear law, μ = 0.3, ζ = 0.5) with
/// normal approach speed 0.1 and tangential relative speed `ratio`·0.1.
struct Oblique {
    /// max |T|/(μ N_e) over all contact steps.
    max_ratio: f64,
    /// max |T|/(μ N_e) over the bulk of the contact (N_e ≥ 10 % of its peak).
    max_ratio_bulk: f64,
    /// Contact steps with |T| = μ N_e (to 1e-12), and all contact steps.
    sliding_steps: usize,
    contact_steps: usize,
    /// Did T always oppose the tangential relative velocity while sliding?
    opposes_slip: bool,
    /// |ΔL|/|L| for the total angular momentum (orbital + spin) over the collision.
    spin_balance: f64,
}

fn oblique_impact(ratio: f64) -> Oblique {
    let mu = 0.3;
    let law = Linear {
        kn: 1e5,
        kt: 1e5,
        zeta: 0.5,
        zeta_t: 0.0,
        cohesion: NoCohesion,
        friction: Coulomb { mu },
        rolling: NoRolling,
    };
    let vn = 0.1;
    let vt = ratio * vn;
    let mut sys = two_spheres(law, 1e-5);
    sys.u[0] = Vector3::new(0.5 * vn, -0.5 * vt, 0.0);
    sys.u[1] = Vector3::new(-0.5 * vn, 0.5 * vt, 0.0);
    sys.dt = 1e-6;
    sys.init_forces();
    let momentum = |sys: &System<D3, _>| -> Vector3<f64> {
        (0..2)
            .map(|i| sys.position(i).cross(&sys.u[i]) * sys.mass[i] + sys.w[i] / sys.inv_inertia[i])
            .sum()
    };
    let l0 = momentum(&sys);
    let mut out = Oblique {
        max_ratio: 0.0,
        max_ratio_bulk: 0.0,
        sliding_steps: 0,
        contact_steps: 0,
        opposes_slip: true,
        spin_balance: 0.0,
    };
    let mut history = Vec::new();
    let mut started = false;
    for _ in 0..20_000 {
        sys.step();
        let it = sys.interactions();
        if it.is_empty() || it[0].gap >= 0.0 {
            if started {
                break;
            }
            continue;
        }
        started = true;
        out.contact_steps += 1;
        let c = &it[0];
        let t = c.tangential.norm();
        assert!(c.tangential.dot(&c.branch).abs() <= 1e-12 * t, "T ⟂ n");
        let ne = c.normal_elastic;
        let r = t / (mu * ne);
        out.max_ratio = out.max_ratio.max(r);
        history.push((ne, r));
        if (r - 1.0).abs() < 1e-12 {
            out.sliding_steps += 1;
            // Relative tangential velocity of j's contact point with respect to i's.
            let n = c.branch / c.branch.norm();
            let mut v = sys.u[1] - sys.u[0] - (sys.w[0] * 0.5 + sys.w[1] * 0.5).cross(&n);
            v -= n * v.dot(&n);
            if c.tangential.dot(&v) >= 0.0 {
                out.opposes_slip = false;
            }
        }
    }
    assert!(started && out.contact_steps > 100);
    out.spin_balance = (momentum(&sys) - l0).norm() / l0.norm();
    let peak = history.iter().map(|h| h.0).fold(0.0, f64::max);
    out.max_ratio_bulk = history
        .iter()
        .filter(|h| h.0 >= 0.1 * peak)
        .map(|h| h.1)
        .fold(0.0, f64::max);
    out
}

/// GRC07 (8) / AR07 (3): |T| ≤ μ N_e at every step; a grazing impact (tangential speed ten
/// times the normal one) slides through the whole contact with |T| = μ N_e, T opposing the
/// slip; a nearly head-on one (ratio 0.01) stays strictly inside the cone over the
/// bulk of the contact. It does slide at the first step (partial-step overlap, T/N_e ≈
/// (K_T/K_N)(v_t/v_n)·dt/δt) and over the last ~1 % of the contact, where N_e → 0 while the
/// reversed tangential spring is still loaded: that is the physics, not a defect.
/// Total angular momentum (orbital + spin) is conserved up to the lever-arm convention (the
/// moments use R_i, R_j while |r_ij| = R_i + R_j − h: an imbalance ~ h·T, measured 3e-6 and
/// 2e-5 relative); a wrong sign or arm in the moments would break it at the 1e-2–1 level.
#[test]
fn coulomb_oblique_impact() {
    let slide = oblique_impact(10.0);
    eprintln!(
        "oblique ratio 10: max |T|/μN_e − 1 = {:.2e}, sliding {}/{}",
        slide.max_ratio - 1.0,
        slide.sliding_steps,
        slide.contact_steps
    );
    assert!(slide.max_ratio <= 1.0 + 1e-12);
    assert_eq!(
        slide.sliding_steps, slide.contact_steps,
        "slides throughout"
    );
    assert!(slide.opposes_slip);
    eprintln!("oblique: |ΔL|/|L| = {:.2e}", slide.spin_balance);
    assert!(slide.spin_balance < 1e-3);

    let stick = oblique_impact(0.01);
    eprintln!(
        "oblique ratio 0.01: max |T|/μN_e bulk {:.3e}, overall {:.3}, sliding {}/{}",
        stick.max_ratio_bulk, stick.max_ratio, stick.sliding_steps, stick.contact_steps
    );
    assert!(stick.max_ratio <= 1.0 + 1e-12);
    assert!(
        stick.max_ratio_bulk < 0.5,
        "sticks in the bulk of the contact"
    );
    assert!(stick.sliding_steps < stick.contact_steps / 10);
    eprintln!("oblique: |ΔL|/|L| = {:.2e}", stick.spin_balance);
    assert!(stick.spin_balance < 1e-3);
}

/// AR07 App. A: when the overlap (hence K_T ∝ h^{1/2}) drops, T is first scaled by
/// K_T(h_new)/K_T(h_old) = (h_new/h_old)^{1/2}; when it grows, T is not scaled up.
/// The tangential spring is loaded by spinning both grains the same way (relative sliding of
/// the surfaces without any motion of the centres); the overlap is then changed by moving a
/// grain along n with all velocities zero, so no tangential slip is added.
#[test]
fn walton_rescaling() {
    let law = HertzMindlin::new(1e5, 0.3, 0.0, Coulomb { mu: 10.0 });
    let h_old = 1e-3;
    let mut sys = two_spheres(law, -h_old);
    freeze(&mut sys, 0);
    freeze(&mut sys, 1);
    sys.dt = 1e-5;
    // Forces are initialised at rest (see `init_forces_does_not_advance_history`).
    sys.init_forces();
    sys.w[0] = Vector3::new(0.0, 0.0, 1.0);
    sys.w[1] = Vector3::new(0.0, 0.0, 1.0);
    for _ in 0..80 {
        sys.step();
    }
    sys.w[0] = Vector3::zeros();
    sys.w[1] = Vector3::zeros();
    sys.step();
    let before = sys.interactions()[0];
    let t_old = before.tangential;
    // Loaded along +y: −K_T × (slip = −ω (R_i + R_j) dt ŷ) per step, well inside the cone.
    let kt = law.kt_ratio * law.normal_stiffness(h_old, 0.25);
    assert!(rel(t_old.y, kt * 80.0 * 1e-5) < 1e-9, "T = {t_old:?}");
    assert!(t_old.norm() < 0.5 * 10.0 * before.normal_elastic);

    let move_x = |sys: &mut System<D3, _>, dx: f64| sys.s[1].x += dx / SIDE;
    // Unload: overlap 1e-3 → 8e-4.
    move_x(&mut sys, 2e-4);
    sys.step();
    let after = sys.interactions()[0];
    let scale = ((-after.gap) / (-before.gap)).sqrt();
    assert!(rel(-after.gap, 8e-4) < 1e-9);
    let err = (after.tangential - t_old * scale).norm() / t_old.norm();
    eprintln!("walton: unload scaling err {err:.2e} (scale {scale:.6})");
    assert!(
        err < 1e-12,
        "T {:?} vs {:?}",
        after.tangential,
        t_old * scale
    );
    // Reload past the start: overlap 8e-4 → 1.2e-3; T is not scaled up.
    let t_mid = after.tangential;
    move_x(&mut sys, -4e-4);
    sys.step();
    let reload = sys.interactions()[0];
    assert!(rel(-reload.gap, 1.2e-3) < 1e-9);
    assert!((reload.tangential - t_mid).norm() <= 1e-15 * t_mid.norm());
    // A further unload rescales relative to the current stiffness, not the historical one.
    move_x(&mut sys, 2e-4);
    sys.step();
    let last = sys.interactions()[0];
    let scale = ((-last.gap) / (-reload.gap)).sqrt();
    assert!((last.tangential - t_mid * scale).norm() <= 1e-12 * t_mid.norm());
}

// ---------------------------------------------------------------------------------------------
// 5. Rolling resistance
// ---------------------------------------------------------------------------------------------

/// GRC07 (9)–(10): Γ_r = −K_r Δθ (exerted by i on j, Δθ = θ_j − θ_i), capped at μ_r N_e.
/// The disks are held at a fixed overlap (infinite masses) and counter-rotated, ω_i = −ω/2,
/// ω_j = +ω/2: pure rolling (no slip at the contact point, so T stays 0 even with μ large)
/// at the relative rate ω.
#[test]
fn rolling_resistance_spring_and_cap() {
    let (kn, kr, mu_r) = (1e5, 10.0, 0.005);
    let law = Linear {
        kn,
        kt: kn,
        zeta: 0.8,
        zeta_t: 0.0,
        cohesion: NoCohesion,
        friction: Coulomb { mu: 10.0 },
        rolling: RollingSpring { kr, mu_r },
    };
    let h = 1e-3;
    let mut sys = two_disks(law, -h);
    freeze(&mut sys, 0);
    freeze(&mut sys, 1);
    let (omega, dt) = (1.0, 1e-4);
    sys.dt = dt;
    sys.init_forces();
    sys.w[0] = -0.5 * omega;
    sys.w[1] = 0.5 * omega;
    let ne = kn * h;
    let cap = mu_r * ne;
    let yield_steps = (cap / (kr * omega * dt)).round() as usize;
    assert_eq!(yield_steps, 500);
    let mut worst: f64 = 0.0;
    for n in 1..=1000 {
        sys.step();
        let c = sys.interactions()[0];
        assert!(rel(c.normal_elastic, ne) < 1e-9);
        assert_eq!(c.tangential, Vector2::zeros(), "pure rolling: no slip");
        let expected = -(kr * omega * dt * n as f64).min(cap);
        worst = worst.max((c.rolling - expected).abs() / cap);
        assert!(
            (c.rolling - expected).abs() <= 1e-9 * cap,
            "step {n}: {}",
            c.rolling
        );
        // Moments: +Γ on j, −Γ on i.
        assert_eq!(sys.torque[1], c.rolling);
        assert_eq!(sys.torque[0], -c.rolling);
    }
    // Reverse: elastic unloading from the cap through zero to the opposite cap.
    sys.w[0] = 0.5 * omega;
    sys.w[1] = -0.5 * omega;
    for n in 1..=1500 {
        sys.step();
        let g = sys.interactions()[0].rolling;
        let expected = (-cap + kr * omega * dt * n as f64).min(cap);
        worst = worst.max((g - expected).abs() / cap);
        assert!((g - expected).abs() <= 1e-9 * cap, "reverse step {n}: {g}");
    }
    eprintln!("rolling: worst |Γ − Γ_exact|/(μ_r N_e) = {worst:.2e}");
}

// ---------------------------------------------------------------------------------------------
// 6. Energy conservation
// ---------------------------------------------------------------------------------------------

fn elastic_gas_drift<D: Dim, L: ContactLaw<D>>(
    law: L,
    d_min: f64,
    phi: f64,
    dt: f64,
    steps: usize,
    potential: impl Fn(f64, f64) -> f64,
) -> (f64, usize) {
    let gas = random_gas::<D>(200, d_min, None, phi, 7).unwrap();
    let cell = Cell::new(gas.l, 1.0);
    let mut sys = System::new(law, cell, gas.s, &gas.diameter, 0.3);
    sys.check_cell().unwrap();
    sys.u = maxwell_velocities::<D>(&sys.mass, 1.0, 7);
    sys.dt = dt;
    sys.init_forces();
    let energy = |sys: &System<D, L>| -> f64 {
        let mut e = sys.kinetic_energy();
        for c in sys.interactions() {
            if c.gap < 0.0 {
                let (ri, rj) = (sys.radius[c.i], sys.radius[c.j]);
                e += potential(-c.gap, ri * rj / (ri + rj));
            }
        }
        e
    };
    let e0 = energy(&sys);
    let mut worst: f64 = 0.0;
    let mut contacts = 0;
    for n in 0..steps {
        sys.step();
        if n % 10 == 9 {
            let it = sys.interactions();
            contacts += it.iter().filter(|c| c.gap < 0.0).count();
            worst = worst.max(rel(energy(&sys), e0));
        }
    }
    (worst, contacts)
}

/// Elastic, frictionless gas of 200 grains in a fixed periodic cell: kinetic + elastic energy
/// is conserved to 1e-6 over 1e4 velocity-Verlet steps (bounded O(dt²) error) with dt a
/// small fraction of the binary contact time. Exercises the neighbour list (rebuilds,
/// periodic images) as well as the laws.
#[test]
fn energy_conservation_linear_2d() {
    let kn = 1e3;
    let law = Linear {
        kn,
        kt: kn,
        zeta: 0.0,
        zeta_t: 0.0,
        cohesion: NoCohesion,
        friction: Frictionless,
        rolling: NoRolling,
    };
    // Shortest contact: the two lightest disks, m* = 0.25²/2.
    let t_c = std::f64::consts::PI * (0.25f64 * 0.25 / 2.0 / kn).sqrt();
    let (err, contacts) =
        elastic_gas_drift::<D2, _>(law, 0.5, 0.5, t_c / 1000.0, 10_000, |h, _| 0.5 * kn * h * h);
    eprintln!("energy linear 2D: max rel drift {err:.2e}, contact samples {contacts}");
    assert!(contacts > 100, "the gas must collide");
    assert!(err < 1e-6);
}

#[test]
fn energy_conservation_hertz_3d() {
    let e_tilde = 1e5;
    let law = HertzMindlin::new(e_tilde, 0.3, 0.0, Frictionless);
    // Contact time of two unit spheres at the rms relative speed √2 (t_c ∝ v^{-1/5}).
    let k = 2.0 / 3.0 * e_tilde * 0.5;
    let v: f64 = 2f64.sqrt();
    let t_c = HERTZ_DURATION * (5.0 * 0.5 * v * v / (4.0 * k)).powf(0.4) / v;
    let (err, contacts) =
        elastic_gas_drift::<D3, _>(law, 1.0, 0.3, t_c / 1000.0, 10_000, |h, r| {
            0.4 * (2.0 / 3.0 * e_tilde * r.sqrt()) * h.powf(2.5)
        });
    eprintln!("energy hertz 3D: max rel drift {err:.2e}, contact samples {contacts}");
    assert!(contacts > 100, "the gas must collide");
    assert!(err < 1e-6);
}

// ---------------------------------------------------------------------------------------------
// 7. Friction kinds
// ---------------------------------------------------------------------------------------------

/// Spin both spheres of a held pair about z at ω: the surfaces slide past each other at
/// ω (R_i + R_j) with no motion of the centres. Returns |T|/N_e after each step.
fn spin_drive<F: grainbench_engine::contact::slider::Friction>(
    friction: F,
    steps: usize,
) -> (Vec<f64>, f64, f64) {
    let law = Linear {
        kn: 1e5,
        kt: 1e5,
        zeta: 0.5,
        zeta_t: 0.0,
        cohesion: NoCohesion,
        friction,
        rolling: NoRolling,
    };
    let mut sys = two_spheres(law, -1e-3);
    freeze(&mut sys, 0);
    freeze(&mut sys, 1);
    sys.dt = 1e-4;
    sys.init_forces();
    sys.w[0] = Vector3::new(0.0, 0.0, 1.0);
    sys.w[1] = Vector3::new(0.0, 0.0, 1.0);
    let mut ratios = Vec::new();
    let mut t_last = 0.0;
    for _ in 0..steps {
        sys.step();
        let c = sys.interactions()[0];
        ratios.push(c.tangential.norm() / c.normal_elastic);
        t_last = c.tangential.y;
    }
    (ratios, t_last, law.kt * 1.0 * sys.dt * steps as f64)
}

/// μ = ∞ (`NoSlip`): under a sustained tangential drive the spring grows without bound,
/// T = K_T × slip exactly, far beyond any μ N_e. The same drive with `Coulomb` saturates at
/// μ N_e.
#[test]
fn noslip_never_slides() {
    let (ratios, t, expected) = spin_drive(NoSlip, 10_000);
    assert!(rel(t, expected) < 1e-9, "T = {t} vs K_T·slip = {expected}");
    assert!(
        ratios.windows(2).all(|w| w[1] > w[0]),
        "|T| grows monotonically"
    );
    assert!(
        *ratios.last().unwrap() > 100.0,
        "|T|/N_e = {}",
        ratios.last().unwrap()
    );

    let (ratios, _, _) = spin_drive(Coulomb { mu: 0.3 }, 10_000);
    let last = *ratios.last().unwrap();
    assert!((last - 0.3).abs() < 1e-12, "Coulomb saturates at μ: {last}");
}

/// μ = 0 (`Frictionless`): exactly zero tangential force, forces along the branch vector, and
/// angular velocities untouched, in a grazing impact of spinning grains. With no moment at all
/// (Hertz, frictionless) rotations are not even stored; with a moment-capable law (a rolling
/// spring of zero stiffness) they are integrated and must stay bit-for-bit unchanged.
#[test]
fn frictionless_exerts_no_tangential_force() {
    // Hertz: no moments, no rotational state.
    let law = HertzMindlin::new(1e5, 0.3, 0.5, Frictionless);
    let mut sys = two_spheres(law, 1e-4);
    // The law exerts no moments: rotations are never integrated (the arrays stay zero).
    const { assert!(!<HertzMindlin<Frictionless> as ContactLaw<D3>>::MOMENTS) };
    sys.u[0] = Vector3::new(0.05, -0.3, 0.1);
    sys.u[1] = Vector3::new(-0.05, 0.3, -0.1);
    sys.dt = 1e-5;
    sys.init_forces();
    let mut seen = 0;
    for _ in 0..10_000 {
        sys.step();
        for c in sys.interactions() {
            seen += 1;
            assert_eq!(c.tangential, Vector3::zeros());
            let n = c.branch / c.branch.norm();
            let f = sys.force[1];
            assert!(
                (f - n * f.dot(&n)).norm() <= 1e-12 * f.norm(),
                "force along n"
            );
        }
    }
    assert!(seen > 100);
    assert!(sys
        .w
        .iter()
        .chain(&sys.torque)
        .all(|x| *x == Vector3::zeros()));

    // Linear frictionless with a (null) rolling spring: rotations integrated.
    let law = Linear {
        kn: 1e5,
        kt: 1e5,
        zeta: 0.5,
        zeta_t: 0.0,
        cohesion: NoCohesion,
        friction: Frictionless,
        rolling: RollingSpring { kr: 0.0, mu_r: 0.0 },
    };
    let mut sys = two_spheres(law, 1e-4);
    sys.u[0] = Vector3::new(0.05, -0.3, 0.1);
    sys.u[1] = Vector3::new(-0.05, 0.3, -0.1);
    let w0 = [Vector3::new(3.0, -1.0, 2.0), Vector3::new(-0.5, 4.0, 1.5)];
    sys.w = w0.to_vec();
    sys.dt = 1e-5;
    sys.init_forces();
    let mut seen = 0;
    for _ in 0..10_000 {
        sys.step();
        for c in sys.interactions() {
            seen += 1;
            assert_eq!(c.tangential, Vector3::zeros());
        }
        assert_eq!(sys.torque[0], Vector3::zeros());
        assert_eq!(sys.w[0], w0[0]);
        assert_eq!(sys.w[1], w0[1]);
    }
    assert!(seen > 100);
}

// ---------------------------------------------------------------------------------------------
// Integrator start
// ---------------------------------------------------------------------------------------------

/// The force evaluation of `init_forces` happens at t = 0, before any displacement: it must
/// not add an increment u·dt to the tangential or rolling springs of existing contacts (only
/// `step`, whose force pass follows the drift by u_{n+1/2}·dt, may). Otherwise every start
/// from a configuration with sliding or rolling contacts (e.g. a reloaded packing) loads the
/// springs by one spurious step.
#[test]
fn init_forces_does_not_advance_history() {
    let law = Linear {
        kn: 1e5,
        kt: 1e5,
        zeta: 0.5,
        zeta_t: 0.0,
        cohesion: NoCohesion,
        friction: NoSlip,
        rolling: RollingSpring {
            kr: 10.0,
            mu_r: 1.0,
        },
    };
    let mut sys = two_spheres(law, -1e-3);
    freeze(&mut sys, 0);
    freeze(&mut sys, 1);
    sys.dt = 1e-4;
    // Sliding (equal spins about z) and rolling (opposite spins about y) at the contact.
    sys.w[0] = Vector3::new(0.0, -1.0, 1.0);
    sys.w[1] = Vector3::new(0.0, 1.0, 1.0);
    sys.init_forces();
    let c = sys.interactions()[0];
    assert_eq!(c.tangential, Vector3::zeros(), "T after init_forces");
    assert_eq!(c.rolling, Vector3::zeros(), "Γ after init_forces");
    // One step loads each spring by exactly one increment.
    sys.step();
    let c = sys.interactions()[0];
    assert!(rel(c.tangential.norm(), 1e5 * 1e-4) < 1e-9);
    assert!(rel(c.rolling.norm(), 10.0 * 2.0 * 1e-4) < 1e-9);
}

/// The optional tangential/rolling dashpot (`law.tangential_damping`, not in GRC07): with the
/// same motion, the damped law differs from the undamped one by exactly −η_t v_t in T
/// (η_t = 2ζ_t√(K_T m*)) and by −η_r ω_r in the rolling moment (η_r = 2ζ_t√(K_r m*) r*);
/// ζ_t = 0 leaves the law unchanged.
#[test]
fn tangential_damping_adds_a_dashpot_outside_the_springs() {
    let law = |zeta_t: f64| Linear {
        kn: 1e5,
        kt: 1e5,
        zeta: 0.8,
        zeta_t,
        cohesion: NoCohesion,
        friction: Coulomb { mu: 10.0 },
        rolling: RollingSpring {
            kr: 10.0,
            mu_r: 10.0,
        },
    };
    let run = |zeta_t: f64| {
        let mut sys = two_disks(law(zeta_t), -1e-3);
        freeze(&mut sys, 0);
        freeze(&mut sys, 1);
        sys.dt = 1e-6;
        sys.init_forces();
        // Slip of j relative to i along +y at 0.01, and relative rolling rate 0.5.
        sys.u[0] = Vector2::new(0.0, -0.005);
        sys.u[1] = Vector2::new(0.0, 0.005);
        sys.w[0] = -0.25;
        sys.w[1] = 0.25;
        sys.step();
        // Force and moment on j (the snapshot rows hold the springs' parts only).
        (sys.force[1], sys.torque[1])
    };
    let (plain, damped) = (run(0.0), run(0.3));
    let (m_eff, r_eff): (f64, f64) = (0.5, 0.25);
    let eta_t = 2.0 * 0.3 * (1e5 * m_eff).sqrt();
    let eta_r = 2.0 * 0.3 * (10.0 * m_eff).sqrt() * r_eff;
    // Contact-point slip: (u_j − u_i) − (ω_i R_i + ω_j R_j) ẑ × n, n = x̂.
    let v_slip = 0.01 - (-0.25 * 0.5 + 0.25 * 0.5);
    let d_force = damped.0 - plain.0;
    assert!(
        (d_force - Vector2::new(0.0, -eta_t * v_slip)).norm() <= 1e-6 * eta_t * v_slip,
        "{d_force:?}"
    );
    // Moment on j: the lever arm −R_j n of the tangential dashpot, and the rolling dashpot.
    let d_moment = damped.1 - plain.1;
    let expected = -0.5 * d_force.y - eta_r * 0.5;
    assert!(
        (d_moment - expected).abs() <= 1e-6 * eta_r,
        "{d_moment} vs {expected}"
    );
    // Undamped, after one step the springs hold only K_T v dt.
    assert!(plain.0.y.abs() < 0.01 * eta_t * v_slip);
}
