//! Elastic moduli of an equilibrated packing from the stiffness matrix of its contact network
//! (GRC08 §II.D.3 eq. (6), §VI), with the Voigt and Reuss estimates (GRC08 (12)–(14)) and the
//! concentration of the elastic energy of a pressure increment (GRC08 §VI.E).
//!
//! K·U = F^ext (GRC08 (6)) is solved with F^ext = V·Δσ on the strains and no load on the
//! grains, once for each unit Δσ_α, by a sparse Cholesky factorization (faer). Floppy modes
//! that the load does not excite (free rolling of one-contact grains, global translations)
//! get the energy cost 1e-10 × the largest diagonal entry, as AR07 §IV.D does: the response to a
//! stress increment changes by that relative amount, unless a mechanism moves the cell, where
//! the modulus comes out ≈ 0, as it is.

use super::stiffness::{rigidity, ContactStiffness, Network, Rigidity};
use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use grainbench_engine::snapshot::{Contact, Snapshot};
use nalgebra::DMatrix;
use serde::Serialize;

/// Regularisation of floppy modes, relative to the largest diagonal entry of each block.
pub const FLOPPY_COST: f64 = 1e-10;

/// The elastic response of one snapshot.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Moduli {
    /// C_αβ = ∂σ_α/∂ε_β over the diagonal strains (d × d; extension and tension positive),
    /// in force unit / a^(d−1).
    pub stiffness: Vec<Vec<f64>>,
    /// B = (1/d²) Σ_αβ C_αβ: (C11 + C12)/2 in 2D (GRC08 §II.D.3), (C11 + 2C12)/3 in 3D.
    pub bulk: f64,
    /// G = (C11 − C12)/2, C11 and C12 averaged over the axes (GRC08 §II.D.3).
    pub shear: f64,
    /// Voigt estimates (GRC08 (12), without its approximations): grain centres follow the
    /// strain, no rotation — the strain block of K over the volume.
    pub voigt_bulk: f64,
    pub voigt_shear: f64,
    /// Reuss estimate (GRC08 (13)–(14), without its approximations): trial force increments
    /// proportional to the forces carried, B^R = V P² / Σ_c (N²/K_N + T²/K_T + Γ²/K_r), the
    /// sum over contacts; `None` unless P > 0 and some contact is stressed.
    pub reuss_bulk: Option<f64>,
    /// Fraction of the contacts that carry 95 % of the elastic energy of the response to an
    /// isotropic pressure increment, largest first (GRC08 §VI.E: 46 % loose cohesive, ~65 %
    /// dense, 68–70 % cohesionless).
    pub energy_95: Option<f64>,
    /// Interactions, distant ones among them, degrees of freedom of the solve.
    pub interactions: usize,
    pub distant: usize,
    pub dofs: usize,
    /// Mechanisms and force indeterminacy with the cell fixed (GRC07 App. A); `None` when not
    /// asked for.
    pub rigidity: Option<Rigidity>,
}

