//! The particle system and one time step: velocity Verlet for the grains (AR07 (6)) and the
//! cell lengths (AR07 (7)), with the stress of AR07 (8).
//!
//! Every parallel loop runs over fixed chunks and reduces in chunk order, so for a given seed
//! results are bit-for-bit identical for any number of threads; the chunks are handed out as
//! one contiguous piece per thread (engine/src/parallel.rs).

use crate::cell::Cell;
use crate::contact::batch::{self, PairChunk};
use crate::contact::{ContactLaw, Pair, PairForce};
use crate::geometry::{add_outer, Dim, Tensor, VectorOps};
use crate::neighbor::{branch, wrap_moved, NeighborList, ROW_CHUNK};
use crate::parallel::{balanced_cuts, piece_len};
use rayon::prelude::*;

/// Grains handled per parallel task in the per-grain loops.
const GRAIN_CHUNK: usize = 256;

/// Grains (structure of arrays), cell, neighbour list and contact law.
#[derive(Clone, Debug)]
pub struct System<D: Dim, L: ContactLaw<D>> {
    pub law: L,
    pub cell: Cell<D>,
    /// Reduced positions s ∈ [0,1)^d; r = L·s.
    pub s: Vec<D::V>,
    /// Peculiar velocities u = L·ṡ (the velocity relative to the affine cell motion).
    pub u: Vec<D::V>,
    /// Angular velocities (left empty when the law exerts no moments).
    pub w: Vec<D::Ang>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub inv_mass: Vec<f64>,
    pub inv_inertia: Vec<f64>,
    /// Net force and moment on each grain from the last force evaluation.
    pub force: Vec<D::V>,
    pub torque: Vec<D::Ang>,
    /// Peculiar displacement since the last neighbour-list build.
    pub disp: Vec<D::V>,
    pub nlist: NeighborList<L::History>,
    /// Per pair: force exerted by i on j, n × T, and the rolling moment (the last two only
    /// when the law has them).
    pair_force: Vec<D::V>,
    pair_cross: Vec<D::Ang>,
    pair_roll: Vec<D::Ang>,
    /// Contact part of Ω σ (AR07 (8)) from the last force evaluation.
    pub contact_virial: Tensor,
    /// Kinetic part Σ m u_α u_β.
    pub kinetic_virial: Tensor,
    /// Largest overlap relative to the smaller radius at the last force evaluation, and the pair.
    pub max_overlap: (f64, u32, u32),
    pub dt: f64,
    pub time: f64,
    pub step: u64,
    max_disp: f64,
    /// Largest radius, at construction and at each list build (so the per-step staleness
    /// check does not scan the radii).
    r_max: f64,
    /// Run the law's batch (SIMD) force kernel where it has one, [`ContactLaw::force_batch`]
    /// (default: where the CPU runs it and `GRAINBENCH_SCALAR` is unset, `contact::batch`);
    /// `false` keeps the scalar reference path.
    pub simd: bool,
    /// Set by [`System::shed_step_buffers`]: the system can be read, no longer stepped.
    shed: bool,
}

/// One chunk of rows of the force pass, with its slices of the per-pair arrays.
struct Job<'a, H, V, A> {
    rows: std::ops::Range<usize>,
    first: usize,
    hist: &'a mut [H],
    f: &'a mut [V],
    c: &'a mut [A],
    g: &'a mut [A],
}

/// Grain i of a pair, loaded once per row of the force pass.
struct RowGrain<D: Dim> {
    s: D::V,
    u: D::V,
    w: D::Ang,
    r: f64,
    m: f64,
}

/// Summary of one force pass over a chunk of rows.
#[derive(Clone, Copy)]
struct ChunkSum {
    virial: Tensor,
    overlap: (f64, u32, u32),
}

