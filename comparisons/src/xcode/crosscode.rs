//! The cross-code table: every metric of every code's final packing, against the paper value,
//! the golden (recorded) values and our engine, with the stated tolerances
//! (`golden/xcode-bands.toml`).

use super::code::Code;
use crate::metrics::impact::{Check, ImpactReport};
use crate::metrics::pair_history::{PairHistory, PEAK_TOLERANCE};
use crate::outcome::Outcome;
use crate::report::format::dec4;
use crate::report::paper;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Metrics shown in the terminal table (the files carry all of them).
pub const TABLE_METRICS: &[&str] = &[
    "phi", "z", "z_star", "x0", "pressure", "Z2", "X1", "M1", "M2", "Q6", "z_plus", "z_minus",
    "z_zero", "clusters",
];

/// Also shown for cohesive scenes: fractions of grains with 1–4 interactions (GRC07 T.V–T.VI).
pub const COHESIVE_TABLE_METRICS: &[&str] = &["xk1", "xk2", "xk3", "xk4"];

/// What became of one code's run.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CodeResult {
    pub code: Code,
    /// `ran`, `recorded`, `missing` (binary not found), `refused` (scene not expressible),
    /// `failed`, `timeout`, `interrupted`.
    pub outcome: Outcome,
    /// Status of the final state (`equilibrium`, `time-limit`, …) when it ran.
    pub status: Option<String>,
    /// Version line of the code.
    pub version: Option<String>,
    pub wall_seconds: Option<f64>,
    /// What went wrong, or the install command when missing.
    pub message: Option<String>,
    /// Approximate features of the deck.
    pub deviations: Vec<String>,
    pub metrics: BTreeMap<String, f64>,
    /// Mean of the recorded golden values (`golden/<scene>/<code>.json`), if any.
    pub golden: BTreeMap<String, f64>,
    /// Target of the last stage and the allowed deviation of the contact-stress pressure.
    pub pressure_target: Option<f64>,
    pub pressure_tolerance: Option<f64>,
}

impl CodeResult {
    /// A result with only its code and outcome filled in.
    pub fn new(code: Code, outcome: Outcome) -> CodeResult {
        CodeResult {
            code,
            outcome,
            status: None,
            version: None,
            wall_seconds: None,
            message: None,
            deviations: Vec::new(),
            metrics: BTreeMap::new(),
            golden: BTreeMap::new(),
            pressure_target: None,
            pressure_tolerance: None,
        }
    }
}

/// Cross-code tolerance of one metric: |code − rust| ≤ k·√2·spread.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Band {
    /// Sample s.d. of our engine's value over seeds of the scene.
    pub spread: f64,
    /// Seeds behind `spread`.
    pub seeds: u32,
}

/// `golden/xcode-bands.toml`: scene → metric → band, and the multiplier k.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Bands {
    /// Multiplier of √2·spread (two independent samples differ by √2 s.d.).
    pub k: f64,
    pub scenes: BTreeMap<String, BTreeMap<String, Band>>,
}

impl Bands {
    pub const FILE: &'static str = "golden/xcode-bands.toml";
    pub const TEXT: &'static str = include_str!("../../../golden/xcode-bands.toml");

    pub fn embedded() -> Bands {
        toml::from_str(Self::TEXT).expect("golden/xcode-bands.toml parses (tested)")
    }
    /// Allowed |code − rust| for `metric` in `scene`.
    pub fn tolerance(&self, scene: &str, metric: &str) -> Option<f64> {
        self.scenes
            .get(scene)
            .and_then(|m| m.get(metric))
            .map(|b| self.k * std::f64::consts::SQRT_2 * b.spread)
    }
}

/// One row of the table.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Row {
    pub metric: String,
    pub paper: Option<f64>,
    pub paper_sd: Option<f64>,
    pub reference: Option<String>,
    /// Allowed |code − rust| (cross-code band), if stated.
    pub tolerance: Option<f64>,
    pub values: BTreeMap<String, f64>,
    pub golden: BTreeMap<String, f64>,
    /// (value − paper)/paper s.d. per code.
    pub paper_sigma: BTreeMap<String, f64>,
    /// (value − rust)/(√2·spread) per code.
    pub rust_sigma: BTreeMap<String, f64>,
}

