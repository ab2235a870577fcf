//! LAMMPS deck generator for Debian's LAMMPS 29 Sep 2021 (`lammps`) and the current release,
//! 22 Jul 2025 Update 4 (`lammps-2025`), GRANULAR package (`docs/external-codes.md`). The two
//! decks differ only in the normal dashpot's `damping` sub-model ([`damping`]).
//!
//! Files: `in.lammps` (input script) and `data.lammps` (atoms, `atom_style sphere`). Run as
//! `lmp -in in.lammps -log log.lammps -screen none`-like with the deck directory as cwd. The
//! run leaves `final.atoms` (`dump custom`), `final.contacts` (`dump local`) and `final.status`
//! (`equilibrium` or `time-limit`), read back by [`crate::xcode::import::lammps`] (columns documented
//! in `docs/external-formats/lammps.md`).
//!
//! Law (reduced units, `units lj`):
//! * Hertz–Mindlin: `pair_style granular`, `hertz/material E e ν` with E = Ẽ(1−ν²), which
//!   LAMMPS mixes back to 4/3·E/(2(1−ν²)) = (2/3)Ẽ, i.e. N = (2/3)Ẽ√(R* h) h (our law);
//!   `damping tsuji` gives F_d = c(e)·√(m* k) ḣ with k = (2/3)Ẽ√(R* h) = (2/3)K_N, so our
//!   2ζ√(m* K_N) needs c = √6·ζ: e is the root of the Tsuji polynomial c(e) = √6·ζ (negative
//!   for ζ > 0.63; this LAMMPS has no range check). Tangential:
//!   `mindlin_rescale/force NULL 0.0 μ` (K_T = 8G*a = (2−2ν)/(2−ν) K_N, incremental, rescaled
//!   on unloading, no tangential damping).
//! * Linear: `hooke K_N e` with `damping tsuji` (c = 2ζ, k = K_N) and
//!   `tangential linear_history K_T 0.0 μ`.
//! * LAMMPS 2025 rejects a negative restitution. Its `damping coeff_restitution` gives
//!   F_d = d(e)·√(m* F_ne/h) ḣ with d = −2 ln e/√(π² + ln²e) (hooke) or −√5 ln e/√(π² + ln²e)
//!   (Hertz, F_ne/h = (2/3)K_N): exact with e = exp(−πζ/√(1−ζ²)) (linear) or
//!   e = exp(−π√6ζ/√(5−6ζ²)) (Hertz), which is AR07's own restitution, for ζ < 1 and ζ < 0.913.
//!   Hertz at ζ = 0.98 needs d = √6ζ > √5: there `damping tsuji` is exact with the root of
//!   c(e) = √6ζ on the polynomial's rising branch e > 1.119 (e = 1.560 for ζ = 0.98), which
//!   this release accepts without a range check (two-particle tests,
//!   comparisons/tests/lammps_two_particle.rs).
//! * μ = 0: `tangential linear_nohistory 0.0 0.0`; μ = ∞: μ = 1e300.
//!
//! Stages: `Compress` is `fix press/berendsen iso P P τ modulus B dilate all` on the virial
//! pressure. Its linear dilation per step is (1 − dt/τ·(P_t − P)/B)^{1/3} (fix_press_berendsen.cpp,
//! in 2D too), i.e. a strain rate −(P_t − P)/(3Bτ): we take τ = 1 and B = P_t/(3 ε̇_max) so that
//! the initial rate (P ≈ 0) is the stage's cap. `FixedVolume` has no barostat. Each stage is a
//! single `run` (no chunks: `mindlin_rescale` re-applies its rescale at each run setup) stopped
//! by `fix halt` on an equal-style variable that is 1 when all criteria hold, checked every
//! `check_every` steps.

use super::lammps_table::{pair_lines, tables, Classes, TABLE};
use super::{header_lines, num, Code, Deck, PlanStage, StageKind, Start};
use grainbench_engine::scene::{Law, Mu, Relax, RelaxMethod};
use std::f64::consts::PI;
use std::fmt::Write as _;

/// The columns of a contact dump: `compute property/local patom1 patom2` and `compute
/// pair/local dist fx fy fz p1 p2 p3` (the importer's order, `import/lammps.rs`).
const CONTACT_COLUMNS: &str =
    "c_prl[1] c_prl[2] c_pl[1] c_pl[2] c_pl[3] c_pl[4] c_pl[5] c_pl[6] c_pl[7]";

/// Tsuji et al. damping coefficient of a restitution `e`, as LAMMPS `damping tsuji`
/// computes it (pair_granular.cpp).
pub fn tsuji_coefficient(e: f64) -> f64 {
    1.2728 - 4.2783 * e + 11.087 * e.powi(2) - 22.348 * e.powi(3) + 27.467 * e.powi(4)
        - 18.022 * e.powi(5)
        + 4.8218 * e.powi(6)
}