/// The moduli of `snap` carried by the interactions `contacts` (the backbone) under `law`,
/// with the network's mechanisms and force indeterminacy when `with_rigidity` (a dense rank up
/// to [`super::stiffness::MAX_RIGIDITY_DOFS`], seconds at a few thousand degrees of freedom
/// where the moduli take a fraction of one; a sparse inertia count above).
///
/// # Errors
/// No interaction; a degenerate contact; a stiffness matrix that is not positive definite
/// (an unstable state: distant attractions stiffer than the contacts around them).
pub fn elastic_moduli(
    snap: &Snapshot,
    contacts: &[&Contact],
    law: &ContactStiffness,
    with_rigidity: bool,
) -> Result<Moduli, String> {
    let d = snap.dimension;
    if contacts.is_empty() {
        return Err("no interaction to carry a load".into());
    }
    let net = Network::build(snap, contacts, law, true)?;
    let eps0 = net.strain_dof().unwrap_or(net.dofs);
    let volume: f64 = snap.cell.lengths.iter().product();
    let mut entries = net.matrix(false);
    // Voigt: the strain block alone, before the floppy-mode cost below.
    let mut voigt = vec![vec![0.0; d]; d];
    for &(r, c, v) in &entries {
        if r >= eps0 && c >= eps0 {
            voigt[r - eps0][c - eps0] = v / volume;
        }
    }

    // Floppy modes: a small cost on every diagonal entry, per block.
    let mut top = [0.0_f64; 2];
    for &(r, c, v) in &entries {
        if r == c {
            let b = usize::from(r >= eps0);
            top[b] = top[b].max(v);
        }
    }
    let mut diag_seen = vec![false; net.dofs];
    for e in entries.iter_mut() {
        if e.0 == e.1 {
            e.2 += FLOPPY_COST * top[usize::from(e.0 >= eps0)].max(f64::MIN_POSITIVE);
            diag_seen[e.0] = true;
        }
    }
    for (a, seen) in diag_seen.iter().enumerate() {
        if !seen {
            let cost = FLOPPY_COST * top[usize::from(a >= eps0)].max(f64::MIN_POSITIVE);
            entries.push((a, a, cost));
        }
    }
    let trip: Vec<Triplet<usize, usize, f64>> = entries
        .iter()
        .map(|&(r, c, v)| Triplet::new(r, c, v))
        .collect();
    let k = SparseColMat::<usize, f64>::try_new_from_triplets(net.dofs, net.dofs, &trip)
        .map_err(|e| format!("assembling the stiffness matrix: {e:?}"))?;
    let llt = k.sp_cholesky(faer::Side::Lower).map_err(|_| {
        "the stiffness matrix is not positive definite: the state is not a stable equilibrium \
         (GRC07 App. A)"
            .to_string()
    })?;

    // One solve per unit stress Δσ_α (work V Δσ_α ε_α).
    let mut rhs = faer::Mat::<f64>::zeros(net.dofs, d);
    for a in 0..d {
        rhs[(eps0 + a, a)] = volume;
    }
    let u = llt.solve(&rhs);
    let compliance = DMatrix::from_fn(d, d, |b, a| u[(eps0 + b, a)]);
    let c = compliance
        .try_inverse()
        .ok_or("the compliance matrix is singular")?;
    let stiffness: Vec<Vec<f64>> = (0..d)
        .map(|a| (0..d).map(|b| c[(a, b)]).collect())
        .collect();
    let (bulk, shear) = bulk_shear(&stiffness);

    let (voigt_bulk, voigt_shear) = bulk_shear(&voigt);

    // GRC08 §VI.E: the response to an isotropic pressure increment (Δσ_α = −1).
    let iso: Vec<f64> = (0..net.dofs)
        .map(|r| -(0..d).map(|a| u[(r, a)]).sum::<f64>())
        .collect();
    let energy_95 = energy_concentration(&net, &net.deformation(&iso), 0.95);

    Ok(Moduli {
        stiffness,
        bulk,
        shear,
        voigt_bulk,
        voigt_shear,
        reuss_bulk: reuss_bulk(snap, contacts, &net, volume),
        energy_95,
        interactions: net.interactions,
        distant: net.distant,
        dofs: net.dofs,
        rigidity: if with_rigidity { rigidity(&net) } else { None },
    })
}

/// B = (1/d²) Σ C_αβ, G = (C̄11 − C̄12)/2 with the diagonal and off-diagonal means.
fn bulk_shear(c: &[Vec<f64>]) -> (f64, f64) {
    let d = c.len() as f64;
    let all: f64 = c.iter().flatten().sum();
    let diag: f64 = (0..c.len()).map(|a| c[a][a]).sum::<f64>() / d;
    let off = (all - diag * d) / (d * d - d);
    (all / (d * d), (diag - off) / 2.0)
}

