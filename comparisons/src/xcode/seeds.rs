//! A cross-code comparison over several seeds (`compare --seeds`): every code's metrics as
//! mean ± s.d. over the seeds it finished, beside the paper's value, and the checks each
//! seed's comparison failed. Each seed is one [`Comparison`]: the codes start from the same
//! packing within a seed, so the per-seed checks against our engine stay the pass/fail rule.

use super::crosscode::{Comparison, COHESIVE_TABLE_METRICS, TABLE_METRICS};
use crate::outcome::Outcome;
use crate::report::format::sig4;
use crate::report::reproduction::SeedStats;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// One metric over the seeds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SeedRow {
    pub metric: String,
    pub paper: Option<f64>,
    pub paper_sd: Option<f64>,
    /// Each code's mean ± s.d. over the seeds that gave the metric.
    pub codes: BTreeMap<String, SeedStats>,
}

/// The comparison of several seeds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OverSeeds {
    pub scene: String,
    pub n: usize,
    pub seeds: Vec<u64>,
    /// Codes in the order of the first seed's comparison.
    pub codes: Vec<String>,
    /// Metrics in the comparisons' order, then `wall_seconds` (runs that ran to their end).
    pub rows: Vec<SeedRow>,
    /// Each seed's failed checks, prefixed by the seed.
    pub failures: Vec<String>,
}

/// Combines the comparisons of one scene run with several seeds.
pub fn over_seeds(runs: &[(u64, Comparison)]) -> OverSeeds {
    let mut codes: Vec<String> = Vec::new();
    let mut order: Vec<String> = Vec::new();
    let mut paper: BTreeMap<String, (Option<f64>, Option<f64>)> = BTreeMap::new();
    let mut values: BTreeMap<(String, String), Vec<f64>> = BTreeMap::new();
    let mut failures = Vec::new();
    for (seed, cmp) in runs {
        for c in &cmp.codes {
            let name = c.code.name().to_string();
            if !codes.contains(&name) {
                codes.push(name.clone());
            }
            if let (Outcome::Ran, Some(w)) = (c.outcome, c.wall_seconds) {
                values
                    .entry(("wall_seconds".into(), name))
                    .or_default()
                    .push(w);
            }
        }
        for r in &cmp.rows {
            if !order.contains(&r.metric) {
                order.push(r.metric.clone());
                paper.insert(r.metric.clone(), (r.paper, r.paper_sd));
            }
            for (code, v) in &r.values {
                values
                    .entry((r.metric.clone(), code.clone()))
                    .or_default()
                    .push(*v);
            }
        }
        failures.extend(cmp.failures.iter().map(|f| format!("seed {seed}: {f}")));
    }
    order.push("wall_seconds".into());
    let rows = order
        .into_iter()
        .map(|metric| {
            let (p, sd) = paper.get(&metric).copied().unwrap_or_default();
            let per_code = codes
                .iter()
                .filter_map(|c| {
                    let v = values.get(&(metric.clone(), c.clone()))?;
                    Some((c.clone(), SeedStats::from_values(v)?))
                })
                .collect();
            SeedRow {
                metric,
                paper: p,
                paper_sd: sd,
                codes: per_code,
            }
        })
        .collect();
    let first = runs.first().map(|(_, c)| c);
    OverSeeds {
        scene: first.map(|c| c.scene.clone()).unwrap_or_default(),
        n: first.map_or(0, |c| c.n),
        seeds: runs.iter().map(|(s, _)| *s).collect(),
        codes,
        rows,
        failures,
    }
}

impl OverSeeds {
    /// Markdown: one column per code, mean ± s.d. (n when a code missed seeds); the headline
    /// metrics unless `all_metrics`.
    pub fn to_markdown(&self, all_metrics: bool) -> String {
        let seeds: Vec<String> = self.seeds.iter().map(|s| s.to_string()).collect();
        let mut s = format!(
            "## {} over seeds {} (N = {})\n\nCells: mean ± sample s.d. over the seeds (n when fewer than {}); every seed's own table is in seed-K/compare.md.\n\n| metric | paper |",
            self.scene,
            seeds.join(", "),
            self.n,
            self.seeds.len()
        );
        for c in &self.codes {
            let _ = write!(s, " {c} |");
        }
        s.push_str("\n| --- | --- |");
        for _ in &self.codes {
            s.push_str(" --- |");
        }
        s.push('\n');
        let cohesive = self.rows.iter().any(|r| r.metric == "z_plus");
        for r in &self.rows {
            let shown = TABLE_METRICS.contains(&r.metric.as_str())
                || (cohesive && COHESIVE_TABLE_METRICS.contains(&r.metric.as_str()))
                || r.metric == "wall_seconds";
            if !all_metrics && !shown {
                continue;
            }
            let paper = match (r.paper, r.paper_sd) {
                (Some(v), Some(sd)) => format!("{} ± {}", sig4(v), sig4(sd)),
                (Some(v), None) => sig4(v),
                _ => "–".into(),
            };
            let _ = write!(s, "| {} | {paper} |", r.metric);
            for c in &self.codes {
                let cell = match r.codes.get(c) {
                    None => "–".to_string(),
                    Some(st) => {
                        let n = if st.n < self.seeds.len() {
                            format!(" (n={})", st.n)
                        } else {
                            String::new()
                        };
                        match st.sd {
                            Some(sd) => format!("{} ± {}{n}", sig4(st.mean), sig4(sd)),
                            None => format!("{}{n}", sig4(st.mean)),
                        }
                    }
                };
                let _ = write!(s, " {cell} |");
            }
            s.push('\n');
        }
        if self.failures.is_empty() {
            s.push_str("\nEvery seed passed its checks.\n");
        } else {
            let _ = writeln!(s, "\n{} failed check(s):\n", self.failures.len());
            for f in &self.failures {
                let _ = writeln!(s, "- {f}");
            }
        }
        s
    }