/// The root of c(e) = `c` on `[lo, hi]`, where the Tsuji polynomial is monotonic (bisection).
fn tsuji_root(c: f64, (mut lo, mut hi): (f64, f64)) -> f64 {
    let rising = tsuji_coefficient(hi) > tsuji_coefficient(lo);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        let root_above = if rising {
            tsuji_coefficient(mid) < c
        } else {
            tsuji_coefficient(mid) > c
        };
        if root_above {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The restitution `e` in [−1, 1) for which LAMMPS `damping tsuji` gives the coefficient `c`
/// (negative when c > 1.2728, i.e. above ζ ≈ 0.52 in Hertz units): the polynomial decreases
/// on [−1, 1].
pub fn tsuji_restitution(c: f64) -> f64 {
    tsuji_root(c, (-1.0, 1.0))
}

/// The restitution above 1 for which `damping tsuji` gives `c` > 0: the polynomial's rising
/// branch past its minimum at e ≈ 1.119 (LAMMPS 2025 accepts e > 1 there).
pub fn tsuji_restitution_above_one(c: f64) -> f64 {
    tsuji_root(c, (1.119, 3.0))
}

/// The `damping` sub-model and the restitution `e` to give the normal model, for a dashpot
/// 2ζ√(m* K) with `c` = √6ζ (Hertz, `hertz` true) or 2ζ (hooke): Tsuji's negative root in
/// LAMMPS 2021; `coeff_restitution` (or Tsuji's root above 1) in LAMMPS 2025.
pub fn damping(code: Code, c: f64, hertz: bool) -> (&'static str, f64) {
    if code != Code::Lammps2025 {
        return ("tsuji", tsuji_restitution(c));
    }
    // coeff_restitution: d = −k ln e/√(π² + ln²e), k = √5 (Hertz) or 2 (hooke), d < k.
    let k = if hertz { 5f64.sqrt() } else { 2.0 };
    if c <= 0.0 {
        ("coeff_restitution", 1.0)
    } else if c < k {
        (
            "coeff_restitution",
            (-PI * c / (k * k - c * c).sqrt()).exp(),
        )
    } else {
        ("tsuji", tsuji_restitution_above_one(c))
    }
}

/// GRC07 (4)–(5) attraction as a `lepton/sphere` potential of the surface gap
/// h = r − R_i − R_j (lepton differentiates it): U = F0 h − F0 D0/2 in contact (force −F0),
/// F0(h − h²/2D0) − F0 D0/2 for 0 ≤ h ≤ D0 (force −F0(1 − h/D0)), 0 beyond.
pub fn lepton_attraction(f0: f64, d0: f64) -> String {
    format!(
        "select(step(-h), F0*h - 0.5*F0*D0, select(step(D0-h), F0*(h-h^2/(2*D0)) - 0.5*F0*D0, 0)); h=r-radi-radj; F0={}; D0={}",
        num(f0),
        num(d0)
    )
}

/// `pair_style` of the scene: `granular`, or with adhesion `hybrid/overlay granular
/// lepton/sphere` with a cut-off covering 2R_max + D0 (LAMMPS 2025), or `hybrid/overlay
/// granular table` with one attraction table per pair of diameter classes, their `pair_coeff`
/// lines included (LAMMPS 2021; the matrix refuses scenes without classes).
fn pair_style(start: &Start, code: Code) -> String {
    match start.law().cohesion() {
        None => "pair_style granular".into(),
        Some(c) if code == Code::Lammps => {
            let classes = type_classes(start, code).expect("the matrix refuses continuous sizes");
            pair_lines(&classes, c.d0, TABLE).trim_end().to_string()
        }
        Some(c) => {
            let dmax = start.diameter.iter().fold(0.0_f64, |a, &d| a.max(d));
            format!(
                "pair_style hybrid/overlay granular lepton/sphere {}",
                num(dmax + 2.0 * c.d0)
            )
        }
    }
}

/// `pair_coeff * * …` lines of the scene's law at stiffness parameter `kappa` and friction
/// `mu`; `zeta_t` > 0 adds a tangential dashpot of that fraction of critical (linear law:
/// `linear_history`'s damping is x_t times the normal one, 2ζ√(m* K_N), so x_t = ζ_t√K_T/(ζ√K_N)).
fn pair_coeff(start: &Start, kappa: f64, mu: Mu, code: Code, zeta_t: f64) -> String {
    let tangential = |kt: &str, damp: f64| -> String {
        if mu.value() > 0.0 {
            let damp = if damp > 0.0 { num(damp) } else { "0.0".into() };
            format!("tangential {kt} {damp} {}", super::mu_text(mu))
        } else {
            "tangential linear_nohistory 0.0 0.0".into()
        }
    };
    match start.law() {
        Law::HertzMindlin { zeta, poisson, .. } => {
            // κ = (Ẽ/P)^(2/3) with P = 1 (AR07 (21)).
            let e_tilde = kappa.powf(1.5);
            let (model, e) = damping(code, 6f64.sqrt() * zeta, true);
            let t = if mu.value() > 0.0 {
                tangential("mindlin_rescale/force NULL", 0.0)
            } else {
                tangential("", 0.0)
            };
            format!(
                "pair_coeff * * hertz/material {} {} {} {t} damping {model}",
                num(e_tilde * (1.0 - poisson * poisson)),
                num(e),
                num(*poisson)
            )
        }
        Law::Linear {
            zeta,
            kt_over_kn,
            cohesion,
            rolling,
            ..
        } => {
            // κ = K_N/P (cohesionless, P = 1) or K_N a/F0 (cohesive, F0 = 1).
            let (model, e) = damping(code, 2.0 * zeta, false);
            let xt = if zeta_t > 0.0 && *zeta > 0.0 {
                zeta_t * kt_over_kn.sqrt() / zeta
            } else {
                0.0
            };
            let t = tangential(&format!("linear_history {}", num(kappa * kt_over_kn)), xt);
            let granular = format!("hooke {} {} {t} damping {model}", num(kappa), num(e));
            let sub = if cohesion.is_some() { "granular " } else { "" };
            // Rolling resistance: `rolling sds` per pair of diameter classes ([`rolling_sds`]).
            let granular_lines = match (rolling, type_classes(start, code)) {
                (Some(r), Some(classes)) => {
                    let mut lines = Vec::new();
                    for i in 0..classes.len() {
                        for j in i..classes.len() {
                            let (k, g, m) = rolling_sds(
                                &classes,
                                start.dimension,
                                (i, j),
                                r.kr * kappa,
                                r.mu_r,
                                zeta_t,
                            );
                            lines.push(format!(
                                "pair_coeff {} {} {sub}{granular} rolling sds {} {} {}",
                                i + 1,
                                j + 1,
                                num(k),
                                num(g),
                                num(m)
                            ));
                        }
                    }
                    lines.join("\n")
                }
                _ => format!("pair_coeff * * {sub}{granular}"),
            };
            match cohesion {
                // LAMMPS 2021: the tables' pair_coeff lines come with the pair_style
                // ([`pair_style`]); a granular line given again keeps its place in
                // hybrid/overlay's list.
                None => granular_lines,
                Some(_) if code == Code::Lammps => granular_lines,
                // lepton/sphere first: hybrid/overlay's copy_svector (LAMMPS 2025) passes on
                // the extra values (`compute pair/local p1 p2 p3`, the tangential force) of the
                // last sub-style given to a type pair only.
                Some(c) => format!(
                    "pair_coeff * * lepton/sphere \"{}\"\n{granular_lines}",
                    lepton_attraction(1.0, c.d0)
                ),
            }
        }
    }
}

/// The diameter classes that become atom types: with LAMMPS 2021 adhesion (one table per type
/// pair) or rolling resistance (`rolling sds` coefficients per type pair); `None` otherwise
/// (one type).
fn type_classes(start: &Start, code: Code) -> Option<Classes> {
    let rolling = matches!(
        start.law(),
        Law::Linear {
            rolling: Some(_),
            ..
        }
    );
    if (start.cohesive() && code == Code::Lammps) || rolling {
        Classes::of(start)
    } else {
        None
    }
}

/// `rolling sds` (k_roll, γ_roll, μ_roll) for classes (i, j): LAMMPS integrates a rolling
/// displacement ξ with dξ/dt = R*(ω_i − ω_j) × n and exerts the moment R* n × F_r, F_r = −k_roll ξ
/// − γ_roll dξ/dt capped at μ_roll·|N| (pair_granular.cpp), i.e. Γ = k_roll R*² θ: GRC07 (9)–(10)
/// with K_r (`kr`) and μ_r are k_roll = K_r/R*², μ_roll = μ_r/R* — the cap on LAMMPS's total normal
/// force, damping included, where ours has N_e. The relaxation's rolling dashpot
/// η_r = 2ζ_t√(K_r m*) R* (engine/src/contact/linear.rs) is γ_roll = η_r/R*².
fn rolling_sds(
    classes: &Classes,
    dimension: usize,
    (i, j): (usize, usize),
    kr: f64,
    mu_r: f64,
    zeta_t: f64,
) -> (f64, f64, f64) {
    let (di, dj) = (classes.diameter[i], classes.diameter[j]);
    let r_eff = 0.25 * di * dj / (0.5 * (di + dj));
    let (mi, mj) = (di.powi(dimension as i32), dj.powi(dimension as i32));
    let m_eff = mi * mj / (mi + mj);
    let eta = 2.0 * zeta_t * (kr * m_eff).sqrt() * r_eff;
    (kr / (r_eff * r_eff), eta / (r_eff * r_eff), mu_r / r_eff)
}

/// Gain g of the first-order servo, per-axis rate g·(σ_αα − P)/P: the scene's
/// `numerics.servo_gain` where it sets one (our engine then runs the same servo); otherwise,
/// in adhesive decks, 2·cap (full cap beyond 50 % of the target), lowered to keep the loop
/// stable. Each step the affine remap changes the stress by B·rate·dt with B ≈ κ/4 (measured
/// on the smoke packing: a step at the cap moved σ by 0.055 at κ = 1e4); g·B·dt/P > 2 makes
/// the box flip between two sizes every step with σ ≈ P ± 0.028 (seen), so g ≤ P/(2 κ dt) (B
/// taken as κ/4, 4× margin on the stability bound B·g·dt/P < 2).
fn servo_gain(pressure: f64, st: &PlanStage) -> f64 {
    st.servo_gain
        .unwrap_or((2.0 * st.max_strain_rate).min(pressure / (2.0 * st.kappa * st.dt)))
}

/// How the deck's comment names g.
fn servo_gain_source(st: &PlanStage) -> &'static str {
    if st.servo_gain.is_some() {
        "the scene's numerics.servo_gain"
    } else {
        "min(2 cap, P/(2 κ dt))"
    }
}

/// LAMMPS 2021's stand-in for deform/pressure (which it lacks) in adhesive stage `k`: `fix
/// deform` with `variable` box lengths, each step L ← L(1 + r·dt) per axis with r = g·(σ_αα −
/// P)/P at most the cap (g from [`servo_gain`]), σ from that step's virial (a `fix ave/time`
/// every step keeps it current; defined first, it runs first at the end of the step). fix
/// deform measures its displacement from the box at each run's start: returns the lines that
/// record that box, to give before every `run` of the stage.
fn servo_2021(s: &mut String, start: &Start, st: &PlanStage, k: usize, pressure: f64) -> String {
    let axes = &["x", "y", "z"][..start.dimension];
    let cols: Vec<String> = (1..=start.dimension)
        .map(|a| format!("c_pvir[{a}]"))
        .collect();
    let (p, g, cap) = (
        num(pressure),
        num(servo_gain(pressure, st)),
        num(st.max_strain_rate),
    );
    let src = servo_gain_source(st);
    let _ = writeln!(
        s,
        "# Stress control (LAMMPS 2021 has no deform/pressure): fix deform sets each box length to\n\
         # L(1 + r dt), r = g·(σ_αα − P)/P at most the cap {cap}, g = {src} = {g}.\n\
         fix avp{k} all ave/time 1 1 1 {}",
        cols.join(" ")
    );
    let mut rebase = String::new();
    let mut deform = String::from("fix baro all deform 1");
    for (a, ax) in axes.iter().enumerate() {
        let a1 = a + 1;
        let _ = writeln!(
            s,
            "variable r{k}{ax}raw equal {g}*(f_avp{k}[{a1}]-{p})/{p}\n\
             variable r{k}{ax} equal (v_r{k}{ax}raw>{cap})*{cap}-(v_r{k}{ax}raw<-{cap})*{cap}+(abs(v_r{k}{ax}raw)<={cap})*v_r{k}{ax}raw\n\
             variable d{k}{ax} equal l{ax}*(1+v_r{k}{ax}*dt)-v_l0{k}{ax}\n\
             variable u{k}{ax} equal l{ax}*v_r{k}{ax}"
        );
        let _ = writeln!(rebase, "variable l0{k}{ax} equal $(l{ax})");
        let _ = write!(deform, " {ax} variable v_d{k}{ax} v_u{k}{ax}");
    }
    let _ = writeln!(s, "{rebase}{deform} remap x");
    rebase
}

/// Stress control of adhesive decks (replaces the matrix's Berendsen line in their header).
pub const ADHESIVE_STRESS_CONTROL: &str = "stress-control: fix deform/pressure (LAMMPS 2025), per-axis strain rate g·(σ_αα − P)/P on the virial stress, g = min(2·cap, P/(2κ dt)) for a stable loop, at most the cap (Berendsen's unbounded rate collapses the cell when an adhesive packing's virial swings to ±100 P), no cell mass";

/// Stress control of LAMMPS 2021 adhesive decks ([`servo_2021`]).
pub const ADHESIVE_STRESS_CONTROL_2021: &str = "stress-control: fix deform with variable box lengths (LAMMPS 2021 has no deform/pressure): each step L ← L(1 + r dt) per axis, r = g·(σ_αα − P)/P from that step's virial stress, at most the cap, g as LAMMPS 2025's deform/pressure decks, no cell mass";

/// The deviation line of feature `f` (matrix reason `why`) in an adhesive LAMMPS deck, whose
/// stress control is deform/pressure (2025) or a fix deform servo (2021), not Berendsen.
pub fn adhesive_deviation(f: super::Feature, why: &str, code: Code) -> String {
    let (control, change) = if code == Code::Lammps2025 {
        (ADHESIVE_STRESS_CONTROL, "deform/pressure box change")
    } else {
        (ADHESIVE_STRESS_CONTROL_2021, "fix deform box change")
    };
    match f {
        super::Feature::StressControl => control.to_string(),
        _ => format!("{}: {}", f.key(), why.replace("Berendsen dilation", change)),
    }
}

/// The LAMMPS deck of `start` for `code` (either LAMMPS version).
pub fn deck(start: &Start, code: Code, deviations: &[String]) -> Deck {
    // One atom type per diameter class where coefficients depend on the pair (LAMMPS 2021
    // adhesion: the attraction in tables; rolling resistance).
    let types = type_classes(start, code);
    let mut files = vec![
        ("in.lammps".into(), input(start, code, deviations)),
        ("data.lammps".into(), data(start, types.as_ref())),
    ];
    if let (Some(c), Some(k), Code::Lammps) = (start.law().cohesion(), &types, code) {
        files.push((
            TABLE.into(),
            tables(k, c.d0, &format!("scene {}", start.scene.name)),
        ));
    }
    Deck {
        code,
        files,
        deviations: deviations.to_vec(),
        args: vec![
            "-in".into(),
            "in.lammps".into(),
            "-log".into(),
            "log.lammps".into(),
            "-nocite".into(),
        ],
    }
}

/// The data file; with `classes`, atom type k + 1 is diameter class k.
fn data(start: &Start, classes: Option<&Classes>) -> String {
    let d3 = start.dimension == 3;
    let mut s = format!("grainbench start of scene {}\n\n", start.scene.name);
    let _ = writeln!(
        s,
        "{} atoms\n{} atom types\n",
        start.n(),
        classes.map_or(1, Classes::len)
    );
    let axes = ["x", "y", "z"];
    for (a, ax) in axes.iter().enumerate() {
        let hi = if a < start.dimension {
            num(start.lengths[a])
        } else {
            "0.5".into()
        };
        let lo = if a < start.dimension { "0" } else { "-0.5" };
        let _ = writeln!(s, "{lo} {hi} {ax}lo {ax}hi");
    }
    s.push_str("\nAtoms # sphere\n\n");
    for i in 0..start.n() {
        let d = start.diameter[i];
        // read_data sets m = ρ·πd³/6 in 2D as in 3D: give ρ per atom so that m is ours.
        let rho = start.mass[i] / (PI * d * d * d / 6.0);
        let p = &start.position[i];
        let z = if d3 { num(p[2]) } else { "0".into() };
        let _ = writeln!(
            s,
            "{} {} {} {} {} {} {z}",
            i + 1,
            classes.map_or(1, |k| k.of[i] + 1),
            num(d),
            num(rho),
            num(p[0]),
            num(p[1])
        );
    }
    if start.velocity.iter().flatten().any(|&v| v != 0.0) || start.spinning() {
        s.push_str("\nVelocities\n\n");
        for (i, v) in start.velocity.iter().enumerate() {
            let vz = if d3 { num(v[2]) } else { "0".into() };
            let w = start.spin3(i).map(num);
            let _ = writeln!(
                s,
                "{} {} {} {vz} {} {} {}",
                i + 1,
                num(v[0]),
                num(v[1]),
                w[0],
                w[1],
                w[2]
            );
        }
    }
    s
}

fn input(start: &Start, code: Code, deviations: &[String]) -> String {
    let d3 = start.dimension == 3;
    let n = start.n();
    let mut s = String::new();
    for h in header_lines(start, code, deviations) {
        let _ = writeln!(s, "# {h}");
    }
    let solid: f64 = start
        .diameter
        .iter()
        .map(|&x| {
            if d3 {
                PI * x * x * x / 6.0
            } else {
                PI * x * x / 4.0
            }
        })
        .sum();
    let friction = start.stages.iter().any(|st| st.mu.value() > 0.0);
    let inertia = if d3 { "0.4" } else { "0.5" };
    let omega2 = if d3 {
        "c_pa[7]^2+c_pa[8]^2+c_pa[9]^2"
    } else {
        "c_pa[9]^2"
    };
    let f2 = if d3 {
        "c_pa[1]^2+c_pa[2]^2+c_pa[3]^2"
    } else {
        "c_pa[1]^2+c_pa[2]^2"
    };
    let t2 = if d3 {
        "c_pa[4]^2+c_pa[5]^2+c_pa[6]^2"
    } else {
        "c_pa[6]^2"
    };
    let v2 = if d3 { "vx^2+vy^2+vz^2" } else { "vx^2+vy^2" };
    let _ = write!(
        s,
        "\nunits lj\n\
         atom_style sphere\n\
         dimension {dim}\n\
         boundary p p p\n\
         atom_modify map array\n\
         comm_modify vel yes\n\
         read_data data.lammps\n\
         {style}\n\
         {coeff}\n\
         # Verlet skin: the scene's numerics.skin (a), as in our engine.\n\
         neighbor {skin} bin\n\
         neigh_modify delay 0 every 1 check yes\n\
         fix integ all nve/sphere{disc}\n\
         {e2d}\
         \n\
         # Equilibrium measures (AR07 §III, GRC07 §II.D, as our engine's): largest net force and torque on a\n\
         # grain, diagonal virial stress (compressive positive, force/a^(d-1)), kinetic energy\n\
         # per grain: translation of all grains, rotation of grains with a contact (I = {inertia} m r²).\n\
         compute pvir all pressure NULL virial\n\
         compute pa all property/atom fx fy fz tqx tqy tqz omegax omegay omegaz radius\n\
         compute cn all contact/atom\n\
         variable fmag atom sqrt({f2})\n\
         variable tmag atom sqrt({t2})\n\
         variable ek atom 0.5*mass*({v2})+(c_cn>0)*0.5*{inertia}*mass*c_pa[10]^2*({omega2})\n\
         compute fmax all reduce max v_fmag v_tmag\n\
         compute eksum all reduce sum v_ek\n\
         variable kpg equal c_eksum/{n}\n\
         variable phi equal {solid}/vol\n\
         # Contacts: pair/local dist, normal force on I (fx fy fz), tangential (p1 p2 p3).\n\
         compute pl all pair/local dist fx fy fz p1 p2 p3{cutoff}\n\
         compute prl all property/local patom1 patom2{cutoff}\n",
        dim = start.dimension,
        coeff = start
            .stages
            .first()
            .map(|st| pair_coeff(start, st.kappa, st.mu, code, 0.0))
            .unwrap_or_else(|| {
                pair_coeff(start, start.law().kappa(), Mu::Finite(0.0), code, 0.0)
            }),
        style = pair_style(start, code),
        // With adhesion every pair within the cut-off (distant attractions included); the
        // importer drops the ones that carry no force.
        cutoff = if start.cohesive() { "" } else { " cutoff radius" },
        disc = if d3 { "" } else { " disc" },
        e2d = if d3 { "" } else { "fix e2d all enforce2d\n" },
        solid = num(solid),
        skin = num(start.scene.numerics.skin),
    );
    if let Some(k) = start.trace_steps {
        let _ = writeln!(
            s,
            "\n# Trace (scene output.trace_every): every {k} steps each grain with its force, and\n\
             # each contact as in final.contacts (docs/external-formats/lammps.md).\n\
             dump tr all custom {k} trace.atoms id radius mass x y z vx vy vz omegax omegay omegaz fx fy fz\n\
             dump_modify tr format float %.17g time yes\n\
             dump trc all local {k} trace.contacts {CONTACT_COLUMNS}\n\
             dump_modify trc format float %.17g"
        );
    }
    for (k, st) in start.stages.iter().enumerate() {
        stage(&mut s, start, code, k, st, friction);
    }
    if start.trace_steps.is_some() {
        s.push_str("undump tr\nundump trc\n");
    }
    let _ = write!(
        s,
        "\n# Final state (columns: docs/external-formats/lammps.md). The contacts are dumped at the\n\
         # setup of a `run 0` (no history update, forces from the final velocities), the atoms after\n\
         # it so that their fx fy fz are the same forces.\n\
         dump fc all local 1 final.contacts {CONTACT_COLUMNS}\n\
         dump_modify fc format float %.17g\n\
         run 0\n\
         undump fc\n\
         write_dump all custom final.atoms id radius mass x y z vx vy vz omegax omegay omegaz fx fy fz modify format float %.17g time yes\n\
         print \"${{status}}\" file final.status\n",
    );
    s
}

/// Stage `k` of the input: its time step and law (after the first), the stress control of a
/// compression (Berendsen, deform/pressure or the 2021 adhesive servo), the equilibrium
/// criteria as one variable, and the run: relaxed, quenched, or stopped by `fix halt` at
/// equilibrium or at the stage's time limit.
fn stage(s: &mut String, start: &Start, code: Code, k: usize, st: &PlanStage, friction: bool) {
    let tol = st.tolerances;
    let k1 = k + 1;
    let _ = writeln!(s, "\n# Stage {k1}: {:?}", st.kind);
    let _ = writeln!(s, "timestep {}", num(st.dt));
    if k > 0 {
        let _ = writeln!(s, "{}", pair_coeff(start, st.kappa, st.mu, code, 0.0));
    }
    // Every criterion but the kinetic one (the quench's test), then all of them.
    let kinetic = format!("(v_kpg<{})", num(tol.kinetic_per_grain));
    let mut crit = vec![format!("(c_fmax[1]<{})", num(tol.force))];
    if friction && st.mu.value() > 0.0 {
        crit.push(format!("(c_fmax[2]<{})", num(tol.moment)));
    }
    // Lines before each `run` of the stage (LAMMPS 2021 adhesive servo: the box at the run's start).
    let mut rebase = String::new();
    if let StageKind::Compress { pressure } = st.kind {
        let servo = start.cohesive() || st.servo_gain.is_some();
        if servo && code == Code::Lammps {
            rebase = servo_2021(s, start, st, k1, pressure);
        } else if servo {
            // An adhesive packing's virial swings to ±100 P while grains collide and
            // stick: Berendsen's rate (P − σ)/(3Bτ) has no bound and collapses the cell.
            // LAMMPS 2025's deform/pressure caps it: per axis, rate = g(σ_αα − P)/P at
            // most the cap, g from [`servo_gain`].
            let axes = ["x", "y", "z"][..start.dimension]
                .iter()
                .map(|a| {
                    format!(
                        "{a} pressure {} {}",
                        num(pressure),
                        num(servo_gain(pressure, st))
                    )
                })
                .collect::<Vec<_>>()
                .join(" ");
            let _ = writeln!(
                s,
                "# Stress control: fix deform/pressure, per-axis strain rate g·(σ_αα − P)/P, g = {}, at most the cap\n\
                 fix baro all deform/pressure 1 {axes} max/rate {} normalize/pressure yes remap x\n\
                 fix_modify baro press pvir",
                servo_gain_source(st),
                num(st.max_strain_rate)
            );
        } else {
            let b = pressure / (3.0 * st.max_strain_rate);
            let _ = writeln!(
                s,
                "# Berendsen: strain rate -(P_t - P)/(3 B tau); tau = 1, B = P_t/(3 rate cap) = {}",
                num(b)
            );
            let _ = writeln!(
                s,
                "fix baro all press/berendsen aniso {p} {p} 1 modulus {b} dilate all\n\
                 fix_modify baro press pvir",
                p = num(pressure),
                b = num(b)
            );
        }
        for a in 1..=start.dimension {
            crit.push(format!(
                "(abs(c_pvir[{a}]-{})<{})",
                num(pressure),
                num(tol.stress)
            ));
        }
    }
    let (force, rest) = crit.split_first().expect("the force criterion");
    let _ = writeln!(
        s,
        "variable ok{k1} equal {force}*{kinetic}{}",
        rest.iter().map(|c| format!("*{c}")).collect::<String>()
    );
    if st.quench {
        let _ = writeln!(s, "variable q{k1} equal {}", crit.join("*"));
    }
    let full_time = matches!(st.kind, StageKind::FixedVolume { full_time: true });
    // FIRE (`relax.method = "fire"`) is not generated: the stage runs the law's dynamics
    // to the criteria (capability `fire-relaxation`, approximate).
    if let Some(relax) = st.relax.filter(|r| r.method == RelaxMethod::Damping) {
        relaxed_stage(s, start, st, k1, relax, code, &rebase);
    } else if st.quench && !full_time {
        quenched_stage(s, st, k1, &rebase);
    } else {
        let _ = writeln!(
            s,
            "thermo_style custom step time v_phi c_pvir[1] c_pvir[2] c_pvir[3] c_fmax[1] c_fmax[2] v_kpg v_ok{k1}\n\
             thermo_modify norm no flush yes\n\
             thermo {}",
            st.check_every
        );
        if !full_time {
            let _ = writeln!(
                s,
                "fix halt all halt {} v_ok{k1} > 0.5 error continue",
                st.check_every
            );
        }
        let _ = writeln!(s, "{rebase}run {}", st.max_steps);
        // The thermo line at the run's last step invokes the computes v_ok reads.
        let _ = writeln!(
            s,
            "if \"${{ok{k1}}} > 0.5\" then \"variable status string equilibrium\" else \"variable status string time-limit\""
        );
        if !full_time {
            s.push_str("unfix halt\n");
        }
    }
    if matches!(st.kind, StageKind::Compress { .. }) {
        s.push_str("unfix baro\n");
        if !rebase.is_empty() {
            let _ = writeln!(s, "unfix avp{k1}");
        }
    }
}

/// A stage with `criteria.quench` (engine/src/run/quench.rs): runs stopped by `fix halt` when
/// every criterion but the kinetic one holds; then the stage ends if the kinetic one holds too,
/// or every velocity and spin is set to zero and the stage goes on for one check interval,
/// judged again at its end as our engine judges its next check.
fn quenched_stage(s: &mut String, st: &PlanStage, k: usize, rebase: &str) {
    let _ = write!(
        s,
        "thermo_style custom step time v_phi c_pvir[1] c_pvir[2] c_pvir[3] c_fmax[1] c_fmax[2] v_kpg v_ok{k} v_q{k}\n\
         thermo_modify norm no flush yes\n\
         thermo {every}\n\
         # Quench (criteria.quench, AR07 §III.A): where only the kinetic criterion fails, all\n\
         # velocities and spins are set to zero and the stage goes on.\n\
         variable end{k} equal $(step+{max})\n\
         variable nq{k} equal 0\n\
         label quench{k}\n\
         fix halt all halt {every} v_q{k} > 0.5 error continue\n\
         {rebase}run ${{end{k}}} upto\n\
         unfix halt\n\
         label judge{k}\n\
         if \"${{ok{k}}} > 0.5\" then \"variable status string equilibrium\" \"jump SELF done{k}\"\n\
         if \"$(step) >= ${{end{k}}}\" then \"variable status string time-limit\" \"jump SELF done{k}\"\n\
         if \"${{q{k}}} < 0.5\" then \"jump SELF quench{k}\"\n\
         velocity all set 0.0 0.0 0.0\n\
         set group all omega 0.0 0.0 0.0\n\
         variable nq{k} equal $(v_nq{k}+1)\n\
         print \"grainbench: quench ${{nq{k}}} at step $(step), time $(time)\"\n\
         {rebase}run {every}\n\
         jump SELF judge{k}\n\
         label done{k}\n",
        every = st.check_every,
        max = st.max_steps,
    );
}

/// A stage with a final relaxation (`relax`, engine/src/run/relax.rs), as far as LAMMPS can
/// say it. Phase A runs the law as it is in chunks of `settle_time` and switches when, at the end
/// of a chunk, the number of contacts (`compute contact/atom`: touching pairs, not the list) is
/// the one at the end of the previous chunk and the kinetic (without one-contact grains with
/// `free_rollers`) and stress criteria hold to `settle_factor`; with `settle_time = 0`, one run
/// stopped by `fix halt` at the first check where they hold. Phase B damps the velocities with
/// `fix langevin` at T = 0 (drag −m v γ; spins at LAMMPS's rotational rate) and adds the
/// tangential dashpot, until the criteria hold over the window: runs stopped by `fix halt` when
/// they first hold, then a window-long run stopped when they break (none without a window).
fn relaxed_stage(
    s: &mut String,
    start: &Start,
    st: &PlanStage,
    k: usize,
    relax: Relax,
    code: Code,
    rebase: &str,
) {
    let tol = st.tolerances;
    let n = start.n();
    let settle = ((relax.settle_time / st.dt).ceil() as u64).max(st.check_every);
    let window = ((st.window / st.dt).ceil() as u64).max(st.check_every);
    let every = st.check_every;
    let f = relax.settle_factor;
    let mut rest = vec![format!("(c_eks{k}/{n}<{})", num(f * tol.kinetic_per_grain))];
    if let StageKind::Compress { pressure } = st.kind {
        for a in 1..=start.dimension {
            rest.push(format!(
                "(abs(c_pvir[{a}]-{})<{})",
                num(pressure),
                num(f * tol.stress)
            ));
        }
    }
    let settling_ek = if relax.free_rollers {
        "v_ek*(c_cn!=1)"
    } else {
        "v_ek"
    };
    // With settle_time = 0 our switch asks nothing of the list (it has been unchanged for
    // zero time at any check): the first check at rest switches, so one run stopped by
    // `fix halt` replaces the chunks (and their per-run set-up).
    let (phase_a, how) = if relax.settle_time > 0.0 {
        (
            format!(
                "variable nprev{k} equal -1\n\
                 label settle{k}\n\
                 {rebase}run {settle}\n\
                 if \"${{ncnt{k}}} == ${{nprev{k}}} && ${{rest{k}}} > 0.5\" then \"jump SELF damp{k}\"\n\
                 variable nprev{k} equal ${{ncnt{k}}}\n\
                 if \"$(step) < ${{end{k}}}\" then \"jump SELF settle{k}\"\n"
            ),
            format!(
                "in chunks of settle_time ({settle} steps), until the contact count is unchanged over a chunk and"
            ),
        )
    } else {
        (
            format!(
                "fix halt all halt {every} v_rest{k} > 0.5 error continue\n\
                 {rebase}run ${{end{k}}} upto\n\
                 unfix halt\n\
                 if \"${{rest{k}}} > 0.5\" then \"jump SELF damp{k}\"\n"
            ),
            "stopped by fix halt at the first check where".to_string(),
        )
    };
    // The criteria must then hold over the window; with none (AR07 presets) the first check
    // where they hold ends the stage, as ours.
    let (hold, over) = if st.window > 0.0 {
        (
            format!(
                "fix halt all halt {every} v_ok{k} < 0.5 error continue\n\
                 {rebase}run {window}\n\
                 unfix halt\n\
                 if \"${{ok{k}}} > 0.5\" then \"variable status string equilibrium\" \"jump SELF undamp{k}\"\n\
                 jump SELF hold{k}\n"
            ),
            format!(" over the window ({window} steps)"),
        )
    } else {
        (
            "variable status string equilibrium\n".to_string(),
            String::new(),
        )
    };
    let damped = pair_coeff(start, st.kappa, st.mu, code, relax.tangential_zeta);
    let plain = pair_coeff(start, st.kappa, st.mu, code, 0.0);
    let _ = write!(
        s,
        "# Final relaxation (relax = {{ damping = {gamma}, tangential_zeta = {zt}, settle_time = {st_time}, free_rollers = {fr}, settle_factor = {sf} }}).\n\
         # Phase A: the law as it is, {how}\n\
         # the kinetic{fr_note} and stress criteria are met (to settle_factor).\n\
         variable end{k} equal $(step+{max})\n\
         compute ncs{k} all reduce sum c_cn\n\
         variable ncnt{k} equal c_ncs{k}\n\
         variable eks{k} atom {settling_ek}\n\
         compute eks{k} all reduce sum v_eks{k}\n\
         variable rest{k} equal {rest}\n\
         thermo_style custom step time v_phi c_pvir[1] c_pvir[2] c_pvir[3] c_fmax[1] c_fmax[2] v_kpg v_ok{k} v_ncnt{k} v_rest{k}\n\
         thermo_modify norm no flush yes\n\
         thermo {every}\n\
         {phase_a}\
         variable status string time-limit\n\
         jump SELF done{k}\n\
         # Phase B: drag -m v gamma on every grain (fix langevin at T = 0) and the tangential dashpot,\n\
         # until the criteria hold{over}.\n\
         label damp{k}\n\
         print \"grainbench: damping on at step $(step), time $(time)\"\n\
         fix relax{k} all langevin 0.0 0.0 {damp} 1 omega yes\n\
         {damped}\n\
         label hold{k}\n\
         if \"$(step) >= ${{end{k}}}\" then \"variable status string time-limit\" \"jump SELF undamp{k}\"\n\
         fix halt all halt {every} v_ok{k} > 0.5 error continue\n\
         {rebase}run ${{end{k}}} upto\n\
         unfix halt\n\
         if \"${{ok{k}}} < 0.5\" then \"variable status string time-limit\" \"jump SELF undamp{k}\"\n\
         {hold}\
         label undamp{k}\n\
         unfix relax{k}\n\
         {plain}\n\
         label done{k}\n",
        gamma = num(relax.damping),
        zt = num(relax.tangential_zeta),
        st_time = num(relax.settle_time),
        fr = relax.free_rollers,
        sf = num(relax.settle_factor),
        fr_note = if relax.free_rollers { " (one-contact grains left out)" } else { "" },
        max = st.max_steps,
        rest = rest.join("*"),
        damp = num(1.0 / relax.damping),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// LAMMPS 2025 `coeff_restitution`: d(e) = −k ln e/√(π² + ln²e).
    fn coeff_restitution(e: f64, k: f64) -> f64 {
        -k * e.ln() / (PI * PI + e.ln().powi(2)).sqrt()
    }

    #[test]
    fn lammps_2025_damping_gives_back_the_coefficient() {
        for (zeta, hertz) in [
            (0.098, true),
            (0.5, true),
            (0.9, true),
            (0.8, false),
            (0.98, false),
        ] {
            let (c, k) = if hertz {
                (6f64.sqrt() * zeta, 5f64.sqrt())
            } else {
                (2.0 * zeta, 2.0)
            };
            let (model, e) = damping(Code::Lammps2025, c, hertz);
            assert_eq!(model, "coeff_restitution", "ζ = {zeta}");
            assert!((0.0..1.0).contains(&e));
            assert!((coeff_restitution(e, k) - c).abs() < 1e-12, "ζ = {zeta}");
        }
        // Hertz at ζ = 0.98 is past coeff_restitution's reach (√6ζ > √5): Tsuji above 1.
        let c = 6f64.sqrt() * 0.98;
        let (model, e) = damping(Code::Lammps2025, c, true);
        assert_eq!(model, "tsuji");
        assert!((e - 1.560056331).abs() < 1e-6, "{e}");
        assert!((tsuji_coefficient(e) - c).abs() < 1e-9);
        // No damping: e = 1 (e = 0 gives NaN forces in that release).
        assert_eq!(
            damping(Code::Lammps2025, 0.0, true),
            ("coeff_restitution", 1.0)
        );
        // LAMMPS 2021 keeps Tsuji's negative root.
        let (model, e) = damping(Code::Lammps, c, true);
        assert_eq!(model, "tsuji");
        assert!(e < 0.0 && (tsuji_coefficient(e) - c).abs() < 1e-9);
    }

    /// The common start of an embedded scene.
    fn library_start(name: &str) -> Start {
        let scene = grainbench_engine::library::scene(name).unwrap().unwrap();
        Start::of(&scene).unwrap()
    }

    /// Adhesive scene: LAMMPS 2025 gets the exact GRC07 attraction by lepton/sphere,
    /// a capped deform/pressure servo and the relaxation loop; LAMMPS 2021 refuses it.
    #[test]
    fn adhesive_deck_overlays_lepton_and_relaxes() {
        let start = library_start("xcode-cohesive-smoke");
        let deck = super::super::deck(&start, Code::Lammps2025).unwrap();
        let input = &deck.files[0].1;
        for line in [
            "pair_style hybrid/overlay granular lepton/sphere",
            "pair_coeff * * granular hooke 1e4",
            "pair_coeff * * lepton/sphere \"select(step(-h)",
            "fix baro all deform/pressure 1 x pressure 1e-2 2.2203770805215026e-3 y pressure 1e-2 2.2203770805215026e-3 max/rate 2e-3",
            "label settle1",
            "fix relax1 all langevin 0.0 0.0 1 1 omega yes",
            // ζ_t/ζ = 0.5/0.8 with K_T = K_N.
            "tangential linear_history 1e4 6.25e-1 5e-1",
            "variable eks1 atom v_ek*(c_cn!=1)",
        ] {
            assert!(input.contains(line), "missing `{line}`");
        }
        // Distant attractions are dumped (no `cutoff radius`).
        assert!(input.contains("compute pl all pair/local dist fx fy fz p1 p2 p3\n"));
        assert!(!input.contains("press/berendsen"));
        assert!(deck
            .deviations
            .iter()
            .any(|d| d.starts_with("stress-control: fix deform/pressure")));
        // Continuous sizes: LAMMPS 2021 (tables per atom-type pair) refuses, naming the fix.
        let refusal = super::super::deck(&start, Code::Lammps).unwrap_err();
        assert_eq!(
            refusal.missing.iter().map(|(f, _)| *f).collect::<Vec<_>>(),
            [super::super::Feature::AdhesionContinuousSizes]
        );
        assert!(refusal.to_string().contains("particles.classes"));
    }

    /// A relaxation with `settle_time = 0` switches at the first check at rest, as ours does
    /// (the list has been unchanged for zero time at any check); with a settle time the
    /// contact count must also hold over a chunk.
    #[test]
    fn relaxation_without_settle_time_switches_on_rest_alone() {
        let start = library_start("ar07-D-10kPa-n1372-relax");
        let input = &super::super::deck(&start, Code::Lammps).unwrap().files[0].1;
        assert!(input.contains(
            "fix halt all halt 200 v_rest1 > 0.5 error continue\nrun ${end1} upto\nunfix halt\nif \"${rest1} > 0.5\" then \"jump SELF damp1\""
        ));
        assert!(!input.contains("label settle1"));
        assert!(input.contains("fix relax1 all langevin 0.0 0.0 3.3333333333333335 1 omega yes"));
        assert!(!input.contains("${ncnt1} == ${nprev1}"));
        let start = library_start("xcode-cohesive-smoke");
        let input = &super::super::deck(&start, Code::Lammps2025).unwrap().files[0].1;
        assert!(input.contains("if \"${ncnt1} == ${nprev1} && ${rest1} > 0.5\" then"));
    }

    /// LAMMPS 2021, diameters in classes: one atom type per class, one table per type pair
    /// (cut-off = the table's r_hi), the granular line last (its p1..p3 reach pair/local), the
    /// fix deform servo re-based before every run, and the same relaxation.
    #[test]
    fn adhesive_class_deck_uses_tables_and_a_deform_servo() {
        let start = library_start("xcode-cohesive-classes-smoke");
        let deck = super::super::deck(&start, Code::Lammps).unwrap();
        let input = &deck.files[0].1;
        let data = &deck.files[1].1;
        assert!(data.contains("\n5 atom types\n"));
        let table = &deck.files.iter().find(|(n, _)| n == TABLE).unwrap().1;
        assert_eq!(table.matches("\nN 10001 RSQ ").count(), 15);
        for line in [
            "pair_style hybrid/overlay granular table linear 10001\npair_coeff 1 1 table cohesion.table C_1_1 5.01e-1\n",
            "pair_coeff 5 5 table cohesion.table C_5_5 1.001\npair_coeff * * granular hooke 1e4",
            "fix avp1 all ave/time 1 1 1 c_pvir[1] c_pvir[2]",
            "variable d1x equal lx*(1+v_r1x*dt)-v_l01x",
            "fix baro all deform 1 x variable v_d1x v_u1x y variable v_d1y v_u1y remap x",
            "label settle1\nvariable l01x equal $(lx)\nvariable l01y equal $(ly)\nrun ",
            "fix relax1 all langevin 0.0 0.0 1 1 omega yes",
            "unfix baro\nunfix avp1\n",
        ] {
            assert!(input.contains(line), "missing `{line}`");
        }
        assert!(!input.contains("all deform/pressure") && !input.contains("lepton/sphere"));
        // Every run of the stage starts from a re-based servo.
        assert_eq!(
            input.matches("\nrun ").count() - 1,
            input.matches("variable l01y equal $(ly)\nrun ").count(),
            "the final `run 0` aside"
        );
        assert!(deck
            .deviations
            .iter()
            .any(|d| d.starts_with("stress-control: fix deform with variable box lengths")));
    }

    /// Rolling resistance on a class scene: one `rolling sds` line per pair of classes, with
    /// k_roll = K_r/R*² and μ_roll = μ_r/R*, in both versions; the relaxation's lines carry
    /// γ_roll = 2ζ_t√(K_r m*)/R*; the switch to it tests the criteria to `settle_factor`.
    #[test]
    fn rolling_resistance_is_per_class_pair() {
        let start = library_start("xcode-cohesive-rr-smoke");
        for code in [Code::Lammps, Code::Lammps2025] {
            let deck = super::super::deck(&start, code).unwrap();
            let input = &deck.files[0].1;
            // Classes 1 and 5 (d = 0.5 and 1): R* = 0.25·0.5/0.75 = 1/6, K_r = 1e-4·1e4 = 1.
            let classes = Classes::of(&start).unwrap();
            let (k, g0, m) = rolling_sds(&classes, 2, (0, 4), 1.0, 0.005, 0.0);
            assert!((k - 36.0).abs() < 1e-9 && g0 == 0.0 && (m - 0.03).abs() < 1e-12);
            let line = format!(
                "pair_coeff 1 5 granular hooke 1e4 {} tangential linear_history 1e4 0.0 5e-1 damping {} rolling sds {} 0 {}",
                num(damping(code, 1.6, false).1),
                damping(code, 1.6, false).0,
                num(k),
                num(m)
            );
            assert!(
                input.contains(&line),
                "{code}: missing `{line}` in {:?}",
                input
                    .lines()
                    .filter(|l| l.starts_with("pair_coeff 1 5"))
                    .collect::<Vec<_>>()
            );
            // Stage start, damped and plain again in the relaxation: 3 × 15 pairs.
            let lines = input
                .lines()
                .filter(|l| l.starts_with("pair_coeff") && l.contains(" rolling sds "))
                .count();
            assert_eq!(lines, 3 * 15, "{code}");
            // Relaxation: m* = 0.25·1/1.25 = 0.2, γ_roll = 2·0.5·√0.2·6.
            let gamma = 2.0 * 0.5 * 0.2f64.sqrt() * 6.0;
            let (_, g, _) = rolling_sds(&classes, 2, (0, 4), 1.0, 0.005, 0.5);
            assert!((g - gamma).abs() < 1e-12);
            assert!(input.contains(&format!("rolling sds {} {} {}", num(k), num(g), num(m))));
            // settle_factor = 10 on GRC07's 5e-8 F0 a per grain and 1e-4 F0/a: the switch only.
            assert!(input.contains(
                "variable rest1 equal (c_eks1/200<5e-7)*(abs(c_pvir[1]-1e-2)<1e-3)*(abs(c_pvir[2]-1e-2)<1e-3)"
            ));
            assert!(input.contains("(v_kpg<5e-8)"));
            // The scene's servo gain (numerics.servo_gain = 2.25e-3), not the decks' own: the
            // stress control and the unremapped velocities are then ours, no deviation line.
            let servo = match code {
                Code::Lammps => "variable r1xraw equal 2.25e-3*(f_avp1[1]-1e-2)/1e-2",
                _ => "fix baro all deform/pressure 1 x pressure 1e-2 2.25e-3 y pressure 1e-2 2.25e-3 max/rate 2e-3",
            };
            assert!(input.contains(servo), "{code}: no `{servo}`");
            assert!(
                !deck.deviations.iter().any(|d| d.starts_with("stress")
                    || d.starts_with("affine-velocity")
                    || d.starts_with("remap")),
                "{code}: {:?}",
                deck.deviations
            );
        }
    }

    /// `criteria.quench` (AR07 §III.A): LAMMPS stops on every criterion but the kinetic one,
    /// zeroes velocities and spins and judges again one check later; YADE does it in its check;
    /// LIGGGHTS, without `set … omega`, refuses the scene.
    #[test]
    fn quench_decks_zero_the_velocities_where_only_the_kinetic_criterion_fails() {
        let start = library_start("ar07-D-10kPa-n1372-quench");
        for code in [Code::Lammps, Code::Lammps2025] {
            let input = &super::super::deck(&start, code).unwrap().files[0].1;
            for line in [
                "variable q1 equal (c_fmax[1]<1e-4)*(c_fmax[2]<1e-4)*(abs(c_pvir[1]-1)<1e-4)",
                "fix halt all halt 200 v_q1 > 0.5 error continue\nrun ${end1} upto\nunfix halt\nlabel judge1\n",
                "if \"${q1} < 0.5\" then \"jump SELF quench1\"\nvelocity all set 0.0 0.0 0.0\nset group all omega 0.0 0.0 0.0\n",
                "run 200\njump SELF judge1\nlabel done1\n",
            ] {
                assert!(input.contains(line), "{code:?} lacks {line}:\n{input}");
            }
        }
        let yade = &super::super::deck(&start, Code::Yade).unwrap().files[0].1;
        assert!(yade.contains("tol_kinetic=1e-8, quench=True)"), "{yade}");
        assert!(yade.contains("    elif rest and st['quench']:\n"));
        let refusal = super::super::deck(&start, Code::Liggghts).unwrap_err();
        assert!(
            refusal.to_string().contains("velocity-quench unsupported"),
            "{refusal}"
        );
        // Without `quench` none of it is written.
        let plain = library_start("ar07-D-10kPa-n1372");
        let input = &super::super::deck(&plain, Code::Lammps).unwrap().files[0].1;
        assert!(!input.contains("velocity all set") && !input.contains("variable q1"));
    }

    /// A frictional scene without the servo keeps Berendsen, and says that LAMMPS's velocities
    /// do not see the affine strain rate.
    #[test]
    fn berendsen_decks_name_the_affine_velocity_deviation() {
        let start = library_start("xcode-smoke");
        let deck = super::super::deck(&start, Code::Lammps).unwrap();
        assert!(deck.files[0].1.contains("press/berendsen"));
        assert!(deck
            .deviations
            .iter()
            .any(|d| d.starts_with("affine-velocity: the box change remaps positions")));
    }
}
