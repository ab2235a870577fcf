//! Event-driven molecular dynamics of hard spheres (3D) or hard disks (2D) with elastic
//! collisions in a fixed orthorhombic periodic box: melting of the FCC lattice (AR07 §III),
//! "mixing" at fixed volume (AR07 §IV.B), and Lubachevsky–Stillinger (LS) growth of the
//! diameters (AR07 §III.A, state A').
//!
//! Algorithm (Alder–Wainwright, Rapaport; Donev–Torquato–Stillinger for growth):
//! - cell list in reduced coordinates, cells at least one (final) maximum diameter wide;
//! - one predicted event per grain (earliest pair collision with the grains of the 3^d
//!   neighbouring cells, periodic images included, or crossing of a cell face), in a binary
//!   heap with lazy invalidation: an entry is stale when its grain was re-predicted since
//!   (prediction counter), a collision is void when the partner's velocity changed since
//!   (trajectory counter) and the grain is then re-predicted;
//! - free flight between events, positions advanced lazily per grain (per-grain time stamp);
//!   O(log n) per event;
//! - box lengths of at least two (final) largest diameters, so that a pair in contact is its
//!   minimum image; pairs in contact that approach more slowly than 1e-11 (relative) are
//!   taken as grazing, which stops roundoff from repeating a collision.
//!
//! Units: whatever the caller uses (lengths of the box and radii, masses, velocities); the
//! time unit follows. Collision counts "per grain" are 2 × (pair collisions) / n: the average
//! number of collisions each grain took part in (AR07 §IV.B, n_coll = 50).

use crate::geometry::{Dim, VectorOps};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Largest relative overlap 1 − |r_ij|/(R_i + R_j) accepted by [`HardSpheres::new`].
pub const OVERLAP_TOL: f64 = 1e-10;
/// LS growth stops with an error ("jammed") when the reduced pressure Z measured over one
/// rescaling interval exceeds this value (mean gaps ~ d·Z⁻¹ ≈ 1e-6 diameters).
pub const JAM_PRESSURE: f64 = 1e6;
/// LS growth stops with an error when it takes more than this many collisions per grain
/// divided by the rate (a safety net behind [`JAM_PRESSURE`]).
pub const MAX_GROWTH_COLLISIONS: f64 = 1e3;
/// Relative tolerance on the approach rate b = r·v − σσ̇ below which a pair is grazing and
/// treated as not approaching: stops repeated collisions of one pair caused by roundoff.
const GRAZE: f64 = 1e-11;
/// During growth, the normal receding velocity after a collision exceeds the growth speed of
/// the contact distance by at least this fraction of it (separation of grazing pairs).
const SEPARATION_MARGIN: f64 = 1e-6;
/// Cells are wider than the largest diameter by this fraction (cell membership roundoff).
const CELL_MARGIN: f64 = 1e-9;
/// `run_collisions` gives up after this many events (cell crossings included) per requested
/// collision, e.g. when no grain moves towards any other.
const MAX_EVENTS_PER_COLLISION: u64 = 1000;
const NONE: u32 = u32::MAX;

/// Hard grains (spheres for [`D3`](crate::geometry::D3), disks for
/// [`D2`](crate::geometry::D2)) in an orthorhombic periodic box, moving freely between
/// elastic collisions. Fields are public: between calls they may be changed freely (e.g.
/// velocities set to zero, lengths scaled), as long as no two grains overlap.
#[derive(Clone, Debug)]
pub struct HardSpheres<D: Dim> {
    /// Box lengths.
    pub l: D::V,
    /// Reduced positions in [0,1)^d; the absolute position is `D::mul(l, s)`.
    pub s: Vec<D::V>,
    /// Absolute velocities.
    pub vel: Vec<D::V>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    /// Elapsed time, summed over the runs.
    pub time: f64,
    /// Pair collisions, summed over the runs.
    pub collisions: u64,
}

/// What one run did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Pair collisions.
    pub collisions: u64,
    /// 2 × collisions / n.
    pub collisions_per_grain: f64,
    pub cell_crossings: u64,
    /// Duration.
    pub time: f64,
    /// Compressibility factor Z = PV/(NkT) = 1 + Σ_c J_c |r_c| / ∫ Σ_i m_i v_i² dt (collision
    /// virial, impulses J_c exchanged at distance |r_c|; NkT = ⟨Σ m v²⟩/d). NaN if no time
    /// elapsed. During growth the impulses include the growth part (indicative only).
    pub z: f64,
    /// kT = Σ m v² / (d n) at the end.
    pub temperature: f64,
    /// Packing fraction at the end.
    pub packing_fraction: f64,
    /// Kinetic energy rescalings (LS growth).
    pub rescalings: u64,
}

impl<D: Dim> HardSpheres<D> {
    /// Checks and builds the system; reduced positions are wrapped into [0,1). Errors if the
    /// lengths differ, if a radius, mass, length or coordinate is not positive / finite, if a
    /// box length is below two largest diameters, or if two grains overlap (naming the pair
    /// and the overlap).
    pub fn new(
        l: D::V,
        s: Vec<D::V>,
        radius: Vec<f64>,
        mass: Vec<f64>,
        vel: Vec<D::V>,
    ) -> Result<Self, String> {
        let n = s.len();
        if radius.len() != n || mass.len() != n || vel.len() != n {
            return Err(format!(
                "hard spheres: {n} positions but {} radii, {} masses, {} velocities",
                radius.len(),
                mass.len(),
                vel.len()
            ));
        }
        if (0..D::D).any(|a| !(l[a] > 0.0 && l[a].is_finite())) {
            return Err(format!(
                "hard spheres: box lengths {:?} must be positive",
                l
            ));
        }
        for i in 0..n {
            let positive = |x: f64| x > 0.0 && x.is_finite();
            if !(positive(radius[i]) && positive(mass[i])) {
                return Err(format!(
                    "hard spheres: grain {i} has radius {} and mass {} (both must be positive)",
                    radius[i], mass[i]
                ));
            }
            if !s[i].is_finite() || !vel[i].is_finite() {
                return Err(format!(
                    "hard spheres: grain {i} has a non-finite position or velocity"
                ));
            }
        }
        let mut hs = HardSpheres {
            l,
            s,
            vel,
            radius,
            mass,
            time: 0.0,
            collisions: 0,
        };
        hs.check_box(hs.max_diameter())?;
        for x in hs.s.iter_mut() {
            wrap_floor::<D>(x);
        }
        if let Some((i, j, overlap)) = hs.max_overlap() {
            if overlap > OVERLAP_TOL {
                return Err(format!(
                    "hard spheres: grains {i} and {j} overlap by {overlap:.3e} of their contact distance {:.6} (tolerance {OVERLAP_TOL:e})",
                    hs.radius[i] + hs.radius[j]
                ));
            }
        }
        Ok(hs)
    }