/// Fraction of contacts that carry `share` of the elastic energy of the deformation `delta`
/// (one value per constraint), largest first. Distant attractions (negative stiffness) are
/// left out.
fn energy_concentration(net: &Network, delta: &[f64], share: f64) -> Option<f64> {
    let mut per = vec![0.0; net.interactions];
    let mut stiff = vec![false; net.interactions];
    for (c, x) in net.constraints.iter().zip(delta) {
        if c.k > 0.0 {
            per[c.contact] += 0.5 * c.k * x * x;
            stiff[c.contact] = true;
        }
    }
    let mut e: Vec<f64> = per
        .into_iter()
        .zip(&stiff)
        .filter(|(_, &s)| s)
        .map(|(e, _)| e)
        .collect();
    let total: f64 = e.iter().sum();
    if e.is_empty() || total <= 0.0 || total.is_nan() {
        return None;
    }
    e.sort_unstable_by(|a, b| b.total_cmp(a));
    let mut acc = 0.0;
    let count = e
        .iter()
        .take_while(|&&x| {
            let before = acc;
            acc += x;
            before < share * total
        })
        .count();
    Some(count as f64 / e.len() as f64)
}

/// GRC08 (13)–(14) in exact form: V P² / Σ_c (N²/K_N + |T|²/K_T + |Γ|²/K_r), over contacts.
fn reuss_bulk(snap: &Snapshot, contacts: &[&Contact], net: &Network, volume: f64) -> Option<f64> {
    let d = snap.dimension;
    let p = (0..d).map(|a| snap.cell.contact_stress[a][a]).sum::<f64>() / d as f64;
    // The stiffness of each kind on each contact (tangential and rolling components share it).
    let mut k = vec![[0.0_f64; 3]; net.interactions];
    for c in net.constraints.iter().filter(|c| c.k > 0.0) {
        k[c.contact][c.kind as usize] = c.k;
    }
    let sq = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>();
    let sum: f64 = contacts
        .iter()
        .zip(&k)
        .map(|(c, k)| {
            let term = |x: f64, k: f64| if k > 0.0 { x / k } else { 0.0 };
            term(c.normal * c.normal, k[0])
                + term(sq(&c.tangential), k[1])
                + term(sq(&c.rolling), k[2])
        })
        .sum();
    (p > 0.0 && sum > 0.0).then(|| volume * p * p / sum)
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::{bond, lattice, snapshot, Bond};
    use super::super::stiffness::{rigidity_by, NormalStiffness, RankMethod, Rigidity};
    use super::*;

    fn linear(kn: f64, kt: Option<f64>, kr: Option<f64>) -> ContactStiffness {
        ContactStiffness {
            normal: NormalStiffness::Constant(kn),
            tangential_ratio: kt.map(|kt| kt / kn),
            rolling: kr,
            attraction: None,
        }
    }

    fn moduli_of(snap: &Snapshot, law: &ContactStiffness) -> Moduli {
        let all: Vec<&Contact> = snap.contacts.iter().collect();
        elastic_moduli(snap, &all, law, true).unwrap()
    }

    fn close(x: f64, y: f64, rel: f64) -> bool {
        (x - y).abs() <= rel * y.abs().max(1e-300)
    }

    /// Square lattice, contacts along x and y: affine, C11 = K_N, C12 = 0 whatever K_T.
    #[test]
    fn square_lattice_known_moduli() {
        let (l, r, p, b) = lattice(2, 4, 0.99, 0.5, 1.0);
        let snap = snapshot(l, r, p, &b, false, Some(0.5));
        let m = moduli_of(&snap, &linear(100.0, Some(70.0), None));
        assert!(close(m.stiffness[0][0], 100.0, 1e-8), "{:?}", m.stiffness);
        assert!(m.stiffness[0][1].abs() < 1e-6);
        assert!(close(m.bulk, 50.0, 1e-8) && close(m.shear, 50.0, 1e-8));
        assert!(close(m.voigt_bulk, m.bulk, 1e-8));
        // Equal forces: the Reuss bound is exact, B^R = V P²/(N_c N²/K_N) = K_N/2.
        assert!(close(m.reuss_bulk.unwrap(), 50.0, 1e-12));
        // Every contact carries the same energy: ⌈0.95·32⌉ = 31 of 32.
        assert_eq!(m.energy_95, Some(31.0 / 32.0));
    }

    /// Periodic triangular lattice (k × k, k even) of spacing s, one bond per neighbour pair.
    fn triangular(k: usize, s: f64) -> (Vec<f64>, Vec<f64>, Vec<Vec<f64>>, Vec<Bond>) {
        let h = s * 3f64.sqrt() / 2.0;
        let idx = |x: usize, y: usize| (y % k) * k + (x % k);
        let mut p = Vec::new();
        let mut b = Vec::new();
        for y in 0..k {
            for x in 0..k {
                let shift = if y % 2 == 1 { 0.5 * s } else { 0.0 };
                p.push(vec![x as f64 * s + shift, y as f64 * h]);
                // +x, and the two neighbours of the row above.
                let (ul, ur) = if y % 2 == 0 {
                    (x + k - 1, x)
                } else {
                    (x, x + 1)
                };
                b.push(bond(idx(x, y), idx(x + 1, y), 1.0));
                b.push(bond(idx(x, y), idx(ul, y + 1), 1.0));
                b.push(bond(idx(x, y), idx(ur, y + 1), 1.0));
            }
        }
        (vec![k as f64 * s, k as f64 * h], vec![0.5; k * k], p, b)
    }

    /// C11 = √3(3K_N + K_T)/4, C12 = √3(K_N − K_T)/4: B = √3 K_N/2 and
    /// G = √3(K_N + K_T)/4, which are GRC08 (12)'s Voigt values at z = 6, Φ = π/(2√3).
    #[test]
    fn triangular_lattice_known_moduli() {
        let (kn, kt) = (100.0, 50.0);
        let (l, r, p, b) = triangular(4, 0.99);
        let snap = snapshot(l, r, p, &b, false, Some(0.5));
        let m = moduli_of(&snap, &linear(kn, Some(kt), None));
        let s3 = 3f64.sqrt();
        assert!(close(m.stiffness[0][0], s3 * (3.0 * kn + kt) / 4.0, 1e-8));
        assert!(close(m.stiffness[1][1], s3 * (3.0 * kn + kt) / 4.0, 1e-8));
        assert!(close(m.stiffness[0][1], s3 * (kn - kt) / 4.0, 1e-8));
        assert!(close(m.bulk, s3 * kn / 2.0, 1e-8));
        assert!(close(m.shear, s3 * (kn + kt) / 4.0, 1e-8));
        assert!(close(m.voigt_shear, m.shear, 1e-8));
        assert!(close(m.reuss_bulk.unwrap(), s3 * kn / 2.0, 1e-12));
        // Without friction: K_T plays no part, G = √3 K_N/4.
        let snap0 = snapshot(
            snap.cell.lengths.clone(),
            snap.particles.radius.clone(),
            snap.particles.position.iter().map(|p| p.to_vec()).collect(),
            &b,
            false,
            Some(0.0),
        );
        let m0 = moduli_of(&snap0, &linear(kn, None, None));
        assert!(close(m0.shear, s3 * kn / 4.0, 1e-8));
        assert_eq!(m0.dofs, 2 * 16 + 2, "no rotations without friction");
    }

    /// FCC of spacing s: C11 = √2(K_N + K_T)/s, C12 = (K_N − K_T)/(√2 s); with Hertz contacts
    /// K_N = Ẽ √(R* h).
    #[test]
    fn fcc_crystal_known_moduli() {
        let s = 0.99;
        let m = 3;
        let ac = s * 2f64.sqrt();
        let basis = [
            [0.0, 0.0, 0.0],
            [0.5, 0.5, 0.0],
            [0.5, 0.0, 0.5],
            [0.0, 0.5, 0.5],
        ];
        let mut p = Vec::new();
        for x in 0..m {
            for y in 0..m {
                for z in 0..m {
                    for q in basis {
                        p.push(vec![
                            (x as f64 + q[0]) * ac,
                            (y as f64 + q[1]) * ac,
                            (z as f64 + q[2]) * ac,
                        ]);
                    }
                }
            }
        }
        let l = vec![m as f64 * ac; 3];
        let mut b = Vec::new();
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                let r = super::super::fixtures::branch(&l, &p[i], &p[j]);
                if (r.iter().map(|x| x * x).sum::<f64>().sqrt() - s).abs() < 1e-9 {
                    b.push(bond(i, j, 1.0));
                }
            }
        }
        assert_eq!(b.len(), 6 * p.len());
        let n = p.len();
        let snap = snapshot(l, vec![0.5; n], p, &b, false, Some(0.3));
        let e_tilde = 2000.0;
        let kn = e_tilde * (0.25_f64 * 0.01).sqrt();
        let law = ContactStiffness {
            normal: NormalStiffness::Hertz { e_tilde },
            tangential_ratio: Some(0.8),
            rolling: None,
            attraction: None,
        };
        let got = moduli_of(&snap, &law);
        let kt = 0.8 * kn;
        let c11 = 2f64.sqrt() * (kn + kt) / s;
        let c12 = (kn - kt) / (2f64.sqrt() * s);
        for a in 0..3 {
            assert!(close(got.stiffness[a][a], c11, 1e-7), "{:?}", got.stiffness);
            assert!(close(got.stiffness[a][(a + 1) % 3], c12, 1e-6));
        }
        assert!(close(got.bulk, (c11 + 2.0 * c12) / 3.0, 1e-7));
        assert!(close(got.shear, (c11 - c12) / 2.0, 1e-7));
        // 6 rotations and translations per grain; the 3 translations are the only mechanisms.
        let rig = got.rigidity.unwrap();
        assert_eq!((rig.dofs, rig.constraints), (6 * n, 3 * b.len()));
        assert_eq!(rig.mechanisms, 3);
    }

    /// Disks of radius 0.5005 (1e-3 overlaps) at `pos` in a large cell, in contact along `pairs`.
    fn cluster(pos: &[[f64; 2]], pairs: &[(usize, usize)], mu: f64) -> Snapshot {
        let p: Vec<Vec<f64>> = pos.iter().map(|q| vec![q[0] + 5.0, q[1] + 5.0]).collect();
        let b: Vec<Bond> = pairs.iter().map(|&(i, j)| bond(i, j, 0.0)).collect();
        snapshot(
            vec![20.0, 20.0],
            vec![0.5005; pos.len()],
            p,
            &b,
            false,
            Some(mu),
        )
    }

    /// The rigidity counts of every contact of `snap`, dense and sparse (which must agree).
    fn count(snap: &Snapshot, law: &ContactStiffness) -> Rigidity {
        let all: Vec<&Contact> = snap.contacts.iter().collect();
        let net = Network::build(snap, &all, law, false).unwrap();
        let dense = rigidity_by(&net, Some(RankMethod::DenseEigenvalues)).unwrap();
        let sparse = rigidity_by(&net, Some(RankMethod::SparseInertia)).unwrap();
        assert_eq!(
            (dense.rank, dense.mechanisms, dense.indeterminacy),
            (sparse.rank, sparse.mechanisms, sparse.indeterminacy),
            "dense and sparse counts differ"
        );
        dense
    }

    /// The sparse count (Sylvester's inertia) against the dense eigenvalues on the committed
    /// equilibrated starts: a 1400-disk adhesive packing with and without rolling resistance
    /// and with frictionless contacts, and a 1372-sphere Hertz packing, frictionless and
    /// frictional.
    #[test]
    fn sparse_rank_matches_dense_on_packings() {
        // A start's grains, in contact where they overlap (the starts carry no contact list).
        let start = |name: &str| {
            let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../reference-inputs/starts/");
            let s = Snapshot::read(std::path::Path::new(&format!("{dir}{name}"))).unwrap();
            let (l, r) = (s.cell.lengths.clone(), s.particles.radius.clone());
            let p: Vec<Vec<f64>> = s.particles.position.iter().map(|q| q.to_vec()).collect();
            let mut b = Vec::new();
            for i in 0..p.len() {
                for j in i + 1..p.len() {
                    let d = super::super::fixtures::branch(&l, &p[i], &p[j]);
                    if d.iter().map(|x| x * x).sum::<f64>().sqrt() < r[i] + r[j] {
                        b.push(bond(i, j, 1.0));
                    }
                }
            }
            snapshot(l, r, p, &b, false, Some(0.5))
        };
        let disks = start("grc07-type1-phi052-mu05-rr-classes.snap.json");
        let spheres = start("ar07-D-10kPa-n1372.snap.json");
        let hertz = |t: Option<f64>| ContactStiffness {
            normal: NormalStiffness::Hertz { e_tilde: 1.0 },
            tangential_ratio: t,
            rolling: None,
            attraction: None,
        };
        for (snap, law) in [
            (&disks, linear(1.0, Some(1.0), Some(1e-4))),
            (&disks, linear(1.0, Some(1.0), None)),
            (&disks, linear(1.0, None, None)),
            (&spheres, hertz(None)),
            (&spheres, hertz(Some(0.8))),
        ] {
            let got = count(snap, &law);
            assert!(
                got.dofs > 2000 && got.mechanisms >= snap.dimension,
                "{got:?}"
            );
        }
    }

    /// GRC07 §IV.B, Fig. 13 and App. A: N_f + H = M + K, K counting the 3 motions of an
    /// isolated rigid cluster. The triangle is isostatic (H = 0); the "double triangle" is
    /// rigid with H = 1; a loop of four has one internal mechanism (a rhombus without friction,
    /// counter-rotating gears with friction), none with rolling resistance, where its three
    /// self-stress states are the two force components around the loop and a rolling moment.
    #[test]
    fn rigidity_of_small_clusters() {
        let h = 3f64.sqrt() / 2.0;
        let tri = cluster(
            &[[0.0, 0.0], [1.0, 0.0], [0.5, h]],
            &[(0, 1), (1, 2), (0, 2)],
            0.3,
        );
        let dbl = cluster(
            &[[0.0, 0.0], [1.0, 0.0], [0.5, h], [1.5, h]],
            &[(0, 1), (1, 2), (0, 2), (1, 3), (2, 3)],
            0.3,
        );
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let ring = [(0, 1), (1, 2), (2, 3), (3, 0)];
        let fr = linear(1.0, Some(1.0), None);
        let k = |r: Rigidity| (r.dofs, r.constraints, r.mechanisms, r.indeterminacy);
        assert_eq!(k(count(&tri, &fr)), (9, 6, 3, 0));
        assert_eq!(k(count(&dbl, &fr)), (12, 10, 3, 1));
        let loop0 = cluster(&sq, &ring, 0.0);
        assert_eq!(k(count(&loop0, &linear(1.0, None, None))), (8, 4, 4, 0));
        let loop1 = cluster(&sq, &ring, 0.3);
        assert_eq!(k(count(&loop1, &fr)), (12, 8, 4, 0));
        assert_eq!(
            k(count(&loop1, &linear(1.0, Some(1.0), Some(1e-4)))),
            (12, 12, 3, 3)
        );
    }

    /// A distant attraction is a negative normal stiffness: a lone bond is unstable.
    #[test]
    fn negative_stiffness_is_unstable() {
        let mut snap = cluster(&[[0.0, 0.0], [1.0015, 0.0]], &[(0, 1)], 0.3);
        snap.cohesive = true;
        let law = ContactStiffness {
            attraction: Some(1e3),
            ..linear(1e4, Some(1e4), None)
        };
        let all: Vec<&Contact> = snap.contacts.iter().collect();
        let err = elastic_moduli(&snap, &all, &law, true).unwrap_err();
        assert!(err.contains("not positive definite"), "{err}");
    }
}
