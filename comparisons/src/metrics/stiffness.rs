//! The stiffness matrix of a contact network (GRC07 App. A; GRC08 §II.D.3).
//!
//! Degrees of freedom, GRC07 (A1): each grain's displacement ũ_i (the part not due to the
//! global strain) and, where the law has moments, its rotation Δθ_i; with
//! [`Network::build`]'s `strain`, the cell's d diagonal strains ε_α last (GRC08: "order
//! 3N + 2"). Constraints, GRC07 (A2)–(A3): the relative displacement of the contact point of j
//! with respect to that of i,
//!
//! `δu = ũ_j − ũ_i + ε·r_ij + n × (R_i Δθ_i + R_j Δθ_j)`
//!
//! (r_ij the branch vector, n = r_ij/|r_ij|; ε extension-positive) split into its normal part
//! (every interaction), its tangential part (contacts, with friction) and the relative rotation
//! Δθ_j − Δθ_i, less its twist about n in 3D (contacts, with rolling resistance; the engine's
//! rolling spring, GRC07 (9)). Distant attractions constrain the normal part only, with the
//! negative stiffness −F0/D0 (GRC08 §II.D.3). K = ᵀG·𝒦·G, GRC07 (A6), without the small
//! geometric correction of the forces already carried (GRC07 App. A, AR07 App. B).

use grainbench_engine::snapshot::{Contact, Snapshot};
use serde::Serialize;

/// The normal stiffness of a contact.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum NormalStiffness {
    /// The linear law's K_N (GRC07 (5)).
    Constant(f64),
    /// Hertz's tangent stiffness K_N = Ẽ √(R* h) at the contact's overlap h (AR07 (2)).
    Hertz { e_tilde: f64 },
}

/// Contact stiffnesses of a law, in the snapshot's reduced units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ContactStiffness {
    pub normal: NormalStiffness,
    /// K_T/K_N (GRC07: 1; AR07 (3): (2−2ν)/(2−ν)); `None` without friction (μ = 0): no
    /// tangential constraint, and rotations are left out (GRC07 App. A, AR07 §II.C).
    pub tangential_ratio: Option<f64>,
    /// K_r (GRC07 (9), K_r = kr·K_N a²); `None` without rolling resistance.
    pub rolling: Option<f64>,
    /// F0/D0 (GRC07 (4)): a distant attraction's normal stiffness is −F0/D0.
    pub attraction: Option<f64>,
}

impl ContactStiffness {
    /// Does the network carry moments (rotational degrees of freedom)?
    pub fn rotations(&self) -> bool {
        self.tangential_ratio.is_some() || self.rolling.is_some()
    }
}

/// What a constraint restrains.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Normal,
    Tangential,
    Rolling,
}

/// One row of the rigidity matrix G with its stiffness.
#[derive(Clone, Debug)]
pub struct Constraint {
    /// Index of the interaction (in the list given to [`Network::build`]).
    pub contact: usize,
    pub kind: Kind,
    /// Stiffness (K_N, −F0/D0, K_T or K_r).
    pub k: f64,
    /// Non-zero entries (degree of freedom, coefficient).
    pub entries: Vec<(usize, f64)>,
}

/// The degrees of freedom and constraints of a contact network.
#[derive(Clone, Debug)]
pub struct Network {
    pub dimension: usize,
    /// Snapshot indices of the grains that carry degrees of freedom (those with an
    /// interaction), in order; grain `grains[g]` owns the dofs `g·per_grain ..`.
    pub grains: Vec<usize>,
    /// Degrees of freedom per grain: d translations, and 1 (2D) or 3 (3D) rotations.
    pub per_grain: usize,
    /// Are the cell's d diagonal strains the last degrees of freedom?
    pub strain: bool,
    pub dofs: usize,
    pub constraints: Vec<Constraint>,
    /// Interactions given, and how many of them were distant (positive gap).
    pub interactions: usize,
    pub distant: usize,
}