impl<D: Dim, L: ContactLaw<D>> System<D, L> {
    /// A system of grains at reduced positions `s` with diameters `diameter`; masses are
    /// (d/a)^d with a = 1 (the largest diameter) and moments of inertia c·m·d².
    pub fn new(law: L, cell: Cell<D>, s: Vec<D::V>, diameter: &[f64], skin: f64) -> Self {
        let n = s.len();
        let radius: Vec<f64> = diameter.iter().map(|d| 0.5 * d).collect();
        let mass: Vec<f64> = diameter.iter().map(|d| d.powi(D::D as i32)).collect();
        let inv_mass = mass.iter().map(|m| 1.0 / m).collect();
        let inv_inertia = mass
            .iter()
            .zip(diameter)
            .map(|(m, d)| 1.0 / (D::INERTIA_FACTOR * m * d * d))
            .collect();
        let mut sys = System {
            law,
            cell,
            s,
            u: vec![D::V::zero(); n],
            // Allocated for every law so the per-grain loops can zip over them; never read
            // or written in the hot loops when the law exerts no moments.
            w: vec![D::Ang::zero(); n],
            radius,
            mass,
            inv_mass,
            inv_inertia,
            force: vec![D::V::zero(); n],
            torque: vec![D::Ang::zero(); n],
            disp: vec![D::V::zero(); n],
            nlist: NeighborList::new(skin),
            pair_force: Vec::new(),
            pair_cross: Vec::new(),
            pair_roll: Vec::new(),
            contact_virial: [[0.0; 3]; 3],
            kinetic_virial: [[0.0; 3]; 3],
            max_overlap: (0.0, 0, 0),
            dt: 0.0,
            time: 0.0,
            step: 0,
            max_disp: 0.0,
            r_max: 0.0,
            simd: batch::wanted(),
            shed: false,
        };
        sys.r_max = sys.radius.iter().cloned().fold(0.0, f64::max);
        for x in sys.s.iter_mut() {
            wrap_moved::<D>(x);
        }
        sys
    }

    pub fn len(&self) -> usize {
        self.s.len()
    }

    pub fn is_empty(&self) -> bool {
        self.s.is_empty()
    }

    /// Listing reach: largest 2R + interaction range + skin.
    fn reach(&self) -> f64 {
        2.0 * self.r_max + self.law.range() + self.nlist.skin
    }

    /// Rebuilds the neighbour list now.
    pub fn rebuild(&mut self) {
        self.r_max = self.radius.iter().cloned().fold(0.0, f64::max);
        let range = self.law.range();
        self.nlist
            .build::<D>(&self.s, &self.radius, &self.cell.l, range);
        for d in self.disp.iter_mut() {
            *d = D::V::zero();
        }
        self.max_disp = 0.0;
        self.size_pair_buffers();
    }

    /// Sizes the per-pair forces and moments to the list, zeroed: a pass may leave a pair
    /// that was and stays out of reach untouched (the AVX kernel's `flush`).
    fn size_pair_buffers(&mut self) {
        let np = self.nlist.pairs();
        self.pair_force.clear();
        self.pair_force.resize(np, D::V::zero());
        if L::MOMENTS {
            self.pair_cross.clear();
            self.pair_cross.resize(np, D::Ang::zero());
        }
        if L::ROLLING {
            self.pair_roll.clear();
            self.pair_roll.resize(np, D::Ang::zero());
        }
    }

    /// Frees what only stepping uses (per-pair forces, net forces and moments, displacements,
    /// inverse masses, the list's transposed index) once a run is over, so that the final
    /// snapshot is built beside a smaller system and the run's peak memory stays lower
    /// (docs/performance.md). Positions, velocities, the list with its history, the virials and
    /// [`System::interactions`] stay; [`System::step`] refuses to run afterwards.
    pub(crate) fn shed_step_buffers(&mut self) {
        self.shed = true;
        self.pair_force = Vec::new();
        self.pair_cross = Vec::new();
        self.pair_roll = Vec::new();
        self.force = Vec::new();
        self.torque = Vec::new();
        self.disp = Vec::new();
        self.inv_mass = Vec::new();
        self.inv_inertia = Vec::new();
        self.nlist.col_start = Vec::new();
        self.nlist.col_pair = Vec::new();
    }

    /// Checks that the cell is large enough for the minimum-image convention.
    pub fn check_cell(&self) -> Result<(), String> {
        let reach = self.reach();
        for a in 0..D::D {
            if self.cell.l[a] < 2.0 * reach {
                return Err(format!(
                    "cell length L_{} = {:.4} is less than twice the interaction reach {:.4}: use more grains",
                    a + 1,
                    self.cell.l[a],
                    reach
                ));
            }
        }
        Ok(())
    }

