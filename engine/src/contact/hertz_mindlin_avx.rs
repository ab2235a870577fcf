//! The Hertz–Mindlin force pass of 3D frictional spheres, four pairs at a time with AVX
//! (x86-64): AR07 (1)–(5), the spring transport (B3)–(B5) and Walton's rescaling (App. A) in
//! batch form: `HertzMindlin`'s `ContactLaw::force_batch`, taken at run time where the CPU
//! has AVX and `System::simd` is on; the scalar path
//! ([`super::hertz_mindlin::HertzMindlin::interact`] behind `System::pair_with`) stays the
//! reference.
//!
//! A scalar range test first sends the listed pairs within reach to the batches (7668 of 11 298
//! in the `kernels` bench packing), so lanes are not spent on pairs that only clear
//! their springs; it tests a block of pairs, without a branch on the outcome, before the
//! block's batches run. Each lane performs the scalar path's IEEE operations in the same
//! order (no fused multiply–add, the same divisions), and the virial and largest overlap are
//! summed lane by lane in pair order, so springs, forces, virial and overlap are bit for bit
//! the scalar ones (`tests/simd_kernel.rs`) and results stay identical for any thread count.
//! The rare lanes whose spring turned by more than ~3 mrad in a step, or pivoted by more than
//! 1e-3 rad, take the scalar formula for that part.

use super::batch::{self, ChunkSum, PairChunk};
use super::slider::Spring;
use crate::geometry::D3;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// The law's numbers the kernel reads (`HertzMindlin`'s, without its type parameters).
#[derive(Clone, Copy, Debug)]
pub struct Coefficients {
    pub e_tilde: f64,
    pub kt_ratio: f64,
    pub zeta: f64,
    /// μ of the Coulomb cap, read where the kernel caps (`CAP`).
    pub mu: f64,
}

/// One chunk of the force pass, concretely typed: 3D, with tangential springs.
pub type Chunk<'a> = PairChunk<'a, D3, Spring<V3>>;

