//! The files of `accuracy`: CSV, JSON, Markdown and the error-against-cost plots.

use super::knobs::Settings;
use super::table::{Row, Table, METRICS};
use anyhow::Result;
use grainbench_comparisons::report::format::{sci4_or_blank, sig3_or_dash};
use grainbench_comparisons::report::plots;
use grainbench_comparisons::stats::pareto;
use grainbench_comparisons::xcode::decks::Code;
use grainbench_engine::snapshot::write_atomic;
use grainbench_engine::Scene;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// A status for the Markdown table: the cause without the scene name and the advice (the
/// CSV and JSON keep the whole message).
fn md_status(status: &str) -> String {
    let s = status.split(". Likely cause").next().unwrap_or(status);
    match s.split_once(": scene ") {
        Some((head, rest)) => match rest.split_once(": ") {
            Some((_, cause)) => format!("{head}: {cause}"),
            None => s.to_string(),
        },
        None => s.to_string(),
    }
    .replace('|', "/")
}

/// accuracy.csv, accuracy.json (with `max_time`, the cap on stage times), accuracy.md (printed
/// unless `quiet`) and the error-against-cost plots.
pub fn write_outputs(
    out: &Path,
    base: &Scene,
    seeds: &[u64],
    t: &Table,
    max_time: Option<f64>,
    quiet: bool,
) -> Result<()> {
    write_atomic(&out.join("accuracy.csv"), to_csv(t).as_bytes())?;
    let doc = to_json(base, seeds, t, max_time);
    write_atomic(
        &out.join("accuracy.json"),
        serde_json::to_string_pretty(&doc)?.as_bytes(),
    )?;
    let md = to_markdown(base, seeds, t);
    write_atomic(&out.join("accuracy.md"), md.as_bytes())?;
    let plotted = plot(out, base, t);
    if !quiet {
        print!("{md}");
    }
    println!(
        "wrote {}, {}, {}{}",
        out.join("accuracy.md").display(),
        out.join("accuracy.csv").display(),
        out.join("accuracy.json").display(),
        if plotted.is_empty() {
            String::new()
        } else {
            format!(" and {} plots (SVG + PNG)", plotted.len())
        }
    );
    Ok(())
}

/// accuracy.csv: one row per code, knob value and seed-averaged result.
fn to_csv(t: &Table) -> String {
    let mut csv = String::from("code,knob,value,default,status,wall_seconds,steps,phi,z_star,x0,err_phi,err_z_star,err_x0,ks,combined,pareto,paper_err_phi,paper_err_z_star,paper_err_x0,dt_fraction,inertia_cap,tolerance_factor,kappa\n");
    for r in &t.rows {
        let _ = writeln!(
            csv,
            "{},{},{:e},{},\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:e},{},{:e},{:e}",
            r.code.name(),
            r.knob,
            r.value,
            r.is_default,
            r.status.replace('"', "'"),
            sci4_or_blank(r.wall_seconds),
            sci4_or_blank(r.steps),
            sci4_or_blank(r.values.get("phi").copied()),
            sci4_or_blank(r.values.get("z_star").copied()),
            sci4_or_blank(r.values.get("x0").copied()),
            sci4_or_blank(r.errors.get("phi").copied()),
            sci4_or_blank(r.errors.get("z_star").copied()),
            sci4_or_blank(r.errors.get("x0").copied()),
            sci4_or_blank(r.errors.get("ks").copied()),
            sci4_or_blank(r.combined),
            r.pareto,
            sci4_or_blank(r.paper_errors.get("phi").copied()),
            sci4_or_blank(r.paper_errors.get("z_star").copied()),
            sci4_or_blank(r.paper_errors.get("x0").copied()),
            r.settings.dt,
            sci4_or_blank(r.settings.inertia),
            r.settings.tolerance,
            r.settings.kappa,
        );
    }
    csv
}