    /// Prepares forces for the first step (list build and one force evaluation).
    /// The springs are not advanced (no time passes).
    pub fn init_forces(&mut self) {
        self.rebuild();
        self.compute_forces(0.0);
        self.accumulate(0.0);
    }

    /// One velocity-Verlet step: half kick, drift, forces, half kick (grains and cell).
    pub fn step(&mut self) {
        assert!(
            !self.shed,
            "a system is not stepped after shed_step_buffers"
        );
        let dt = self.dt;
        self.kick_drift();
        // Cell: its rates were kicked at the end of the previous step (leapfrog); drift.
        self.cell.drift(dt);
        if self
            .nlist
            .stale::<D>(self.max_disp, &self.cell.l, self.reach())
        {
            self.rebuild();
        }
        self.compute_forces(dt);
        self.accumulate(0.5 * dt);
        let (stress, contact) = (self.stress(), self.contact_stress());
        self.cell.kick(&stress, &contact, dt);
        self.time += dt;
        self.step += 1;
    }

    /// Opening half kick and drift of the grains (AR07 (6): m s̈ = L⁻¹F, i.e.
    /// u̇ = F/m + ε̇·u), with the forces of the last evaluation; updates the largest
    /// displacement since the list build. The cell is not moved.
    pub fn kick_drift(&mut self) {
        let dt = self.dt;
        let h = 0.5 * dt;
        let erate = self.cell.velocity_strain_rate();
        let inv_l = D::div(ones::<D>(), self.cell.l);
        let piece = piece_len(self.s.len().div_ceil(GRAIN_CHUNK));
        let maxd = {
            let force = &self.force;
            let torque = &self.torque;
            let inv_mass = &self.inv_mass;
            let inv_i = &self.inv_inertia;
            self.s
                .par_chunks_mut(GRAIN_CHUNK)
                .zip(self.u.par_chunks_mut(GRAIN_CHUNK))
                .zip(self.disp.par_chunks_mut(GRAIN_CHUNK))
                .zip(self.w.par_chunks_mut(GRAIN_CHUNK))
                .enumerate()
                .with_min_len(piece)
                .map(|(c, (((s, u), disp), w))| {
                    let base = c * GRAIN_CHUNK;
                    let mut m: f64 = 0.0;
                    for k in 0..s.len() {
                        let i = base + k;
                        let v = u[k] + (force[i] * inv_mass[i] + D::mul(erate, u[k])) * h;
                        u[k] = v;
                        let step = v * dt;
                        s[k] += D::mul(step, inv_l);
                        wrap_moved::<D>(&mut s[k]);
                        disp[k] += step;
                        m = m.max(disp[k].norm_squared());
                        if L::MOMENTS {
                            w[k] += torque[i] * (inv_i[i] * h);
                        }
                    }
                    m
                })
                .reduce(|| 0.0, f64::max)
        };
        self.max_disp = maxd.sqrt();
    }

    /// Background damping of a relaxation (engine/src/run/relax.rs): peculiar velocities and
    /// spins multiplied by `factor` = e^{−γ dt}, once per step after the closing kick.
    pub fn damp(&mut self, factor: f64) {
        for u in &mut self.u {
            *u = *u * factor;
        }
        if L::MOMENTS {
            for w in &mut self.w {
                *w = *w * factor;
            }
        }
    }

    /// Sets every velocity and spin and the cell's rate to zero (AR07 §III.A,
    /// `criteria.quench`).
    pub fn quench(&mut self) {
        self.damp(0.0);
        self.cell.ldot = D::V::zero();
    }

    /// Measured stress σ (AR07 (8)): (contact + kinetic virial)/Ω.
    pub fn stress(&self) -> Tensor {
        let omega = self.cell.volume();
        let mut t = [[0.0; 3]; 3];
        for (a, row) in t.iter_mut().enumerate() {
            for (b, x) in row.iter_mut().enumerate() {
                *x = (self.contact_virial[a][b] + self.kinetic_virial[a][b]) / omega;
            }
        }
        t
    }

