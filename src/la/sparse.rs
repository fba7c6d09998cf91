//! Sparse storage for assembled finite-element matrices.
//!
//! The mesh is fixed, so every matrix pattern is derived once from the node graph (which nodes
//! share a cell); assembly then only adds values at known positions (found by binary search in
//! a sorted column). A matrix over nodal blocks of `rows_per_node × cols_per_node` dofs has,
//! in column `q·c + j`, the rows `p·r + i` for every neighbour p of q and i < r.

use std::sync::Arc;

use super::graph::NodeGraph;

use rayon::prelude::*;

use faer::sparse::{SparseColMat, SymbolicSparseColMat};

/// A compressed-sparse-column matrix with a pattern fixed at creation.
///
/// The pattern is shared: a clone has values of its own and the same pattern (the problem's
/// mass, viscous, elastic and energy matrices are clones of one template, so they hold one
/// pattern, not four: 0.8 GB less at 10⁶ unknowns in 3D).
#[derive(Debug, Clone)]
pub struct CscMatrix {
    pub n_rows: usize,
    pub n_cols: usize,
    pub col_ptr: Arc<[usize]>,
    /// 32-bit row indices: 4 bytes per entry less than `usize` (0.25 GB at 972k unknowns in 3D;
    /// a matrix with 2³² rows would not fit in memory here anyway, see [`row_index`]).
    pub row_idx: Arc<[u32]>,
    pub values: Vec<f64>,
}

/// Row r as a stored index: rows must fit in 32 bits (2³² rows of a P1 matrix in 3D would take
/// over 10¹² bytes of values).
#[inline]
pub fn row_index(r: usize) -> u32 {
    u32::try_from(r).expect("a matrix with fewer than 2³² rows")
}

impl CscMatrix {
    /// Zero matrix over nodal blocks (`rows_per_node`, `cols_per_node`) with the pattern of
    /// `graph`: row p·r + i of column q·c + j (r, c the rows and columns per node) is the
    /// column's entry k·r + i, k the place of p among q's sorted neighbours, so that an assembly
    /// finds a node pair's entries in every such matrix with one search, and a node's columns
    /// one after the other ([`ColumnsMut::columns`]).
    pub fn from_graph(graph: &NodeGraph, rows_per_node: usize, cols_per_node: usize) -> Self {
        Self::from_graph_columns(graph, rows_per_node, cols_per_node, None)
    }

    /// [`CscMatrix::from_graph`] with only the columns of the nodes `kept` marks (all where
    /// `None`): the others empty, the kept ones laid out as in the whole pattern. A rank of a
    /// distributed run keeps the columns its rows read (`crate::model::ColumnShare`).
    pub fn from_graph_columns(
        graph: &NodeGraph,
        rows_per_node: usize,
        cols_per_node: usize,
        kept: Option<&[bool]>,
    ) -> Self {
        let n = graph.n_nodes();
        debug_assert!(kept.is_none_or(|kept| kept.len() == n));
        let column_nodes = |q: usize| match kept {
            Some(kept) if !kept[q] => &[][..],
            _ => graph.neighbours(q),
        };
        let mut col_ptr = Vec::with_capacity(n * cols_per_node + 1);
        col_ptr.push(0);
        for q in 0..n {
            for _ in 0..cols_per_node {
                col_ptr.push(col_ptr[col_ptr.len() - 1] + column_nodes(q).len() * rows_per_node);
            }
        }
        let nnz = col_ptr[col_ptr.len() - 1];
        // The row indices are written once, into the shared slice itself: collected from an
        // iterator of known length, not from a `Vec` (which an `Arc<[_]>` copies: 0.27 GB
        // more written at 10⁶ unknowns with `usize` indices).
        let (mut q, mut j, mut k, mut i) = (0, 0, 0, 0);
        let row_idx: Arc<[u32]> = (0..nnz)
            .map(|_| {
                while k == column_nodes(q).len() {
                    k = 0;
                    j += 1;
                    if j == cols_per_node {
                        (j, q) = (0, q + 1);
                    }
                }
                let row = column_nodes(q)[k] * rows_per_node + i;
                i += 1;
                if i == rows_per_node {
                    (i, k) = (0, k + 1);
                }
                row_index(row)
            })
            .collect();
        CscMatrix {
            n_rows: n * rows_per_node,
            n_cols: n * cols_per_node,
            col_ptr: col_ptr.into(),
            row_idx,
            values: vec![0.0; nnz],
        }
    }

    /// A zero matrix with this one's (shared) pattern.
    pub fn zeros_like(&self) -> Self {
        CscMatrix {
            n_rows: self.n_rows,
            n_cols: self.n_cols,
            col_ptr: Arc::clone(&self.col_ptr),
            row_idx: Arc::clone(&self.row_idx),
            values: vec![0.0; self.values.len()],
        }
    }

