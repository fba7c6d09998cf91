//! The AMG-preconditioned iterative path (`solver.preconditioner = "amg"`): smoothed-aggregation
//! AMG of the velocity block as the coarse correction of the ILU(0) of the Newton matrix Ã.
//!
//! **Why.** ILU(0) is a one-level preconditioner: it removes the mass term's share of Ã and the
//! local coupling, not the smooth, long-range errors of the stiffness. While ρℳ/k dominates (the
//! paper's k) that is all there is, and GMRES + ILU(0) takes 5–9 iterations at any size. Once
//! the stiffness weighs (larger k, stiffer or smaller bodies, finer meshes) its count grows like
//! h⁻¹: at k = 1/8 from 21 (98k unknowns) to 38–44 (972k) (docs/krylov-study.md, §3). A
//! multigrid hierarchy of the velocity block removes exactly those errors.
//!
//! **The preconditioner: one ILU(0) sweep, an AMG coarse correction of the velocities, one ILU(0)
//! sweep** (a multiplicative two-level method, PETSc's PCCOMPOSITE "multiplicative"):
//!
//! ```text
//! z  = Ĩ⁻¹ r                         Ĩ = ILU(0) of Ã, refactored in its Γ_C rows per Newton iteration
//! z += Rᵀ B⁻¹ R (r − Ã z)            B⁻¹ = one V-cycle of GAMG on the velocity block A_ww of A
//! z += Ĩ⁻¹ (r − Ã z)
//! ```
//!
//! R restricts to the velocity unknowns. The V-cycle does no smoothing on its finest level: the
//! ILU(0) sweeps are that level's smoother (measured: 0.39 s against 0.44 s per solve at 230k
//! unknowns and k = 1/8, docs/krylov-study.md). B is set up once per step size, on the constant A_ww:
//! the contact rows that each linearization changes (a stick node's w_i = 0, a slip node's
//! −ℓ_i B_i) are the ILU's to resolve, exactly as on the ILU(0)-only path; the AMG supplies the
//! global correction that a sweep cannot. It runs in the nodes' frames, each node's unknowns
//! padded to d (a held direction gets an identity row) so that GAMG aggregates nodes, with the
//! rigid-body modes, written in the same frames, as its near-nullspace.
//!
//! **Over the ranks** of a distributed run (`crate::step::ranks`) the same method runs on PETSc:
//! each rank's ILU(0) sweeps (restricted additive Schwarz, or block Jacobi) around GAMG on the
//! velocity block distributed by nodes, the rank's own nodes' padded slots consecutive
//! (`RankVelocityBlock`, the C layer's `tc_dist_two_level_apply`). GAMG on the whole coupled
//! Ã instead, which the distributed path first used for `amg`, stalled near 10⁻⁸ on the brake
//! pad (`scenarios/brake_pad3d.toml`) and its run stopped in the first step on 2 ranks.
//!
//! **Rejected.** A block-diagonal preconditioner diag(AMG(A_ww), ILU(A_θθ)) (the krylov study's
//! first plan) drops the coupling G of velocity and temperature and the contact rows: the stick
//! rows of Ã are far from A's, and GMRES would have to find a rank-n_t perturbation.
//! GMRES on Ã with the AMG alone (no ILU sweeps) likewise.

use std::sync::Mutex;

use crate::la::vector::dot;
use crate::la::{CsrMatrix, FactorStage, Ilu0, LaError as Error, Preconditioner};
use crate::model::Problem;

#[cfg(feature = "petsc")]
use crate::la::petsc::{FineSmoothing, Gamg};
#[cfg(not(feature = "petsc"))]
use unavailable::{FineSmoothing, Gamg};

/// The velocity block A_ww of the step matrix in the nodes' frames, padded to d unknowns per
/// node, and its AMG hierarchy.
pub struct VelocityAmg {
    gamg: Gamg,
    /// (row of the ordered system, index in the padded numbering) of each velocity unknown.
    rows: Vec<(u32, u32)>,
    scratch: Mutex<Scratch>,
}

/// The work vectors of one application.
struct Scratch {
    /// A residual of the ordered system.
    residual: Vec<f64>,
    /// A sweep's correction.
    sweep: Vec<f64>,
    /// Restricted residual and coarse correction, padded numbering.
    coarse_in: Vec<f64>,
    coarse_out: Vec<f64>,
}

impl VelocityAmg {
    /// Whether this build has the AMG (the cargo feature `petsc`).
    pub const AVAILABLE: bool = cfg!(feature = "petsc");

