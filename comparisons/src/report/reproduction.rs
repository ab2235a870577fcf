//! The reproduction table: our values over several seeds against the published ones.
//!
//! Input: a state key of `golden/paper-values.toml` (see [`super::paper`]) and, per seed, a list
//! of `(metric key, value)` pairs. For every metric the paper gives for that state, one [`Row`]:
//! our mean, sample s.d. and number of seeds; the paper's value, s.d. and reference; the
//! difference in units of the paper's s.d. (or relative, where the paper gives none); the
//! difference in units of our own seed spread; and a verdict.
//!
//! Verdict rule ([`Verdict`]):
//! * paper s.d. given: `MISS` when |ours − paper| > 2 s.d. ([`SD_LIMIT`]);
//! * no s.d., paper value ≠ 0: `MISS` when |ours − paper| / |paper| > 1 % ([`REL_LIMIT`]);
//! * no s.d., paper value = 0 (e.g. x2 = 0, M1 = 0 without friction): `MISS` when
//!   |ours| > [`ZERO_ABS_LIMIT`];
//! * no finite value from any seed: `n/a`.
//!
//! Rendered as Markdown ([`Reproduction::to_markdown`]), CSV ([`Reproduction::to_csv`]) and
//! JSON ([`Reproduction::to_json`]).

use super::format::{sig4, signed_sig4};
use super::paper::{self, StateValues};
use crate::stats;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

/// A difference beyond this many paper standard deviations is a `MISS`.
pub const SD_LIMIT: f64 = 2.0;
/// Without a paper s.d., a relative difference beyond this is a `MISS` (1 %).
pub const REL_LIMIT: f64 = 0.01;
/// Without a paper s.d. and with a published value of exactly 0, an absolute value beyond this
/// is a `MISS`.
pub const ZERO_ABS_LIMIT: f64 = 1e-3;

/// Why a reproduction table could not be built.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ReproductionError {
    /// The state is not in `golden/paper-values.toml`.
    #[error("unknown state {0:?} (see golden/paper-values.toml)")]
    UnknownState(String),
    /// One seed lists the same metric twice.
    #[error("seed {seed} gives metric {metric:?} twice")]
    DuplicateMetric {
        /// Index of the seed in the input.
        seed: usize,
        /// The repeated key.
        metric: String,
    },
}

/// Our value of one metric over the seeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedStats {
    /// Mean over the seeds that gave a finite value.
    pub mean: f64,
    /// Sample standard deviation (n − 1 in the denominator); `None` for one seed.
    pub sd: Option<f64>,
    /// Number of seeds that gave a finite value.
    pub n: usize,
    /// How the value combines the seeds.
    #[serde(default, skip_serializing_if = "Basis::is_seeds")]
    pub basis: Basis,
}

/// How a [`SeedStats`] combines the seeds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Basis {
    /// Mean and sample s.d. of the seeds' values.
    #[default]
    Seeds,
    /// One fit to the seeds' mean curve (GRC08 T.III: "measurements … averaged over all
    /// available samples"); `sd` is the fit's standard error.
    MeanCurveFit,
}

impl Basis {
    fn is_seeds(&self) -> bool {
        *self == Basis::Seeds
    }
}

impl SeedStats {
    /// Mean and sample s.d. of the finite values; `None` if there is none.
    pub fn from_values(values: &[f64]) -> Option<SeedStats> {
        let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        Some(SeedStats {
            mean: stats::mean(&v)?,
            sd: stats::sample_sd(&v),
            n: v.len(),
            basis: Basis::Seeds,
        })
    }

    /// A value fitted to the mean curve of `n` seeds, with the fit's standard error if known.
    pub fn mean_curve_fit(value: f64, se: Option<f64>, n: usize) -> SeedStats {
        SeedStats {
            mean: value,
            sd: se.filter(|s| s.is_finite()),
            n,
            basis: Basis::MeanCurveFit,
        }
    }
}

/// What the `diff` of a [`Row`] is measured in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DiffKind {
    /// (ours − paper) / paper s.d.
    PaperSd,
    /// (ours − paper) / |paper| (the paper gives no s.d.).
    Relative,
    /// ours − paper (the paper gives 0 without s.d.).
    Absolute,
}

/// The verdict on one metric.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Verdict {
    /// Within the limits.
    #[serde(rename = "ok")]
    Ok,
    /// Outside the limits.
    #[serde(rename = "MISS")]
    Miss,
    /// We have no value for this metric.
    #[serde(rename = "n/a")]
    NotMeasured,
}

