//! Rattlers fixed onto the backbone: variant II of AR07 §III.C (T.I, T.V, Figs. 6, 9–12,
//! eq. (36)).
//!
//! AR07: "we regard each backbone grain as a fixed object, exert small isotropically
//! distributed random forces on all rattlers and let them move to a final equilibrium
//! position (assuming frictionless contacts)", each rattler ending with d contacts with the
//! backbone or previously fixed rattlers. Here:
//!
//! * every rattler g gets a constant force `f u_g`, `u_g` a unit vector drawn isotropically
//!   from a seeded generator (the same seed gives the same directions, whatever the other
//!   grains);
//! * backbone grains do not move; rattlers descend the energy
//!   `U = Σ_pairs ½ k δ² − Σ_rattlers f u_g·r_g`, δ the overlap of a pair involving a rattler
//!   (frictionless repulsion): block Gauss–Seidel sweeps of damped Newton steps on each
//!   rattler (regularised so that a rattler on fewer than d contacts rolls on), a capped
//!   step, and a long free step while out of contact;
//! * the repulsion is stiffened in stages, `f/k = 1e-2 a … 1e-5 a`, so the final overlaps are
//!   ~1e-5 a: the rigid-grain limit, up to that resolution;
//! * a rattler is settled when the net force on it is below `1e-3 f` with at least d
//!   contacts (a frictionless sphere pushed by a generic constant force rests on d contacts;
//!   fewer is a saddle that the descent leaves).
//!
//! Contacts of variant II ("geometric", AR07 T.V) are then the pairs that overlap or touch
//! (`h ≤ 0`) once the rattlers are fixed, together with the counted backbone contacts of
//! variant I (which keeps the distant attractions of cohesive packings). With this,
//! z^II(0) ≈ z + 6x0 − 2N_rr/n (AR07 (36)) when each rattler rests on 3 contacts.

use super::neighbors::{for_each_pair, norm2, points, separation, valid_cell, CellGrid, Point};
use super::rattlers::contact_number_fractions;
use serde::Serialize;
use std::collections::HashSet;

/// Seed of the random force directions used by [`crate::analyze`].
pub const DEFAULT_SEED: u64 = 0x05ee_da07;

/// Stages of the repulsion: the force-to-stiffness ratio f/k, in units of a.
const STAGES: [f64; 4] = [1e-2, 1e-3, 1e-4, 1e-5];
/// A rattler is in equilibrium when the net force is below this fraction of f.
const TOLERANCE: f64 = 1e-3;
/// Verlet skin, in a.
const SKIN: f64 = 0.3;
/// Regularisation λ = ROLL·k·c of the Newton steps (see [`relax_rattlers`]).
const ROLL: f64 = 0.02;
/// Damping of the Newton steps.
const OMEGA: f64 = 0.9;
/// A rattler that has travelled this far (in a) without coming to rest is in no cage (a
/// gas, a cell stretched far beyond its grains): it is left where it is, unsettled, rather
/// than falling through empty space for the whole step budget (found by tests/fuzz.rs).
/// Caged rattlers move less than one diameter.
const MAX_TRAVEL: f64 = 10.0;

/// Solves `m x = b` for the symmetric positive definite leading `d × d` block (d = 2, 3).
fn solve_spd(m: &[[f64; 3]; 3], b: &[f64; 3], d: usize) -> [f64; 3] {
    if d == 2 {
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        return [
            (b[0] * m[1][1] - b[1] * m[0][1]) / det,
            (m[0][0] * b[1] - m[1][0] * b[0]) / det,
            0.0,
        ];
    }
    let det3 = |a: [[f64; 3]; 3]| {
        a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
    };
    let det = det3(*m);
    let mut x = [0.0; 3];
    for (c, xc) in x.iter_mut().enumerate() {
        let mut a = *m;
        for r in 0..3 {
            a[r][c] = b[r];
        }
        *xc = det3(a) / det;
    }
    x
}

/// Outcome of the relaxation.
#[derive(Clone, Debug, PartialEq)]
pub struct Relaxed {
    /// All grain centres, rattlers moved (not wrapped into the cell).
    pub position: Vec<[f64; 3]>,
    /// Rattlers that did not reach equilibrium with at least d contacts.
    pub unsettled: usize,
    /// Descent steps taken, all stages together.
    pub steps: usize,
}

