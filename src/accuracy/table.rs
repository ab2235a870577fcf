//! The table of `accuracy`: per point the mean over seeds, the error against the reference
//! of the same seed, the combined error in units of the seed spread, and the Pareto front.

use super::knobs::{Point, Settings};
use super::record::{short_message, Record};
use grainbench_comparisons::report::paper;
use grainbench_comparisons::stats::{ks_distance, mean, pareto, sample_sd};
use grainbench_comparisons::xcode::decks::Code;
use grainbench_engine::run::StepEnd;
use grainbench_engine::Scene;
use std::collections::BTreeMap;

/// The metrics errors are measured on.
pub const METRICS: [&str; 4] = ["phi", "z_star", "x0", "ks"];

pub fn metric_of(r: &Record, m: &str) -> Option<f64> {
    match m {
        "phi" => r.phi,
        "z_star" => r.z_star,
        "x0" => r.x0,
        _ => None,
    }
}

/// One row of the table.
#[derive(Clone, Debug)]
pub struct Row {
    pub code: Code,
    pub knob: String,
    pub value: f64,
    pub is_default: bool,
    pub settings: Settings,
    pub status: String,
    pub wall_seconds: Option<f64>,
    pub steps: Option<f64>,
    /// Metric → (mean over seeds of the metric, error against the reference).
    pub values: BTreeMap<&'static str, f64>,
    pub errors: BTreeMap<&'static str, f64>,
    /// Metric → |seed mean − paper value|.
    pub paper_errors: BTreeMap<&'static str, f64>,
    pub combined: Option<f64>,
    pub pareto: bool,
}

pub struct Table {
    pub rows: Vec<Row>,
    /// Reference (per code): metric → (mean, seed spread).
    pub reference: BTreeMap<&'static str, ReferenceStats>,
    pub paper_state: Option<String>,
    /// Metric → (paper value, paper sd).
    pub paper: BTreeMap<&'static str, (f64, Option<f64>)>,
}

#[derive(Clone, Debug, Default)]
pub struct ReferenceStats {
    pub settings: Option<Settings>,
    pub status: String,
    pub wall_seconds: Option<f64>,
    pub mean: BTreeMap<&'static str, f64>,
    /// Sample s.d. over seeds (KS: mean leave-one-out distance of a seed to the others).
    pub spread: BTreeMap<&'static str, f64>,
}

pub fn build_table(
    base: &Scene,
    points: &[Point],
    records: &BTreeMap<(Code, String, u64), Record>,
    seeds: &[u64],
) -> Table {
    let recs = |p: &Point| -> Vec<&Record> {
        seeds
            .iter()
            .filter_map(|&s| records.get(&(p.code, p.settings.key(), s)))
            .collect()
    };
    let paper_state = base.paper_state.clone();
    let mut paper_vals = BTreeMap::new();
    if let Some(st) = paper_state.as_deref().and_then(paper::paper_values) {
        for m in ["phi", "z_star", "x0"] {
            if let Some(v) = st.values.get(m) {
                paper_vals.insert(m, (v.value, v.sd));
            }
        }
    }
    let mut reference: BTreeMap<&'static str, ReferenceStats> = BTreeMap::new();
    let mut rows = Vec::new();
    let codes: Vec<Code> = {
        let mut c: Vec<Code> = points.iter().map(|p| p.code).collect();
        c.dedup();
        c
    };
    for code in codes {
        let Some(rp) = points.iter().find(|p| p.code == code && p.knob.is_none()) else {
            continue;
        };
        let ref_recs = recs(rp);
        let ref_ok: BTreeMap<u64, &Record> = ref_recs
            .iter()
            .filter(|r| r.packing())
            .map(|r| (r.seed, *r))
            .collect();
        let pooled: Vec<f64> = ref_ok.values().flat_map(|r| r.forces.clone()).collect();
        let rs = reference_stats(rp, &ref_recs, &ref_ok, seeds.len());
        let mut code_rows = Vec::new();
        for p in points.iter().filter(|p| p.code == code && p.knob.is_some()) {
            let rr = recs(p);
            let status = point_status(&rr, seeds.len());
            let mut row = Row {
                code,
                knob: p.knob.map_or("reference", |k| k.name()).to_string(),
                value: p.knob.map_or(f64::NAN, |k| p.settings.get(k)),
                is_default: p.is_default,
                settings: p.settings,
                status: status.clone(),
                wall_seconds: mean(&rr.iter().map(|r| r.wall_seconds).collect::<Vec<_>>()),
                steps: mean(&rr.iter().map(|r| r.steps as f64).collect::<Vec<_>>()),
                values: BTreeMap::new(),
                errors: BTreeMap::new(),
                paper_errors: BTreeMap::new(),
                combined: None,
                pareto: false,
            };
            let stable = rr.len() == seeds.len() && rr.iter().all(|r| r.packing());
            if stable {
                for m in ["phi", "z_star", "x0"] {
                    let v: Vec<f64> = rr.iter().filter_map(|r| metric_of(r, m)).collect();
                    if let Some(x) = mean(&v) {
                        row.values.insert(m, x);
                        if let Some((pv, _)) = paper_vals.get(m) {
                            row.paper_errors.insert(m, (x - pv).abs());
                        }
                    }
                    let e: Vec<f64> = rr
                        .iter()
                        .filter_map(|r| {
                            Some((metric_of(r, m)? - metric_of(ref_ok.get(&r.seed)?, m)?).abs())
                        })
                        .collect();
                    if let Some(x) = mean(&e) {
                        row.errors.insert(m, x);
                    }
                }
                let ks: Vec<f64> = rr
                    .iter()
                    .filter_map(|r| ks_distance(&r.forces, &pooled))
                    .collect();
                if let Some(x) = mean(&ks) {
                    row.errors.insert("ks", x);
                }
            }
            code_rows.push(row);
        }
        combine(&mut code_rows, &rs);
        reference.insert(code.name(), rs);
        rows.extend(code_rows);
    }
    Table {
        rows,
        reference,
        paper_state,
        paper: paper_vals,
    }
}

