//! Published values to reproduce (the tables of AR07, GRC07 and GRC08, and a few values from
//! their text and figures), loaded from `golden/paper-values.toml`.
//!
//! The file is embedded at compile time and parsed once. It holds one table per state
//! (`ar07-D`, `grc07-type1-phi036-mu05`, …), each with its metric values: the paper's mean, the
//! sample-to-sample standard deviation where the paper gives one, and the table or figure it comes
//! from. Fractions are stored as fractions (x0 = 1.3 % → 0.013). Metric keys are documented in
//! [`METRIC_KEYS`].
//!
//! ```
//! use grainbench_comparisons::report::paper::paper_values;
//! let d = paper_values("ar07-D").unwrap();
//! let phi = &d.values["phi"];
//! assert_eq!((phi.value, phi.sd), (0.5923, Some(0.0006)));
//! assert_eq!(phi.reference, "AR07 T.IV");
//! ```

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::OnceLock;

/// The embedded data file.
pub const PAPER_VALUES_TOML: &str = include_str!("../../../golden/paper-values.toml");

/// One published value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaperValue {
    /// Mean over the paper's samples (fractions, not percent).
    pub value: f64,
    /// Sample-to-sample standard deviation, where the paper gives one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sd: Option<f64>,
    /// Where it comes from: `"AR07 T.IV"`, `"AR07 §IV.E (text)"`, `"AR07 Fig. 10 (fig.)"`.
    #[serde(rename = "ref")]
    pub reference: String,
    /// Caveats: discrepancies between tables, units, approximate readings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// The published values for one state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateValues {
    /// `"AR07"`, `"GRC07"` or `"GRC08"`.
    pub paper: String,
    /// How the state is made, in one line.
    pub description: String,
    /// Grains per sample, where one size applies.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n: Option<u32>,
    /// Number of samples the means are over, where the paper says.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<u32>,
    /// Caveats about the state as a whole.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// Where the state is a level of another state's pressure program (AR07 T.III's QS rows):
    /// it is judged on that level's stage-end snapshot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub level_of: Option<LevelOf>,
    /// The state whose published consolidation law (GRC08 (9), T.III) this state's curve
    /// joins once it compacts (GRC08 §III.C.1, Fig. 6: type 1 joins type 2); its plot draws
    /// that law.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joins: Option<String>,
    /// Metric key (see [`METRIC_KEYS`]) → published value.
    pub values: BTreeMap<String, PaperValue>,
}

/// A level of another state's pressure program.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LevelOf {
    /// The state whose scene runs the program (`"ar07-D-QS-100kPa"`).
    pub state: String,
    /// The level's pressure, in the scene's pressure unit (P_ref: 1 kPa in AR07's scenes).
    pub pressure: f64,
}

