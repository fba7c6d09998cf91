//! Linear solvers for the step system A x = b: the direct LDLᵀ of today and a first iterative one,
//! restarted GMRES right-preconditioned by ILU(0) of A (issue 11).
//!
//! A = [[ℳ/k + 𝒦_A + k𝒦_B, G], [−Gᵀ, ℳ_θ/k + 𝒦_θ]] is not symmetric, but its symmetric part is
//! block-diagonal with SPD blocks (A is positive real), so GMRES converges and ILU(0) needs no
//! pivoting. Why this pair and when it pays (the study that chose it): docs/krylov-study.md. In
//! short: at the paper's time step (k = 1/64) the mass term dominates and GMRES + ILU(0) needs
//! 5–7 iterations at 10⁵–10⁶ unknowns; the iteration count grows with k (≈ 20 at k = 1/8), where
//! the AMG coarse correction of [`super::amg`] keeps it bounded ([`Preconditioner`] is what
//! GMRES sees of either).
//!
//! The iterative path's step solver ([`super::newton_krylov`]) uses [`gmres`] and [`Ilu0`]
//! directly: its matrix changes in the contact rows at every Newton iteration, and
//! [`Ilu0::refactor_from`] refactors just those rows. [`LinearSolver`], with [`DirectSolver`]
//! and [`IterativeSolver`] for the constant step matrix, is the interface the studies and
//! `tests/krylov.rs` compare the two kinds of solve through.

use rayon::prelude::*;

use super::factor::QuasiDefiniteLdlt;
use crate::error::{Error, FactorStage};
use crate::fem::sparse::CscMatrix;

/// Tolerance and caps of a Krylov solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KrylovParams {
    /// Stop when ‖b − A x‖ ≤ rtol ‖b‖ (the true, unpreconditioned residual).
    pub rtol: f64,
    /// Iteration cap (products with A).
    pub max_iterations: usize,
    /// GMRES restart length.
    pub restart: usize,
    /// ILU(0) alone, or with the AMG coarse correction of the velocities ([`super::amg`]).
    pub preconditioner: PreconditionerKind,
}

/// The preconditioner of the iterative path's GMRES.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PreconditionerKind {
    /// ILU(0) of the Newton matrix: bounded iterations while the mass term dominates (the
    /// paper's k), growing like h⁻¹ once the stiffness weighs.
    #[default]
    Ilu,
    /// ILU(0) sweeps around a smoothed-aggregation AMG correction of the velocities (PETSc's
    /// GAMG; builds with the `petsc` feature): bounded iterations where the stiffness weighs.
    Amg,
    /// [`PreconditionerKind::Amg`] where the build has it and ILU(0) needs more than
    /// [`PreconditionerKind::AUTO_AMG_ABOVE`] Krylov iterations for the first step's system,
    /// [`PreconditionerKind::Ilu`] otherwise ([`super::newton_krylov::KrylovSystem::new`]).
    Auto,
}

impl PreconditionerKind {
    /// The ILU(0) Krylov count (first step's system from zero, relative residual 10⁻⁸) above
    /// which `auto` sets up the AMG. An AMG-preconditioned iteration costs 4–6 ILU(0) ones (two
    /// sweeps, two products with Ã and PETSc's single-threaded V-cycle), and the warm-started
    /// Newton solves of a run need fewer iterations than this cold probe, so the AMG pays only
    /// where ILU(0)'s count is far beyond its own 7–14. Measured on the 3D example at 70k
    /// unknowns, 4 steps (README, "3D at scale"): at k = 1/8 (probe 19) ILU(0) runs the solves
    /// in 4.9 s, the AMG in 9.5 s; at k = 1/2 (probe 71) 30.3 s against 30.5 s; at k = 1 (probe
    /// 146) 39.0 s against 22.6 s.
    pub const AUTO_AMG_ABOVE: usize = 80;

    /// The name in scenarios and summaries.
    pub fn name(&self) -> &'static str {
        match self {
            PreconditionerKind::Ilu => "ilu",
            PreconditionerKind::Amg => "amg",
            PreconditionerKind::Auto => "auto",
        }
    }
}

impl Default for KrylovParams {
    fn default() -> Self {
        KrylovParams {
            rtol: 1e-10,
            max_iterations: 500,
            restart: 30,
            preconditioner: PreconditionerKind::Ilu,
        }
    }
}

/// What a solve did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveInfo {
    /// Krylov iterations (0 for a direct solve).
    pub iterations: usize,
    /// ‖b − A x‖ / ‖b‖ at the end as the method estimates it (0 for a direct solve).
    pub residual: f64,
}

/// A fixed linear approximation M⁻¹ of A⁻¹ for right-preconditioned GMRES.
pub trait Preconditioner {
    /// z = M⁻¹ r.
    fn apply(&self, r: &[f64], z: &mut [f64]) -> Result<(), Error>;

    /// The method's name with this preconditioner, for the error of a solve that fails.
    fn method(&self) -> &'static str;
}

impl Preconditioner for Ilu0 {
    fn apply(&self, r: &[f64], z: &mut [f64]) -> Result<(), Error> {
        Ilu0::apply(self, r, z);
        Ok(())
    }

    fn method(&self) -> &'static str {
        "GMRES + ILU(0)"
    }
}

/// A solver of the step system A x = b, set up once for the constant matrix.
pub trait LinearSolver: Send + Sync {
    /// Number of unknowns.
    fn n(&self) -> usize;

