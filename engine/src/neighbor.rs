//! Neighbour search: cell lists and a Verlet skin, in a periodic cell whose lengths change.
//!
//! The list is a half list in compressed-row form (pairs i < j, each row sorted by j); the
//! per-pair contact history lives in an array beside it and is carried over at each rebuild by
//! looking the pair up in the old row, so it survives rebuilds without a hash map. A transposed
//! index lets each grain gather the forces of the pairs where it is the second member, so the
//! force sums are computed in a fixed order whatever the number of threads.

use crate::geometry::{Dim, VectorOps};
use rayon::prelude::*;

/// Rows handled per parallel task: fixed, so results do not depend on the thread count.
pub const ROW_CHUNK: usize = 256;

/// Verlet half list with history.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct NeighborList<H> {
    /// Row i holds partners `partner[row_start[i]..row_start[i+1]]`, all > i, ascending.
    pub row_start: Vec<u32>,
    pub partner: Vec<u32>,
    /// Contact history, one per pair.
    pub history: Vec<H>,
    /// Transposed index: pairs where grain j is the partner are `col_pair[col_start[j]..col_start[j+1]]`.
    pub col_start: Vec<u32>,
    pub col_pair: Vec<u32>,
    /// Listing distance beyond contact (interaction range + skin).
    pub skin: f64,
    /// Cell lengths at the last build.
    pub l_build: Vec<f64>,
    /// Number of rebuilds so far.
    pub builds: u64,
}

impl<H: Copy + Default + Send + Sync> NeighborList<H> {
    pub fn new(skin: f64) -> Self {
        NeighborList {
            row_start: vec![0],
            partner: Vec::new(),
            history: Vec::new(),
            col_start: vec![0],
            col_pair: Vec::new(),
            skin,
            l_build: Vec::new(),
            builds: 0,
        }
    }

    pub fn pairs(&self) -> usize {
        self.partner.len()
    }

    /// Row range of grain i.
    #[inline(always)]
    pub fn row(&self, i: usize) -> std::ops::Range<usize> {
        self.row_start[i] as usize..self.row_start[i + 1] as usize
    }

    /// Does the list need a rebuild? `max_disp` is the largest peculiar displacement of a
    /// grain since the build, `l` the current lengths, `reach` the largest listing distance
    /// 2R_max + range + skin. A pair left out at build time was farther than its cut-off plus
    /// the skin; it cannot have come within its cut-off while 2·max_disp plus the affine
    /// shrinkage of `reach` stays below the skin.
    pub fn stale<D: Dim>(&self, max_disp: f64, l: &D::V, reach: f64) -> bool {
        if self.l_build.len() != D::D {
            return true;
        }
        let mut shrink: f64 = 0.0;
        for a in 0..D::D {
            shrink = shrink.max(1.0 - l[a] / self.l_build[a]);
        }
        2.0 * max_disp + shrink.max(0.0) * reach >= self.skin
    }

