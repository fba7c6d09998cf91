//! The iterative path's Krylov solves on PETSc over the MPI ranks of a distributed run (cargo
//! feature `mpi`, `mpirun -n P thermocontact run`; docs/distributed.md).
//!
//! **What is distributed, what is replicated.** Every rank holds the problem, with of 𝒦_A, 𝒦_B
//! and G only the columns its rows read ([`crate::model::ColumnShare`]), and the Newton
//! iterates x, w, ξ (vectors of N and of Γ_C: 8 bytes per unknown each). Of the ordered
//! step matrix Ã of [`super::iterative`] a rank assembles only its own rows and the Γ_C rows
//! ([`RankRows::assembled`]), and keeps only the Γ_C rows after set-up. The Krylov solve,
//! which is where a step spends its time, runs on PETSc: rank r owns the rows of Ã at the
//! unknowns of its part of the mesh ([`MeshPartition`](crate::partition::MeshPartition):
//! PT-Scotch on the dual graph, computed on rank 0 and broadcast once per run, shared with the
//! frames' pieces: [`Problem::partition`]; [`DofLayout`]: each rank's unknowns consecutive),
//! hands them to PETSc's MPIAIJ matrix at set-up, split into its diagonal block and the rest,
//! which PETSc keeps without a copy ([`DistributedMatrix::from_split`]) and, after each
//! linearization, only the rows it changed ([`DistributedMatrix::set_rows`]), and PETSc's GCR
//! (GMRES's iterates; it keeps its residual: [`DistributedKrylov`]'s header; its directions
//! allocated as the solves need them: `csrc/petsc_mpi.c`) runs with
//! restricted additive Schwarz (one overlapping block per rank: the rank's rows and those of
//! other ranks that they read), block Jacobi (one block per rank, `solver.overlap = 0`), or
//! either's sweeps around GAMG on the velocity block (the serial path's two-level method,
//! [`RankKrylov::set_velocity_amg`]), from the previous iterate and its residual as the serial
//! solves do. Each rank's unknowns are numbered in the system's order, so its block has its
//! Γ_C rows last (then, with Schwarz, its overlap's rows) and its ILU(0) is the serial path's:
//! single precision, refactored only from the first row a linearization changes
//! ([`RankBlock`]).
//!
//! **Each Newton iteration on the rows a rank owns.** A rank linearizes the law at its own
//! contact nodes and at those of its block's overlap ([`RankKrylov::row_here`]): it changes
//! their rows of Ã in place, hands its own to PETSc and refactors its block; it recomputes the
//! residual in its own rows that the linearization changed (Ã's Γ_C rows, and the contact
//! nodes' temperature rows, whose right-hand side carries the frictional heat); and it forms ξ
//! at its own nodes, made whole on every rank by one reduction
//! ([`RankKrylov::share_owned_entries`]). Of the solution each rank takes its own rows and
//! gathers those the next iteration reads, the columns of Ã's Γ_C rows (the same on every rank:
//! [`RankKrylov::solve`]). So every rank holds the same w and ξ on Γ_C, and classifies every
//! contact node (stick or slip), runs the bounds' prediction (a Gauss–Seidel sweep over Γ_C's
//! rows, which follows Γ_C's order) and the stop tests from the same numbers: the ranks take
//! the same branches by construction, and follow one process's path, bit for bit in the
//! linearized rows. The whole solution is gathered once per step, for the state
//! ([`RankKrylov::gather_whole`]).
//!
//! **Why the blocks overlap.** Block Jacobi drops every coupling between two ranks' unknowns,
//! so its Krylov count grows with the ranks (344 iterations against one process's 303 at 972k
//! unknowns on 2 ranks, 4 steps). With each block extended by one layer of rows (the overlap:
//! rows of other ranks that the rank's rows read) and each rank keeping only its own entries of
//! its block's solution (restricted additive Schwarz: Cai & Sarkis, SIAM J. Sci. Comput. 21
//! (1999); PETSc's `PCASM` of type `restrict`), the count is one process's again: 304. The
//! overlap costs one scatter of its entries per application and 1.3 % more rows in each ILU(0)
//! at 972k on 2 ranks (6 254 rows); the time per step fell 3.55–3.60 → 3.37–3.41 s there
//! (docs/distributed.md). PETSc's own `PCASM` (overlap 1, ILU(0) in double precision, refactored whole at each
//! linearization) took 90 Krylov iterations where this takes 86 (98k unknowns, 4 steps, 2
//! ranks), but 0.49 s per step against 0.12 s: this crate's ILU(0) keeps the rows that no
//! linearization changes.
//!
//! **What stays replicated, and why.** The classification, the prediction and the stop tests
//! read Γ_C's unknowns and their neighbours': O(|Γ_C|) = O(N^{2/3}) per Newton iteration,
//! against the Krylov solve's O(N/P) per Krylov iteration; held alike on every rank, they
//! cost a gather of the Γ_C neighbourhood, and no rank can leave a loop while another iterates
//! (it would hang in the next collective call), where reductions of every test would leave
//! that to rounding; and the prediction's sweep, which runs node after node in Γ_C's order,
//! would take another path on each partition if each rank swept its own nodes. What
//! replication still costs is memory (what every rank holds whole: ≈ 520 bytes per unknown)
//! and a gather of N values per step (2–5 ms at 972k unknowns on 2 ranks); docs/distributed.md
//! gives the figures and the plan for 10⁷–10⁸ unknowns.
//!
//! Depends on: [`crate::la::mpi`] (the distributed matrix, the communicator),
//! [`crate::partition`] (the layout), [`crate::model`].

