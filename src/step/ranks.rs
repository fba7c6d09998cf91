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
//! CSR rows at set-up ([`DistributedMatrix::from_rows`]) and, after each linearization, only
//! the rows it changed ([`DistributedMatrix::set_rows`]), and GMRES runs with block Jacobi (one
//! block per rank) or GAMG, from the previous iterate as the serial solves do. Each rank's
//! unknowns are numbered in the system's order, so its block has its Γ_C rows last and its
//! ILU(0) is the serial path's: single precision, refactored only from the first row a
//! linearization changes ([`RankBlock`]). The solution is gathered on every rank
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
use crate::la::{CsrMatrix, Ilu0, LaError, Preconditioner, SolveInfo};
use crate::model::{node_unknowns, Problem};
use crate::partition::DofLayout;

/// The Krylov solver of Ã x = b̃ over the ranks: Ã's rows that this rank owns in PETSc's
/// matrix, the maps between the serial system's order and PETSc's layout, and the
/// preconditioner of this rank's block where block Jacobi uses this crate's ILU(0).
pub(crate) struct RankKrylov {
    matrix: DistributedMatrix,
    rows: RankRows,
    params: DistributedKrylov,
    /// Stored entries of this rank's rows.
    n_entries: usize,
    /// This rank's diagonal block of Ã and its ILU(0), for
    /// [`DistributedPreconditioner::BlockJacobiShell`].
    block: Option<Box<RankBlock>>,
    /// The first row of Ã (the system's order) that a linearization changes.
    first_changing: usize,
}

/// The ILU(0) of this rank's diagonal block of Ã (its owned rows and columns, in the system's
/// order, so with its Γ_C tangential rows last) in single precision, which each linearization
/// refactors from the rank's first Γ_C row on, as the serial path does
/// ([`Ilu0::refactor_rows_from`]); only those rows of the block are kept. PETSc's block Jacobi
/// with ILU(0) refactors the whole block after each linearization, in double precision (2.4 of
/// 8.1 s of Krylov solves at 98k unknowns on 2 ranks, docs/distributed.md).
struct RankBlock {
    ilu: Ilu0,
    /// The block's rows from `first_changing` on: offsets, local columns, values.
    changing: (Vec<usize>, Vec<u32>, Vec<f64>),
    /// The first row of the block a linearization changes.
    first_changing: usize,
    /// For each value of `changing`, the index of its value among the values of Ã's rows
    /// from the first changing one on ([`CsrMatrix::values_from`]).
    value_of_entry: Vec<usize>,
}

impl RankBlock {
    /// The ILU(0) of the block of Ã at the system rows `owned_rows` (ascending), the rows from
    /// the system row `first_changing` on kept for [`RankBlock::update`].
    fn new(a: &CsrMatrix, owned_rows: &[usize], first_changing: usize) -> Result<Self, LaError> {
        let mut local_of_row = vec![u32::MAX; a.n()];
        owned_rows
            .iter()
            .enumerate()
            .for_each(|(local, &row)| local_of_row[row] = local as u32);
        let first = owned_rows.partition_point(|&row| row < first_changing);
        let (mut ptr, mut col, mut val, mut value_of_entry) = (vec![0], Vec::new(), Vec::new(), Vec::new());
        for (i, &row) in owned_rows.iter().enumerate() {
            let (cols, values) = a.row(row);
            for (j, (&c, &v)) in cols.iter().zip(values).enumerate() {
                let local = local_of_row[c as usize];
                if local != u32::MAX {
                    col.push(local);
                    val.push(v);
                    if i >= first {
                        value_of_entry.push(a.offset_from(first_changing, row).start + j);
                    }
                }
            }
            ptr.push(col.len());
        }
        drop(local_of_row);
        let start = ptr[first];
        let changing = (
            ptr[first..].iter().map(|&p| p - start).collect(),
            col[start..].to_vec(),
            val[start..].to_vec(),
        );
        let ilu = Ilu0::new(&CsrMatrix::from_rows(owned_rows.len(), ptr, col, val))?;
        Ok(RankBlock {
            ilu,
            changing,
            first_changing: first,
            value_of_entry,
        })
    }