impl Network {
    /// The network of `contacts` (interactions of `snap`) under the stiffnesses `law`.
    ///
    /// # Errors
    /// A contact between a grain and itself, or with a zero branch vector.
    pub fn build(
        snap: &Snapshot,
        contacts: &[&Contact],
        law: &ContactStiffness,
        strain: bool,
    ) -> Result<Network, String> {
        let d = snap.dimension;
        let n = snap.particles.radius.len();
        let rot = if law.rotations() {
            if d == 2 {
                1
            } else {
                3
            }
        } else {
            0
        };
        let per_grain = d + rot;
        let mut slot = vec![usize::MAX; n];
        let mut grains = Vec::new();
        for c in contacts {
            for g in [c.i, c.j] {
                if slot[g] == usize::MAX {
                    slot[g] = grains.len();
                    grains.push(g);
                }
            }
        }
        let dofs = grains.len() * per_grain + if strain { d } else { 0 };
        let eps0 = grains.len() * per_grain;
        let radius = &snap.particles.radius;
        let mut constraints = Vec::new();
        let mut distant = 0;
        for (ci, c) in contacts.iter().enumerate() {
            if c.i == c.j {
                return Err(format!("interaction {ci} joins grain {} to itself", c.i));
            }
            let r = &c.branch;
            let len = r.iter().map(|x| x * x).sum::<f64>().sqrt();
            if len <= 0.0 || len.is_nan() {
                return Err(format!(
                    "interaction {ci} ({}–{}) has a zero branch vector",
                    c.i, c.j
                ));
            }
            let nv: Vec<f64> = r.iter().map(|x| x / len).collect();
            let (bi, bj) = (slot[c.i] * per_grain, slot[c.j] * per_grain);
            let (ri, rj) = (radius[c.i], radius[c.j]);
            // A row: δu·e for a unit vector e (translations and strains), plus rotations.
            let translation_row = |e: &[f64]| {
                let mut v = Vec::with_capacity(3 * d + 2 * rot);
                for a in 0..d {
                    v.push((bj + a, e[a]));
                    v.push((bi + a, -e[a]));
                    if strain {
                        v.push((eps0 + a, e[a] * r[a]));
                    }
                }
                v
            };
            let contact = c.gap < 0.0;
            let kn = if contact {
                match law.normal {
                    NormalStiffness::Constant(k) => k,
                    NormalStiffness::Hertz { e_tilde } => {
                        e_tilde * (ri * rj / (ri + rj) * (-c.gap)).sqrt()
                    }
                }
            } else {
                distant += 1;
                match law.attraction {
                    Some(a) => -a,
                    // A listed pair at a gap without attraction carries nothing.
                    None => continue,
                }
            };
            constraints.push(Constraint {
                contact: ci,
                kind: Kind::Normal,
                k: kn,
                entries: translation_row(&nv),
            });
            if !contact {
                continue;
            }
            if let Some(ratio) = law.tangential_ratio {
                for t in tangents(&nv) {
                    let mut row = translation_row(&t);
                    // δu·t from n × (R_i θ_i + R_j θ_j): (n × w)·t = w·(t × n).
                    let txn = cross_or_scalar(&t, &nv);
                    for (b, rr) in [(bi, ri), (bj, rj)] {
                        for (q, x) in txn.iter().enumerate() {
                            row.push((b + d + q, rr * x));
                        }
                    }
                    constraints.push(Constraint {
                        contact: ci,
                        kind: Kind::Tangential,
                        k: kn * ratio,
                        entries: row,
                    });
                }
            }
            if let Some(kr) = law.rolling {
                // Δθ_j − Δθ_i: the scalar in 2D, its two components across n in 3D.
                let axes: Vec<Vec<f64>> = if d == 2 {
                    vec![vec![1.0]]
                } else {
                    tangents(&nv)
                };
                for e in axes {
                    let mut row = Vec::with_capacity(2 * rot);
                    for (q, x) in e.iter().enumerate() {
                        row.push((bj + d + q, *x));
                        row.push((bi + d + q, -x));
                    }
                    constraints.push(Constraint {
                        contact: ci,
                        kind: Kind::Rolling,
                        k: kr,
                        entries: row,
                    });
                }
            }
        }
        Ok(Network {
            dimension: d,
            grains,
            per_grain,
            strain,
            dofs,
            constraints,
            interactions: contacts.len(),
            distant,
        })
    }

    /// First strain degree of freedom (`dofs − d`), if the strains are included.
    pub fn strain_dof(&self) -> Option<usize> {
        self.strain.then(|| self.dofs - self.dimension)
    }