use super::amg::RankVelocityBlock;
use super::iterative::RowHere;
use crate::la::mpi::{
    Communicator, CsrParts, DistributedKrylov, DistributedMatrix, DistributedPreconditioner, RowPattern,
};
use crate::la::{CsrMatrix, Ilu0, LaError, Preconditioner, SolveInfo};
use crate::model::{node_unknowns, Problem};
use crate::partition::DofLayout;

/// The Krylov solver of Ã x = b̃ over the ranks: Ã's rows that this rank owns in PETSc's
/// matrix, the maps between the serial system's order and PETSc's layout, and the
/// preconditioner of this rank's block where block Jacobi or Schwarz uses this crate's ILU(0).
pub(crate) struct RankKrylov {
    matrix: DistributedMatrix,
    rows: RankRows,
    params: DistributedKrylov,
    /// Stored entries of this rank's rows.
    n_entries: usize,
    /// This rank's block of Ã's ILU(0), for [`DistributedPreconditioner::BlockJacobiShell`]
    /// (its diagonal block) and [`DistributedPreconditioner::SchwarzShell`] (overlapped).
    block: Option<Box<RankBlock>>,
    /// The first row of Ã (the system's order) that a linearization changes.
    first_changing: usize,
    /// This rank's rows that a linearization changes, as PETSc's matrix gets them.
    changing: Box<ChangingRows>,
    /// What each solve hands to PETSc and brings back ([`RankKrylov::solve`]).
    exchange: Box<SolveExchange>,
    /// Where each row of Ã from `first_changing` on is kept: this rank's own, its block's
    /// overlap, or neither ([`RankKrylov::row_here`]).
    changing_here: Vec<RowHere>,
    comm: Communicator,
}

/// The vectors of [`RankKrylov::solve`], kept for the run (boxed, as `changing`: the solver
/// is a variant of the step's linear system).
struct SolveExchange {
    /// This rank's entries of b̃, of x and of the residual b̃ − Ã x for PETSc.
    owned_rhs: Vec<f64>,
    owned_x: Vec<f64>,
    owned_residual: Vec<f64>,
    /// The rows of x (the system's order) that a linearization reads besides this rank's own:
    /// the columns of Ã's rows from `first_changing` on and of the rows whose residual the
    /// caller recomputes (`RankKrylov::new`'s `also`), gathered after each solve; and their
    /// values.
    read: Vec<usize>,
    read_values: Vec<f64>,
}