    pub fn len(&self) -> usize {
        self.s.len()
    }

    pub fn is_empty(&self) -> bool {
        self.s.is_empty()
    }

    /// Solid volume (area in 2D) over box volume.
    pub fn packing_fraction(&self) -> f64 {
        let solid: f64 = self.radius.iter().map(|&r| D::grain_volume(2.0 * r)).sum();
        solid / D::product(self.l)
    }

    /// Σ ½ m v².
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.mv2()
    }

    /// Σ m v.
    pub fn momentum(&self) -> D::V {
        let mut p = D::V::zero();
        for (v, &m) in self.vel.iter().zip(&self.mass) {
            p += *v * m;
        }
        p
    }

    /// kT = Σ m v² / (d n).
    pub fn temperature(&self) -> f64 {
        self.mv2() / (D::D * self.len().max(1)) as f64
    }

    /// Maxwell velocities of root-mean-square speed `rms`, zero total momentum
    /// ([`crate::init::maxwell_velocities`]).
    pub fn set_maxwell_velocities(&mut self, rms: f64, seed: u64) {
        self.vel = crate::init::maxwell_velocities::<D>(&self.mass, rms, seed);
    }

    /// Multiplies box lengths and radii by `factor` (reduced positions unchanged), e.g. to
    /// bring the largest diameter back to the length unit after growth.
    pub fn scale_lengths(&mut self, factor: f64) {
        self.l = self.l * factor;
        for r in self.radius.iter_mut() {
            *r *= factor;
        }
    }

    /// The pair (i, j) with the largest relative overlap 1 − |r_ij|/(R_i + R_j) (minimum
    /// image), negative if no pair overlaps; `None` for fewer than two grains. Uses a cell
    /// grid; assumes box lengths of at least two largest diameters.
    pub fn max_overlap(&self) -> Option<(usize, usize, f64)> {
        if self.len() < 2 {
            return None;
        }
        let mut s = self.s.clone();
        for x in s.iter_mut() {
            wrap_floor::<D>(x);
        }
        let grid = Grid::<D>::new(self.l, self.max_diameter() * (1.0 + CELL_MARGIN), &s);
        let mut worst: Option<(usize, usize, f64)> = None;
        for i in 0..self.len() {
            grid.for_neighbours(i, |j, shift| {
                if j > i {
                    let dr = D::mul(s[j] + shift - s[i], self.l);
                    let sigma = self.radius[i] + self.radius[j];
                    let overlap = 1.0 - dr.norm() / sigma;
                    let better = match worst {
                        None => true,
                        Some((_, _, w)) => overlap > w,
                    };
                    if better {
                        worst = Some((i, j, overlap));
                    }
                }
            });
        }
        worst
    }

    /// Runs until ⌈collisions_per_grain · n / 2⌉ more pair collisions (each grain takes part,
    /// on average, in `collisions_per_grain` collisions; AR07 §IV.B), or until no grain moves
    /// or 1000 events per requested collision have passed. Energy and momentum are conserved.
    ///
    /// Panics if a box length is below two largest diameters.
    pub fn run_collisions(&mut self, collisions_per_grain: f64) -> Stats {
        let n = self.len();
        let target = (collisions_per_grain * n as f64 / 2.0).ceil().max(0.0) as u64;
        if n < 2 || target == 0 {
            return self.stats(&Engine::<D>::empty(), 0.0);
        }
        let width = self.checked_width(self.max_diameter());
        let mut eng = Engine::new(self, width, 0.0);
        let max_events = MAX_EVENTS_PER_COLLISION.saturating_mul(target + n as u64);
        eng.run(self, f64::INFINITY, target, max_events);
        let t = eng.t;
        self.finish(&mut eng, t)
    }

    /// Runs for a time `t` (elastic collisions), returns the statistics, with the collisional
    /// pressure Z over the run.
    ///
    /// Panics if a box length is below two largest diameters.
    pub fn run_time(&mut self, t: f64) -> Stats {
        if self.len() < 2 || t <= 0.0 {
            return self.stats(&Engine::<D>::empty(), 0.0);
        }
        let width = self.checked_width(self.max_diameter());
        let mut eng = Engine::new(self, width, 0.0);
        eng.run(self, t, u64::MAX, u64::MAX);
        self.finish(&mut eng, t)
    }

    /// Lubachevsky–Stillinger growth (AR07 §III.A): every diameter grows in proportion,
    /// d_i(t) = d_i(0)(1 + g t), box fixed, until the packing fraction is exactly `target`.
    /// `rate` is the growth speed of the largest diameter over the quadratic mean velocity
    /// at the start, rate = ḋ_max / √⟨v²⟩ (AR07: 1e-2; DTS: 1e-4).
    ///
    /// Collisions: in the frame of the growing surfaces the normal velocity is reflected,
    /// u' = 2σ̇ − u (σ̇ = contact distance growth speed), so the pair separates even though both
    /// grow; this raises the kinetic energy, which is rescaled to its initial value after every
    /// n collisions and at the end (so the rate stays `rate` in units of the current
    /// quadratic mean velocity). Momentum is conserved. On success radii are the grown ones,
    /// positions and velocities are those at the end.
    ///
    /// Errors, leaving the system at the point reached (valid, no overlaps), if the packing
    /// jams first (reduced pressure over one rescaling interval above [`JAM_PRESSURE`], or
    /// more than [`MAX_GROWTH_COLLISIONS`]/rate collisions per grain), if no grain moves, if
    /// `target` is below the current packing fraction, or if the box is shorter than two final
    /// diameters.
    pub fn grow(&mut self, target: f64, rate: f64) -> Result<Stats, String> {
        let n = self.len();
        let phi0 = self.packing_fraction();
        if !(target.is_finite() && target > 0.0 && rate.is_finite() && rate > 0.0) {
            return Err(format!(
                "LS growth: target {target} and rate {rate} must be positive"
            ));
        }
        if target <= phi0 {
            if target < phi0 * (1.0 - 1e-12) {
                return Err(format!(
                    "LS growth: target Φ = {target} is below the current Φ = {phi0}"
                ));
            }
            return Ok(self.stats(&Engine::<D>::empty(), 0.0));
        }
        let mv2_0 = self.mv2();
        let v_rms = (self.vel.iter().map(|v| v.norm_squared()).sum::<f64>() / n as f64).sqrt();
        if v_rms.is_nan() || v_rms <= 0.0 {
            return Err("LS growth: all grains are at rest; set velocities first".into());
        }
        let f = (target / phi0).powf(1.0 / D::D as f64);
        let d_max = self.max_diameter();
        let width = d_max * f * (1.0 + CELL_MARGIN);
        self.check_box(width)
            .map_err(|e| format!("LS growth to Φ = {target}: {e}"))?;
        let g = rate * v_rms / d_max;
        let t_end = (f - 1.0) / g;
        let mut eng = Engine::new(self, width, g);
        let interval = n as u64;
        let max_total = (MAX_GROWTH_COLLISIONS / rate * n as f64 / 2.0).ceil() as u64;
        let max_events = MAX_EVENTS_PER_COLLISION * (interval + n as u64);
        loop {
            eng.flush_kinetic();
            let (virial0, kin0) = (eng.virial, eng.kin);
            let halt = eng.run(self, t_end, eng.collisions + interval, max_events);
            if halt == Halt::Events {
                let t = eng.t;
                self.finish(&mut eng, t);
                for r in self.radius.iter_mut() {
                    *r *= 1.0 + g * t;
                }
                return Err(format!(
                    "LS growth stalled at Φ = {:.6} before reaching Φ = {target}: {max_events} events without {interval} collisions",
                    self.packing_fraction()
                ));
            }
            if halt != Halt::Collisions {
                break;
            }
            eng.flush_kinetic();
            let z = 1.0 + (eng.virial - virial0) / (eng.kin - kin0);
            let jammed = z.is_nan() || z >= JAM_PRESSURE;
            if jammed || eng.collisions > max_total {
                let t = eng.t;
                let phi = phi0 * (1.0 + g * t).powi(D::D as i32);
                let mut stats = self.finish(&mut eng, t);
                for r in self.radius.iter_mut() {
                    *r *= 1.0 + g * t;
                }
                stats.packing_fraction = phi;
                let why = if jammed {
                    format!("reduced pressure Z = {z:.3e} over the last {interval} collisions exceeds {JAM_PRESSURE:e}")
                } else {
                    format!("more than {MAX_GROWTH_COLLISIONS:e}/rate collisions per grain")
                };
                return Err(format!(
                    "LS growth jammed at Φ = {phi:.6} before reaching Φ = {target} (rate {rate}, after {:.0} collisions per grain): {why}",
                    stats.collisions_per_grain
                ));
            }
            eng.rescale(self, mv2_0);
        }
        let mut stats = self.finish(&mut eng, t_end);
        for r in self.radius.iter_mut() {
            *r *= f;
        }
        let mv2 = self.mv2();
        if mv2 > 0.0 {
            let lambda = (mv2_0 / mv2).sqrt();
            for v in self.vel.iter_mut() {
                *v = *v * lambda;
            }
        }
        stats.rescalings += 1;
        stats.packing_fraction = self.packing_fraction();
        stats.temperature = self.temperature();
        Ok(stats)
    }

    fn mv2(&self) -> f64 {
        self.vel
            .iter()
            .zip(&self.mass)
            .map(|(v, &m)| m * v.norm_squared())
            .sum()
    }

    fn max_diameter(&self) -> f64 {
        2.0 * self.radius.iter().fold(0.0f64, |a, &r| a.max(r))
    }

    fn check_box(&self, width: f64) -> Result<(), String> {
        for a in 0..D::D {
            if self.l[a] < 2.0 * width {
                return Err(format!(
                    "box length {} (axis {a}) is below two largest diameters ({})",
                    self.l[a],
                    2.0 * width
                ));
            }
        }
        Ok(())
    }

    fn checked_width(&self, d_max: f64) -> f64 {
        let width = d_max * (1.0 + CELL_MARGIN);
        if let Err(e) = self.check_box(width) {
            panic!("hard spheres: {e}");
        }
        width
    }

    /// Brings every grain to time `t`, wraps positions, accumulates time and collisions.
    fn finish(&mut self, eng: &mut Engine<D>, t: f64) -> Stats {
        eng.t = t;
        eng.flush_kinetic();
        eng.write_back(self);
        self.time += t;
        self.collisions += eng.collisions;
        self.stats(eng, t)
    }

    fn stats(&self, eng: &Engine<D>, t: f64) -> Stats {
        Stats {
            collisions: eng.collisions,
            collisions_per_grain: 2.0 * eng.collisions as f64 / self.len().max(1) as f64,
            cell_crossings: eng.crossings,
            time: t,
            z: if eng.kin > 0.0 {
                1.0 + eng.virial / eng.kin
            } else {
                f64::NAN
            },
            temperature: self.temperature(),
            packing_fraction: self.packing_fraction(),
            rescalings: eng.rescalings,
        }
    }
}

