//! The step matrix A of Problem 14 as a PETSc matrix distributed over the ranks (cargo feature
//! `mpi`), and its linear solve: the foundation of the distributed step (docs/distributed.md).
//!
//! With the mesh partitioned ([`MeshPartition`]) and the unknowns numbered so that each rank's
//! are consecutive ([`DofLayout`]: per owned node, its velocities in E^h's basis, then its
//! temperature), rank r assembles the rows it owns of P A Pᵀ (P the layout's permutation) with
//! [`ordered_rows_range`], the same sums as the serial iterative path's [`super::ordered_rows`],
//! and hands them to PETSc as COO pairs, once per step size; each row is then on the rank that
//! owns it and PETSc sends nothing at assembly. The right-hand side's owned entries likewise.
//!
//! **Owned rows rather than each cell's contributions.** A's rows are formed from the global
//! P1 matrices through E^h's constraint P (bilateral contact, symmetry, clamps) and the θ_D
//! lift ([`super::StepMatrix`]); a cell-by-cell assembly would be a second copy of that sum, to
//! be kept bitwise equal to the first. The distributed matrix takes either: its COO pairs may
//! name any row, PETSc sums repeated pairs across ranks (`la::mpi`'s test assembles a Laplacian
//! so, by elements split over the ranks).
//!
//! What is replicated in this foundation: every rank builds the [`Problem`] (E^h, Γ_C, the
//! mesh) as rank 0 does, with its share of the P1 matrices (of 𝒦_A, 𝒦_B and G the columns its
//! rows read: [`super::ColumnShare`]), and keeps A's rows of its own unknowns only. Where this
//! stops scaling and what replaces it: docs/distributed.md.
//!
//! Depends on: [`crate::la::mpi`] (the distributed matrix), [`crate::partition`] (the layout).

use super::problem::Problem;
use super::step_matrix::ordered_rows_range;
use crate::la::mpi::{Communicator, DistributedKrylov, DistributedMatrix, DistributedSolveInfo};
use crate::la::LaError;
use crate::partition::{DofLayout, MeshPartition};

/// The unknowns of `node`: its velocities (E^h's basis at the node, none if clamped), then its
/// temperature (none at a θ_D node), appended to `out`.
pub fn node_unknowns(problem: &Problem, node: usize, out: &mut Vec<usize>) {
    out.extend(problem.velocity.node_unknowns(node));
    if let Some(r) = problem.temperature.free[node] {
        out.push(problem.velocity.n_free + r);
    }
}

/// The step matrix A of one step size k, distributed by rows over the ranks.
pub struct DistributedStepMatrix {
    /// The global numbering of the unknowns (PETSc's layout).
    pub layout: DofLayout,
    matrix: DistributedMatrix,
    rank: usize,
}

impl DistributedStepMatrix {
    /// Assembles this rank's rows of A for step size k, the unknowns laid out by `partition`
    /// (the same on every rank); collective.
    pub fn assemble(
        comm: &Communicator,
        problem: &Problem,
        partition: &MeshPartition,
        k: f64,
    ) -> Result<Self, LaError> {
        let layout = DofLayout::new(partition, problem.n_unknowns(), |p, out| node_unknowns(problem, p, out));
        let owned = layout.owned(comm.rank());
        let (ptr, col, val) = ordered_rows_range(problem, k, &layout.order, owned.clone());
        let rows: Vec<usize> = (0..owned.len())
            .flat_map(|i| std::iter::repeat_n(owned.start + i, ptr[i + 1] - ptr[i]))
            .collect();
        let cols: Vec<usize> = col.iter().map(|&j| j as usize).collect();
        let mut matrix = DistributedMatrix::new(comm, owned.len(), 1, &rows, &cols)?;
        matrix.set_values(&val)?;
        Ok(DistributedStepMatrix {
            layout,
            matrix,
            rank: comm.rank(),
        })
    }

    /// Solves A x = b by PETSc's GMRES (`params`), b given whole in the crate's numbering of
    /// the unknowns (each rank passes on its own entries): this rank's owned part of x, in the
    /// layout's global order.
    pub fn solve(
        &mut self,
        params: &DistributedKrylov,
        b: &[f64],
    ) -> Result<(Vec<f64>, DistributedSolveInfo), LaError> {
        let owned: Vec<usize> = self.layout.owned(self.rank).collect();
        let values: Vec<f64> = owned.iter().map(|&g| b[self.layout.order[g]]).collect();
        self.matrix.solve(params, &owned, &values)
    }

    /// The last solution on rank 0, in the crate's numbering of the unknowns (`None` on the
    /// others); collective.
    pub fn gather_on_root(&self, comm: &Communicator) -> Result<Option<Vec<f64>>, LaError> {
        Ok(self.matrix.gather_on_root(comm)?.map(|global| {
            let mut x = vec![0.0; global.len()];
            for (g, value) in global.into_iter().enumerate() {
                x[self.layout.order[g]] = value;
            }
            x
        }))
    }
}