impl Verdict {
    /// `"ok"`, `"MISS"` or `"n/a"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Ok => "ok",
            Verdict::Miss => "MISS",
            Verdict::NotMeasured => "n/a",
        }
    }
}

/// One metric of the reproduction table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Metric key (see [`super::paper::METRIC_KEYS`]).
    pub metric: String,
    /// Our value over the seeds; `None` if no seed gave it.
    pub ours: Option<SeedStats>,
    /// The published mean.
    pub paper_value: f64,
    /// The published sample-to-sample s.d., if any.
    pub paper_sd: Option<f64>,
    /// Where the published value comes from.
    pub reference: String,
    /// Difference to the paper, in the unit given by `diff_kind`.
    pub diff: Option<f64>,
    /// The unit of `diff`.
    pub diff_kind: DiffKind,
    /// (ours − paper) / our own seed s.d.; `None` with fewer than 2 seeds or zero spread.
    pub diff_own_sd: Option<f64>,
    /// `ok`, `MISS` or `n/a`.
    pub verdict: Verdict,
}

impl Row {
    /// Compares our seed statistics with one published value.
    pub fn compare(metric: &str, ours: Option<SeedStats>, paper: &super::paper::PaperValue) -> Row {
        let sd = paper.sd.filter(|s| *s > 0.0);
        let diff_kind = match sd {
            Some(_) => DiffKind::PaperSd,
            None if paper.value != 0.0 => DiffKind::Relative,
            None => DiffKind::Absolute,
        };
        let (diff, diff_own_sd, verdict) = match &ours {
            None => (None, None, Verdict::NotMeasured),
            Some(o) => {
                let delta = o.mean - paper.value;
                let (diff, limit) = match diff_kind {
                    DiffKind::PaperSd => (delta / sd.unwrap_or(1.0), SD_LIMIT),
                    DiffKind::Relative => (delta / paper.value.abs(), REL_LIMIT),
                    DiffKind::Absolute => (delta, ZERO_ABS_LIMIT),
                };
                let own = o.sd.filter(|s| *s > 0.0).map(|s| delta / s);
                let verdict = if diff.abs() > limit {
                    Verdict::Miss
                } else {
                    Verdict::Ok
                };
                (Some(diff), own, verdict)
            }
        };
        Row {
            metric: metric.to_string(),
            ours,
            paper_value: paper.value,
            paper_sd: paper.sd,
            reference: paper.reference.clone(),
            diff,
            diff_kind,
            diff_own_sd,
            verdict,
        }
    }
}

/// The reproduction table of one state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reproduction {
    /// State key, e.g. `"ar07-D"`.
    pub state: String,
    /// The state's one-line description from the data file.
    pub description: String,
    /// Number of seeds given (some may lack some metrics).
    pub seeds: usize,
    /// One row per published metric, in the order of [`super::paper::METRIC_KEYS`].
    pub rows: Vec<Row>,
    /// Metrics we measured that the paper does not give for this state.
    pub unmatched: Vec<String>,
}

impl Reproduction {
    /// Number of rows with a `MISS`.
    pub fn misses(&self) -> usize {
        self.rows
            .iter()
            .filter(|r| r.verdict == Verdict::Miss)
            .count()
    }

