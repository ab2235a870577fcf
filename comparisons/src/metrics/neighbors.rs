//! Pair search in the periodic orthorhombic cell with a cell list: `O(n)` for a fixed cut-off
//! and density, any dimension up to 3. Separations are nearest periodic images, so a pair is
//! found once even if the cut-off exceeds half the cell (only its nearest image is seen).

/// A point, padded with zeros beyond the dimension.
pub(crate) type Point = [f64; 3];

/// Grain centres of a snapshot as padded points (missing components read as 0).
pub(crate) fn points(d: usize, position: &[impl std::ops::Deref<Target = [f64]>]) -> Vec<Point> {
    position
        .iter()
        .map(|p| {
            let mut q = [0.0; 3];
            for (a, x) in q.iter_mut().enumerate().take(d.min(3)) {
                *x = p.get(a).copied().unwrap_or(0.0);
            }
            q
        })
        .collect()
}

/// Are these cell lengths usable (2 or 3 of them, finite, positive)?
pub(crate) fn valid_cell(lengths: &[f64]) -> bool {
    (2..=3).contains(&lengths.len()) && lengths.iter().all(|l| l.is_finite() && *l > 0.0)
}

/// Nearest periodic image of `b − a`.
#[inline]
pub(crate) fn separation(lengths: &[f64], a: &Point, b: &Point) -> Point {
    let mut r = [0.0; 3];
    for (k, l) in lengths.iter().enumerate() {
        let d = b[k] - a[k];
        r[k] = d - l * (d / l).round();
    }
    r
}

#[inline]
pub(crate) fn norm2(r: &Point) -> f64 {
    r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
}

/// Stencil half-width in cells: cells are at least `cutoff / REACH` wide.
const REACH: i64 = 2;

/// Points sorted into the cells of a periodic grid, cells at least `cutoff / REACH` wide.
pub(crate) struct CellGrid<'a> {
    lengths: &'a [f64],
    cutoff: f64,
    m: [usize; 3],
    /// Points in cell order, with their original indices.
    pts: Vec<Point>,
    ids: Vec<usize>,
    /// Points of cell c are `start[c]..start[c + 1]`.
    start: Vec<usize>,
    /// Distinct neighbour cells along each axis, for each cell index.
    around: Vec<Vec<Vec<usize>>>,
}

impl<'a> CellGrid<'a> {
    /// `None` for a bad cell or a cut-off that is not positive and finite. Non-finite
    /// coordinates never panic (such a point lands in some cell and matches nothing).
    pub(crate) fn new(lengths: &'a [f64], pts: &[Point], cutoff: f64) -> Option<Self> {
        if !(valid_cell(lengths) && cutoff > 0.0 && cutoff.is_finite()) {
            return None;
        }
        let n = pts.len();
        let d = lengths.len();
        let mut m = [1usize; 3];
        for a in 0..d {
            let x = (REACH as f64 * lengths[a] / cutoff).floor();
            m[a] = if x >= 1.0 { x.min(1e6) as usize } else { 1 };
        }
        // Never more cells than a few per point.
        let cap = 4 * n + 64;
        while m.iter().product::<usize>() > cap {
            let a = (0..3).max_by_key(|&a| m[a]).unwrap_or(0);
            m[a] = (m[a] / 2).max(1);
        }
        let around = (0..3)
            .map(|a| {
                (0..m[a])
                    .map(|c| {
                        let mut v: Vec<usize> = (-REACH..=REACH)
                            .map(|o| (c as i64 + o).rem_euclid(m[a] as i64) as usize)
                            .collect();
                        v.sort_unstable();
                        v.dedup();
                        v
                    })
                    .collect()
            })
            .collect();
        let mut grid = CellGrid {
            lengths,
            cutoff,
            m,
            pts: Vec::with_capacity(n),
            ids: vec![0; n],
            start: vec![0; m[0] * m[1] * m[2] + 1],
            around,
        };
        // Counting sort of the points by cell.
        let home: Vec<usize> = pts.iter().map(|p| grid.index(&grid.cell_of(p))).collect();
        for &c in &home {
            grid.start[c + 1] += 1;
        }
        for c in 0..grid.start.len() - 1 {
            grid.start[c + 1] += grid.start[c];
        }
        let mut fill = grid.start.clone();
        for (i, &c) in home.iter().enumerate() {
            grid.ids[fill[c]] = i;
            fill[c] += 1;
        }
        grid.pts = grid.ids.iter().map(|&i| pts[i]).collect();
        Some(grid)
    }

