//! Rendering an [`Analysis`]: a markdown table (`metric | value | note`) or JSON.

use super::format::sig6;
use crate::metrics::stiffness::RankMethod;
use crate::metrics::Analysis;
use std::fmt::Write;

/// Pretty-printed JSON of the whole analysis (non-finite numbers become `null`).
pub fn to_json(a: &Analysis) -> String {
    serde_json::to_string_pretty(a).expect("Analysis serialises to JSON")
}

fn opt(x: Option<f64>) -> String {
    x.map(sig6).unwrap_or_else(|| "n/a".to_string())
}

fn pct(x: f64) -> String {
    format!("{}%", sig6(100.0 * x))
}

/// Abscissa of the largest ordinate (first one on ties).
fn mode(x: &[f64], y: &[f64]) -> f64 {
    let mut best = 0;
    for k in 1..y.len().min(x.len()) {
        if y[k] > y[best] {
            best = k;
        }
    }
    x.get(best).copied().unwrap_or(f64::NAN)
}

/// Markdown rendering: a title line and one table `metric | value | note`.
pub fn to_markdown(a: &Analysis) -> String {
    let mut rows: Vec<(String, String, String)> = Vec::new();
    {
        let mut row = |m: &str, v: String, note: &str| rows.push((m.into(), v, note.into()));
        coordination_rows(a, &mut row);
        force_rows(a, &mut row);
        structure_rows(a, &mut row);
        density_rows(a, &mut row);
        moduli_rows(a, &mut row);
        pressure_rows(a, &mut row);
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "## {} ({}, step {}, t = {}, {})\n",
        a.scene,
        a.code,
        a.step,
        sig6(a.time),
        a.status
    );
    out.push_str("| metric | value | note |\n| --- | --- | --- |\n");
    for (m, v, n) in rows {
        let _ = writeln!(out, "| {m} | {v} | {} |", n.replace('|', "\\|"));
    }
    out
}

/// The grains and their contacts: Φ, z, the rattlers (AR07 §III.B–C), x_k, and the split of
/// cohesive interactions by force sign (GRC07 T.VI).
fn coordination_rows(a: &Analysis, row: &mut dyn FnMut(&str, String, &str)) {
    row("n", a.n.to_string(), "grains");
    row("dimension", a.dimension.to_string(), "");
    row(
        "μ",
        a.mu.map(sig6).unwrap_or_else(|| "∞".into()),
        if a.cohesive {
            "cohesive law"
        } else {
            "cohesionless law"
        },
    );
    row("Φ", sig6(a.packing_fraction), "solid fraction");
    row(
        "interactions",
        a.interactions.to_string(),
        "listed contacts and distant attractions",
    );
    row(
        "force threshold",
        sig6(a.force_threshold),
        if a.cohesive {
            "absolute, in the force unit (F0 for GRC07, T.VI)"
        } else {
            "tolerance × ⟨|N|⟩"
        },
    );
    row(
        "force-carrying",
        a.force_carrying.to_string(),
        "interactions with |N| above threshold",
    );
    row(
        "N_c",
        a.contacts.to_string(),
        if a.cohesive {
            "all interactions between non-isolated grains"
        } else {
            "force-carrying contacts between backbone grains"
        },
    );
    row("z", sig6(a.z), "2N_c/n (AR07 §III.B)");
    row("rule", format!("{:?}", a.rule), &a.rule.describe());
    row(
        "x0",
        pct(a.rattler_fraction),
        &format!(
            "rattlers: {} grains, {} sweep(s)",
            a.rattlers, a.rattler_sweeps
        ),
    );
    row("z*", opt(a.z_backbone), "z/(1−x0), GRC07 (13)");
    for (k, &x) in a.x_k.iter().enumerate() {
        if x > 0.0 {
            row(
                &format!("x_{k}"),
                pct(x),
                if k == 0 {
                    "= x0"
                } else {
                    "grains with k contacts (AR07 T.V, I)"
                },
            );
        }
    }
    if let Some(f) = &a.fixed_rattlers {
        row(
            "z^II(0)",
            sig6(f.z_geometric),
            &format!(
                "rattlers fixed onto the backbone (AR07 §III.C, II): {} moved, {} contacts with \
                 rattlers ({} between rattlers), {} unsettled",
                f.rattlers, f.rattler_contacts, f.rattler_rattler_contacts, f.unsettled
            ),
        );
        for (k, &x) in f.x_k.iter().enumerate() {
            if x > 0.0 {
                row(
                    &format!("x_{k}^II"),
                    pct(x),
                    "grains with k geometric contacts (AR07 T.V, II)",
                );
            }
        }
    }
    if let Some(s) = &a.cohesive_split {
        row("z+", sig6(s.z_plus), "repulsive (GRC07 T.VI)");
        row("z−", sig6(s.z_minus), "attractive");
        row("z0", sig6(s.z_zero), "|N| ≤ threshold");
        row("distant pairs", s.distant.to_string(), "gap > 0");
        row(
            "clusters",
            s.clusters.to_string(),
            "groups of grains linked by interactions",
        );
        row(
            "wrapped axes",
            format!("{} of {}", s.wrapped_axes, a.dimension),
            "axes along which the interaction network wraps the cell (GRC07 §III.B.1)",
        );
        row("N+", opt(s.mean_repulsive), "mean repulsive force");
        row("N+^(2)", opt(s.rms_repulsive), "quadratic mean");
        row("N−", opt(s.mean_attractive), "mean |attractive force|");
        row("N−^(2)", opt(s.rms_attractive), "quadratic mean");
    }
}