    /// Markdown table for the terminal and the README.
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "### {} — {} seed{}\n\n{}\n",
            self.state,
            self.seeds,
            if self.seeds == 1 { "" } else { "s" },
            self.description
        );
        s.push_str(
            "| metric | ours (mean ± s.d., n) | paper | ref | Δ | Δ / our s.d. | verdict |\n",
        );
        s.push_str("| --- | --- | --- | --- | --- | --- | --- |\n");
        for r in &self.rows {
            let ours = match &r.ours {
                None => "—".to_string(),
                Some(o) => {
                    let n = match o.basis {
                        Basis::Seeds => format!("n={}", o.n),
                        Basis::MeanCurveFit => format!("fit of the mean of n={}", o.n),
                    };
                    match o.sd {
                        Some(sd) => format!("{} ± {} ({n})", sig4(o.mean), sig4(sd)),
                        None => format!("{} ({n})", sig4(o.mean)),
                    }
                }
            };
            let paper = match r.paper_sd {
                Some(sd) => format!("{} ± {}", sig4(r.paper_value), sig4(sd)),
                None => sig4(r.paper_value),
            };
            let diff = match r.diff {
                None => "—".to_string(),
                Some(d) => match r.diff_kind {
                    DiffKind::PaperSd => format!("{d:+.2} σ"),
                    DiffKind::Relative => format!("{:+.2} %", 100.0 * d),
                    DiffKind::Absolute => format!("{} abs", signed_sig4(d)),
                },
            };
            let own = r
                .diff_own_sd
                .map_or("—".to_string(), |d| format!("{d:+.2}"));
            let verdict = match r.verdict {
                Verdict::Miss => "**MISS**",
                v => v.as_str(),
            };
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} |",
                r.metric, ours, paper, r.reference, diff, own, verdict
            );
        }
        let measured = self.rows.iter().filter(|r| r.ours.is_some()).count();
        let _ = writeln!(
            s,
            "\n{} of {} published metrics measured, {} MISS (|Δ| > {} paper s.d., or > {} % without one).",
            measured,
            self.rows.len(),
            self.misses(),
            SD_LIMIT,
            100.0 * REL_LIMIT
        );
        if self.rows.iter().any(|r| {
            r.ours
                .as_ref()
                .is_some_and(|o| o.basis == Basis::MeanCurveFit)
        }) {
            let _ = writeln!(
                s,
                "\"fit of the mean\": one fit to the seeds' mean curve, ± its standard error (which the Δ / our s.d. column then uses)."
            );
        }
        if !self.unmatched.is_empty() {
            let _ = writeln!(
                s,
                "Measured but not published for this state: {}.",
                self.unmatched.join(", ")
            );
        }
        s
    }

    /// CSV with a header line; numbers in full precision, empty fields for missing values.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "state,metric,ours_mean,ours_sd,ours_n,ours_basis,paper_value,paper_sd,ref,diff,diff_kind,diff_own_sd,verdict\n",
        );
        let num = |x: Option<f64>| x.map_or(String::new(), |v| v.to_string());
        for r in &self.rows {
            let fields = [
                csv_field(&self.state),
                csv_field(&r.metric),
                num(r.ours.as_ref().map(|o| o.mean)),
                num(r.ours.as_ref().and_then(|o| o.sd)),
                r.ours.as_ref().map_or(String::new(), |o| o.n.to_string()),
                r.ours.as_ref().map_or(String::new(), |o| {
                    match o.basis {
                        Basis::Seeds => "seeds",
                        Basis::MeanCurveFit => "mean_curve_fit",
                    }
                    .to_string()
                }),
                r.paper_value.to_string(),
                num(r.paper_sd),
                csv_field(&r.reference),
                num(r.diff),
                match r.diff_kind {
                    DiffKind::PaperSd => "paper_sd",
                    DiffKind::Relative => "relative",
                    DiffKind::Absolute => "absolute",
                }
                .to_string(),
                num(r.diff_own_sd),
                r.verdict.as_str().to_string(),
            ];
            s.push_str(&fields.join(","));
            s.push('\n');
        }
        s
    }

    /// Pretty-printed JSON of the whole table.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a reproduction table always serializes")
    }
}

/// Builds the reproduction table of `state` from per-seed `(metric, value)` lists.
///
/// Non-finite values are skipped (a seed that gives NaN for a metric does not count for it).
pub fn build(state: &str, seeds: &[Vec<(String, f64)>]) -> Result<Reproduction, ReproductionError> {
    build_pooled(state, seeds, &[])
}

/// As [`build`], with `pooled` values standing for the seeds' in their metrics' rows (the fit
/// of the seeds' mean curve, [`SeedStats::mean_curve_fit`]).
pub fn build_pooled(
    state: &str,
    seeds: &[Vec<(String, f64)>],
    pooled: &[(String, SeedStats)],
) -> Result<Reproduction, ReproductionError> {
    let published =
        paper::paper_values(state).ok_or_else(|| ReproductionError::UnknownState(state.into()))?;
    let mut table = build_against(state, published, seeds)?;
    for (metric, ours) in pooled {
        if let Some(row) = table.rows.iter_mut().find(|r| &r.metric == metric) {
            *row = Row::compare(metric, Some(ours.clone()), &published.values[metric]);
        }
    }
    Ok(table)
}