/// A rank's rows of Ã that a linearization changes (its last, in the system's order): their
/// pattern in PETSc's matrix, prepared once, and their values, gathered from Ã at each
/// linearization into one buffer.
struct ChangingRows {
    /// The first of them, by its index among the rank's rows.
    first: usize,
    pattern: RowPattern,
    values: Vec<f64>,
}

/// The ILU(0) of this rank's diagonal block of Ã (its owned rows and columns, in the system's
/// order, so with its Γ_C tangential rows last) in single precision, which each linearization
/// refactors from the rank's first Γ_C row on, as the serial path does
/// ([`Ilu0::refactor_rows_from`]); only those rows of the block are kept. PETSc's block Jacobi
/// with ILU(0) refactors the whole block after each linearization, in double precision (2.4 of
/// 8.1 s of Krylov solves at 98k unknowns on 2 ranks, docs/distributed.md).
///
/// With restricted additive Schwarz ([`RankBlock::overlapped`]) the block is the rank's rows
/// and its overlap's (the other ranks' rows that its rows read), numbered [owned, overlap]: its
/// changing rows are then its own Γ_C rows and every overlap row, the ones of other ranks that
/// no linearization changes fetched once from PETSc.
struct RankBlock {
    ilu: Ilu0,
    /// The block's rows from `first_changing` on: offsets, local columns, values.
    changing: (Vec<usize>, Vec<u32>, Vec<f64>),
    /// The first row of the block a linearization changes.
    first_changing: usize,
    /// For each value of `changing`, the index of its value among the values of Ã's rows
    /// from the first changing one on ([`CsrMatrix::values_from`]), or [`FIXED`].
    value_of_entry: Vec<usize>,
}

/// An entry of [`RankBlock`]'s changing rows that no linearization changes (an overlap row of
/// another rank off Γ_C).
const FIXED: usize = usize::MAX;

/// What [`RankKrylov::new`] keeps of a rank's off-diagonal part for its overlapped block: the
/// overlap (the global rows its columns name, ascending) and, per row, the columns as the
/// block numbers them (n_owned + the position in the overlap).
struct Overlap {
    rows: Vec<usize>,
    ptr: Vec<usize>,
    cols: Vec<u32>,
}

impl Overlap {
    /// The overlap of a rank's rows whose off-diagonal part is `(ptr, cols, _)` (global
    /// columns, ascending in each row).
    fn of(n_owned: usize, (ptr, cols, _): &CsrParts) -> Self {
        let mut rows: Vec<usize> = cols.iter().map(|&g| g as usize).collect();
        rows.sort_unstable();
        rows.dedup();
        let cols = cols
            .iter()
            .map(|&g| (n_owned + rows.partition_point(|&r| r < g as usize)) as u32)
            .collect();
        Overlap {
            rows,
            ptr: ptr.clone(),
            cols,
        }
    }
}

impl RankBlock {
    /// The ILU(0) of this rank's diagonal block of Ã, its rows from the block's row `first` on
    /// kept for [`RankBlock::update`] with `value_of_entry` (for each of their entries, the
    /// index of its value among Ã's values from its first changing row on).
    fn new(block: &CsrMatrix, first: usize, value_of_entry: Vec<usize>) -> Result<Self, LaError> {
        let rows = first..block.n();
        let mut ptr = vec![0];
        rows.clone()
            .for_each(|i| ptr.push(ptr[ptr.len() - 1] + block.row(i).0.len()));
        let changing = (
            ptr,
            rows.flat_map(|i| block.row(i).0).copied().collect(),
            block.values_from(first).to_vec(),
        );
        Ok(RankBlock {
            ilu: Ilu0::new(block)?,
            changing,
            first_changing: first,
            value_of_entry,
        })
    }

