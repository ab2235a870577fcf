//! LIGGGHTS 3.8.0 deck generator (`docs/external-codes.md`).
//!
//! * Law: `pair_style gran model hertz tangential history tangential_damping on` with
//!   `youngsModulus` E = Ẽ(1−ν²) (LIGGGHTS's Y* = E/(2(1−ν²)) for identical materials, so its
//!   normal force (4/3)Y*√(R*h)·h is our (2/3)Ẽ√(R*h)·h), `poissonsRatio` ν (its
//!   K_T = 8G*√(R*h) is our (2−2ν)/(2−ν)·K_N), `coefficientRestitution` from ζ (see
//!   [`restitution`]) and `coefficientFriction` μ (μ = ∞ as 1e300). `units si` with reduced
//!   numbers: `soft_particles yes` lifts the E ≥ 5e6 check. With friction, tangential damping
//!   (at the same fraction of critical as the normal one, on K_T) is kept on, a deviation: with
//!   it off, the smoke packing kept 1.8e-8 kinetic energy per grain in a grain rocking on one
//!   contact. Frictionless scenes turn it off (no tangential force at all, as ours).
//! * Cohesion: `cohesion sjkr` with `cohesionEnergyDensity` k when the scene's Hertz–Mindlin law
//!   has `sjkr = k` (the same law as engine/src/contact/sjkr.rs; LIGGGHTS adds it to the
//!   normal force its tangential model caps with, as ours does).
//! * Stress control: LIGGGHTS has no barostat fix. A servo: `fix ave/time` of the virial
//!   pressure compute feeds `fix deform … variable`, with per-axis strain rates
//!   ε̇_α = cap·clamp((σ_αα − P_target)/(w·P_target), −1, 1) ([`SERVO_BAND`] = w), so the cell
//!   moves at the cap far from the target and slows down proportionally within w of it. Each
//!   axis has its own rate as in our engine (AR07 (7)): an isotropic rate leaves diagonal
//!   stresses apart by several % and the per-axis stress criterion never holds.
//! * Kinetic energy per grain: translation of all grains plus rotation of grains with a
//!   contact (`compute contact/atom`), as our engine counts it (free spins of rattlers are
//!   never damped).
//! * Stages run in chunks of `check_every` steps; after each chunk an `if` tests the
//!   equilibrium criteria and `jump`s out (this LIGGGHTS has no `fix halt`).
//! * Output: `final.atoms` (dump custom: id radius mass x y z vx vy vz omegax omegay
//!   omegaz), `final.contacts` (dump local of `compute pair/gran/local id force delta`:
//!   id1 id2 periodic-flag fx fy fz delta, force on the first grain), `final.status`
//!   (`equilibrium` or `time-limit`), `final.time` (elapsed time and step).

use super::{header_lines, num, Code, Deck, PlanStage, StageKind, Start};
use grainbench_engine::scene::Law;
use std::fmt::Write as _;

/// The columns of a contact dump (`compute pgl all pair/gran/local id force delta`): id1 id2
/// periodic-flag fx fy fz delta.
const CONTACT_COLUMNS: &str = "c_pgl[1] c_pgl[2] c_pgl[3] c_pgl[4] c_pgl[5] c_pgl[6] c_pgl[7]";

/// Smallest restitution LIGGGHTS 3.8.0 accepts (it requires 0.05 < e ≤ 1).
pub const MIN_RESTITUTION: f64 = 0.0501;

/// Relative pressure error over which the servo's strain rate goes from 0 to the cap.
pub const SERVO_BAND: f64 = 0.5;

/// LIGGGHTS's Hertz damping: γ_n = 2√(5/6)·|β|·√(S_n m*) with S_n = 2Y*√(R*h) = our K_N and
/// β = ln e/√(ln²e + π²), i.e. ζ = √(5/6)|β| of our α = 2ζ√(m* K_N). Returns (e, effective ζ):
/// e is clamped to [[`MIN_RESTITUTION`], 1], so ζ is capped near 0.63.
pub fn restitution(zeta: f64) -> (f64, f64) {
    let pi = std::f64::consts::PI;
    let beta = zeta / (5.0f64 / 6.0).sqrt();
    let e = if beta >= 1.0 {
        0.0
    } else {
        (-pi * beta / (1.0 - beta * beta).sqrt()).exp()
    };
    let e = e.clamp(MIN_RESTITUTION, 1.0);
    let ln = e.ln();
    let zeta_eff = (5.0f64 / 6.0).sqrt() * ln.abs() / (ln * ln + pi * pi).sqrt();
    (e, zeta_eff)
}