    /// Contact part of the stress only.
    pub fn contact_stress(&self) -> Tensor {
        let omega = self.cell.volume();
        let mut t = self.contact_virial;
        for row in t.iter_mut() {
            for x in row.iter_mut() {
                *x /= omega;
            }
        }
        t
    }

    /// Geometry and kinematics of pair (i, j) as the law sees them.
    /// `None` when the pair is out of the law's range (checked before any square root).
    #[inline(always)]
    fn pair(&self, i: usize, j: usize, erate: &D::V, range: f64) -> Option<(Pair<D>, D::V, f64)> {
        let gi = self.grain(i);
        self.pair_with(&gi, j, erate, range)
    }

    /// What the force pass reads of grain i, loaded once per row.
    #[inline(always)]
    fn grain(&self, i: usize) -> RowGrain<D> {
        RowGrain {
            s: self.s[i],
            u: self.u[i],
            w: if L::MOMENTS {
                self.w[i]
            } else {
                D::Ang::zero()
            },
            r: self.radius[i],
            m: self.mass[i],
        }
    }

    /// [`Self::pair`] with grain i already loaded.
    #[inline(always)]
    fn pair_with(
        &self,
        gi: &RowGrain<D>,
        j: usize,
        erate: &D::V,
        range: f64,
    ) -> Option<(Pair<D>, D::V, f64)> {
        let r = branch::<D>(&gi.s, &self.s[j], &self.cell.l);
        let ri = gi.r;
        let rj = self.radius[j];
        let d2 = r.norm_squared();
        let cut = ri + rj + range;
        if d2 >= cut * cut {
            return None;
        }
        let d = d2.sqrt();
        let n = if d > 0.0 { r * (1.0 / d) } else { r };
        let mut v = self.u[j] - gi.u + D::mul(*erate, r);
        let (w_i, w_j) = if L::MOMENTS {
            let (wi, wj) = (gi.w, self.w[j]);
            v -= D::ang_cross(wi * ri + wj * rj, n);
            (wi, wj)
        } else {
            (D::Ang::zero(), D::Ang::zero())
        };
        let mi = gi.m;
        let mj = self.mass[j];
        // One division for both reduced quantities.
        let inv = 1.0 / ((ri + rj) * (mi + mj));
        Some((
            Pair {
                n,
                gap: d - ri - rj,
                v_contact: v,
                w_i,
                w_j,
                r_eff: ri * rj * (mi + mj) * inv,
                m_eff: mi * mj * (ri + rj) * inv,
                r_sum: ri + rj,
            },
            r,
            ri.min(rj),
        ))
    }