    /// The ILU(0) of this rank's overlapped block for restricted additive Schwarz: its rows
    /// (`rows.owned`, read where PETSc keeps them, `matrix`) and the overlap's, on the columns
    /// of both, numbered [owned, overlap]; `a` holds Ã's rows from `first_changing` on, the
    /// rank's first of them its row `first`. Sets the matrix's overlap; collective (the
    /// overlap rows off Γ_C are fetched from their ranks).
    fn overlapped(
        matrix: &mut DistributedMatrix,
        rows: &RankRows,
        (a, first_changing, first): (&CsrMatrix, usize, usize),
        overlap: Overlap,
    ) -> Result<Self, LaError> {
        let n_owned = rows.owned.len();
        let n = n_owned + overlap.rows.len();
        matrix.set_overlap(&overlap.rows)?;
        let owned = rows.first..rows.first + n_owned;
        let block_col = |g: usize| match owned.contains(&g) {
            true => Some((g - owned.start) as u32),
            false => overlap.rows.binary_search(&g).ok().map(|v| (n_owned + v) as u32),
        };
        let mut row_of_overlap = vec![0; overlap.rows.len()];
        for (row, &g) in rows.global_of_row.iter().enumerate() {
            if let Some(b) = block_col(g).filter(|&b| b as usize >= n_owned) {
                row_of_overlap[b as usize - n_owned] = row;
            }
        }
        // The overlap rows that no linearization changes, from their ranks, once.
        let fixed: Vec<usize> = (0..overlap.rows.len())
            .filter(|&v| row_of_overlap[v] < first_changing)
            .collect();
        let fixed_rows: Vec<usize> = fixed.iter().map(|&v| overlap.rows[v]).collect();
        let mut columns: Vec<usize> = overlap.rows.iter().copied().chain(owned.clone()).collect();
        columns.sort_unstable();
        let (fetched_ptr, fetched_col, fetched_val) = matrix.fetch_rows(&fixed_rows, &columns)?;
        let mut changing = (vec![0], Vec::new(), Vec::new());
        let mut value_of_entry = Vec::new();
        let mut entries: Vec<(u32, f64, usize)> = Vec::new();
        for i in first..n {
            entries.clear();
            let row = match i.checked_sub(n_owned) {
                None => Some(rows.owned[i]),
                Some(v) => Some(row_of_overlap[v]).filter(|&row| row >= first_changing),
            };
            match row {
                Some(row) => {
                    let (cols, vals) = a.row(row);
                    let start = a.offset_from(first_changing, row).start;
                    for (j, (&c, &value)) in cols.iter().zip(vals).enumerate() {
                        if let Some(b) = block_col(rows.global_of_row[c as usize]) {
                            entries.push((b, value, start + j));
                        }
                    }
                }
                None => {
                    let f = fixed.binary_search(&(i - n_owned)).expect("an overlap row off Γ_C");
                    for e in fetched_ptr[f]..fetched_ptr[f + 1] {
                        let b = block_col(columns[fetched_col[e] as usize]).expect("a column of the block");
                        entries.push((b, fetched_val[e], FIXED));
                    }
                }
            }
            entries.sort_unstable_by_key(|e| e.0);
            changing.1.extend(entries.iter().map(|e| e.0));
            changing.2.extend(entries.iter().map(|e| e.1));
            value_of_entry.extend(entries.iter().map(|e| e.2));
            changing.0.push(changing.1.len());
        }
        let split = matrix.split_rows().ok_or_else(|| LaError::Petsc {
            operation: "MatCreateMPIAIJWithSplitArrays",
            detail: "the overlapped block reads the rank's rows from its split arrays".into(),
        })?;
        let (ptr, col, val) = &changing;
        let ilu = Ilu0::from_row_parts(n, [0, 0], |i| match i.checked_sub(first) {
            None => {
                let (diagonal, off_values) = split.row(i);
                let o = overlap.ptr[i]..overlap.ptr[i + 1];
                [diagonal, (&overlap.cols[o], off_values)]
            }
            Some(c) => {
                let r = ptr[c]..ptr[c + 1];
                [(&col[r.clone()], &val[r]), (&[], &[])]
            }
        })?;
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
        (val.iter_mut().zip(&self.value_of_entry))
            .filter(|(_, &p)| p != FIXED)
            .for_each(|(v, &p)| *v = all[p]);
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
    /// The global index of this rank's first row: `global_of_row[owned[i]]` is `first + i`.
    first: usize,
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
        let (mut owned, mut first) = (Vec::new(), 0);
        for rank in 0..comm.size() {
            let range = layout.owned(rank);
            let mut rows: Vec<usize> = layout.order[range.clone()].iter().map(|&u| row_of_unknown[u]).collect();
            rows.sort_unstable();
            rows.iter()
                .zip(range.clone())
                .for_each(|(&row, g)| global_of_row[row] = g);
            if rank == comm.rank() {
                (owned, first) = (rows, range.start);
            }
        }
        Ok(RankRows {
            owned,
            global_of_row,
            first,
        })
    }