/// Wraps a reduced position into [0,1) by subtracting its floor.
fn wrap_floor<D: Dim>(s: &mut D::V) {
    for a in 0..D::D {
        let mut x = s[a] - s[a].floor();
        if x >= 1.0 {
            x = 0.0;
        }
        s[a] = x;
    }
}

/// Cell grid in reduced coordinates with intrusive doubly linked lists.
struct Grid<D: Dim> {
    m: [usize; 3],
    head: Vec<u32>,
    next: Vec<u32>,
    prev: Vec<u32>,
    cell: Vec<[usize; 3]>,
    _d: std::marker::PhantomData<D>,
}

impl<D: Dim> Grid<D> {
    /// Cells at least `width` wide (at least two per axis: box lengths ≥ 2 width), filled
    /// with the wrapped positions `s`.
    fn new(l: D::V, width: f64, s: &[D::V]) -> Self {
        let mut m = [1usize; 3];
        for a in 0..D::D {
            m[a] = ((l[a] / width).floor() as usize).max(1);
        }
        let n = s.len();
        let mut grid = Grid {
            m,
            head: vec![NONE; m.iter().product()],
            next: vec![NONE; n],
            prev: vec![NONE; n],
            cell: vec![[0; 3]; n],
            _d: std::marker::PhantomData,
        };
        for (i, x) in s.iter().enumerate() {
            let mut c = [0usize; 3];
            for a in 0..D::D {
                c[a] = ((x[a] * m[a] as f64).floor().max(0.0) as usize).min(m[a] - 1);
            }
            grid.insert(i, c);
        }
        grid
    }

    fn flat(&self, c: [usize; 3]) -> usize {
        c[0] + self.m[0] * (c[1] + self.m[1] * c[2])
    }

    fn insert(&mut self, i: usize, c: [usize; 3]) {
        let k = self.flat(c);
        let h = self.head[k];
        self.next[i] = h;
        self.prev[i] = NONE;
        if h != NONE {
            self.prev[h as usize] = i as u32;
        }
        self.head[k] = i as u32;
        self.cell[i] = c;
    }