    fn cell_of(&self, p: &Point) -> [usize; 3] {
        let mut c = [0usize; 3];
        for (a, l) in self.lengths.iter().enumerate() {
            let s = (p[a] / l).rem_euclid(1.0) * self.m[a] as f64;
            c[a] = (s as usize).min(self.m[a] - 1);
        }
        c
    }

    fn index(&self, c: &[usize; 3]) -> usize {
        (c[2] * self.m[1] + c[1]) * self.m[0] + c[0]
    }

    /// Cells of the stencil around cell `c`, each once.
    fn near(&self, c: &[usize; 3], out: &mut Vec<usize>) {
        out.clear();
        for &z in &self.around[2][c[2]] {
            for &y in &self.around[1][c[1]] {
                for &x in &self.around[0][c[0]] {
                    out.push(self.index(&[x, y, z]));
                }
            }
        }
    }

    /// Calls `f(i, r, r²)` for every point i of the grid with `r = r_i − p` shorter than the
    /// cut-off (p itself included if it is one of the points).
    pub(crate) fn query<F: FnMut(usize, &Point, f64)>(&self, p: &Point, mut f: F) {
        let cut2 = self.cutoff * self.cutoff;
        let mut near = Vec::with_capacity(125);
        self.near(&self.cell_of(p), &mut near);
        for &c in &near {
            for k in self.start[c]..self.start[c + 1] {
                let r = separation(self.lengths, p, &self.pts[k]);
                let r2 = norm2(&r);
                if r2 < cut2 {
                    f(self.ids[k], &r, r2);
                }
            }
        }
    }