    /// The AMG of the velocity block of `a` (the step matrix, row i the unknown `order[i]`).
    pub fn new(problem: &Problem, a: &CsrMatrix, order: &[usize]) -> Result<Self, Error> {
        let d = problem.dim();
        let n_w = problem.velocity.n_free;
        let n_padded = d * problem.mesh.n_nodes();
        let padded = padded_slots(problem)?;
        let rows: Vec<(u32, u32)> = (order.iter().enumerate())
            .filter(|&(_, &u)| u < n_w)
            .map(|(i, &u)| Ok((index32(i)?, padded[u])))
            .collect::<Result<_, Error>>()?;
        let mut row_of = vec![None; n_padded];
        rows.iter().for_each(|&(i, q)| row_of[q as usize] = Some(i as usize));

        let mean_diagonal = rows.iter().map(|&(i, _)| a.diagonal(i as usize)).sum::<f64>() / rows.len().max(1) as f64;
        let (ptr, col, val) = padded_rows(a, (order, n_w), &row_of, (0, mean_diagonal), |u| padded[u]);
        let row_ptr = (ptr.iter().map(|&p| i32::try_from(p)))
            .collect::<Result<Vec<i32>, _>>()
            .map_err(|_| too_large(col.len()))?;
        let col: Vec<i32> = col.into_iter().map(|c| c as i32).collect();
        let modes = rigid_body_modes(problem, &padded);
        // The ILU(0) sweeps are the finest level's smoother.
        let gamg = Gamg::new(row_ptr, col, val, d, &modes, FineSmoothing::None)?;
        let n = a.n();
        Ok(VelocityAmg {
            gamg,
            rows,
            scratch: Mutex::new(Scratch {
                residual: vec![0.0; n],
                sweep: vec![0.0; n],
                coarse_in: vec![0.0; n_padded],
                coarse_out: vec![0.0; n_padded],
            }),
        })
    }

    /// Levels of the hierarchy.
    pub fn levels(&self) -> usize {
        self.gamg.levels()
    }

    /// Stored entries of all levels over the finest level's.
    pub fn operator_complexity(&self) -> f64 {
        self.gamg.operator_complexity()
    }

    /// The two-level preconditioner of Ã: ILU(0) `ilu` of `a` with this coarse correction.
    pub fn with<'a>(&'a self, a: &'a CsrMatrix, ilu: &'a Ilu0) -> TwoLevel<'a> {
        TwoLevel { a, ilu, amg: self }
    }
}

/// Ĩ⁻¹ sweeps around the AMG coarse correction ([the module's header](self)).
pub struct TwoLevel<'a> {
    a: &'a CsrMatrix,
    ilu: &'a Ilu0,
    amg: &'a VelocityAmg,
}

impl Preconditioner for TwoLevel<'_> {
    fn apply(&self, r: &[f64], z: &mut [f64]) -> Result<(), Error> {
        let mut guard = self.amg.scratch.lock().unwrap_or_else(|e| e.into_inner());
        let s = &mut *guard;
        self.ilu.apply(r, z);
        residual_of(self.a, r, z, &mut s.residual);
        s.coarse_in.fill(0.0);
        for &(i, q) in &self.amg.rows {
            s.coarse_in[q as usize] = s.residual[i as usize];
        }
        self.amg.gamg.apply(&s.coarse_in, &mut s.coarse_out)?;
        for &(i, q) in &self.amg.rows {
            z[i as usize] += s.coarse_out[q as usize];
        }
        residual_of(self.a, r, z, &mut s.residual);
        self.ilu.apply(&s.residual, &mut s.sweep);
        z.iter_mut().zip(&s.sweep).for_each(|(z, c)| *z += c);
        Ok(())
    }

    fn method(&self) -> &'static str {
        "GMRES + ILU(0) with AMG (GAMG)"
    }
}

/// A rank's share of the velocity block for the distributed two-level method
/// (`crate::la::mpi::DistributedPreconditioner::SchwarzAmgShell`): the block's rows at the
/// padded slots of the rank's own nodes (the nodes ordered by owner, then by index: each rank's
/// slots consecutive), in global columns; those rows' part of the near-nullspace; and for each
/// of the rank's rows of the system (local index) that is a velocity, its slot (local index).
#[cfg(feature = "mpi")]
pub(crate) struct RankVelocityBlock {
    pub rows: (Vec<usize>, Vec<u32>, Vec<f64>),
    pub modes: Vec<Vec<f64>>,
    pub slots: Vec<(u32, u32)>,
}

