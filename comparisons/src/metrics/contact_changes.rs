//! GRC08 §VII, T.IV: the contacts one compression step keeps, destroys and creates — the
//! lists of two equilibrium states of one sample compared pair by pair.

use grainbench_engine::snapshot::Snapshot;
use serde::Serialize;
use std::collections::BTreeSet;

/// Contacts (surface gap h ≤ 0) kept, lost and gained between two states of one sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct ContactChanges {
    /// Contacts of the first state.
    pub before: usize,
    /// N^(=), N^(−), N^(+) of GRC08 T.IV.
    pub kept: usize,
    pub lost: usize,
    pub new: usize,
}

impl ContactChanges {
    /// `(key, value)` pairs as paper-values.toml names them (GRC08 T.IV; the fractions are
    /// of the first state's contacts, as T.IV prints them).
    pub fn values(&self) -> Vec<(String, f64)> {
        let of = |n: usize| n as f64 / self.before.max(1) as f64;
        [
            ("n_kept", self.kept as f64),
            ("n_lost", self.lost as f64),
            ("n_new", self.new as f64),
            ("frac_kept", of(self.kept)),
            ("frac_lost", of(self.lost)),
            ("frac_new", of(self.new)),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }
}

fn contacts(s: &Snapshot) -> BTreeSet<(usize, usize)> {
    s.contacts
        .iter()
        .filter(|c| c.gap <= 0.0)
        .map(|c| (c.i.min(c.j), c.i.max(c.j)))
        .collect()
}

/// The changes from `before` to `after`; `None` unless both hold the same grains.
pub fn contact_changes(before: &Snapshot, after: &Snapshot) -> Option<ContactChanges> {
    if before.particles.radius.len() != after.particles.radius.len() {
        return None;
    }
    let (a, b) = (contacts(before), contacts(after));
    let kept = a.intersection(&b).count();
    Some(ContactChanges {
        before: a.len(),
        kept,
        lost: a.len() - kept,
        new: b.len() - kept,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::fixtures;

    #[test]
    fn kept_lost_and_new_pairs() {
        // 4 × 4 square lattice of touching disks: 32 contacts.
        let (l, r, pos, bonds) = fixtures::lattice(2, 4, 1.0, 0.5, 1.0);
        let mut a = fixtures::unchecked_snapshot(l, r, pos, &bonds, false, None);
        let n = a.contacts.len();
        assert_eq!(n, 32);
        let mut b = a.clone();
        // One contact opens (h > 0: not a contact), one listed the other way round stays
        // the same pair, one new pair closes.
        b.contacts[0].gap = 1e-3;
        let (i, j) = (b.contacts[1].i, b.contacts[1].j);
        b.contacts[1].i = j;
        b.contacts[1].j = i;
        let mut extra = b.contacts[2].clone();
        extra.i = 0;
        extra.j = a.particles.radius.len() - 1;
        b.contacts.push(extra);
        // A distant pair in the first state is no contact either: it is new in the second.
        a.contacts[3].gap = 5e-4;
        let c = contact_changes(&a, &b).unwrap();
        assert_eq!(c.before, n - 1);
        assert_eq!(c.lost, 1, "{c:?}");
        assert_eq!(c.kept, n - 2, "{c:?}");
        assert_eq!(c.new, 2, "{c:?}");
        let v = c.values();
        let get = |k: &str| v.iter().find(|(key, _)| key == k).unwrap().1;
        assert_eq!(get("n_kept"), (n - 2) as f64);
        assert!((get("frac_kept") + get("frac_lost") - 1.0).abs() < 1e-12);
        let mut fewer = b.clone();
        fewer.particles.radius.pop();
        assert!(contact_changes(&a, &fewer).is_none());
    }
}
