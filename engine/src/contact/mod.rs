//! Contact laws. Each law is a type implementing [`ContactLaw`]; the features a scene does not
//! use (friction, rolling resistance, cohesion) are type parameters that compile to nothing,
//! so a frictionless scene runs a kernel with no tangential state at all.
//!
//! - [`hertz_mindlin::HertzMindlin`]: AR07 (1)–(5), App. A (Walton rescaling), App. B (transport);
//!   its cohesion models (one file each):
//!   - [`sjkr::Sjkr`]: LIGGGHTS 3.8's `cohesion sjkr` (attraction ∝ the area of the contact
//!     circle), the cohesive law a LIGGGHTS run reproduces exactly;
//!   - [`dmt::Dmt`]: YADE's DMT adhesion (a constant pull 4πR*γ in contact), the cohesive law a
//!     YADE run reproduces exactly;
//!   - [`hertz_mindlin_avx`]: its force pass for 3D frictional spheres, four pairs at a time
//!     (AVX), bit for bit the scalar one; the law's [`ContactLaw::force_batch`].
//! - [`linear::Linear`]: GRC07 (4)–(10): spring–dashpot–Coulomb with optional adhesion and
//!   rolling resistance; with no adhesion it is the classic cohesionless linear law.
//! - [`slider`]: the elastic-plastic sliders (Coulomb and rolling) shared by them.
//! - [`batch`]: what a batch kernel reads and writes, and whether runs use them.
//! - [`from_scene`]: the law of a scene's `[law]` table, in reduced units: its type and its
//!   numbers, chosen in one place ([`from_scene::with_law`]).

pub mod batch;
pub mod dmt;
pub mod from_scene;
pub mod hertz_mindlin;
pub mod hertz_mindlin_avx;
pub mod linear;
pub mod sjkr;
pub mod slider;

use crate::geometry::Dim;
use batch::{ChunkSum, PairChunk};

/// Kinematics of one pair, as seen by the law. `n` points from i to j.
#[derive(Clone, Copy, Debug)]
pub struct Pair<D: Dim> {
    /// Unit normal from i to j.
    pub n: D::V,
    /// Surface gap h = |r_ij| − R_i − R_j (negative: overlap).
    pub gap: f64,
    /// Relative velocity of the contact point of j with respect to i.
    pub v_contact: D::V,
    /// Angular velocities.
    pub w_i: D::Ang,
    pub w_j: D::Ang,
    /// Reduced radius R_i R_j/(R_i+R_j) and reduced mass m_i m_j/(m_i+m_j).
    pub r_eff: f64,
    pub m_eff: f64,
    /// R_i + R_j (the centre distance is `r_sum + gap`).
    pub r_sum: f64,
}

/// What a law returns for one pair.
#[derive(Clone, Copy, Debug, Default)]
pub struct PairForce<D: Dim> {
    /// Total normal force N (repulsive positive), along n, exerted by i on j.
    pub normal: f64,
    /// Elastic repulsive part N_e (threshold of the sliders).
    pub normal_elastic: f64,
    /// Tangential force exerted by i on j.
    pub tangential: D::V,
    /// Rolling moment exerted by i on j.
    pub rolling: D::Ang,
}

/// What a per-pair state (contact history, spring) must be: plain data, shared across
/// threads, and saved in checkpoints.
pub trait PairState:
    Copy
    + Default
    + Send
    + Sync
    + std::fmt::Debug
    + serde::Serialize
    + serde::de::DeserializeOwned
    + 'static
{
}

impl<T> PairState for T where
    T: Copy
        + Default
        + Send
        + Sync
        + std::fmt::Debug
        + serde::Serialize
        + serde::de::DeserializeOwned
        + 'static
{
}

/// A contact (interaction) law.
pub trait ContactLaw<D: Dim>: Copy + Send + Sync + std::fmt::Debug + 'static {
    /// Per-pair history (tangential spring, rolling spring); `()` when there is none.
    type History: PairState;
    /// Does the law exert moments (friction or rolling resistance)? If not, rotations are not
    /// integrated at all.
    const MOMENTS: bool;
    /// Does the law have rolling resistance?
    const ROLLING: bool;
    /// Largest gap at which two grains still interact (0 for contact-only laws).
    fn range(&self) -> f64;
    /// Force for one pair; `hist` is reset by the caller's law when the pair is not in contact.
    fn interact(&self, p: &Pair<D>, hist: &mut Self::History, dt: f64) -> PairForce<D>;
    /// Stiffest normal stiffness to expect, for the time step (`force` is the largest normal
    /// force expected, in force units).
    fn max_stiffness(&self, force: f64, r_eff_max: f64) -> f64;
    /// Short description for logs (`hertz-mindlin μ=0.3 ζ=0.98 …`).
    fn describe(&self) -> String;
    /// The same law with the stiffness parameter κ multiplied by `factor` (GRC07 §III.B.2:
    /// κ ramps); `factor = 1` returns the law unchanged, bit for bit.
    fn with_kappa_scaled(&self, factor: f64) -> Self;
    /// The same law with tangential and rolling dashpots of `zeta_t` (fraction of critical;
    /// the final relaxation of a stage, engine/src/run/relax.rs). Laws without them
    /// (Hertz–Mindlin, AR07 §II.A has no tangential viscosity) return themselves; the scene
    /// validator refuses `relax.tangential_zeta` > 0 for them.
    fn with_tangential_damping(&self, _zeta_t: f64) -> Self {
        *self
    }
    /// The same law without its normal dashpot (ζ = 0): FIRE's phase of a final relaxation
    /// (engine/src/run/fire.rs), where the velocity resets dissipate and the dashpot would
    /// only lower the stable time step; it exerts no force at rest, so the equilibria are
    /// the law's.
    fn without_normal_damping(&self) -> Self;
    /// Tangential force and rolling moment stored in the history (for snapshots).
    fn stored(&self, hist: &Self::History) -> (D::V, D::Ang);
    /// The force pass over `chunk` by the law's batch kernel, where it has one for this
    /// dimension and this CPU: it writes bit for bit what [`ContactLaw::interact`] gives pair
    /// by pair. `None` leaves the chunk to the per-pair path, the reference.
    fn force_batch(&self, _chunk: &mut PairChunk<'_, D, Self::History>) -> Option<ChunkSum> {
        None
    }
}