    /// Rebuilds the list for reduced positions `s` in [0,1)^d, radii `radius` and lengths `l`;
    /// pairs closer than R_i + R_j + `range` + skin are listed. History is carried over.
    pub fn build<D: Dim>(&mut self, s: &[D::V], radius: &[f64], l: &D::V, range: f64) {
        let n = s.len();
        let r_max = radius.iter().cloned().fold(0.0, f64::max);
        let reach = 2.0 * r_max + range + self.skin;
        // Cells of side ≥ reach; fewer than 3 along an axis falls back to all pairs. At most
        // ~64 cells a grain: a dilute gas gets larger cells, not a grid beyond memory (or an
        // overflow of the cell count, found by tests/fuzz.rs).
        let mut ncell = [1usize; 3];
        let mut brute = false;
        let most = ((64 * n.max(1)) as f64)
            .powf(1.0 / D::D as f64)
            .floor()
            .max(3.0);
        for a in 0..D::D {
            ncell[a] = (l[a] / reach).floor().min(most) as usize;
            if ncell[a] < 3 {
                brute = true;
            }
            ncell[a] = ncell[a].max(1);
        }
        let cell_of = |x: &D::V| -> usize {
            let mut c = 0;
            for a in (0..D::D).rev() {
                let k = ((x[a] * ncell[a] as f64) as usize).min(ncell[a] - 1);
                c = c * ncell[a] + k;
            }
            c
        };
        let total: usize = ncell[..D::D].iter().product();
        // Counting sort of grains into cells.
        let mut head = vec![0u32; total + 1];
        let cells: Vec<u32> = if brute {
            vec![0; n]
        } else {
            s.par_iter().map(|x| cell_of(x) as u32).collect()
        };
        for &c in &cells {
            head[c as usize + 1] += 1;
        }
        for c in 0..total {
            head[c + 1] += head[c];
        }
        let mut fill = head.clone();
        let mut order = vec![0u32; n];
        for (i, &c) in cells.iter().enumerate() {
            let c = c as usize;
            order[fill[c] as usize] = i as u32;
            fill[c] += 1;
        }
        drop(cells);
        let skin = self.skin;
        let listed = |i: usize, j: usize| -> bool {
            let r = branch::<D>(&s[i], &s[j], l);
            let cut = radius[i] + radius[j] + range + skin;
            r.norm_squared() < cut * cut
        };
        // Appends row i (ascending partners) to `row`.
        let row_of = |i: usize, row: &mut Vec<u32>| {
            let first = row.len();
            if brute {
                for j in i + 1..n {
                    if listed(i, j) {
                        row.push(j as u32);
                    }
                }
                return;
            }
            let mut ci = [0usize; 3];
            for a in 0..D::D {
                ci[a] = ((s[i][a] * ncell[a] as f64) as usize).min(ncell[a] - 1);
            }
            let span = |a: usize| -> [usize; 3] {
                let m = ncell[a];
                [(ci[a] + m - 1) % m, ci[a], (ci[a] + 1) % m]
            };
            let sx = span(0);
            let sy = span(1);
            let sz = if D::D == 3 { span(2) } else { [0, 0, 0] };
            let nz = if D::D == 3 { 3 } else { 1 };
            for z in sz.iter().take(nz) {
                for y in &sy {
                    for x in &sx {
                        let c = if D::D == 3 {
                            (z * ncell[1] + y) * ncell[0] + x
                        } else {
                            y * ncell[0] + x
                        };
                        for &j in &order[head[c] as usize..head[c + 1] as usize] {
                            let j = j as usize;
                            if j > i && listed(i, j) {
                                row.push(j as u32);
                            }
                        }
                    }
                }
            }
            row[first..].sort_unstable();
        };
        // Rows in fixed chunks, each chunk one buffer of partners and one of row ends (one
        // allocation per chunk rather than per grain: less transient memory at large N).
        let chunks: Vec<(Vec<u32>, Vec<u32>)> = (0..n.div_ceil(ROW_CHUNK))
            .into_par_iter()
            .map(|c| {
                let rows = c * ROW_CHUNK..((c + 1) * ROW_CHUNK).min(n);
                let mut ends = Vec::with_capacity(rows.len());
                let mut part = Vec::new();
                for i in rows {
                    row_of(i, &mut part);
                    ends.push(part.len() as u32);
                }
                (ends, part)
            })
            .collect();
        let mut row_start = Vec::with_capacity(n + 1);
        row_start.push(0u32);
        let mut partner = Vec::with_capacity(chunks.iter().map(|c| c.1.len()).sum());
        for (ends, part) in chunks {
            let base = partner.len() as u32;
            row_start.extend(ends.iter().map(|e| base + e));
            partner.extend_from_slice(&part);
        }
        // Carry the history over.
        let old = (&self.row_start, &self.partner, &self.history);
        let history: Vec<H> = (0..n)
            .into_par_iter()
            .flat_map_iter(|i| {
                let new_row = &partner[row_start[i] as usize..row_start[i + 1] as usize];
                let old_row = if i + 1 < old.0.len() {
                    let r = old.0[i] as usize..old.0[i + 1] as usize;
                    (&old.1[r.clone()], &old.2[r])
                } else {
                    (&[][..], &[][..])
                };
                new_row
                    .iter()
                    .map(move |j| match old_row.0.binary_search(j) {
                        Ok(k) => old_row.1[k],
                        Err(_) => H::default(),
                    })
            })
            .collect();
        // Transposed index, by counting sort (pairs in ascending order within each column).
        let mut col_start = vec![0u32; n + 1];
        for &j in &partner {
            col_start[j as usize + 1] += 1;
        }
        for j in 0..n {
            col_start[j + 1] += col_start[j];
        }
        let mut col_fill = col_start.clone();
        let mut col_pair = vec![0u32; partner.len()];
        for (p, &j) in partner.iter().enumerate() {
            col_pair[col_fill[j as usize] as usize] = p as u32;
            col_fill[j as usize] += 1;
        }
        self.row_start = row_start;
        self.partner = partner;
        self.history = history;
        self.col_start = col_start;
        self.col_pair = col_pair;
        self.l_build = (0..D::D).map(|a| l[a]).collect();
        self.builds += 1;
    }
}