    fn remove(&mut self, i: usize) {
        let (p, q) = (self.prev[i], self.next[i]);
        if p != NONE {
            self.next[p as usize] = q;
        } else {
            let k = self.flat(self.cell[i]);
            self.head[k] = q;
        }
        if q != NONE {
            self.prev[q as usize] = p;
        }
    }

    /// Calls `f(j, shift)` for every grain j of the 3^d cells around the cell of i, where
    /// `s_j + shift` is the image of j next to i. With two cells on an axis, the neighbour
    /// cell is visited twice, once for each image.
    #[inline]
    fn for_neighbours(&self, i: usize, mut f: impl FnMut(usize, D::V)) {
        let ci = self.cell[i];
        // Per axis: the three neighbour layers as (flat index contribution, image shift).
        let mut layer = [[(0usize, 0.0f64); 3]; 3];
        let mut stride = 1;
        for a in 0..D::D {
            let m = self.m[a];
            let c = ci[a];
            layer[a] = [
                if c == 0 {
                    ((m - 1) * stride, -1.0)
                } else {
                    ((c - 1) * stride, 0.0)
                },
                (c * stride, 0.0),
                if c + 1 == m {
                    (0, 1.0)
                } else {
                    ((c + 1) * stride, 0.0)
                },
            ];
            stride *= m;
        }
        let nz = if D::D == 3 { 3 } else { 1 };
        for &(kz, sz) in &layer[2][..nz] {
            for &(ky, sy) in &layer[1] {
                for &(kx, sx) in &layer[0] {
                    let mut shift = D::V::zero();
                    shift[0] = sx;
                    shift[1] = sy;
                    if D::D == 3 {
                        shift[2] = sz;
                    }
                    let mut j = self.head[kx + ky + kz];
                    while j != NONE {
                        f(j as usize, shift);
                        j = self.next[j as usize];
                    }
                }
            }
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// Collision with `partner`, valid while its trajectory counter equals `traj`.
    Collide { partner: u32, traj: u32 },
    /// Crossing of a cell face along `axis`, upwards or downwards.
    Cross { axis: u8, up: bool },
}

/// Heap entry: the earliest predicted event of `grain`, valid while its prediction counter
/// equals `count`. Ordered so that the heap top is the earliest (ties: lower grain index).
#[derive(Clone, Copy, Debug)]
struct Entry {
    time: f64,
    grain: u32,
    count: u32,
    kind: Kind,
}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .time
            .total_cmp(&self.time)
            .then(other.grain.cmp(&self.grain))
            .then(other.count.cmp(&self.count))
    }
}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Entry {}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Halt {
    /// No event before the end time.
    Time,
    Collisions,
    Events,
    /// No event left at all.
    Idle,
}

/// Per-grain state read by the prediction loop, packed in one cache line: the reduced
/// position at time `stamp`, the absolute velocity, the radius at the start of the run.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct StampedGrain<D: Dim> {
    s: D::V,
    v: D::V,
    stamp: f64,
    r: f64,
}

/// Event calendar, cell list and grain states of one run (positions and velocities are
/// written back to [`HardSpheres`] at the end); time counts from the start of the run.
struct Engine<D: Dim> {
    grid: Grid<D>,
    grains: Vec<StampedGrain<D>>,
    inv_l: D::V,
    /// Prediction counters (heap entry validity).
    pred: Vec<u32>,
    /// Trajectory counters (partner validity).
    traj: Vec<u32>,
    heap: BinaryHeap<Entry>,
    t: f64,
    /// Relative growth rate of the diameters: d(t) = d(0)(1 + g t).
    g: f64,
    /// Σ J |r| over collisions.
    virial: f64,
    /// ∫ Σ m v² dt up to `kin_t`.
    kin: f64,
    kin_t: f64,
    /// Current Σ m v².
    mv2: f64,
    collisions: u64,
    crossings: u64,
    rescalings: u64,
}

impl<D: Dim> Engine<D> {
    fn empty() -> Self {
        Engine {
            grid: Grid::new(D::V::zero(), 1.0, &[]),
            grains: Vec::new(),
            inv_l: D::V::zero(),
            pred: Vec::new(),
            traj: Vec::new(),
            heap: BinaryHeap::new(),
            t: 0.0,
            g: 0.0,
            virial: 0.0,
            kin: 0.0,
            kin_t: 0.0,
            mv2: 0.0,
            collisions: 0,
            crossings: 0,
            rescalings: 0,
        }
    }

    fn new(hs: &mut HardSpheres<D>, width: f64, g: f64) -> Self {
        let n = hs.len();
        for x in hs.s.iter_mut() {
            wrap_floor::<D>(x);
        }
        let mut inv_l = D::V::zero();
        for a in 0..D::D {
            inv_l[a] = 1.0 / hs.l[a];
        }
        let grains = (0..n)
            .map(|i| StampedGrain {
                s: hs.s[i],
                v: hs.vel[i],
                stamp: 0.0,
                r: hs.radius[i],
            })
            .collect();
        let mut eng = Engine {
            grid: Grid::new(hs.l, width, &hs.s),
            grains,
            inv_l,
            pred: vec![0; n],
            traj: vec![0; n],
            heap: BinaryHeap::with_capacity(4 * n),
            g,
            mv2: hs.mv2(),
            ..Self::empty()
        };
        for i in 0..n {
            eng.predict(hs.l, i);
        }
        eng
    }

    /// Free flight of grain i up to the current time.
    #[inline]
    fn advance(&mut self, i: usize) {
        let p = &mut self.grains[i];
        let dt = self.t - p.stamp;
        if dt != 0.0 {
            p.s += D::mul(p.v, self.inv_l) * dt;
            p.stamp = self.t;
        }
    }

    /// Writes positions (at the current time, wrapped) and velocities back.
    fn write_back(&mut self, hs: &mut HardSpheres<D>) {
        for i in 0..self.grains.len() {
            self.advance(i);
            hs.s[i] = self.grains[i].s;
            wrap_floor::<D>(&mut hs.s[i]);
            hs.vel[i] = self.grains[i].v;
        }
    }

    fn flush_kinetic(&mut self) {
        self.kin += self.mv2 * (self.t - self.kin_t);
        self.kin_t = self.t;
    }

