//! The capability matrix: for each scene feature and each code, `exact`, `approximate` (with
//! the deviation) or `unsupported` (with what is missing). Entries marked exact are checked by
//! a two-particle deck test per code (`tests/externals.rs`); the sources are the codes'
//! manuals and the observations in `docs/external-codes.md`.

pub use super::feature::{Feature, Support};
use super::lammps_table::Classes;
use super::{Code, StageKind, Start};
use grainbench_engine::scene::{Law, Mu, RelaxMethod};

/// The features `start` uses.
pub fn features(start: &Start) -> Vec<Feature> {
    let mut f = Vec::new();
    let any_mu = |pred: &dyn Fn(Mu) -> bool| start.stages.iter().any(|s| pred(s.mu));
    match start.law() {
        Law::HertzMindlin { sjkr, dmt, .. } => {
            f.push(Feature::HertzNormal);
            f.push(Feature::HertzDamping);
            if sjkr.is_some() {
                f.push(Feature::SjkrCohesion);
            }
            if dmt.is_some() {
                f.push(Feature::DmtAdhesion);
            }
            if any_mu(&|m| m.value() > 0.0) {
                f.push(Feature::MindlinTangential);
                f.push(Feature::MindlinUnloading);
            }
        }
        Law::Linear {
            zeta,
            tangential_damping,
            cohesion,
            rolling,
            ..
        } => {
            f.push(Feature::LinearSprings);
            if *zeta > 0.0 {
                f.push(Feature::LinearDamping);
            }
            // More distinct diameters than per-type-pair coefficients can hold.
            let continuous = Classes::of(start).is_none();
            if cohesion.is_some() {
                f.push(Feature::Adhesion);
                if continuous {
                    f.push(Feature::AdhesionContinuousSizes);
                }
            }
            if rolling.is_some() {
                f.push(Feature::Rolling);
                if continuous {
                    f.push(Feature::RollingContinuousSizes);
                }
            }
            if *tangential_damping > 0.0 {
                f.push(Feature::TangentialDamping);
            }
        }
    }
    if any_mu(&|m| matches!(m, Mu::Finite(x) if x > 0.0)) {
        f.push(Feature::Coulomb);
    }
    if any_mu(&|m| m == Mu::Infinite) {
        f.push(Feature::NoSlip);
    }
    if start.dimension == 2 {
        f.push(Feature::Disks);
    }
    if start.scene.particles.min_diameter < 1.0 {
        f.push(Feature::Polydisperse);
    }
    let kinds = |pred: &dyn Fn(&StageKind) -> bool| start.stages.iter().any(|s| pred(&s.kind));
    if kinds(&|k| matches!(k, StageKind::Compress { .. })) {
        let n = &start.scene.numerics;
        f.push(if n.servo_gain.is_some() {
            Feature::StressServo
        } else {
            Feature::StressControl
        });
        f.push(if n.affine_velocity {
            Feature::AffineVelocity
        } else {
            Feature::RemapPositionsOnly
        });
    }
    if kinds(&|k| matches!(k, StageKind::FixedVolume { .. } | StageKind::Aggregate)) {
        f.push(Feature::FixedCell);
    }
    if kinds(&|k| matches!(k, StageKind::Aggregate)) {
        f.push(Feature::OneClusterStop);
    }
    if start.stages.len() > 1 {
        f.push(Feature::MultiStage);
    }
    f.push(Feature::EquilibriumCriteria);
    let method = |m: RelaxMethod| {
        start
            .scene
            .stages()
            .iter()
            .any(|(_, s)| s.relax().is_some_and(|r| r.method == m))
    };
    if method(RelaxMethod::Damping) {
        f.push(Feature::FinalRelaxation);
    }
    if method(RelaxMethod::Fire) {
        f.push(Feature::FireRelaxation);
    }
    if start
        .scene
        .stages()
        .iter()
        .any(|(_, s)| s.relax().is_some_and(|r| r.mean_stress))
    {
        f.push(Feature::RelaxMeanStress);
    }
    if start.stages.iter().any(|s| s.quench) {
        f.push(Feature::VelocityQuench);
    }
    if !start.prelude.is_empty() {
        f.push(Feature::HardGrainPrelude);
    }
    if !start.interlude.is_empty() {
        f.push(Feature::HardGrainInterlude);
    }
    f.push(Feature::ContactDump);
    f.sort();
    f.dedup();
    f
}