    /// Upper-and-lower entries of K = ᵀG·𝒦·G, duplicates summed, sorted by (column, row);
    /// with `unit`, every stiffness is 1 (ᵀG·G: the same null space, for counting).
    pub fn matrix(&self, unit: bool) -> Vec<(usize, usize, f64)> {
        let mut t = Vec::new();
        for c in &self.constraints {
            let k = if unit { 1.0 } else { c.k };
            for &(a, ga) in &c.entries {
                for &(b, gb) in &c.entries {
                    t.push((b, a, k * ga * gb));
                }
            }
        }
        t.sort_unstable_by_key(|&(r, c, _)| (c, r));
        let mut out: Vec<(usize, usize, f64)> = Vec::with_capacity(t.len() / 2);
        for (r, c, v) in t {
            match out.last_mut() {
                Some(last) if last.0 == r && last.1 == c => last.2 += v,
                _ => out.push((r, c, v)),
            }
        }
        out
    }

    /// The constraint values G·U.
    pub fn deformation(&self, u: &[f64]) -> Vec<f64> {
        self.constraints
            .iter()
            .map(|c| c.entries.iter().map(|&(a, g)| g * u[a]).sum())
            .collect()
    }
}

/// Orthonormal tangents to the unit normal n: one in 2D (n rotated by +90°), two in 3D.
fn tangents(n: &[f64]) -> Vec<Vec<f64>> {
    if n.len() == 2 {
        return vec![vec![-n[1], n[0]]];
    }
    // The axis least aligned with n, made orthogonal to it.
    let k = (0..3)
        .min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
        .unwrap_or(0);
    let mut t1 = vec![0.0; 3];
    t1[k] = 1.0;
    let dot = n[k];
    for a in 0..3 {
        t1[a] -= dot * n[a];
    }
    let l = t1.iter().map(|x| x * x).sum::<f64>().sqrt();
    t1.iter_mut().for_each(|x| *x /= l);
    let t2 = vec![
        n[1] * t1[2] - n[2] * t1[1],
        n[2] * t1[0] - n[0] * t1[2],
        n[0] * t1[1] - n[1] * t1[0],
    ];
    vec![t1, t2]
}

/// t × n: a vector in 3D, its z component (one entry) in 2D.
fn cross_or_scalar(t: &[f64], n: &[f64]) -> Vec<f64> {
    if t.len() == 2 {
        vec![t[0] * n[1] - t[1] * n[0]]
    } else {
        vec![
            t[1] * n[2] - t[2] * n[1],
            t[2] * n[0] - t[0] * n[2],
            t[0] * n[1] - t[1] * n[0],
        ]
    }
}

/// Mechanisms and force indeterminacy of a network with the cell fixed (GRC07 App. A:
/// N_f + H = M + K).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Rigidity {
    /// N_f: degrees of freedom of the grains with an interaction.
    pub dofs: usize,
    /// M: constraint components (normal, tangential, rolling).
    pub constraints: usize,
    /// Rank of G.
    pub rank: usize,
    /// K = N_f − rank: mechanisms (floppy modes), the d global translations included
    /// (GRC07 (19)–(21); an isolated rigid cluster in 2D has K = 3).
    pub mechanisms: usize,
    /// H = M − rank: the degree of force indeterminacy (hyperstaticity).
    pub indeterminacy: usize,
    /// How the zero eigenvalues were counted.
    pub method: RankMethod,
}

/// The most degrees of freedom [`rigidity`] counts with the dense eigenvalue solve (O(N_f³):
/// ~4200 for 1400 disks with rotations takes seconds); larger networks are counted by
/// [`zero_modes_sparse`].
pub const MAX_RIGIDITY_DOFS: usize = 6000;

/// How [`rigidity`] counted the zero eigenvalues of ᵀG·G.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RankMethod {
    /// All eigenvalues, dense (up to [`MAX_RIGIDITY_DOFS`]).
    DenseEigenvalues,
    /// Sylvester's inertia of a sparse LDLᵀ ([`zero_modes_sparse`]).
    SparseInertia,
}

/// Counts mechanisms and force indeterminacy from the eigenvalues of ᵀG·G (unit stiffnesses,
/// the cell fixed): eigenvalues below 1e-9 of the largest are zero. Dense up to
/// [`MAX_RIGIDITY_DOFS`], sparse above. `None` for a network without constraints, or if the
/// sparse factorization meets an exactly zero pivot.
pub fn rigidity(net: &Network) -> Option<Rigidity> {
    rigidity_by(net, None)
}