/// Does LIGGGHTS's restitution give ζ exactly (ζ ≤ 0.63)? Then the matrix's `hertz-damping`
/// deviation (the cap) does not apply to the deck.
pub fn damping_exact(zeta: f64) -> bool {
    (restitution(zeta).1 - zeta).abs() <= 1e-9 * zeta.max(1.0)
}

/// Young's modulus and Poisson ratio for the Hertz law at stage κ: Ẽ = κ^1.5 (AR07 (21) with
/// P_ref = 1), E = Ẽ(1−ν²).
fn young(kappa: f64, poisson: f64) -> f64 {
    kappa.powf(1.5) * (1.0 - poisson * poisson)
}

/// The LIGGGHTS deck of `start`.
pub fn deck(start: &Start, deviations: &[String]) -> Deck {
    let (poisson, zeta, sjkr) = match start.law() {
        Law::HertzMindlin {
            poisson,
            zeta,
            sjkr,
            ..
        } => (*poisson, *zeta, *sjkr),
        // The capability matrix refuses the linear law for LIGGGHTS.
        Law::Linear { zeta, .. } => (0.0, *zeta, None),
    };
    let (e, zeta_eff) = restitution(zeta);
    let mut devs: Vec<String> = deviations.to_vec();
    if !damping_exact(zeta) {
        devs.push(format!(
            "normal damping ζ = {zeta} given as restitution e = {} (LIGGGHTS needs 0.05 < e ≤ 1): effective ζ = {:.6}",
            num(e),
            zeta_eff
        ));
    }
    let friction = start.stages.iter().any(|st| st.mu.value() > 0.0);
    if zeta_eff > 0.0 && friction {
        devs.push(format!(
            "tangential viscous damping γ_t = 2ζ√(m* K_T) with ζ = {zeta_eff:.6} (LIGGGHTS `tangential_damping on`): without it, grains held by one contact rock without damping and the kinetic-energy criterion is never met"
        ));
    }
    let mut s = String::new();
    for h in header_lines(start, Code::Liggghts, &devs) {
        let _ = writeln!(s, "# {h}");
    }
    let _ = writeln!(
        s,
        "# Run: liggghts -in in.liggghts -log log.liggghts (in this directory).\n\
         # Writes final.atoms, final.contacts (id1 id2 periodic fx fy fz delta; force on id1),\n\
         # final.status (equilibrium | time-limit) and final.time (time step).\n"
    );
    let first = &start.stages[0];
    // Verlet skin: the scene's numerics.skin (a), as in our engine.
    let _ = writeln!(
        s,
        "atom_style granular\natom_modify map array\nboundary p p p\nnewton off\n\
         communicate single vel yes\nunits si\nsoft_particles yes\n\
         read_data data.liggghts\nneighbor {} bin\nneigh_modify delay 0\n",
        num(start.scene.numerics.skin)
    );
    let _ = writeln!(
        s,
        "fix m1 all property/global youngsModulus peratomtype {}\n\
         fix m2 all property/global poissonsRatio peratomtype {}\n\
         fix m3 all property/global coefficientRestitution peratomtypepair 1 {}\n\
         fix m4 all property/global coefficientFriction peratomtypepair 1 {}\n\
         {}pair_style gran model hertz tangential history{} tangential_damping {}\n\
         pair_coeff * *\nfix integr all nve/sphere\n",
        num(young(first.kappa, poisson)),
        num(poisson),
        num(e),
        super::mu_text(first.mu),
        // SJKR (engine/src/contact/sjkr.rs): F = k·πa² in contact, k in units of P_ref.
        match sjkr {
            Some(k) => format!(
                "fix m5 all property/global cohesionEnergyDensity peratomtypepair 1 {}\n",
                num(k)
            ),
            None => String::new(),
        },
        if sjkr.is_some() { " cohesion sjkr" } else { "" },
        // Frictionless: off. With μ = 0 the history model caps T to 0 every step, but a run's
        // setup force pass does not advance the (zero) displacement, so its cap test passes and
        // the dashpot alone acts on the first step of every chunk.
        if friction { "on" } else { "off" },
    );
    // Measures (the pair/gran/local compute must exist before the first run).
    let _ = writeln!(
        s,
        "compute pgl all pair/gran/local id force delta\n\
         compute p all pressure thermo_temp virial\n\
         fix pav all ave/time 1 1 1 c_p[1] c_p[2] c_p[3]\n\
         variable P equal (f_pav[1]+f_pav[2]+f_pav[3])/3\n\
         compute tq all property/atom tqx tqy tqz\n\
         variable fm atom sqrt(fx^2+fy^2+fz^2)\n\
         variable tm atom sqrt(c_tq[1]^2+c_tq[2]^2+c_tq[3]^2)\n\
         compute fmax all reduce max v_fm\n\
         compute tmax all reduce max v_tm\n\
         compute ket all ke\n\
         compute cn all contact/atom\n\
         compute rw all property/atom radius omegax omegay omegaz\n\
         variable er atom (c_cn>0)*0.2*mass*c_rw[1]^2*(c_rw[2]^2+c_rw[3]^2+c_rw[4]^2)\n\
         compute ker all reduce sum v_er\n\
         variable kpg equal (c_ket+c_ker)/atoms\n\
         variable Lxnow equal lx\nvariable Lynow equal ly\nvariable Lznow equal lz\n\
         variable stepnow equal step\n\
         variable tsum equal 0\n\
"
    );
    // The trace (scene output.trace_every); the step gives the time (one time step).
    if let Some(k) = start.trace_steps.filter(|_| start.uniform_dt().is_some()) {
        let _ = writeln!(
            s,
            "# trace: every {k} steps each grain with its force, and each contact\n\
             # (docs/external-formats/liggghts.md)\n\
             dump tr all custom {k} trace.atoms id radius mass x y z vx vy vz omegax omegay omegaz fx fy fz\n\
             dump_modify tr format \"%d {}\"\n\
             dump trc all local {k} trace.contacts {}\n\
             dump_modify trc format \"{}\"",
            vec!["%.17g"; 14].join(" "),
            CONTACT_COLUMNS,
            ["%.17g"; 7].join(" ")
        );
    }
    let mut prev = first;
    for (k, st) in start.stages.iter().enumerate() {
        stage(&mut s, k, st, prev, poisson);
        prev = st;
    }
    let cols = CONTACT_COLUMNS;
    let g17 = |n: usize| vec!["%.17g"; n].join(" ");
    if start.trace_steps.is_some() && start.uniform_dt().is_some() {
        s.push_str("undump tr\nundump trc\n");
    }
    let _ = writeln!(
        s,
        "# ---- final state\n\
         print \"${{st}}\" file final.status\n\
         print \"${{tsum}} ${{stepnow}}\" file final.time\n\
         dump da all custom 1 final.atoms id radius mass x y z vx vy vz omegax omegay omegaz\n\
         dump_modify da format \"%d {}\"\n\
         dump dc all local 1 final.contacts {cols}\n\
         dump_modify dc format \"{}\"\n\
         run 0\n\
         undump da\nundump dc\n\
         print \"grainbench: done (${{st}})\"",
        g17(11),
        g17(7)
    );
    Deck {
        code: Code::Liggghts,
        files: vec![
            ("in.liggghts".into(), s),
            ("data.liggghts".into(), data_file(start)),
        ],
        deviations: devs,
        args: vec![
            "-in".into(),
            "in.liggghts".into(),
            "-log".into(),
            "log.liggghts".into(),
        ],
    }
}