/// As [`build`], against an explicit set of published values (e.g. parsed from another file).
pub fn build_against(
    state: &str,
    published: &StateValues,
    seeds: &[Vec<(String, f64)>],
) -> Result<Reproduction, ReproductionError> {
    let mut per_metric: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    for (i, seed) in seeds.iter().enumerate() {
        let mut seen = BTreeSet::new();
        for (k, v) in seed {
            if !seen.insert(k.as_str()) {
                return Err(ReproductionError::DuplicateMetric {
                    seed: i,
                    metric: k.clone(),
                });
            }
            per_metric.entry(k.as_str()).or_default().push(*v);
        }
    }
    let mut keys: Vec<&String> = published.values.keys().collect();
    keys.sort_by_key(|k| (paper::metric_order(k), k.as_str()));
    let rows = keys
        .into_iter()
        .map(|k| {
            let ours = per_metric
                .get(k.as_str())
                .and_then(|v| SeedStats::from_values(v));
            Row::compare(k, ours, &published.values[k])
        })
        .collect();
    let unmatched = per_metric
        .keys()
        .filter(|k| !published.values.contains_key(**k))
        .map(|k| k.to_string())
        .collect();
    Ok(Reproduction {
        state: state.to_string(),
        description: published.description.clone(),
        seeds: seeds.len(),
        rows,
        unmatched,
    })
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::paper::parse;

    fn seeds(rows: &[&[(&str, f64)]]) -> Vec<Vec<(String, f64)>> {
        rows.iter()
            .map(|r| r.iter().map(|(k, v)| (k.to_string(), *v)).collect())
            .collect()
    }

    fn fixture() -> StateValues {
        let text = r#"
[t]
paper = "AR07"
description = "hand-made state"
[t.values]
phi = { value = 0.60, sd = 0.001, ref = "AR07 T.IV" }
z_star = { value = 4.5, sd = 0.01, ref = "AR07 T.IV" }
Z2 = { value = 1.50, ref = "AR07 T.IV" }
M1 = { value = 0.0, ref = "AR07 T.IV" }
x0 = { value = 0.10, sd = 0.004, ref = "AR07 T.IV, note" }
"#;
        parse(text).unwrap().remove("t").unwrap()
    }

    fn row<'a>(r: &'a Reproduction, m: &str) -> &'a Row {
        r.rows.iter().find(|x| x.metric == m).unwrap()
    }

    #[test]
    fn seed_stats_mean_and_sample_sd() {
        let s = SeedStats::from_values(&[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert_eq!(s.n, 4);
        assert!((s.mean - 2.5).abs() < 1e-15);
        // Sample s.d.: sqrt(5/3).
        assert!((s.sd.unwrap() - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
        let one = SeedStats::from_values(&[0.7, f64::NAN]).unwrap();
        assert_eq!((one.mean, one.sd, one.n), (0.7, None, 1));
        assert!(SeedStats::from_values(&[f64::NAN]).is_none());
        assert!(SeedStats::from_values(&[]).is_none());
    }

    #[test]
    fn arithmetic_and_verdicts() {
        let input = seeds(&[
            &[
                ("phi", 0.600),
                ("z_star", 4.54),
                ("Z2", 1.51),
                ("M1", 0.0005),
                ("x0", 0.10),
            ],
            &[
                ("phi", 0.602),
                ("z_star", 4.52),
                ("Z2", 1.53),
                ("M1", 0.0025),
                ("x0", 0.11),
            ],
            &[
                ("phi", 0.601),
                ("z_star", 4.53),
                ("Z2", 1.52),
                ("M1", 0.0015),
            ],
        ]);
        let r = build_against("t", &fixture(), &input).unwrap();
        assert_eq!(r.seeds, 3);
        // phi: mean 0.601, sample sd 0.001 → +1 paper sd: ok; +1 own sd.
        let phi = row(&r, "phi");
        let o = phi.ours.as_ref().unwrap();
        assert!((o.mean - 0.601).abs() < 1e-12 && o.n == 3);
        assert!((o.sd.unwrap() - 0.001).abs() < 1e-12);
        assert_eq!(phi.diff_kind, DiffKind::PaperSd);
        assert!((phi.diff.unwrap() - 1.0).abs() < 1e-9);
        assert!((phi.diff_own_sd.unwrap() - 1.0).abs() < 1e-9);
        // z_star: mean 4.53 → +3 paper sd: MISS; own sd 0.01 → +3.
        let zs = row(&r, "z_star");
        assert!((zs.diff.unwrap() - 3.0).abs() < 1e-9);
        assert_eq!(zs.verdict, Verdict::Miss);
        assert!((zs.diff_own_sd.unwrap() - 3.0).abs() < 1e-9);
        // Z2: no paper sd → relative: 1.52/1.50 - 1 = +1.33 % > 1 %: MISS.
        let z2 = row(&r, "Z2");
        assert_eq!(z2.diff_kind, DiffKind::Relative);
        assert!((z2.diff.unwrap() - 0.02 / 1.5).abs() < 1e-12);
        assert_eq!(z2.verdict, Verdict::Miss);
        // M1: paper 0 without sd → absolute: 0.0015 > 1e-3: MISS.
        let m1 = row(&r, "M1");
        assert_eq!(m1.diff_kind, DiffKind::Absolute);
        assert!((m1.diff.unwrap() - 0.0015).abs() < 1e-12);
        assert_eq!(m1.verdict, Verdict::Miss);
        // x0: only two seeds give it: mean 0.105 → +1.25 sd: ok.
        let x0 = row(&r, "x0");
        assert_eq!(x0.ours.as_ref().unwrap().n, 2);
        assert!((x0.diff.unwrap() - 1.25).abs() < 1e-9);
        assert_eq!(x0.verdict, Verdict::Ok);
        assert_eq!(phi.verdict, Verdict::Ok);
        assert_eq!(r.misses(), 3);
        // Rows follow METRIC_KEYS order.
        let order: Vec<&str> = r.rows.iter().map(|x| x.metric.as_str()).collect();
        assert_eq!(order, ["phi", "z_star", "x0", "Z2", "M1"]);
    }

    #[test]
    fn relative_rule_passes_within_one_percent_and_negative_diffs_count() {
        let input = seeds(&[&[("Z2", 1.4895), ("z_star", 4.47)]]);
        let r = build_against("t", &fixture(), &input).unwrap();
        let z2 = row(&r, "Z2");
        assert!((z2.diff.unwrap() + 0.007).abs() < 1e-12);
        assert_eq!(z2.verdict, Verdict::Ok);
        assert_eq!(z2.diff_own_sd, None, "one seed: no own spread");
        assert_eq!(
            row(&r, "z_star").verdict,
            Verdict::Miss,
            "-3 sd is a miss too"
        );
    }

    #[test]
    fn missing_and_unmatched_metrics() {
        let input = seeds(&[&[("phi", 0.6), ("Q6", 0.02)], &[("phi", 0.6), ("Q6", 0.03)]]);
        let r = build_against("t", &fixture(), &input).unwrap();
        let zs = row(&r, "z_star");
        assert_eq!(zs.verdict, Verdict::NotMeasured);
        assert!(zs.ours.is_none() && zs.diff.is_none());
        // Zero seed spread gives no own-sd difference.
        assert_eq!(row(&r, "phi").diff_own_sd, None);
        assert_eq!(r.unmatched, ["Q6"]);
        assert_eq!(r.misses(), 0);
    }

    #[test]
    fn errors() {
        assert_eq!(
            build("no-such-state", &[]).unwrap_err(),
            ReproductionError::UnknownState("no-such-state".into())
        );
        let dup = seeds(&[&[("phi", 0.6)], &[("phi", 0.6), ("phi", 0.61)]]);
        assert_eq!(
            build_against("t", &fixture(), &dup).unwrap_err(),
            ReproductionError::DuplicateMetric {
                seed: 1,
                metric: "phi".into()
            }
        );
    }

    #[test]
    fn against_the_embedded_file() {
        // Two seeds of AR07 D at the published means: every measured metric is ok.
        let input = seeds(&[
            &[("phi", 0.5920), ("z_star", 4.55), ("x0", 0.110)],
            &[("phi", 0.5926), ("z_star", 4.542), ("x0", 0.112)],
        ]);
        let r = build("ar07-D", &input).unwrap();
        assert_eq!(r.state, "ar07-D");
        assert_eq!(r.rows[0].metric, "phi");
        assert_eq!(r.rows[0].reference, "AR07 T.IV");
        assert_eq!(r.misses(), 0);
        assert!(r.rows.iter().any(|x| x.verdict == Verdict::NotMeasured));
    }

    #[test]
    fn renderings() {
        let input = seeds(&[
            &[("phi", 0.6005), ("z_star", 4.54), ("x0", 0.1)],
            &[("phi", 0.6015), ("z_star", 4.52), ("x0", 0.1)],
        ]);
        let r = build_against("t", &fixture(), &input).unwrap();
        let md = r.to_markdown();
        assert!(md.contains("| metric | ours"));
        assert!(md.contains("| phi | 0.601 ± 0.0007071 (n=2) | 0.6 ± 0.001 | AR07 T.IV | +1.00 σ | +1.41 | ok |"), "{md}");
        assert!(md.contains("| z_star | 4.53 ± 0.01414 (n=2) | 4.5 ± 0.01 | AR07 T.IV | +3.00 σ | +2.12 | **MISS** |"), "{md}");
        assert!(
            md.contains("| Z2 | — | 1.5 | AR07 T.IV | — | — | n/a |"),
            "{md}"
        );
        assert!(md.contains("1 MISS"));

        let csv = r.to_csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 1 + r.rows.len());
        assert!(lines[0].starts_with("state,metric,ours_mean"));
        assert!(lines.iter().all(|l| l.split(',').count() >= 13));
        let x0 = lines.iter().find(|l| l.starts_with("t,x0,")).unwrap();
        assert!(x0.contains(",\"AR07 T.IV, note\","), "quoted ref: {x0}");
        assert!(
            x0.ends_with(",paper_sd,,ok"),
            "zero spread leaves diff_own_sd empty: {x0}"
        );
        assert!(csv.contains("t,Z2,,,,,1.5,,AR07 T.IV,,relative,,n/a"));

        let json: serde_json::Value = serde_json::from_str(&r.to_json()).unwrap();
        assert_eq!(json["state"], "t");
        assert_eq!(json["rows"][1]["verdict"], "MISS");
        assert_eq!(json["rows"][1]["diff_kind"], "paper_sd");
        assert_eq!(json["rows"][3]["verdict"], "n/a");
        // Reads back (floats to within serde_json's parsing precision).
        let back: Reproduction = serde_json::from_str(&r.to_json()).unwrap();
        assert_eq!(back.rows.len(), r.rows.len());
        for (b, o) in back.rows.iter().zip(&r.rows) {
            assert_eq!(
                (&b.metric, b.verdict, b.diff_kind),
                (&o.metric, o.verdict, o.diff_kind)
            );
            let close = |x: Option<f64>, y: Option<f64>| match (x, y) {
                (Some(x), Some(y)) => (x - y).abs() <= 1e-12 * y.abs().max(1.0),
                (x, y) => x == y,
            };
            assert!(close(b.diff, o.diff) && close(b.diff_own_sd, o.diff_own_sd));
        }
    }

    #[test]
    fn pooled_values_replace_the_seed_statistics_of_their_rows() {
        // GRC08 T.III's λ = 0.194 ± 0.004: the seeds scatter (0.26 ± 0.12, a miss) while one
        // fit to their mean curve lands within the band.
        let input = seeds(&[
            &[("lambda", 0.188), ("phi_at_pmax", 0.779)],
            &[("lambda", 0.185), ("phi_at_pmax", 0.776)],
            &[("lambda", 0.40), ("phi_at_pmax", 0.776)],
        ]);
        let state = "grc08-consolidation-rr";
        let plain = build(state, &input).unwrap();
        let row = |r: &Reproduction, m: &str| r.rows.iter().find(|x| x.metric == m).cloned();
        assert_eq!(row(&plain, "lambda").unwrap().verdict, Verdict::Miss);
        let pooled = [(
            "lambda".to_string(),
            SeedStats::mean_curve_fit(0.196, Some(0.003), 3),
        )];
        let r = build_pooled(state, &input, &pooled).unwrap();
        let lambda = row(&r, "lambda").unwrap();
        assert_eq!(lambda.verdict, Verdict::Ok);
        assert_eq!(lambda.ours.as_ref().unwrap().basis, Basis::MeanCurveFit);
        assert!((lambda.diff_own_sd.unwrap() - 0.002 / 0.003).abs() < 1e-9);
        // Other rows keep the seeds' statistics.
        assert_eq!(row(&r, "phi_at_pmax"), row(&plain, "phi_at_pmax"));
        let md = r.to_markdown();
        assert!(
            md.contains("| lambda | 0.196 ± 0.003 (fit of the mean of n=3) |"),
            "{md}"
        );
        assert!(md.contains("one fit to the seeds' mean curve"), "{md}");
        assert!(r.to_csv().contains(",lambda,0.196,0.003,3,mean_curve_fit,"));
        let back: Reproduction = serde_json::from_str(&r.to_json()).unwrap();
        assert_eq!(
            row(&back, "lambda").unwrap().ours.unwrap().basis,
            Basis::MeanCurveFit
        );
        // A seeds' row serializes without the field (records written before it read alike).
        assert!(!plain.to_json().contains("basis"));
    }
}