    /// The block's changing rows again from Ã's values (no row before them changed; Ã's
    /// first changing row `first_changing`), refactored.
    fn update(&mut self, a: &CsrMatrix, first_changing: usize) -> Result<(), LaError> {
        let all = a.values_from(first_changing);
        let (ptr, col, val) = &mut self.changing;
        val.iter_mut().zip(&self.value_of_entry).for_each(|(v, &p)| *v = all[p]);
        let first = self.first_changing;
        let (ptr, col, val) = (&*ptr, &*col, &*val);
        self.ilu.refactor_rows_from(first, |i| {
            let range = ptr[i - first]..ptr[i - first + 1];
            (&col[range.clone()], &val[range])
        })
    }
}

/// Which rows of Ã a rank owns and where every row of Ã is in PETSc's layout: the run's
/// partition of the mesh ([`Problem::partition`]) laid out by unknowns ([`DofLayout`]), each
/// rank's rows numbered in the system's order.
pub(crate) struct RankRows {
    /// The row of Ã (the system's order) of each global index this rank owns, in order:
    /// ascending, so that PETSc's order of a rank's rows is the system's.
    owned: Vec<usize>,
    /// The global index (PETSc's layout) of each row of Ã.
    global_of_row: Vec<usize>,
}

impl RankRows {
    /// The layout of Ã's rows (row i the unknown `order[i]`) over the ranks; collective.
    pub(crate) fn new(problem: &Problem, order: &[usize]) -> Result<Self, LaError> {
        let comm = Communicator::world()?;
        let partition = problem.partition(&comm)?;
        let layout = DofLayout::new(partition, order.len(), |p, out| node_unknowns(problem, p, out));
        let mut row_of_unknown = vec![0; order.len()];
        order.iter().enumerate().for_each(|(row, &u)| row_of_unknown[u] = row);
        let mut global_of_row = vec![0; order.len()];
        let mut owned = Vec::new();
        for rank in 0..comm.size() {
            let range = layout.owned(rank);
            let mut rows: Vec<usize> = layout.order[range.clone()].iter().map(|&u| row_of_unknown[u]).collect();
            rows.sort_unstable();
            rows.iter().zip(range).for_each(|(&row, g)| global_of_row[row] = g);
            if rank == comm.rank() {
                owned = rows;
            }
        }
        Ok(RankRows { owned, global_of_row })
    }

    /// The rows of Ã this rank assembles: its own, and every row from `first_changing` on
    /// (those a linearization changes, which every rank forms from the same iterate).
    pub(crate) fn assembled(&self, first_changing: usize) -> Vec<usize> {
        let own = self.owned.iter().copied().filter(|&row| row < first_changing);
        own.chain(first_changing..self.global_of_row.len()).collect()
    }
}

