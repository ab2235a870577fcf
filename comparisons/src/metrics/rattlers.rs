//! The rattler algorithm: which grains belong to the force-carrying backbone.
//!
//! Rattlers are grains that carry no force and are free to move inside the cage of their
//! neighbours (AR07 §III.B, GRC07 §III.A). They are found by iterated removal on the graph of
//! *force-carrying* contacts (contacts whose force is above tolerance, chosen by the caller):
//!
//! 1. every grain with fewer than [`Rule::min_contacts`] such contacts is a rattler;
//! 2. the contacts of rattlers are removed, which may leave neighbours below the threshold;
//! 3. repeat until no grain is removed (AR07: "twice at most is enough in our samples").
//!
//! The thresholds (AR07 §III.B, AR07 §IV.D, GRC07 §III.A):
//!
//! | rule | a backbone grain needs | why |
//! | --- | --- | --- |
//! | [`Rule::Frictionless`] | `d + 1` contacts (4 in 3D, 3 in 2D) | fewer than `d` is a mechanism, and exactly `d` cannot balance strictly compressive normal forces (AR07 Fig. 13) |
//! | [`Rule::Frictional`] | 2 contacts | grains with 2 and 3 contacts carry force through friction (AR07 T.V, Fig. 14; GRC07 Fig. 3) |
//! | [`Rule::Cohesive`] | 1 interaction | cohesive packings have virtually no rattlers (GRC07 §III.A); only isolated grains are removed |
//!
//! The removal is done as a graph peeling in sweeps (`O(n + N_c)` overall): sweep 1 removes
//! every grain below the threshold, sweep `s + 1` the grains that fell below it in sweep `s`.
//! The result is the same as recounting all grains after each sweep.

use grainbench_engine::network::Incidence;
use grainbench_engine::snapshot::Snapshot;
use serde::Serialize;

/// Which grains may stay on the backbone.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Rule {
    /// μ = 0: at least `dim + 1` force-carrying contacts (AR07 §III.B).
    Frictionless { dim: usize },
    /// μ > 0 (or μ = ∞): at least 2 force-carrying contacts (AR07 §IV.D, GRC07 §III.A).
    Frictional,
    /// Cohesive law: at least 1 interaction (GRC07 §III.A: no rattlers but isolated grains).
    Cohesive,
}

impl Rule {
    /// The rule a snapshot calls for: cohesive law → [`Rule::Cohesive`]; `mu == Some(0.0)` →
    /// [`Rule::Frictionless`] in the snapshot's dimension; otherwise [`Rule::Frictional`].
    pub fn for_snapshot(snap: &Snapshot) -> Rule {
        if snap.cohesive {
            Rule::Cohesive
        } else if snap.mu == Some(0.0) {
            Rule::Frictionless {
                dim: snap.dimension,
            }
        } else {
            Rule::Frictional
        }
    }

    /// Fewest contacts a backbone grain may have: `d + 1`, 2 or 1.
    pub fn min_contacts(self) -> usize {
        match self {
            Rule::Frictionless { dim } => dim + 1,
            Rule::Frictional => 2,
            Rule::Cohesive => 1,
        }
    }

    /// Short human-readable description, for reports.
    pub fn describe(self) -> String {
        match self {
            Rule::Frictionless { dim } => {
                format!("frictionless: remove grains with < {} contacts", dim + 1)
            }
            Rule::Frictional => "frictional: remove grains with 0 or 1 contact".to_string(),
            Rule::Cohesive => "cohesive: remove isolated grains only".to_string(),
        }
    }
}

/// Outcome of [`find_rattlers`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rattlers {
    /// One entry per grain: `true` for a rattler.
    pub is_rattler: Vec<bool>,
    /// One entry per input pair: `true` if the contact survives (both grains on the backbone).
    pub kept: Vec<bool>,
    /// Number of surviving contacts, N_c of AR07 §III.B (`z = 2 N_c / n`).
    pub contacts: usize,
    /// Number of removal sweeps that removed something (0 when there is no rattler).
    pub sweeps: usize,
}