    /// CSV, one line per metric and code: scene,metric,code,mean,sd,n,paper,paper_sd.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("scene,metric,code,mean,sd,n,paper,paper_sd\n");
        let num = |x: Option<f64>| x.map_or(String::new(), |v| v.to_string());
        for r in &self.rows {
            for c in &self.codes {
                if let Some(st) = r.codes.get(c) {
                    let _ = writeln!(
                        s,
                        "{},{},{c},{},{},{},{},{}",
                        self.scene,
                        r.metric,
                        st.mean,
                        num(st.sd),
                        st.n,
                        num(r.paper),
                        num(r.paper_sd)
                    );
                }
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::xcode::crosscode::{build, Bands, CodeResult};
    use crate::xcode::Code;

    fn result(code: Code, phi: f64, z: Option<f64>, wall: f64) -> CodeResult {
        let mut r = CodeResult::new(code, Outcome::Ran);
        r.metrics.insert("phi".into(), phi);
        if let Some(z) = z {
            r.metrics.insert("z".into(), z);
        }
        r.wall_seconds = Some(wall);
        r.status = Some("equilibrium".into());
        r
    }

    fn seed(phi: [f64; 2], z_lammps: Option<f64>) -> Comparison {
        build(
            "ar07-D",
            100,
            Some("ar07-D"),
            vec![
                result(Code::Rust, phi[0], Some(4.5), 10.0),
                result(Code::Lammps, phi[1], z_lammps, 20.0),
            ],
            &Bands::embedded(),
        )
    }

    #[test]
    fn means_and_spreads_per_code_with_the_paper_value() {
        let runs = vec![
            (1, seed([0.590, 0.591], Some(4.4))),
            (2, seed([0.594, 0.593], None)),
            (3, seed([0.592, 0.595], Some(4.6))),
        ];
        let o = over_seeds(&runs);
        assert_eq!(o.seeds, vec![1, 2, 3]);
        assert_eq!(o.codes, vec!["rust".to_string(), "lammps".to_string()]);
        let row = |m: &str| o.rows.iter().find(|r| r.metric == m).unwrap();
        let phi = row("phi");
        assert!((phi.codes["rust"].mean - 0.592).abs() < 1e-12);
        assert!((phi.codes["rust"].sd.unwrap() - 0.002).abs() < 1e-12);
        assert!((phi.codes["lammps"].mean - 0.593).abs() < 1e-12);
        assert_eq!(phi.paper, Some(0.5923));
        // LAMMPS gave z in two seeds of three.
        assert_eq!(row("z").codes["lammps"].n, 2);
        assert!((row("z").codes["lammps"].mean - 4.5).abs() < 1e-12);
        assert_eq!(row("wall_seconds").codes["lammps"].mean, 20.0);
        let md = o.to_markdown(false);
        assert!(md.contains("over seeds 1, 2, 3"), "{md}");
        assert!(
            md.contains("| phi | 0.5923 ± 0.0006 | 0.592 ± 0.002 | 0.593 ± 0.002 |"),
            "{md}"
        );
        assert!(md.contains("| 4.5 ± 0.1414 (n=2) |"), "{md}");
        let csv = o.to_csv();
        assert!(csv.starts_with("scene,metric,code,mean,sd,n,paper,paper_sd\n"));
        assert!(csv.contains("ar07-D,phi,lammps,0.593"), "{csv}");
    }

    #[test]
    fn failures_carry_their_seed() {
        let mut a = seed([0.59, 0.59], None);
        a.failures.push("lammps: phi differs".into());
        let o = over_seeds(&[(7, a), (8, seed([0.59, 0.59], None))]);
        assert_eq!(o.failures, vec!["seed 7: lammps: phi differs".to_string()]);
        assert!(o
            .to_markdown(false)
            .contains("- seed 7: lammps: phi differs"));
        let clean = over_seeds(&[(1, seed([0.59, 0.59], None))]);
        assert!(clean
            .to_markdown(false)
            .contains("Every seed passed its checks."));
    }
}