/// Spreads the low 21 bits of `x` to every third bit (3D Morton interleave).
#[inline(always)]
fn spread3(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | x << 32) & 0x1f_0000_0000_ffff;
    x = (x | x << 16) & 0x1f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    (x | x << 2) & 0x1249_2492_4924_9249
}

/// Spreads the low 32 bits of `x` to every second bit (2D Morton interleave).
#[inline(always)]
fn spread2(x: u64) -> u64 {
    let mut x = x & 0xffff_ffff;
    x = (x | x << 16) & 0x0000_ffff_0000_ffff;
    x = (x | x << 8) & 0x00ff_00ff_00ff_00ff;
    x = (x | x << 4) & 0x0f0f_0f0f_0f0f_0f0f;
    x = (x | x << 2) & 0x3333_3333_3333_3333;
    (x | x << 1) & 0x5555_5555_5555_5555
}

/// Indices of the reduced positions `s` (in [0,1)^d) in Morton (Z-curve) order; ties keep
/// their input order, so the result is deterministic.
pub fn morton_order<D: Dim>(s: &[D::V]) -> Vec<u32> {
    let bits = if D::D == 3 { 21 } else { 32 };
    let scale = (1u64 << bits) as f64;
    let top = (1u64 << bits) - 1;
    let key = |x: &D::V| -> u64 {
        let q = |a: usize| ((x[a] * scale) as u64).min(top);
        if D::D == 3 {
            spread3(q(0)) | spread3(q(1)) << 1 | spread3(q(2)) << 2
        } else {
            spread2(q(0)) | spread2(q(1)) << 1
        }
    };
    let mut keyed: Vec<(u64, u32)> = s
        .iter()
        .enumerate()
        .map(|(i, x)| (key(x), i as u32))
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// Branch vector from grain i to the nearest periodic image of grain j: L·(s_j − s_i) of the
/// reduced positions `si`, `sj` (in [0, 1)) in a cell of lengths `l`.
#[inline(always)]
pub fn branch<D: Dim>(si: &D::V, sj: &D::V, l: &D::V) -> D::V {
    let mut ds = *sj - *si;
    min_image::<D>(&mut ds);
    D::mul(ds, *l)
}

/// Nearest periodic image of a reduced separation with components in (−1, 1).
#[inline(always)]
pub fn min_image<D: Dim>(ds: &mut D::V) {
    for a in 0..D::D {
        if ds[a] > 0.5 {
            ds[a] -= 1.0;
        } else if ds[a] < -0.5 {
            ds[a] += 1.0;
        }
    }
}

/// Wraps a reduced position moved by a time step into [0, 1) (grains move far less than a
/// cell per step, so one shift is the common case; `floor` handles the rest).
#[inline(always)]
pub fn wrap_moved<D: Dim>(s: &mut D::V) {
    for a in 0..D::D {
        let mut x = s[a];
        if x >= 1.0 {
            x -= 1.0;
        } else if x < 0.0 {
            x += 1.0;
        }
        if !(0.0..1.0).contains(&x) {
            x -= x.floor();
            if x >= 1.0 {
                x = 0.0;
            }
        }
        s[a] = x;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{D2, D3};
    use nalgebra::{Vector2, Vector3};
    use rand::{Rng, SeedableRng};

    fn brute<D: Dim>(s: &[D::V], radius: &[f64], l: &D::V, cut: f64) -> Vec<(u32, u32)> {
        let mut v = Vec::new();
        for i in 0..s.len() {
            for j in i + 1..s.len() {
                let r = branch::<D>(&s[i], &s[j], l);
                let c = radius[i] + radius[j] + cut;
                if r.norm_squared() < c * c {
                    v.push((i as u32, j as u32));
                }
            }
        }
        v
    }

    fn pairs<H: Copy + Default + Send + Sync>(nl: &NeighborList<H>) -> Vec<(u32, u32)> {
        let mut v = Vec::new();
        for i in 0..nl.row_start.len() - 1 {
            for k in nl.row(i) {
                v.push((i as u32, nl.partner[k]));
            }
        }
        v
    }

    #[test]
    fn morton_order_is_a_permutation_along_the_curve() {
        let s = vec![
            Vector2::new(0.9, 0.9),
            Vector2::new(0.1, 0.1),
            Vector2::new(0.9, 0.1),
            Vector2::new(0.1, 0.9),
        ];
        assert_eq!(morton_order::<D2>(&s), vec![1, 2, 3, 0]);
        let s3 = vec![Vector3::new(0.7, 0.2, 0.6), Vector3::new(0.2, 0.7, 0.1)];
        assert_eq!(morton_order::<D3>(&s3), vec![1, 0]);
        assert_eq!(spread3(0b111), 0b1001001);
    }

    #[test]
    fn cell_list_matches_all_pairs_3d() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let n = 700;
        let s: Vec<Vector3<f64>> = (0..n)
            .map(|_| Vector3::new(rng.gen(), rng.gen(), rng.gen()))
            .collect();
        let radius: Vec<f64> = (0..n).map(|_| rng.gen_range(0.25..0.5)).collect();
        let l = Vector3::new(9.0, 7.5, 8.2);
        let mut nl = NeighborList::<f64>::new(0.1);
        nl.build::<D3>(&s, &radius, &l, 0.0);
        assert_eq!(pairs(&nl), brute::<D3>(&s, &radius, &l, 0.1));
        // Transposed index covers every pair once.
        let mut seen = vec![0; nl.pairs()];
        for j in 0..n {
            for k in nl.col_start[j]..nl.col_start[j + 1] {
                let p = nl.col_pair[k as usize] as usize;
                assert_eq!(nl.partner[p] as usize, j);
                seen[p] += 1;
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
    }

    #[test]
    fn cell_list_matches_all_pairs_2d_and_keeps_history() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let n = 500;
        let s: Vec<Vector2<f64>> = (0..n).map(|_| Vector2::new(rng.gen(), rng.gen())).collect();
        let radius: Vec<f64> = (0..n).map(|_| rng.gen_range(0.25..0.5)).collect();
        let l = Vector2::new(14.0, 11.0);
        let mut nl = NeighborList::<f64>::new(0.2);
        nl.build::<D2>(&s, &radius, &l, 0.01);
        assert_eq!(pairs(&nl), brute::<D2>(&s, &radius, &l, 0.21));
        // Tag each pair's history, rebuild with a slightly smaller skin: kept pairs keep it.
        for i in 0..n {
            for k in nl.row(i) {
                nl.history[k] = (i * 10000 + nl.partner[k] as usize) as f64;
            }
        }
        nl.skin = 0.1;
        nl.build::<D2>(&s, &radius, &l, 0.01);
        for i in 0..n {
            for k in nl.row(i) {
                assert_eq!(nl.history[k], (i * 10000 + nl.partner[k] as usize) as f64);
            }
        }
    }
}