    /// Solves A x = b; on entry `x` holds the initial guess (a direct solver ignores it).
    fn solve(&self, b: &[f64], x: &mut [f64]) -> Result<SolveInfo, Error>;
}

/// A square sparse matrix stored by rows, column indices sorted within each row.
#[derive(Debug, Clone)]
pub struct CsrMatrix {
    n: usize,
    ptr: Vec<usize>,
    /// Column indices, 32-bit: a quarter less data per product than 64-bit ones
    /// (docs/krylov-study.md, §5).
    col: Vec<u32>,
    val: Vec<f64>,
}

impl CsrMatrix {
    /// A = J S from the symmetric form S = J A of the step matrix ([`super::system::StepSystem`]
    /// stores S), J = diag(I, −I) with the first `n_w` unknowns the velocities: S's columns are
    /// its rows, so A's rows are S's columns with the temperature rows negated.
    pub fn from_symmetric_form(s: &CscMatrix, n_w: usize) -> Self {
        assert_eq!(s.n_rows, s.n_cols, "a square matrix");
        let mut val = s.values.clone();
        for row in n_w..s.n_cols {
            for v in &mut val[s.col_ptr[row]..s.col_ptr[row + 1]] {
                *v = -*v;
            }
        }
        CsrMatrix {
            n: s.n_rows,
            ptr: s.col_ptr.to_vec(),
            col: s.row_idx.iter().map(|&r| index32(r)).collect(),
            val,
        }
    }

    /// Number of rows (and columns).
    pub fn n(&self) -> usize {
        self.n
    }

    /// A matrix from its rows: `ptr` (n + 1 offsets), each row's column indices sorted.
    ///
    /// # Panics
    /// If the offsets do not match the entries.
    pub fn from_rows(n: usize, ptr: Vec<usize>, col: Vec<u32>, val: Vec<f64>) -> Self {
        assert!(ptr.len() == n + 1 && ptr[n] == col.len() && col.len() == val.len());
        CsrMatrix { n, ptr, col, val }
    }

    /// P A Pᵀ of A = J S (as [`CsrMatrix::from_symmetric_form`]) for the ordering `order`:
    /// row and column i of the result are row and column `order[i]` of A.
    ///
    /// # Panics
    /// If `order` is not a permutation of S's unknowns.
    pub fn from_symmetric_form_ordered(s: &CscMatrix, n_w: usize, order: &[usize]) -> Self {
        assert_eq!(order.len(), s.n_cols, "an ordering of every unknown");
        let mut position = vec![usize::MAX; order.len()];
        for (new, &old) in order.iter().enumerate() {
            assert_eq!(position[old], usize::MAX, "unknown {old} ordered twice");
            position[old] = new;
        }
        let mut ptr = Vec::with_capacity(s.n_cols + 1);
        let mut col = Vec::with_capacity(s.values.len());
        let mut val = Vec::with_capacity(s.values.len());
        let mut row: Vec<(usize, f64)> = Vec::new();
        ptr.push(0);
        for &old in order {
            // Row `old` of A is column `old` of S, negated in the temperature rows.
            let sign = if old < n_w { 1.0 } else { -1.0 };
            let range = s.col_ptr[old]..s.col_ptr[old + 1];
            row.clear();
            row.extend(
                s.row_idx[range.clone()]
                    .iter()
                    .zip(&s.values[range])
                    .map(|(&c, &v)| (position[c], sign * v)),
            );
            row.sort_unstable_by_key(|&(c, _)| c);
            col.extend(row.iter().map(|&(c, _)| index32(c)));
            val.extend(row.iter().map(|&(_, v)| v));
            ptr.push(col.len());
        }
        CsrMatrix {
            n: s.n_cols,
            ptr,
            col,
            val,
        }
    }

    /// Row i: its column indices and values.
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let range = self.ptr[i]..self.ptr[i + 1];
        (&self.col[range.clone()], &self.val[range])
    }

    /// The diagonal entry A_ii (0 where the pattern has none).
    pub fn diagonal(&self, i: usize) -> f64 {
        let (cols, vals) = self.row(i);
        cols.binary_search(&index32(i)).map_or(0.0, |p| vals[p])
    }

    /// Row i's values, to change them in place (the pattern stays).
    pub fn row_values_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.val[self.ptr[i]..self.ptr[i + 1]]
    }

    /// The values of rows `first..n`, one after the other (the rows are stored in order).
    pub fn values_from(&self, first: usize) -> &[f64] {
        &self.val[self.ptr[first]..]
    }

    /// The same, to change in place.
    pub fn values_from_mut(&mut self, first: usize) -> &mut [f64] {
        &mut self.val[self.ptr[first]..]
    }

    /// Σ_c v_c x_c over row i's pattern with the values `values` (row i's own, or another
    /// matrix's on the same pattern).
    pub fn row_dot(&self, i: usize, values: &[f64], x: &[f64]) -> f64 {
        sparse_dot32(&self.col[self.ptr[i]..self.ptr[i + 1]], values, x, 0)
    }

    /// Where row i starts among rows `first..n` ([`Self::values_from`]).
    pub fn offset_from(&self, first: usize, i: usize) -> std::ops::Range<usize> {
        self.ptr[i] - self.ptr[first]..self.ptr[i + 1] - self.ptr[first]
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.val.len()
    }

    /// y = A x, rows in parallel blocks: each row's sum is computed alone and in one order,
    /// so y is the same to the bit on any number of threads.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        y[..self.n]
            .par_chunks_mut(MUL_ROWS_PER_TASK)
            .enumerate()
            .for_each(|(block, ys)| {
                let first = block * MUL_ROWS_PER_TASK;
                for (i, y) in (first..).zip(ys.iter_mut()) {
                    let (s, e) = (self.ptr[i], self.ptr[i + 1]);
                    *y = sparse_dot32(&self.col[s..e], &self.val[s..e], x, 0);
                }
            });
    }
}

