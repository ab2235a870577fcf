//! Contact-force statistics: the normal-force distribution P(f) (AR07 Fig. 4, Fig. 15), its
//! moments Z(α) (AR07 (27)), the strong/weak split X1, M1, M2 and its breakdown on contacts of
//! 2- and 3-coordinated grains (AR07 T.VI), and the histogram of the angle between the contact
//! normal and the contact force (GRC07 Fig. 15).
//!
//! Every statistic is taken over the contacts [`crate::metrics`] counts for z (the
//! force-carrying contacts between backbone grains; every interaction in cohesive packings),
//! so that `z⟨N⟩` enters the pressure relation AR07 (22) consistently.

use super::math::{mean, norm};
use super::series::Histogram;
use grainbench_engine::snapshot::Contact;
use serde::Serialize;

/// Normal-force statistics over the N_c counted contacts.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ForceStats {
    /// ⟨N⟩.
    pub mean_normal: Option<f64>,
    /// Z(2) = ⟨N²⟩/⟨N⟩² (AR07 (27), T.IV).
    pub z2: Option<f64>,
    /// Z(5/3) (AR07 (27)–(28)); only when no N is negative.
    pub z5_3: Option<f64>,
    /// X1: fraction of contacts with N > ⟨N⟩ (AR07 T.VI).
    pub x1: Option<f64>,
    /// M1, M2: mean |T|/N over contacts with N > ⟨N⟩, resp. 0 < N < ⟨N⟩ (AR07 T.VI).
    pub m1: Option<f64>,
    pub m2: Option<f64>,
    /// P(f), f = N/`pdf_unit`, as a density: AR07 Figs. 4, 15 (unit ⟨N⟩); for cohesive
    /// packings GRC07 Fig. 9 normalises by F0 instead (unit 1 in the F0 force unit).
    pub pdf: Option<Histogram>,
    /// The force that f is measured in: ⟨N⟩ (cohesionless) or F0 = 1 (cohesive).
    pub pdf_unit: Option<f64>,
    /// AR07 T.VI, superscript (2): contacts implying a grain with 2 backbone contacts.
    pub coordination_2: Option<PopulationStats>,
    /// AR07 T.VI, superscript (3): contacts implying a grain with 3 backbone contacts.
    pub coordination_3: Option<PopulationStats>,
    /// GRC07 Fig. 15: angle θ (degrees) between the normal n and the force F = Nn + T.
    pub angles: Option<Histogram>,
}

/// AR07 T.VI statistics of one population of contacts (those implying a grain of given
/// backbone coordination). X1, M1, M2 split the population at the *global* ⟨N⟩.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PopulationStats {
    /// Contacts in the population.
    pub contacts: usize,
    /// Mean normal force, in the snapshot's force unit.
    pub mean_normal: f64,
    /// N^(k): the mean normal force over P a^(d−1) (AR07: "normalized by Pa²"), with P the
    /// snapshot's `pressure_target` and a the largest diameter; `None` without a target.
    pub mean_normal_reduced: Option<f64>,
    /// X1^(k): fraction of the population with N > ⟨N⟩.
    pub x1: f64,
    /// M1^(k), M2^(k): mean |T|/N over the population with N > ⟨N⟩, resp. 0 < N < ⟨N⟩.
    pub m1: Option<f64>,
    pub m2: Option<f64>,
}

/// `|T|/N` (M1, M2 of AR07 T.VI).
fn mobilisation(c: &Contact) -> f64 {
    norm(&c.tangential) / c.normal
}

/// Z(α) = ⟨N^α⟩/⟨N⟩^α, AR07 (27). `None` for no forces, ⟨N⟩ = 0, a non-finite result, or a
/// non-integer α with some N < 0.
pub fn force_moment(normals: &[f64], alpha: f64) -> Option<f64> {
    let m = mean(normals.iter().copied())?;
    let integer = alpha.fract() == 0.0 && alpha.abs() < 64.0;
    if !integer && normals.iter().any(|&n| n < 0.0) {
        return None;
    }
    let pow = |x: f64| {
        if integer {
            x.powi(alpha as i32)
        } else {
            x.powf(alpha)
        }
    };
    let v = mean(normals.iter().map(|&n| pow(n)))? / pow(m);
    v.is_finite().then_some(v)
}

