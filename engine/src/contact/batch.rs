//! What a law's batch force kernel reads and writes ([`super::ContactLaw::force_batch`]), and
//! whether runs use such kernels at all. A batch kernel computes several pairs per instruction
//! (SIMD) and must write bit for bit what the per-pair path writes, which stays the reference.

use crate::geometry::{Dim, Tensor};

/// One chunk of rows of the force pass: the grains' state, the chunk's rows of the neighbour
/// list, and its slices of the per-pair arrays (history, force exerted by i on j, n × T). A
/// law with rolling resistance has no batch kernel: its moments are not in the chunk.
pub struct PairChunk<'a, D: Dim, H> {
    pub rows: std::ops::Range<usize>,
    /// Index of the chunk's first pair in the neighbour list.
    pub first: usize,
    pub row_start: &'a [u32],
    pub partner: &'a [u32],
    pub s: &'a [D::V],
    pub u: &'a [D::V],
    pub w: &'a [D::Ang],
    pub radius: &'a [f64],
    pub mass: &'a [f64],
    /// Cell lengths and the strain rate of the velocity field (`Cell::velocity_strain_rate`).
    pub l: D::V,
    pub erate: D::V,
    pub dt: f64,
    pub hist: &'a mut [H],
    pub f: &'a mut [D::V],
    pub c: &'a mut [D::Ang],
}

/// What a force pass over a chunk sums: the contact virial Σ f ⊗ r, and the largest overlap
/// relative to the smaller radius with its pair.
pub type ChunkSum = (Tensor, (f64, u32, u32));

/// Does this CPU run the batch kernels (AVX)?
pub fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Should a new system use the batch kernels: where the CPU runs them, unless the environment
/// sets `GRAINBENCH_SCALAR` (any value), which keeps every run on the per-pair reference path.
pub fn wanted() -> bool {
    available() && std::env::var_os("GRAINBENCH_SCALAR").is_none()
}