#[cfg(feature = "mpi")]
impl RankVelocityBlock {
    /// The share of rank `rank` from `a`, which holds (at least) the rank's rows `owned` of
    /// the step matrix (row i the unknown `order[i]`), with `node_owner` the rank of each node.
    pub(crate) fn new(
        problem: &Problem,
        a: &CsrMatrix,
        order: &[usize],
        owned: &[usize],
        (node_owner, rank): (&[usize], usize),
    ) -> Result<Self, Error> {
        let d = problem.dim();
        let n_w = problem.velocity.n_free;
        let padded = padded_slots(problem)?;
        let n_parts = node_owner.iter().copied().max().map_or(1, |m| m + 1);
        let mut first_node = vec![0usize; n_parts + 1];
        node_owner.iter().for_each(|&o| first_node[o + 1] += 1);
        (0..n_parts).for_each(|r| first_node[r + 1] += first_node[r]);
        // The position of each node among the nodes ordered by owner, then by index.
        let mut next = first_node.clone();
        let position: Vec<usize> = node_owner
            .iter()
            .map(|&o| {
                next[o] += 1;
                next[o] - 1
            })
            .collect();
        index32(d * node_owner.len())?;
        let global = |u: usize| -> u32 {
            let q = padded[u] as usize;
            (d * position[q / d] + q % d) as u32
        };
        let first_slot = d * first_node[rank];
        let n_slots = d * (first_node[rank + 1] - first_node[rank]);
        let mut row_of_slot = vec![None; n_slots];
        let mut slots = Vec::new();
        for (l, &i) in owned.iter().enumerate() {
            let u = order[i];
            if u < n_w {
                let q = global(u) as usize - first_slot;
                row_of_slot[q] = Some(i);
                slots.push((index32(l)?, index32(q)?));
            }
        }
        let held: Vec<f64> = row_of_slot.iter().flatten().map(|&i| a.diagonal(i)).collect();
        let mean_diagonal = held.iter().sum::<f64>() / held.len().max(1) as f64;
        let rows = padded_rows(a, (order, n_w), &row_of_slot, (first_slot, mean_diagonal), global);
        let own_nodes: Vec<usize> = (0..node_owner.len()).filter(|&p| node_owner[p] == rank).collect();
        let modes = rigid_body_modes(problem, &padded)
            .into_iter()
            .map(|mode| {
                own_nodes
                    .iter()
                    .flat_map(|&p| (0..d).map(move |k| (p, k)))
                    .map(|(p, k)| mode[d * p + k])
                    .collect()
            })
            .collect();
        Ok(RankVelocityBlock { rows, modes, slots })
    }
}

/// Rows of the padded velocity block: at slot `first_slot + q` the row `row_of_slot[q]` of `a`
/// on its velocity columns (column c the unknown `order[c]`, a velocity below `n_w`, at slot
/// `slot_of(order[c])`), ascending; where the slot has no row, a direction the node's
/// constraints hold, an identity row of A's scale (`mean_diagonal`).
fn padded_rows(
    a: &CsrMatrix,
    (order, n_w): (&[usize], usize),
    row_of_slot: &[Option<usize>],
    (first_slot, mean_diagonal): (usize, f64),
    slot_of: impl Fn(usize) -> u32,
) -> (Vec<usize>, Vec<u32>, Vec<f64>) {
    let (mut ptr, mut col, mut val) = (Vec::with_capacity(row_of_slot.len() + 1), Vec::new(), Vec::new());
    ptr.push(0);
    let mut entries: Vec<(u32, f64)> = Vec::new();
    for (q, row) in row_of_slot.iter().enumerate() {
        entries.clear();
        match row {
            Some(i) => {
                let (cols, vals) = a.row(*i);
                entries.extend(
                    (cols.iter().zip(vals))
                        .filter(|(&c, _)| order[c as usize] < n_w)
                        .map(|(&c, &v)| (slot_of(order[c as usize]), v)),
                );
                entries.sort_unstable_by_key(|e| e.0);
            }
            None => entries.push(((first_slot + q) as u32, mean_diagonal)),
        }
        col.extend(entries.iter().map(|e| e.0));
        val.extend(entries.iter().map(|e| e.1));
        ptr.push(col.len());
    }
    (ptr, col, val)
}

/// out = r − A z.
fn residual_of(a: &CsrMatrix, r: &[f64], z: &[f64], out: &mut [f64]) {
    a.mul(z, out);
    out.iter_mut().zip(r).for_each(|(o, r)| *o = r - *o);
}

/// The slot of each velocity unknown in the padded numbering: node p's k-th unknown is d p + k.
fn padded_slots(problem: &Problem) -> Result<Vec<u32>, Error> {
    let d = problem.dim();
    let mut padded = vec![0u32; problem.velocity.n_free];
    for p in 0..problem.mesh.n_nodes() {
        for (k, u) in problem.velocity.node_unknowns(p).enumerate() {
            padded[u] = index32(d * p + k)?;
        }
    }
    Ok(padded)
}