impl RankKrylov {
    /// Sets PETSc's matrix up with this rank's rows of `a` (the system's rows, laid out by
    /// `rows`; at least [`RankRows::assembled`]'s rows of Ã), the rows from `first_changing`
    /// on those a linearization changes, and returns the solver with `a`'s rows from
    /// `first_changing` on, the only ones read after set-up (the others emptied:
    /// [`CsrMatrix::keep_rows_from`]); collective.
    ///
    /// The order keeps the peak low: this rank's block and its factor first, then PETSc's rows
    /// in PETSc's numbering, then `a`'s own rows are dropped before PETSc copies those, so that
    /// at most three of (`a`'s rows, the block, PETSc's rows, their copy in PETSc) are held at a
    /// time. Measured at 972k unknowns on 2 ranks: docs/distributed.md.
    pub(crate) fn new(
        rows: RankRows,
        (a, first_changing): (CsrMatrix, usize),
        params: DistributedKrylov,
    ) -> Result<(Self, CsrMatrix), LaError> {
        let comm = Communicator::world()?;
        let block = match params.preconditioner {
            DistributedPreconditioner::BlockJacobiShell => {
                Some(Box::new(RankBlock::new(&a, &rows.owned, first_changing)?))
            }
            _ => None,
        };
        let n_entries: usize = rows.owned.iter().map(|&row| a.row(row).0.len()).sum();
        let (mut ptr, mut cols, mut values) = (vec![0], Vec::with_capacity(n_entries), Vec::with_capacity(n_entries));
        let mut entries = Vec::new();
        for &row in &rows.owned {
            let (c, v) = a.row(row);
            entries.clear();
            entries.extend(c.iter().map(|&c| rows.global_of_row[c as usize] as u32).zip(v));
            entries.sort_unstable_by_key(|&(g, _)| g);
            cols.extend(entries.iter().map(|&(g, _)| g));
            values.extend(entries.iter().map(|&(_, &v)| v));
            ptr.push(cols.len());
        }
        let a = a.keep_rows_from(first_changing);
        let matrix = DistributedMatrix::from_rows(&comm, &ptr, &cols, &values)?;
        let solver = RankKrylov {
            matrix,
            rows,
            params,
            n_entries,
            block,
            first_changing,
        };
        Ok((solver, a))
    }

    /// Ã's values into PETSc's matrix (this rank's rows), and into this rank's block, whose
    /// rows from Ã's row `first_changed` on are refactored; collective. Only rows from
    /// `first_changing` on change after set-up (A's rows are fixed per step size).
    pub(crate) fn set_matrix(&mut self, a: &CsrMatrix, first_changed: usize) -> Result<(), LaError> {
        debug_assert!(
            first_changed >= self.first_changing,
            "a row before the changing ones changed"
        );
        let first = self
            .rows
            .owned
            .partition_point(|&row| row < first_changed.max(self.first_changing));
        self.set_rows_from(a, first)?;
        match &mut self.block {
            Some(block) => block.update(a, self.first_changing),
            None => Ok(()),
        }
    }

    /// This rank's rows of Ã from its `first` owned row on (in the system's order, so the rows
    /// a linearization changes are a rank's last) into PETSc's matrix; collective.
    fn set_rows_from(&mut self, a: &CsrMatrix, first: usize) -> Result<(), LaError> {
        let rows = &self.rows.owned[first..];
        let start = self.matrix.owned().start + first;
        let (mut ptr, mut cols, mut values) = (vec![0], Vec::new(), Vec::new());
        for &row in rows {
            let (c, v) = a.row(row);
            cols.extend(c.iter().map(|&c| self.rows.global_of_row[c as usize]));
            values.extend_from_slice(v);
            ptr.push(cols.len());
        }
        let globals: Vec<usize> = (start..start + rows.len()).collect();
        self.matrix.set_rows(&globals, &ptr, &cols, &values)
    }

    /// Solves Ã x = b̃ by PETSc's GMRES from x (b̃ and x whole, in the system's order, the same
    /// on every rank), x replaced by the solution on every rank; collective.
    pub(crate) fn solve(&mut self, rhs: &[f64], x: &mut [f64]) -> Result<SolveInfo, LaError> {
        let owned_rhs: Vec<f64> = self.rows.owned.iter().map(|&row| rhs[row]).collect();
        let mut owned_x: Vec<f64> = self.rows.owned.iter().map(|&row| x[row]).collect();
        let block = self.block.as_ref().map(|b| &b.ilu as &dyn Preconditioner);
        let solved = self.matrix.solve_from(&self.params, &owned_rhs, &mut owned_x, block);
        // Every rank reaches here with the same outcome (PETSc's reason is collective).
        let info = solved?;
        let whole = self.matrix.all_gather()?;
        x.iter_mut()
            .zip(&self.rows.global_of_row)
            .for_each(|(x, &g)| *x = whole[g]);
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
        if preconditioner != DistributedPreconditioner::BlockJacobiShell {
            self.block = None;
        }
    }

    /// Stored entries of Ã on this rank.
    pub(crate) fn nnz(&self) -> usize {
        self.n_entries
    }
}