/// The whole comparison.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Comparison {
    pub scene: String,
    pub n: usize,
    pub paper_state: Option<String>,
    pub codes: Vec<CodeResult>,
    pub rows: Vec<Row>,
    /// Every check that failed, in words.
    pub failures: Vec<String>,
    /// Two-body impacts (scenes with `output.trace_every`), per code.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub impacts: Vec<CodeImpact>,
    /// The contacts of a traced scene of more than two grains, pair by pair, per code.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pairs: Vec<CodePairs>,
}

/// One code's contacts over a few-body trace.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CodePairs {
    pub code: Code,
    pub pairs: Vec<PairHistory>,
}

/// One code's two-body impact against the analytic values.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CodeImpact {
    pub code: Code,
    pub report: ImpactReport,
}

/// The golden files of the default comparison scene, embedded so that a bare `grainbench` run
/// outside the repository still shows them for the codes that are not installed.
fn embedded_golden(scene: &str, code: Code) -> Option<&'static str> {
    match (scene, code) {
        ("xcode-smoke", Code::Rust) => Some(include_str!("../../../golden/xcode-smoke/rust.json")),
        ("xcode-smoke", Code::Lammps) => {
            Some(include_str!("../../../golden/xcode-smoke/lammps.json"))
        }
        ("xcode-smoke", Code::Lammps2025) => {
            Some(include_str!("../../../golden/xcode-smoke/lammps-2025.json"))
        }
        ("xcode-smoke", Code::Liggghts) => {
            Some(include_str!("../../../golden/xcode-smoke/liggghts.json"))
        }
        ("xcode-smoke", Code::Yade) => Some(include_str!("../../../golden/xcode-smoke/yade.json")),
        _ => None,
    }
}

/// Where the golden record of `code` on scene `scene` is, relative to the repository root:
/// `golden/<scene>/<code>.json`. Every reader and writer of golden records finds it here.
pub fn golden_file(scene: &str, code: Code) -> PathBuf {
    Path::new("golden")
        .join(scene)
        .join(format!("{}.json", code.name()))
}

/// The recorded document [`golden_file`] under `root` (the embedded copy for the default
/// scene when the file is not there).
fn golden_doc(root: &Path, scene: &str, code: Code) -> Option<serde_json::Value> {
    let path = root.join(golden_file(scene, code));
    let text = std::fs::read_to_string(&path)
        .ok()
        .or_else(|| embedded_golden(scene, code).map(String::from))?;
    serde_json::from_str(&text).ok()
}

/// Mean of each metric over the seeds of a golden document.
fn mean_metrics(doc: &serde_json::Value) -> BTreeMap<String, f64> {
    let mut sums: BTreeMap<String, (f64, usize)> = BTreeMap::new();
    for seed in doc["seeds"].as_array().into_iter().flatten() {
        if let Some(m) = seed["metrics"].as_object() {
            for (k, v) in m {
                if let Some(x) = v.as_f64() {
                    let e = sums.entry(k.clone()).or_insert((0.0, 0));
                    e.0 += x;
                    e.1 += 1;
                }
            }
        }
    }
    sums.into_iter()
        .map(|(k, (s, n))| (k, s / n as f64))
        .collect()
}

/// The mean metrics of `golden/<scene>/<code>.json` (any number of seeds); empty if none.
pub fn golden_metrics(root: &Path, scene: &str, code: Code) -> BTreeMap<String, f64> {
    golden_doc(root, scene, code)
        .map(|d| mean_metrics(&d))
        .unwrap_or_default()
}