    /// Calls `f(i, j, r, r²)` once for every pair `i < j` of grid points with
    /// `r = r_j − r_i` shorter than the cut-off.
    pub(crate) fn pairs<F: FnMut(usize, usize, &Point, f64)>(&self, mut f: F) {
        let cut2 = self.cutoff * self.cutoff;
        let mut near = Vec::with_capacity(125);
        for cz in 0..self.m[2] {
            for cy in 0..self.m[1] {
                for cx in 0..self.m[0] {
                    let c = self.index(&[cx, cy, cz]);
                    if self.start[c] == self.start[c + 1] {
                        continue;
                    }
                    // Half stencil: each unordered pair of cells once.
                    self.near(&[cx, cy, cz], &mut near);
                    for &c2 in near.iter().filter(|&&c2| c2 >= c) {
                        for k in self.start[c]..self.start[c + 1] {
                            let from = if c2 == c { k + 1 } else { self.start[c2] };
                            for k2 in from..self.start[c2 + 1] {
                                let r = separation(self.lengths, &self.pts[k], &self.pts[k2]);
                                let r2 = norm2(&r);
                                if r2 < cut2 {
                                    let (i, j) = (self.ids[k], self.ids[k2]);
                                    if i < j {
                                        f(i, j, &r, r2);
                                    } else {
                                        f(j, i, &r.map(|x| -x), r2);
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Calls `f(i, j, r, r²)` once for every pair `i < j` whose nearest-image separation
/// `r = r_j − r_i` is shorter than `cutoff`. Does nothing for fewer than 2 points, a bad cell
/// or a cut-off that is not positive and finite.
pub(crate) fn for_each_pair<F>(lengths: &[f64], pts: &[Point], cutoff: f64, f: F)
where
    F: FnMut(usize, usize, &Point, f64),
{
    if pts.len() < 2 {
        return;
    }
    if let Some(grid) = CellGrid::new(lengths, pts, cutoff) {
        grid.pairs(f);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::fixtures::Lcg;

    fn brute(lengths: &[f64], pts: &[Point], cutoff: f64) -> Vec<(usize, usize)> {
        let mut v = Vec::new();
        for i in 0..pts.len() {
            for j in i + 1..pts.len() {
                if norm2(&separation(lengths, &pts[i], &pts[j])) < cutoff * cutoff {
                    v.push((i, j));
                }
            }
        }
        v
    }

    /// The cell list finds exactly the pairs of the all-pairs search, in 2D and 3D, for
    /// cut-offs from a fraction of the cell to more than half of it, points outside the cell.
    #[test]
    fn same_pairs_as_brute_force() {
        let mut rng = Lcg(11);
        for (lengths, n) in [(vec![7.0, 5.0], 300), (vec![6.0, 4.5, 5.5], 400)] {
            let pts: Vec<Point> = (0..n)
                .map(|_| {
                    let mut p = [0.0; 3];
                    for (a, l) in lengths.iter().enumerate() {
                        p[a] = (3.0 * rng.next() - 1.0) * l;
                    }
                    p
                })
                .collect();
            for cutoff in [0.3, 1.0, 1.7, 2.4, 10.0] {
                let mut got = Vec::new();
                for_each_pair(&lengths, &pts, cutoff, |i, j, r, r2| {
                    let s = separation(&lengths, &pts[i], &pts[j]);
                    assert!((norm2(r) - r2).abs() < 1e-12 && s == *r);
                    got.push((i, j));
                });
                got.sort_unstable();
                assert_eq!(got, brute(&lengths, &pts, cutoff), "cutoff {cutoff}");
            }
        }
    }

    /// Queries return exactly the points within the cut-off, with r = r_i − p.
    #[test]
    fn query_matches_brute_force() {
        let mut rng = Lcg(4);
        let lengths = vec![5.0, 6.0, 7.0];
        let pts: Vec<Point> = (0..300)
            .map(|_| [5.0 * rng.next(), 6.0 * rng.next(), 7.0 * rng.next()])
            .collect();
        let grid = CellGrid::new(&lengths, &pts, 1.2).unwrap();
        for _ in 0..20 {
            let p = [10.0 * rng.next() - 2.0, 6.0 * rng.next(), 7.0 * rng.next()];
            let mut got = Vec::new();
            grid.query(&p, |i, r, r2| {
                assert_eq!(*r, separation(&lengths, &p, &pts[i]));
                assert!((norm2(r) - r2).abs() < 1e-12);
                got.push(i);
            });
            got.sort_unstable();
            let want: Vec<usize> = (0..pts.len())
                .filter(|&i| norm2(&separation(&lengths, &p, &pts[i])) < 1.44)
                .collect();
            assert_eq!(got, want);
        }
    }

    #[test]
    fn degenerate_inputs_do_nothing() {
        let pts = vec![[0.0; 3], [0.1, 0.0, 0.0], [f64::NAN, 0.0, 0.0]];
        let mut k = 0;
        for_each_pair(&[1.0, 1.0], &pts, 0.0, |_, _, _, _| k += 1);
        for_each_pair(&[1.0, -1.0], &pts, 0.5, |_, _, _, _| k += 1);
        for_each_pair(&[1.0, 1.0], &pts, f64::NAN, |_, _, _, _| k += 1);
        assert_eq!(k, 0);
        // Tiny cut-off: the number of cells stays bounded, the NaN point matches nothing.
        for_each_pair(&[1.0, 1.0], &pts, 1e-300, |_, _, _, _| k += 1);
        for_each_pair(&[1.0, 1.0], &pts, 0.2, |_, _, _, _| k += 1);
        assert_eq!(k, 1);
    }
}