/// Rows per parallel task of a product with A: large enough that a task's work (≈ 60 entries a
/// row in 3D) dwarfs its scheduling.
const MUL_ROWS_PER_TASK: usize = 8192;

/// A matrix index as the 32-bit index the CSR and ILU(0) layouts store.
///
/// # Panics
/// Past 2³² unknowns, which the memory estimate refuses long before (`crate::resources`).
fn index32(i: usize) -> u32 {
    u32::try_from(i).expect("fewer than 2^32 unknowns")
}

/// Σ v·x[c − offset] over 32-bit column indices (x holds the unknowns from `offset` on) with
/// four partial sums: a single sequential sum makes each row a long chain of dependent additions
/// (docs/krylov-study.md, §5).
#[inline]
fn sparse_dot32<V: Copy + Into<f64>>(cols: &[u32], vals: &[V], x: &[f64], offset: usize) -> f64 {
    let mut acc = [0.0; 4];
    let (c4, v4) = (cols.chunks_exact(4), vals.chunks_exact(4));
    let (cr, vr) = (c4.remainder(), v4.remainder());
    for (c, v) in c4.zip(v4) {
        for k in 0..4 {
            acc[k] += v[k].into() * x[c[k] as usize - offset];
        }
    }
    let tail: f64 = cr
        .iter()
        .zip(vr)
        .map(|(&c, &v)| v.into() * x[c as usize - offset])
        .sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// ILU(0) of a [`CsrMatrix`]: L (unit diagonal) and U on A's own pattern.
///
/// Stored for its sweeps: L and U in separate arrays, so that each sweep streams only its own
/// half, with 32-bit column indices and U's inverted diagonal. Measured at 98k unknowns: one
/// solve 5 ms, against 26 ms with L and U left interleaved in A's rows (docs/krylov-study.md, §5).
///
/// The off-diagonal values are kept in single precision (the sweeps sum in double). A sweep reads
/// each entry once and does two flops with it, so it runs at the memory's speed, and at 3·10⁵
/// unknowns one sweep on one core already streams ≈ 20 GB/s, near what both cores get: a
/// second core would add little, a smaller entry (8 bytes with its index instead of 12) takes a
/// third off. The preconditioner only has to be *a* fixed approximation of Ã⁻¹: rounding its
/// entries to 6·10⁻⁸ is far inside what ILU(0) already drops, and GMRES still works to the true
/// residual of Ã in double precision.
#[derive(Debug, Clone)]
pub struct Ilu0 {
    l_ptr: Vec<usize>,
    l_col: Vec<u32>,
    l_val: Vec<f32>,
    u_ptr: Vec<usize>,
    u_col: Vec<u32>,
    u_val: Vec<f32>,
    inv_diag: Vec<f64>,
    /// Rows `0..parts[0]` and `parts[0]..parts[1]` share no entry of A: the sweeps run them on
    /// two threads, then the rows from `parts[1]` on in sequence ([`Ilu0::with_domains`]).
    parts: [usize; 2],
    /// The dense row of [`Ilu0::refactor_from`], kept between the refactorizations of the
    /// contact rows at every Newton iteration.
    scratch: RowScratch,
}

impl Ilu0 {
    /// Factors A (IKJ order, no pivoting). A zero or non-finite pivot is an error.
    ///
    /// The factor is laid out first and then computed row by row into that layout
    /// ([`Ilu0::refactor_from`] from row 0): no second copy of A's values (0.45 GB at 10⁶
    /// unknowns).
    pub fn new(a: &CsrMatrix) -> Result<Self, Error> {
        Self::with_domains(a, [0, 0])
    }

    /// Factors A whose rows `0..parts[0]` and `parts[0]..parts[1]` are two domains that share no
    /// entry (neither has a column in the other): each sweep of [`Ilu0::apply`] runs the two on
    /// two threads, then the remaining rows in sequence. The factor is the same as
    /// [`Ilu0::new`]'s; only the sweeps' schedule differs, and their result is the same to the
    /// bit on any number of threads. Domains that do share an entry are an error.
    pub fn with_domains(a: &CsrMatrix, parts: [usize; 2]) -> Result<Self, Error> {
        let n = a.n;
        let [first_end, second_end] = parts;
        if first_end > second_end || second_end > n {
            return Err(Error::Factorization {
                stage: FactorStage::IncompleteLu,
                detail: format!("domains 0..{first_end} and {first_end}..{second_end} of {n} rows"),
            });
        }
        let crossing =
            |i: usize, other: std::ops::Range<usize>| a.row(i).0.iter().any(|&c| other.contains(&(c as usize)));
        if let Some(i) = (0..first_end)
            .find(|&i| crossing(i, first_end..second_end))
            .or_else(|| (first_end..second_end).find(|&i| crossing(i, 0..first_end)))
        {
            return Err(Error::Factorization {
                stage: FactorStage::IncompleteLu,
                detail: format!("row {i} couples the domains 0..{first_end} and {first_end}..{second_end}"),
            });
        }
        if u32::try_from(n).is_err() {
            return Err(Error::Factorization {
                stage: FactorStage::IncompleteLu,
                detail: format!("{n} unknowns exceed 32-bit indices"),
            });
        }
        let mut diag = Vec::with_capacity(n);
        for i in 0..n {
            match a.row(i).0.binary_search(&(i as u32)) {
                Ok(p) => diag.push(a.ptr[i] + p),
                Err(_) => {
                    return Err(Error::Factorization {
                        stage: FactorStage::IncompleteLu,
                        detail: format!("row {i} has no diagonal entry"),
                    })
                }
            }
        }
        let n_lower: usize = (0..n).map(|i| diag[i] - a.ptr[i]).sum();
        let mut f = Ilu0 {
            l_ptr: Vec::with_capacity(n + 1),
            l_col: Vec::with_capacity(n_lower),
            l_val: vec![0.0f32; n_lower],
            u_ptr: Vec::with_capacity(n + 1),
            u_col: Vec::with_capacity(a.nnz() - n_lower - n),
            u_val: vec![0.0f32; a.nnz() - n_lower - n],
            inv_diag: vec![0.0; n],
            parts,
            scratch: RowScratch::new(n),
        };
        f.l_ptr.push(0);
        f.u_ptr.push(0);
        for i in 0..n {
            f.l_col.extend_from_slice(&a.col[a.ptr[i]..diag[i]]);
            f.l_ptr.push(f.l_col.len());
            f.u_col.extend_from_slice(&a.col[diag[i] + 1..a.ptr[i + 1]]);
            f.u_ptr.push(f.u_col.len());
        }
        f.refactor_from(a, 0)?;
        Ok(f)
    }

    /// Factors rows `first..n` of A again after their values changed, rows before `first`
    /// unchanged: the rows of an ILU(0) depend only on the rows above them, so a matrix whose
    /// changing rows are ordered last is refactored in time proportional to those rows (the
    /// contact rows of a Newton matrix, [`super::newton_krylov`]). From row 0, the two domains
    /// of [`Ilu0::with_domains`] are factored on two threads.
    pub fn refactor_from(&mut self, a: &CsrMatrix, first: usize) -> Result<(), Error> {
        let [first_end, second_end] = self.parts;
        let Ilu0 {
            l_ptr,
            l_col,
            l_val,
            u_ptr,
            u_col,
            u_val,
            inv_diag,
            scratch,
            ..
        } = self;
        let pattern = Pattern {
            l_ptr,
            l_col,
            u_ptr,
            u_col,
        };
        let mut sequential_from = first;
        if first == 0 && second_end > 0 {
            let (l1, l2) = l_val[..l_ptr[second_end]].split_at_mut(l_ptr[first_end]);
            let (u1, u2) = u_val[..u_ptr[second_end]].split_at_mut(u_ptr[first_end]);
            let (d1, d2) = inv_diag[..second_end].split_at_mut(first_end);
            // Each domain's rows refer only to its own: its values start at its first row.
            let (r1, r2) = rayon::join(
                || pattern.factor_rows(a, 0..first_end, 0, (l1, u1, d1), &mut RowScratch::new(a.n)),
                || {
                    pattern.factor_rows(
                        a,
                        first_end..second_end,
                        first_end,
                        (l2, u2, d2),
                        &mut RowScratch::new(a.n),
                    )
                },
            );
            r1.and(r2)?;
            sequential_from = second_end;
        }
        pattern.factor_rows(a, sequential_from..a.n, 0, (l_val, u_val, inv_diag), scratch)
    }

    /// Stored entries of L and U (the diagonal included).
    pub fn nnz(&self) -> usize {
        self.l_val.len() + self.u_val.len() + self.inv_diag.len()
    }

    /// z = (LU)⁻¹ r.
    pub fn apply(&self, r: &[f64], z: &mut [f64]) {
        let n = self.inv_diag.len();
        let [first_end, second_end] = self.parts;
        {
            let (parts, _) = z.split_at_mut(second_end);
            let (first, second) = parts.split_at_mut(first_end);
            rayon::join(
                || self.forward(0..first_end, r, first),
                || self.forward(first_end..second_end, r, second),
            );
        }
        self.forward_rest(second_end, r, z);
        for i in (second_end..n).rev() {
            let (s, e) = (self.u_ptr[i], self.u_ptr[i + 1]);
            z[i] = (z[i] - sparse_dot32(&self.u_col[s..e], &self.u_val[s..e], z, 0)) * self.inv_diag[i];
        }
        let (parts, rest) = z.split_at_mut(second_end);
        let (first, second) = parts.split_at_mut(first_end);
        rayon::join(
            || self.backward(0..first_end, first, rest, second_end),
            || self.backward(first_end..second_end, second, rest, second_end),
        );
    }

    /// The forward sweep over the rows of one domain, whose unknowns are `z` (z\[0\] is row
    /// `rows.start`): their L entries lie inside the domain.
    fn forward(&self, rows: std::ops::Range<usize>, r: &[f64], z: &mut [f64]) {
        let offset = rows.start;
        for i in rows {
            let (s, e) = (self.l_ptr[i], self.l_ptr[i + 1]);
            z[i - offset] = r[i] - sparse_dot32(&self.l_col[s..e], &self.l_val[s..e], z, offset);
        }
    }

    /// The forward sweep over the rows from `first` on, which may see any earlier row.
    fn forward_rest(&self, first: usize, r: &[f64], z: &mut [f64]) {
        for i in first..self.inv_diag.len() {
            let (s, e) = (self.l_ptr[i], self.l_ptr[i + 1]);
            z[i] = r[i] - sparse_dot32(&self.l_col[s..e], &self.l_val[s..e], z, 0);
        }
    }

    /// The backward sweep over the rows of one domain (`z` as in [`Ilu0::forward`]): their U
    /// entries lie inside the domain or in the rows from `rest_start` on, already swept (`rest`).
    fn backward(&self, rows: std::ops::Range<usize>, z: &mut [f64], rest: &[f64], rest_start: usize) {
        let (offset, end) = (rows.start, rows.end as u32);
        for i in rows.rev() {
            let (s, e) = (self.u_ptr[i], self.u_ptr[i + 1]);
            let (cols, vals) = (&self.u_col[s..e], &self.u_val[s..e]);
            let inside = cols.partition_point(|&c| c < end);
            let sum = sparse_dot32(&cols[..inside], &vals[..inside], z, offset)
                + sparse_dot32(&cols[inside..], &vals[inside..], rest, rest_start);
            z[i - offset] = (z[i - offset] - sum) * self.inv_diag[i];
        }
    }
}

/// The pattern of an [`Ilu0`], borrowed apart from its values so that two threads can fill
/// the values of two domains.
struct Pattern<'a> {
    l_ptr: &'a [usize],
    l_col: &'a [u32],
    u_ptr: &'a [usize],
    u_col: &'a [u32],
}