/// Every metric key the data file may use, with its meaning. The first block is the project's
/// fixed list; the rest name quantities that list does not cover.
pub const METRIC_KEYS: &[(&str, &str)] = &[
    ("phi", "solid fraction Φ"),
    ("z", "coordination number 2N_c/n over force-carrying contacts (and distant attractions in 2D)"),
    ("z_star", "backbone coordination number z* = z/(1 - x0)"),
    ("x0", "rattler fraction"),
    ("xk2", "fraction of grains with 2 contacts, rattlers' contacts ignored (variant I, AR07 T.I/T.V)"),
    ("xk3", "x_3, variant I"),
    ("xk4", "x_4, variant I"),
    ("xk5", "x_5, variant I"),
    ("xk6", "x_6, variant I"),
    ("xk7", "x_7, variant I"),
    ("xk8", "x_8, variant I"),
    ("xk9", "x_9, variant I"),
    ("xk10", "x_10, variant I"),
    ("xk11", "x_11, variant I"),
    ("xk12", "x_12, variant I"),
    ("xk2_II", "x_2 with rattlers fixed onto the backbone (variant II, AR07 T.I/T.V)"),
    ("xk3_II", "x_3, variant II"),
    ("xk4_II", "x_4, variant II"),
    ("xk5_II", "x_5, variant II"),
    ("xk6_II", "x_6, variant II"),
    ("xk7_II", "x_7, variant II"),
    ("xk8_II", "x_8, variant II"),
    ("xk9_II", "x_9, variant II"),
    ("xk10_II", "x_10, variant II"),
    ("xk11_II", "x_11, variant II"),
    ("xk12_II", "x_12, variant II"),
    ("mean_N", "mean normal force ⟨N⟩"),
    ("Z2", "Z(2) = ⟨N²⟩/⟨N⟩², AR07 (27)"),
    ("Z5_3", "Z(5/3), AR07 (27)"),
    ("X1", "fraction of contacts with N > ⟨N⟩ (AR07 T.VI)"),
    ("M1", "mean |T|/N over contacts with N > ⟨N⟩"),
    ("M2", "mean |T|/N over contacts with N < ⟨N⟩"),
    ("N_2", "mean N on contacts of 2-coordinated grains, in units of P a² (AR07 T.VI)"),
    ("X1_2", "X1 for contacts of 2-coordinated grains"),
    ("M1_2", "M1 for contacts of 2-coordinated grains"),
    ("M2_2", "M2 for contacts of 2-coordinated grains"),
    ("N_3", "mean N on contacts of 3-coordinated grains, in units of P a²"),
    ("X1_3", "X1 for contacts of 3-coordinated grains"),
    ("M1_3", "M1 for contacts of 3-coordinated grains"),
    ("M2_3", "M2 for contacts of 3-coordinated grains"),
    ("Q4", "global bond order Q4"),
    ("Q6", "global bond order Q6 (AR07 T.II, d_c = 1.35a)"),
    ("Q4loc", "mean local Q4, AR07 (31)"),
    ("Q6loc", "mean local Q6, AR07 (31)"),
    ("Z_bond", "bond (first-neighbour, r < d_c) coordination number (AR07 T.II)"),
    ("Z_cr", "crystalline-bond coordination number, AR07 (34)"),
    ("Q6loc_cr", "mean local Q6 within crystalline regions"),
    ("x_cr", "fraction of crystalline grains (≥ 7 crystalline bonds)"),
    ("n_cr", "mass average of the crystalline cluster size"),
    ("Z_bond_140", "Z_bond with d_c = 1.40a"),
    ("Z_cr_140", "Z_cr with d_c = 1.40a"),
    ("Q6_140", "Q6 with d_c = 1.40a"),
    ("Q6loc_140", "Q6loc with d_c = 1.40a"),
    ("Q6loc_cr_140", "Q6loc_cr with d_c = 1.40a"),
    ("x_cr_140", "x_cr with d_c = 1.40a"),
    ("n_cr_140", "n_cr with d_c = 1.40a"),
    ("fcc_110", "fcc-like grains, (Q4loc, Q6loc) within ±0.05 of (0.191, 0.574), d_c = 1.1a (AR07 T.VII–T.VIII)"),
    ("hcp_110", "hcp-like grains, (Q4loc, Q6loc) within ±0.05 of (0.097, 0.485), d_c = 1.1a"),
    ("dis_F_110", "grains in the disordered mode of Aste et al.'s sample F (Φ ≈ 0.640), d_c = 1.1a (AR07 T.VII)"),
    ("dis_D_110", "grains in the disordered mode of Aste et al.'s sample D (Φ ≈ 0.626), d_c = 1.1a (AR07 T.VIII)"),
    ("dis_B_110", "grains in the disordered mode of Aste et al.'s sample B (Φ ≈ 0.596), d_c = 1.1a (AR07 T.VIII)"),
    ("hcp_not_F_110", "hcp-like grains outside the disordered mode of Aste et al.'s sample F (Φ ≈ 0.640), d_c = 1.1a"),
    ("hcp_not_D_110", "hcp-like grains outside the disordered mode of Aste et al.'s sample D (Φ ≈ 0.626), d_c = 1.1a"),
    ("hcp_not_B_110", "hcp-like grains outside the disordered mode of Aste et al.'s sample B (Φ ≈ 0.596), d_c = 1.1a"),
    ("fcc_120", "fcc-like grains, (Q4loc, Q6loc) within ±0.05 of (0.191, 0.574), d_c = 1.2a (AR07 T.VII–T.VIII)"),
    ("hcp_120", "hcp-like grains, (Q4loc, Q6loc) within ±0.05 of (0.097, 0.485), d_c = 1.2a"),
    ("dis_F_120", "grains in the disordered mode of Aste et al.'s sample F (Φ ≈ 0.640), d_c = 1.2a (AR07 T.VII)"),
    ("dis_D_120", "grains in the disordered mode of Aste et al.'s sample D (Φ ≈ 0.626), d_c = 1.2a (AR07 T.VIII)"),
    ("dis_B_120", "grains in the disordered mode of Aste et al.'s sample B (Φ ≈ 0.596), d_c = 1.2a (AR07 T.VIII)"),
    ("hcp_not_F_120", "hcp-like grains outside the disordered mode of Aste et al.'s sample F (Φ ≈ 0.640), d_c = 1.2a"),
    ("hcp_not_D_120", "hcp-like grains outside the disordered mode of Aste et al.'s sample D (Φ ≈ 0.626), d_c = 1.2a"),
    ("hcp_not_B_120", "hcp-like grains outside the disordered mode of Aste et al.'s sample B (Φ ≈ 0.596), d_c = 1.2a"),
    ("fcc_130", "fcc-like grains, (Q4loc, Q6loc) within ±0.05 of (0.191, 0.574), d_c = 1.3a (AR07 T.VII–T.VIII)"),
    ("hcp_130", "hcp-like grains, (Q4loc, Q6loc) within ±0.05 of (0.097, 0.485), d_c = 1.3a"),
    ("dis_F_130", "grains in the disordered mode of Aste et al.'s sample F (Φ ≈ 0.640), d_c = 1.3a (AR07 T.VII)"),
    ("dis_D_130", "grains in the disordered mode of Aste et al.'s sample D (Φ ≈ 0.626), d_c = 1.3a (AR07 T.VIII)"),
    ("dis_B_130", "grains in the disordered mode of Aste et al.'s sample B (Φ ≈ 0.596), d_c = 1.3a (AR07 T.VIII)"),
    ("hcp_not_F_130", "hcp-like grains outside the disordered mode of Aste et al.'s sample F (Φ ≈ 0.640), d_c = 1.3a"),
    ("hcp_not_D_130", "hcp-like grains outside the disordered mode of Aste et al.'s sample D (Φ ≈ 0.626), d_c = 1.3a"),
    ("hcp_not_B_130", "hcp-like grains outside the disordered mode of Aste et al.'s sample B (Φ ≈ 0.596), d_c = 1.3a"),
    ("fcc_140", "fcc-like grains, (Q4loc, Q6loc) within ±0.05 of (0.191, 0.574), d_c = 1.4a (AR07 T.VII–T.VIII)"),
    ("hcp_140", "hcp-like grains, (Q4loc, Q6loc) within ±0.05 of (0.097, 0.485), d_c = 1.4a"),
    ("dis_F_140", "grains in the disordered mode of Aste et al.'s sample F (Φ ≈ 0.640), d_c = 1.4a (AR07 T.VII)"),
    ("dis_D_140", "grains in the disordered mode of Aste et al.'s sample D (Φ ≈ 0.626), d_c = 1.4a (AR07 T.VIII)"),
    ("dis_B_140", "grains in the disordered mode of Aste et al.'s sample B (Φ ≈ 0.596), d_c = 1.4a (AR07 T.VIII)"),
    ("hcp_not_F_140", "hcp-like grains outside the disordered mode of Aste et al.'s sample F (Φ ≈ 0.640), d_c = 1.4a"),
    ("hcp_not_D_140", "hcp-like grains outside the disordered mode of Aste et al.'s sample D (Φ ≈ 0.626), d_c = 1.4a"),
    ("hcp_not_B_140", "hcp-like grains outside the disordered mode of Aste et al.'s sample B (Φ ≈ 0.596), d_c = 1.4a"),
    ("z_plus", "coordination number of repulsive contacts (GRC07 T.VI)"),
    ("z_minus", "coordination number of attractive contacts (GRC07 T.VI)"),
    ("z_zero", "coordination number of contacts below 1e-4 F0 (GRC07 T.VI)"),
    ("clusters", "clusters of grains linked by interactions"),
    ("wrapped_axes", "axes along which the interaction network wraps the cell"),
    ("d_F", "fractal dimension from the fit of I(k) by GRC07 (28)"),
    ("xi", "fractal blob size ξ/a from GRC07 (28)"),
    ("B", "bulk modulus from the stiffness matrix, GRC08 (6): (C11 + C12)/2 in 2D"),
    ("G", "shear modulus from the stiffness matrix, GRC08 (6): (C11 − C12)/2"),
    ("B_V", "Voigt (affine) bulk modulus, GRC08 (12)"),
    ("G_V", "Voigt (affine) shear modulus, GRC08 (12)"),
    ("B_R", "Reuss bulk modulus, GRC08 (13)–(14)"),
    ("E95", "fraction of contacts carrying 95 % of the elastic energy of a pressure increment (GRC08 §VI.E)"),
    ("mechanisms", "mechanisms K of the network, cell fixed, global translations included (GRC07 App. A)"),
    ("H", "degree of force indeterminacy H, cell fixed (GRC07 App. A)"),
    // Quantities outside the fixed list.
    ("xk1", "x_1, variant I (0 by the rattler rule)"),
    ("xk1_II", "x_1, variant II"),
    ("phi_init", "solid fraction Φ_I of the initial (I-)state, GRC07"),
    ("delta_phi_28", "ΔΦ to the rigid limit by AR07 (28)"),
    ("z_iso", "z_0 = 4(1 - x0) - 2x2/3, AR07 (38)"),
    ("H_over_Nf", "degree of hyperstaticity over degrees of freedom, H/N_f (AR07 §IV.E)"),
    ("triangles_per_grain", "equilateral contact triangles per backbone grain (AR07 §III.D)"),
    ("x_tetra", "fraction of grains in a contact tetrahedron (AR07 §III.D)"),
    ("beta_I", "exponent β_I of the fit z^I(h) = z^I(0) + A h^β, AR07 (35)"),
    ("beta_II", "exponent β_II of the fit z^II(h) = z^II(0) + A h^β, AR07 (35)"),
    ("N_plus", "mean repulsive normal force, units of F0 (GRC07 T.VI)"),
    ("N_plus_rms", "quadratic average of repulsive normal forces, units of F0 (GRC07 T.VI)"),
    ("N_minus", "mean magnitude of attractive normal forces, units of F0 (GRC07 T.VI)"),
    ("N_minus_rms", "quadratic average of attractive normal forces, units of F0 (GRC07 T.VI)"),
    ("R_w", "mass-weighted mean hole radius ⟨R⟩_w/a, GRC07 (30)"),
    ("N_C1", "normal force in contact C1 of GRC07 Fig. 18, units of F0"),
    ("N_C2", "normal force in contact C2 of GRC07 Fig. 18, units of F0"),
    ("z_star_0", "z* extrapolated to P = 0 (GRC08 §III.A)"),
    ("P0_star", "P0*, where the consolidation curve joins GRC08 (7)"),
    ("phi0", "Φ0 at P0*, GRC08 (7)"),
    ("lambda", "plasticity index λ, GRC08 (7)"),
    ("phi_max", "Φ_max of the fit by GRC08 (9)"),
    ("alpha", "exponent α of GRC08 (8)-(9)"),
    ("P1_star", "crossover pressure P1* of GRC08 (9)"),
    ("phi_at_pmax", "solid fraction reached at the largest pressure P* = 13.3 (GRC08 §III.B)"),
    ("d_F_p001", "fractal dimension d_F of I(k) at P* = 0.01 on loading (GRC08 §IV, Fig. 15)"),
    ("xi_p001", "correlation length ξ/a of I(k) at P* = 0.01 on loading (GRC08 §IV, Fig. 15)"),
    ("R_w_p001", "pores' mean radius of gyration ξ'/a = ⟨R⟩_w/a at P* = 0.01 (GRC08 Fig. 16)"),
    ("d_F_p0178", "d_F of I(k) at P* = 0.178 on loading (GRC08 Fig. 15)"),
    ("xi_p0178", "ξ/a of I(k) at P* = 0.178 on loading (GRC08 Fig. 15)"),
    ("R_w_p0178", "ξ'/a at P* = 0.178 on loading (GRC08 Fig. 16)"),
    ("d_F_p1", "d_F of I(k) at P* = 1 on loading (GRC08 Fig. 15: no fractal range left)"),
    ("xi_p1", "ξ/a of I(k) at P* = 1 on loading (GRC08 Fig. 15)"),
    ("R_w_p1", "ξ'/a at P* = 1 on loading (GRC08 Fig. 16)"),
    ("xi_phi_slope", "slope of ln ξ against ln Φ on loading up to P* = 0.178 (GRC08 (10))"),
    ("xi_phi_slope_eq10", "the slope GRC08 (10) predicts, −1/(2 − d_F), d_F averaged over those levels"),
    ("dphi_rel", "relative change of Φ in one compression step (GRC08 T.IV)"),
    ("dz_rel", "relative change of z in one compression step (GRC08 T.IV)"),
    ("n_kept", "contacts maintained in the step (GRC08 T.IV)"),
    ("n_lost", "contacts destroyed in the step (GRC08 T.IV)"),
    ("n_new", "contacts created in the step (GRC08 T.IV)"),
    ("frac_kept", "n_kept over the initial number of contacts"),
    ("frac_lost", "n_lost over the initial number of contacts"),
    ("frac_new", "n_new over the initial number of contacts"),
];