/// Stage `k` of the deck: μ and κ where they change from the stage before (`prev`), the time
/// step, the servo of a compression (per axis, fix deform) and the check loop that ends the
/// stage at equilibrium or at its time limit.
fn stage(s: &mut String, k: usize, st: &PlanStage, prev: &PlanStage, poisson: f64) {
    let k1 = k + 1;
    let _ = writeln!(s, "# ---- stage {k1}: {:?}", st.kind);
    if st.mu != prev.mu {
        let _ = writeln!(
            s,
            "fix m4 all property/global coefficientFriction peratomtypepair 1 {}",
            super::mu_text(st.mu)
        );
    }
    if st.kappa != prev.kappa {
        let _ = writeln!(
            s,
            "fix m1 all property/global youngsModulus peratomtype {}",
            num(young(st.kappa, poisson))
        );
    }
    let _ = writeln!(s, "timestep {}", num(st.dt));
    let tol = &st.tolerances;
    let mut ok = format!(
        "(c_fmax<={})*(c_tmax<={})*(v_kpg<={})",
        num(tol.force),
        num(tol.moment),
        num(tol.kinetic_per_grain)
    );
    let mut thermo = "step atoms v_P f_pav[1] f_pav[2] f_pav[3] c_fmax c_tmax v_kpg lx".to_string();
    match st.kind {
        StageKind::Compress { pressure } => {
            for a in 1..=3 {
                let _ = write!(
                    ok,
                    "*(abs(f_pav[{a}]-{})<={})",
                    num(pressure),
                    num(tol.stress)
                );
            }
            // Per axis: ε̇_α = cap·clamp((σ_αα − P)/(w P), −1, 1), clamp written with abs
            // (no min/max in equal-style variables of this version).
            let dt = num(st.dt);
            for (a, ax) in ["x", "y", "z"].iter().enumerate() {
                let a1 = a + 1;
                let _ = writeln!(
                    s,
                    "variable e{ax}{k1} equal (f_pav[{a1}]-{p})/{w}\n\
                     variable r{ax}{k1} equal {c}*0.5*(abs(v_e{ax}{k1}+1)-abs(v_e{ax}{k1}-1))\n\
                     variable L0{ax}{k1} equal 0\n\
                     variable dL{ax}{k1} equal l{ax}*(1+v_r{ax}{k1}*{dt})-v_L0{ax}{k1}\n\
                     variable vL{ax}{k1} equal l{ax}*v_r{ax}{k1}",
                    p = num(pressure),
                    // Band w·P_target (w in absolute units for a zero target).
                    w = num(SERVO_BAND * if pressure > 0.0 { pressure } else { 1.0 }),
                    c = num(st.max_strain_rate),
                );
            }
            let _ = writeln!(
                s,
                "fix servo all deform 1 x variable v_dLx{k1} v_vLx{k1} y variable v_dLy{k1} v_vLy{k1} z variable v_dLz{k1} v_vLz{k1} remap x"
            );
            thermo.push_str(&format!(" v_rx{k1} v_ry{k1} v_rz{k1}"));
        }
        StageKind::FixedVolume { .. } | StageKind::Aggregate => {}
    }
    let full_time = matches!(st.kind, StageKind::FixedVolume { full_time: true });
    let chunks = st.max_steps.div_ceil(st.check_every).max(1);
    let _ = writeln!(
        s,
        "variable ok{k1} equal {ok}\n\
         thermo_style custom {thermo} v_ok{k1}\n\
         thermo_modify norm no lost ignore\n\
         thermo {ce}\n\
         variable st string time-limit\n\
         variable s0_{k1} equal ${{stepnow}}\n\
         variable n{k1} loop {chunks}\n\
         label loop{k1}",
        ce = st.check_every,
    );
    if matches!(st.kind, StageKind::Compress { .. }) {
        // fix deform sets L = L(run start) + dL: the start lengths of this chunk.
        let _ = writeln!(
            s,
            "variable L0x{k1} equal ${{Lxnow}}\nvariable L0y{k1} equal ${{Lynow}}\nvariable L0z{k1} equal ${{Lznow}}"
        );
    }
    let _ = writeln!(s, "run {}", st.check_every);
    if full_time {
        let _ = writeln!(
            s,
            "if \"${{ok{k1}}} > 0.5\" then \"variable st string equilibrium\" else \"variable st string time-limit\""
        );
    } else {
        let _ = writeln!(
            s,
            "if \"${{ok{k1}}} > 0.5\" then \"variable st string equilibrium\" \"jump SELF done{k1}\""
        );
    }
    let _ = writeln!(
        s,
        "next n{k1}\njump SELF loop{k1}\nlabel done{k1}\n\
         variable tsum equal ${{tsum}}+(${{stepnow}}-${{s0_{k1}}})*{dt}",
        dt = num(st.dt)
    );
    if matches!(st.kind, StageKind::Compress { .. }) {
        let _ = writeln!(s, "unfix servo");
    }
    let _ = writeln!(s, "print \"stage {k1} end: ${{st}}\"\n");
}