/// Strong/weak split at `threshold` (⟨N⟩ of AR07 T.VI): `(X1, M1, M2)` = fraction with
/// N > threshold, mean |T|/N over N > threshold (N > 0), over 0 < N < threshold.
pub fn strong_weak(
    contacts: &[&Contact],
    threshold: f64,
) -> (Option<f64>, Option<f64>, Option<f64>) {
    if contacts.is_empty() {
        return (None, None, None);
    }
    let strong = contacts.iter().filter(|c| c.normal > threshold);
    let x1 = strong.clone().count() as f64 / contacts.len() as f64;
    let m1 = mean(strong.filter(|c| c.normal > 0.0).map(|c| mobilisation(c)));
    let m2 = mean(
        contacts
            .iter()
            .filter(|c| c.normal < threshold && c.normal > 0.0)
            .map(|c| mobilisation(c)),
    );
    (Some(x1), m1, m2)
}

/// P(f), f = N/⟨N⟩ (AR07 Fig. 4, Fig. 15): density histogram with bins of width `bin_width`
/// in f starting at 0 (below if some N < 0). `None` without forces or unless ⟨N⟩ > 0.
pub fn pf_histogram(normals: &[f64], bin_width: f64) -> Option<Histogram> {
    pf_histogram_in(normals, mean(normals.iter().copied())?, bin_width)
}

/// P(f) with f = N/`unit` (GRC07 Fig. 9: unit F0 for cohesive packings). `None` without
/// forces or unless `unit` > 0.
pub fn pf_histogram_in(normals: &[f64], unit: f64, bin_width: f64) -> Option<Histogram> {
    if !(unit > 0.0 && unit.is_finite()) {
        return None;
    }
    let f: Vec<f64> = normals.iter().map(|n| n / unit).collect();
    Histogram::density_auto(&f, bin_width)
}

/// Angle θ in degrees between the contact normal n = branch/|branch| and the force
/// F = N n + T exerted by i on j (GRC07 Fig. 15): 0° for a repulsive normal force without
/// tangential part, 180° for a tensile one. `None` for F = 0 or a degenerate branch.
pub fn force_angle(c: &Contact) -> Option<f64> {
    let len = norm(&c.branch);
    if !(len > 0.0 && len.is_finite()) {
        return None;
    }
    let n: Vec<f64> = c.branch.iter().map(|x| x / len).collect();
    let t_n: f64 = c.tangential.iter().zip(&n).map(|(t, n)| t * n).sum();
    let along = c.normal + t_n;
    let across = (0..n.len())
        .map(|a| c.tangential.get(a).copied().unwrap_or(0.0) - t_n * n[a])
        .map(|x| x * x)
        .sum::<f64>()
        .sqrt();
    if along == 0.0 && across == 0.0 {
        return None;
    }
    let theta = across.atan2(along).to_degrees();
    theta.is_finite().then_some(theta)
}

/// GRC07 Fig. 15: density histogram (per degree) of [`force_angle`] over `contacts`, on
/// [0°, 180°] in bins of about `bin_width_deg` (narrowed to divide 180°; 180° itself falls in
/// the last bin). `None` if no contact carries a force.
pub fn force_angle_histogram(contacts: &[&Contact], bin_width_deg: f64) -> Option<Histogram> {
    if !(bin_width_deg > 0.0 && bin_width_deg.is_finite()) {
        return None;
    }
    let angles: Vec<f64> = contacts.iter().filter_map(|c| force_angle(c)).collect();
    let bins = (180.0 / bin_width_deg)
        .ceil()
        .clamp(1.0, super::series::MAX_BINS as f64) as usize;
    Histogram::density(&angles, 0.0, 180.0 / bins as f64, bins)
}