    /// Force pass over all listed pairs (parallel over fixed chunks of rows): per-pair forces,
    /// contact virial and largest overlap; the springs advance by `dt` (0: evaluation only).
    /// The net forces on the grains are summed by [`Self::accumulate`].
    pub fn compute_forces(&mut self, dt: f64) {
        let n = self.len();
        let erate = self.cell.velocity_strain_rate();
        let range = self.law.range();
        let nchunks = n.div_ceil(ROW_CHUNK);
        // Move the per-pair arrays out so the chunks can borrow them while `self` is shared.
        let mut history = std::mem::take(&mut self.nlist.history);
        let mut pair_force = std::mem::take(&mut self.pair_force);
        let mut pair_cross = std::mem::take(&mut self.pair_cross);
        let mut pair_roll = std::mem::take(&mut self.pair_roll);
        let mut jobs = Vec::with_capacity(nchunks);
        {
            let mut hist = &mut history[..];
            let mut f = &mut pair_force[..];
            let mut c = &mut pair_cross[..];
            let mut g = &mut pair_roll[..];
            for k in 0..nchunks {
                let rows = k * ROW_CHUNK..((k + 1) * ROW_CHUNK).min(n);
                let first = self.nlist.row_start[rows.start] as usize;
                let np = self.nlist.row_start[rows.end] as usize - first;
                let (h0, h1) = std::mem::take(&mut hist).split_at_mut(np);
                hist = h1;
                let (f0, f1) = std::mem::take(&mut f).split_at_mut(np);
                f = f1;
                let (c0, c1) = std::mem::take(&mut c).split_at_mut(if L::MOMENTS { np } else { 0 });
                c = c1;
                let (g0, g1) = std::mem::take(&mut g).split_at_mut(if L::ROLLING { np } else { 0 });
                g = g1;
                jobs.push(Job {
                    rows,
                    first,
                    hist: h0,
                    f: f0,
                    c: c0,
                    g: g0,
                });
            }
        }
        // One group of consecutive chunks per thread, of nearly equal pair counts.
        let cuts = balanced_cuts(&jobs.iter().map(|j| j.f.len()).collect::<Vec<_>>());
        let mut jobs = jobs.into_iter();
        let groups: Vec<Vec<_>> = cuts
            .windows(2)
            .map(|w| jobs.by_ref().take(w[1] - w[0]).collect())
            .collect();
        let this = &*self;
        let sums: Vec<Vec<ChunkSum>> = groups
            .into_par_iter()
            .map(|group| {
                group
                    .into_iter()
                    .map(|job| this.force_chunk(job, &erate, range, dt))
                    .collect()
            })
            .collect();
        self.nlist.history = history;
        self.pair_force = pair_force;
        self.pair_cross = pair_cross;
        self.pair_roll = pair_roll;
        let mut virial = [[0.0; 3]; 3];
        let mut overlap = (0.0, 0, 0);
        for s in sums.iter().flatten() {
            add_tensor(&mut virial, &s.virial);
            if s.overlap.0 > overlap.0 || s.overlap.0.is_nan() {
                overlap = s.overlap;
            }
        }
        self.contact_virial = virial;
        self.max_overlap = overlap;
    }

    /// Force pass over one chunk of rows (a named function, so profiles show it).
    #[inline(never)]
    fn force_chunk(
        &self,
        mut job: Job<'_, L::History, D::V, D::Ang>,
        erate: &D::V,
        range: f64,
        dt: f64,
    ) -> ChunkSum {
        if self.simd {
            if let Some(sum) = self.force_chunk_batch(&mut job, erate, dt) {
                return sum;
            }
        }
        let mut sum = ChunkSum {
            virial: [[0.0; 3]; 3],
            overlap: (0.0, 0, 0),
        };
        for i in job.rows.clone() {
            let gi = self.grain(i);
            for p in self.nlist.row(i) {
                let j = self.nlist.partner[p] as usize;
                let k = p - job.first;
                let Some((pair, r, rmin)) = self.pair_with(&gi, j, erate, range) else {
                    job.hist[k] = Default::default();
                    job.f[k] = D::V::zero();
                    if L::MOMENTS {
                        job.c[k] = D::Ang::zero();
                    }
                    if L::ROLLING {
                        job.g[k] = D::Ang::zero();
                    }
                    continue;
                };
                let pf: PairForce<D> = self.law.interact(&pair, &mut job.hist[k], dt);
                let f = pair.n * pf.normal + pf.tangential;
                job.f[k] = f;
                if L::MOMENTS {
                    job.c[k] = D::cross(pair.n, pf.tangential);
                }
                if L::ROLLING {
                    job.g[k] = pf.rolling;
                }
                add_outer::<D>(&mut sum.virial, &f, &r);
                // Overlap relative to the smaller radius; divide only for a new maximum.
                if -pair.gap > sum.overlap.0 * rmin || pair.gap.is_nan() {
                    sum.overlap = (-pair.gap / rmin, i as u32, j as u32);
                }
            }
        }
        sum
    }

    /// [`Self::force_chunk`] by the law's batch kernel, where it has one for this dimension
    /// and CPU; `None` otherwise.
    fn force_chunk_batch(
        &self,
        job: &mut Job<'_, L::History, D::V, D::Ang>,
        erate: &D::V,
        dt: f64,
    ) -> Option<ChunkSum> {
        let mut chunk = PairChunk {
            rows: job.rows.clone(),
            first: job.first,
            row_start: &self.nlist.row_start,
            partner: &self.nlist.partner,
            s: &self.s,
            u: &self.u,
            w: &self.w,
            radius: &self.radius,
            mass: &self.mass,
            l: self.cell.l,
            erate: *erate,
            dt,
            hist: &mut *job.hist,
            f: &mut *job.f,
            c: &mut *job.c,
        };
        let (virial, overlap) = self.law.force_batch(&mut chunk)?;
        Some(ChunkSum { virial, overlap })
    }