/// Summary of variant II for [`crate::Analysis`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FixedRattlers {
    /// x_k^II, k = 0, 1, …: fraction of all grains with k geometric contacts (AR07 T.I, T.V,
    /// II). At least [`X_K_MIN_LEN`](super::rattlers::X_K_MIN_LEN) entries.
    pub x_k: Vec<f64>,
    /// z^II(0) = 2 × contacts / n, the geometric coordination number.
    pub z_geometric: f64,
    /// Rattlers moved.
    pub rattlers: usize,
    /// Contacts involving a rattler once fixed, and those between two rattlers (N_rr).
    pub rattler_contacts: usize,
    pub rattler_rattler_contacts: usize,
    /// Rattlers left out of equilibrium (should be 0; non-zero if some rattler was not
    /// caged).
    pub unsettled: usize,
    pub steps: usize,
    /// Seed of the force directions.
    pub seed: u64,
}

/// SplitMix64.
fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Isotropically distributed unit vector in `d` dimensions for grain `g` (normalised
/// Gaussian vector), from `seed` and `g` only.
pub fn random_direction(d: usize, seed: u64, g: usize) -> [f64; 3] {
    let mut s = seed ^ (g as u64).wrapping_mul(0xd605_bbb5_8c8a_bd9b);
    loop {
        let mut v = [0.0; 3];
        for x in v.iter_mut().take(d.min(3)) {
            // Box–Muller, one normal deviate per pair of uniforms.
            let u1 = ((splitmix(&mut s) >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
            let u2 = (splitmix(&mut s) >> 11) as f64 / (1u64 << 53) as f64;
            *x = (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos();
        }
        let len = norm2(&v).sqrt();
        if len > 1e-6 {
            return v.map(|x| x / len);
        }
    }
}

/// Moves the rattlers (`is_rattler`) under the constant forces of directions `direction[g]`
/// (unit vectors, any magnitude works: only directions matter) until each rests in
/// frictionless equilibrium on fixed grains and other rattlers; see the module
/// documentation. `max_steps` bounds each stage. `None` for a bad cell, no grain, zero radii,
/// or no fixed grain.
pub fn relax_rattlers(
    lengths: &[f64],
    position: &[impl std::ops::Deref<Target = [f64]>],
    radius: &[f64],
    is_rattler: &[bool],
    direction: &[[f64; 3]],
    max_steps: usize,
) -> Option<Relaxed> {
    let n = position.len();
    let d = lengths.len();
    if !valid_cell(lengths) || n == 0 || radius.len() != n || is_rattler.len() != n {
        return None;
    }
    if direction.len() != n || is_rattler.iter().all(|&r| r) {
        return None;
    }
    let r_max = radius.iter().copied().fold(0.0, f64::max);
    let a = 2.0 * r_max;
    if !(a > 0.0 && a.is_finite()) {
        return None;
    }
    let mut pts = points(d, position);
    let rattlers: Vec<usize> = (0..n).filter(|&g| is_rattler[g]).collect();
    if rattlers.is_empty() {
        return Some(Relaxed {
            position: pts,
            unsettled: 0,
            steps: 0,
        });
    }
    let mut slot = vec![usize::MAX; n];
    for (s, &g) in rattlers.iter().enumerate() {
        slot[g] = s;
    }
    let nr = rattlers.len();
    let skin = SKIN * a;
    let cap = skin / 8.0;
    let reach = 2.0 * r_max + skin;
    let fixed: Vec<usize> = (0..n).filter(|&g| !is_rattler[g]).collect();
    let fixed_pts: Vec<Point> = fixed.iter().map(|&g| pts[g]).collect();
    let fixed_grid = CellGrid::new(lengths, &fixed_pts, reach);
    let mut nbr: Vec<Vec<usize>> = vec![Vec::new(); nr];
    let mut built: Vec<Point> = Vec::new();
    let mut need_build = true;
    let mut moved_max: f64 = 0.0;
    let f = 1.0;
    let mut steps = 0;
    let mut settled = vec![false; nr];
    let start: Vec<Point> = rattlers.iter().map(|&g| pts[g]).collect();
    let mut lost = vec![false; nr];

    for &delta in &STAGES {
        let k = f / (delta * a);
        let gamma = 0.2 / k;
        let mut awake: Vec<usize> = (0..nr).collect();
        let mut queued = vec![false; nr];
        settled.iter_mut().for_each(|s| *s = false);
        for _ in 0..max_steps {
            if need_build {
                // Neighbours of each rattler: fixed grains from the static grid, rattlers
                // from a grid of the rattlers alone, so a rebuild costs O(rattlers).
                let rpts: Vec<Point> = rattlers.iter().map(|&g| pts[g]).collect();
                let rgrid = CellGrid::new(lengths, &rpts, reach);
                for (s, list) in nbr.iter_mut().enumerate() {
                    list.clear();
                    let g = rattlers[s];
                    let mut keep = |h: usize, r2: f64| {
                        if h != g && r2.sqrt() < radius[g] + radius[h] + skin {
                            list.push(h);
                        }
                    };
                    if let Some(fg) = &fixed_grid {
                        fg.query(&pts[g], |k, _, r2| keep(fixed[k], r2));
                    }
                    if let Some(rg) = &rgrid {
                        rg.query(&pts[g], |k, _, r2| keep(rattlers[k], r2));
                    }
                }
                built = rpts;
                moved_max = 0.0;
                need_build = false;
            }
            // One block Gauss–Seidel sweep over the awake rattlers (the others have not moved,
            // nor their neighbours): each takes a damped Newton step
            // Δ = ω (H + λ)⁻¹ F on its own position, H = k Σ n nᵀ over its contacts,
            // λ = ROLL·k·c so that a rattler on fewer than d contacts can roll. Block
            // Gauss–Seidel converges on the coupled (positive definite) problem of touching
            // rattlers. Out of contact, a long step that cannot create an overlap.
            let mut next = Vec::new();
            for &s in &awake {
                let g = rattlers[s];
                if lost[s] {
                    continue;
                }
                let mut fr = direction[g].map(|x| x * f);
                let (mut c, mut gm) = (0usize, skin / 2.0);
                let mut h = [[0.0; 3]; 3];
                for &j in &nbr[s] {
                    let r = separation(lengths, &pts[g], &pts[j]);
                    let dist = norm2(&r).sqrt();
                    let gap = dist - radius[g] - radius[j];
                    if gap < 0.0 && dist > 0.0 {
                        c += 1;
                        let u = r.map(|x| x / dist);
                        for x in 0..3 {
                            fr[x] += k * gap * u[x];
                            for y in 0..3 {
                                h[x][y] += k * u[x] * u[y];
                            }
                        }
                    } else if gap < gm {
                        gm = gap.max(0.0);
                    }
                }
                let fl = norm2(&fr).sqrt();
                settled[s] = fl < TOLERANCE * f && c >= d;
                if settled[s] || !(fl > 0.0 && fl.is_finite()) {
                    continue;
                }
                let mut delta_x = if c == 0 {
                    let step = (gamma * fl).max(0.45 * gm);
                    fr.map(|x| x * step / fl)
                } else {
                    let lambda = ROLL * k * c as f64;
                    for (x, row) in h.iter_mut().enumerate() {
                        row[x] += lambda;
                    }
                    solve_spd(&h, &fr, d).map(|x| OMEGA * x)
                };
                let len = norm2(&delta_x).sqrt();
                if !len.is_finite() {
                    continue;
                }
                if len > cap {
                    delta_x = delta_x.map(|x| x * cap / len);
                }
                for x in 0..d {
                    pts[g][x] += delta_x[x];
                }
                let travel: Point = std::array::from_fn(|x| pts[g][x] - start[s][x]);
                if norm2(&travel) > (MAX_TRAVEL * a).powi(2) {
                    lost[s] = true;
                }
                moved_max = moved_max.max(norm2(&separation(lengths, &built[s], &pts[g])));
                for t in std::iter::once(s).chain(nbr[s].iter().map(|&j| slot[j])) {
                    if t != usize::MAX && !queued[t] {
                        queued[t] = true;
                        next.push(t);
                    }
                }
            }
            steps += 1;
            if next.is_empty() {
                break;
            }
            next.iter().for_each(|&t| queued[t] = false);
            awake = next;
            if moved_max.sqrt() > skin / 4.0 {
                need_build = true;
            }
        }
    }
    Some(Relaxed {
        position: pts,
        unsettled: settled.iter().filter(|&&s| !s).count(),
        steps,
    })
}

/// Geometric contact numbers after fixing the rattlers: pairs with `h ≤ 0` in `position`
/// plus the `counted` pairs (variant I backbone contacts), each pair once. Returns the
/// number of contacts of each grain and the list of pairs.
pub fn geometric_contacts(
    lengths: &[f64],
    position: &[[f64; 3]],
    radius: &[f64],
    counted: &[(usize, usize)],
) -> (Vec<usize>, Vec<(usize, usize)>) {
    let n = position.len();
    let key = |i: usize, j: usize| (i.min(j), i.max(j));
    let mut set: HashSet<(usize, usize)> = counted
        .iter()
        .filter(|(i, j)| *i < n && *j < n && i != j)
        .map(|&(i, j)| key(i, j))
        .collect();
    let r_max = radius.iter().copied().fold(0.0, f64::max);
    for_each_pair(
        lengths,
        position,
        2.0 * r_max * (1.0 + 1e-9),
        |i, j, _, r2| {
            if r2.sqrt() - radius[i] - radius[j] <= 0.0 {
                set.insert(key(i, j));
            }
        },
    );
    let mut pairs: Vec<(usize, usize)> = set.into_iter().collect();
    pairs.sort_unstable();
    let mut k = vec![0usize; n];
    for &(i, j) in &pairs {
        k[i] += 1;
        k[j] += 1;
    }
    (k, pairs)
}

/// Variant II of x_k (AR07 T.I, T.V): rattlers fixed by [`relax_rattlers`] with directions
/// from `seed`, then [`geometric_contacts`] with the variant-I `counted` backbone pairs.
/// Returns the summary and the relaxed configuration. `None` if there is no backbone grain
/// (nothing to fix the rattlers onto) or for a bad cell.
pub fn fix_rattlers(
    lengths: &[f64],
    position: &[impl std::ops::Deref<Target = [f64]>],
    radius: &[f64],
    is_rattler: &[bool],
    counted: &[(usize, usize)],
    seed: u64,
) -> Option<(FixedRattlers, Relaxed)> {
    let n = position.len();
    let d = lengths.len();
    let dirs: Vec<[f64; 3]> = (0..n).map(|g| random_direction(d, seed, g)).collect();
    let relaxed = relax_rattlers(lengths, position, radius, is_rattler, &dirs, 100_000)?;
    let (k, pairs) = geometric_contacts(lengths, &relaxed.position, radius, counted);
    let x_k = contact_number_fractions(&k);
    let rat = |g: usize| is_rattler[g];
    let summary = FixedRattlers {
        x_k,
        z_geometric: 2.0 * pairs.len() as f64 / n as f64,
        rattlers: (0..n).filter(|&g| rat(g)).count(),
        rattler_contacts: pairs.iter().filter(|(i, j)| rat(*i) || rat(*j)).count(),
        rattler_rattler_contacts: pairs.iter().filter(|(i, j)| rat(*i) && rat(*j)).count(),
        unsettled: relaxed.unsettled,
        steps: relaxed.steps,
        seed,
    };
    Some((summary, relaxed))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::fixtures::{lattice, Lcg};

    /// Solves `A λ = b` (d × d, columns `cols`) by Gaussian elimination with pivoting.
    fn solve(cols: &[[f64; 3]], b: [f64; 3], d: usize) -> Vec<f64> {
        let mut m: Vec<Vec<f64>> = (0..d)
            .map(|r| {
                let mut row: Vec<f64> = cols.iter().map(|c| c[r]).collect();
                row.push(b[r]);
                row
            })
            .collect();
        for c in 0..d {
            let p = (c..d)
                .max_by(|&x, &y| m[x][c].abs().total_cmp(&m[y][c].abs()))
                .unwrap();
            m.swap(c, p);
            let pivot = m[c].clone();
            for (r, row) in m.iter_mut().enumerate() {
                if r != c {
                    let q = row[c] / pivot[c];
                    row.iter_mut()
                        .zip(&pivot)
                        .skip(c)
                        .for_each(|(x, p)| *x -= q * p);
                }
            }
        }
        (0..d).map(|r| m[r][d] / m[r][r]).collect()
    }

    /// Perturbed periodic lattice (square or cubic, spacing 1, diameter 1) with every lattice
    /// bond listed, plus one small rattler at the centre of the cell at the origin.
    type Caged = (Vec<f64>, Vec<f64>, Vec<Vec<f64>>, Vec<(usize, usize)>);

    fn caged(d: usize, seed: u64) -> Caged {
        let (l, mut r, mut p, b) = lattice(d, 4, 1.0, 0.5, 1.0);
        let mut rng = Lcg(seed);
        for q in p.iter_mut() {
            q.iter_mut().for_each(|x| *x += 0.03 * (rng.next() - 0.5));
        }
        r.push(if d == 3 { 0.3 } else { 0.15 });
        p.push(vec![0.5; d]);
        (l, r, p, b.iter().map(|b| (b.i, b.j)).collect())
    }

    /// One rattler in a cage of fixed grains (perturbed, so that no symmetric pocket holds
    /// it on more than d contacts): it ends in frictionless equilibrium on exactly d = 3
    /// contacts in 3D, 2 in 2D, with the force direction inside the cone of its contact
    /// directions, overlaps ~1e-5 a; x_k^II moves it from x0 to x_d and d cage grains up by one.
    #[test]
    fn caged_rattler_rests_on_d_contacts() {
        for d in [2, 3] {
            for seed in 0..8u64 {
                let (l, r, p, counted) = caged(d, 100 + seed);
                let n = r.len();
                let g = n - 1;
                let mut is_r = vec![false; n];
                is_r[g] = true;
                let dirs: Vec<[f64; 3]> = (0..n).map(|h| random_direction(d, seed, h)).collect();
                let relaxed = relax_rattlers(&l, &p, &r, &is_r, &dirs, 20_000).unwrap();
                assert_eq!(relaxed.unsettled, 0, "d = {d}, seed {seed}");
                // Backbone untouched.
                for (moved, given) in relaxed.position.iter().zip(&p).take(g) {
                    assert_eq!(moved[..d], given[..]);
                }
                let pos = &relaxed.position;
                let mut normals = Vec::new();
                for h in 0..g {
                    let v = separation(&l, &pos[g], &pos[h]);
                    let dist = norm2(&v).sqrt();
                    let gap = dist - r[g] - r[h];
                    assert!(gap > -5e-5, "overlap {gap}");
                    if gap <= 0.0 {
                        normals.push(v.map(|x| x / dist));
                    }
                }
                assert_eq!(normals.len(), d, "d = {d}, seed {seed}");
                let lambda = solve(&normals, dirs[g], d);
                assert!(lambda.iter().all(|&x| x > 0.0), "{lambda:?}");
                // x_k^II through the public entry point.
                let (fixed, _) = fix_rattlers(&l, &p, &r, &is_r, &counted, seed).unwrap();
                let nf = n as f64;
                assert_eq!(fixed.x_k[0], 0.0, "{fixed:?}");
                assert!((fixed.x_k[d] - 1.0 / nf).abs() < 1e-15);
                assert!((fixed.x_k[2 * d] - (g - d) as f64 / nf).abs() < 1e-15);
                assert!((fixed.x_k[2 * d + 1] - d as f64 / nf).abs() < 1e-15);
                assert_eq!(
                    (fixed.rattler_contacts, fixed.rattler_rattler_contacts),
                    (d, 0)
                );
                let z = 2.0 * counted.len() as f64 / nf;
                assert!((fixed.z_geometric - (z + 2.0 * d as f64 / nf)).abs() < 1e-14);
            }
        }
    }

    /// Two rattlers in one vacancy of a perturbed cubic lattice: both settle, each on at
    /// least 3 contacts, and the pair is isostatic: 6 contacts involve rattlers (3 per
    /// rattler degree of freedom count, shared contacts once).
    /// A rattler pushed away from a one-grain backbone in a cell 1e6 a long: it stops after
    /// `MAX_TRAVEL`, unsettled, instead of falling through the cell for every step of every
    /// stage (tests/fuzz.rs found a 12 s analysis of a stretched YADE cell).
    #[test]
    fn an_uncaged_rattler_is_given_up_after_max_travel() {
        let l = vec![1e6, 1e6];
        let p = vec![vec![0.0, 0.0], vec![2.0, 0.0]];
        let r = vec![0.5, 0.5];
        let dirs = vec![[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]];
        let relaxed = relax_rattlers(&l, &p, &r, &[false, true], &dirs, 1_000_000).unwrap();
        assert_eq!(relaxed.unsettled, 1);
        let x = relaxed.position[1][0] - 2.0;
        assert!(x > MAX_TRAVEL && x < MAX_TRAVEL + 1.0, "{x}");
        assert!(relaxed.steps < 2000, "{}", relaxed.steps);
    }

    #[test]
    fn two_rattlers_in_a_vacancy() {
        for seed in 0..6u64 {
            let (l, mut r, mut p, _) = lattice(3, 4, 1.0, 0.5, 1.0);
            let mut rng = Lcg(7 + seed);
            for q in p.iter_mut() {
                q.iter_mut().for_each(|x| *x += 0.03 * (rng.next() - 0.5));
            }
            // Grain 21 = (1, 1, 1) becomes two small rattlers along the cube diagonal, where
            // the vacancy has room for both (0.62 apart, ≥ 0.85 from the lattice grains).
            let c = p[21].clone();
            let t = 0.31 / 3f64.sqrt();
            r[21] = 0.3;
            p[21] = c.iter().map(|x| x - t).collect();
            r.push(0.3);
            p.push(c.iter().map(|x| x + t).collect());
            let n = r.len();
            let mut is_r = vec![false; n];
            is_r[21] = true;
            is_r[n - 1] = true;
            let (f, _) = fix_rattlers(&l, &p, &r, &is_r, &[], 50 + seed).unwrap();
            assert_eq!(f.unsettled, 0, "seed {seed}");
            assert_eq!(f.rattler_contacts, 6, "seed {seed}: {f:?}");
            assert!(f.rattler_rattler_contacts <= 1);
        }
    }

    #[test]
    fn directions_are_isotropic_unit_vectors_and_reproducible() {
        let mut mean = [0.0; 3];
        let mut zz = 0.0;
        let m = 20_000;
        for g in 0..m {
            let u = random_direction(3, 1, g);
            assert!((norm2(&u) - 1.0).abs() < 1e-12);
            mean.iter_mut()
                .zip(&u)
                .for_each(|(s, x)| *s += x / m as f64);
            zz += u[2] * u[2] / m as f64;
        }
        assert!(mean.iter().all(|x| x.abs() < 0.02), "{mean:?}");
        assert!((zz - 1.0 / 3.0).abs() < 0.01);
        assert_eq!(random_direction(2, 9, 4), random_direction(2, 9, 4));
        assert_eq!(random_direction(2, 9, 4)[2], 0.0);
        assert_ne!(random_direction(3, 9, 4), random_direction(3, 10, 4));
    }

    #[test]
    fn nothing_to_fix_onto() {
        let p = vec![vec![0.5, 0.5], vec![2.0, 2.0]];
        assert!(fix_rattlers(&[4.0, 4.0], &p, &[0.5, 0.5], &[true, true], &[], 1).is_none());
        let e: Vec<Vec<f64>> = Vec::new();
        assert!(fix_rattlers(&[4.0, 4.0], &e, &[], &[], &[], 1).is_none());
        // No rattler: the contacts are the listed ones plus the geometric overlaps.
        let (f, _) =
            fix_rattlers(&[4.0, 4.0], &p, &[0.5, 0.5], &[false, false], &[(0, 1)], 1).unwrap();
        assert_eq!((f.z_geometric, f.x_k[1], f.steps), (1.0, 1.0, 0));
    }
}
