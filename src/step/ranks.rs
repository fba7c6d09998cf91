//! The iterative path's Krylov solves on PETSc over the MPI ranks of a distributed run (cargo
//! feature `mpi`, `mpirun -n P thermocontact run`; docs/distributed.md).
//!
//! **What is distributed, what is replicated.** Every rank holds the whole problem, the ordered
//! step matrix Ã of [`super::iterative`] and the Newton iterates x, w, ξ (vectors of N and of
//! Γ_C: 8 bytes per unknown each). Each linearization changes Ã's Γ_C rows in place on every
//! rank, the same way from the same iterate. The Krylov solve, which is where a step spends its
//! time, runs on PETSc: rank r owns the rows of Ã at the unknowns of its part of the mesh
//! ([`MeshPartition`](crate::partition::MeshPartition): PT-Scotch on the dual graph, computed
//! on rank 0 and broadcast once per run, shared with the frames' pieces: [`Problem::partition`];
//! [`DofLayout`]: each rank's unknowns consecutive), hands them to PETSc's MPIAIJ matrix as
//! values of a COO pattern fixed at set-up ([`DistributedMatrix::set_values`], after each
//! linearization), and GMRES runs with block Jacobi + ILU(0) (one block per rank) or GAMG, from
//! the previous iterate as the serial solves do. The solution is gathered on every rank
//! (PETSc's scatter to all), so that the nodal law, the stop tests, the slip counts and the
//! cutback decision are computed from the same numbers on every rank and agree without a
//! reduction: the ranks take the same branches by construction.
//!
//! **Why replicate the iterates rather than distribute the Newton method too.** The nodal law
//! is O(|Γ_C|) and the stop tests O(N) per iteration against the Krylov solve's O(N) per
//! Krylov iteration times 5–30 iterations: replicated, they cost little, and the ranks cannot
//! disagree on a branch (a rank that stops its loop while another iterates would hang in the
//! next collective call). What replication costs is memory (the problem and Ã on every rank)
//! and a gather of N values per Newton iteration; docs/distributed.md gives the figures and
//! what ends them (each rank assembling its own rows, [`crate::model::DistributedStepMatrix`],
//! with the law on owned Γ_C nodes and reductions for the tests).
//!
//! Depends on: [`crate::la::mpi`] (the distributed matrix, the communicator),
//! [`crate::partition`] (the layout), [`crate::model`].

use crate::la::mpi::{Communicator, DistributedKrylov, DistributedMatrix, DistributedPreconditioner};
use crate::la::{CsrMatrix, LaError, SolveInfo};
use crate::model::{node_unknowns, Problem};
use crate::partition::DofLayout;

/// The Krylov solver of Ã x = b̃ over the ranks: Ã's rows that this rank owns in PETSc's
/// matrix, and the maps between the serial system's order and PETSc's layout.
pub(crate) struct RankKrylov {
    matrix: DistributedMatrix,
    /// For each of this rank's COO pairs, the index of its value in Ã's values.
    value_of_pair: Vec<usize>,
    /// The row of Ã (the system's order) of each global index this rank owns, in order.
    owned_rows: Vec<usize>,
    /// The global index (PETSc's layout) of each row of Ã.
    global_of_row: Vec<usize>,
    params: DistributedKrylov,
    values: Vec<f64>,
}

impl RankKrylov {
    /// Lays the unknowns out over the run's partition of the mesh ([`Problem::partition`]) and
    /// sets PETSc's matrix up with this rank's rows of `a` (the system's rows, row i the unknown
    /// `order[i]`); collective.
    pub(crate) fn new(
        problem: &Problem,
        a: &CsrMatrix,
        order: &[usize],
        params: DistributedKrylov,
    ) -> Result<Self, LaError> {
        let comm = Communicator::world()?;
        let partition = problem.partition(&comm)?;
        let layout = DofLayout::new(partition, order.len(), |p, out| node_unknowns(problem, p, out));
        let global_of_row: Vec<usize> = order.iter().map(|&u| layout.index_of[u]).collect();
        let mut row_of_global = vec![0; order.len()];
        global_of_row
            .iter()
            .enumerate()
            .for_each(|(row, &g)| row_of_global[g] = row);
        let owned = layout.owned(comm.rank());
        let owned_rows: Vec<usize> = owned.clone().map(|g| row_of_global[g]).collect();
        let (mut rows, mut cols, mut value_of_pair) = (Vec::new(), Vec::new(), Vec::new());
        for (g, &row) in owned.zip(&owned_rows) {
            let range = a.offset_from(0, row);
            for (p, &col) in range.clone().zip(a.row(row).0) {
                rows.push(g);
                cols.push(global_of_row[col as usize]);
                value_of_pair.push(p);
            }
        }
        let matrix = DistributedMatrix::new(&comm, owned_rows.len(), 1, &rows, &cols)?;
        let mut solver = RankKrylov {
            matrix,
            values: vec![0.0; value_of_pair.len()],
            value_of_pair,
            owned_rows,
            global_of_row,
            params,
        };
        solver.set_matrix(a)?;
        Ok(solver)
    }

    /// Ã's values into PETSc's matrix (this rank's rows); collective.
    pub(crate) fn set_matrix(&mut self, a: &CsrMatrix) -> Result<(), LaError> {
        let all = a.values_from(0);
        (self.values.iter_mut().zip(&self.value_of_pair)).for_each(|(v, &p)| *v = all[p]);
        self.matrix.set_values(&self.values)
    }

    /// Solves Ã x = b̃ by PETSc's GMRES from x (b̃ and x whole, in the system's order, the same
    /// on every rank), x replaced by the solution on every rank; collective.
    pub(crate) fn solve(&mut self, rhs: &[f64], x: &mut [f64]) -> Result<SolveInfo, LaError> {
        let owned_rhs: Vec<f64> = self.owned_rows.iter().map(|&row| rhs[row]).collect();
        let mut owned_x: Vec<f64> = self.owned_rows.iter().map(|&row| x[row]).collect();
        let solved = self.matrix.solve_from(&self.params, &owned_rhs, &mut owned_x);
        // Every rank reaches here with the same outcome (PETSc's reason is collective).
        let info = solved?;
        let whole = self.matrix.all_gather()?;
        x.iter_mut().zip(&self.global_of_row).for_each(|(x, &g)| *x = whole[g]);
        Ok(SolveInfo {
            iterations: info.iterations,
            residual: info.residual,
        })
    }

    /// Solves Ã x = b̃ from x as [`RankKrylov::solve`], with `params` for this solve only (the
    /// `auto` rule's probe).
    pub(crate) fn probe(
        &mut self,
        params: &DistributedKrylov,
        rhs: &[f64],
        x: &mut [f64],
    ) -> Result<SolveInfo, LaError> {
        let kept = std::mem::replace(&mut self.params, *params);
        let solved = self.solve(rhs, x);
        self.params = kept;
        solved
    }

    /// The preconditioner PETSc runs.
    pub(crate) fn preconditioner(&self) -> DistributedPreconditioner {
        self.params.preconditioner
    }

    /// Switches the preconditioner (the `auto` probe's choice).
    pub(crate) fn set_preconditioner(&mut self, preconditioner: DistributedPreconditioner) {
        self.params.preconditioner = preconditioner;
    }

    /// Stored entries of Ã on this rank.
    pub(crate) fn nnz(&self) -> usize {
        self.value_of_pair.len()
    }
}