    /// Gathers the pair forces on each grain in a fixed order, then the closing half kick
    /// of length `h` (0: forces and kinetic virial only).
    pub fn accumulate(&mut self, h: f64) {
        let erate = self.cell.velocity_strain_rate();
        let nl = &self.nlist;
        let pf = &self.pair_force;
        let pc = &self.pair_cross;
        let pg = &self.pair_roll;
        let radius = &self.radius;
        let inv_mass = &self.inv_mass;
        let mass = &self.mass;
        let inv_i = &self.inv_inertia;
        let piece = piece_len(self.force.len().div_ceil(GRAIN_CHUNK));
        let kin: Vec<Tensor> = self
            .force
            .par_chunks_mut(GRAIN_CHUNK)
            .zip(self.u.par_chunks_mut(GRAIN_CHUNK))
            .zip(self.torque.par_chunks_mut(GRAIN_CHUNK))
            .zip(self.w.par_chunks_mut(GRAIN_CHUNK))
            .enumerate()
            .with_min_len(piece)
            .map(|(c, (((force, u), torque), w))| {
                let base = c * GRAIN_CHUNK;
                let mut kv = [[0.0; 3]; 3];
                for k in 0..force.len() {
                    let i = base + k;
                    let ri = radius[i];
                    let mut f = D::V::zero();
                    let mut t = D::Ang::zero();
                    for p in nl.row(i) {
                        f -= pf[p];
                        if L::MOMENTS {
                            t -= pc[p] * ri;
                        }
                        if L::ROLLING {
                            t -= pg[p];
                        }
                    }
                    for q in nl.col_start[i]..nl.col_start[i + 1] {
                        let p = nl.col_pair[q as usize] as usize;
                        f += pf[p];
                        if L::MOMENTS {
                            t -= pc[p] * ri;
                        }
                        if L::ROLLING {
                            t += pg[p];
                        }
                    }
                    force[k] = f;
                    let v = u[k] + (f * inv_mass[i] + D::mul(erate, u[k])) * h;
                    u[k] = v;
                    let mv = v * mass[i];
                    add_outer::<D>(&mut kv, &mv, &v);
                    if L::MOMENTS {
                        torque[k] = t;
                        w[k] += t * (inv_i[i] * h);
                    }
                }
                kv
            })
            .collect();
        let mut kv = [[0.0; 3]; 3];
        for t in &kin {
            add_tensor(&mut kv, t);
        }
        self.kinetic_virial = kv;
    }

    /// Kinetic energy (translational + rotational), peculiar velocities.
    pub fn kinetic_energy(&self) -> f64 {
        let mut e = 0.0;
        for i in 0..self.len() {
            e += 0.5 * self.mass[i] * self.u[i].norm_squared();
        }
        if L::MOMENTS {
            for i in 0..self.len() {
                e += 0.5 * self.w[i].norm_squared() / self.inv_inertia[i];
            }
        }
        e
    }

    /// Largest net force and net moment on a grain.
    pub fn max_unbalanced(&self) -> (f64, f64) {
        let f = self
            .force
            .iter()
            .map(|f| f.norm_squared())
            .fold(0.0, f64::max)
            .sqrt();
        let t = self
            .torque
            .iter()
            .map(|t| t.norm_squared())
            .fold(0.0, f64::max)
            .sqrt();
        (f, t)
    }

    /// Solid fraction Φ.
    pub fn packing_fraction(&self) -> f64 {
        let solid: f64 = self.radius.iter().map(|r| D::grain_volume(2.0 * r)).sum();
        solid / self.cell.volume()
    }

    /// Physical position of grain i in [0, L).
    pub fn position(&self, i: usize) -> D::V {
        D::mul(self.s[i], self.cell.l)
    }