/// accuracy.json: the rows, the references and the paper's values, with the run settings.
fn to_json(base: &Scene, seeds: &[u64], t: &Table, max_time: Option<f64>) -> Value {
    let rows: Vec<Value> = t
        .rows
        .iter()
        .map(|r| {
            json!({
                "code": r.code.name(),
                "knob": r.knob,
                "value": r.value,
                "default": r.is_default,
                "status": r.status,
                "stable": !r.errors.is_empty(),
                "wall_seconds": r.wall_seconds,
                "steps": r.steps,
                "values": r.values,
                "errors": r.errors,
                "combined_error": r.combined,
                "pareto": r.pareto,
                "paper_errors": r.paper_errors,
                "settings": r.settings.to_json(),
            })
        })
        .collect();
    let reference: BTreeMap<&str, Value> = t
        .reference
        .iter()
        .map(|(c, rs)| {
            (
                *c,
                json!({
                    "settings": rs.settings.map(Settings::to_json),
                    "status": rs.status,
                    "wall_seconds": rs.wall_seconds,
                    "mean": rs.mean,
                    "seed_spread": rs.spread,
                }),
            )
        })
        .collect();
    let paper: BTreeMap<&str, Value> = t
        .paper
        .iter()
        .map(|(m, (v, sd))| (*m, json!({"value": v, "sd": sd})))
        .collect();
    json!({
        "scene": base.name,
        "seeds": seeds,
        "max_time": max_time,
        "threads": rayon::current_num_threads(),
        "engine": env!("CARGO_PKG_VERSION"),
        "paper_state": t.paper_state,
        "paper": paper,
        "reference": reference,
        "error_definition": "mean over seeds of |metric - reference of the same seed| (phi, z_star, x0); ks: mean over seeds of the two-sample Kolmogorov-Smirnov distance of f = N/<N> to the pooled reference forces; combined: mean of the four errors, each in units of the reference seed spread (or of the sweep's largest error of that metric when there is no spread)",
        "rows": rows,
    })
}