/// AR07 T.VI: statistics of the contacts implying a grain with exactly `k` counted contacts
/// (`k_of[g]`, backbone coordination). `threshold` is the global ⟨N⟩ splitting strong and
/// weak contacts; `pressure_scale` is P a^(d−1), the unit of N^(k). `None` if no contact
/// implies such a grain.
pub fn coordination_population(
    contacts: &[&Contact],
    k_of: &[usize],
    k: usize,
    threshold: f64,
    pressure_scale: Option<f64>,
) -> Option<PopulationStats> {
    let pop: Vec<&Contact> = contacts
        .iter()
        .copied()
        .filter(|c| k_of.get(c.i) == Some(&k) || k_of.get(c.j) == Some(&k))
        .collect();
    let mean_normal = mean(pop.iter().map(|c| c.normal))?;
    let (x1, m1, m2) = strong_weak(&pop, threshold);
    Some(PopulationStats {
        contacts: pop.len(),
        mean_normal,
        mean_normal_reduced: pressure_scale
            .filter(|s| *s > 0.0 && s.is_finite())
            .map(|s| mean_normal / s),
        x1: x1.unwrap_or(0.0),
        m1,
        m2,
    })
}

/// All of [`ForceStats`] over the counted `contacts`; `k_of[g]` is the number of counted
/// contacts of grain g, `pressure_scale` = P a^(d−1) (see [`PopulationStats`]), `pdf_unit`
/// the force unit of P(f) (`None`: ⟨N⟩).
pub fn force_stats(
    contacts: &[&Contact],
    k_of: &[usize],
    pressure_scale: Option<f64>,
    pdf_unit: Option<f64>,
    pdf_bin_width: f64,
    angle_bin_width_deg: f64,
) -> ForceStats {
    let normals: Vec<f64> = contacts.iter().map(|c| c.normal).collect();
    let mean_normal = mean(normals.iter().copied());
    let angles = force_angle_histogram(contacts, angle_bin_width_deg);
    let Some(m) = mean_normal else {
        return ForceStats {
            mean_normal: None,
            z2: None,
            z5_3: None,
            x1: None,
            m1: None,
            m2: None,
            pdf: None,
            pdf_unit: None,
            coordination_2: None,
            coordination_3: None,
            angles,
        };
    };
    let (x1, m1, m2) = strong_weak(contacts, m);
    let unit = pdf_unit.unwrap_or(m);
    let pdf = pf_histogram_in(&normals, unit, pdf_bin_width);
    ForceStats {
        mean_normal: Some(m),
        z2: force_moment(&normals, 2.0),
        z5_3: force_moment(&normals, 5.0 / 3.0),
        x1,
        m1,
        m2,
        pdf_unit: pdf.as_ref().map(|_| unit),
        pdf,
        coordination_2: coordination_population(contacts, k_of, 2, m, pressure_scale),
        coordination_3: coordination_population(contacts, k_of, 3, m, pressure_scale),
        angles,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use grainbench_engine::snapshot::Vector;

    fn contact(i: usize, j: usize, branch: &[f64], normal: f64, t: &[f64]) -> Contact {
        Contact {
            i,
            j,
            branch: Vector::from_slice(branch),
            normal,
            normal_elastic: normal.max(0.0),
            tangential: Vector::from_slice(t),
            rolling: Vector::new(),
            gap: 0.0,
        }
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1.0)
    }

    /// Z(α) on N = {1, 2, 3, 6}: ⟨N⟩ = 3, Z(2) = 50/4/9, Z(5/3) and Z(3) by hand; a
    /// fractional moment of a set with a negative force is undefined, an integer one is not.
    #[test]
    fn general_moments() {
        let n = [1.0, 2.0, 3.0, 6.0];
        assert!(close(force_moment(&n, 1.0).unwrap(), 1.0, 1e-15));
        assert!(close(
            force_moment(&n, 2.0).unwrap(),
            50.0 / 4.0 / 9.0,
            1e-15
        ));
        assert!(close(
            force_moment(&n, 3.0).unwrap(),
            252.0 / 4.0 / 27.0,
            1e-15
        ));
        let z53: f64 =
            n.iter().map(|x: &f64| x.powf(5.0 / 3.0)).sum::<f64>() / 4.0 / 3f64.powf(5.0 / 3.0);
        assert!(close(force_moment(&n, 5.0 / 3.0).unwrap(), z53, 1e-14));
        // Z(2) ≥ 1 (Jensen) and = 1 for equal forces.
        assert_eq!(force_moment(&[2.0; 5], 2.0), Some(1.0));
        let neg = [-1.0, 3.0];
        assert!(close(force_moment(&neg, 2.0).unwrap(), 5.0, 1e-15));
        assert_eq!(force_moment(&neg, 5.0 / 3.0), None);
        assert_eq!(force_moment(&[], 2.0), None);
        assert_eq!(force_moment(&[1.0, -1.0], 2.0), None, "⟨N⟩ = 0");
    }

    /// P(f) of N = {0.5, 0.5, 1, 2} (⟨N⟩ = 1) with bins of 0.5: densities 0, 1, 0.5, 0, 0.5,
    /// integrating to 1; undefined for ⟨N⟩ ≤ 0.
    #[test]
    fn pf_histogram_is_a_density_of_n_over_mean() {
        let h = pf_histogram(&[0.5, 0.5, 1.0, 2.0], 0.5).unwrap();
        assert_eq!(h.x, vec![0.25, 0.75, 1.25, 1.75, 2.25]);
        assert_eq!(h.y, vec![0.0, 1.0, 0.5, 0.0, 0.5]);
        assert_eq!(h.samples, 4);
        // Scaling every force leaves P(f) unchanged.
        assert_eq!(pf_histogram(&[5.0, 5.0, 10.0, 20.0], 0.5).unwrap(), h);
        assert!(pf_histogram(&[-1.0, 0.5], 0.1).is_none());
        // In a fixed unit (GRC07 Fig. 9, F0), negative forces get bins below 0.
        let h = pf_histogram_in(&[-1.0, 0.5], 1.0, 0.5).unwrap();
        assert_eq!(h.x, vec![-0.75, -0.25, 0.25, 0.75]);
        assert_eq!(h.y, vec![1.0, 0.0, 0.0, 1.0]);
        assert!(pf_histogram(&[], 0.1).is_none());
    }

    /// GRC07 Fig. 15 conventions: θ = 0 for N > 0, T = 0; 180° for N < 0, T = 0; the X-shaped
    /// pattern T/N = ±√3 of GRC07 (20) gives 60° (N > 0) and 120° (N < 0), in 2D and 3D.
    #[test]
    fn force_angles_follow_grc07_fig15() {
        let s3 = 3f64.sqrt();
        let cases = [
            (contact(0, 1, &[2.0, 0.0], 1.0, &[0.0, 0.0]), 0.0),
            (contact(0, 1, &[2.0, 0.0], -1.0, &[0.0, 0.0]), 180.0),
            (contact(0, 1, &[1.0, 0.0], 1.0, &[0.0, s3]), 60.0),
            (contact(0, 1, &[1.0, 0.0], 1.0, &[0.0, -s3]), 60.0),
            (contact(0, 1, &[1.0, 0.0], -1.0, &[0.0, s3]), 120.0),
            (contact(0, 1, &[0.0, 1.0], 0.0, &[0.3, 0.0]), 90.0),
            (contact(0, 1, &[0.0, 0.0, 1.0], 2.0, &[0.0, 2.0, 0.0]), 45.0),
            (contact(0, 1, &[0.0, 1.0, 0.0], 2.0, &[]), 0.0),
        ];
        for (c, theta) in &cases {
            assert!(close(force_angle(c).unwrap(), *theta, 1e-12), "{c:?}");
        }
        assert_eq!(force_angle(&contact(0, 1, &[1.0, 0.0], 0.0, &[])), None);
        let refs: Vec<&Contact> = cases.iter().map(|(c, _)| c).collect();
        // 40° asked: 5 bins of 36°. 0, 0 | 45, 60, 60 | 90 | 120 | 180 (in the last bin).
        let h = force_angle_histogram(&refs, 40.0).unwrap();
        assert_eq!(h.x, vec![18.0, 54.0, 90.0, 126.0, 162.0]);
        let per_deg = 1.0 / (8.0 * 36.0);
        let counts: Vec<f64> = h.y.iter().map(|y| y / per_deg).collect();
        for (got, want) in counts.iter().zip([2.0, 3.0, 1.0, 1.0, 1.0]) {
            assert!(close(*got, want, 1e-12), "{counts:?}");
        }
    }

    /// AR07 T.VI on a hand-made set: grain 0 has 2 contacts, grain 1 has 3, the others more.
    /// Contacts (N, |T|): A = 0–2 (3, 0.3), B = 0–3 (1, 0.2) are the (2) population;
    /// C = 1–4 (0.5, 0.05), D = 1–5 (2, 0.4), E = 1–6 (0.5, 0.1) the (3) population; F = 4–5
    /// (1, 0) implies neither. ⟨N⟩ = 8/6.
    #[test]
    fn t6_breakdown_by_coordination() {
        let cs = [
            contact(0, 2, &[1.0, 0.0], 3.0, &[0.0, 0.3]),
            contact(0, 3, &[0.0, 1.0], 1.0, &[0.2, 0.0]),
            contact(1, 4, &[1.0, 0.0], 0.5, &[0.0, 0.05]),
            contact(1, 5, &[1.0, 0.0], 2.0, &[0.0, -0.4]),
            contact(6, 1, &[1.0, 0.0], 0.5, &[0.0, 0.1]),
            contact(4, 5, &[1.0, 0.0], 1.0, &[0.0, 0.0]),
        ];
        let refs: Vec<&Contact> = cs.iter().collect();
        let k_of = [2, 3, 4, 4, 4, 4, 4];
        let s = force_stats(&refs, &k_of, Some(0.5), None, 0.1, 5.0);
        let m = 8.0 / 6.0;
        assert!(close(s.mean_normal.unwrap(), m, 1e-15));
        assert!(close(s.x1.unwrap(), 2.0 / 6.0, 1e-15));
        assert!(close(s.m1.unwrap(), (0.1 + 0.2) / 2.0, 1e-14));
        assert!(close(s.m2.unwrap(), (0.2 + 0.1 + 0.2 + 0.0) / 4.0, 1e-14));
        let p2 = s.coordination_2.unwrap();
        assert_eq!(p2.contacts, 2);
        assert!(close(p2.mean_normal, 2.0, 1e-15));
        assert!(close(p2.mean_normal_reduced.unwrap(), 4.0, 1e-15));
        assert!(close(p2.x1, 0.5, 1e-15));
        assert!(close(p2.m1.unwrap(), 0.1, 1e-14));
        assert!(close(p2.m2.unwrap(), 0.2, 1e-14));
        let p3 = s.coordination_3.unwrap();
        assert_eq!(p3.contacts, 3);
        assert!(close(p3.mean_normal, 1.0, 1e-15));
        assert!(close(p3.mean_normal_reduced.unwrap(), 2.0, 1e-15));
        assert!(close(p3.x1, 1.0 / 3.0, 1e-15));
        assert!(close(p3.m1.unwrap(), 0.2, 1e-14));
        assert!(close(p3.m2.unwrap(), (0.1 + 0.2) / 2.0, 1e-14));
        // Without a pressure the reduced force is undefined; without 2-coordinated grains the
        // (2) population is.
        let s = force_stats(&refs, &[5, 3, 4, 4, 4, 4, 4], None, None, 0.1, 5.0);
        assert!(s.coordination_2.is_none());
        assert!(s.coordination_3.unwrap().mean_normal_reduced.is_none());
        // No contacts at all: nothing defined, nothing panics.
        let e = force_stats(&[], &[], Some(1.0), None, 0.1, 5.0);
        assert!(e.mean_normal.is_none() && e.pdf.is_none() && e.angles.is_none());
    }
}