/// [`rigidity`] with the method forced (`None`: by size).
pub fn rigidity_by(net: &Network, method: Option<RankMethod>) -> Option<Rigidity> {
    if net.strain {
        return rigidity_by(
            &Network {
                strain: false,
                dofs: net.dofs - net.dimension,
                constraints: net
                    .constraints
                    .iter()
                    .map(|c| Constraint {
                        entries: c
                            .entries
                            .iter()
                            .copied()
                            .filter(|&(a, _)| a < net.dofs - net.dimension)
                            .collect(),
                        ..c.clone()
                    })
                    .collect(),
                ..net.clone()
            },
            method,
        );
    }
    let n = net.dofs;
    if n == 0 || net.constraints.is_empty() {
        return None;
    }
    let method = method.unwrap_or(if n <= MAX_RIGIDITY_DOFS {
        RankMethod::DenseEigenvalues
    } else {
        RankMethod::SparseInertia
    });
    let entries = net.matrix(true);
    let zero = match method {
        RankMethod::DenseEigenvalues => {
            let mut m = faer::Mat::<f64>::zeros(n, n);
            for &(r, c, v) in &entries {
                m[(r, c)] = v;
            }
            let ev = m.self_adjoint_eigenvalues(faer::Side::Lower).ok()?;
            let top = ev.iter().copied().fold(0.0, f64::max);
            ev.iter().filter(|&&x| x <= ZERO_EIGENVALUE * top).count()
        }
        RankMethod::SparseInertia => zero_modes_sparse(n, &entries)?,
    };
    let rank = n - zero;
    let constraints = net.constraints.len();
    Some(Rigidity {
        dofs: n,
        constraints,
        rank,
        mechanisms: zero,
        indeterminacy: constraints - rank,
        method,
    })
}

/// An eigenvalue of ᵀG·G at most this fraction of the largest counts as zero.
const ZERO_EIGENVALUE: f64 = 1e-9;

/// The eigenvalues of the symmetric positive semi-definite `n × n` matrix `entries` (both
/// triangles, as [`Network::matrix`]) at most 1e-9 of its largest, counted without computing
/// them: by Sylvester's law of inertia, the number of eigenvalues below τ is the number of
/// negative pivots of the LDLᵀ factorization of A − τI (any symmetric ordering; here AMD, a
/// simplicial factor, whose diagonal is D). The largest eigenvalue comes from power
/// iteration. `None` on an exactly zero pivot.
pub fn zero_modes_sparse(n: usize, entries: &[(usize, usize, f64)]) -> Option<usize> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
    use faer::sparse::linalg::cholesky::{
        factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering,
    };
    use faer::sparse::linalg::SupernodalThreshold;
    use faer::sparse::{SparseColMat, Triplet};
    use faer::{Par, Side};

    let tau = ZERO_EIGENVALUE * largest_eigenvalue(n, entries);
    let mut trip: Vec<Triplet<usize, usize, f64>> = entries
        .iter()
        .filter(|&&(r, c, _)| r > c)
        .map(|&(r, c, v)| Triplet::new(r, c, v))
        .collect();
    // The whole diagonal, shifted (a dof in no constraint has a zero one).
    let mut diagonal = vec![-tau; n];
    for &(r, c, v) in entries {
        if r == c {
            diagonal[r] += v;
        }
    }
    trip.extend(
        diagonal
            .iter()
            .enumerate()
            .map(|(a, &v)| Triplet::new(a, a, v)),
    );
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip).ok()?;
    let symbolic = factorize_symbolic_cholesky(
        a.symbolic(),
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        },
    )
    .ok()?;
    let mut values = vec![0.0; symbolic.len_val()];
    let mut buffer = MemBuffer::new(
        symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
    );
    symbolic
        .factorize_numeric_ldlt(
            &mut values,
            a.as_ref(),
            Side::Lower,
            LdltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut buffer),
            Default::default(),
        )
        .ok()?;
    let SymbolicCholeskyRaw::Simplicial(factor) = symbolic.raw() else {
        return None;
    };
    // Each column of the simplicial factor starts with its diagonal entry: D.
    let (start, row) = (factor.col_ptr(), factor.row_idx());
    let mut negative = 0;
    for j in 0..n {
        if row[start[j]] != j {
            return None;
        }
        if values[start[j]] < 0.0 {
            negative += 1;
        }
    }
    Some(negative)
}