/// The values (L, U, inverted diagonal) of the factor's rows from some row on.
type RowValues<'v> = (&'v mut [f32], &'v mut [f32], &'v mut [f64]);

/// A row of the factorization spread over all columns, zero and unmarked between rows.
#[derive(Debug, Clone)]
struct RowScratch {
    dense: Vec<f64>,
    in_row: Vec<bool>,
}

impl RowScratch {
    fn new(n: usize) -> Self {
        RowScratch {
            dense: vec![0.0; n],
            in_row: vec![false; n],
        }
    }
}

impl Pattern<'_> {
    /// Factors `rows` (IKJ order), reading the U rows above them: `values` hold the rows from
    /// `base` on, and every row that `rows` refer to lies there.
    fn factor_rows(
        &self,
        a: &CsrMatrix,
        rows: std::ops::Range<usize>,
        base: usize,
        (l_val, u_val, inv_diag): RowValues,
        scratch: &mut RowScratch,
    ) -> Result<(), Error> {
        let (l0, u0) = (self.l_ptr[base], self.u_ptr[base]);
        let RowScratch { dense, in_row } = scratch;
        for i in rows {
            let (cols, vals) = a.row(i);
            for (&c, &v) in cols.iter().zip(vals) {
                dense[c as usize] = v;
                in_row[c as usize] = true;
            }
            for k in cols.iter().map(|&k| k as usize).take_while(|&k| k < i) {
                let l = dense[k] * inv_diag[k - base];
                dense[k] = l;
                let range = self.u_ptr[k]..self.u_ptr[k + 1];
                let u_row = &u_val[range.start - u0..range.end - u0];
                for (&c, &u) in self.u_col[range].iter().zip(u_row) {
                    if in_row[c as usize] {
                        dense[c as usize] -= l * f64::from(u);
                    }
                }
            }
            let pivot = dense[i];
            if pivot == 0.0 || !pivot.is_finite() {
                // The scratch is kept for the next refactorization: leave it clean.
                for &c in cols {
                    dense[c as usize] = 0.0;
                    in_row[c as usize] = false;
                }
                return Err(Error::Factorization {
                    stage: FactorStage::IncompleteLu,
                    detail: format!("pivot {pivot} in row {i}"),
                });
            }
            let (l_range, u_range) = (self.l_ptr[i]..self.l_ptr[i + 1], self.u_ptr[i]..self.u_ptr[i + 1]);
            let l_row = &mut l_val[l_range.start - l0..l_range.end - l0];
            for (slot, &c) in l_row.iter_mut().zip(&self.l_col[l_range]) {
                *slot = dense[c as usize] as f32;
            }
            let u_row = &mut u_val[u_range.start - u0..u_range.end - u0];
            for (slot, &c) in u_row.iter_mut().zip(&self.u_col[u_range]) {
                *slot = dense[c as usize] as f32;
            }
            inv_diag[i - base] = 1.0 / pivot;
            for &c in cols {
                dense[c as usize] = 0.0;
                in_row[c as usize] = false;
            }
        }
        Ok(())
    }
}