    /// The rows of Ã this rank assembles: its own, every row from `first_changing` on (those a
    /// linearization changes, which every rank forms from the same iterate) and the rows
    /// `also` (those whose right-hand side a linearization changes: the caller recomputes their
    /// residual).
    pub(crate) fn assembled(&self, first_changing: usize, also: &[usize]) -> Vec<usize> {
        let own = self.owned.iter().copied().filter(|&row| row < first_changing);
        let mut rows: Vec<usize> = own
            .chain(also.iter().copied().filter(|&row| row < first_changing))
            .collect();
        rows.sort_unstable();
        rows.dedup();
        rows.extend(first_changing..self.global_of_row.len());
        rows
    }

    /// This rank's rows of `a` as PETSc keeps them ([`DistributedMatrix::from_split`]): the
    /// diagonal block, in local columns, and the rest, in global columns; and for each entry of
    /// the diagonal block in the rows from `first_changing` on, the index of its value among
    /// `a`'s values from there. A rank's global rows are its system rows in their order, so the
    /// diagonal block is Ã's block of this rank's rows and columns, in the system's order.
    fn split(&self, a: &CsrMatrix, first_changing: usize) -> (CsrParts, CsrParts, Vec<usize>) {
        let n_owned = self.owned.len();
        let most: usize = self.owned.iter().map(|&row| a.row(row).0.len()).sum();
        let mut diagonal = (
            Vec::with_capacity(n_owned + 1),
            Vec::with_capacity(most),
            Vec::with_capacity(most),
        );
        let mut off_diagonal = (vec![0], Vec::new(), Vec::new());
        diagonal.0.push(0);
        let mut value_of_entry = Vec::new();
        let mut entries = Vec::new();
        for &row in &self.owned {
            let (cols, values) = a.row(row);
            entries.clear();
            entries.extend((cols.iter().enumerate()).map(|(j, &c)| (self.global_of_row[c as usize], j)));
            entries.sort_unstable();
            let changing = (row >= first_changing).then(|| a.offset_from(first_changing, row).start);
            for &(g, j) in &entries {
                match g.checked_sub(self.first).filter(|&local| local < n_owned) {
                    Some(local) => {
                        diagonal.1.push(local as u32);
                        diagonal.2.push(values[j]);
                        value_of_entry.extend(changing.map(|start| start + j));
                    }
                    None => {
                        off_diagonal.1.push(g as u32);
                        off_diagonal.2.push(values[j]);
                    }
                }
            }
            diagonal.0.push(diagonal.1.len());
            off_diagonal.0.push(off_diagonal.1.len());
        }
        (diagonal, off_diagonal, value_of_entry)
    }
}