/// The largest eigenvalue of a symmetric positive semi-definite matrix (both triangles), by
/// power iteration to 1e-3 (the zero threshold needs only its order of magnitude).
fn largest_eigenvalue(n: usize, entries: &[(usize, usize, f64)]) -> f64 {
    // A start with a component along every eigenvector, in practice.
    let mut x: Vec<f64> = (0..n)
        .map(|a| 1.0 + ((a * 7919) % 101) as f64 / 101.0)
        .collect();
    let mut y = vec![0.0; n];
    let mut lambda = 0.0;
    for _ in 0..1000 {
        let norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm == 0.0 {
            return 0.0;
        }
        x.iter_mut().for_each(|v| *v /= norm);
        y.iter_mut().for_each(|v| *v = 0.0);
        for &(r, c, v) in entries {
            y[r] += v * x[c];
        }
        let next: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
        std::mem::swap(&mut x, &mut y);
        if (next - lambda).abs() <= 1e-3 * next {
            return next;
        }
        lambda = next;
    }
    lambda
}

impl ContactStiffness {
    /// The stiffnesses of `scene`'s law for `snap`: the κ of the scene's last stage, the
    /// snapshot's μ.
    ///
    /// # Errors
    /// A scene of another dimension than the snapshot's, or a law [`Self::of_law`] refuses.
    pub fn of_scene(
        scene: &grainbench_engine::Scene,
        snap: &grainbench_engine::Snapshot,
    ) -> Result<Self, String> {
        if scene.dimension != snap.dimension {
            return Err(format!(
                "a {}D scene for a {}D snapshot",
                scene.dimension, snap.dimension
            ));
        }
        let kappa = scene
            .protocol
            .last()
            .and_then(|s| s.kappa())
            .unwrap_or_else(|| scene.law.kappa());
        Self::of_law(&scene.law, kappa, snap.mu)
    }

    /// The stiffnesses of a scene's law at stiffness `kappa` (a stage's override, or
    /// `law.kappa`) and friction `mu` (the snapshot's; `None` is μ = ∞), in reduced units:
    /// linear law K_N = κ, K_T = κ·kt_over_kn, K_r = kr·κ, F0/D0 = 1/D0 (GRC07 §II.C);
    /// Hertz–Mindlin Ẽ = κ^{3/2}, K_T/K_N = (2−2ν)/(2−ν) (AR07 (2)–(3), (21)).
    ///
    /// # Errors
    /// Hertz–Mindlin with a cohesion model (its attraction's stiffness is not modelled here).
    pub fn of_law(
        law: &grainbench_engine::scene::Law,
        kappa: f64,
        mu: Option<f64>,
    ) -> Result<Self, String> {
        use grainbench_engine::contact::from_scene::hertz_mindlin_law;
        use grainbench_engine::contact::slider::Frictionless;
        use grainbench_engine::scene::Law;
        let friction = mu != Some(0.0);
        match law {
            Law::Linear {
                kt_over_kn,
                cohesion,
                rolling,
                ..
            } => Ok(ContactStiffness {
                normal: NormalStiffness::Constant(kappa),
                tangential_ratio: friction.then_some(*kt_over_kn),
                rolling: rolling.map(|r| r.kr * kappa),
                attraction: cohesion.map(|c| 1.0 / c.d0),
            }),
            Law::HertzMindlin { sjkr, dmt, .. } => {
                if sjkr.is_some() || dmt.is_some() {
                    return Err("elastic moduli: the stiffness of the sjkr/dmt attraction is not modelled; only cohesionless Hertz–Mindlin and the linear law are".into());
                }
                let hm = hertz_mindlin_law(law, Frictionless);
                Ok(ContactStiffness {
                    normal: NormalStiffness::Hertz {
                        // Ẽ ∝ κ^{3/2} (AR07 (21)).
                        e_tilde: hm.e_tilde * (kappa / law.kappa()).powf(1.5),
                    },
                    tangential_ratio: friction.then_some(hm.kt_ratio),
                    rolling: None,
                    attraction: None,
                })
            }
        }
    }
}