/// `read_data` file for `atom_style granular`: id type diameter density x y z, then the
/// velocities (id vx vy vz ωx ωy ωz) when any is nonzero.
fn data_file(start: &Start) -> String {
    let mut s = format!(
        "LIGGGHTS data file written by grainbench (scene {})\n\n{} atoms\n1 atom types\n\n",
        start.scene.name,
        start.n()
    );
    let l3: Vec<f64> = (0..3)
        .map(|a| start.lengths.get(a).copied().unwrap_or(1.0))
        .collect();
    for (a, ax) in ["x", "y", "z"].iter().enumerate() {
        let _ = writeln!(s, "0 {} {ax}lo {ax}hi", num(l3[a]));
    }
    let rho = num(start.density());
    s.push_str("\nAtoms\n\n");
    for (i, (p, d)) in start.position.iter().zip(&start.diameter).enumerate() {
        let c = |a: usize| p.get(a).copied().unwrap_or(0.0);
        let _ = writeln!(
            s,
            "{} 1 {} {rho} {} {} {}",
            i + 1,
            num(*d),
            num(c(0)),
            num(c(1)),
            num(c(2))
        );
    }
    if start.velocity.iter().flatten().any(|&v| v != 0.0) || start.spinning() {
        s.push_str("\nVelocities\n\n");
        for (i, v) in start.velocity.iter().enumerate() {
            let c = |a: usize| v.get(a).copied().unwrap_or(0.0);
            let w = start.spin3(i).map(num);
            let _ = writeln!(
                s,
                "{} {} {} {} {} {} {}",
                i + 1,
                num(c(0)),
                num(c(1)),
                num(c(2)),
                w[0],
                w[1],
                w[2]
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn restitution_maps_zeta() {
        // ζ = 0.3 is representable: the effective ζ round-trips.
        let (e, z) = restitution(0.3);
        assert!(e > MIN_RESTITUTION && e < 1.0);
        assert!((z - 0.3).abs() < 1e-12, "{z}");
        // ζ = 0.98 is capped near 0.63.
        let (e, z) = restitution(0.98);
        assert_eq!(e, MIN_RESTITUTION);
        assert!((z - 0.63).abs() < 0.005, "{z}");
        assert_eq!(restitution(0.0), (1.0, 0.0));
    }

    fn library_deck(name: &str) -> (Deck, String) {
        let scene = grainbench_engine::library::scene(name).unwrap().unwrap();
        let start = Start::of(&scene).unwrap();
        let deck = super::super::deck(&start, Code::Liggghts).unwrap();
        let input = deck.files[0].1.clone();
        (deck, input)
    }

    /// The SJKR scene: `cohesion sjkr` with its energy density, no tangential dashpot
    /// (frictionless), and neither the damping cap nor tangential damping among the deviations
    /// (ζ = 0.5 is exact).
    #[test]
    fn sjkr_deck_adds_the_area_cohesion() {
        let (deck, input) = library_deck("xcode-sjkr-smoke");
        for line in [
            "fix m5 all property/global cohesionEnergyDensity peratomtypepair 1 5e3\n",
            "pair_style gran model hertz tangential history cohesion sjkr tangential_damping off\n",
        ] {
            assert!(input.contains(line), "missing {line:?}");
        }
        // The deviations listed in the deck's header.
        let listed = |input: &str| -> Vec<String> {
            input
                .lines()
                .filter_map(|l| l.strip_prefix("#   - ").map(str::to_string))
                .collect()
        };
        let devs = listed(&input);
        assert!(!devs.is_empty() && devs.len() == deck.deviations.len());
        assert!(
            devs.iter()
                .all(|d| !d.contains("damping") && !d.contains("sjkr")),
            "{devs:?}"
        );
        // Frictional Hertz scenes keep the tangential dashpot and have no cohesion.
        let (_, input) = library_deck("xcode-smoke");
        assert!(input.contains("tangential history tangential_damping on\n"));
        assert!(!input.contains("cohesionEnergyDensity"));
        assert!(listed(&input)
            .iter()
            .any(|d| d.contains("tangential viscous damping")));
    }
}