/// accuracy.md: the references, the paper comparison and the table of every knob value.
fn to_markdown(base: &Scene, seeds: &[u64], t: &Table) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Speed against error: {} (seeds {})\n",
        base.name,
        seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    );
    for (c, rs) in &t.reference {
        let s = rs.settings.expect("reference settings");
        let _ = writeln!(
            md,
            "Reference ({c}): dt_fraction = {}, I = {}, tolerance × {}, κ = {} — {}, {} s per seed.  ",
            s.dt,
            sig3_or_dash(s.inertia),
            s.tolerance,
            s.kappa,
            rs.status,
            sig3_or_dash(rs.wall_seconds)
        );
        let _ = writeln!(
            md,
            "Reference means: Φ = {}, z* = {}, x0 = {}; seed spread (s.d.): Φ {}, z* {}, x0 {}, KS (leave-one-out) {}.\n",
            sig3_or_dash(rs.mean.get("phi").copied()),
            sig3_or_dash(rs.mean.get("z_star").copied()),
            sig3_or_dash(rs.mean.get("x0").copied()),
            sig3_or_dash(rs.spread.get("phi").copied()),
            sig3_or_dash(rs.spread.get("z_star").copied()),
            sig3_or_dash(rs.spread.get("x0").copied()),
            sig3_or_dash(rs.spread.get("ks").copied()),
        );
    }
    if let Some(ps) = &t.paper_state {
        let _ = writeln!(
            md,
            "Paper ({ps}): {}.\n",
            t.paper
                .iter()
                .map(|(m, (v, sd))| format!(
                    "{m} = {v}{}",
                    sd.map(|s| format!(" ± {s}")).unwrap_or_default()
                ))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let _ = writeln!(md, "Errors: mean over seeds of |metric − reference of the same seed|; KS = mean Kolmogorov–Smirnov distance of P(f) to the pooled reference forces; comb. = mean of the four errors in units of the reference seed spread (≲ 1: within sample noise); P = on the Pareto front of (wall time, comb.). `*` marks the scene's own value.\n");
    let paper_cols = !t.paper.is_empty();
    let _ = writeln!(
        md,
        "| code | knob | value | status | wall s | steps | Φ | z* | x0 | err Φ | err z* | err x0 | KS | comb. | P |{}",
        if paper_cols {
            " Φ−paper | z*−paper | x0−paper |"
        } else {
            ""
        }
    );
    let _ = writeln!(
        md,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|{}",
        if paper_cols { "---|---|---|" } else { "" }
    );
    for r in &t.rows {
        let g = |m: &BTreeMap<&str, f64>, k: &str| sig3_or_dash(m.get(k).copied());
        let _ = write!(
            md,
            "| {} | {} | {}{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.code.name(),
            r.knob,
            format_args!("{:.3e}", r.value),
            if r.is_default { " *" } else { "" },
            md_status(&r.status),
            sig3_or_dash(r.wall_seconds),
            r.steps
                .filter(|s| *s > 0.0)
                .map_or("—".into(), |s| format!("{s:.0}")),
            g(&r.values, "phi"),
            g(&r.values, "z_star"),
            g(&r.values, "x0"),
            g(&r.errors, "phi"),
            g(&r.errors, "z_star"),
            g(&r.errors, "x0"),
            g(&r.errors, "ks"),
            sig3_or_dash(r.combined),
            if r.pareto { "P" } else { "" },
        );
        if paper_cols {
            let _ = write!(
                md,
                " {} | {} | {} |",
                g(&r.paper_errors, "phi"),
                g(&r.paper_errors, "z_star"),
                g(&r.paper_errors, "x0")
            );
        }
        md.push('\n');
    }
    md.push_str("\nKnobs per code: rust — dt, inertia, tolerance, kappa; lammps — dt only (its deck takes our time step; no strain-rate cap of our kind, no equilibrium criteria, κ fixed by the deck).\n");
    md
}

/// Error against wall time, one plot per metric and the combined one; returns the SVGs.
fn plot(out: &Path, base: &Scene, t: &Table) -> Vec<String> {
    let mut plotted = Vec::new();
    for m in METRICS.iter().copied().chain(["combined"]) {
        let err_of = |r: &Row| {
            if m == "combined" {
                r.combined
            } else {
                r.errors.get(m).copied()
            }
        };
        let mut series_pts: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        let mut all: Vec<Option<(f64, f64)>> = Vec::new();
        let mut curves: BTreeMap<String, Vec<(f64, f64, f64)>> = BTreeMap::new();
        for r in &t.rows {
            let p = r.wall_seconds.zip(err_of(r));
            if r.code == Code::Rust {
                all.push(p);
            }
            if let Some((c, e)) = p {
                curves
                    .entry(format!("{} {}", r.code.name(), r.knob))
                    .or_default()
                    .push((r.value, c, e));
            }
        }
        for (label, mut v) in curves {
            v.sort_by(|x, y| x.0.total_cmp(&y.0));
            series_pts.push((label, v.into_iter().map(|(_, c, e)| (c, e)).collect()));
        }
        let flags = pareto(&all);
        let rust_rows: Vec<&Row> = t.rows.iter().filter(|r| r.code == Code::Rust).collect();
        let mut front: Vec<(f64, f64)> = rust_rows
            .iter()
            .zip(&flags)
            .filter(|(_, f)| **f)
            .filter_map(|(r, _)| r.wall_seconds.zip(err_of(r)))
            .collect();
        front.sort_by(|x, y| x.0.total_cmp(&y.0));
        front.dedup();
        series_pts.push(("Pareto front (rust)".into(), front));
        let series: Vec<plots::Series> = series_pts
            .iter()
            .map(|(l, p)| plots::Series::new(l, p))
            .collect();
        let title = format!("{}: error of {m} against cost", base.name);
        let y_label = match m {
            "combined" => "combined error (units of seed spread)".to_string(),
            "ks" => "KS distance of P(f)".to_string(),
            _ => format!("|{m} - reference|"),
        };
        let mut plot = plots::LinePlot::new(&title, "wall time per seed (s)", &y_label, &series);
        plot.x_axis = plots::Axis::Log;
        plot.y_axis = plots::Axis::Log;
        plot.marks = plots::Marks::LinesAndPoints;
        match plots::line_plot(&out.join(format!("accuracy-{m}")), &plot) {
            Ok(f) => plotted.push(f.svg.display().to_string()),
            Err(e) => eprintln!("accuracy: no plot of {m}: {e}"),
        }
    }
    plotted
}