impl Rattlers {
    /// Number of rattlers.
    pub fn count(&self) -> usize {
        self.is_rattler.iter().filter(|&&r| r).count()
    }

    /// Surviving contacts of each grain (0 for rattlers).
    pub fn contact_numbers(&self, n: usize, pairs: &[(usize, usize)]) -> Vec<usize> {
        let mut k = vec![0usize; n];
        for (&(i, j), &kept) in pairs.iter().zip(&self.kept) {
            if kept {
                k[i] += 1;
                k[j] += 1;
            }
        }
        k
    }
}

/// Largest contact number given its own `x_k` entry at least (more are added if present).
pub const X_K_MIN_LEN: usize = 13;

/// x_k, k = 0, 1, …: the fraction of the grains with k contacts, given each grain's contact
/// number (AR07 T.I, T.V); at least [`X_K_MIN_LEN`] entries, all 0 without grains.
pub fn contact_number_fractions(k_of: &[usize]) -> Vec<f64> {
    let n = k_of.len();
    let kmax = k_of.iter().copied().max().unwrap_or(0);
    let mut x_k = vec![0.0; X_K_MIN_LEN.max(kmax + 1)];
    for &k in k_of {
        x_k[k] += 1.0;
    }
    if n > 0 {
        x_k.iter_mut().for_each(|x| *x /= n as f64);
    }
    x_k
}