    /// Pushes the earliest event of grain i (already advanced to the current time).
    fn predict(&mut self, l: D::V, i: usize) {
        let t = self.t;
        let StampedGrain { s: si, v: vi, .. } = self.grains[i];
        let ri = self.grains[i].r;
        let sdi = D::mul(vi, self.inv_l);
        let mut best = f64::INFINITY;
        let mut kind = None;
        let ci = self.grid.cell[i];
        for a in 0..D::D {
            let m = self.grid.m[a] as f64;
            let (face, up) = if sdi[a] > 0.0 {
                ((ci[a] + 1) as f64 / m, true)
            } else if sdi[a] < 0.0 {
                (ci[a] as f64 / m, false)
            } else {
                continue;
            };
            let dt = ((face - si[a]) / sdi[a]).max(0.0);
            if dt < best {
                best = dt;
                kind = Some(Kind::Cross { axis: a as u8, up });
            }
        }
        let grow = 1.0 + self.g * t;
        let (grains, inv_l, g, traj) = (&self.grains, self.inv_l, self.g, &self.traj);
        self.grid.for_neighbours(i, |j, shift| {
            if j == i {
                return;
            }
            let pj = &grains[j];
            let sj = pj.s + D::mul(pj.v, inv_l) * (t - pj.stamp);
            let dr = D::mul(sj + shift - si, l);
            let dv = pj.v - vi;
            let sigma0 = ri + pj.r;
            if let Some(dt) = collision_time::<D>(dr, dv, sigma0 * grow, sigma0 * g) {
                if dt < best {
                    best = dt;
                    kind = Some(Kind::Collide {
                        partner: j as u32,
                        traj: traj[j],
                    });
                }
            }
        });
        if let Some(kind) = kind {
            self.heap.push(Entry {
                time: t + best,
                grain: i as u32,
                count: self.pred[i],
                kind,
            });
        }
    }

    fn repredict(&mut self, l: D::V, i: usize) {
        self.advance(i);
        self.pred[i] = self.pred[i].wrapping_add(1);
        self.predict(l, i);
    }

    /// Processes events up to `t_end`, until the collision counter reaches `max_collisions`,
    /// or `max_events` valid events.
    fn run(
        &mut self,
        hs: &HardSpheres<D>,
        t_end: f64,
        max_collisions: u64,
        max_events: u64,
    ) -> Halt {
        let n = hs.len();
        let mut events = 0u64;
        loop {
            let Some(&e) = self.heap.peek() else {
                return Halt::Idle;
            };
            if e.time > t_end {
                return Halt::Time;
            }
            self.heap.pop();
            let i = e.grain as usize;
            if e.count != self.pred[i] {
                continue;
            }
            if events >= max_events {
                self.heap.push(e);
                return Halt::Events;
            }
            events += 1;
            self.t = self.t.max(e.time);
            match e.kind {
                Kind::Collide { partner, traj } => {
                    let j = partner as usize;
                    if self.traj[j] != traj {
                        self.repredict(hs.l, i);
                    } else {
                        self.collide(hs, i, j);
                        if self.collisions >= max_collisions {
                            return Halt::Collisions;
                        }
                    }
                }
                Kind::Cross { axis, up } => self.cross(hs.l, i, axis as usize, up),
            }
            if self.heap.len() > 8 * n + 1024 {
                let pred = &self.pred;
                self.heap.retain(|e| e.count == pred[e.grain as usize]);
            }
        }
    }

    /// Elastic collision of i and j now; with growth, elastic in the frame of the growing
    /// surfaces (u' = 2σ̇ − u, at least σ̇(1 + 1e-6)).
    fn collide(&mut self, hs: &HardSpheres<D>, i: usize, j: usize) {
        self.advance(i);
        self.advance(j);
        let (pi, pj) = (self.grains[i], self.grains[j]);
        let mut ds = pj.s - pi.s;
        for a in 0..D::D {
            ds[a] -= ds[a].round();
        }
        let r = D::mul(ds, hs.l);
        let dist = r.norm();
        let nrm = r * (1.0 / dist);
        let sigma_dot = (pi.r + pj.r) * self.g;
        let u = (pj.v - pi.v).dot(&nrm);
        let mut after = 2.0 * sigma_dot - u;
        if self.g > 0.0 {
            after = after.max(sigma_dot * (1.0 + SEPARATION_MARGIN));
        }
        let du = after - u;
        if du > 0.0 && dist > 0.0 {
            let (mi, mj) = (hs.mass[i], hs.mass[j]);
            let impulse = mi * mj / (mi + mj) * du;
            self.flush_kinetic();
            let before = mi * pi.v.norm_squared() + mj * pj.v.norm_squared();
            let vi = pi.v - nrm * (impulse / mi);
            let vj = pj.v + nrm * (impulse / mj);
            self.grains[i].v = vi;
            self.grains[j].v = vj;
            self.mv2 += mi * vi.norm_squared() + mj * vj.norm_squared() - before;
            self.virial += impulse * dist;
            self.collisions += 1;
            self.traj[i] = self.traj[i].wrapping_add(1);
            self.traj[j] = self.traj[j].wrapping_add(1);
        }
        self.repredict(hs.l, i);
        self.repredict(hs.l, j);
    }

    /// Grain i crosses a cell face: snapped onto it, moved to the next cell (wrapping through
    /// the periodic boundary), re-predicted.
    fn cross(&mut self, l: D::V, i: usize, axis: usize, up: bool) {
        self.advance(i);
        let m = self.grid.m[axis];
        let mut c = self.grid.cell[i];
        self.grid.remove(i);
        let x = &mut self.grains[i].s[axis];
        if up {
            *x = (c[axis] + 1) as f64 / m as f64;
            if c[axis] + 1 == m {
                c[axis] = 0;
                *x -= 1.0;
            } else {
                c[axis] += 1;
            }
        } else {
            *x = c[axis] as f64 / m as f64;
            if c[axis] == 0 {
                c[axis] = m - 1;
                *x += 1.0;
            } else {
                c[axis] -= 1;
            }
        }
        self.grid.insert(i, c);
        self.crossings += 1;
        self.pred[i] = self.pred[i].wrapping_add(1);
        self.predict(l, i);
    }

    /// All grains to the current time, velocities scaled so that Σ m v² = `mv2`, all events
    /// predicted afresh (LS growth).
    fn rescale(&mut self, hs: &HardSpheres<D>, mv2: f64) {
        self.flush_kinetic();
        let now: f64 = self
            .grains
            .iter()
            .zip(&hs.mass)
            .map(|(p, &m)| m * p.v.norm_squared())
            .sum();
        if now > 0.0 {
            let lambda = (mv2 / now).sqrt();
            for i in 0..self.grains.len() {
                self.advance(i);
                self.grains[i].v = self.grains[i].v * lambda;
            }
        }
        self.mv2 = self
            .grains
            .iter()
            .zip(&hs.mass)
            .map(|(p, &m)| m * p.v.norm_squared())
            .sum();
        self.heap.clear();
        for i in 0..self.grains.len() {
            self.traj[i] = self.traj[i].wrapping_add(1);
            self.pred[i] = self.pred[i].wrapping_add(1);
            self.predict(hs.l, i);
        }
        self.rescalings += 1;
    }
}

