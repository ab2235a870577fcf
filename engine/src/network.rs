//! Connectivity of an interaction network in the periodic cell: the edges at each grain, the
//! axes it wraps.

/// The edges at each grain in compressed rows: [`Incidence::of`] lists the indices of the
/// edges with that grain as an end, in edge order. 32-bit indices and one flat array: this runs
/// on the first check of large packings (the peak of a run's memory) and in the rattler
/// removal, where a list per grain costs ten times as much.
pub struct Incidence {
    start: Vec<usize>,
    edge: Vec<u32>,
}

impl Incidence {
    /// The incidence of `n` grains joined by the edges whose ends `ends` yields, in order
    /// (walked twice).
    ///
    /// # Panics
    /// If an end is ≥ `n`.
    pub fn new(n: usize, ends: impl Iterator<Item = (usize, usize)> + Clone) -> Self {
        let mut start = vec![0usize; n + 1];
        for (i, j) in ends.clone() {
            start[i + 1] += 1;
            start[j + 1] += 1;
        }
        for k in 0..n {
            start[k + 1] += start[k];
        }
        let mut fill = start[..n].to_vec();
        let mut edge = vec![0u32; start[n]];
        for (k, (i, j)) in ends.enumerate() {
            for g in [i, j] {
                edge[fill[g]] = k as u32;
                fill[g] += 1;
            }
        }
        Incidence { start, edge }
    }

    /// Indices of the edges at grain `g`.
    pub fn of(&self, g: usize) -> &[u32] {
        &self.edge[self.start[g]..self.start[g + 1]]
    }
}

/// Axes along which the network of `edges` — grains `pair(e) = (i, j)` joined by `branch(e)`,
/// r_j − r_i taken to the nearest image (asked for once per edge and end, when the walk reaches
/// it) — wraps the periodic cell of sides `lengths`: some closed path of
/// interactions crosses the cell a net non-zero number of times along that axis.
///
/// A network that does not wrap along an axis cannot carry stress along it at any cell length:
/// under a prescribed stress (P* = 0 in GRC07 §III.B.1) nothing holds the cell there, and the
/// cell drifts with the kinetic stress of the grains.
///
/// # Panics
/// If an edge names a grain ≥ `n` or has a branch shorter than `lengths`.
pub fn wrapped_axes<E, B>(
    lengths: &[f64],
    n: usize,
    edges: &[E],
    pair: impl Fn(&E) -> (usize, usize),
    branch: impl Fn(&E) -> B,
) -> Vec<bool>
where
    B: std::ops::Index<usize, Output = f64>,
{
    let d = lengths.len();
    let incidence = Incidence::new(n, edges.iter().map(&pair));
    // Breadth-first walk: each grain gets an unwrapped position (`offset`, d values a grain)
    // relative to the first grain of its cluster; an edge closing a loop whose branches sum to
    // a non-zero lattice vector wraps the cell.
    let mut offset = vec![0.0; n * d];
    let mut placed = vec![false; n];
    let mut wraps = vec![false; d];
    let mut queue = std::collections::VecDeque::new();
    for first in 0..n {
        if placed[first] {
            continue;
        }
        placed[first] = true;
        queue.push_back(first);
        while let Some(i) = queue.pop_front() {
            for &e in incidence.of(i) {
                let edge = &edges[e as usize];
                let ((from, to), branch) = (pair(edge), branch(edge));
                // The branch points from `from` to `to`: walked from its other end, reversed.
                let (j, sign) = if from == i { (to, 1.0) } else { (from, -1.0) };
                for a in 0..d {
                    let reached = offset[i * d + a] + sign * branch[a];
                    if !placed[j] {
                        offset[j * d + a] = reached;
                    } else if ((reached - offset[j * d + a]) / lengths[a]).round() != 0.0 {
                        wraps[a] = true;
                    }
                }
                if !placed[j] {
                    placed[j] = true;
                    queue.push_back(j);
                }
            }
        }
    }
    wraps
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ring of `k` grains at spacing 1 along x in a cell of side `k` (each a neighbour of the
    /// next, the last of the first through the boundary).
    fn ring(k: usize) -> Vec<(usize, usize, Vec<f64>)> {
        (0..k).map(|i| (i, (i + 1) % k, vec![1.0, 0.0])).collect()
    }

    fn axes(lengths: &[f64], n: usize, edges: &[(usize, usize, Vec<f64>)]) -> Vec<bool> {
        wrapped_axes(
            lengths,
            n,
            edges,
            |(i, j, _)| (*i, *j),
            |(_, _, b)| b.clone(),
        )
    }

    #[test]
    fn a_chain_through_the_boundary_wraps_its_axis_only() {
        assert_eq!(axes(&[6.0, 10.0], 6, &ring(6)), [true, false]);
        // The same chain with one link missing spans the cell but does not wrap it.
        assert_eq!(axes(&[6.0, 10.0], 6, &ring(6)[..5]), [false, false]);
    }

    #[test]
    fn a_finite_loop_does_not_wrap() {
        // A triangle well inside the cell, listed in both orientations.
        let tri = [
            (0, 1, vec![1.0, 0.0]),
            (2, 1, vec![0.5, -0.8]),
            (2, 0, vec![-0.5, -0.8]),
        ];
        assert_eq!(axes(&[10.0, 10.0], 3, &tri), [false, false]);
    }

    #[test]
    fn a_square_lattice_wraps_both_axes_and_a_cubic_one_all_three() {
        let (k, mut edges) = (4usize, Vec::new());
        for x in 0..k {
            for y in 0..k {
                let i = x * k + y;
                edges.push((i, ((x + 1) % k) * k + y, vec![1.0, 0.0]));
                edges.push((i, x * k + (y + 1) % k, vec![0.0, 1.0]));
            }
        }
        assert_eq!(axes(&[4.0, 4.0], k * k, &edges), [true, true]);
        // Cut every x bond across the boundary: stripes along x no longer close.
        let cut: Vec<_> = edges
            .iter()
            .filter(|(i, j, b)| !(b[0] == 1.0 && j < i))
            .cloned()
            .collect();
        assert_eq!(axes(&[4.0, 4.0], k * k, &cut), [false, true]);
        let cube: Vec<_> = (0..27usize)
            .flat_map(|i| {
                let (x, y, z) = (i / 9, (i / 3) % 3, i % 3);
                [
                    (i, ((x + 1) % 3) * 9 + y * 3 + z, vec![1.0, 0.0, 0.0]),
                    (i, x * 9 + ((y + 1) % 3) * 3 + z, vec![0.0, 1.0, 0.0]),
                    (i, x * 9 + y * 3 + (z + 1) % 3, vec![0.0, 0.0, 1.0]),
                ]
            })
            .collect();
        assert_eq!(axes(&[3.0; 3], 27, &cube), [true, true, true]);
    }

    #[test]
    fn a_diagonal_loop_wraps_both_axes() {
        // One grain linked to its own image at (+1, +1) through a second grain.
        let edges = [(0, 1, vec![1.0, 1.0]), (1, 0, vec![1.0, 1.0])];
        assert_eq!(axes(&[2.0, 2.0], 2, &edges), [true, true]);
    }
}