/// The force pass over `chunk` with the law `law`, its springs capped by Coulomb (`CAP`, μ
/// finite) or never (μ = ∞, AR07 Z); `None` where the CPU lacks AVX.
pub fn force_chunk<const CAP: bool>(law: &Coefficients, chunk: &mut Chunk<'_>) -> Option<ChunkSum> {
    #[cfg(target_arch = "x86_64")]
    {
        if batch::available() {
            // SAFETY: the CPU has AVX (checked just above).
            return Some(unsafe { avx::force_chunk::<CAP>(law, chunk) });
        }
    }
    let _ = (law, chunk);
    None
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::{Chunk, ChunkSum, Coefficients, V3};
    use crate::contact::slider::Spring;
    use crate::geometry::D3;
    use crate::neighbor::branch;
    use std::arch::x86_64::*;

    /// Lanes per batch: one AVX register. Eight lanes in two registers (two chains of square
    /// roots in flight) spill the sixteen registers and ran 14 % slower (criterion `kernels`,
    /// 345.6 µs against 302.9 µs, 2026-12-05); eight in one AVX-512 register, bit for bit the
    /// same, ran 11 % slower on a Sapphire Rapids Xeon (305 against 274 µs, 2026-12-06).
    const W: usize = 4;

    #[derive(Clone, Copy)]
    struct F(__m256d);

    macro_rules! lanewise {
        ($(#[$doc:meta])* $name:ident($($arg:ident),+) => $op:ident) => {
            $(#[$doc])*
            #[target_feature(enable = "avx")]
            #[inline]
            fn $name($($arg: F),+) -> F {
                F($op($($arg.0),+))
            }
        };
    }
    lanewise!(add(a, b) => _mm256_add_pd);
    lanewise!(sub(a, b) => _mm256_sub_pd);
    lanewise!(mul(a, b) => _mm256_mul_pd);
    lanewise!(div(a, b) => _mm256_div_pd);
    lanewise!(and(a, b) => _mm256_and_pd);
    lanewise!(xor(a, b) => _mm256_xor_pd);
    lanewise!(sqrt(a) => _mm256_sqrt_pd);
    lanewise!(
        /// `min(a, b)`, `b` where either is NaN (as `f64::min(a, b)` for a constant `b`).
        min(a, b) => _mm256_min_pd
    );
    lanewise!(
        /// `max(a, b)`, `b` where either is NaN.
        max(a, b) => _mm256_max_pd
    );
    lanewise!(
        /// `mask ? b : a`.
        pick(a, b, mask) => _mm256_blendv_pd
    );
    /// `a & !b`.
    #[target_feature(enable = "avx")]
    #[inline]
    fn and_not(a: F, b: F) -> F {
        F(_mm256_andnot_pd(b.0, a.0))
    }
    /// Lane mask of the comparison `P` (`_CMP_…`).
    #[target_feature(enable = "avx")]
    #[inline]
    fn cmp<const P: i32>(a: F, b: F) -> F {
        F(_mm256_cmp_pd::<P>(a.0, b.0))
    }
    #[target_feature(enable = "avx")]
    #[inline]
    fn splat(x: f64) -> F {
        F(_mm256_set1_pd(x))
    }
    #[target_feature(enable = "avx")]
    #[inline]
    fn from(a: [f64; W]) -> F {
        F(_mm256_set_pd(a[3], a[2], a[1], a[0]))
    }
    #[target_feature(enable = "avx")]
    #[inline]
    fn to(x: F) -> [f64; W] {
        let mut a = [0.0; W];
        // SAFETY: `a` holds four f64; an unaligned store.
        unsafe { _mm256_storeu_pd(a.as_mut_ptr(), x.0) };
        a
    }
    #[target_feature(enable = "avx")]
    #[inline]
    fn any(mask: F) -> bool {
        _mm256_movemask_pd(mask.0) != 0
    }
    /// `f(v[idx[l]])` in lane l.
    #[target_feature(enable = "avx")]
    #[inline]
    fn gather<T>(v: &[T], idx: &[usize; W], f: impl Fn(&T) -> f64) -> F {
        let (a, b, c, d) = (&v[idx[0]], &v[idx[1]], &v[idx[2]], &v[idx[3]]);
        F(_mm256_set_pd(f(d), f(c), f(b), f(a)))
    }

    /// A 3-vector per lane.
    #[derive(Clone, Copy)]
    struct V([F; 3]);

    impl V {
        #[target_feature(enable = "avx")]
        #[inline]
        fn add(self, o: V) -> V {
            V([
                add(self.0[0], o.0[0]),
                add(self.0[1], o.0[1]),
                add(self.0[2], o.0[2]),
            ])
        }
        #[target_feature(enable = "avx")]
        #[inline]
        fn sub(self, o: V) -> V {
            V([
                sub(self.0[0], o.0[0]),
                sub(self.0[1], o.0[1]),
                sub(self.0[2], o.0[2]),
            ])
        }
        /// Component-wise product (`D::mul`).
        #[target_feature(enable = "avx")]
        #[inline]
        fn cmul(self, o: V) -> V {
            V([
                mul(self.0[0], o.0[0]),
                mul(self.0[1], o.0[1]),
                mul(self.0[2], o.0[2]),
            ])
        }
        #[target_feature(enable = "avx")]
        #[inline]
        fn scale(self, k: F) -> V {
            V([mul(self.0[0], k), mul(self.0[1], k), mul(self.0[2], k)])
        }
        /// nalgebra's order: (x x' + y y') + z z'.
        #[target_feature(enable = "avx")]
        #[inline]
        fn dot(self, o: V) -> F {
            add(
                add(mul(self.0[0], o.0[0]), mul(self.0[1], o.0[1])),
                mul(self.0[2], o.0[2]),
            )
        }
        #[target_feature(enable = "avx")]
        #[inline]
        fn cross(self, b: V) -> V {
            let [ax, ay, az] = self.0;
            let [bx, by, bz] = b.0;
            V([
                sub(mul(ay, bz), mul(az, by)),
                sub(mul(az, bx), mul(ax, bz)),
                sub(mul(ax, by), mul(ay, bx)),
            ])
        }
        #[target_feature(enable = "avx")]
        #[inline]
        fn pick(self, o: V, mask: F) -> V {
            V([
                pick(self.0[0], o.0[0], mask),
                pick(self.0[1], o.0[1], mask),
                pick(self.0[2], o.0[2], mask),
            ])
        }
        #[target_feature(enable = "avx")]
        #[inline]
        fn gather(v: &[V3], idx: &[usize; W]) -> V {
            V([
                gather(v, idx, |p| p.x),
                gather(v, idx, |p| p.y),
                gather(v, idx, |p| p.z),
            ])
        }
        #[target_feature(enable = "avx")]
        #[inline]
        fn splat(v: &V3) -> V {
            V([splat(v.x), splat(v.y), splat(v.z)])
        }
        #[target_feature(enable = "avx")]
        #[inline]
        fn lanes(self) -> [V3; W] {
            let (x, y, z) = (to(self.0[0]), to(self.0[1]), to(self.0[2]));
            std::array::from_fn(|l| V3::new(x[l], y[l], z[l]))
        }
    }

    #[target_feature(enable = "avx")]
    #[inline]
    fn gather1(v: &[f64], idx: &[usize; W]) -> F {
        gather(v, idx, |x| *x)
    }

    /// Listed pairs range-tested per block before its batches run: the test writes every pair
    /// to the next free slot and advances by whether it is within reach, so that an
    /// unpredictable outcome costs no branch (1.10× whole runs of the dense D, 2026-12-06).
    const BLOCK: usize = 64;

    /// `System::force_chunk` for `law`, four pairs within reach at a time.
    #[target_feature(enable = "avx")]
    pub fn force_chunk<const CAP: bool>(law: &Coefficients, ch: &mut Chunk<'_>) -> ChunkSum {
        let mut sum: ChunkSum = ([[0.0; 3]; 3], (0.0, 0, 0));
        let mut lanes = Lanes {
            pair: [(0, 0); BLOCK + W],
            r: [[0.0; BLOCK + W]; 3],
            full: 0,
            out: [0; BLOCK],
            empty: 0,
        };
        let mut tested = 0;
        for i in ch.rows.clone() {
            let (si, ri) = (ch.s[i], ch.radius[i]);
            for p in ch.row_start[i] as usize..ch.row_start[i + 1] as usize {
                // `System::pair_with`'s range test, here so that the batches hold only pairs
                // within reach.
                let j = ch.partner[p] as usize;
                let r = branch::<D3>(&si, &ch.s[j], &ch.l);
                let cut = ri + ch.radius[j];
                let reach = r.norm_squared() < cut * cut;
                lanes.pair[lanes.full] = (i, p);
                for a in 0..3 {
                    lanes.r[a][lanes.full] = r[a];
                }
                lanes.full += reach as usize;
                lanes.out[lanes.empty] = p - ch.first;
                lanes.empty += !reach as usize;
                tested += 1;
                if tested == BLOCK {
                    flush::<CAP>(law, ch, &mut lanes, &mut sum);
                    tested = 0;
                }
            }
        }
        flush::<CAP>(law, ch, &mut lanes, &mut sum);
        let full = lanes.full;
        if full > 0 {
            // Pad with copies of the first pair; only the first `full` lanes are stored.
            for l in full..W {
                lanes.pair[l] = lanes.pair[0];
                for a in 0..3 {
                    lanes.r[a][l] = lanes.r[a][0];
                }
            }
            batch::<CAP>(law, ch, &lanes, 0, full, &mut sum);
        }
        sum
    }

    /// Clears the springs, forces and moments of the block's pairs out of reach and runs its
    /// whole batches; the rest (fewer than `W`) moves to the front for the next block.
    #[target_feature(enable = "avx")]
    #[inline]
    fn flush<const CAP: bool>(
        law: &Coefficients,
        ch: &mut Chunk<'_>,
        lanes: &mut Lanes,
        sum: &mut ChunkSum,
    ) {
        for &k in &lanes.out[..lanes.empty] {
            // Only a pair that has just left contact holds a spring, force and moment to
            // clear: one out of reach before, or new in the list, holds zeros already
            // (`System::size_pair_buffers`), and most pairs out of reach stay so.
            let h = &ch.hist[k];
            if h.kt != 0.0 || h.t != V3::zeros() {
                ch.hist[k] = Spring::default();
                ch.f[k] = V3::zeros();
                ch.c[k] = V3::zeros();
            }
        }
        lanes.empty = 0;
        let whole = lanes.full - lanes.full % W;
        for start in (0..whole).step_by(W) {
            batch::<CAP>(law, ch, lanes, start, W, sum);
        }
        for l in whole..lanes.full {
            lanes.pair[l - whole] = lanes.pair[l];
            for a in 0..3 {
                lanes.r[a][l - whole] = lanes.r[a][l];
            }
        }
        lanes.full -= whole;
    }

    /// The listed pairs of one block: those within reach, in list order, as (grain i, list
    /// index p) with the branch vector r = L·(s_j − s_i) of each; then the chunk indices of
    /// those out of reach.
    struct Lanes {
        pair: [(usize, usize); BLOCK + W],
        r: [[f64; BLOCK + W]; 3],
        full: usize,
        out: [usize; BLOCK],
        empty: usize,
    }

    /// The `W` pairs of `lanes` from `start`, of which the first `live` are stored.
    #[target_feature(enable = "avx")]
    #[inline]
    fn batch<const CAP: bool>(
        law: &Coefficients,
        ch: &mut Chunk<'_>,
        lanes: &Lanes,
        start: usize,
        live: usize,
        sum: &mut ChunkSum,
    ) {
        let pair: [(usize, usize); W] = std::array::from_fn(|l| lanes.pair[start + l]);
        let rb: [[f64; W]; 3] =
            std::array::from_fn(|a| std::array::from_fn(|l| lanes.r[a][start + l]));
        let ii: [usize; W] = std::array::from_fn(|l| pair[l].0);
        let jj: [usize; W] = std::array::from_fn(|l| ch.partner[pair[l].1] as usize);
        let kk: [usize; W] = std::array::from_fn(|l| pair[l].1 - ch.first);
        let zero = splat(0.0);
        let one = splat(1.0);

        // System::pair_with, past its range test.
        let r = V([from(rb[0]), from(rb[1]), from(rb[2])]);
        let ri = gather1(ch.radius, &ii);
        let rj = gather1(ch.radius, &jj);
        let d2 = r.dot(r);
        let cut = add(ri, rj);
        let d = sqrt(d2);
        let inv_d = div(one, d);
        let n = r.pick(r.scale(inv_d), cmp::<_CMP_GT_OQ>(d, zero));
        let wi = V::gather(ch.w, &ii);
        let wj = V::gather(ch.w, &jj);
        let v = V::gather(ch.u, &jj)
            .sub(V::gather(ch.u, &ii))
            .add(V::splat(&ch.erate).cmul(r))
            .sub(wi.scale(ri).add(wj.scale(rj)).cross(n));
        let mi = gather1(ch.mass, &ii);
        let mj = gather1(ch.mass, &jj);
        let inv = div(one, mul(cut, add(mi, mj)));
        let r_eff = mul(mul(mul(ri, rj), add(mi, mj)), inv);
        let m_eff = mul(mul(mul(mi, mj), cut), inv);
        let gap = sub(sub(d, ri), rj);

        // HertzMindlin::interact: in contact unless gap ≥ 0.
        let touch = cmp::<_CMP_NGE_UQ>(gap, zero);
        let h = xor(gap, splat(-0.0));
        let kn = mul(splat(law.e_tilde), sqrt(mul(r_eff, h)));
        let ne = mul(mul(splat(2.0 / 3.0), kn), h);
        let vn = v.dot(n);
        let alpha = mul(splat(2.0 * law.zeta), sqrt(mul(m_eff, kn)));
        let normal = sub(ne, mul(alpha, vn));
        let dt = splat(ch.dt);
        let slip = v.sub(n.scale(vn)).scale(dt);
        let pivot = mul(mul(splat(0.5), wi.add(wj).dot(n)), dt);
        let kt = mul(splat(law.kt_ratio), kn);

        // Spring: slider::elastic_update.
        let t0 = V([
            gather(ch.hist, &kk, |h| h.t.x),
            gather(ch.hist, &kk, |h| h.t.y),
            gather(ch.hist, &kk, |h| h.t.z),
        ]);
        let kt0 = gather(ch.hist, &kk, |h| h.kt);
        let before = t0.dot(t0);
        let inv_before = div(one, before);
        let inv_kt = div(one, kt0);
        // keep_norm_in_plane_with: a spring turned by little keeps its norm by a series.
        let tn = t0.dot(n);
        let pl = t0.sub(n.scale(tn));
        let x = mul(mul(tn, tn), inv_before);
        let series = add(one, mul(x, add(splat(0.5), mul(splat(0.375), x))));
        let mut t = pl.scale(series);
        let fresh = cmp::<_CMP_EQ_OQ>(before, zero);
        let far = cmp::<_CMP_NLT_UQ>(x, splat(1e-5));
        if any(and_not(and(touch, far), fresh)) {
            let after = pl.dot(pl);
            let exact = pl.scale(sqrt(div(before, after)));
            let exact = exact.pick(V([zero; 3]), cmp::<_CMP_EQ_OQ>(after, zero));
            t = t.pick(exact, far);
        }
        t = t.pick(t0, fresh);
        // Pivoting about n (D3::pivot): Taylor series below 1e-3 rad, sin_cos above.
        let a2 = mul(pivot, pivot);
        let mut sn = mul(pivot, sub(one, div(a2, splat(6.0))));
        let mut cs = sub(
            one,
            mul(mul(splat(0.5), a2), sub(one, div(a2, splat(12.0)))),
        );
        let abs = and_not(pivot, splat(-0.0));
        let wide = cmp::<_CMP_NLT_UQ>(abs, splat(1e-3));
        if any(and(touch, wide)) {
            let (angle, wide) = (to(pivot), to(wide));
            let (mut s4, mut c4) = (to(sn), to(cs));
            for l in 0..W {
                if wide[l].to_bits() != 0 {
                    (s4[l], c4[l]) = angle[l].sin_cos();
                }
            }
            (sn, cs) = (from(s4), from(c4));
        }
        t = t.scale(cs).add(n.cross(t).scale(sn));
        // AR07 App. A: scaled down, never up (min returns 1 where the ratio is NaN).
        t = t.scale(min(mul(kt, inv_kt), one));
        t = t.sub(slip.scale(kt));
        if CAP {
            // Coulomb: |T| ≤ μ max(N_e, 0).
            let cap = mul(splat(law.mu), max(ne, zero));
            let t2 = t.dot(t);
            let over = cmp::<_CMP_GT_OQ>(t2, mul(cap, cap));
            if any(over) {
                t = t.pick(t.scale(div(cap, sqrt(t2))), over);
            }
        }
        let f = n.scale(normal).add(t);
        let c = n.cross(t);

        let touch = to(touch);
        let (t, kt, f, c) = (t.lanes(), to(kt), f.lanes(), c.lanes());
        let (gap, rmin) = (to(gap), to(min(ri, rj)));
        for l in 0..live {
            let k = kk[l];
            // The virial takes the lane's force from registers: reading `ch.f[k]` back
            // straddles the two stores that wrote it and stalls store forwarding.
            let fk = if touch[l].to_bits() != 0 {
                ch.hist[k] = Spring { t: t[l], kt: kt[l] };
                ch.c[k] = c[l];
                f[l]
            } else {
                ch.hist[k] = Spring::default();
                ch.c[k] = V3::zeros();
                V3::zeros()
            };
            ch.f[k] = fk;
            for (a, row) in sum.0.iter_mut().enumerate() {
                for (b, x) in row.iter_mut().enumerate() {
                    *x += fk[a] * rb[b][l];
                }
            }
            if -gap[l] > sum.1 .0 * rmin[l] || gap[l].is_nan() {
                sum.1 = (-gap[l] / rmin[l], ii[l] as u32, jj[l] as u32);
            }
        }
    }
}
