//! How the passes of a step are shared among threads: one contiguous piece per thread.
//!
//! rayon's `join` runs its first half on the calling thread and leaves the second to an idle
//! worker, so a pass cut into one piece per thread gives each thread the same grains and pairs
//! at every step. Left to split adaptively into many small pieces, work stealing moved them
//! between cores from pass to pass: two threads on the dense N = 4000 AR07 D took 9.3–16.5 s
//! for 40 000 steps against 14.1–14.6 s on one (docs/performance.md). The per-grain
//! passes are cut by grains, the force pass by listed pairs.
//!
//! Only the cutting changes with the thread count: the fixed chunks inside each piece, and the
//! order in which their sums are reduced, do not.
//!
//! Between passes an idle rayon worker soon falls asleep, and waking it (a futex, through the
//! hypervisor on a VM) can take longer than its piece: the caller then runs both pieces itself.
//! While a [`KeepAwake`] lives, the other workers of the pool spin instead, taking any pending
//! job as it appears.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

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

/// While alive, every other thread of the current rayon pool spins (running each pending job
/// it finds, else yielding to the OS scheduler) instead of sleeping between the passes of a
/// step. Made on a pool thread with others beside it, `None` elsewhere; keeps the other cores
/// busy whether or not there is work, so it lives only while a system is stepped.
pub struct KeepAwake {
    stop: Arc<AtomicBool>,
    /// Whether this thread held one already (a run inside a run).
    held: bool,
    /// Dropped on the thread that made it, where `held` is restored.
    _here: std::marker::PhantomData<*const ()>,
}

thread_local! {
    /// Whether a [`KeepAwake`] made on this thread is alive: another one's spinner landing here
    /// returns at once, so two runs stepped side by side in one pool never park each other's
    /// threads.
    static HOLDS: Cell<bool> = const { Cell::new(false) };
}

impl KeepAwake {
    pub fn new() -> Option<Self> {
        rayon::current_thread_index()?;
        if rayon::current_num_threads() < 2 {
            return None;
        }
        let held = HOLDS.with(|h| h.replace(true));
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        rayon::spawn_broadcast(move |_| {
            // The caller's own copy (and a copy on any thread stepping a run of its own)
            // returns at once: it runs whenever that thread looks for work, and must never
            // hold it.
            if HOLDS.with(|h| h.get()) {
                return;
            }
            while !flag.load(Ordering::Relaxed) {
                if rayon::yield_now() != Some(rayon::Yield::Executed) {
                    // Leave the core to any other runnable thread (tests, other runs): with
                    // none, this returns at once and the vCPU never halts.
                    std::thread::yield_now();
                }
            }
        });
        Some(KeepAwake {
            stop,
            held,
            _here: std::marker::PhantomData,
        })
    }
}

impl Drop for KeepAwake {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        HOLDS.with(|h| h.set(self.held));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

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
    fn keep_awake_only_on_a_pool_thread_with_others() {
        assert!(KeepAwake::new().is_none() || rayon::current_thread_index().is_some());
        assert!(in_pool(1, || KeepAwake::new().is_none()));
        // Two threads: the other spins until the guard drops and takes the pool's work; the
        // caller's own copy of the spinner returns when the caller picks it up (else this
        // hangs).
        let sum = in_pool(2, || {
            let guard = KeepAwake::new();
            assert!(guard.is_some());
            for _ in 0..100 {
                rayon::yield_now();
            }
            let s: usize = (0..10_000usize).into_par_iter().with_min_len(5_000).sum();
            drop(guard);
            s
        });
        assert_eq!(sum, 49_995_000);
        // Two holders stepped side by side, one on each thread: neither thread is parked in the
        // other's spinner (else this hangs).
        let run = || {
            let _guard = KeepAwake::new();
            (0..1_000_000usize)
                .into_par_iter()
                .with_min_len(1000)
                .sum::<usize>()
        };
        let (a, b) = in_pool(2, || rayon::join(run, run));
        assert_eq!(a, b);
    }

    #[test]
    fn pieces_of_one_per_thread() {
        assert_eq!(in_pool(2, || piece_len(16)), 8);
        assert_eq!(in_pool(2, || piece_len(5)), 2);
        assert_eq!(in_pool(4, || piece_len(3)), 1);
        assert_eq!(in_pool(1, || piece_len(7)), 7);
    }
}
