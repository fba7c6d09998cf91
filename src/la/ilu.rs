//! ILU(0): the incomplete LU factor on A's own pattern that preconditions GMRES, with rows
//! refactored in place from some row on (the rows a Newton linearization changes) and sweeps
//! over two independent domains on two threads ([`super::graph::level_bisection`]).

use super::error::{FactorStage, LaError as Error};
use super::gmres::Preconditioner;
use super::sparse::{sparse_dot32, CsrMatrix};

impl Preconditioner for Ilu0 {
    fn apply(&self, r: &[f64], z: &mut [f64]) -> Result<(), Error> {
        Ilu0::apply(self, r, z);
        Ok(())
    }

    fn method(&self) -> &'static str {
        "GMRES + ILU(0)"
    }
}

/// ILU(0) of a [`CsrMatrix`]: L (unit diagonal) and U on A's own pattern.
///
/// Stored for its sweeps: L and U in separate arrays, so that each sweep streams only its own
/// half, with 32-bit column indices and U's inverted diagonal. Measured at 98k unknowns: one
/// solve 5 ms, against 26 ms with L and U left interleaved in A's rows (docs/krylov-study.md, §5).
/// Only the columns read from A's rows (the values apart, as here) still cost 1.5× in the sweeps
/// (26 M entries: 41–49 ms against 24–31 ms, 2026-11-27), so the factor keeps its own columns,
/// half of its bytes (docs/distributed.md).
///
/// The off-diagonal values are kept in single precision (the sweeps sum in double). A sweep reads
/// each entry once and does two flops with it, so it runs at the memory's speed, and at 3·10⁵
/// unknowns one sweep on one core already streams ≈ 20 GB/s, near what both cores get: a
/// second core would add little, a smaller entry (8 bytes with its index instead of 12) takes a
/// third off. The preconditioner only has to be *a* fixed approximation of Ã⁻¹: rounding its
/// entries to 6·10⁻⁸ is far inside what ILU(0) already drops, and GMRES still works to the true
/// residual of Ã in double precision.
///
/// On the machine of 2026-11-28 (AMD EPYC, x86-64-v3 build) a sweep is bound by its
/// instructions, not by memory: two sweeps of 27 M entries at once take 13 ms each, as one
/// alone (≈ 1.4 cycles an entry). Fewer bytes then cost more than they save: columns stored as
/// runs of consecutive columns (4.8 bytes an entry instead of 8) made a sweep 1.6× slower and
/// a step at 972k unknowns 3.0–3.1 → 3.8–3.9 s (docs/performance.md, "One Krylov iteration at
/// 10⁶ unknowns").
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
        Self::from_row_parts(n, parts, |i| {
            let (cols, vals) = a.row(i);
            [(cols, vals), (&[], &[])]
        })
    }

    /// The factor of the n × n matrix whose row i is `row(i)`, given in two parts (columns
    /// ascending within each, every column of the first below every column of the second): a
    /// row kept in two arrays, such as a rank's rows in PETSc's diagonal and off-diagonal parts
    /// with the latter's columns numbered after the former's, is factored where it lies, without
    /// a copy of the matrix. `parts`: the two domains of [`Ilu0::with_domains`], not checked here.
    pub fn from_row_parts<'a>(
        n: usize,
        parts: [usize; 2],
        row: impl Fn(usize) -> RowParts<'a> + Sync,
    ) -> Result<Self, Error> {
        if u32::try_from(n).is_err() {
            return Err(Error::Factorization {
                stage: FactorStage::IncompleteLu,
                detail: format!("{n} unknowns exceed 32-bit indices"),
            });
        }
        let (mut n_lower, mut n_upper) = (0, 0);
        for i in 0..n {
            let [(c0, _), (c1, _)] = row(i);
            let below = c0.partition_point(|&c| (c as usize) < i) + c1.partition_point(|&c| (c as usize) < i);
            let has_diagonal = c0.binary_search(&(i as u32)).is_ok() || c1.binary_search(&(i as u32)).is_ok();
            if !has_diagonal {
                return Err(Error::Factorization {
                    stage: FactorStage::IncompleteLu,
                    detail: format!("row {i} has no diagonal entry"),
                });
            }
            n_lower += below;
            n_upper += c0.len() + c1.len() - below - 1;
        }
        let mut f = Ilu0 {
            l_ptr: Vec::with_capacity(n + 1),
            l_col: Vec::with_capacity(n_lower),
            l_val: vec![0.0f32; n_lower],
            u_ptr: Vec::with_capacity(n + 1),
            u_col: Vec::with_capacity(n_upper),
            u_val: vec![0.0f32; n_upper],
            inv_diag: vec![0.0; n],
            parts,
            scratch: RowScratch::new(n),
        };
        f.l_ptr.push(0);
        f.u_ptr.push(0);
        for i in 0..n {
            let i32 = i as u32;
            for (cols, _) in row(i) {
                f.l_col.extend(cols.iter().filter(|&&c| c < i32));
                f.u_col.extend(cols.iter().filter(|&&c| c > i32));
            }
            f.l_ptr.push(f.l_col.len());
            f.u_ptr.push(f.u_col.len());
        }
        f.refactor_parts_from(0, row)?;
        Ok(f)
    }

    /// Factors rows `first..n` of A again after their values changed, rows before `first`
    /// unchanged: the rows of an ILU(0) depend only on the rows above them, so a matrix whose
    /// changing rows are ordered last is refactored in time proportional to those rows (the
    /// contact rows of a Newton matrix, the iterative path of `crate::step`). From row 0, the two domains
    /// of [`Ilu0::with_domains`] are factored on two threads.
    pub fn refactor_from(&mut self, a: &CsrMatrix, first: usize) -> Result<(), Error> {
        self.refactor_rows_from(first, |i| a.row(i))
    }

    /// [`Ilu0::refactor_from`] with the rows of A from `first` on given by `row(i)` (column
    /// indices sorted, A's pattern): a caller that changes a few last rows keeps only those.
    pub fn refactor_rows_from<'a>(
        &mut self,
        first: usize,
        row: impl Fn(usize) -> (&'a [u32], &'a [f64]) + Sync,
    ) -> Result<(), Error> {
        self.refactor_parts_from(first, |i| {
            let (cols, vals) = row(i);
            [(cols, vals), (&[], &[])]
        })
    }

    /// [`Ilu0::refactor_rows_from`] with each row in two parts, as [`Ilu0::from_row_parts`].
    pub fn refactor_parts_from<'a>(
        &mut self,
        first: usize,
        row: impl Fn(usize) -> RowParts<'a> + Sync,
    ) -> Result<(), Error> {
        let n = self.inv_diag.len();
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
                || pattern.factor_rows(&row, 0..first_end, 0, (l1, u1, d1), &mut RowScratch::new(n)),
                || {
                    pattern.factor_rows(
                        &row,
                        first_end..second_end,
                        first_end,
                        (l2, u2, d2),
                        &mut RowScratch::new(n),
                    )
                },
            );
            r1.and(r2)?;
            sequential_from = second_end;
        }
        pattern.factor_rows(&row, sequential_from..n, 0, (l_val, u_val, inv_diag), scratch)
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