    /// Builds a matrix from (row, col, value) triplets, summing duplicates.
    pub fn from_triplets(n_rows: usize, n_cols: usize, mut triplets: Vec<(usize, usize, f64)>) -> Self {
        triplets.sort_unstable_by_key(|&(r, c, _)| (c, r));
        let mut col_ptr = vec![0usize; n_cols + 1];
        let mut row_idx = Vec::with_capacity(triplets.len());
        let mut values: Vec<f64> = Vec::with_capacity(triplets.len());
        let mut last = None;
        for (r, c, v) in triplets {
            debug_assert!(r < n_rows && c < n_cols);
            if last == Some((r, c)) {
                *values.last_mut().expect("a previous entry exists") += v;
            } else {
                row_idx.push(row_index(r));
                values.push(v);
                col_ptr[c + 1] += 1;
                last = Some((r, c));
            }
        }
        for c in 0..n_cols {
            col_ptr[c + 1] += col_ptr[c];
        }
        CscMatrix {
            n_rows,
            n_cols,
            col_ptr: col_ptr.into(),
            row_idx: row_idx.into(),
            values,
        }
    }

    /// An n_rows × n_cols matrix with no stored entry.
    pub fn empty(n_rows: usize, n_cols: usize) -> Self {
        CscMatrix {
            n_rows,
            n_cols,
            col_ptr: vec![0; n_cols + 1].into(),
            row_idx: Vec::new().into(),
            values: Vec::new(),
        }
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Position of entry (row, col) in `values`, if it is in the pattern.
    pub fn position(&self, row: usize, col: usize) -> Option<usize> {
        let (start, end) = (self.col_ptr[col], self.col_ptr[col + 1]);
        let row = u32::try_from(row).ok()?;
        self.row_idx[start..end].binary_search(&row).ok().map(|k| start + k)
    }

    /// Adds `value` at (row, col); the entry must be in the pattern.
    #[inline]
    pub fn add(&mut self, row: usize, col: usize, value: f64) {
        let k = self.position(row, col).expect("entry outside the assembled pattern");
        self.values[k] += value;
    }

    /// Splits the matrix into consecutive ranges of whole columns, the columns of nodes
    /// `node_bounds[b] .. node_bounds[b + 1]` (`cols_per_node` columns per node), each writable
    /// on its own thread.
    pub fn split_columns_mut(&mut self, node_bounds: &[usize], cols_per_node: usize) -> Vec<ColumnsMut<'_>> {
        let mut rest: &mut [f64] = &mut self.values;
        let mut taken = self.col_ptr[node_bounds[0] * cols_per_node];
        rest = &mut rest[taken..];
        node_bounds
            .windows(2)
            .map(|bounds| {
                let end = self.col_ptr[bounds[1] * cols_per_node];
                let (values, tail) = std::mem::take(&mut rest).split_at_mut(end - taken);
                rest = tail;
                let offset = taken;
                taken = end;
                ColumnsMut {
                    col_ptr: &self.col_ptr,
                    values,
                    offset,
                }
            })
            .collect()
    }

    /// Entry (row, col), zero outside the pattern.
    pub fn get(&self, row: usize, col: usize) -> f64 {
        self.position(row, col).map_or(0.0, |k| self.values[k])
    }

    /// y += alpha · A x.
    pub fn mul_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n_cols);
        debug_assert_eq!(y.len(), self.n_rows);
        for (c, &xc) in x.iter().enumerate() {
            if xc == 0.0 {
                continue;
            }
            let ax = alpha * xc;
            for k in self.col_ptr[c]..self.col_ptr[c + 1] {
                y[self.row_idx[k] as usize] += self.values[k] * ax;
            }
        }
    }

    /// y += alpha · Aᵀ x.
    pub fn mul_transpose_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n_rows);
        debug_assert_eq!(y.len(), self.n_cols);
        for (c, yc) in y.iter_mut().enumerate() {
            let mut sum = 0.0;
            for k in self.col_ptr[c]..self.col_ptr[c + 1] {
                sum += self.values[k] * x[self.row_idx[k] as usize];
            }
            *yc += alpha * sum;
        }
    }

    /// A x as a new vector.
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n_rows];
        self.mul_add(1.0, x, &mut y);
        y
    }

    /// Quadratic form xᵀ A x (A square).
    pub fn quadratic_form(&self, x: &[f64]) -> f64 {
        self.mul(x).iter().zip(x).map(|(a, b)| a * b).sum()
    }

    /// Triplets of the stored entries.
    pub fn triplets(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        (0..self.n_cols).flat_map(move |c| {
            (self.col_ptr[c]..self.col_ptr[c + 1]).map(move |k| (self.row_idx[k] as usize, c, self.values[k]))
        })
    }

    /// Converts to a faer matrix (for factorization).
    pub fn to_faer(&self) -> SparseColMat<usize, f64> {
        // The pattern is sorted and duplicate-free by construction, so the unchecked path is safe
        // to describe; we still go through the checked constructor to validate it in debug runs.
        let symbolic = SymbolicSparseColMat::new_checked(
            self.n_rows,
            self.n_cols,
            self.col_ptr.to_vec(),
            None,
            self.row_idx.iter().map(|&r| r as usize).collect(),
        );
        SparseColMat::new(symbolic, self.values.clone())
    }
}