/// The meaning of a metric key, if it is documented.
pub fn metric_description(key: &str) -> Option<&'static str> {
    METRIC_KEYS.iter().find(|(k, _)| *k == key).map(|(_, d)| *d)
}

/// Position of a key in [`METRIC_KEYS`] (the order tables are printed in); unknown keys last.
pub fn metric_order(key: &str) -> usize {
    METRIC_KEYS
        .iter()
        .position(|(k, _)| *k == key)
        .unwrap_or(METRIC_KEYS.len())
}

/// Parses a paper-values document (the embedded one, or another for tests).
pub fn parse(text: &str) -> Result<BTreeMap<String, StateValues>, toml::de::Error> {
    toml::from_str(text)
}

/// All states of the embedded file, parsed once.
///
/// # Panics
/// If the embedded file does not parse, which the unit tests rule out.
pub fn all_states() -> &'static BTreeMap<String, StateValues> {
    static STATES: OnceLock<BTreeMap<String, StateValues>> = OnceLock::new();
    STATES.get_or_init(|| {
        parse(PAPER_VALUES_TOML).expect("golden/paper-values.toml is checked by the unit tests")
    })
}

/// The published values for `state` (e.g. `"ar07-D"`), if the file has it.
pub fn paper_values(state: &str) -> Option<&'static StateValues> {
    all_states().get(state)
}