/// The contact forces: ⟨N⟩, Z(2), Z(5/3), X1, M1, M2 (AR07 (27)–(28), T.VI), P(f) and the
/// force angles.
fn force_rows(a: &Analysis, row: &mut dyn FnMut(&str, String, &str)) {
    let f = &a.forces;
    row("⟨N⟩", opt(f.mean_normal), "over the N_c contacts");
    row("Z(2)", opt(f.z2), "⟨N²⟩/⟨N⟩², AR07 (27)");
    row("Z(5/3)", opt(f.z5_3), "AR07 (28)");
    row("X1", opt(f.x1), "fraction with N > ⟨N⟩ (AR07 T.VI)");
    row("M1", opt(f.m1), "⟨|T|/N⟩, N > ⟨N⟩");
    row("M2", opt(f.m2), "⟨|T|/N⟩, N < ⟨N⟩");
    for (k, pop) in [(2, &f.coordination_2), (3, &f.coordination_3)] {
        if let Some(p) = pop {
            row(
                &format!("N^({k})"),
                opt(p.mean_normal_reduced),
                &format!(
                    "mean N / (P a^(d−1)) on the {} contacts of {k}-coordinated grains (AR07 T.VI)",
                    p.contacts
                ),
            );
            row(&format!("X1^({k})"), sig6(p.x1), "fraction with N > ⟨N⟩");
            row(&format!("M1^({k})"), opt(p.m1), "⟨|T|/N⟩, N > ⟨N⟩");
            row(&format!("M2^({k})"), opt(p.m2), "⟨|T|/N⟩, N < ⟨N⟩");
        }
    }
    if let Some(h) = &f.pdf {
        row(
            "P(f)",
            format!("{} bins", h.x.len()),
            &format!(
                "f = N/{}, width {}, mode at f = {} (series in JSON: forces.pdf)",
                if a.cohesive {
                    "(force unit)"
                } else {
                    "⟨N⟩"
                },
                sig6(h.bin_width),
                sig6(mode(&h.x, &h.y))
            ),
        );
    }
    if let Some(h) = &f.angles {
        row(
            "force angle θ",
            format!("{} bins", h.x.len()),
            &format!(
                "angle between n and F (GRC07 Fig. 15), mode at {}° (series in JSON: forces.angles)",
                sig6(mode(&h.x, &h.y))
            ),
        );
    }
}

