//! The scene features a code may express, and how it expresses each (the capability matrix's
//! rows and cells; [`super::capability`] fills the matrix).

/// How a code expresses a feature.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Support {
    Exact,
    Approximate(&'static str),
    Unsupported(&'static str),
}

impl Support {
    pub fn label(self) -> &'static str {
        match self {
            Support::Exact => "exact",
            Support::Approximate(_) => "approximate",
            Support::Unsupported(_) => "unsupported",
        }
    }
    /// Table cell: `exact`, or the label with its reason.
    pub fn cell(self) -> String {
        match self.reason() {
            "" => self.label().to_string(),
            r => format!("{}: {r}", self.label()),
        }
    }
    pub fn reason(self) -> &'static str {
        match self {
            Support::Exact => "",
            Support::Approximate(r) | Support::Unsupported(r) => r,
        }
    }
}

/// A feature a scene may use (rows of the matrix).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Feature {
    /// Hertz normal force N = (Ẽ√a/3) h^{3/2} (AR07 (1)).
    HertzNormal,
    /// K_T = (2−2ν)/(2−ν) K_N(h), incremental tangential force (AR07 (3)).
    MindlinTangential,
    /// T scaled down by the K_T ratio when N decreases (AR07 App. A).
    MindlinUnloading,
    /// Normal damping ζ of critical with α ∝ √(m K_N(h)) (AR07 (5)).
    HertzDamping,
    /// Linear K_N, K_T (GRC07 (4), (7)).
    LinearSprings,
    /// Linear normal dashpot ζ of critical (GRC07 (6)).
    LinearDamping,
    /// Coulomb cap |T| ≤ μ N_e on the elastic normal force (AR07 (4), GRC07 (8)).
    Coulomb,
    /// μ = ∞: contacts never slide.
    NoSlip,
    /// Contact pull −F0 and linear attraction over the gap D0 (GRC07 (4)–(5)).
    Adhesion,
    /// Adhesion between grains of more than [`MAX_CLASSES`](super::lammps_table::MAX_CLASSES) distinct diameters (continuous
    /// sizes): the attraction depends on each pair's R_i + R_j.
    AdhesionContinuousSizes,
    /// LIGGGHTS 3.8's `cohesion sjkr`: attraction k·πa² in contact, πa² the area of the
    /// spheres' intersection circle (`engine/src/contact/sjkr.rs`).
    SjkrCohesion,
    /// YADE's DMT adhesion: a constant pull 4πR*γ in contact, its dashpot capped at the pull
    /// while the contact is tensile (`engine/src/contact/dmt.rs`).
    DmtAdhesion,
    /// Rolling spring K_r with cap μ_r N_e (GRC07 (9)–(10)).
    Rolling,
    /// Rolling resistance between grains of more than [`MAX_CLASSES`](super::lammps_table::MAX_CLASSES)
    /// distinct diameters: K_r and μ_r become per-pair coefficients through R*.
    RollingContinuousSizes,
    /// Tangential/rolling viscosity (grainbench option, not in GRC07).
    TangentialDamping,
    /// Disks in 2D.
    Disks,
    /// Polydisperse grains (GRC07: d uniform in [a/2, a]).
    Polydisperse,
    /// Stress-controlled periodic cell with a strain-rate cap (AR07 (6)–(8), (23); GRC08 I_a).
    StressControl,
    /// Stress control by the scene's first-order servo with no cell mass (`numerics.servo_gain`:
    /// ε̇_α = g·(σ_αα − P)/P, at most the cap) instead of AR07 (7).
    StressServo,
    /// Grain and contact velocities see the cell's strain rate (AR07 (6): the dashpot and the
    /// tangential spring see Δu + ε̇·r).
    AffineVelocity,
    /// Positions follow the cell, velocities do not (`numerics.affine_velocity = false`,
    /// LAMMPS's `remap x`).
    RemapPositionsOnly,
    /// Fixed periodic cell.
    FixedCell,
    /// Stop when all grains form one cluster (GRC07 method 2).
    OneClusterStop,
    /// Several stages with pressure or κ changes (AR07 T.III QS, GRC07 series B, GRC08).
    MultiStage,
    /// Equilibrium criteria on forces, stress and kinetic energy (AR07 §III, GRC07 §II.D).
    EquilibriumCriteria,
    /// Background damping once the interaction list has settled (`relax`: GRC07's law alone
    /// leaves rolling and tangential modes undamped; engine/src/run/relax.rs).
    FinalRelaxation,
    /// The relaxation's switch on the pressure averaged over `settle_time`
    /// (`relax.mean_stress`, GRC08 pressure programs).
    RelaxMeanStress,
    /// FIRE in place of the damping after the switch (`relax.method = "fire"`, frictionless
    /// stages).
    FireRelaxation,
    /// Velocities and spins set to zero at a check where only the kinetic criterion fails
    /// (`criteria.quench`, AR07 §III.A).
    VelocityQuench,
    /// Hard-grain stages before the first DEM stage (melting, growth, expansion).
    HardGrainPrelude,
    /// Hard-grain stages between DEM stages (AR07 §IV.B state C: expand, mix, compress again).
    HardGrainInterlude,
    /// Per-contact dump (pair, branch, N, T, rolling moment).
    ContactDump,
}