impl RankKrylov {
    /// Sets PETSc's matrix up with this rank's rows of `a` (the system's rows, laid out by
    /// `rows`; at least [`RankRows::assembled`]'s rows of Ã), the rows from `first_changing`
    /// on those a linearization changes, and returns the solver with `a`'s rows from
    /// `first_changing` on and the rows `also` (before it: rows whose right-hand side a
    /// linearization changes), the only ones read after set-up (the others emptied:
    /// [`CsrMatrix::keep_rows`]); collective.
    ///
    /// One copy of the rank's rows is made, split as PETSc keeps them
    /// ([`DistributedMatrix::from_split`], which keeps that copy, not one of its own); `a`'s
    /// own rows are dropped before the block's ILU(0) is factored from the diagonal part.
    /// Measured at 972k unknowns on 2 ranks: docs/distributed.md.
    pub(crate) fn new(
        rows: RankRows,
        (a, first_changing, also): (CsrMatrix, usize, &[usize]),
        params: DistributedKrylov,
    ) -> Result<(Self, CsrMatrix), LaError> {
        let comm = Communicator::world()?;
        // This rank's first changing row, by its index among the rank's rows.
        let first = rows.owned.partition_point(|&row| row < first_changing);
        let (diagonal, off_diagonal, value_of_entry) = rows.split(&a, first_changing);
        let n_entries = diagonal.1.len() + off_diagonal.1.len();
        let a = a.keep_rows(first_changing, also);
        let mut overlap = None;
        let (diagonal, mut block) = match params.preconditioner {
            DistributedPreconditioner::BlockJacobiShell => {
                let block = CsrMatrix::from_rows(rows.owned.len(), diagonal.0, diagonal.1, diagonal.2);
                let factored = RankBlock::new(&block, first, value_of_entry)?;
                (block.into_parts(), Some(Box::new(factored)))
            }
            DistributedPreconditioner::SchwarzShell | DistributedPreconditioner::SchwarzAmgShell => {
                overlap = Some(Overlap::of(rows.owned.len(), &off_diagonal));
                (diagonal, None)
            }
            _ => (diagonal, None),
        };
        let mut matrix = DistributedMatrix::from_split(&comm, diagonal, off_diagonal)?;
        if params.preconditioner == DistributedPreconditioner::BlockJacobiShell {
            // Block Jacobi is Schwarz without an overlap: the two-level method sweeps with it.
            matrix.set_overlap(&[])?;
        }
        // Where the rows a linearization changes are: the rank's own (below), its overlap's,
        // the others'.
        let mut changing_here = vec![RowHere::Elsewhere; a.n() - first_changing];
        if let Some(overlap) = &overlap {
            for (here, row) in changing_here.iter_mut().zip(first_changing..) {
                if overlap.rows.binary_search(&rows.global_of_row[row]).is_ok() {
                    *here = RowHere::Overlap;
                }
            }
        }
        if let Some(overlap) = overlap {
            let block_of = RankBlock::overlapped(&mut matrix, &rows, (&a, first_changing, first), overlap)?;
            block = Some(Box::new(block_of));
        }
        let changing = &rows.owned[first..];
        let (mut ptr, mut cols) = (vec![0], Vec::new());
        for &row in changing {
            cols.extend(a.row(row).0.iter().map(|&c| rows.global_of_row[c as usize]));
            ptr.push(cols.len());
        }
        changing
            .iter()
            .for_each(|&row| changing_here[row - first_changing] = RowHere::Owned);
        let globals: Vec<usize> = changing.iter().map(|&row| rows.global_of_row[row]).collect();
        let changing = Box::new(ChangingRows {
            first,
            pattern: matrix.row_pattern(&globals, &ptr, &cols)?,
            values: Vec::with_capacity(cols.len()),
        });
        let mut read: Vec<usize> = (first_changing..a.n())
            .chain(also.iter().copied())
            .flat_map(|row| a.row(row).0.iter().map(|&c| c as usize))
            .collect();
        read.sort_unstable();
        read.dedup();
        matrix.select(&read.iter().map(|&row| rows.global_of_row[row]).collect::<Vec<_>>())?;
        let exchange = Box::new(SolveExchange {
            owned_rhs: Vec::with_capacity(rows.owned.len()),
            owned_x: Vec::with_capacity(rows.owned.len()),
            owned_residual: Vec::with_capacity(rows.owned.len()),
            read_values: vec![0.0; read.len()],
            read,
        });
        let solver = RankKrylov {
            matrix,
            rows,
            params,
            n_entries,
            block,
            first_changing,
            changing,
            exchange,
            changing_here,
            comm,
        };
        Ok((solver, a))
    }