/// The recorded result of `code` (`golden/<scene>/<code>.json`) as a table column: mean metrics
/// over its seeds, status and wall time of its first seed, the code's version.
pub fn recorded(root: &Path, scene: &str, code: Code) -> Option<CodeResult> {
    let doc = golden_doc(root, scene, code)?;
    let first = &doc["seeds"][0];
    Some(CodeResult {
        status: first["status"].as_str().map(String::from),
        version: doc["code"].as_str().map(String::from),
        wall_seconds: first["wall_seconds"].as_f64(),
        message: doc["command"].as_str().map(String::from),
        deviations: doc["deviations"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|d| d.as_str().map(String::from))
            .collect(),
        metrics: mean_metrics(&doc),
        ..CodeResult::new(code, Outcome::Recorded)
    })
}

/// Builds the rows and the failed checks.
pub fn build(
    scene: &str,
    n: usize,
    paper_state: Option<&str>,
    codes: Vec<CodeResult>,
    bands: &Bands,
) -> Comparison {
    build_with(scene, n, paper_state, codes, bands, None, false)
}

/// [`build`] for a scene that traces a two-body impact (`impacts` given): the impact of each
/// code that ran is checked against the analytic values instead of its final state against
/// the equilibrium criteria (two grains apart keep their kinetic energy); a code that ran
/// without a measurable impact fails. With `full_time` (the scene runs its whole time, as a
/// traced few-body scene does) a final state short of the criteria is no failure.
pub fn build_with(
    scene: &str,
    n: usize,
    paper_state: Option<&str>,
    codes: Vec<CodeResult>,
    bands: &Bands,
    impacts: Option<Vec<CodeImpact>>,
    full_time: bool,
) -> Comparison {
    let published = paper_state.and_then(paper::paper_values);
    let mut keys: Vec<String> = codes
        .iter()
        .flat_map(|c| c.metrics.keys().chain(c.golden.keys()).cloned())
        .collect();
    keys.sort_by_key(|k| (paper::metric_order(k), k.clone()));
    keys.dedup();
    let rust = codes.iter().find(|c| c.code == Code::Rust);
    let mut failures = Vec::new();
    let mut rows = Vec::new();
    for key in keys {
        let p = published.and_then(|s| s.values.get(&key));
        let tolerance = bands.tolerance(scene, &key);
        let spread = bands
            .scenes
            .get(scene)
            .and_then(|m| m.get(&key))
            .map(|b| b.spread);
        let mut row = Row {
            metric: key.clone(),
            paper: p.map(|v| v.value),
            paper_sd: p.and_then(|v| v.sd),
            reference: p.map(|v| v.reference.clone()),
            tolerance,
            values: BTreeMap::new(),
            golden: BTreeMap::new(),
            paper_sigma: BTreeMap::new(),
            rust_sigma: BTreeMap::new(),
        };
        let ours = rust.and_then(|r| r.metrics.get(&key)).copied();
        for c in &codes {
            if let Some(g) = c.golden.get(&key) {
                row.golden.insert(c.code.name().to_string(), *g);
            }
            let Some(&v) = c.metrics.get(&key) else {
                continue;
            };
            row.values.insert(c.code.name().to_string(), v);
            if let (Some(pv), Some(sd)) = (row.paper, row.paper_sd) {
                if sd > 0.0 {
                    row.paper_sigma
                        .insert(c.code.name().to_string(), (v - pv) / sd);
                }
            }
            if let (Some(o), Some(s)) = (ours, spread) {
                if c.code != Code::Rust && s > 0.0 {
                    row.rust_sigma.insert(
                        c.code.name().to_string(),
                        (v - o) / (std::f64::consts::SQRT_2 * s),
                    );
                    if let Some(t) = tolerance {
                        if (v - o).abs() > t {
                            failures.push(format!(
                                "{}: {key} = {v:.6} differs from rust ({o:.6}) by {:.3e} > tolerance {t:.3e} ({} × √2 × seed spread {s:.3e})",
                                c.code,
                                (v - o).abs(),
                                bands.k
                            ));
                        }
                    }
                }
            }
        }
        rows.push(row);
    }
    for c in &codes {
        match c.outcome {
            Outcome::Ran | Outcome::Recorded if impacts.is_some() => {
                let found = impacts.iter().flatten().find(|i| i.code == c.code);
                match found {
                    None => failures.push(format!(
                        "{}: no impact measured in its trace (no contact, or still in contact at the end)",
                        c.code
                    )),
                    Some(i) => {
                        for k in i.report.checks().iter().filter(|k| !k.passed()) {
                            failures.push(format!(
                                "{}: {} = {:.6e} differs from the analytic {:.6e} by {:+.2} % (tolerance {:.2} %)",
                                c.code,
                                k.quantity,
                                k.measured,
                                k.expected,
                                100.0 * k.deviation(),
                                100.0 * k.tolerance
                            ));
                        }
                    }
                }
            }
            Outcome::Ran | Outcome::Recorded => {
                if !full_time && c.status.as_deref() != Some("equilibrium") {
                    failures.push(format!(
                        "{}: final state is `{}`, not `equilibrium`",
                        c.code,
                        c.status.as_deref().unwrap_or("?")
                    ));
                }
                if let (Some(t), Some(tol), Some(p)) = (
                    c.pressure_target,
                    c.pressure_tolerance,
                    c.metrics.get("pressure"),
                ) {
                    if (p - t).abs() > tol {
                        failures.push(format!(
                            "{}: contact-stress pressure {p:.6} misses the target {t} by {:.2e} > criterion {tol:.2e}",
                            c.code,
                            (p - t).abs()
                        ));
                    }
                }
            }
            Outcome::Missing | Outcome::Refused => {}
            other => failures.push(format!(
                "{}: {other}{}",
                c.code,
                c.message
                    .as_deref()
                    .map(|m| format!(": {m}"))
                    .unwrap_or_default()
            )),
        }
    }
    Comparison {
        scene: scene.into(),
        n,
        paper_state: paper_state.map(String::from),
        codes,
        rows,
        failures,
        impacts: impacts.unwrap_or_default(),
        pairs: Vec::new(),
    }
}