    /// Every interacting pair with its forces, evaluated on the current state without
    /// advancing any history.
    pub fn interactions(&self) -> Vec<Interaction<D>> {
        let mut out = Vec::new();
        self.for_each_interaction(|c| out.push(c));
        out
    }

    /// [`System::interactions`] one at a time, in the same order, without collecting them.
    pub fn for_each_interaction(&self, mut f: impl FnMut(Interaction<D>)) {
        let erate = self.cell.velocity_strain_rate();
        for i in 0..self.len() {
            for p in self.nlist.row(i) {
                let j = self.nlist.partner[p] as usize;
                let Some((pair, r, _)) = self.pair(i, j, &erate, self.law.range()) else {
                    continue;
                };
                let mut hist = self.nlist.history[p];
                let pf = self.law.interact(&pair, &mut hist, 0.0);
                if pf.normal != 0.0 || pf.normal_elastic != 0.0 || pair.gap < 0.0 {
                    let (t, g) = self.law.stored(&self.nlist.history[p]);
                    f(Interaction {
                        i,
                        j,
                        branch: r,
                        normal: pf.normal,
                        normal_elastic: pf.normal_elastic,
                        tangential: t,
                        rolling: g,
                        gap: pair.gap,
                    });
                }
            }
        }
    }
}

/// The last good state, in memory, that a blown-up run returns to (not the checkpoint file,
/// [`crate::checkpoint::Checkpoint`]): positions, velocities, cell, and the contact history
/// with the list it belongs to. Everything else (forces, pair buffers, the transposed index,
/// displacements) is derived, so it costs less than half a [`System`].
#[derive(Clone, Debug)]
pub struct LastGood<D: Dim, L: ContactLaw<D>> {
    s: Vec<D::V>,
    u: Vec<D::V>,
    w: Vec<D::Ang>,
    cell: Cell<D>,
    time: f64,
    step: u64,
    row_start: Vec<u32>,
    partner: Vec<u32>,
    history: Vec<L::History>,
}

impl<D: Dim, L: ContactLaw<D>> System<D, L> {
    /// Copies the restart state into `cp`, reusing its allocations.
    pub fn save(&self, cp: &mut Option<LastGood<D, L>>) {
        match cp {
            None => {
                *cp = Some(LastGood {
                    s: self.s.clone(),
                    u: self.u.clone(),
                    w: self.w.clone(),
                    cell: self.cell.clone(),
                    time: self.time,
                    step: self.step,
                    row_start: self.nlist.row_start.clone(),
                    partner: self.nlist.partner.clone(),
                    history: self.nlist.history.clone(),
                })
            }
            Some(c) => {
                c.s.clone_from(&self.s);
                c.u.clone_from(&self.u);
                c.w.clone_from(&self.w);
                c.cell = self.cell.clone();
                c.time = self.time;
                c.step = self.step;
                c.row_start.clone_from(&self.nlist.row_start);
                c.partner.clone_from(&self.nlist.partner);
                c.history.clone_from(&self.nlist.history);
            }
        }
    }

    /// Returns to a saved state: state restored, list rebuilt (keeping the saved history) and
    /// forces evaluated without advancing any spring.
    pub fn restore(&mut self, cp: &LastGood<D, L>) {
        self.s.clone_from(&cp.s);
        self.u.clone_from(&cp.u);
        self.w.clone_from(&cp.w);
        self.cell = cp.cell.clone();
        self.nlist.row_start.clone_from(&cp.row_start);
        self.nlist.partner.clone_from(&cp.partner);
        self.nlist.history.clone_from(&cp.history);
        self.init_forces();
        self.time = cp.time;
        self.step = cp.step;
    }
}

/// The complete integrator state: what a checkpoint on disk holds so that a resumed run
/// continues bit for bit (forces, cell rates, list and history included; nothing recomputed).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(bound(
    serialize = "H: serde::Serialize",
    deserialize = "H: serde::de::DeserializeOwned"
))]
pub struct State<D: Dim, H> {
    cell: Cell<D>,
    s: Vec<D::V>,
    u: Vec<D::V>,
    w: Vec<D::Ang>,
    radius: Vec<f64>,
    force: Vec<D::V>,
    torque: Vec<D::Ang>,
    disp: Vec<D::V>,
    nlist: NeighborList<H>,
    contact_virial: Tensor,
    kinetic_virial: Tensor,
    max_overlap: (f64, u32, u32),
    dt: f64,
    time: f64,
    step: u64,
    max_disp: f64,
}

