//! Reading a scene file and checking every value: errors name the file, the field and what
//! is allowed.

use super::error::SceneError;
use super::{Arrangement, ForceScale, Law, Mu, RelaxMethod, Scene, Step};
use crate::run::layout;
use std::path::Path;

/// Largest `numerics.check_every`: a stop request is honoured within this many steps
/// (with 1e10 the run would not stop on SIGTERM; docs/reliability.md).
pub const MAX_CHECK_EVERY: u64 = 10_000;

/// Thinnest initial gas accepted (tests/fuzz.rs: 1e-300 overflowed the cell grids).
pub const MIN_INITIAL_PACKING_FRACTION: f64 = 1e-3;

/// Range of the stiffness number κ (law and stage overrides).
pub const KAPPA_MIN: f64 = 10.0;
pub const KAPPA_MAX: f64 = 1e12;

/// Below this `min_diameter` the run's cost is worth a warning ([`Scene::warnings`]).
pub const SMALL_MIN_DIAMETER: f64 = 0.1;

/// Largest Φ_I a random sequential placement reaches in reasonable time (RSA jamming limits:
/// 0.547 for disks, 0.384 for spheres, a little less to leave room).
pub fn max_random_packing_fraction(dimension: usize) -> f64 {
    if dimension == 2 {
        0.54
    } else {
        0.37
    }
}

/// The checks' errors for one scene file, and the checks several tables share.
struct Fields<'p> {
    path: &'p Path,
}

impl Fields<'_> {
    fn err(&self, field: &str, message: String) -> SceneError {
        SceneError {
            file: self.path.to_owned(),
            field: field.to_string(),
            message,
        }
    }

    fn positive(&self, field: &str, x: f64) -> Result<(), SceneError> {
        if x.is_finite() && x > 0.0 {
            Ok(())
        } else {
            Err(self.err(field, format!("must be a finite number > 0, got {x}")))
        }
    }

    fn in_range(&self, field: &str, x: f64, lo: f64, hi: f64) -> Result<(), SceneError> {
        if x.is_finite() && x >= lo && x <= hi {
            Ok(())
        } else {
            Err(self.err(field, format!("must lie in [{lo}, {hi}], got {x}")))
        }
    }

    /// κ sets the typical overlap h/a ~ 1/κ (AR07 (3), GRC07 §II.A); 1e-300 underflowed the
    /// stiffness to 0 and the time step to infinity (tests/fuzz.rs).
    fn stiffness(&self, field: &str, k: f64) -> Result<(), SceneError> {
        if k.is_finite() && (KAPPA_MIN..=KAPPA_MAX).contains(&k) {
            Ok(())
        } else {
            Err(self.err(
                field,
                format!("must lie in [{KAPPA_MIN}, {KAPPA_MAX:e}], got {k}: κ sets the typical overlap h/a ~ 1/κ (the papers use 10²–2·10⁵)"),
            ))
        }
    }

    fn mu(&self, field: &str, mu: Mu) -> Result<(), SceneError> {
        match mu {
            Mu::Infinite => Ok(()),
            Mu::Finite(x) if x.is_finite() && x >= 0.0 => Ok(()),
            Mu::Finite(x) => {
                Err(self.err(field, format!("must be a number ≥ 0 or \"inf\", got {x}")))
            }
        }
    }
}

