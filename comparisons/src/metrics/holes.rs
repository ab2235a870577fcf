//! Holes of a 2D packing (GRC07 §V.B–C): the connected sets of empty mesh nodes, each with its
//! equivalent radius R_H (GRC07 (29)), and their mass-weighted mean ⟨R⟩_w (GRC07 (30)).

use super::density_field::Mesh;
use serde::Serialize;

/// Holes of one mesh.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Holes {
    /// Connected sets of empty nodes (4-neighbour connectivity, periodic).
    pub count: usize,
    /// Some hole connects to its own periodic image: the empty space percolates (GRC07 §V.C
    /// restricts ⟨R⟩_w to P* > 0 for this reason).
    pub percolating: bool,
    /// GRC07 (30), ⟨R⟩_w = Σ N_H R_H / Σ N_H; `None` when the empty space percolates.
    pub weighted_radius: Option<f64>,
    /// Distribution of R_H: shells of five per decade, holes and nodes in each (non-empty
    /// shells only; percolating holes left out).
    pub distribution: Vec<HoleShell>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HoleShell {
    pub r_min: f64,
    pub r_max: f64,
    pub holes: usize,
    pub nodes: usize,
}

/// Labels the holes of `mesh` by breadth-first search, tracking how many times each node has
/// been reached across the cell boundary, so that a hole reaching a node twice with different
/// windings wraps the cell.
pub fn holes(mesh: &Mesh) -> Holes {
    let (nx, ny) = (mesh.nx as i64, mesh.ny as i64);
    let n = mesh.solid.len();
    const UNSEEN: u32 = u32::MAX;
    let mut label = vec![UNSEEN; n];
    let mut winding = vec![[0i32; 2]; n];
    let mut queue: Vec<usize> = Vec::new();
    let mut found: Vec<(usize, f64)> = Vec::new();
    let mut percolating = false;
    let mut count = 0usize;
    for start in 0..n {
        if mesh.solid[start] || label[start] != UNSEEN {
            continue;
        }
        let id = count as u32;
        count += 1;
        label[start] = id;
        winding[start] = [0, 0];
        queue.clear();
        queue.push(start);
        let mut head = 0;
        let mut wraps = false;
        let (mut sx, mut sy, mut sxx) = (0.0f64, 0.0f64, 0.0f64);
        while head < queue.len() {
            let p = queue[head];
            head += 1;
            let (i, j) = ((p as i64) % nx, (p as i64) / nx);
            let w = winding[p];
            let (x, y) = (
                (i + w[0] as i64 * nx) as f64 * mesh.dx,
                (j + w[1] as i64 * ny) as f64 * mesh.dy,
            );
            sx += x;
            sy += y;
            sxx += x * x + y * y;
            for (di, dj) in [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)] {
                let (qi, wx) = wrap(i + di, nx);
                let (qj, wy) = wrap(j + dj, ny);
                let qw = [w[0] + wx, w[1] + wy];
                let q = (qj * nx + qi) as usize;
                if mesh.solid[q] {
                    continue;
                }
                if label[q] == UNSEEN {
                    label[q] = id;
                    winding[q] = qw;
                    queue.push(q);
                } else if winding[q] != qw {
                    wraps = true;
                }
            }
        }
        if wraps {
            percolating = true;
            continue;
        }
        let m = queue.len() as f64;
        // GRC07 (29): R_H² = (2/N_H) Σ |r_i − r_c|².
        let r2 = 2.0 * (sxx / m - (sx * sx + sy * sy) / (m * m));
        found.push((queue.len(), r2.max(0.0).sqrt()));
    }
    let total: usize = found.iter().map(|h| h.0).sum();
    let weighted_radius = (!percolating && total > 0)
        .then(|| found.iter().map(|&(m, r)| m as f64 * r).sum::<f64>() / total as f64);
    Holes {
        count,
        percolating,
        weighted_radius,
        distribution: shells(&found),
    }
}

/// Index `i` brought into 0..n, and the winding that took (−1, 0 or +1: one step at most).
fn wrap(i: i64, n: i64) -> (i64, i32) {
    if i < 0 {
        (i + n, -1)
    } else if i >= n {
        (i - n, 1)
    } else {
        (i, 0)
    }
}

fn shells(found: &[(usize, f64)]) -> Vec<HoleShell> {
    let per_decade = 5.0;
    let mut bins: std::collections::BTreeMap<i64, (usize, usize)> = Default::default();
    for &(m, r) in found.iter().filter(|h| h.1 > 0.0) {
        let b = (r.log10() * per_decade).floor() as i64;
        let e = bins.entry(b).or_default();
        e.0 += 1;
        e.1 += m;
    }
    bins.into_iter()
        .map(|(b, (holes, nodes))| HoleShell {
            r_min: 10f64.powf(b as f64 / per_decade),
            r_max: 10f64.powf((b + 1) as f64 / per_decade),
            holes,
            nodes,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(nx: usize, ny: usize, h: f64, empty: impl Fn(f64, f64) -> bool) -> Mesh {
        let solid = (0..nx * ny)
            .map(|p| !empty((p % nx) as f64 * h, (p / nx) as f64 * h))
            .collect();
        Mesh {
            nx,
            ny,
            dx: h,
            dy: h,
            solid,
        }
    }

    /// A circular hole of radius R: R_H = R (GRC07 (29) is the radius of the disk with the
    /// same radius of gyration); one across the cell boundary is measured whole.
    #[test]
    fn a_round_hole_has_its_radius() {
        for centre in [(10.0, 10.0), (0.5, 19.7)] {
            let m = mesh(400, 400, 0.05, |x, y| {
                let dx = (x - centre.0 + 10.0).rem_euclid(20.0) - 10.0;
                let dy = (y - centre.1 + 10.0).rem_euclid(20.0) - 10.0;
                dx * dx + dy * dy < 9.0
            });
            let h = holes(&m);
            assert_eq!(h.count, 1);
            assert!(!h.percolating);
            let r = h.weighted_radius.unwrap();
            assert!((r - 3.0).abs() < 0.02, "{r}");
        }
    }

    /// ⟨R⟩_w weighs each hole by its nodes (GRC07 (30)): radii 1 and 3 give
    /// (1²·1 + 3²·3)/(1² + 3²) = 2.8.
    #[test]
    fn the_mean_is_weighted_by_area() {
        let m = mesh(600, 300, 0.05, |x, y| {
            let a = (x - 5.0).powi(2) + (y - 7.0).powi(2) < 1.0;
            let b = (x - 18.0).powi(2) + (y - 7.0).powi(2) < 9.0;
            a || b
        });
        let h = holes(&m);
        assert_eq!(h.count, 2);
        let r = h.weighted_radius.unwrap();
        assert!((r - 2.8).abs() < 0.03, "{r}");
        assert_eq!(h.distribution.iter().map(|s| s.holes).sum::<usize>(), 2);
    }

    /// An empty channel along x wraps the cell: percolating, no ⟨R⟩_w.
    #[test]
    fn a_channel_percolates() {
        let m = mesh(200, 200, 0.1, |_, y| (y - 10.0).abs() < 1.0);
        let h = holes(&m);
        assert!(h.percolating);
        assert_eq!(h.weighted_radius, None);
    }
}