/// The states reached at levels of `state`'s pressure program, with their level pressures, in
/// the order of the file's state names.
pub fn levels_of(state: &str) -> Vec<(&'static str, f64)> {
    all_states()
        .iter()
        .filter_map(|(name, s)| {
            let l = s.level_of.as_ref()?;
            (l.state == state).then_some((name.as_str(), l.pressure))
        })
        .collect()
}

/// The names of all states, sorted.
pub fn state_names() -> Vec<&'static str> {
    all_states().keys().map(String::as_str).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value(state: &str, key: &str) -> &'static PaperValue {
        paper_values(state)
            .unwrap_or_else(|| panic!("no state {state}"))
            .values
            .get(key)
            .unwrap_or_else(|| panic!("no {key} in {state}"))
    }

    #[test]
    fn embedded_file_parses() {
        let states = parse(PAPER_VALUES_TOML).expect("paper-values.toml parses");
        assert!(states.len() > 50, "only {} states", states.len());
        for (name, s) in &states {
            assert!(!s.values.is_empty(), "{name} has no values");
            assert!(
                ["AR07", "GRC07", "GRC08"].contains(&s.paper.as_str()),
                "{name}"
            );
            assert!(
                name.starts_with(&s.paper.to_lowercase()),
                "{name} is filed under {}",
                s.paper
            );
        }
    }

    #[test]
    fn joined_states_publish_a_whole_law() {
        let mut joined = 0;
        for (name, s) in all_states() {
            let Some(other) = &s.joins else { continue };
            let law = paper_values(other)
                .unwrap_or_else(|| panic!("{name} joins {other}: no such state"));
            for key in ["P0_star", "phi0", "lambda", "alpha", "P1_star"] {
                assert!(
                    law.values.contains_key(key),
                    "{name} joins {other}, which has no {key}"
                );
            }
            // The intrinsic parameters judged on the joining curve are the joined state's.
            for (key, v) in &s.values {
                if let Some(w) = law.values.get(key) {
                    assert_eq!((v.value, v.sd), (w.value, w.sd), "{name}.{key}");
                }
            }
            joined += 1;
        }
        assert_eq!(joined, 2, "GRC08 Fig. 6: type 1 with and without RR");
    }

    #[test]
    fn required_states_are_present() {
        for s in [
            "ar07-A",
            "ar07-Aprime",
            "ar07-B",
            "ar07-C",
            "ar07-D",
            "ar07-D-10kPa",
            "ar07-D-100kPa",
            "ar07-D-QS-10kPa",
            "ar07-D-QS-100kPa",
            "ar07-D-10kPa-zeta0098",
            "ar07-D-10kPa-Imax01",
            "ar07-Z",
            "grc07-type1-phi013-mu05",
            "grc07-type1-phi036-mu05",
            "grc07-type1-phi052-mu05",
            "grc07-type1-phi036-mu015-rr",
            "grc07-cohesionless-phi036-mu05",
            "grc07-type2-phi036",
            "grc07-type2-phi036-rr",
            "grc07-type2-phi036-p0",
            "grc07-type2-phi036-rr-p0",
            "grc07-type2-phi036-rr-p0-v0-9p5",
            "grc08-type2",
            "grc08-consolidation",
            "grc08-consolidation-rr",
        ] {
            assert!(paper_values(s).is_some(), "missing state {s}");
        }
        assert!(paper_values("ar07-E").is_none());
        assert_eq!(state_names().len(), all_states().len());
    }

    #[test]
    fn every_key_is_documented() {
        let mut seen = std::collections::HashSet::new();
        for (k, d) in METRIC_KEYS {
            assert!(seen.insert(*k), "{k} listed twice");
            assert!(!d.is_empty());
        }
        for (name, s) in all_states() {
            for key in s.values.keys() {
                assert!(
                    metric_description(key).is_some(),
                    "{name}: undocumented key {key}"
                );
            }
        }
    }

    #[test]
    fn values_are_sane() {
        for (name, s) in all_states() {
            for (key, v) in &s.values {
                assert!(v.value.is_finite(), "{name}.{key}");
                if let Some(sd) = v.sd {
                    assert!(sd > 0.0 && sd.is_finite(), "{name}.{key}: sd {sd}");
                }
                assert!(
                    ["AR07", "GRC07", "GRC08"]
                        .iter()
                        .any(|p| v.reference.starts_with(p)),
                    "{name}.{key}: ref {:?}",
                    v.reference
                );
                // Fractions stay fractions: nothing that should be below 1 is in percent.
                let fraction = key == "phi"
                    || key.starts_with("xk")
                    || key.starts_with("x0")
                    || key.starts_with("dis_")
                    || key.starts_with("hcp_")
                    || key.starts_with("frac_")
                    || key.starts_with("x_");
                if fraction {
                    assert!((0.0..=1.0).contains(&v.value), "{name}.{key} = {}", v.value);
                }
            }
        }
    }

    #[test]
    fn key_values_match_the_tables() {
        // AR07 T.IV.
        let phi = value("ar07-D", "phi");
        assert_eq!((phi.value, phi.sd), (0.5923, Some(0.0006)));
        assert_eq!(phi.reference, "AR07 T.IV");
        let zs = value("ar07-A", "z_star");
        assert_eq!((zs.value, zs.sd), (6.074, Some(0.0015)));
        assert_eq!(value("ar07-A", "x0").value, 0.013);
        assert_eq!(value("ar07-A", "x0").sd, Some(0.002));
        assert_eq!(value("ar07-C", "x0").sd, Some(0.005));
        assert_eq!(value("ar07-D", "M2").value, 0.217);
        assert_eq!(value("ar07-B", "Z2").value, 1.52);
        assert_eq!(value("ar07-A", "Z5_3").value, 1.284);
        // AR07 T.III and §IV.E.
        assert_eq!(value("ar07-D-QS-100kPa", "z_star").value, 4.79);
        assert_eq!(value("ar07-D-1kPa", "phi").value, 0.5930);
        assert_eq!(value("ar07-Z", "xk2").sd, Some(0.005));
        // AR07 T.I, T.II, T.V, T.VI.
        assert_eq!(value("ar07-A", "xk6").value, 0.284);
        assert_eq!(value("ar07-Aprime", "xk3_II").value, 0.017);
        assert_eq!(value("ar07-D", "xk4").value, 0.291);
        assert_eq!(value("ar07-A", "Q6loc_140").value, 0.370);
        assert_eq!(value("ar07-Aprime", "n_cr").value, 54.8);
        assert_eq!(value("ar07-C", "N_2").value, 0.58);
        // GRC07 T.II–T.VII.
        let p = value("grc07-type1-phi036-mu05", "phi");
        assert_eq!((p.value, p.sd), (0.7232, Some(0.0012)));
        let z = value("grc07-cohesionless-phi036-mu05", "z");
        assert_eq!((z.value, z.sd), (2.65, Some(0.02)));
        assert_eq!(value("grc07-type2-phi036-p0", "z").value, 3.1407);
        assert_eq!(value("grc07-type2-phi036-rr", "phi").value, 0.524);
        assert_eq!(value("grc07-type2-phi036-rr-p0-v0-0p095", "z").value, 2.004);
        assert_eq!(
            value("grc07-type2-phi036-rr-p0-v0-95", "N_plus").value,
            0.058
        );
        let df = value("grc07-type2-phi036-p0", "d_F");
        assert_eq!((df.value, df.sd), (1.925, Some(0.024)));
        assert_eq!(value("grc07-type2-phi036-rr", "xi").value, 5.06);
        // GRC08 T.II, T.III.
        assert_eq!(value("grc08-type1", "phi").value, 0.723);
        let l = value("grc08-consolidation-rr", "lambda");
        assert_eq!((l.value, l.sd), (0.194, Some(0.004)));
        assert_eq!(value("grc08-consolidation", "phi_max").value, 0.7808);
    }

    #[test]
    fn xk_rows_sum_to_one() {
        // Each transcribed x_k row (with x0 for variant I) sums to 100 % up to table rounding.
        for state in ["ar07-A", "ar07-Aprime", "ar07-B", "ar07-C", "ar07-D"] {
            let s = paper_values(state).unwrap();
            let sum = |suffix: &str| -> f64 {
                (1..=12)
                    .filter_map(|k| s.values.get(&format!("xk{k}{suffix}")))
                    .map(|v| v.value)
                    .sum()
            };
            let one = s.values["x0"].value + sum("");
            let two = sum("_II");
            assert!((one - 1.0).abs() < 0.01, "{state} I: {one}");
            assert!((two - 1.0).abs() < 0.01, "{state} II: {two}");
        }
    }

    #[test]
    fn qs_rows_are_levels_of_the_qs_program() {
        assert_eq!(
            levels_of("ar07-D-QS-100kPa"),
            vec![("ar07-D-QS-10kPa", 10.0)]
        );
        assert!(levels_of("ar07-D").is_empty());
        // Every level belongs to a state of the file, at a positive pressure.
        for (name, s) in all_states() {
            if let Some(l) = &s.level_of {
                assert!(all_states().contains_key(&l.state), "{name}: {}", l.state);
                assert!(l.pressure > 0.0, "{name}");
            }
        }
    }

    #[test]
    fn malformed_entries_are_rejected() {
        let typo = "[s]\npaper = \"AR07\"\ndescription = \"d\"\n[s.values]\nphi = { value = 0.6, sdd = 0.1, ref = \"AR07 T.IV\" }\n";
        assert!(parse(typo).is_err());
        let no_ref =
            "[s]\npaper = \"AR07\"\ndescription = \"d\"\n[s.values]\nphi = { value = 0.6 }\n";
        assert!(parse(no_ref).is_err());
    }
}