    /// Ã's values into PETSc's matrix (this rank's rows), and into this rank's block, whose
    /// rows from Ã's row `first_changed` on are refactored; collective. Only rows from
    /// `first_changing` on change after set-up (A's rows are fixed per step size): those are
    /// the rows set again.
    pub(crate) fn set_matrix(&mut self, a: &CsrMatrix, first_changed: usize) -> Result<(), LaError> {
        debug_assert!(
            first_changed >= self.first_changing,
            "a row before the changing ones changed"
        );
        self.set_changing_rows(a)?;
        match &mut self.block {
            Some(block) => block.update(a, self.first_changing),
            None => Ok(()),
        }
    }

    /// The values of this rank's rows of Ã that a linearization changes (its last, in the
    /// system's order) into PETSc's matrix, through the pattern set up once; collective.
    fn set_changing_rows(&mut self, a: &CsrMatrix) -> Result<(), LaError> {
        let ChangingRows { first, pattern, values } = &mut *self.changing;
        values.clear();
        for &row in &self.rows.owned[*first..] {
            values.extend_from_slice(a.row(row).1);
        }
        self.matrix.set_rows(pattern, values)
    }

    /// Solves Ã x = b̃ by PETSc's GCR from x (b̃ and x in the system's order, the same on every
    /// rank at the rows it reads: its own), x replaced by the solution at this rank's own rows
    /// and at the rows a linearization reads (the columns of Ã's Γ_C rows, the same on every
    /// rank), the other rows left as they were; collective. So between the Newton iterations
    /// of a step a rank's x is the iterate where the iterations read it, and
    /// [`RankKrylov::gather_whole`] makes it whole once the step is solved: a gather of the
    /// Γ_C rows' neighbourhood per Newton iteration, of N values per step.
    ///
    /// `residual`, as the serial [`Gmres::solve`](crate::la::Gmres::solve)'s but read and
    /// written at this rank's own rows only: when it has n entries, b̃ − Ã x at those rows,
    /// which the solve starts from instead of a product with Ã (a caller recomputes it where a
    /// linearization changed Ã or b̃: Ã's kept rows, [`RankKrylov::new`]); left with n entries
    /// holding the solution's residual there (PETSc's GCR keeps it), or empty after a failure.
    /// `forcing`: the inexact Newton forcing term of
    /// [`DistributedMatrix::solve_from_inexact`](crate::la::mpi::DistributedMatrix::solve_from_inexact) (0: to rtol).
    pub(crate) fn solve(
        &mut self,
        rhs: &[f64],
        x: &mut [f64],
        residual: &mut Vec<f64>,
        forcing: f64,
    ) -> Result<SolveInfo, LaError> {
        let SolveExchange {
            owned_rhs,
            owned_x,
            owned_residual,
            read,
            read_values,
        } = &mut *self.exchange;
        let owned = &self.rows.owned;
        owned_rhs.clear();
        owned_rhs.extend(owned.iter().map(|&row| rhs[row]));
        owned_x.clear();
        owned_x.extend(owned.iter().map(|&row| x[row]));
        owned_residual.clear();
        if residual.len() == x.len() {
            owned_residual.extend(owned.iter().map(|&row| residual[row]));
        }
        let block = self.block.as_ref().map(|b| &b.ilu as &dyn Preconditioner);
        let solved =
            (self.matrix).solve_from_inexact(&self.params, (owned_rhs, owned_x), Some(owned_residual), block, forcing);
        // Every rank reaches here with the same outcome (PETSc's reason is collective).
        let info = match solved {
            Ok(info) => info,
            Err(failed) => {
                residual.clear();
                return Err(failed);
            }
        };
        residual.resize(x.len(), 0.0);
        owned
            .iter()
            .zip(owned_residual.iter())
            .for_each(|(&row, &r)| residual[row] = r);
        self.matrix.gather_selected(read_values)?;
        let own = owned.iter().zip(owned_x.iter());
        own.chain(read.iter().zip(read_values.iter()))
            .for_each(|(&row, &value)| x[row] = value);
        Ok(SolveInfo {
            iterations: info.iterations,
            residual: info.residual,
        })
    }