/// A range of whole columns of a [`CscMatrix`] ([`CscMatrix::split_columns_mut`]).
#[derive(Debug)]
pub struct ColumnsMut<'a> {
    col_ptr: &'a [usize],
    values: &'a mut [f64],
    /// Position in the matrix's `values` of `values[0]`.
    offset: usize,
}

impl ColumnsMut<'_> {
    /// The stored entries of columns `cols` (in the range), one column after the other.
    pub fn columns(&mut self, cols: std::ops::Range<usize>) -> &mut [f64] {
        let (start, end) = (self.col_ptr[cols.start], self.col_ptr[cols.end]);
        &mut self.values[start - self.offset..end - self.offset]
    }
}

/// A square sparse matrix stored by rows, column indices sorted within each row.
#[derive(Debug, Clone)]
pub struct CsrMatrix {
    pub(super) n: usize,
    pub(super) ptr: Vec<usize>,
    /// Column indices, 32-bit: a quarter less data per product than 64-bit ones
    /// (docs/krylov-study.md, §5).
    pub(super) col: Vec<u32>,
    pub(super) val: Vec<f64>,
}

impl CsrMatrix {
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

    /// The row pointers, column indices and values, for a caller that keeps them in another
    /// form (PETSc's arrays: `crate::la::mpi::DistributedMatrix::from_split`).
    pub fn into_parts(self) -> (Vec<usize>, Vec<u32>, Vec<f64>) {
        (self.ptr, self.col, self.val)
    }

    /// The same matrix with the rows before `first` emptied but those in `also`: rows
    /// `first..n` and `also` kept as they are, with their columns (a rank of a distributed run
    /// keeps only the rows each linearization changes or whose residual it recomputes once
    /// PETSc and its block have the others: `step::ranks`).
    pub fn keep_rows(self, first: usize, also: &[usize]) -> Self {
        let mut kept = vec![false; first];
        also.iter()
            .filter(|&&row| row < first)
            .for_each(|&row| kept[row] = true);
        let tail = self.nnz() - self.ptr[first];
        let (mut col, mut val) = (Vec::with_capacity(tail), Vec::with_capacity(tail));
        let mut ptr = Vec::with_capacity(self.n + 1);
        ptr.push(0);
        for row in 0..self.n {
            if row >= first || kept[row] {
                let range = self.ptr[row]..self.ptr[row + 1];
                col.extend_from_slice(&self.col[range.clone()]);
                val.extend_from_slice(&self.val[range]);
            }
            ptr.push(col.len());
        }
        CsrMatrix {
            n: self.n,
            ptr,
            col,
            val,
        }
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
pub(crate) fn index32(i: usize) -> u32 {
    u32::try_from(i).expect("fewer than 2^32 unknowns")
}

/// Σ v·x[c − offset] over 32-bit column indices (x holds the unknowns from `offset` on) with
/// four partial sums: a single sequential sum makes each row a long chain of dependent additions
/// (docs/krylov-study.md, §5).
#[inline]
pub(crate) fn sparse_dot32<V: Copy + Into<f64>>(cols: &[u32], vals: &[V], x: &[f64], offset: usize) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows kept from `first` on and those named are the rows they were, their values where
    /// [`CsrMatrix::values_from`] finds them; the other rows are empty.
    #[test]
    fn kept_rows_are_the_rows_and_the_others_are_empty() {
        let a = CsrMatrix::from_rows(
            4,
            vec![0, 2, 3, 5, 6],
            vec![0, 2, 1, 0, 2, 3],
            vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
        );
        let kept = a.clone().keep_rows(2, &[1]);
        assert_eq!(kept.row(0), (&[][..], &[][..]));
        for i in 1..4 {
            assert_eq!(kept.row(i), a.row(i));
        }
        for i in 2..4 {
            assert_eq!(kept.offset_from(2, i), a.offset_from(2, i));
        }
        assert_eq!(kept.values_from(2), a.values_from(2));
        assert_eq!(kept.nnz(), 4);
    }

    #[test]
    fn triplets_sum_duplicates_and_multiply() {
        let a = CscMatrix::from_triplets(2, 3, vec![(0, 0, 1.0), (1, 2, 2.0), (0, 0, 3.0), (1, 0, -1.0)]);
        assert_eq!(a.nnz(), 3);
        assert_eq!(a.get(0, 0), 4.0);
        assert_eq!(a.mul(&[1.0, 5.0, 2.0]), vec![4.0, 3.0]);
        let mut y = vec![0.0; 3];
        a.mul_transpose_add(1.0, &[1.0, 1.0], &mut y);
        assert_eq!(y, vec![3.0, 0.0, 2.0]);
    }

    #[test]
    fn graph_pattern_has_blocks() {
        let graph = NodeGraph::new(4, &[0, 1, 2, 1, 3, 2], 3);
        assert_eq!(graph.neighbours(0), &[0, 1, 2]);
        assert_eq!(graph.neighbours(1), &[0, 1, 2, 3]);
        let m = CscMatrix::from_graph(&graph, 2, 1);
        assert_eq!(m.n_rows, 8);
        assert_eq!(m.n_cols, 4);
        assert!(m.position(7, 1).is_some() && m.position(7, 0).is_none());
    }
}