/// The structure: g(r), z(h), bond order and local environments (AR07 §III.D, T.II,
/// T.VII–T.VIII).
fn structure_rows(a: &Analysis, row: &mut dyn FnMut(&str, String, &str)) {
    let st = &a.structure;
    if let Some(g) = &st.pair_correlation {
        row(
            "g(r)",
            format!("{} bins", g.x.len()),
            &format!(
                "peak g = {} at r/a = {} (series in JSON: structure.pair_correlation)",
                sig6(g.y.iter().copied().fold(0.0, f64::max)),
                sig6(mode(&g.x, &g.y))
            ),
        );
    }
    for (name, z) in [
        ("z^I", &st.gap_coordination_i),
        ("z^II", &st.gap_coordination_ii),
        ("z^III", &st.gap_coordination_iii),
    ] {
        if let Some(z) = z {
            let at = |h: f64| {
                z.x.iter()
                    .position(|&x| x >= h * (1.0 - 1e-9))
                    .map(|k| sig6(z.y[k]))
                    .unwrap_or_else(|| "n/a".into())
            };
            row(
                &format!("{name}(h)"),
                at(0.0),
                &format!(
                    "at h = 0; {} at h = 0.01a, {} at h = 0.1a (AR07 §III.D, series in JSON)",
                    at(0.01),
                    at(0.1)
                ),
            );
        }
    }
    if let Some(b) = &a.bond_order {
        let dc = format!("d_c = {}a", sig6(b.cutoff));
        row(
            "Z (bonds)",
            sig6(b.z_bond),
            &format!("{dc}, {} bonds (AR07 T.II)", b.bonds),
        );
        row("Q6", opt(b.q6_global), "global, over all bonds");
        row("Q4", opt(b.q4_global), "global, over all bonds");
        row("Q6^loc", opt(b.q6_local), "mean of AR07 (31)");
        row("Q4^loc", opt(b.q4_local), "mean of AR07 (31)");
        row(
            "Z_cr",
            sig6(b.z_cr),
            &format!("{} crystalline bonds, AR07 (34)", b.crystalline_bonds),
        );
        row(
            "x_cr",
            sig6(b.x_cr),
            &format!("{} grains with ≥ 7 crystalline bonds", b.crystalline_grains),
        );
        row(
            "Q6^loc,cr",
            opt(b.q6_local_cr),
            "mean Q6^loc of crystalline grains",
        );
        row(
            "⟨n_cr⟩",
            opt(b.n_cr),
            &format!(
                "mass-average cluster size ({} clusters, largest {})",
                b.clusters, b.largest_cluster
            ),
        );
    }
    let by_sample = |v: &[(String, f64)]| {
        v.iter()
            .map(|(sample, x)| format!("{sample} {}", pct(*x)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for e in a.local_environments.iter().flatten() {
        row(
            &format!("fcc / hcp, d_c = {}a", sig6(e.cutoff)),
            format!("{} / {}", pct(e.fcc), pct(e.hcp)),
            &format!(
                "AR07 T.VII–T.VIII; disordered modes of Aste et al.'s samples: {}; hcp-like outside each: {}",
                by_sample(&e.disordered),
                by_sample(&e.hcp_outside)
            ),
        );
    }
}

/// The density correlations of 2D cohesive packings (GRC07 §V).
fn density_rows(a: &Analysis, row: &mut dyn FnMut(&str, String, &str)) {
    if let Some(c) = &a.density {
        match &c.fit {
            Some(f) => row(
                "d_F, ξ",
                format!(
                    "{} ± {}, {} ± {}",
                    sig6(f.model.d_f),
                    sig6(f.d_f_error),
                    sig6(f.model.xi),
                    sig6(f.xi_error)
                ),
                &format!(
                    "GRC07 (28) fitted to I(k) over {} ≤ ka ≤ {} ({} shells, rms ln residual {}; \
                     mesh {}×{}, series in JSON: density)",
                    sig6(f.k_min),
                    sig6(f.k_max),
                    f.points,
                    sig6(f.rms_log_residual),
                    c.nodes[0],
                    c.nodes[1]
                ),
            ),
            None => row(
                "d_F, ξ",
                "n/a".into(),
                "GRC07 (28) could not be fitted to I(k)",
            ),
        }
        row(
            "⟨R⟩_w",
            opt(c.holes.weighted_radius),
            &format!(
                "hole radius, GRC07 (30), in a: {} holes{}",
                c.holes.count,
                if c.holes.percolating {
                    "; the empty space percolates (GRC07 §V.C: P* > 0 only)"
                } else {
                    ""
                }
            ),
        );
    }
}

/// The elastic moduli and rigidity (GRC08 §VI, GRC07 App. A), where asked for.
fn moduli_rows(a: &Analysis, row: &mut dyn FnMut(&str, String, &str)) {
    match &a.moduli {
        Some(Ok(m)) => {
            row(
                "B, G",
                format!("{}, {}", sig6(m.bulk), sig6(m.shear)),
                &format!(
                    "elastic moduli from K·U = F^ext (GRC08 (6)): {} interactions ({} distant), {} degrees of freedom; C_αβ = [{}]",
                    m.interactions,
                    m.distant,
                    m.dofs,
                    m.stiffness
                        .iter()
                        .map(|r| r.iter().map(|x| sig6(*x)).collect::<Vec<_>>().join(", "))
                        .collect::<Vec<_>>()
                        .join("; ")
                ),
            );
            row(
                "B^V, G^V",
                format!("{}, {}", sig6(m.voigt_bulk), sig6(m.voigt_shear)),
                &format!(
                    "Voigt (GRC08 (12), affine): B^V/B = {}, G^V/G = {}",
                    sig6(m.voigt_bulk / m.bulk),
                    sig6(m.voigt_shear / m.shear)
                ),
            );
            row(
                "B^R",
                opt(m.reuss_bulk),
                &format!(
                    "Reuss (GRC08 (13)–(14), forces scaled with P): B/B^R = {}",
                    opt(m.reuss_bulk.map(|r| m.bulk / r))
                ),
            );
            row(
                "95 % of the energy",
                m.energy_95.map(pct).unwrap_or_else(|| "n/a".into()),
                "of the contacts, by decreasing energy, in the response to an isotropic pressure increment (GRC08 §VI.E)",
            );
            if let Some(r) = &m.rigidity {
                row(
                    "mechanisms K, indeterminacy H",
                    format!("{}, {}", r.mechanisms, r.indeterminacy),
                    &format!(
                        "cell fixed, GRC07 App. A: N_f + H = M + K with N_f = {}, M = {} (K counts the global translations; zero eigenvalues of ᵀG·G counted {})",
                        r.dofs,
                        r.constraints,
                        match r.method {
                            RankMethod::DenseEigenvalues => "from all eigenvalues",
                            RankMethod::SparseInertia => "by the inertia of a sparse LDLᵀ",
                        }
                    ),
                );
            }
        }
        Some(Err(e)) => row("B, G", "n/a".into(), e),
        None => {}
    }
}

/// The pressure and its checks (AR07 (22), Rumpf, GRC07 (18)).
fn pressure_rows(a: &Analysis, row: &mut dyn FnMut(&str, String, &str)) {
    let p = &a.pressure;
    row("P measured", opt(p.measured), "tr σ_contact / d");
    row("P kinetic", opt(p.kinetic), "tr σ_kinetic / d");
    row(
        "P exact",
        sig6(p.exact),
        &format!(
            "(1/dΩ) Σ (N|r| + T·r), rel. diff {} (tangential part {})",
            opt(p.exact_rel_diff),
            sig6(p.exact_tangential)
        ),
    );
    if let Some(r) = &p.ar07_22 {
        row(
            "P, AR07 (22)",
            sig6(r.p_predicted),
            &format!(
                "zΦ⟨N⟩/(πa²), a = {}, rel. diff {}",
                sig6(r.diameter),
                sig6(r.rel_diff)
            ),
        );
    }
    if let Some(r) = &p.rumpf {
        row(
            "⟨N⟩, GRC07 (17)",
            sig6(r.mean_normal_predicted),
            &format!(
                "π⟨d^D⟩P/(⟨d⟩zΦ), ⟨d⟩ = {}, ⟨d^D⟩ = {}, rel. diff {}",
                sig6(r.mean_diameter),
                sig6(r.mean_diameter_pow_d),
                opt(r.rel_diff)
            ),
        );
    }
    if let Some(r) = &p.grc07_18 {
        row(
            "⟨N⟩, GRC07 (18)",
            sig6(r.mean_normal_predicted),
            &format!(
                "7πaP/(9zΦ), a = {}, ⟨d⟩/a = {} (3/4), ⟨d²⟩/a² = {} (7/12), rel. diff {}",
                sig6(r.a),
                sig6(r.mean_diameter_over_a),
                sig6(r.mean_diameter_sq_over_a2),
                opt(r.rel_diff)
            ),
        );
    }
}