/// Iterated rattler removal (AR07 §III.B) on `n` grains joined by the force-carrying
/// contacts `pairs` (grain indices `i`, `j`; each pair is one contact).
///
/// # Panics
/// If a pair names a grain `>= n` or joins a grain to itself.
pub fn find_rattlers(n: usize, pairs: &[(usize, usize)], rule: Rule) -> Rattlers {
    let min = rule.min_contacts();
    let mut degree = vec![0usize; n];
    for (k, &(i, j)) in pairs.iter().enumerate() {
        assert!(
            i < n && j < n && i != j,
            "contact {k} joins grains {i} and {j} (there are {n} grains)"
        );
        degree[i] += 1;
        degree[j] += 1;
    }
    let incident = Incidence::new(n, pairs.iter().copied());

    let mut is_rattler: Vec<bool> = degree.iter().map(|&z| z < min).collect();
    let mut kept = vec![true; pairs.len()];
    let mut frontier: Vec<usize> = (0..n).filter(|&g| is_rattler[g]).collect();
    let mut sweeps = 0;
    while !frontier.is_empty() {
        sweeps += 1;
        let mut next = Vec::new();
        for &g in &frontier {
            for &k in incident.of(g) {
                let k = k as usize;
                if !kept[k] {
                    continue;
                }
                kept[k] = false;
                let (i, j) = pairs[k];
                let other = if i == g { j } else { i };
                degree[g] -= 1;
                degree[other] -= 1;
                if !is_rattler[other] && degree[other] < min {
                    is_rattler[other] = true;
                    next.push(other);
                }
            }
        }
        frontier = next;
    }
    let contacts = kept.iter().filter(|&&k| k).count();
    Rattlers {
        is_rattler,
        kept,
        contacts,
        sweeps,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Complete graph on `nodes` (each grain has `nodes.len() - 1` contacts).
    fn complete(nodes: &[usize]) -> Vec<(usize, usize)> {
        let mut p = Vec::new();
        for (a, &i) in nodes.iter().enumerate() {
            for &j in &nodes[a + 1..] {
                p.push((i, j));
            }
        }
        p
    }

    fn rattler_set(r: &Rattlers) -> Vec<usize> {
        (0..r.is_rattler.len())
            .filter(|&g| r.is_rattler[g])
            .collect()
    }

    #[test]
    fn thresholds_follow_the_papers() {
        assert_eq!(Rule::Frictionless { dim: 3 }.min_contacts(), 4);
        assert_eq!(Rule::Frictionless { dim: 2 }.min_contacts(), 3);
        assert_eq!(Rule::Frictional.min_contacts(), 2);
        assert_eq!(Rule::Cohesive.min_contacts(), 1);
    }

    #[test]
    fn frictionless_3d_cascade() {
        // Core K5 (grains 0..5, 4 contacts each) keeps everyone at 4.
        // Grain 5: contacts with 6, 0, 1 (3 contacts) → rattler in sweep 1.
        // Grain 6: contacts with 5, 2, 3, 4 (4 contacts) → 3 once 5 is gone → sweep 2.
        let mut pairs = complete(&[0, 1, 2, 3, 4]);
        pairs.extend([(5, 6), (5, 0), (5, 1), (6, 2), (6, 3), (6, 4)]);
        let r = find_rattlers(7, &pairs, Rule::Frictionless { dim: 3 });
        assert_eq!(rattler_set(&r), vec![5, 6]);
        assert_eq!(r.contacts, 10);
        assert_eq!(r.sweeps, 2);
        assert_eq!(r.contact_numbers(7, &pairs), vec![4, 4, 4, 4, 4, 0, 0]);
        // The same graph under the frictional rule loses nothing.
        let f = find_rattlers(7, &pairs, Rule::Frictional);
        assert_eq!(f.count(), 0);
        assert_eq!(f.contacts, pairs.len());
        assert_eq!(f.sweeps, 0);
    }

    #[test]
    fn frictionless_3d_keeps_four_contacts() {
        // K5: exactly 4 contacts each, the 3D threshold: nobody goes.
        let pairs = complete(&[0, 1, 2, 3, 4]);
        let r = find_rattlers(5, &pairs, Rule::Frictionless { dim: 3 });
        assert_eq!(r.count(), 0);
        assert_eq!(r.contacts, 10);
        // K4 (3 contacts each) collapses entirely in one sweep.
        let pairs = complete(&[0, 1, 2, 3]);
        let r = find_rattlers(4, &pairs, Rule::Frictionless { dim: 3 });
        assert_eq!(r.count(), 4);
        assert_eq!(r.contacts, 0);
        assert_eq!(r.sweeps, 1);
        // ... but stands in 2D, where 3 contacts are enough.
        let r = find_rattlers(4, &pairs, Rule::Frictionless { dim: 2 });
        assert_eq!(r.count(), 0);
    }

    #[test]
    fn frictional_dangling_chain_cascades() {
        // Ring 0-1-2-3-0 (2 contacts each), chain 0-4-5-6 hanging from grain 0, isolated 7.
        let pairs = vec![(0, 1), (1, 2), (2, 3), (3, 0), (0, 4), (4, 5), (5, 6)];
        let r = find_rattlers(8, &pairs, Rule::Frictional);
        assert_eq!(rattler_set(&r), vec![4, 5, 6, 7]);
        assert_eq!(r.contacts, 4);
        assert_eq!(r.sweeps, 3, "6 and 7, then 5, then 4");
        assert_eq!(r.kept, vec![true, true, true, true, false, false, false]);
        // Frictionless 2D needs 3: the ring goes as well.
        let r = find_rattlers(8, &pairs, Rule::Frictionless { dim: 2 });
        assert_eq!(r.count(), 8);
        assert_eq!(r.contacts, 0);
    }

    #[test]
    fn cohesive_removes_only_isolated_grains() {
        let pairs = vec![(0, 1), (1, 2)];
        let r = find_rattlers(4, &pairs, Rule::Cohesive);
        assert_eq!(rattler_set(&r), vec![3]);
        assert_eq!(r.contacts, 2);
        assert_eq!(r.sweeps, 1);
    }

    #[test]
    fn duplicate_pairs_count_twice() {
        // Two grains joined twice: 2 contacts each, frictional backbone.
        let r = find_rattlers(2, &[(0, 1), (1, 0)], Rule::Frictional);
        assert_eq!(r.count(), 0);
    }

    #[test]
    #[should_panic(expected = "joins grains")]
    fn bad_index_panics() {
        find_rattlers(2, &[(0, 2)], Rule::Frictional);
    }
}