/// The rigid-body modes of the velocity field (d translations, d(d−1)/2 rotations about the
/// nodes' centroid) in the padded numbering of the nodes' frames (Pᵀ r, zero in the held
/// slots), orthonormalized; a mode the constraints remove entirely is dropped.
fn rigid_body_modes(problem: &Problem, padded: &[u32]) -> Vec<Vec<f64>> {
    let d = problem.dim();
    let coords = &problem.mesh.coords;
    let n_nodes = coords.len();
    let mut centroid = [0.0; 3];
    coords
        .iter()
        .for_each(|x| (0..3).for_each(|c| centroid[c] += x[c] / n_nodes as f64));
    let n_modes = d * (d + 1) / 2;
    let mut modes = vec![vec![0.0; d * n_nodes]; n_modes];
    for (p, x) in coords.iter().enumerate() {
        let y: [f64; 3] = std::array::from_fn(|c| x[c] - centroid[c]);
        // Full-space mode m at this node, component c.
        let full = |m: usize, c: usize| -> f64 {
            if m < d {
                return f64::from(u8::from(m == c));
            }
            // Rotation about axis ω: ω × y. In 2D the one rotation is about z: (−y₁, y₀).
            let axis = if d == 2 { 2 } else { m - d };
            let omega: [f64; 3] = std::array::from_fn(|k| f64::from(u8::from(k == axis)));
            let cross = [
                omega[1] * y[2] - omega[2] * y[1],
                omega[2] * y[0] - omega[0] * y[2],
                omega[0] * y[1] - omega[1] * y[0],
            ];
            cross[c]
        };
        for c in 0..d {
            for &(u, coefficient) in problem.velocity.row(p * d + c) {
                for (m, mode) in modes.iter_mut().enumerate() {
                    mode[padded[u] as usize] += coefficient * full(m, c);
                }
            }
        }
    }
    orthonormalize(modes)
}

/// Modified Gram–Schmidt, twice; vectors that vanish against the earlier ones are dropped.
fn orthonormalize(vectors: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(vectors.len());
    for mut v in vectors {
        let original = dot(&v, &v).sqrt();
        for _ in 0..2 {
            for b in &basis {
                let c = dot(&v, b);
                v.iter_mut().zip(b).for_each(|(v, b)| *v -= c * b);
            }
        }
        let norm = dot(&v, &v).sqrt();
        if norm > 1e-8 * original {
            v.iter_mut().for_each(|v| *v /= norm);
            basis.push(v);
        }
    }
    basis
}

fn index32(i: usize) -> Result<u32, Error> {
    u32::try_from(i).map_err(|_| too_large(i))
}

fn too_large(count: usize) -> Error {
    Error::Factorization {
        stage: FactorStage::Multigrid,
        detail: format!("{count} exceeds the 32-bit indices of the AMG's matrix"),
    }
}

/// The AMG of a build without the `petsc` feature: it cannot be set up.
#[cfg(not(feature = "petsc"))]
mod unavailable {
    use crate::la::{FactorStage, LaError as Error};

    pub(super) enum Gamg {}

    pub(super) enum FineSmoothing {
        None,
    }

    impl Gamg {
        pub(super) fn new(
            _: Vec<i32>,
            _: Vec<i32>,
            _: Vec<f64>,
            _: usize,
            _: &[Vec<f64>],
            _: FineSmoothing,
        ) -> Result<Self, Error> {
            Err(Error::Factorization {
                stage: FactorStage::Multigrid,
                detail: "this build has no AMG: build thermocontact with `--features petsc` (needs PETSc)".into(),
            })
        }

        pub(super) fn apply(&self, _: &[f64], _: &mut [f64]) -> Result<(), Error> {
            match *self {}
        }

        pub(super) fn levels(&self) -> usize {
            match *self {}
        }

        pub(super) fn operator_complexity(&self) -> f64 {
            match *self {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orthonormalize_drops_dependent_vectors() {
        let v = orthonormalize(vec![vec![1.0, 1.0, 0.0], vec![2.0, 2.0, 0.0], vec![0.0, 1.0, 1.0]]);
        assert_eq!(v.len(), 2);
        assert!((dot(&v[0], &v[0]) - 1.0).abs() < 1e-14 && (dot(&v[1], &v[1]) - 1.0).abs() < 1e-14);
        assert!(dot(&v[0], &v[1]).abs() < 1e-14);
    }

    /// On the 3D example (its contact nodes slide in their frames, its clamped nodes are held)
    /// all six modes survive the constraints, orthonormal.
    #[test]
    fn six_orthonormal_rigid_body_modes_in_3d() {
        let problem = crate::model::samples::paper_3d([4, 2, 2], 64).unwrap();
        let modes = rigid_body_modes(&problem, &padded_slots(&problem).unwrap());
        assert_eq!(modes.len(), 6);
        for (i, a) in modes.iter().enumerate() {
            for (j, b) in modes.iter().enumerate() {
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!((dot(a, b) - expected).abs() < 1e-12, "modes {i}, {j}");
            }
        }
    }
}