impl Scene {
    /// Parses and validates a scene file.
    pub fn from_file(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: path.to_owned(),
            field: String::new(),
            message: format!("cannot read the file: {e}"),
        })?;
        Self::from_toml(&text, path)
    }

    /// Parses and validates scene text; `path` is used in messages only.
    pub fn from_toml(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let scene: Scene = toml::from_str(text).map_err(|e| SceneError {
            file: path.to_owned(),
            field: String::new(),
            message: e.to_string().trim_end().to_string(),
        })?;
        scene.validate(path)?;
        Ok(scene)
    }

    /// Checks every value, table by table; the first problem found is returned.
    pub fn validate(&self, path: &Path) -> Result<(), SceneError> {
        let ck = Fields { path };
        self.check_particles(&ck)?;
        self.check_law(&ck)?;
        self.check_initial(&ck)?;
        self.check_numerics(&ck)?;
        self.check_protocol(&ck)?;
        self.check_output(&ck)
    }

    /// `name`, `dimension` and `[particles]`.
    fn check_particles(&self, ck: &Fields) -> Result<(), SceneError> {
        if self.name.trim().is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
        {
            return Err(ck.err(
                "name",
                format!(
                    "must be non-empty and use only letters, digits, '-', '_' and '.', got {:?}",
                    self.name
                ),
            ));
        }
        if self.dimension != 2 && self.dimension != 3 {
            return Err(ck.err(
                "dimension",
                format!("must be 2 (disks) or 3 (spheres), got {}", self.dimension),
            ));
        }
        if self.particles.count < 2 {
            return Err(ck.err(
                "particles.count",
                format!("needs at least 2 grains, got {}", self.particles.count),
            ));
        }
        if self.particles.count > u32::MAX as usize / 64 {
            return Err(ck.err(
                "particles.count",
                format!(
                    "at most {} grains are supported, got {}",
                    u32::MAX as usize / 64,
                    self.particles.count
                ),
            ));
        }
        let dmin = self.particles.min_diameter;
        if !(dmin.is_finite() && dmin > 0.0 && dmin <= 1.0) {
            return Err(ck.err(
                "particles.min_diameter",
                format!("must lie in (0, 1] (units of the largest diameter a), got {dmin}"),
            ));
        }
        if let Some(k) = self.particles.classes {
            if k < 2 || dmin >= 1.0 {
                return Err(ck.err(
                    "particles.classes",
                    format!("needs at least 2 classes and min_diameter < 1 (got {k} classes, min_diameter = {dmin}); remove it for equal or continuous sizes"),
                ));
            }
        }
        Ok(())
    }

    /// `[law]`.
    fn check_law(&self, ck: &Fields) -> Result<(), SceneError> {
        let dmin = self.particles.min_diameter;
        match &self.law {
            Law::HertzMindlin {
                kappa,
                mu,
                zeta,
                poisson,
                sjkr,
                dmt,
            } => {
                if self.dimension != 3 {
                    return Err(ck.err(
                        "law.kind",
                        "\"hertz-mindlin\" needs dimension = 3 (Hertz contacts are between spheres); use kind = \"linear\" for disks".into(),
                    ));
                }
                ck.stiffness("law.kappa", *kappa)?;
                ck.mu("law.mu", *mu)?;
                ck.in_range("law.zeta", *zeta, 0.0, 1.0)?;
                if !(poisson.is_finite() && *poisson > -1.0 && *poisson < 0.5) {
                    return Err(ck.err(
                        "law.poisson",
                        format!("must lie in (-1, 0.5), got {poisson}"),
                    ));
                }
                if let Some(k) = sjkr {
                    if !(k.is_finite() && *k >= 0.0) {
                        return Err(ck.err(
                            "law.sjkr",
                            format!("must be a finite cohesion energy density ≥ 0 (units of P_ref), got {k}"),
                        ));
                    }
                }
                if let Some(g) = dmt {
                    if !(g.is_finite() && *g >= 0.0) {
                        return Err(ck.err(
                            "law.dmt",
                            format!(
                                "must be a finite surface energy γ ≥ 0 (units of P_ref·a), got {g}"
                            ),
                        ));
                    }
                    if sjkr.is_some() {
                        return Err(ck.err(
                            "law.dmt",
                            "cannot be combined with law.sjkr: give one cohesion law (LIGGGHTS's sjkr or YADE's dmt)".into(),
                        ));
                    }
                }
            }
            Law::Linear {
                kappa,
                mu,
                zeta,
                kt_over_kn,
                cohesion,
                rolling,
                tangential_damping,
            } => {
                ck.in_range("law.tangential_damping", *tangential_damping, 0.0, 1.0)?;
                ck.stiffness("law.kappa", *kappa)?;
                ck.mu("law.mu", *mu)?;
                ck.in_range("law.zeta", *zeta, 0.0, 1.0)?;
                ck.positive("law.kt_over_kn", *kt_over_kn)?;
                if let Some(c) = cohesion {
                    if !(c.d0.is_finite() && c.d0 > 0.0 && c.d0 < 0.5 * dmin) {
                        return Err(ck.err(
                            "law.cohesion.d0",
                            format!(
                                "must lie in (0, {}) (units of a; less than the smallest radius), got {}",
                                0.5 * dmin,
                                c.d0
                            ),
                        ));
                    }
                }
                if let Some(r) = rolling {
                    ck.positive("law.rolling.kr", r.kr)?;
                    if !(r.mu_r.is_finite() && r.mu_r >= 0.0) {
                        return Err(ck.err(
                            "law.rolling.mu_r",
                            format!("must be a finite number ≥ 0 (units of a), got {}", r.mu_r),
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// `[initial]`.
    fn check_initial(&self, ck: &Fields) -> Result<(), SceneError> {
        let dmin = self.particles.min_diameter;
        let phi = self.initial.packing_fraction;
        let listed = self.initial.particles.is_some() || self.initial.grains.is_some();
        let from_file = self.initial.snapshot.is_some() || listed;
        let starts = [
            self.initial.snapshot.is_some(),
            self.initial.particles.is_some(),
            self.initial.grains.is_some(),
        ];
        if starts.iter().filter(|s| **s).count() > 1 {
            return Err(ck.err(
                "initial",
                "a scene starts from one of `snapshot`, `particles` (a CSV file) or `grains` (listed in the scene), not several".into(),
            ));
        }
        match &self.initial.cell {
            Some(cell) if !listed => {
                return Err(ck.err(
                    "initial.cell",
                    format!("{cell:?} is only read with `initial.particles` or `initial.grains`; remove it, or list the grains"),
                ))
            }
            Some(cell)
                if cell.len() != self.dimension
                    || cell.iter().any(|l| !(l.is_finite() && *l > 0.0)) =>
            {
                return Err(ck.err(
                    "initial.cell",
                    format!(
                        "must list {} positive side lengths (units of a), got {cell:?}",
                        self.dimension
                    ),
                ))
            }
            None if listed => {
                return Err(ck.err(
                    "initial.cell",
                    format!(
                        "a `particles` or `grains` start needs the periodic cell's side lengths, e.g. cell = [{}]",
                        vec!["20.0"; self.dimension].join(", ")
                    ),
                ))
            }
            _ => {}
        }
        match self.initial.arrangement {
            // The grains of a file: Φ_I is theirs.
            _ if from_file => {}
            Arrangement::Random => {
                let phi_max = max_random_packing_fraction(self.dimension);
                if !(phi.is_finite() && phi >= MIN_INITIAL_PACKING_FRACTION && phi <= phi_max) {
                    return Err(ck.err(
                        "initial.packing_fraction",
                        format!(
                            "must lie in [{MIN_INITIAL_PACKING_FRACTION}, {phi_max}]: a random sequential placement of {} cannot reach {phi} (the papers start at 0.13–0.52; a thinner gas only costs compression time)",
                            if self.dimension == 2 { "disks" } else { "spheres" }
                        ),
                    ));
                }
            }
            Arrangement::Fcc => {
                let n = self.particles.count;
                let k = (0..=1000usize).find(|k| 4 * k * k * k >= n).unwrap_or(0);
                if self.dimension != 3 || 4 * k * k * k != n || dmin != 1.0 {
                    return Err(ck.err(
                        "initial.arrangement",
                        format!("\"fcc\" needs dimension = 3, equal diameters (particles.min_diameter = 1) and particles.count = 4k³ (500, 864, 2048, 4000, …), got dimension {} and {n} grains", self.dimension),
                    ));
                }
                let fcc_max = std::f64::consts::PI / (3.0 * 2f64.sqrt());
                if !(phi.is_finite() && phi >= MIN_INITIAL_PACKING_FRACTION && phi < fcc_max) {
                    return Err(ck.err(
                        "initial.packing_fraction",
                        format!("must lie in [{MIN_INITIAL_PACKING_FRACTION}, {fcc_max:.4}) for an FCC lattice, got {phi}"),
                    ));
                }
            }
        }
        if !(self.initial.rms_velocity.is_finite() && self.initial.rms_velocity >= 0.0) {
            return Err(ck.err(
                "initial.rms_velocity",
                format!(
                    "must be a finite number ≥ 0, got {}",
                    self.initial.rms_velocity
                ),
            ));
        }
        Ok(())
    }

    /// `[numerics]`.
    fn check_numerics(&self, ck: &Fields) -> Result<(), SceneError> {
        let n = &self.numerics;
        ck.in_range("numerics.dt_fraction", n.dt_fraction, 1e-6, 0.5)?;
        ck.positive("numerics.stiffness_force", n.stiffness_force)?;
        ck.in_range("numerics.skin", n.skin, 1e-4, 1.0)?;
        ck.positive("numerics.cell_mass", n.cell_mass)?;
        if let Some(g) = n.servo_gain {
            ck.in_range("numerics.servo_gain", g, 1e-12, 1e3)?;
            if let Some(k) = self
                .protocol
                .iter()
                .position(|s| matches!(s, Step::Compress { pressure, .. } if *pressure <= 0.0))
            {
                return Err(ck.err(
                    "numerics.servo_gain",
                    format!(
                        "the servo's rate g·(σ − P)/P needs P > 0, but protocol step {} compresses to P = 0: remove servo_gain (the cell-mass control of AR07 (7) takes P = 0)",
                        k + 1
                    ),
                ));
            }
        }
        if !(1..=MAX_CHECK_EVERY).contains(&n.check_every) {
            return Err(ck.err(
                "numerics.check_every",
                format!(
                    "is {}, must be in [1, {MAX_CHECK_EVERY}]: the criteria, max_time, progress and a stop request (Ctrl-C, SIGTERM) are looked at only every check_every steps, and a check costs about one step",
                    n.check_every
                ),
            ));
        }
        ck.in_range("numerics.max_overlap", n.max_overlap, 1e-6, 1.0)?;
        Ok(())
    }

    /// `[[protocol]]`: each step, by its kind and by the settings every DEM step shares.
    fn check_protocol(&self, ck: &Fields) -> Result<(), SceneError> {
        if self.protocol.is_empty() {
            return Err(ck.err(
                "protocol",
                "needs at least one step ([[protocol]] with kind = \"compress\", \"fixed-volume\", \"aggregate\", \"pressure-program\", \"hard-sphere-mix\", \"grow\" or \"expand\")"
                    .into(),
            ));
        }
        let cohesive = self.law.cohesion().is_some();
        for (k, step) in self.protocol.iter().enumerate() {
            self.check_step_kind(ck, k, step, cohesive)?;
            self.check_step_settings(ck, k, step, cohesive)?;
        }
        Ok(())
    }

    /// Protocol step `k`: what its kind requires (pressures, factors, targets).
    fn check_step_kind(
        &self,
        ck: &Fields,
        k: usize,
        step: &Step,
        cohesive: bool,
    ) -> Result<(), SceneError> {
        let f = |name: &str| format!("protocol[{k}].{name}");
        let check_pressure = |name: &str, pressure: f64| -> Result<(), SceneError> {
            if !(pressure.is_finite() && pressure >= 0.0) {
                return Err(ck.err(
                    &f(name),
                    format!("must be a finite number ≥ 0, got {pressure}"),
                ));
            }
            if pressure == 0.0 && !cohesive {
                return Err(ck.err(
                    &f(name),
                    "must be > 0 without cohesion (a cohesionless packing cannot hold at P = 0)"
                        .into(),
                ));
            }
            Ok(())
        };
        // Levels of a program: each the previous one times (or divided by) the factor.
        let check_factor = |factor: f64| -> Result<(), SceneError> {
            if factor.is_finite() && factor > 1.0 + 1e-6 && factor <= 100.0 {
                Ok(())
            } else {
                Err(ck.err(
                    &f("factor"),
                    format!("must lie in (1, 100] (each level is the previous one times or divided by it), got {factor}"),
                ))
            }
        };
        match step {
            Step::Compress {
                pressure,
                inertia_cap,
                ..
            } => {
                check_pressure("pressure", *pressure)?;
                ck.positive(&f("inertia_cap"), *inertia_cap)?;
            }
            Step::PressureProgram {
                from,
                to,
                factor,
                inertia_cap,
                ..
            } => {
                check_pressure("from", *from)?;
                check_pressure("to", *to)?;
                if *from == 0.0 || *to == 0.0 {
                    return Err(ck.err(
                        &f(if *from == 0.0 { "from" } else { "to" }),
                        "must be > 0 (levels are multiples of each other)".into(),
                    ));
                }
                check_factor(*factor)?;
                ck.positive(&f("inertia_cap"), *inertia_cap)?;
            }
            Step::KappaRamp {
                from,
                to,
                factor,
                pressure,
                inertia_cap,
                ..
            } => {
                ck.stiffness(&f("from"), *from)?;
                ck.stiffness(&f("to"), *to)?;
                check_pressure("pressure", *pressure)?;
                check_factor(*factor)?;
                ck.positive(&f("inertia_cap"), *inertia_cap)?;
            }
            Step::HardSphereMix {
                collisions_per_grain,
            } => ck.in_range(&f("collisions_per_grain"), *collisions_per_grain, 1e-3, 1e6)?,
            Step::Grow {
                packing_fraction,
                rate,
            } => {
                let top = if self.dimension == 2 { 0.9 } else { 0.74 };
                ck.in_range(&f("packing_fraction"), *packing_fraction, 0.0, top)?;
                ck.in_range(&f("rate"), *rate, 1e-9, 10.0)?;
            }
            Step::Expand { factor } => ck.in_range(&f("factor"), *factor, 1.0, 2.0)?,
            Step::FixedVolume { .. } | Step::Aggregate { .. } => {}
        }
        Ok(())
    }

    /// Protocol step `k`: μ, κ, criteria, relaxation and the kind the law allows.
    fn check_step_settings(
        &self,
        ck: &Fields,
        k: usize,
        step: &Step,
        cohesive: bool,
    ) -> Result<(), SceneError> {
        let f = |name: &str| format!("protocol[{k}].{name}");
        if let Some(mu) = step.mu() {
            ck.mu(&f("mu"), mu)?;
        }
        if let Some(kappa) = step.kappa() {
            ck.stiffness(&f("kappa"), kappa)?;
        }
        if step.is_dem() {
            ck.positive(&f("max_time"), step.max_time())?;
            let c = step.criteria();
            ck.positive(&f("criteria.force"), c.force)?;
            ck.positive(&f("criteria.moment"), c.moment)?;
            ck.positive(&f("criteria.pressure"), c.pressure)?;
            ck.positive(&f("criteria.kinetic"), c.kinetic)?;
            ck.in_range(&f("criteria.window"), c.window, 0.0, step.max_time())?;
            if let Some(r) = step.relax() {
                match r.method {
                    RelaxMethod::Damping => ck.positive(&f("relax.damping"), r.damping)?,
                    // AR07 §III.A: only frictionless, non-adhesive equilibria are the
                    // minima of an energy that FIRE can descend to.
                    RelaxMethod::Fire => {
                        let mu = step.mu().unwrap_or(self.law.mu()).value();
                        let rolling = matches!(
                            self.law,
                            Law::Linear {
                                rolling: Some(_),
                                ..
                            }
                        );
                        let why = if mu != 0.0 {
                            Some(format!("needs frictionless contacts: this step has μ = {mu}, and friction makes the contact forces depend on the path, not on an energy (AR07 §III.A); set mu = 0.0 or use method = \"damping\""))
                        } else if self.law.attractive() || rolling {
                            Some("needs a non-adhesive law without rolling resistance (AR07 §III.A: the equilibria of frictionless, non-adhesive grains minimise the enthalpy); use method = \"damping\"".to_string())
                        } else if r.damping != 0.0
                            || r.tangential_zeta != 0.0
                            || r.free_rollers
                            || r.mean_stress
                        {
                            Some("takes only settle_time and settle_factor: damping, tangential_zeta, free_rollers and mean_stress belong to method = \"damping\"; remove them".to_string())
                        } else {
                            None
                        };
                        if let Some(why) = why {
                            return Err(ck.err(&f("relax.method"), format!("\"fire\" {why}")));
                        }
                    }
                }
                ck.in_range(&f("relax.settle_time"), r.settle_time, 0.0, step.max_time())?;
                ck.in_range(&f("relax.tangential_zeta"), r.tangential_zeta, 0.0, 1.0)?;
                ck.in_range(&f("relax.settle_factor"), r.settle_factor, 1.0, 1e6)?;
                let no_rr = matches!(self.law, Law::Linear { rolling: None, .. });
                if r.free_rollers && !(cohesive && no_rr) {
                    return Err(ck.err(
                        &f("relax.free_rollers"),
                        "free rollers (GRC07 §III.A) are one-contact grains of a cohesive law without rolling resistance; remove it, or use law.cohesion without law.rolling".into(),
                    ));
                }
                if r.tangential_zeta > 0.0 && !matches!(self.law, Law::Linear { .. }) {
                    return Err(ck.err(
                        &f("relax.tangential_zeta"),
                        "tangential and rolling dashpots exist in the linear law only; use 0 with the Hertz–Mindlin law".into(),
                    ));
                }
            }
            let zero_pressure = matches!(
                step,
                Step::Compress { pressure, .. } | Step::KappaRamp { pressure, .. } if *pressure == 0.0
            );
            if c.scale == ForceScale::Pressure && zero_pressure {
                return Err(ck.err(
                    &f("criteria.scale"),
                    "\"pressure\" measures the criteria in units of the pressure, here 0: no state could meet them; use criteria = { preset = \"grc07\" } (scale \"cohesion\", units of F0)".into(),
                ));
            }
            if c.scale == ForceScale::Cohesion && !cohesive {
                return Err(ck.err(
                    &f("criteria.scale"),
                    "\"cohesion\" needs a cohesive law (law.cohesion); use \"pressure\"".into(),
                ));
            }
        }
        if matches!(step, Step::Aggregate { .. }) && !cohesive {
            return Err(ck.err(
                &f("kind"),
                "\"aggregate\" needs a cohesive law (law.cohesion): cohesionless grains never form one cluster".into(),
            ));
        }
        Ok(())
    }

    /// `[output]`.
    fn check_output(&self, ck: &Fields) -> Result<(), SceneError> {
        if self.output.snapshot.is_empty()
            || self.output.snapshot.contains('/')
            || self.output.snapshot.contains('\\')
        {
            return Err(ck.err(
                "output.snapshot",
                format!(
                    "must be a plain file name (no directories), got {:?}",
                    self.output.snapshot
                ),
            ));
        }
        if let Some(t) = self.output.trace_every {
            if !(t.is_finite() && t > 0.0) {
                return Err(ck.err(
                    "output.trace_every",
                    format!("must be a positive time in the scene's reduced units, got {t}"),
                ));
            }
            if self.particles.count > super::MAX_TRACE_GRAINS {
                return Err(ck.err(
                    "output.trace_every",
                    format!(
                        "a trace keeps every frame: for few-body scenes (at most {} grains), this one has {}; remove it",
                        super::MAX_TRACE_GRAINS,
                        self.particles.count
                    ),
                ));
            }
        }
        let name = self.output.snapshot.as_str();
        if matches!(name, "." | "..") || layout::RESERVED.contains(&name) {
            return Err(ck.err(
                "output.snapshot",
                format!(
                    "{name:?} is a name the run itself uses in the output directory ({}): the files would overwrite each other; choose another name, e.g. \"final.snap.json\"",
                    layout::RESERVED.join(", ")
                ),
            ));
        }
        Ok(())
    }

    /// Settings that are valid but costly, each a sentence naming the field: the time step
    /// follows the lightest grain (mass ∝ d^dim), so `particles.min_diameter` = d_min makes it
    /// d_min^(dim/2) of an equal-size scene's.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        let dmin = self.particles.min_diameter;
        if dmin < SMALL_MIN_DIAMETER {
            let f = dmin.powf(-(self.dimension as f64) / 2.0);
            let factor = if f < 1e4 {
                format!("{f:.0}")
            } else {
                format!("{f:.1e}")
            };
            w.push(format!(
                "particles.min_diameter = {dmin}: the time step follows the lightest grain, so this scene needs {factor}× the steps of an equal-size one (the papers use ≥ 0.5; below {SMALL_MIN_DIAMETER} this is rarely meant)"
            ));
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Criteria;

    const BASE: &str = include_str!("../../../reference-inputs/scenes/grc07-cohesive-small.toml");

    fn err(text: &str) -> SceneError {
        Scene::from_toml(text, Path::new("s.toml")).unwrap_err()
    }

    #[test]
    fn valid_scene_parses_with_presets() {
        let s = Scene::from_toml(BASE, Path::new("s.toml")).unwrap();
        // The scene asks for the criteria to hold over a 2 T0 window (`criteria.window`).
        assert_eq!(
            s.protocol[0].criteria(),
            Criteria {
                window: 2.0,
                ..Criteria::grc07()
            }
        );
        assert!(s.law.cohesion().is_some());
        let r = s.protocol[0].relax().unwrap();
        assert_eq!(
            (r.damping, r.tangential_zeta, r.settle_time),
            (1.0, 0.5, 10.0)
        );
    }

    /// tests/fuzz.rs: `kappa = 1e-300` underflowed the stiffness and tripped a debug
    /// assertion on the time step.
    #[test]
    fn kappa_is_bounded() {
        for bad in ["1e-300", "1.0", "1e300"] {
            let e = err(&BASE.replace("kappa = 1e5", &format!("kappa = {bad}")));
            assert_eq!(e.field, "law.kappa", "{e}");
            assert!(e.message.contains("h/a ~ 1/κ"), "{e}");
        }
    }

    /// A tiny `min_diameter` is accepted, with a word on what it costs.
    #[test]
    fn a_tiny_min_diameter_is_warned_about() {
        let s = Scene::from_toml(BASE, Path::new("s.toml")).unwrap();
        assert!(s.warnings().is_empty());
        let tiny = BASE.replace("min_diameter = 0.5", "min_diameter = 0.01");
        let s = Scene::from_toml(&tiny, Path::new("s.toml")).unwrap();
        let w = s.warnings().join("\n");
        // 2D: mass ∝ d², time step ∝ d_min, so 100 times the steps.
        assert!(
            w.contains("particles.min_diameter = 0.01") && w.contains(" 100×"),
            "{w}"
        );
        let mut tinier = s.clone();
        tinier.particles.min_diameter = 1e-6;
        assert!(tinier.warnings()[0].contains("1.0e6×"));
    }

    #[test]
    fn relax_and_window_are_checked() {
        let relax = "relax = { damping = 1.0, tangential_zeta = 0.5, settle_time = 10.0 }";
        let e = err(&BASE.replace(relax, "relax = { damping = 0.0, settle_time = 10.0 }"));
        assert_eq!(e.field, "protocol[0].relax.damping", "{e}");
        let e = err(&BASE.replace(relax, "relax = { damping = 1.0, settle_time = 1e9 }"));
        assert_eq!(e.field, "protocol[0].relax.settle_time", "{e}");
        let e = err(&BASE.replace(
            relax,
            "relax = { damping = 1.0, tangential_zeta = 2.0, settle_time = 1.0 }",
        ));
        assert_eq!(e.field, "protocol[0].relax.tangential_zeta", "{e}");
        let e = err(&BASE.replace(
            relax,
            "relax = { damping = 1.0, settle_time = 1.0, settle_factor = 0.5 }",
        ));
        assert_eq!(e.field, "protocol[0].relax.settle_factor", "{e}");
        // Free rollers (GRC07 §III.A) exist only without rolling resistance.
        let rollers = "relax = { damping = 1.0, settle_time = 10.0, free_rollers = true }";
        let e = err(&BASE.replace(relax, rollers));
        assert_eq!(e.field, "protocol[0].relax.free_rollers", "{e}");
        assert!(e.message.contains("law.rolling"), "{e}");
        let no_rr = BASE
            .lines()
            .filter(|l| !l.starts_with("rolling"))
            .collect::<Vec<_>>()
            .join("\n");
        let s = Scene::from_toml(&no_rr.replace(relax, rollers), Path::new("s.toml")).unwrap();
        assert!(s.protocol[0].relax().unwrap().free_rollers);
        let e = err(&BASE.replace(relax, "relax = { damping = 1.0, settle = 1.0 }"));
        assert!(e.message.contains("settle"), "{e}");
        let e = err(&BASE.replace("window = 2.0", "window = -1.0"));
        assert_eq!(e.field, "protocol[0].criteria.window", "{e}");
        // Without `relax` and `window` the stage is the paper's, exactly.
        let plain = Scene::from_toml(
            &BASE
                .replace(&format!("{relax}\n"), "")
                .replace(", window = 2.0", ""),
            Path::new("s.toml"),
        )
        .unwrap();
        assert_eq!(plain.protocol[0].relax(), None);
        assert_eq!(plain.protocol[0].criteria(), Criteria::grc07());
    }

    #[test]
    fn errors_name_the_field_and_what_is_allowed() {
        let e = err(&BASE.replace("zeta = 0.8", "zeta = 1.5"));
        assert_eq!(e.field, "law.zeta");
        assert!(e.to_string().contains("s.toml") && e.to_string().contains("[0, 1]"));
        let e = err(&BASE.replace("d0 = 1e-3", "d0 = 0.3"));
        assert_eq!(e.field, "law.cohesion.d0");
        let e = err(&BASE.replace("pressure = 0.01", "pressure = -1"));
        assert_eq!(e.field, "protocol[0].pressure");
        // Criteria in units of a zero pressure: every ratio infinite, reported as a blow-up.
        let e = err(&BASE
            .replace("pressure = 0.01", "pressure = 0.0")
            .replace("preset = \"grc07\"", "preset = \"ar07\""));
        assert_eq!(e.field, "protocol[0].criteria.scale", "{e}");
        assert!(e.message.contains("grc07"), "{e}");
        let e = err(&BASE.replace("dimension = 2", "dimension = 4"));
        assert_eq!(e.field, "dimension");
        let e = err(&BASE.replace("mu = 0.5", "mu = \"lots\""));
        assert!(e.message.contains("inf"), "{e}");
        let e = err(&BASE.replace("preset = \"grc07\"", "preset = \"grc09\""));
        assert!(e.message.contains("grc08"), "{e}");
        let e = err(&BASE.replace("packing_fraction = 0.36", "packing_fraction = 0.6"));
        assert_eq!(e.field, "initial.packing_fraction");
        let e = err(&BASE.replace("packing_fraction = 0.36", "packing_fraction = 1e-300"));
        assert_eq!(e.field, "initial.packing_fraction");
        // Cohesion-scaled criteria need a cohesive law; zero pressure needs cohesion.
        let no_coh = BASE.replace("cohesion = { d0 = 1e-3 }\n", "");
        assert_eq!(err(&no_coh).field, "protocol[0].criteria.scale");
        let e = err(&BASE
            .replace("pressure = 0.01", "pressure = 0.0")
            .replace("cohesion = { d0 = 1e-3 }\n", ""));
        assert_eq!(e.field, "protocol[0].pressure");
        // Hertz needs spheres.
        let e = err(&BASE
            .replace("kind = \"linear\"", "kind = \"hertz-mindlin\"")
            .replace("kt_over_kn = 1\n", ""));
        assert!(!e.message.is_empty());
        // SJKR cohesion: a finite energy density ≥ 0.
        let sjkr = crate::library::scene_text("xcode-sjkr-smoke").unwrap();
        let e = err(&sjkr.replace("sjkr = 5000.0", "sjkr = -1.0"));
        assert_eq!(e.field, "law.sjkr", "{e}");
        assert!(e.message.contains("P_ref"), "{e}");
        // DMT: γ ≥ 0, and one cohesion law at a time.
        let dmt = crate::library::scene_text("xcode-dmt-smoke").unwrap();
        let e = err(&dmt.replace("dmt = 0.2", "dmt = -0.2"));
        assert_eq!(e.field, "law.dmt", "{e}");
        let e = err(&dmt.replace("dmt = 0.2", "dmt = 0.2\nsjkr = 10.0"));
        assert_eq!(e.field, "law.dmt", "{e}");
        assert!(e.message.contains("sjkr"), "{e}");
    }

    #[test]
    fn procedure_steps_are_checked() {
        let with = |extra: &str| BASE.to_string() + extra;
        // Aggregation needs cohesion; factors of programs must exceed 1; LS targets are bounded.
        let e = err(
            &with("[[protocol]]\nkind = \"aggregate\"\nmax_time = 10.0\n")
                .replace("cohesion = { d0 = 1e-3 }\n", "")
                .replace("preset = \"grc07\"", "preset = \"ar07\"")
                .replace("pressure = 0.01", "pressure = 1.0"),
        );
        assert_eq!(e.field, "protocol[1].kind", "{e}");
        let e = err(&with("[[protocol]]\nkind = \"pressure-program\"\nfrom = 0.01\nto = 1.0\nfactor = 1.0\ninertia_cap = 0.05\nmax_time = 10.0\n"));
        assert_eq!(e.field, "protocol[1].factor", "{e}");
        let e = err(&with(
            "[[protocol]]\nkind = \"grow\"\npacking_fraction = 0.95\n",
        ));
        assert_eq!(e.field, "protocol[1].packing_fraction", "{e}");
        let e = err(&with("[[protocol]]\nkind = \"expand\"\nfactor = 0.9\n"));
        assert_eq!(e.field, "protocol[1].factor", "{e}");
        // FCC needs 4k³ equal spheres.
        let e = err(&BASE.replace(
            "packing_fraction = 0.36",
            "arrangement = \"fcc\"\npacking_fraction = 0.36",
        ));
        assert_eq!(e.field, "initial.arrangement", "{e}");
        // A valid program unrolls into one compress stage per level, ending exactly at `to`.
        let s = Scene::from_toml(
            &with("[[protocol]]\nkind = \"pressure-program\"\nfrom = 0.01\nto = 13.33\nfactor = 1.333521432163324\ninertia_cap = 0.05\nmax_time = 10.0\ncriteria = { preset = \"grc08\" }\n"),
            Path::new("s"),
        )
        .unwrap();
        let stages = s.stages();
        assert_eq!(stages.len(), 1 + 26);
        assert!(
            matches!(stages.last().unwrap().1, Step::Compress { pressure, .. } if pressure == 13.33)
        );
        assert!(stages.iter().all(|(k, _)| *k <= 1));
    }

    #[test]
    fn unknown_keys_are_refused() {
        let e = err(&BASE.replace("seed = 1", "seed = 1\nsede = 2"));
        assert!(e.message.contains("sede"), "{e}");
        let e = err(&BASE.replace("zeta = 0.8", "zeta = 0.8\nkappa_t = 3"));
        assert!(e.message.contains("kappa_t"), "{e}");
    }

    #[test]
    fn infinite_friction_is_a_keyword() {
        let s =
            Scene::from_toml(&BASE.replace("mu = 0.5", "mu = \"inf\""), Path::new("s")).unwrap();
        assert!(matches!(
            s.law,
            Law::Linear {
                mu: Mu::Infinite,
                ..
            }
        ));
    }

    /// The servo reads (σ − P)/P: a gain is checked, and P = 0 is refused with the step named.
    #[test]
    fn servo_gain_needs_a_positive_pressure() {
        let servo = BASE.replace("[numerics]", "[numerics]\nservo_gain = 0.002");
        let s = Scene::from_toml(&servo, Path::new("s.toml")).unwrap();
        assert_eq!(s.numerics.servo_gain, Some(0.002));
        let e = err(&BASE.replace("[numerics]", "[numerics]\nservo_gain = -1.0"));
        assert_eq!(e.field, "numerics.servo_gain", "{e}");
        let e = err(&servo.replace("pressure = 0.01", "pressure = 0.0"));
        assert_eq!(e.field, "numerics.servo_gain", "{e}");
        assert!(e.message.contains("protocol step 1"), "{e}");
    }
}