/// The reference point of a code over its seeds: Φ, z*, x0 (mean and seed spread) and the
/// leave-one-out KS distance of each seed's P(f) to the others' (the spread of `ks`).
fn reference_stats(
    rp: &Point,
    ref_recs: &[&Record],
    ref_ok: &BTreeMap<u64, &Record>,
    seeds: usize,
) -> ReferenceStats {
    let mut rs = ReferenceStats {
        settings: Some(rp.settings),
        status: point_status(ref_recs, seeds),
        wall_seconds: mean(&ref_recs.iter().map(|r| r.wall_seconds).collect::<Vec<_>>()),
        ..Default::default()
    };
    for m in ["phi", "z_star", "x0"] {
        let v: Vec<f64> = ref_ok.values().filter_map(|r| metric_of(r, m)).collect();
        if let Some(x) = mean(&v) {
            rs.mean.insert(m, x);
        }
        if let Some(s) = sample_sd(&v) {
            rs.spread.insert(m, s);
        }
    }
    if ref_ok.len() >= 2 {
        let loo: Vec<f64> = ref_ok
            .iter()
            .filter_map(|(s, r)| {
                let others: Vec<f64> = ref_ok
                    .iter()
                    .filter(|(s2, _)| *s2 != s)
                    .flat_map(|(_, r2)| r2.forces.iter().copied())
                    .collect();
                ks_distance(&r.forces, &others)
            })
            .collect();
        if let Some(x) = mean(&loo) {
            rs.spread.insert("ks", x);
        }
    }
    rs
}

/// Each row's combined error and whether it is on the Pareto front of cost against it.
fn combine(code_rows: &mut [Row], rs: &ReferenceStats) {
    // Combined error: each metric's error in units of the reference's seed spread (or,
    // without one, of the largest error of that metric in the sweep), averaged.
    let scale: BTreeMap<&str, f64> = METRICS
        .iter()
        .map(|&m| {
            let s = rs.spread.get(m).copied().filter(|s| *s > 0.0);
            let max = code_rows
                .iter()
                .filter_map(|r| r.errors.get(m))
                .fold(0.0f64, |a, &b| a.max(b));
            (m, s.unwrap_or(if max > 0.0 { max } else { 1.0 }))
        })
        .collect();
    for row in code_rows.iter_mut() {
        if row.errors.len() == METRICS.len() {
            let c: Vec<f64> = METRICS.iter().map(|m| row.errors[m] / scale[m]).collect();
            row.combined = mean(&c);
        }
    }
    // The Pareto front over distinct settings (the scene's own point is in every curve).
    let pts: Vec<Option<(f64, f64)>> = code_rows
        .iter()
        .map(|r| Some((r.wall_seconds?, r.combined?)))
        .collect();
    let front = pareto(&pts);
    for (row, f) in code_rows.iter_mut().zip(front) {
        row.pareto = f;
    }
}

/// `equilibrium`, `time-limit`, or `unstable: <message>` when any seed failed.
pub fn point_status(rr: &[&Record], seeds: usize) -> String {
    if let Some(bad) = rr.iter().find(|r| !r.packing()) {
        let k = rr.iter().filter(|r| !r.packing()).count();
        let of = if seeds > 1 {
            format!(" ({k}/{seeds} seeds)")
        } else {
            String::new()
        };
        return format!(
            "{}{of}: {}",
            bad.status(),
            short_message(bad.message.as_deref().unwrap_or("no message"))
        );
    }
    if rr.len() < seeds {
        return "missing".into();
    }
    if rr.iter().all(|r| r.equilibrated()) {
        StepEnd::Equilibrium.as_str().into()
    } else {
        let k = rr.iter().filter(|r| !r.equilibrated()).count();
        format!("time-limit ({k}/{seeds} seeds)")
    }
}