/// Entries per block of the vector operations: the blocks' partial sums are computed in
/// parallel and added in block order, so a dot product is the same to the bit on any number of
/// threads.
const VECTOR_BLOCK: usize = 16_384;

/// a · b, by blocks ([`VECTOR_BLOCK`]).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let block = |(x, y): (&[f64], &[f64])| {
        let mut acc = [0.0; 4];
        let (x4, y4) = (x.chunks_exact(4), y.chunks_exact(4));
        let tail: f64 = x4.remainder().iter().zip(y4.remainder()).map(|(p, q)| p * q).sum();
        for (p, q) in x4.zip(y4) {
            for k in 0..4 {
                acc[k] += p[k] * q[k];
            }
        }
        (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
    };
    let partials: Vec<f64> = a
        .par_chunks(VECTOR_BLOCK)
        .zip(b.par_chunks(VECTOR_BLOCK))
        .map(block)
        .collect();
    partials.iter().sum()
}

/// y += alpha x, by blocks in parallel.
fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    y.par_chunks_mut(VECTOR_BLOCK)
        .zip(x.par_chunks(VECTOR_BLOCK))
        .for_each(|(y, x)| y.iter_mut().zip(x).for_each(|(y, x)| *y += alpha * x));
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Restarted GMRES(m), right-preconditioned (so its residual estimate is the true residual's),
/// modified Gram–Schmidt, Givens rotations. `x` holds the initial guess.
///
/// Fails with [`Error::KrylovNotConverged`] (with the residual history) at the iteration cap.
pub fn gmres(
    a: &CsrMatrix,
    pc: &dyn Preconditioner,
    b: &[f64],
    x: &mut [f64],
    params: &KrylovParams,
) -> Result<SolveInfo, Error> {
    let mut r = Vec::new();
    gmres_from_residual(a, pc, b, x, &mut r, params)
}

/// [`gmres`] with the residual r = b − A x of the initial guess given (when `r` has A's size;
/// otherwise it is computed), and left in `r` for the solution it returns: a caller whose next
/// system differs from this one in a few rows updates those rows of r instead of a product
/// with A ([`super::newton_krylov`]).
pub fn gmres_from_residual(
    a: &CsrMatrix,
    pc: &dyn Preconditioner,
    b: &[f64],
    x: &mut [f64],
    r: &mut Vec<f64>,
    params: &KrylovParams,
) -> Result<SolveInfo, Error> {
    let n = a.n;
    let m = params.restart.max(1);
    let mut w = vec![0.0; n];
    if r.len() != n {
        a.mul(x, &mut w);
        r.clear();
        r.extend(b.iter().zip(&w).map(|(b, ax)| b - ax));
    }
    let bnorm = norm(b);
    if bnorm == 0.0 {
        x.fill(0.0);
        r.fill(0.0);
        return Ok(SolveInfo::default());
    }
    let target = params.rtol * bnorm;
    let mut v: Vec<Vec<f64>> = Vec::with_capacity(m + 1);
    let mut history = vec![norm(r) / bnorm];
    let mut it = 0;
    loop {
        let beta = norm(r);
        if !beta.is_finite() {
            return Err(Error::NonFiniteSolution {
                non_finite: r.iter().filter(|v| !v.is_finite()).count(),
                unknowns: n,
            });
        }
        if beta <= target {
            return Ok(SolveInfo {
                iterations: it,
                residual: beta / bnorm,
            });
        }
        if it >= params.max_iterations {
            return Err(Error::KrylovNotConverged {
                method: pc.method(),
                iterations: it,
                rtol: params.rtol,
                residual: beta / bnorm,
                history,
            });
        }
        v.clear();
        v.push(r.iter().map(|r| r / beta).collect());
        // The preconditioned directions M⁻¹ v_j, kept for the update: x += Σ y_j M⁻¹ v_j costs
        // no further sweep of the factor (the sweeps are the sequential part of an iteration).
        let mut zs: Vec<Vec<f64>> = Vec::new();
        let mut h = vec![vec![0.0; m]; m + 1];
        let (mut cs, mut sn) = (vec![0.0; m], vec![0.0; m]);
        let mut g = vec![0.0; m + 1];
        g[0] = beta;
        let mut used = 0;
        for j in 0..m {
            let mut z = vec![0.0; n];
            pc.apply(&v[j], &mut z)?;
            a.mul(&z, &mut w);
            zs.push(z);
            for (i, vi) in v.iter().enumerate() {
                let hij = dot(&w, vi);
                h[i][j] = hij;
                axpy(-hij, vi, &mut w);
            }
            let hn = norm(&w);
            h[j + 1][j] = hn;
            v.push(w.iter().map(|w| if hn > 0.0 { w / hn } else { 0.0 }).collect());
            for i in 0..j {
                let t = cs[i] * h[i][j] + sn[i] * h[i + 1][j];
                h[i + 1][j] = -sn[i] * h[i][j] + cs[i] * h[i + 1][j];
                h[i][j] = t;
            }
            let d = h[j][j].hypot(h[j + 1][j]);
            cs[j] = h[j][j] / d;
            sn[j] = h[j + 1][j] / d;
            h[j][j] = d;
            h[j + 1][j] = 0.0;
            g[j + 1] = -sn[j] * g[j];
            g[j] *= cs[j];
            it += 1;
            used = j + 1;
            history.push(g[j + 1].abs() / bnorm);
            if g[j + 1].abs() <= target || it >= params.max_iterations || hn == 0.0 {
                break;
            }
        }
        // x += M⁻¹ V y = Σ y_j (M⁻¹ v_j) with H y = g.
        let mut y = vec![0.0; used];
        for i in (0..used).rev() {
            let s: f64 = g[i] - (i + 1..used).map(|k| h[i][k] * y[k]).sum::<f64>();
            y[i] = s / h[i][i];
        }
        for (zj, yj) in zs.iter().zip(&y) {
            axpy(*yj, zj, x);
        }
        a.mul(x, &mut w);
        r.iter_mut().zip(b.iter().zip(&w)).for_each(|(r, (b, ax))| *r = b - ax);
    }
}

/// GMRES + ILU(0) on the step matrix, set up once (the ILU(0) factor, as large as A).
pub struct IterativeSolver {
    a: CsrMatrix,
    pc: Ilu0,
    params: KrylovParams,
}

impl IterativeSolver {
    /// Sets the solver up for the step matrix given in its symmetric form S = J A (`n_w`
    /// velocity unknowns first).
    pub fn new(s: &CscMatrix, n_w: usize, params: KrylovParams) -> Result<Self, Error> {
        let a = CsrMatrix::from_symmetric_form(s, n_w);
        let pc = Ilu0::new(&a)?;
        Ok(IterativeSolver { a, pc, params })
    }

    /// The matrix A.
    pub fn matrix(&self) -> &CsrMatrix {
        &self.a
    }
}

impl LinearSolver for IterativeSolver {
    fn n(&self) -> usize {
        self.a.n
    }

    fn solve(&self, b: &[f64], x: &mut [f64]) -> Result<SolveInfo, Error> {
        gmres(&self.a, &self.pc, b, x, &self.params)
    }
}

/// Today's direct path as a [`LinearSolver`]: the LDLᵀ factor of S = J A.
pub struct DirectSolver {
    factor: QuasiDefiniteLdlt,
    n_w: usize,
}

impl DirectSolver {
    /// Factors S = J A (`n_w` velocity unknowns first).
    pub fn new(s: &CscMatrix, n_w: usize) -> Result<Self, Error> {
        Ok(DirectSolver {
            factor: QuasiDefiniteLdlt::new(s)?,
            n_w,
        })
    }
}

impl LinearSolver for DirectSolver {
    fn n(&self) -> usize {
        self.factor.n()
    }

    fn solve(&self, b: &[f64], x: &mut [f64]) -> Result<SolveInfo, Error> {
        x.copy_from_slice(b);
        x[self.n_w..].iter_mut().for_each(|v| *v = -*v);
        self.factor.solve_in_place(x, 1);
        match x.iter().filter(|v| !v.is_finite()).count() {
            0 => Ok(SolveInfo::default()),
            non_finite => Err(Error::NonFiniteSolution {
                non_finite,
                unknowns: x.len(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small nonsymmetric positive-real matrix in the S = J A form: S = [[K, G], [Gᵀ, −M]].
    fn small_s() -> (CscMatrix, usize) {
        let n_w = 4;
        let mut t = Vec::new();
        for i in 0..6 {
            let d = if i < n_w { 4.0 } else { -3.0 };
            t.push((i, i, d));
        }
        for i in 0..n_w - 1 {
            t.push((i, i + 1, -1.0));
            t.push((i + 1, i, -1.0));
        }
        for (r, c, g) in [(0, 4, 0.5), (2, 5, -0.3), (3, 4, 0.2)] {
            t.push((r, c, g));
            t.push((c, r, g));
        }
        (CscMatrix::from_triplets(6, 6, t), n_w)
    }

    #[test]
    fn iterative_and_direct_agree_on_a_small_system() {
        let (s, n_w) = small_s();
        let b = [1.0, -2.0, 0.5, 3.0, 1.0, -1.0];
        let direct = DirectSolver::new(&s, n_w).unwrap();
        let params = KrylovParams {
            rtol: 1e-13,
            ..KrylovParams::default()
        };
        let iterative = IterativeSolver::new(&s, n_w, params).unwrap();
        let (mut xd, mut xi) = (vec![0.0; 6], vec![0.0; 6]);
        direct.solve(&b, &mut xd).unwrap();
        let info = iterative.solve(&b, &mut xi).unwrap();
        assert!(info.iterations > 0 && info.residual <= 1e-13, "{info:?}");
        for (d, i) in xd.iter().zip(&xi) {
            assert!((d - i).abs() <= 1e-12, "{xd:?} {xi:?}");
        }
        // A x = b for A = J S.
        let mut ax = vec![0.0; 6];
        iterative.matrix().mul(&xd, &mut ax);
        for (ax, b) in ax.iter().zip(&b) {
            assert!((ax - b).abs() <= 1e-12);
        }
    }

    /// ILU(0) is exact where it has no fill (a tridiagonal matrix): LU z = r solves A z = r, to
    /// the single precision of the factor's entries.
    #[test]
    fn ilu0_of_a_tridiagonal_matrix_is_its_lu() {
        let n: usize = 6;
        let (mut ptr, mut col, mut val) = (vec![0], vec![], vec![]);
        for i in 0..n {
            for (j, v) in [(i.wrapping_sub(1), -1.0), (i, 4.0 + i as f64), (i + 1, -2.0)] {
                if j < n {
                    col.push(j as u32);
                    val.push(v);
                }
            }
            ptr.push(col.len());
        }
        let a = CsrMatrix::from_rows(n, ptr, col, val);
        let ilu = Ilu0::new(&a).unwrap();
        let r: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let mut z = vec![0.0; n];
        ilu.apply(&r, &mut z);
        let mut az = vec![0.0; n];
        a.mul(&z, &mut az);
        for (x, y) in az.iter().zip(&r) {
            assert!((x - y).abs() <= 1e-6 * y.abs(), "{az:?} {r:?}");
        }
    }

    /// A path graph 0 – 1 – … – 9 with rows 0..4 and 5..9 as two domains: row 4 is the
    /// separator, row 9 a last row coupled to both domains.
    fn two_domains() -> CsrMatrix {
        let n = 10;
        let mut entries = vec![Vec::new(); n];
        let mut link = |i: usize, j: usize, v: f64| {
            entries[i].push((j, v));
            entries[j].push((i, -0.5 * v));
        };
        for (i, j) in [(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 6), (6, 7), (7, 8)] {
            link(i, j, -1.0 - 0.1 * i as f64);
        }
        link(2, 9, 0.3);
        link(6, 9, -0.7);
        let (mut ptr, mut col, mut val) = (vec![0], vec![], vec![]);
        for (i, mut row) in entries.into_iter().enumerate() {
            row.push((i, 5.0 + i as f64));
            row.sort_by_key(|&(j, _)| j);
            col.extend(row.iter().map(|&(j, _)| j as u32));
            val.extend(row.iter().map(|&(_, v)| v));
            ptr.push(col.len());
        }
        CsrMatrix::from_rows(n, ptr, col, val)
    }

    /// The ILU(0) of [`two_domains`] reordered so that 0..4 and 5..9 come first, as two
    /// domains, then the separator 4 and the last row 9; its sweeps on two threads give what the
    /// sequential sweeps of the same factor give, to rounding.
    #[test]
    fn sweeps_over_two_domains_equal_the_sequential_sweeps() {
        let a = two_domains();
        let order = [0, 1, 2, 3, 5, 6, 7, 8, 4, 9];
        let mut position = [0; 10];
        order.iter().enumerate().for_each(|(new, &old)| position[old] = new);
        let (mut ptr, mut col, mut val) = (vec![0], vec![], vec![]);
        for &old in &order {
            let (cols, vals) = a.row(old);
            let mut row: Vec<(u32, f64)> = (cols.iter().zip(vals))
                .map(|(&c, &v)| (position[c as usize] as u32, v))
                .collect();
            row.sort_by_key(|&(c, _)| c);
            col.extend(row.iter().map(|&(c, _)| c));
            val.extend(row.iter().map(|&(_, v)| v));
            ptr.push(col.len());
        }
        let p = CsrMatrix::from_rows(10, ptr, col, val);
        let split = Ilu0::with_domains(&p, [4, 8]).unwrap();
        let sequential = Ilu0::new(&p).unwrap();
        assert_eq!(split.l_val, sequential.l_val);
        assert_eq!(split.u_val, sequential.u_val);
        let r: Vec<f64> = (0..10).map(|i| (i as f64 * 0.7).sin() + 1.5).collect();
        let (mut zs, mut zq) = (vec![0.0; 10], vec![0.0; 10]);
        split.apply(&r, &mut zs);
        sequential.apply(&r, &mut zq);
        for (x, y) in zs.iter().zip(&zq) {
            assert!((x - y).abs() <= 1e-14 * y.abs().max(1.0), "{zs:?} {zq:?}");
        }
        // Not in the reordered form: rows 0..4 and 4..8 of the path graph share entry (3, 4).
        assert!(matches!(
            Ilu0::with_domains(&a, [4, 8]),
            Err(Error::Factorization {
                stage: FactorStage::IncompleteLu,
                ..
            })
        ));
    }

    /// Refactoring the rows from `first` on after they change gives the factor of the changed
    /// matrix, to the bit.
    #[test]
    fn refactoring_the_last_rows_equals_a_new_factor() {
        let (s, n_w) = small_s();
        let mut a = CsrMatrix::from_symmetric_form(&s, n_w);
        let mut ilu = Ilu0::new(&a).unwrap();
        for row in 4..6 {
            for (p, v) in a.row_values_mut(row).iter_mut().enumerate() {
                *v *= 1.5 + 0.25 * p as f64;
            }
        }
        ilu.refactor_from(&a, 4).unwrap();
        let fresh = Ilu0::new(&a).unwrap();
        assert_eq!(ilu.l_val, fresh.l_val);
        assert_eq!(ilu.u_val, fresh.u_val);
        assert_eq!(ilu.inv_diag, fresh.inv_diag);
        assert!(ilu.inv_diag.iter().all(|d| d.is_finite()));
    }

    /// The ordered form is P A Pᵀ: entry (i, j) is A's entry (order[i], order[j]).
    #[test]
    fn ordered_form_permutes_rows_and_columns() {
        let (s, n_w) = small_s();
        let a = CsrMatrix::from_symmetric_form(&s, n_w);
        let order = [2, 5, 0, 4, 1, 3];
        let p = CsrMatrix::from_symmetric_form_ordered(&s, n_w, &order);
        let entry = |m: &CsrMatrix, i: usize, j: usize| {
            let (cols, vals) = m.row(i);
            cols.binary_search(&(j as u32)).map_or(0.0, |k| vals[k])
        };
        for i in 0..6 {
            for j in 0..6 {
                assert_eq!(entry(&p, i, j), entry(&a, order[i], order[j]));
            }
        }
    }

    #[test]
    fn a_capped_solve_is_a_typed_error_with_its_history() {
        let (s, n_w) = small_s();
        let params = KrylovParams {
            rtol: 1e-300,
            max_iterations: 2,
            restart: 1,
            ..KrylovParams::default()
        };
        let solver = IterativeSolver::new(&s, n_w, params).unwrap();
        let mut x = vec![0.0; 6];
        match solver.solve(&[1.0; 6], &mut x) {
            Err(Error::KrylovNotConverged {
                iterations, history, ..
            }) => {
                assert_eq!(iterations, 2);
                assert_eq!(history.len(), 3);
            }
            other => panic!("expected KrylovNotConverged, got {other:?}"),
        }
    }
}