/// [`State`] borrowed from a running system: serializes to the same bytes as the copy
/// [`System::state`] returns, without the copy (a checkpoint streams it to disk).
#[derive(serde::Serialize)]
#[serde(bound(serialize = "H: serde::Serialize"))]
pub struct StateRef<'a, D: Dim, H> {
    cell: &'a Cell<D>,
    s: &'a [D::V],
    u: &'a [D::V],
    w: &'a [D::Ang],
    radius: &'a [f64],
    force: &'a [D::V],
    torque: &'a [D::Ang],
    disp: &'a [D::V],
    nlist: &'a NeighborList<H>,
    contact_virial: &'a Tensor,
    kinetic_virial: &'a Tensor,
    max_overlap: (f64, u32, u32),
    dt: f64,
    time: f64,
    step: u64,
    max_disp: f64,
}

impl<D: Dim, L: ContactLaw<D>> System<D, L> {
    /// A copy of the complete state.
    pub fn state(&self) -> State<D, L::History> {
        State {
            cell: self.cell.clone(),
            s: self.s.clone(),
            u: self.u.clone(),
            w: self.w.clone(),
            radius: self.radius.clone(),
            force: self.force.clone(),
            torque: self.torque.clone(),
            disp: self.disp.clone(),
            nlist: self.nlist.clone(),
            contact_virial: self.contact_virial,
            kinetic_virial: self.kinetic_virial,
            max_overlap: self.max_overlap,
            dt: self.dt,
            time: self.time,
            step: self.step,
            max_disp: self.max_disp,
        }
    }

    /// The complete state, borrowed (what [`System::state`] copies).
    pub fn state_ref(&self) -> StateRef<'_, D, L::History> {
        StateRef {
            cell: &self.cell,
            s: &self.s,
            u: &self.u,
            w: &self.w,
            radius: &self.radius,
            force: &self.force,
            torque: &self.torque,
            disp: &self.disp,
            nlist: &self.nlist,
            contact_virial: &self.contact_virial,
            kinetic_virial: &self.kinetic_virial,
            max_overlap: self.max_overlap,
            dt: self.dt,
            time: self.time,
            step: self.step,
            max_disp: self.max_disp,
        }
    }

    /// The system in a saved state, with the law `law`.
    pub fn from_state(law: L, st: State<D, L::History>) -> Self {
        let diameter: Vec<f64> = st.radius.iter().map(|r| 2.0 * r).collect();
        let mut sys = System::new(law, st.cell, st.s, &diameter, st.nlist.skin);
        sys.u = st.u;
        sys.w = st.w;
        sys.force = st.force;
        sys.torque = st.torque;
        sys.disp = st.disp;
        sys.nlist = st.nlist;
        sys.contact_virial = st.contact_virial;
        sys.kinetic_virial = st.kinetic_virial;
        sys.max_overlap = st.max_overlap;
        sys.dt = st.dt;
        sys.time = st.time;
        sys.step = st.step;
        sys.max_disp = st.max_disp;
        sys.size_pair_buffers();
        sys
    }
}

/// One interacting pair, for output and analysis.
#[derive(Clone, Copy, Debug)]
pub struct Interaction<D: Dim> {
    pub i: usize,
    pub j: usize,
    pub branch: D::V,
    pub normal: f64,
    pub normal_elastic: f64,
    pub tangential: D::V,
    pub rolling: D::Ang,
    pub gap: f64,
}

fn add_tensor(acc: &mut Tensor, t: &Tensor) {
    for (ra, rt) in acc.iter_mut().zip(t) {
        for (a, b) in ra.iter_mut().zip(rt) {
            *a += b;
        }
    }
}

#[inline(always)]
fn ones<D: Dim>() -> D::V {
    let mut v = D::V::zero();
    for a in 0..D::D {
        v[a] = 1.0;
    }
    v
}
