//! How the passes of a step are shared among threads: one contiguous piece per thread.
//!
//! rayon's `join` runs its first half on the calling thread and leaves the second to an idle
//! worker, so a pass cut into one piece per thread gives each thread the same grains and pairs
//! at every step. Left to split adaptively into many small pieces, work stealing moved them
//! between cores from pass to pass: two threads on the dense N = 4000 AR07 D took 9.3–16.5 s
//! for 40 000 steps against 14.1–14.6 s on one (docs/performance.md, issue 15). The per-grain
//! passes are cut by grains, the force pass by listed pairs.
//!
//! Only the cutting changes with the thread count: the fixed chunks inside each piece, and the
//! order in which their sums are reduced, do not.

/// Least number of items per piece for a pass over `n` items, so that rayon cuts it into one
/// piece per thread of the current pool (for a power-of-two count; rayon halves) and no finer.
pub fn piece_len(n: usize) -> usize {
    (n / rayon::current_num_threads()).max(1)
}

/// Cuts items of the given weights, in order, into one contiguous group per thread of the
/// current pool, of nearly equal total weight. Returns the group boundaries: `cuts[k]..cuts[k +
/// 1]` is group k, `cuts[0] = 0`, the last is `weights.len()`.
pub fn balanced_cuts(weights: &[usize]) -> Vec<usize> {
    let groups = rayon::current_num_threads().clamp(1, weights.len().max(1));
    let total: usize = weights.iter().sum();
    let mut cuts = Vec::with_capacity(groups + 1);
    cuts.push(0);
    let mut sum = 0;
    for (i, w) in weights.iter().enumerate() {
        let k = cuts.len();
        if k == groups {
            break;
        }
        // Cut before item i when that leaves group k − 1 closer to its share.
        let target = total * k / groups;
        if i > *cuts.last().unwrap() && sum + w / 2 >= target {
            cuts.push(i);
        }
        sum += w;
    }
    cuts.push(weights.len());
    cuts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn in_pool<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(f)
    }

    #[test]
    fn one_group_per_thread_of_nearly_equal_weight() {
        let w = [5, 5, 5, 5, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1];
        assert_eq!(in_pool(1, || balanced_cuts(&w)), vec![0, 16]);
        // Total 32: the first three items (15) against the rest (17).
        assert_eq!(in_pool(2, || balanced_cuts(&w)), vec![0, 3, 16]);
        let cuts = in_pool(4, || balanced_cuts(&[1; 10]));
        assert_eq!(cuts.len(), 5);
        assert!(cuts
            .windows(2)
            .all(|c| c[1] - c[0] >= 2 && c[1] - c[0] <= 3));
    }

    #[test]
    fn never_an_empty_group() {
        assert_eq!(in_pool(4, || balanced_cuts(&[9, 0])), vec![0, 1, 2]);
        assert_eq!(in_pool(2, || balanced_cuts(&[])), vec![0, 0]);
        assert_eq!(in_pool(2, || balanced_cuts(&[0, 0, 100])), vec![0, 2, 3]);
    }

    #[test]
    fn pieces_of_one_per_thread() {
        assert_eq!(in_pool(2, || piece_len(16)), 8);
        assert_eq!(in_pool(2, || piece_len(5)), 2);
        assert_eq!(in_pool(4, || piece_len(3)), 1);
        assert_eq!(in_pool(1, || piece_len(7)), 7);
    }
}
