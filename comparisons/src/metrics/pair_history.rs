//! The contacts of a few-body trace, pair by pair: when each was closed and the
//! largest normal force it carried — what `compare` checks across codes for a traced scene of
//! more than two grains (two grains: [`super::impact`]).

use serde::{Deserialize, Serialize};

/// One pair's contact over a trace.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PairHistory {
    pub i: usize,
    pub j: usize,
    /// Times of the first and the last frame with the grains overlapping (gap < 0).
    pub first: f64,
    pub last: f64,
    pub peak_normal_force: f64,
}

/// Largest relative difference of a pair's peak normal force from ours, as the two-body impact
/// allows for its peak force (`impact.rs`).
pub const PEAK_TOLERANCE: f64 = 0.01;

/// The pairs that overlapped in some frame of a `trace-contacts.csv` (`t,i,j,gap,fn,…`: the
/// trace every code's is written as), by (i, j) with i < j.
pub fn from_csv(text: &str) -> Result<Vec<PairHistory>, String> {
    let mut rd = csv::Reader::from_reader(text.as_bytes());
    let head = rd.headers().map_err(|e| e.to_string())?.clone();
    let col = |n: &str| {
        head.iter()
            .position(|h| h == n)
            .ok_or_else(|| format!("no column `{n}` in the header {head:?}"))
    };
    let (ct, ci, cj, cg, cn) = (col("t")?, col("i")?, col("j")?, col("gap")?, col("fn")?);
    let mut out: Vec<PairHistory> = Vec::new();
    for (k, rec) in rd.records().enumerate() {
        let rec = rec.map_err(|e| e.to_string())?;
        let num = |c: usize| -> Result<f64, String> {
            rec[c]
                .trim()
                .parse()
                .map_err(|_| format!("line {}: `{}` is not a number", k + 2, &rec[c]))
        };
        if num(cg)? >= 0.0 {
            continue;
        }
        let (a, b) = (num(ci)? as usize, num(cj)? as usize);
        let (i, j) = (a.min(b), a.max(b));
        let (t, f) = (num(ct)?, num(cn)?);
        match out.iter_mut().find(|p| (p.i, p.j) == (i, j)) {
            Some(p) => {
                p.first = p.first.min(t);
                p.last = p.last.max(t);
                p.peak_normal_force = p.peak_normal_force.max(f);
            }
            None => out.push(PairHistory {
                i,
                j,
                first: t,
                last: t,
                peak_normal_force: f,
            }),
        }
    }
    out.sort_by_key(|p| (p.i, p.j));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_keep_their_overlap_times_and_peak_force() {
        let text = "t,i,j,gap,fn,ft_x\n0,1,2,0,0,0\n1,1,0,-0.01,0.5,0\n2,0,1,-0.02,0.9,0\n\
                    2,2,1,-0.001,0.1,0\n3,0,1,-0.005,0.3,0\n4,0,1,0.001,0,0\n";
        let p = from_csv(text).unwrap();
        assert_eq!(p.len(), 2, "{p:?}");
        assert_eq!((p[0].i, p[0].j, p[0].first, p[0].last), (0, 1, 1.0, 3.0));
        assert_eq!(p[0].peak_normal_force, 0.9);
        // Touching at gap 0 (t = 0) is not a contact.
        assert_eq!((p[1].i, p[1].j, p[1].first, p[1].last), (1, 2, 2.0, 2.0));
        let e = from_csv("t,i,j,fn\n").unwrap_err();
        assert!(e.contains("`gap`"), "{e}");
    }
}