/// Time from now to the contact |dr + dv τ| = σ + σ̇ τ of a pair at separation `dr`,
/// relative velocity `dv`, contact distance `sigma` growing at `sigma_dot` ≥ 0; `None` if it
/// never comes. Roots of a τ² + 2b τ + c with a = dv² − σ̇², b = dr·dv − σσ̇, c = dr² − σ²,
/// in cancellation-free form; never negative. Pairs in contact or overlapping by roundoff
/// (c ≤ 0) collide at once if approaching (b < 0, beyond the grazing tolerance).
#[inline]
fn collision_time<D: Dim>(dr: D::V, dv: D::V, sigma: f64, sigma_dot: f64) -> Option<f64> {
    let b = dr.dot(&dv) - sigma * sigma_dot;
    let dv2 = dv.norm_squared();
    let a = dv2 - sigma_dot * sigma_dot;
    if a >= 0.0 && b >= 0.0 {
        return None;
    }
    let dr2 = dr.norm_squared();
    let c = dr2 - sigma * sigma;
    let grazing = || b > -GRAZE * ((dr2 * dv2).sqrt() + sigma * sigma_dot);
    if a >= 0.0 {
        // Ordinary approach (always so without growth): the smaller root.
        if c <= 0.0 {
            return if grazing() { None } else { Some(0.0) };
        }
        let disc = b * b - a * c;
        if disc < 0.0 || grazing() {
            return None;
        }
        return Some(c / (disc.sqrt() - b));
    }
    // a < 0: the contact distance grows faster than the pair separates: contact is certain.
    let disc = (b * b - a * c).max(0.0);
    if b < 0.0 {
        if c <= 0.0 {
            return Some(0.0);
        }
        Some(c / (disc.sqrt() - b))
    } else {
        // Separating: the root where the gap closes (the larger one if c ≤ 0).
        Some(((b + disc.sqrt()) / -a).max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{D2, D3};
    use crate::protocols::lattice::{fcc, fcc_order_parameter};
    use nalgebra::{Vector2, Vector3};

    /// n = 4k³ unit spheres (mass 1) on an FCC lattice at Φ, Maxwell velocities of rms 1.
    fn fcc_system(k: usize, phi: f64, seed: u64) -> HardSpheres<D3> {
        let (side, s) = fcc(k, phi);
        let n = s.len();
        let mass = vec![1.0; n];
        let vel = crate::init::maxwell_velocities::<D3>(&mass, 1.0, seed);
        HardSpheres::new(Vector3::repeat(side), s, vec![0.5; n], mass, vel).unwrap()
    }

    /// Largest relative overlap over all pairs, brute force.
    fn brute_overlap<D: Dim>(hs: &HardSpheres<D>) -> f64 {
        let mut worst = f64::NEG_INFINITY;
        for i in 0..hs.len() {
            for j in i + 1..hs.len() {
                let mut ds = hs.s[j] - hs.s[i];
                for a in 0..D::D {
                    ds[a] -= ds[a].round();
                }
                let sigma = hs.radius[i] + hs.radius[j];
                worst = worst.max(1.0 - D::mul(ds, hs.l).norm() / sigma);
            }
        }
        worst
    }

    #[test]
    fn collision_time_solves_the_contact_equation() {
        // Head-on: gap 1 closing at speed 2.
        let t = collision_time::<D2>(Vector2::new(2.0, 0.0), Vector2::new(-2.0, 0.0), 1.0, 0.0);
        assert_eq!(t, Some(0.5));
        // Receding, or missing.
        assert_eq!(
            collision_time::<D2>(Vector2::new(2.0, 0.0), Vector2::new(1.0, 0.0), 1.0, 0.0),
            None
        );
        assert_eq!(
            collision_time::<D2>(Vector2::new(2.0, 0.0), Vector2::new(-1.0, 5.0), 1.0, 0.0),
            None
        );
        // Growth catches a receding pair: |2 + 0.1 τ| = 1 + 0.5 τ → τ = 2.5.
        let t =
            collision_time::<D2>(Vector2::new(2.0, 0.0), Vector2::new(0.1, 0.0), 1.0, 0.5).unwrap();
        assert!((t - 2.5).abs() < 1e-14, "{t}");
        // Oblique approach with growth: check the root.
        let (dr, dv) = (Vector3::new(1.5, 0.3, -0.2), Vector3::new(-0.7, 0.1, 0.05));
        let t = collision_time::<D3>(dr, dv, 1.0, 0.05).unwrap();
        assert!(((dr + dv * t).norm() - (1.0 + 0.05 * t)).abs() < 1e-14);
        // Touching and receding: no collision; touching and approaching: now.
        let touch = Vector2::new(1.0, 0.0);
        assert_eq!(
            collision_time::<D2>(touch, Vector2::new(1e-3, 0.0), 1.0, 0.0),
            None
        );
        assert_eq!(
            collision_time::<D2>(touch, Vector2::new(-1e-3, 0.0), 1.0, 0.0),
            Some(0.0)
        );
    }

    /// AR07 §III.A: during growth a collision reflects the normal relative velocity in the
    /// frame of the growing surfaces, u' = 2σ̇ − u, at the predicted contact time.
    #[test]
    fn growth_collision_reflects_in_the_growing_frame() {
        let s = vec![Vector2::new(0.4, 0.5), Vector2::new(0.6, 0.5)];
        let v = vec![Vector2::new(1.0, 0.0), Vector2::new(-1.0, 0.0)];
        let mut hs =
            HardSpheres::<D2>::new(Vector2::new(10.0, 10.0), s, vec![0.5; 2], vec![1.0, 3.0], v)
                .unwrap();
        let g = 0.1;
        let mut eng = Engine::new(&mut hs, 1.5, g);
        assert_eq!(eng.run(&hs, f64::INFINITY, 1, 100), Halt::Collisions);
        // |2 − 2τ| = 1 + 0.1 τ; u = −2, σ̇ = 0.1 → u' = 2.2.
        assert!((eng.t - 1.0 / 2.1).abs() < 1e-15, "{}", eng.t);
        let (vi, vj) = (eng.grains[0].v, eng.grains[1].v);
        assert!((vj.x - vi.x - 2.2).abs() < 1e-14, "{vi} {vj}");
        assert!((vi.x + 3.0 * vj.x - (1.0 - 3.0)).abs() < 1e-14);
        assert_eq!((vi.y, vj.y), (0.0, 0.0));
        assert!((eng.virial - 0.75 * 4.2 * (1.0 + g * eng.t)).abs() < 1e-13);
    }

    #[test]
    fn overlapping_input_is_refused_with_the_pair() {
        let l = Vector2::new(10.0, 10.0);
        let s = vec![
            Vector2::new(0.1, 0.5),
            Vector2::new(0.19, 0.5),
            Vector2::new(0.6, 0.6),
        ];
        let e = HardSpheres::<D2>::new(l, s, vec![0.5; 3], vec![1.0; 3], vec![Vector2::zeros(); 3])
            .err()
            .unwrap();
        assert!(e.contains("grains 0 and 1 overlap by 1.000e-1"), "{e}");
        // Through the periodic boundary.
        let s = vec![Vector2::new(0.02, 0.5), Vector2::new(0.95, 0.5)];
        let e = HardSpheres::<D2>::new(l, s, vec![0.5; 2], vec![1.0; 2], vec![Vector2::zeros(); 2])
            .err()
            .unwrap();
        assert!(e.contains("grains 0 and 1 overlap"), "{e}");
    }

    /// Mean and standard error of the block values of Z from `blocks` runs of duration `dt`.
    fn block_z<D: Dim>(hs: &mut HardSpheres<D>, blocks: usize, dt: f64) -> (f64, f64) {
        let z: Vec<f64> = (0..blocks).map(|_| hs.run_time(dt).z).collect();
        let mean = z.iter().sum::<f64>() / blocks as f64;
        let var = z.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (blocks - 1) as f64;
        (mean, (var / blocks as f64).sqrt())
    }

    /// AR07 §III: the hard-sphere fluid at Φ = 0.45 obtained by melting the FCC lattice has
    /// the Carnahan–Starling compressibility factor (within 1 %; Kolafa–Labík–Malijevský,
    /// more accurate, within 0.5 %).
    #[test]
    fn hard_sphere_fluid_matches_carnahan_starling() {
        let eta: f64 = 0.45;
        let mut hs = fcc_system(5, eta, 11);
        hs.run_collisions(100.0);
        let (z, err) = block_z(&mut hs, 40, 5.0);
        let cs = (1.0 + eta + eta * eta - eta.powi(3)) / (1.0 - eta).powi(3);
        let klm =
            (1.0 + eta + eta * eta - 2.0 / 3.0 * (eta.powi(3) + eta.powi(4))) / (1.0 - eta).powi(3);
        eprintln!("3D Φ = 0.45, n = 500: Z = {z:.4} ± {err:.4}, CS {cs:.4}, KLM {klm:.4}");
        assert!((z - cs).abs() < 0.01 * cs, "Z = {z} ± {err}, CS = {cs}");
        assert!(
            (z - klm).abs() < 0.005 * klm,
            "Z = {z} ± {err}, KLM = {klm}"
        );
        assert!(err < 0.002 * cs, "statistical error {err}");
    }

    /// Monodisperse hard disks at Φ = 0.5 (grown from a random gas at 0.4): Henderson's
    /// equation of state, within 1.5 %.
    #[test]
    fn hard_disk_fluid_matches_henderson() {
        let eta: f64 = 0.5;
        let mut hs = disk_system(400, 1.0, 0.4, 5);
        hs.grow(eta, 1e-2).unwrap();
        assert!((hs.packing_fraction() - eta).abs() < 1e-12);
        hs.run_collisions(100.0);
        let (z, err) = block_z(&mut hs, 40, 5.0);
        let henderson = (1.0 + eta * eta / 8.0) / (1.0 - eta).powi(2);
        eprintln!("2D Φ = 0.5, n = 400: Z = {z:.4} ± {err:.4}, Henderson {henderson:.4}");
        assert!((z - henderson).abs() < 0.015 * henderson, "Z = {z} ± {err}");
        assert!(err < 0.002 * henderson, "statistical error {err}");
    }

    /// Disks with diameters uniform in [d_min, 1] (GRC07 §II.A), mass d², random gas at Φ.
    fn disk_system(n: usize, d_min: f64, phi: f64, seed: u64) -> HardSpheres<D2> {
        let gas = crate::init::random_gas::<D2>(n, d_min, None, phi, seed).unwrap();
        let mass: Vec<f64> = gas.diameter.iter().map(|d| d * d).collect();
        let vel = crate::init::maxwell_velocities::<D2>(&mass, 1.0, seed);
        let radius = gas.diameter.iter().map(|d| 0.5 * d).collect();
        HardSpheres::new(gas.l, gas.s, radius, mass, vel).unwrap()
    }

    /// Elastic collisions conserve kinetic energy and momentum to roundoff; no pair overlaps
    /// (3D monodisperse and 2D polydisperse with unequal masses).
    #[test]
    fn energy_and_momentum_conserved_and_no_overlap() {
        fn check<D: Dim>(mut hs: HardSpheres<D>, cpg: f64) {
            let (e0, p0) = (hs.kinetic_energy(), hs.momentum());
            let scale: f64 = hs.vel.iter().zip(&hs.mass).map(|(v, m)| m * v.norm()).sum();
            for _ in 0..10 {
                let st = hs.run_collisions(cpg / 10.0);
                assert!(st.collisions > 0);
                let de = (hs.kinetic_energy() - e0).abs() / e0;
                let dp = (hs.momentum() - p0).norm() / scale;
                let overlap = brute_overlap(&hs);
                assert!(de < 1e-12, "energy drift {de:e}");
                assert!(dp < 1e-13, "momentum drift {dp:e}");
                assert!(overlap < 1e-10, "overlap {overlap:e}");
                assert!(hs
                    .s
                    .iter()
                    .all(|x| (0..D::D).all(|a| (0.0..1.0).contains(&x[a]))));
            }
            assert!(hs.collisions as f64 >= cpg * hs.len() as f64 / 2.0);
        }
        check(fcc_system(3, 0.45, 3), 200.0);
        let mut disks = disk_system(300, 0.5, 0.45, 3);
        disks.grow(0.7, 1e-2).unwrap();
        check(disks, 200.0);
    }

    /// FCC lattice of `k` cells per side at Φ after 100 collisions per grain: translational
    /// order parameter and mean squared displacement (unwrapped, summed over short runs).
    fn order_and_msd(k: usize, phi: f64, seed: u64) -> (f64, f64) {
        let mut hs = fcc_system(k, phi, seed);
        let n = hs.len();
        assert!((fcc_order_parameter(&hs.s, k) - 1.0).abs() < 1e-12);
        let mut disp = vec![Vector3::zeros(); n];
        for _ in 0..50 {
            let before = hs.s.clone();
            hs.run_collisions(2.0);
            for i in 0..n {
                let mut ds = hs.s[i] - before[i];
                ds.iter_mut().for_each(|c| *c -= c.round());
                disp[i] += D3::mul(ds, hs.l);
            }
        }
        let msd = disp.iter().map(|d| d.norm_squared()).sum::<f64>() / n as f64;
        (fcc_order_parameter(&hs.s, k), msd)
    }

    /// AR07 §III: the FCC lattice at Φ = 0.45 (below freezing, 0.494) melts within 100
    /// collisions per grain (at 50 the order parameter is down to ~0.1): the translational
    /// order parameter drops from 1 to the fluid level ~ n^{-1/2}, the root mean squared
    /// displacement exceeds half the nearest-neighbour distance (the radius of a lattice
    /// site's cell); the same lattice at Φ = 0.60 (above melting, 0.545) stays a crystal,
    /// with a mean squared displacement a hundred times smaller.
    #[test]
    fn fcc_lattice_melts_at_0_45() {
        let (order, msd) = order_and_msd(5, 0.45, 2);
        let nn = crate::protocols::lattice::fcc_nearest_neighbour(0.45);
        let (order_solid, msd_solid) = order_and_msd(5, 0.60, 2);
        eprintln!(
            "Φ = 0.45: order {order:.3}, MSD {msd:.3} (nn² = {:.3}); Φ = 0.60: order {order_solid:.3}, MSD {msd_solid:.4}",
            nn * nn
        );
        assert!(order < 0.12, "FCC order parameter {order}");
        assert!(msd > 0.25 * nn * nn, "MSD {msd}");
        assert!(
            order_solid > 0.5 && msd_solid < 0.01 * msd,
            "{order_solid} {msd_solid}"
        );
    }

    /// AR07 §III.A (state A'): LS growth of the melted fluid from Φ = 0.45 to 0.61 reaches
    /// the target exactly, without overlap, with the initial kinetic energy and zero momentum.
    #[test]
    fn ls_growth_reaches_0_61_without_overlap() {
        let mut hs = fcc_system(5, 0.45, 4);
        hs.run_collisions(20.0);
        let e0 = hs.kinetic_energy();
        let st = hs.grow(0.61, 1e-2).unwrap();
        eprintln!("LS 0.45 → 0.61: {st:?}");
        assert!((hs.packing_fraction() - 0.61).abs() < 1e-9);
        assert!((st.packing_fraction - 0.61).abs() < 1e-9);
        let f = (0.61f64 / 0.45).cbrt();
        assert!(hs.radius.iter().all(|&r| (r - 0.5 * f).abs() < 1e-12));
        assert!(brute_overlap(&hs) < 1e-10, "{}", brute_overlap(&hs));
        assert!((hs.kinetic_energy() - e0).abs() < 1e-12 * e0);
        assert!(hs.momentum().norm() < 1e-10);
        assert!(
            st.rescalings > 10 && st.collisions_per_grain > 100.0,
            "{st:?}"
        );
        // Still a fluid, and the hard-sphere dynamics goes on from the grown state.
        assert!(hs.run_collisions(10.0).z > 20.0);
        assert!(brute_overlap(&hs) < 1e-10);
    }

    /// GRC07 §III.A: a polydisperse disk gas (diameters in [a/2, a]) grows to a dense fluid.
    #[test]
    fn ls_growth_of_polydisperse_disks() {
        let mut hs = disk_system(400, 0.5, 0.3, 8);
        let ratio: Vec<f64> = hs.radius.iter().map(|r| r / hs.radius[0]).collect();
        hs.grow(0.78, 1e-2).unwrap();
        assert!((hs.packing_fraction() - 0.78).abs() < 1e-9);
        assert!(brute_overlap(&hs) < 1e-10);
        for (i, r) in ratio.iter().enumerate() {
            assert!((hs.radius[i] / hs.radius[0] - r).abs() < 1e-12);
        }
    }

    /// Beyond the densest packing (Φ = 0.75 > π/(3√2)) growth jams and says so, leaving a
    /// valid state; other refusals.
    #[test]
    fn impossible_growth_target_is_an_error() {
        let mut hs = fcc_system(3, 0.45, 6);
        hs.run_collisions(20.0);
        let e = hs.grow(0.75, 1e-2).err().unwrap();
        eprintln!("{e}");
        assert!(
            e.contains("jammed at Φ = 0.6") && e.contains("Φ = 0.75"),
            "{e}"
        );
        let phi = hs.packing_fraction();
        assert!(phi > 0.6 && phi < 0.7405, "{phi}");
        assert!(brute_overlap(&hs) < 1e-10);
        assert!(hs
            .grow(0.5, 1e-2)
            .err()
            .unwrap()
            .contains("below the current"));
        hs.vel.iter_mut().for_each(|v| *v = Vector3::zeros());
        assert!(hs.grow(0.7, 1e-2).err().unwrap().contains("at rest"));
        // Box too small for the final diameters (2 × 1.41 > 2.5).
        let s = vec![Vector2::new(0.25, 0.25), Vector2::new(0.75, 0.75)];
        let v = vec![Vector2::new(1.0, 0.0), Vector2::new(-1.0, 0.0)];
        let l = Vector2::new(2.5, 2.5);
        let mut small = HardSpheres::<D2>::new(l, s, vec![0.5; 2], vec![1.0; 2], v).unwrap();
        let e = small.grow(0.5, 1e-2).err().unwrap();
        assert!(e.contains("two largest diameters"), "{e}");
    }

    /// Same seed, same bits (positions, velocities, time, statistics), growth included.
    #[test]
    fn same_seed_gives_identical_bits() {
        let run = |seed: u64| {
            let mut hs = fcc_system(3, 0.45, seed);
            let a = hs.run_collisions(30.0);
            let b = hs.grow(0.55, 2e-2).unwrap();
            let c = hs.run_time(1.0);
            let mut bits: Vec<u64> =
                hs.s.iter()
                    .chain(&hs.vel)
                    .flat_map(|v| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                    .collect();
            bits.extend([
                hs.time.to_bits(),
                a.z.to_bits(),
                b.z.to_bits(),
                c.z.to_bits(),
            ]);
            bits.push(hs.collisions);
            bits
        };
        assert_eq!(run(9), run(9));
        assert_ne!(run(9), run(10));
    }
}