/// A row of a matrix in two parts ([`Ilu0::from_row_parts`]): columns and values of each, the
/// second part's columns after the first's (either may be empty).
pub type RowParts<'a> = [(&'a [u32], &'a [f64]); 2];

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
    fn factor_rows<'a>(
        &self,
        row: &impl Fn(usize) -> RowParts<'a>,
        rows: std::ops::Range<usize>,
        base: usize,
        (l_val, u_val, inv_diag): RowValues,
        scratch: &mut RowScratch,
    ) -> Result<(), Error> {
        let (l0, u0) = (self.l_ptr[base], self.u_ptr[base]);
        let RowScratch { dense, in_row } = scratch;
        for i in rows {
            let parts = row(i);
            for (cols, vals) in parts {
                for (&c, &v) in cols.iter().zip(vals) {
                    dense[c as usize] = v;
                    in_row[c as usize] = true;
                }
            }
            let lower = parts.iter().flat_map(|(cols, _)| cols.iter());
            for k in lower.map(|&k| k as usize).take_while(|&k| k < i) {
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
                for &c in parts.iter().flat_map(|(cols, _)| cols.iter()) {
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
            for &c in parts.iter().flat_map(|(cols, _)| cols.iter()) {
                dense[c as usize] = 0.0;
                in_row[c as usize] = false;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

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
    pub(crate) fn two_domains() -> CsrMatrix {
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

    /// Each row given in two parts (split at a column per row, as a rank's rows in PETSc's two
    /// parts) gives the factor of the whole rows, to the bit, and so does refactoring from a
    /// row on in parts.
    #[test]
    fn rows_in_two_parts_give_the_factor_of_the_whole_rows() {
        let mut a = two_domains();
        let split_at = |i: usize| 3 + i % 5;
        let parts = |a: &CsrMatrix| {
            let a = a.clone();
            move |i: usize| {
                let (cols, vals) = a.row(i);
                let s = cols.partition_point(|&c| (c as usize) < split_at(i));
                [
                    (cols[..s].to_vec(), vals[..s].to_vec()),
                    (cols[s..].to_vec(), vals[s..].to_vec()),
                ]
            }
        };
        let rows: Vec<_> = (0..10).map(parts(&a)).collect();
        fn of(rows: &[[(Vec<u32>, Vec<f64>); 2]], i: usize) -> RowParts<'_> {
            let [(c0, v0), (c1, v1)] = &rows[i];
            [(c0.as_slice(), v0.as_slice()), (c1.as_slice(), v1.as_slice())]
        }
        let mut in_parts = Ilu0::from_row_parts(10, [0, 0], |i| of(&rows, i)).unwrap();
        let whole = Ilu0::new(&a).unwrap();
        assert_eq!(in_parts.l_val, whole.l_val);
        assert_eq!(in_parts.u_val, whole.u_val);
        assert_eq!(in_parts.inv_diag, whole.inv_diag);
        for row in 6..10 {
            a.row_values_mut(row).iter_mut().for_each(|v| *v *= 1.25);
        }
        let rows: Vec<_> = (0..10).map(parts(&a)).collect();
        in_parts.refactor_parts_from(6, |i| of(&rows, i)).unwrap();
        let fresh = Ilu0::new(&a).unwrap();
        assert_eq!(in_parts.l_val, fresh.l_val);
        assert_eq!(in_parts.u_val, fresh.u_val);
        assert_eq!(in_parts.inv_diag, fresh.inv_diag);
        assert_ne!(fresh.inv_diag, whole.inv_diag);
    }

    /// Refactoring the rows from `first` on after they change gives the factor of the changed
    /// matrix, to the bit.
    #[test]
    fn refactoring_the_last_rows_equals_a_new_factor() {
        let mut a = two_domains();
        let mut ilu = Ilu0::new(&a).unwrap();
        for row in 7..10 {
            for (p, v) in a.row_values_mut(row).iter_mut().enumerate() {
                *v *= 1.5 + 0.25 * p as f64;
            }
        }
        ilu.refactor_from(&a, 7).unwrap();
        let fresh = Ilu0::new(&a).unwrap();
        assert_eq!(ilu.l_val, fresh.l_val);
        assert_eq!(ilu.u_val, fresh.u_val);
        assert_eq!(ilu.inv_diag, fresh.inv_diag);
        assert!(ilu.inv_diag.iter().all(|d| d.is_finite()));
    }
}