const REMAP: &str = "the box change remaps positions (`remap x`), not velocities: the dashpot and the tangential spring see Δv without ε̇·r";

const RELAX: &str =
    "the switch to background damping on a settled interaction list is not generated";

const FIRE: &str = "the deck runs the law's own dynamics to the criteria, AR07's protocol, in place of FIRE (no FIRE with the cell among its degrees of freedom is generated); on AR07 A the FIRE states are the same to ΔΦ < 1e-5, z* within about one seed s.d. (docs/performance.md)";

const NO_ROLLING: &str = "no rolling resistance at all (see `rolling-resistance`)";

const NO_GRC07_ADHESION: &str = "no GRC07 adhesion at all (see `adhesion`)";

const INTERLUDE: &str = "no event-driven hard-grain dynamics; grainbench prepares hard-grain stages only before the first DEM stage";

/// The matrix.
pub fn support(code: Code, f: Feature) -> Support {
    use Feature as F;
    use Support::*;
    match code {
        Code::Rust => Exact,
        // The format describes every feature; grainbench runs the prelude itself.
        Code::Generic => match f {
            F::HardGrainInterlude => Unsupported(INTERLUDE),
            _ => Exact,
        },
        Code::Adapter(a) => match f {
            F::HardGrainPrelude => Exact,
            F::HardGrainInterlude => Unsupported(INTERLUDE),
            _ => a.support(f),
        },
        // Exact entries checked for each version by comparisons/tests/lammps_two_particle.rs
        // within 1e-3: Hertz normal force, damping (2021: Tsuji's negative root; 2025: Tsuji's
        // root above 1 at ζ = 0.98, equal and unequal masses), Mindlin K_T, rescale on unloading
        // (3D spheres); hooke K_N, damping (2025: coeff_restitution), linear_history K_T (2D
        // disks); the GRC07 adhesion, 2025 by lepton/sphere, 2021 by per-class tables (normal force at seven gaps and
        // overlaps, with damping, and K_T through the overlay). Disk inertia (nve/sphere disc)
        // is not tested.
        Code::Lammps | Code::Lammps2025 => match f {
            F::Coulomb => Approximate("Coulomb cap uses the total normal force (damping included)"),
            F::NoSlip => Approximate("μ = ∞ given as μ = 1e300"),
            F::Adhesion => Exact,
            F::AdhesionContinuousSizes if code == Code::Lammps2025 => Exact,
            F::SjkrCohesion => Unsupported("no area-proportional cohesion in `granular` (`dmt` and `jkr` are other laws); not generated"),
            F::DmtAdhesion => Unsupported("`granular dmt` has the same pull but neither YADE's capped dashpot nor its Coulomb cap; not generated"),
            F::AdhesionContinuousSizes => Unsupported("pair_style table sees only r and the atom types, so the attraction is one table per pair of diameter classes: give the scene `particles.classes` (at most 16)"),
            F::Rolling => Approximate("`rolling sds` per pair of diameter classes, k_roll = K_r/R*², μ_roll = μ_r/R*: the moment cap uses the total normal force (damping included)"),
            F::RollingContinuousSizes => Unsupported("`rolling sds` takes K_r/R*² and μ_r/R* per pair of atom types: give the scene `particles.classes` (at most 16)"),
            F::TangentialDamping => Unsupported("tangential damping in `linear_history` is not generated"),
            F::StressControl => Approximate("fix press/berendsen aniso on the virial stress: each axis' strain rate is (P − σ_αα)/(3Bτ), at the cap only while σ_αα ≈ 0, no cell mass"),
            F::AffineVelocity => Approximate(REMAP),
            F::OneClusterStop => Unsupported("no cluster count to stop on"),
            F::RelaxMeanStress => Unsupported("the switch is tested on the stress at the end of each settle_time chunk, not on its mean over the chunk; not generated"),
            F::FireRelaxation => Approximate(FIRE),
            F::VelocityQuench => Approximate("`velocity all set 0 0 0` and `set group all omega 0 0 0` where the stage's `fix halt` stops on the force, moment and stress criteria (judged as `equilibrium-criteria`); Berendsen has no cell velocity to zero"),
            F::FinalRelaxation => Approximate("switch tested at the end of each settle_time chunk on the contact count (compute contact/atom: touching pairs, not the interaction list) with the kinetic and stress criteria (settle_time = 0: at every check by fix halt, on those criteria alone, as ours); damping by fix langevin at T = 0 (drag −γ m v exact, spins at LAMMPS's rotational rate); tangential dashpot inside the Coulomb cap; window checked by fix halt runs"),
            F::HardGrainInterlude => Unsupported(INTERLUDE),
            F::MultiStage => Approximate("each stage restarts the barostat; contact history carries over"),
            F::EquilibriumCriteria => Approximate("same measures (free spins of grains without contact left out), checked every check_every steps by fix halt on forces computed before that step's Berendsen dilation"),
            _ => Exact,
        },
        Code::Liggghts => match f {
            F::MindlinTangential => Approximate("K_T = 8G*√(R*h) is ours, but `tangential history` gives T = K_T(h)·(accumulated tangential displacement), not an incremental T"),
            F::LinearSprings | F::LinearDamping => Unsupported("hooke/stiffness decks are not generated for LIGGGHTS"),
            F::MindlinUnloading => Approximate("`tangential history` is a total-displacement law: T is not rescaled when N drops"),
            F::HertzDamping => Approximate("ζ = √(5/6)·|ln e|/√(ln²e + π²) with the restitution e in (0.05, 1]: ζ capped at 0.630 (e = 0.0501)"),
            F::Coulomb => Approximate("Coulomb cap includes the damping normal force"),
            F::NoSlip => Approximate("μ = ∞ given as μ = 1e300"),
            F::Adhesion => Unsupported("cohesion sjkr/sjkr2 give a force ∝ contact area, zero at first touch, with no range"),
            F::AdhesionContinuousSizes => Unsupported(NO_GRC07_ADHESION),
            F::SjkrCohesion => Exact,
            F::DmtAdhesion => Unsupported("no constant-pull cohesion model (sjkr/sjkr2 are ∝ contact area)"),
            F::Rolling => Unsupported("rolling_friction epsd3 not generated"),
            F::RollingContinuousSizes => Unsupported(NO_ROLLING),
            F::TangentialDamping => Unsupported("no tangential damping option is generated"),
            F::Disks => Unsupported("2D decks not generated for LIGGGHTS"),
            F::StressControl => Approximate("no barostat fix: per-axis servo of fix deform, strain rate ∝ virial stress error (full cap beyond 50 % of the target), no cell mass"),
            F::StressServo => Approximate("per-axis servo of fix deform with its own gain (full cap beyond 50 % of the target), not the scene's g"),
            F::AffineVelocity => Approximate(REMAP),
            F::OneClusterStop => Unsupported("no cluster count to stop on"),
            F::FinalRelaxation | F::RelaxMeanStress => Unsupported(RELAX),
            F::FireRelaxation => Approximate(FIRE),
            F::VelocityQuench => Unsupported("LIGGGHTS 3.8 has no `set … omega` to zero the spins; not generated"),
            F::HardGrainInterlude => Unsupported(INTERLUDE),
            F::MultiStage => Approximate("each stage restarts the servo; contact history carries over"),
            F::EquilibriumCriteria => Approximate("criteria as ours (kinetic energy: translation of all grains, rotation of grains with a contact), checked between runs of check_every steps"),
            _ => Exact,
        },
        Code::Yade => match f {
            F::MindlinTangential => Approximate("K_T exact; Ig2_Sphere_Sphere_ScGeom scales the relative translational slip by (R1+R2)/d = 1 + h/(R1+R2)"),
            F::MindlinUnloading => Approximate("Law2_ScGeom_MindlinPhys_Mindlin keeps T when N drops"),
            F::HertzDamping => Approximate("total normal force clipped at 0 without adhesion (no viscous pull while separating: restitution 0.423 instead of 0.335 at ζ = 0.3, 0.12 instead of capture at ζ = 0.98), a clipped contact loses its tangential force"),
            F::Coulomb => Approximate("Coulomb cap uses the total normal force (viscous part included)"),
            F::NoSlip => Approximate("μ = ∞ given as friction angle atan(1e300) (tan ≈ 1.6e16); T still drops to 0 while the total normal force is clipped"),
            F::LinearSprings | F::LinearDamping => Unsupported("Law2_ScGeom_FrictPhys_CundallStrack has no dashpot and ViscElPhys is wrong in a deforming periodic cell"),
            F::Adhesion => Unsupported("CohFrictMat gives a spring to −F0 then constant −F0 (not generated)"),
            F::AdhesionContinuousSizes => Unsupported(NO_GRC07_ADHESION),
            F::SjkrCohesion => Unsupported("no area-proportional cohesion law (CohFrictMat bonds are another law)"),
            F::DmtAdhesion => Exact,
            F::Rolling => Unsupported("moment law not generated"),
            F::RollingContinuousSizes => Unsupported(NO_ROLLING),
            F::TangentialDamping => Unsupported("no tangential damping option is generated"),
            F::Disks => Unsupported("2D disks (blockedDOFs emulation) not generated"),
            F::StressControl => Approximate("AR07 (7) cell dynamics and rate cap integrated by a script servo (PyRunner each step, O.cell.velGrad) on the contact stress only; PeriTriaxController hunted around 1.01–1.09 P"),
            F::StressServo => Approximate("the script servo integrates AR07 (7) with a cell mass, not the scene's first-order servo"),
            F::RemapPositionsOnly => Approximate("bodies carry the cell's velocity field (homoDeform): contact velocities include ε̇·r"),
            F::OneClusterStop => Unsupported("no cluster count to stop on"),
            F::FinalRelaxation | F::RelaxMeanStress => Unsupported(RELAX),
            F::FireRelaxation => Approximate(FIRE),
            F::VelocityQuench => Approximate("velocities, spins and the servo's cell rate zeroed in the check PyRunner where the force, moment and stress criteria hold (judged as the deck's other criteria)"),
            F::HardGrainInterlude => Unsupported(INTERLUDE),
            F::MultiStage => Approximate("κ and μ changes rescale kno, kso and tan φ of existing contacts (not checked by a test)"),
            _ => Exact,
        },
    }
}

/// The table's header: one column per external code.
pub fn header() -> String {
    header_for(&Code::EXTERNAL)
}

/// The table's header for `codes`.
pub fn header_for(codes: &[Code]) -> String {
    let names: Vec<&str> = codes.iter().map(|c| c.name()).collect();
    format!(
        "| feature | {} |\n| --- |{}",
        names.join(" | "),
        " --- |".repeat(names.len())
    )
}

/// The matrix as a Markdown table.
pub fn markdown() -> String {
    markdown_for(&Code::EXTERNAL)
}

/// The matrix of `codes` as a Markdown table.
pub fn markdown_for(codes: &[Code]) -> String {
    let mut s = header_for(codes) + "\n";
    for f in Feature::ALL {
        s.push_str(&format!("| `{}` {} |", f.key(), f.describe()));
        for &c in codes {
            s.push_str(&format!(" {} |", support(c, f).cell()));
        }
        s.push('\n');
    }
    s
}