impl Comparison {
    /// Markdown: one column per code; each cell `value [golden] (Δ/σ_paper; Δ/σ_seeds vs rust)`.
    pub fn to_markdown(&self, all_metrics: bool) -> String {
        let mut s = format!("## {} (N = {})\n\n", self.scene, self.n);
        s.push_str(
            "| code | outcome | status | wall s | version |\n| --- | --- | --- | --- | --- |\n",
        );
        for c in &self.codes {
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} |\n",
                c.code,
                c.outcome,
                c.status.as_deref().unwrap_or("–"),
                c.wall_seconds
                    .map(|w| format!("{w:.1}"))
                    .unwrap_or("–".into()),
                c.version.as_deref().or(c.message.as_deref()).unwrap_or("–")
            ));
        }
        s.push_str("\nCells: value [golden] (Δ paper in paper s.d.; Δ rust in units of √2 × our seed-to-seed s.d.). `*` marks a value outside its tolerance.\n\n");
        s.push_str("| metric | paper |");
        for c in &self.codes {
            s.push_str(&format!(" {} |", c.code));
        }
        s.push_str(" tolerance vs rust |\n| --- | --- |");
        for _ in &self.codes {
            s.push_str(" --- |");
        }
        s.push_str(" --- |\n");
        let cohesive = self.rows.iter().any(|r| r.metric == "z_plus");
        for r in &self.rows {
            // Headline metrics, and every metric judged against a band.
            let shown = TABLE_METRICS.contains(&r.metric.as_str())
                || (cohesive && COHESIVE_TABLE_METRICS.contains(&r.metric.as_str()))
                || r.tolerance.is_some();
            if !all_metrics && !shown {
                continue;
            }
            let paper = match (r.paper, r.paper_sd) {
                (Some(v), Some(sd)) => format!(
                    "{} ± {} ({})",
                    dec4(v),
                    dec4(sd),
                    r.reference.as_deref().unwrap_or("")
                ),
                (Some(v), None) => {
                    format!("{} ({})", dec4(v), r.reference.as_deref().unwrap_or(""))
                }
                _ => "–".into(),
            };
            s.push_str(&format!("| {} | {} |", r.metric, paper));
            let ours = r.values.get(Code::Rust.name());
            for c in &self.codes {
                let mut cell = match r.values.get(c.code.name()) {
                    Some(v) => dec4(*v),
                    None => "–".into(),
                };
                if let Some(g) = r.golden.get(c.code.name()) {
                    cell.push_str(&format!(" [{}]", dec4(*g)));
                }
                let mut notes = Vec::new();
                if let Some(z) = r.paper_sigma.get(c.code.name()) {
                    notes.push(format!("{z:+.1}σp"));
                }
                if let Some(z) = r.rust_sigma.get(c.code.name()) {
                    notes.push(format!("{z:+.1}σs"));
                }
                if !notes.is_empty() {
                    cell.push_str(&format!(" ({})", notes.join("; ")));
                }
                if let (Some(t), Some(v), Some(o)) =
                    (r.tolerance, r.values.get(c.code.name()), ours)
                {
                    if (v - o).abs() > t {
                        cell.push_str(" *");
                    }
                }
                s.push_str(&format!(" {cell} |"));
            }
            s.push_str(&format!(
                " {} |\n",
                r.tolerance
                    .map(|t| format!("± {}", dec4(t)))
                    .unwrap_or("–".into())
            ));
        }
        if !self.impacts.is_empty() {
            s.push_str(&self.impact_markdown());
        }
        if !self.pairs.is_empty() {
            s.push_str(&self.pairs_markdown());
        }
        for c in &self.codes {
            if !c.deviations.is_empty() {
                s.push_str(&format!(
                    "\n{} deviations: {}\n",
                    c.code,
                    c.deviations.join("; ")
                ));
            }
        }
        if self.failures.is_empty() {
            s.push_str("\nAll checks passed.\n");
        } else {
            s.push_str("\nFailed checks:\n");
            for f in &self.failures {
                s.push_str(&format!("- {f}\n"));
            }
        }
        s
    }

    /// Adds each code's contacts of a few-body trace and checks them against ours: every pair
    /// we trace is traced, with its peak normal force within [`PEAK_TOLERANCE`].
    pub fn add_pairs(&mut self, pairs: Vec<CodePairs>) {
        if let Some(ours) = pairs.iter().find(|c| c.code == Code::Rust) {
            for c in pairs.iter().filter(|c| c.code != Code::Rust) {
                for p in &ours.pairs {
                    match c.pairs.iter().find(|q| (q.i, q.j) == (p.i, p.j)) {
                        None => self.failures.push(format!(
                            "{}: no contact {}–{} in its trace (ours closes it at t = {:.6e})",
                            c.code, p.i, p.j, p.first
                        )),
                        Some(q) => {
                            let dev = q.peak_normal_force / p.peak_normal_force - 1.0;
                            if dev.abs() > PEAK_TOLERANCE {
                                self.failures.push(format!(
                                    "{}: peak normal force of contact {}–{} {:.6e} differs from ours {:.6e} by {:+.2} % (tolerance {:.2} %)",
                                    c.code, p.i, p.j, q.peak_normal_force, p.peak_normal_force,
                                    100.0 * dev, 100.0 * PEAK_TOLERANCE
                                ));
                            }
                        }
                    }
                }
            }
        }
        self.pairs = pairs;
    }

    /// The few-body contact table: per pair, each code's peak normal force (Δ rust) and the
    /// times it was closed.
    fn pairs_markdown(&self) -> String {
        let mut s = format!(
            "\n### Few-body contacts\n\nPer pair (grains i–j): peak normal force (Δ rust; `*` beyond ± {:.0} %), and the first and last frame with the grains overlapping.\n\n| contact |",
            100.0 * PEAK_TOLERANCE
        );
        for c in &self.pairs {
            s.push_str(&format!(" {} |", c.code));
        }
        s.push_str("\n| --- |");
        s.push_str(&" --- |".repeat(self.pairs.len()));
        s.push('\n');
        let mut keys: Vec<(usize, usize)> = self
            .pairs
            .iter()
            .flat_map(|c| c.pairs.iter().map(|p| (p.i, p.j)))
            .collect();
        keys.sort_unstable();
        keys.dedup();
        let ours = self.pairs.iter().find(|c| c.code == Code::Rust);
        let find =
            |c: &CodePairs, k: (usize, usize)| c.pairs.iter().find(|p| (p.i, p.j) == k).cloned();
        for k in keys {
            let o = ours.and_then(|c| find(c, k));
            s.push_str(&format!("| {}–{} peak force |", k.0, k.1));
            for c in &self.pairs {
                let cell = match (find(c, k), &o) {
                    (Some(p), Some(o)) => {
                        let dev = p.peak_normal_force / o.peak_normal_force - 1.0;
                        format!(
                            "{:.6e} ({:+.3} %){}",
                            p.peak_normal_force,
                            100.0 * dev,
                            if dev.abs() > PEAK_TOLERANCE { " *" } else { "" }
                        )
                    }
                    (Some(p), None) => format!("{:.6e}", p.peak_normal_force),
                    (None, _) => "–".into(),
                };
                s.push_str(&format!(" {cell} |"));
            }
            s.push_str(&format!("\n| {}–{} closed |", k.0, k.1));
            for c in &self.pairs {
                let cell =
                    find(c, k).map_or("–".into(), |p| format!("{:.6} – {:.6}", p.first, p.last));
                s.push_str(&format!(" {cell} |"));
            }
            s.push('\n');
        }
        s
    }

    /// The impact table: each code's measured value, its deviation from the analytic one and
    /// from rust's (Hertz's elastic impact, the impulse balance of an impact that slides
    /// throughout).
    fn impact_markdown(&self) -> String {
        if self.impacts.is_empty() {
            return String::new();
        }
        let mut s = String::from(
            "\n### Two-body impact\n\nCells: measured (Δ analytic; Δ rust). `*` marks a deviation beyond the tolerance.\n\n| quantity | analytic | tolerance |",
        );
        for i in &self.impacts {
            s.push_str(&format!(" {} |", i.code));
        }
        s.push_str("\n| --- | --- | --- |");
        s.push_str(&" --- |".repeat(self.impacts.len()));
        s.push('\n');
        let checks: Vec<Vec<Check>> = self.impacts.iter().map(|i| i.report.checks()).collect();
        let rust = self.impacts.iter().position(|i| i.code == Code::Rust);
        for (q, check) in checks[0].iter().enumerate() {
            s.push_str(&format!(
                "| {} | {:.6e} | ± {:.2} % |",
                check.quantity,
                check.expected,
                100.0 * check.tolerance
            ));
            let ours = rust.and_then(|r| checks[r].get(q).map(|k| k.measured));
            for code_checks in &checks {
                let cell = match code_checks.get(q) {
                    Some(k) => {
                        let vs_rust = ours
                            .map(|o| format!("; {:+.3} %", 100.0 * (k.measured / o - 1.0)))
                            .unwrap_or_default();
                        format!(
                            "{:.6e} ({:+.3} %{vs_rust}){}",
                            k.measured,
                            100.0 * k.deviation(),
                            if k.passed() { "" } else { " *" }
                        )
                    }
                    None => "–".into(),
                };
                s.push_str(&format!(" {cell} |"));
            }
            s.push('\n');
        }
        let m = |f: fn(&ImpactReport) -> String| {
            self.impacts
                .iter()
                .map(|i| format!(" {} |", f(&i.report)))
                .collect::<String>()
        };
        s.push_str(&format!(
            "| incidence angle ° | – | – |{}\n| rebound angle ° | – | – |{}\n| e_t | – | – |{}\n",
            m(|r| format!("{:.3}", r.measured.incidence_angle)),
            m(|r| format!("{:.3}", r.measured.rebound_angle)),
            m(|r| r
                .measured
                .restitution_tangential
                .map_or("–".into(), |e| format!("{e:.5}"))),
        ));
        s
    }

    /// CSV: metric, code, value, golden, paper, paper_sd, reference, tolerance.
    pub fn to_csv(&self) -> String {
        let mut s =
            String::from("metric,code,value,golden,paper,paper_sd,reference,tolerance_vs_rust\n");
        let o = |x: Option<f64>| x.map(|v| v.to_string()).unwrap_or_default();
        for r in &self.rows {
            for c in &self.codes {
                let v = r.values.get(c.code.name()).copied();
                let g = r.golden.get(c.code.name()).copied();
                if v.is_none() && g.is_none() {
                    continue;
                }
                s.push_str(&format!(
                    "{},{},{},{},{},{},\"{}\",{}\n",
                    r.metric,
                    c.code,
                    o(v),
                    o(g),
                    o(r.paper),
                    o(r.paper_sd),
                    r.reference.as_deref().unwrap_or(""),
                    o(r.tolerance)
                ));
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(code: &str, phi: f64, p: f64) -> CodeResult {
        CodeResult {
            code: Code::parse(code).unwrap(),
            outcome: Outcome::Ran,
            status: Some("equilibrium".into()),
            version: None,
            wall_seconds: Some(1.0),
            message: None,
            deviations: vec![],
            metrics: [("phi".to_string(), phi), ("pressure".to_string(), p)].into(),
            golden: BTreeMap::new(),
            pressure_target: Some(1.0),
            pressure_tolerance: Some(1e-4),
        }
    }

    #[test]
    fn bands_file_parses() {
        let b = Bands::embedded();
        assert!(b.k > 0.0);
        assert!(b.tolerance("xcode-smoke", "phi").is_some());
    }

    #[test]
    fn out_of_band_and_pressure_misses_are_failures() {
        let mut bands = Bands {
            k: 3.0,
            scenes: BTreeMap::new(),
        };
        bands.scenes.insert(
            "s".into(),
            [(
                "phi".to_string(),
                Band {
                    spread: 0.001,
                    seeds: 4,
                },
            )]
            .into(),
        );
        let ok = build(
            "s",
            10,
            None,
            vec![result("rust", 0.60, 1.0), result("lammps", 0.603, 1.00005)],
            &bands,
        );
        assert!(ok.failures.is_empty(), "{:?}", ok.failures);
        // 3√2·0.001 = 0.00424: 0.605 is out.
        let bad = build(
            "s",
            10,
            None,
            vec![result("rust", 0.60, 1.0), result("lammps", 0.605, 1.001)],
            &bands,
        );
        assert_eq!(bad.failures.len(), 2, "{:?}", bad.failures);
        let mut missing = result("yade", 0.0, 0.0);
        missing.outcome = Outcome::Missing;
        missing.metrics.clear();
        let m = build(
            "s",
            10,
            None,
            vec![result("rust", 0.60, 1.0), missing],
            &bands,
        );
        assert!(m.failures.is_empty());
        let mut timeout = result("yade", 0.0, 0.0);
        timeout.outcome = Outcome::Timeout;
        timeout.metrics.clear();
        let t = build(
            "s",
            10,
            None,
            vec![result("rust", 0.60, 1.0), timeout],
            &bands,
        );
        assert_eq!(t.failures.len(), 1);
        assert!(t.to_markdown(false).contains("Failed checks"));
    }

    /// Cohesive scenes show the split of z, the cluster count and x_1..x_4; others do not.
    #[test]
    fn cohesive_rows_in_the_terminal_table() {
        let bands = Bands::embedded();
        let with = |keys: &[(&str, f64)]| {
            let mut r = result("rust", 0.7, 0.01);
            for (k, v) in keys {
                r.metrics.insert(k.to_string(), *v);
            }
            build("s", 10, None, vec![r], &bands).to_markdown(false)
        };
        let md = with(&[
            ("z_plus", 1.4),
            ("z_zero", 0.3),
            ("clusters", 1.0),
            ("xk2", 0.25),
            ("xk9", 0.0),
        ]);
        for row in ["| z_zero |", "| clusters |", "| xk2 |"] {
            assert!(md.contains(row), "{row} missing:\n{md}");
        }
        assert!(!md.contains("| xk9 |"));
        assert!(!with(&[("xk2", 0.25)]).contains("| xk2 |"));
    }
}