impl Feature {
    pub const ALL: [Feature; 32] = [
        Feature::HertzNormal,
        Feature::MindlinTangential,
        Feature::MindlinUnloading,
        Feature::HertzDamping,
        Feature::LinearSprings,
        Feature::LinearDamping,
        Feature::Coulomb,
        Feature::NoSlip,
        Feature::Adhesion,
        Feature::AdhesionContinuousSizes,
        Feature::SjkrCohesion,
        Feature::DmtAdhesion,
        Feature::Rolling,
        Feature::RollingContinuousSizes,
        Feature::TangentialDamping,
        Feature::Disks,
        Feature::Polydisperse,
        Feature::StressControl,
        Feature::StressServo,
        Feature::AffineVelocity,
        Feature::RemapPositionsOnly,
        Feature::FixedCell,
        Feature::OneClusterStop,
        Feature::MultiStage,
        Feature::EquilibriumCriteria,
        Feature::FinalRelaxation,
        Feature::RelaxMeanStress,
        Feature::FireRelaxation,
        Feature::VelocityQuench,
        Feature::HardGrainPrelude,
        Feature::HardGrainInterlude,
        Feature::ContactDump,
    ];

    pub fn key(self) -> &'static str {
        match self {
            Feature::HertzNormal => "hertz-normal",
            Feature::MindlinTangential => "mindlin-tangential",
            Feature::MindlinUnloading => "mindlin-unloading",
            Feature::HertzDamping => "hertz-damping",
            Feature::LinearSprings => "linear-springs",
            Feature::LinearDamping => "linear-damping",
            Feature::Coulomb => "coulomb",
            Feature::NoSlip => "no-slip",
            Feature::Adhesion => "adhesion",
            Feature::AdhesionContinuousSizes => "adhesion-continuous-sizes",
            Feature::SjkrCohesion => "sjkr-cohesion",
            Feature::DmtAdhesion => "dmt-adhesion",
            Feature::Rolling => "rolling-resistance",
            Feature::RollingContinuousSizes => "rolling-continuous-sizes",
            Feature::TangentialDamping => "tangential-damping",
            Feature::Disks => "disks-2d",
            Feature::Polydisperse => "polydisperse",
            Feature::StressControl => "stress-control",
            Feature::StressServo => "stress-servo",
            Feature::AffineVelocity => "affine-velocity",
            Feature::RemapPositionsOnly => "remap-positions-only",
            Feature::FixedCell => "fixed-cell",
            Feature::OneClusterStop => "one-cluster-stop",
            Feature::MultiStage => "multi-stage",
            Feature::EquilibriumCriteria => "equilibrium-criteria",
            Feature::FinalRelaxation => "final-relaxation",
            Feature::RelaxMeanStress => "relax-mean-stress",
            Feature::FireRelaxation => "fire-relaxation",
            Feature::VelocityQuench => "velocity-quench",
            Feature::HardGrainPrelude => "hard-grain-prelude",
            Feature::HardGrainInterlude => "hard-grain-interlude",
            Feature::ContactDump => "contact-dump",
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            Feature::HertzNormal => "Hertz normal force N = (Ẽ√a/3)h^3/2 (AR07 (1))",
            Feature::MindlinTangential => "K_T = (2-2ν)/(2-ν) K_N(h), incremental T (AR07 (3))",
            Feature::MindlinUnloading => "T scaled down with K_T when N drops (AR07 App. A)",
            Feature::HertzDamping => "normal damping ζ of critical, α ∝ √(m K_N(h)) (AR07 (5))",
            Feature::LinearSprings => "linear K_N, K_T (GRC07 (4), (7))",
            Feature::LinearDamping => "linear normal dashpot, ζ of critical (GRC07 (6))",
            Feature::Coulomb => "Coulomb |T| ≤ μ N_e on the elastic normal force",
            Feature::NoSlip => "μ = ∞: contacts never slide",
            Feature::Adhesion => "pull -F0 in contact, linear attraction over D0 (GRC07 (4)-(5))",
            Feature::AdhesionContinuousSizes => "adhesion between continuously distributed diameters (more than 16 distinct; `particles.classes` gives classes)",
            Feature::SjkrCohesion => "LIGGGHTS `cohesion sjkr`: attraction k·πa² in contact (a: radius of the contact circle)",
            Feature::DmtAdhesion => "YADE's DMT adhesion: constant pull 4πR*γ in contact (`includeAdhesion`)",
            Feature::Rolling => "rolling spring K_r, cap μ_r N_e (GRC07 (9)-(10))",
            Feature::RollingContinuousSizes => "rolling resistance between continuously distributed diameters (more than 16 distinct; `particles.classes` gives classes)",
            Feature::TangentialDamping => "tangential/rolling viscosity (grainbench option)",
            Feature::Disks => "2D disks",
            Feature::Polydisperse => "diameters uniform in [d_min a, a]",
            Feature::StressControl => "isotropic stress control with a strain-rate cap",
            Feature::StressServo => {
                "stress control by a first-order servo g·(σ − P)/P, no cell mass (`numerics.servo_gain`)"
            }
            Feature::AffineVelocity => {
                "contact velocities include the affine strain rate ε̇·r (AR07 (6))"
            }
            Feature::RemapPositionsOnly => {
                "the cell moves positions, not velocities (`numerics.affine_velocity = false`)"
            }
            Feature::FixedCell => "fixed periodic cell",
            Feature::OneClusterStop => "stop when all grains form one cluster (GRC07 method 2)",
            Feature::MultiStage => "several DEM stages (pressure or κ programs)",
            Feature::EquilibriumCriteria => "force, moment, stress and kinetic-energy criteria",
            Feature::FinalRelaxation => {
                "background damping once the interaction list has settled (`relax`)"
            }
            Feature::RelaxMeanStress => {
                "the relaxation's switch tests the pressure averaged over settle_time (`relax.mean_stress`)"
            }
            Feature::FireRelaxation => {
                "FIRE (Bitzek et al. 2006) on grains and cell after the switch, no normal dashpot (`relax.method = \"fire\"`)"
            }
            Feature::VelocityQuench => {
                "velocities and spins zeroed at a check where only the kinetic criterion fails (`criteria.quench`, AR07 §III.A)"
            }
            Feature::HardGrainPrelude => "hard-grain stages before the first DEM stage",
            Feature::HardGrainInterlude => "hard-grain stages between DEM stages (AR07 state C)",
            Feature::ContactDump => "per-contact dump: pair, branch, N, T, rolling moment",
        }
    }
}