    /// Where row `row` of Ã (one a linearization changes: from `first_changing` on) is kept.
    pub(crate) fn row_here(&self, row: usize) -> RowHere {
        self.changing_here[row - self.first_changing]
    }

    /// Values that each rank holds at its own entries (the others −0.0), summed over the
    /// ranks: every entry its owner's, to the bit (x + (−0.0) = x); collective.
    pub(crate) fn share_owned_entries(&self, values: &mut [f64]) -> Result<(), LaError> {
        self.comm.all_reduce_f64(values, crate::la::mpi::Reduction::Sum)
    }

    /// The last solution, whole, into x (the system's order) on every rank; collective.
    pub(crate) fn gather_whole(&mut self, x: &mut [f64]) -> Result<(), LaError> {
        let whole = self.matrix.all_gather()?;
        x.iter_mut()
            .zip(&self.rows.global_of_row)
            .for_each(|(x, &g)| *x = whole[g]);
        Ok(())
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
        let solved = self.solve(rhs, x, &mut Vec::new(), 0.0);
        self.params = kept;
        solved
    }

    /// Switches to the two-level method ([`DistributedPreconditioner::SchwarzAmgShell`]): GAMG
    /// on the velocity block of the step matrix of step size k (its rows of this rank assembled
    /// again from `problem`, the system's rows being the unknowns `order`), between sweeps with
    /// this rank's block, overlapping or not; collective. For `amg`, and for `auto` where the
    /// one-level sweeps need too many iterations.
    pub(crate) fn set_velocity_amg(&mut self, problem: &Problem, k: f64, order: &[usize]) -> Result<(), LaError> {
        if self.block.is_none() {
            return Err(LaError::Petsc {
                operation: "PCGAMG (velocity block)",
                detail: "the two-level method sweeps with this crate's ILU(0) of each rank's block".into(),
            });
        }
        let comm = Communicator::world()?;
        let partition = problem.partition(&comm)?;
        let (a, _) = crate::model::ordered_rows_at(problem, k, order, &self.rows.owned);
        let block = RankVelocityBlock::new(
            problem,
            &a,
            order,
            &self.rows.owned,
            (&partition.node_owner, comm.rank()),
        )?;
        drop(a);
        let (ptr, col, val) = &block.rows;
        self.matrix
            .set_velocity_amg((ptr, col, val), problem.dim(), &block.modes, &block.slots)?;
        self.params.preconditioner = DistributedPreconditioner::SchwarzAmgShell;
        Ok(())
    }

    /// The preconditioner PETSc runs.
    pub(crate) fn preconditioner(&self) -> DistributedPreconditioner {
        self.params.preconditioner
    }

    /// Stored entries of Ã on this rank.
    pub(crate) fn nnz(&self) -> usize {
        self.n_entries
    }
}
