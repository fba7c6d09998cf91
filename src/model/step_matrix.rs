//! The linear part of one time step of Problem 14: the step matrix and its right-hand side,
//! shared by the direct path (`crate::step::StepSystem`, which factors it) and the iterative
//! path ([`super::newton_krylov`], which preconditions it).
//!
//! With x = (W_n, Θ_n) on the unknowns of E^h × V^h:
//!
//! ```text
//! (ℳ/k + 𝒦_A + k𝒦_B) W_n + G Θ_n   = ℳW_{n−1}/k − 𝒦_B U_{n−1} + F_n + Σ_i ℓ_i ξ_i·t
//! −Gᵀ W_n + (ℳ_θ/k + 𝒦_θ) Θ_n       = ℳ_θ Θ_{n−1}/k + G_n + Σ_i ℓ_i h_τ(t_n, |w_i|)
//! ```
//!
//! The matrix depends on k only, so it is assembled once per step size. It is not symmetric
//! (±G); it is stored in its sign-flipped form S = J A, J = diag(I, −I), which is symmetric
//! quasi-definite.
//!
//! Both forms are summed from the assembled full-dof matrices a column at a time, without
//! triplets. The iterative path's rows of P A Pᵀ ([`ordered_rows`]) take their pattern from the
//! node graph (a row holds the unknowns of its node's neighbours) and read G's rows in place
//! through the mirror of each node-graph entry, so that the set-up at 10⁶ unknowns writes A
//! once, on both cores, and little besides (measurements and the rejected alternatives at
//! [`ordered_rows`]).

use super::error::ModelError as Error;
use super::problem::Problem;
use crate::la::{CscMatrix, CsrMatrix};
use rayon::prelude::*;
use std::sync::Mutex;

use super::state::State;

/// The step matrix of step size k in its symmetric form S = J A, with its right-hand side.
pub struct StepMatrix {
    /// S = J A (rows of the temperature equations negated).
    pub matrix: CscMatrix,
    /// The right-hand side and the state of a solution.
    pub rhs: StepRhs,
}

/// What the right-hand side of a step and the state of a solution need besides the matrix: the
/// iterative path keeps this and lets the symmetric form go once it has its own copy of A.
pub struct StepRhs {
    /// Contributions of θ_D to the right-hand side (moved over from the matrix), from the
    /// Dirichlet nodes whose θ_D is constant in t.
    lift: Vec<f64>,
    /// (row, node, a): the entries a of the matrix columns of the Dirichlet nodes whose θ_D
    /// depends on t; their lift Σ a θ_D(x_node, t) is formed at each step (empty otherwise).
    moving_lift: Vec<(usize, usize, f64)>,
    n_w: usize,
    k: f64,
}

impl StepMatrix {
    /// Assembles the reduced step matrix S for a step size k (unknowns in their own order).
    pub fn assemble(problem: &Problem, k: f64) -> Self {
        let n = problem.velocity.n_free + problem.temperature.n_free;
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        col_ptr.push(0);
        let identity: Vec<usize> = (0..n).collect();
        let rhs = assemble_by_columns(problem, k, &identity, |column| {
            row_idx.extend(column.iter().map(|&(r, _)| crate::la::row_index(r)));
            values.extend(column.iter().map(|&(_, v)| v));
            col_ptr.push(row_idx.len());
        });
        StepMatrix {
            matrix: CscMatrix {
                n_rows: n,
                n_cols: n,
                col_ptr: col_ptr.into(),
                row_idx: row_idx.into(),
                values,
            },
            rhs,
        }
    }
}

/// The step matrix S = J A column by column, without a list of triplets: for each j, column
/// `order[j]` of S with its rows renumbered by their place in `order` (sorted, duplicates
/// summed) goes to `emit`. Memory beyond the caller's copy is O(unknowns).
///
/// With `order` a permutation P, the columns are those of P S Pᵀ; S is symmetric, so they are
/// also its rows, and row j of P A Pᵀ is column j negated where `order[j]` is a temperature
/// unknown (the iterative path builds its CSR of A so, in parallel: [`ordered_rows`]). The
/// triplet list this replaces took 24 bytes per entry of the full-dof matrices (2.3 GB at 10⁶
/// unknowns) on top of the matrix.
///
/// Returns the right-hand side's data (the θ_D lift).
pub fn assemble_by_columns(
    problem: &Problem,
    k: f64,
    order: &[usize],
    mut emit: impl FnMut(&[(usize, f64)]),
) -> StepRhs {
    let source = ColumnSource::new(problem, k, order);
    let mut scratch = ColumnScratch::new(order.len());
    let mut column = Vec::new();
    for &c in order {
        source.column(c, &mut scratch, &mut column);
        emit(&column);
    }
    source.rhs()
}

/// Rows of P A Pᵀ (row and column i are unknown `order[i]`) with the right-hand side's data:
/// the columns of [`assemble_by_columns`], row j negated where `order[j]` is a temperature
/// unknown, the same bits on any number of threads.
///
/// A's pattern comes first, from the node graph: the row of an unknown holds the unknowns of
/// its node's neighbours, so its length is a sum over the node's column of ℳ_θ
/// (`ColumnSource::column_len`), and its columns, the places of those unknowns sorted, are
/// the same for all unknowns of a node (one sort per node's velocities, copied down their
/// consecutive rows). Then blocks of 4096 (`ROWS_PER_BLOCK`) consecutive rows are summed on
/// all threads, each row's terms scattered into a dense row in the order of
/// [`assemble_by_columns`] (the same sums, term by term) and gathered along the pattern,
/// straight into A's own arrays: A's fresh pages are first written by the threads, and
/// nothing is copied.
///
/// Measured on the 3D example at 972k unknowns (one step, release, three pairs interleaved
/// with the version before on the shared 2-core machine, load 1.8–2.5; docs/performance.md,
/// "Pattern first"): the ordered A with its ILU(0) 1.9–2.9 s instead of 5.2–9.8 s, the peak
/// memory 3.02 GB instead of 3.13 GB; the ordered A itself 0.9–1.2 s, of which 0.6–0.8 s of
/// CPU: the rest is A's 0.67 GB of fresh pages. Rejected: each row summed with a list of the
/// places it touched, sorted, into blocks appended to A once a round of blocks was done (the
/// version before: a copy of every block, and A's pages all faulted by one thread; the sort
/// per row itself cost little, within the noise of the node patterns); G copied by rows for
/// the temperature terms of a velocity column (0.2 GB of fresh memory at 10⁶ unknowns, where
/// a page costs ≈ 0.85 s per GB on first touch on this machine: `ColumnSource`'s mirrors read
/// G's rows in place).
pub fn ordered_rows(problem: &Problem, k: f64, order: &[usize]) -> (CsrMatrix, StepRhs) {
    ordered_rows_in_blocks(problem, k, order, ROWS_PER_BLOCK)
}

/// [`ordered_rows`] with blocks of `rows_per_block` rows.
fn ordered_rows_in_blocks(problem: &Problem, k: f64, order: &[usize], rows_per_block: usize) -> (CsrMatrix, StepRhs) {
    let source = ColumnSource::new(problem, k, order);
    let (ptr, col, val) = rows_in_blocks(&source, order, rows_per_block);
    (CsrMatrix::from_rows(order.len(), ptr, col, val), source.rhs())
}

/// [`ordered_rows`] with only the rows `rows` (ascending) assembled, the others empty: the same
/// bits in those rows. A rank of a distributed run keeps only its own rows and the Γ_C rows
/// (`step::ranks`).
pub fn ordered_rows_at(problem: &Problem, k: f64, order: &[usize], rows: &[usize]) -> (CsrMatrix, StepRhs) {
    debug_assert!(rows.windows(2).all(|w| w[0] < w[1]) && rows.last().is_none_or(|&r| r < order.len()));
    let source = ColumnSource::new(problem, k, order);
    let unknowns: Vec<usize> = rows.iter().map(|&r| order[r]).collect();
    let (of_rows, col, val) = rows_in_blocks(&source, &unknowns, ROWS_PER_BLOCK);
    drop(unknowns);
    let mut ptr = vec![0; order.len() + 1];
    rows.iter()
        .zip(of_rows.windows(2))
        .for_each(|(&r, p)| ptr[r + 1] = p[1] - p[0]);
    (1..ptr.len()).for_each(|i| ptr[i] += ptr[i - 1]);
    (CsrMatrix::from_rows(order.len(), ptr, col, val), source.rhs())
}

/// Rows `rows` of P A Pᵀ (row and column i are unknown `order[i]`), as row pointers (from 0),
/// columns and values: [`ordered_rows`]'s rows, the same bits, for the rows a rank owns in a
/// distributed run (`crate::model::DistributedStepMatrix`).
pub fn ordered_rows_range(
    problem: &Problem,
    k: f64,
    order: &[usize],
    rows: std::ops::Range<usize>,
) -> (Vec<usize>, Vec<u32>, Vec<f64>) {
    let source = ColumnSource::new(problem, k, order);
    rows_in_blocks(&source, &order[rows], ROWS_PER_BLOCK)
}

/// The rows of P A Pᵀ of the unknowns `unknowns` (row pointers, columns, values), summed in
/// blocks of `rows_per_block` rows on all threads ([`ordered_rows`]). The row pointers come
/// first, from the node graph ([`ColumnSource::column_len`]), so each block's rows are written
/// straight into their place in A by the thread that sums them: A's fresh pages are mapped on
/// both cores, and nothing is copied.
fn rows_in_blocks(
    source: &ColumnSource,
    unknowns: &[usize],
    rows_per_block: usize,
) -> (Vec<usize>, Vec<u32>, Vec<f64>) {
    let n = source.position.len();
    let n_w = source.problem.velocity.n_free;
    let mut ptr = Vec::with_capacity(unknowns.len() + 1);
    ptr.push(0);
    for &c in unknowns {
        ptr.push(ptr[ptr.len() - 1] + source.column_len(c));
    }
    // Fresh zeros: each page is first written, by the thread that sums its rows.
    let nnz = ptr[unknowns.len()];
    let (mut col, mut val) = (vec![0u32; nnz], vec![0.0; nnz]);
    let mut blocks = Vec::with_capacity(unknowns.len().div_ceil(rows_per_block.max(1)));
    let (mut col_rest, mut val_rest) = (&mut col[..], &mut val[..]);
    for (b, rows) in unknowns.chunks(rows_per_block).enumerate() {
        let row_ptr = &ptr[b * rows_per_block..=b * rows_per_block + rows.len()];
        let len = row_ptr[rows.len()] - row_ptr[0];
        let (block_col, rest) = std::mem::take(&mut col_rest).split_at_mut(len);
        col_rest = rest;
        let (block_val, rest) = std::mem::take(&mut val_rest).split_at_mut(len);
        val_rest = rest;
        blocks.push((rows, row_ptr, block_col, block_val));
    }
    // One dense row per thread of the pool (a block's rows are summed by one thread), zero
    // between rows.
    let sums: Vec<Mutex<Vec<f64>>> = (0..rayon::current_num_threads().max(1))
        .map(|_| Mutex::new(vec![0.0; n]))
        .collect();
    blocks.into_par_iter().for_each(|(rows, row_ptr, col, val)| {
        let thread = rayon::current_thread_index().unwrap_or(0) % sums.len();
        let mut sum = sums[thread].lock().expect("a dense row per thread");
        let mut last: Option<(usize, std::ops::Range<usize>)> = None;
        for (i, &c) in rows.iter().enumerate() {
            let range = row_ptr[i] - row_ptr[0]..row_ptr[i + 1] - row_ptr[0];
            // The pattern: the node's, shared by its unknowns (its velocities are consecutive
            // rows, so most rows copy the row above).
            let node = source.node_of_unknown(c);
            match &last {
                Some((previous, above)) if *previous == node => col.copy_within(above.clone(), range.start),
                _ => source.node_pattern(node, &mut col[range.clone()]),
            }
            source.scatter(c, |p, term| sum[p] += term);
            let sign = if c < n_w { 1.0 } else { -1.0 };
            for (slot, &j) in val[range.clone()].iter_mut().zip(&col[range.clone()]) {
                *slot = sign * sum[j as usize];
                sum[j as usize] = 0.0;
            }
            last = Some((node, range));
        }
        debug_assert!(sum.iter().all(|&v| v == 0.0), "a term outside the node pattern");
    });
    (ptr, col, val)
}

/// Rows of one block in [`ordered_rows`]: ≈ 3 MB of A in 3D, small against A and large
/// against the scheduling of a block.
const ROWS_PER_BLOCK: usize = 4096;

/// What a column of the step matrix is summed from: the θ_D lift (done once), Pᵀ by unknowns,
/// G by rows and the place of each unknown in the ordering.
struct ColumnSource<'p> {
    problem: &'p Problem,
    /// 𝒦_A, 𝒦_B and G.
    stiffness: Stiffness<'p>,
    k: f64,
    lift: Vec<f64>,
    moving_lift: Vec<(usize, usize, f64)>,
    /// Pᵀ by velocity unknowns: (full dof, coefficient) of unknown r at
    /// `full_ptr[r]..full_ptr[r + 1]`, full dofs ascending. (A list per unknown took 0.3–0.5 s
    /// at 10⁶ unknowns in allocations.)
    full_ptr: Vec<usize>,
    full_entries: Vec<(usize, f64)>,
    /// The node of each temperature unknown.
    node_of: Vec<usize>,
    /// The node of each velocity unknown.
    velocity_node: Vec<usize>,
    /// The unknowns of each node (its velocities and its temperature if free).
    unknowns_at: Vec<usize>,
    /// G by rows without a copy of G: entry t of the node graph (the pattern of ℳ_θ), node q
    /// in the column of node p, has its mirror, node p in the column of q, at `mirror[t]`.
    /// G's column q holds node p's d rows at place k·d (k the place of p among q's
    /// neighbours, [`crate::la::CscMatrix::from_graph`]), so row (p, j) of G is read from the
    /// columns of p's neighbours. (G copied by rows took 16 bytes per entry, 0.2 GB of fresh
    /// memory at 10⁶ unknowns.)
    mirror: Vec<u32>,
    position: Vec<usize>,
}

/// 𝒦_A, 𝒦_B and G as a [`ColumnSource`] reads them: the problem's, or, where the problem keeps
/// none (a rank of a distributed run: [`super::ColumnShare`]), the columns its rows read,
/// assembled for the sum and dropped with it (the same bits as the whole problem's columns).
enum Stiffness<'p> {
    Problem(&'p crate::fem::assembly::Matrices),
    Assembled(Box<crate::fem::assembly::StiffnessColumns>),
}

impl Stiffness<'_> {
    fn viscosity(&self) -> &CscMatrix {
        match self {
            Stiffness::Problem(m) => &m.viscosity,
            Stiffness::Assembled(m) => &m.viscosity,
        }
    }

    fn elasticity(&self) -> &CscMatrix {
        match self {
            Stiffness::Problem(m) => &m.elasticity,
            Stiffness::Assembled(m) => &m.elasticity,
        }
    }

    fn coupling(&self) -> &CscMatrix {
        match self {
            Stiffness::Problem(m) => &m.coupling,
            Stiffness::Assembled(m) => &m.coupling,
        }
    }
}

/// The column being summed: its values by position, which positions it has (an entry that
/// sums to zero stays in the pattern), and their list.
struct ColumnScratch {
    sum: Vec<f64>,
    seen: Vec<bool>,
    touched: Vec<usize>,
}

impl ColumnScratch {
    fn new(n: usize) -> Self {
        ColumnScratch {
            sum: vec![0.0; n],
            seen: vec![false; n],
            touched: Vec::new(),
        }
    }

    #[inline]
    fn add(&mut self, p: usize, value: f64) {
        if !self.seen[p] {
            self.seen[p] = true;
            self.touched.push(p);
        }
        self.sum[p] += value;
    }
}

impl<'p> ColumnSource<'p> {
    fn new(problem: &'p Problem, k: f64, order: &[usize]) -> Self {
        let (vel, temp) = (&problem.velocity, &problem.temperature);
        let n_w = vel.n_free;
        let n = n_w + temp.n_free;
        assert_eq!(order.len(), n, "an ordering of every unknown");
        let mats = &problem.matrices;
        let stiffness = match &problem.columns {
            None => Stiffness::Problem(mats),
            Some(share) => Stiffness::Assembled(Box::new(crate::fem::assembly::assemble_stiffness_columns(
                &problem.mesh,
                &problem.materials,
                share.kept(),
            ))),
        };
        let (coupling, heat_mass) = (stiffness.coupling(), &mats.heat_mass);

        // The θ_D lift: the columns of prescribed temperatures, moved to the right-hand side
        // (kept as entries where θ_D depends on t).
        let theta_d = &problem.theta_dirichlet;
        let thermal = &problem.thermal;
        let mut lift = vec![0.0; n];
        let mut moving_lift = Vec::new();
        let mut lift_entry = |r: usize, q: usize, a: f64| {
            if thermal.is_moving(q) {
                moving_lift.push((r, q, a));
            } else {
                lift[r] += a * theta_d[q];
            }
        };
        for (row, q, g) in coupling.triplets() {
            if temp.free[q].is_none() {
                for &(r, a) in vel.row(row) {
                    lift_entry(r, q, a * g);
                }
            }
        }
        for (idx, (p, q, _)) in heat_mass.triplets().enumerate() {
            if let (Some(r), None) = (temp.free[p], temp.free[q]) {
                lift_entry(n_w + r, q, heat_mass.values[idx] / k + mats.conduction.values[idx]);
            }
        }

        let (full_ptr, full_entries) = grouped_by_row(n_w, || {
            (0..vel.n_full()).flat_map(move |f| vel.row(f).iter().map(move |&(r, a)| (r, f, a)))
        });
        let mut node_of = vec![0; temp.n_free];
        for (q, free) in temp.free.iter().enumerate() {
            if let Some(c) = free {
                node_of[*c] = q;
            }
        }
        let mut velocity_node = vec![0; n_w];
        let unknowns_at = (0..problem.mesh.n_nodes())
            .map(|p| {
                let velocities = vel.node_unknowns(p);
                velocity_node[velocities.clone()].fill(p);
                velocities.len() + usize::from(temp.free[p].is_some())
            })
            .collect();
        let mirror = mirrors(heat_mass);
        let d = vel.dim;
        // G's columns where it has them (all, or a rank's share: `ColumnShare`) are laid out
        // as ℳ_θ's, d rows per neighbour.
        let length = |m: &CscMatrix, q: usize| m.col_ptr[q + 1] - m.col_ptr[q];
        assert!(
            coupling.n_rows == d * heat_mass.n_rows
                && (0..heat_mass.n_cols).all(|q| [0, d * length(heat_mass, q)].contains(&length(coupling, q))),
            "G and ℳ_θ on the pattern of one node graph"
        );
        let mut position = vec![0; n];
        order.iter().enumerate().for_each(|(new, &old)| position[old] = new);
        ColumnSource {
            problem,
            stiffness,
            k,
            lift,
            moving_lift,
            full_ptr,
            full_entries,
            node_of,
            velocity_node,
            unknowns_at,
            mirror,
            position,
        }
    }

    /// The node of unknown c.
    fn node_of_unknown(&self, c: usize) -> usize {
        let n_w = self.problem.velocity.n_free;
        if c < n_w {
            self.velocity_node[c]
        } else {
            self.node_of[c - n_w]
        }
    }

    /// The neighbours of a node in the node graph (itself included), sorted: the pattern of
    /// ℳ_θ, whose node pairs are those of every assembled matrix.
    fn neighbours(&self, node: usize) -> &[u32] {
        let graph = &self.problem.matrices.heat_mass;
        &graph.row_idx[graph.col_ptr[node]..graph.col_ptr[node + 1]]
    }

    /// The number of entries of column c of S: the unknowns of the nodes next to c's node.
    /// Every entry of a node pair's blocks is in the pattern of the assembled matrices
    /// ([`crate::la::CscMatrix::from_graph`]), and every unknown of a node has a full dof of it
    /// in its support: the column reaches each of them, and no other unknown.
    fn column_len(&self, c: usize) -> usize {
        (self.neighbours(self.node_of_unknown(c)).iter())
            .map(|&q| self.unknowns_at[q as usize])
            .sum()
    }

    /// The pattern of the columns of a node's unknowns: the places in the ordering of the
    /// unknowns of its neighbours, sorted, into `pattern` (of [`Self::column_len`] entries).
    fn node_pattern(&self, node: usize, pattern: &mut [u32]) {
        let (vel, temp) = (&self.problem.velocity, &self.problem.temperature);
        let n_w = vel.n_free;
        let unknowns = (self.neighbours(node).iter()).flat_map(|&q| {
            let q = q as usize;
            vel.node_unknowns(q).chain(temp.free[q].map(|r| n_w + r))
        });
        let mut filled = 0;
        for (slot, r) in pattern.iter_mut().zip(unknowns) {
            *slot = index32(self.position[r]);
            filled += 1;
        }
        assert_eq!(filled, pattern.len(), "the pattern of node {node}");
        pattern.sort_unstable();
    }

    /// Column c of S, rows by their place in the ordering, sorted, into `column`.
    fn column(&self, c: usize, scratch: &mut ColumnScratch, column: &mut Vec<(usize, f64)>) {
        scratch.touched.clear();
        self.scatter(c, |p, value| scratch.add(p, value));
        let ColumnScratch { sum, seen, touched } = scratch;
        touched.sort_unstable();
        column.clear();
        for &p in touched.iter() {
            column.push((p, sum[p]));
            sum[p] = 0.0;
            seen[p] = false;
        }
    }

    /// Row f = (p, j) of G (f a full velocity dof), as (node q, G_fq) for q ascending over the
    /// neighbours of p: entry (p, j) of G's column q lies at place k·d + j of that column, k
    /// the place of p among q's neighbours, which the mirror of (q in p's column) gives.
    fn coupling_row(&self, f: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (coupling, graph) = (self.stiffness.coupling(), &self.problem.matrices.heat_mass);
        let d = self.problem.velocity.dim;
        let (p, j) = (f / d, f % d);
        (graph.col_ptr[p]..graph.col_ptr[p + 1]).map(move |t| {
            let q = graph.row_idx[t] as usize;
            let place = self.mirror[t] as usize - graph.col_ptr[q];
            (q, coupling.values[coupling.col_ptr[q] + place * d + j])
        })
    }

    /// The terms of column c of S, each as `add(row's place in the ordering, term)`: every
    /// entry's terms in the order the sum takes them (the same bits wherever they are summed).
    #[inline]
    fn scatter(&self, c: usize, mut add: impl FnMut(usize, f64)) {
        let (vel, temp) = (&self.problem.velocity, &self.problem.temperature);
        let mats = &self.problem.matrices;
        let (mass, coupling, heat_mass) = (&mats.mass, self.stiffness.coupling(), &mats.heat_mass);
        let (viscosity, elasticity) = (self.stiffness.viscosity(), self.stiffness.elasticity());
        // ℳ, 𝒦_A and 𝒦_B on 𝒦_A's (vector) pattern, ℳ's entries read through it.
        let vector = viscosity;
        let (k, n_w, position) = (self.k, vel.n_free, &self.position);
        if c < n_w {
            // Velocity column c: (ℳ/k + 𝒦_A + k𝒦_B) Pᵀ and the Gᵀ of the temperature rows.
            for &(f, b) in &self.full_entries[self.full_ptr[c]..self.full_ptr[c + 1]] {
                let (start, mass_column) = (vector.col_ptr[f], mass.column(f));
                for idx in start..vector.col_ptr[f + 1] {
                    let value = mass_column.entry(idx - start) / k + viscosity.values[idx] + k * elasticity.values[idx];
                    for &(r, a) in vel.row(vector.row_idx[idx] as usize) {
                        add(position[r], a * b * value);
                    }
                }
                for (q, g) in self.coupling_row(f) {
                    if let Some(cq) = temp.free[q] {
                        add(position[n_w + cq], b * g);
                    }
                }
            }
        } else {
            // Temperature column: G, and −(ℳ_θ/k + 𝒦_θ) in the (negated) temperature rows.
            let q = self.node_of[c - n_w];
            let range = coupling.col_ptr[q]..coupling.col_ptr[q + 1];
            for (row, g) in coupling.row_idx[range.clone()].iter().zip(&coupling.values[range]) {
                for &(r, a) in vel.row(*row as usize) {
                    add(position[r], a * g);
                }
            }
            for idx in heat_mass.col_ptr[q]..heat_mass.col_ptr[q + 1] {
                if let Some(r) = temp.free[heat_mass.row_idx[idx] as usize] {
                    let value = heat_mass.values[idx] / k + mats.conduction.values[idx];
                    add(position[n_w + r], -value);
                }
            }
        }
    }

    /// The right-hand side's data, once the columns are summed.
    fn rhs(self) -> StepRhs {
        StepRhs {
            lift: self.lift,
            moving_lift: self.moving_lift,
            n_w: self.problem.velocity.n_free,
            k: self.k,
        }
    }
}

impl StepRhs {
    /// The step size k the matrix was made for.
    pub fn time_step(&self) -> f64 {
        self.k
    }

    /// Number of unknowns.
    pub fn n_unknowns(&self) -> usize {
        self.lift.len()
    }

    /// Number of velocity unknowns (the first block of x).
    pub fn n_w(&self) -> usize {
        self.n_w
    }

    /// The right-hand side of step n without the contact terms:
    /// (ℳW_{n−1}/k − 𝒦_B U_{n−1} + F_n, ℳ_θΘ_{n−1}/k + G_n) seen by the unknowns; a nonlinear
    /// heat exchange evaluated at `exchange_at` (default Θ_{n−1}).
    pub fn rhs(
        &self,
        problem: &Problem,
        previous: &State,
        t: f64,
        exchange_at: Option<&[f64]>,
    ) -> Result<Vec<f64>, Error> {
        let mats = &problem.matrices;
        let mut mech = problem.force(t)?;
        mats.mass.mul_add(1.0 / self.k, &previous.w, &mut mech);
        match &problem.columns {
            None => mats.elasticity.mul_add(-1.0, &previous.u, &mut mech),
            // A rank's energies' pass formed 𝒦_B U_{n−1} in its rows (State::elastic_force).
            Some(_) if !previous.elastic_force.is_empty() => {
                mech.iter_mut().zip(&previous.elastic_force).for_each(|(m, f)| *m -= f);
            }
            Some(share) => share.stiffness_mul_add(
                (&problem.mesh, &problem.materials),
                |m| m.elasticity,
                -1.0,
                &previous.u,
                &mut mech,
            ),
        }
        let mut heat = problem.heat_load(t, exchange_at.unwrap_or(&previous.theta))?;
        mats.heat_mass.mul_add(1.0 / self.k, &previous.theta, &mut heat);

        let mut rhs = vec![0.0; self.n_unknowns()];
        problem.velocity.restrict_add(&mech, &mut rhs[..self.n_w]);
        for (p, free) in problem.temperature.free.iter().enumerate() {
            if let Some(r) = free {
                rhs[self.n_w + r] = heat[p];
            }
        }
        rhs.iter_mut().zip(&self.lift).for_each(|(b, l)| *b -= l);
        if !self.moving_lift.is_empty() {
            let theta_d = problem.theta_dirichlet_at(t)?;
            for &(r, q, a) in &self.moving_lift {
                rhs[r] -= a * theta_d[q];
            }
        }
        Ok(rhs)
    }

    /// The unknowns x of a state: its velocity in E^h's coordinates and its temperatures at
    /// the free nodes (the iterative path's initial guess).
    pub fn unknowns_of(&self, problem: &Problem, state: &State) -> Vec<f64> {
        let mut x = problem.velocity.restrict_values(&state.w);
        x.resize(self.n_unknowns(), 0.0);
        for (p, free) in problem.temperature.free.iter().enumerate() {
            if let Some(r) = free {
                x[self.n_w + r] = state.theta[p];
            }
        }
        x
    }

    /// The new state at time t from the solution x of the step from `previous`.
    pub fn state_from(&self, problem: &Problem, previous: &State, t: f64, x: &[f64], xi: Vec<f64>) -> State {
        let w = problem.velocity.prolong(&x[..self.n_w]);
        let u = previous.u.iter().zip(&w).map(|(u, w)| u + self.k * w).collect();
        // θ_D(t) was evaluated without error by the step's right-hand side at the same t.
        let theta_d = problem
            .theta_dirichlet_at(t)
            .expect("θ_D evaluated by the step's right-hand side");
        let theta = problem
            .temperature
            .free
            .iter()
            .zip(theta_d.iter())
            .map(|(free, &fixed)| free.map_or(fixed, |r| x[self.n_w + r]))
            .collect();
        let mut state = State {
            n: previous.n + 1,
            t,
            w,
            u,
            theta,
            xi,
            slip_distance: Vec::new(),
            slip_distance_before: Vec::new(),
            pressure: Vec::new(),
            elastic_force: Vec::new(),
        };
        state.accumulate_slip(problem, previous);
        state
    }
}

/// A = J S from the symmetric form S = J A of the step matrix (`crate::step::StepSystem`
/// stores S), J = diag(I, −I) with the first `n_w` unknowns the velocities: S's columns are
/// its rows, so A's rows are S's columns with the temperature rows negated.
pub fn rows_of_symmetric_form(s: &CscMatrix, n_w: usize) -> CsrMatrix {
    assert_eq!(s.n_rows, s.n_cols, "a square matrix");
    let mut val = s.values.clone();
    for row in n_w..s.n_cols {
        for v in &mut val[s.col_ptr[row]..s.col_ptr[row + 1]] {
            *v = -*v;
        }
    }
    CsrMatrix::from_rows(s.n_rows, s.col_ptr.to_vec(), s.row_idx.to_vec(), val)
}

/// P A Pᵀ of A = J S (as [`rows_of_symmetric_form`]) for the ordering `order`:
/// row and column i of the result are row and column `order[i]` of A.
///
/// # Panics
/// If `order` is not a permutation of S's unknowns.
pub fn rows_of_symmetric_form_ordered(s: &CscMatrix, n_w: usize, order: &[usize]) -> CsrMatrix {
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
                .map(|(&c, &v)| (position[c as usize], sign * v)),
        );
        row.sort_unstable_by_key(|&(c, _)| c);
        col.extend(row.iter().map(|&(c, _)| index32(c)));
        val.extend(row.iter().map(|&(_, v)| v));
        ptr.push(col.len());
    }
    CsrMatrix::from_rows(s.n_cols, ptr, col, val)
}

/// The (row, column, value) entries of `entries()` grouped by row: (column, value) of row r at
/// `ptr[r]..ptr[r + 1]`, in the order of the list.
fn grouped_by_row<I: Iterator<Item = (usize, usize, f64)>>(
    n_rows: usize,
    entries: impl Fn() -> I,
) -> (Vec<usize>, Vec<(usize, f64)>) {
    let mut ptr = vec![0usize; n_rows + 1];
    entries().for_each(|(r, _, _)| ptr[r + 1] += 1);
    for r in 0..n_rows {
        ptr[r + 1] += ptr[r];
    }
    let mut grouped = vec![(0usize, 0.0); ptr[n_rows]];
    let mut fill = ptr.clone();
    for (r, c, v) in entries() {
        grouped[fill[r]] = (c, v);
        fill[r] += 1;
    }
    (ptr, grouped)
}

/// The mirror of each entry of a matrix with a symmetric pattern, sorted rows in each column:
/// entry t, row q in column p, has its mirror (row p in column q) at `mirror[t]`. The columns
/// are swept in order, so each column's mirrors are met in the order of its rows: no search.
fn mirrors(matrix: &CscMatrix) -> Vec<u32> {
    let mut mirror = vec![0u32; matrix.row_idx.len()];
    let mut next: Vec<usize> = matrix.col_ptr[..matrix.n_cols].to_vec();
    for q in 0..matrix.n_cols {
        for t in matrix.col_ptr[q]..matrix.col_ptr[q + 1] {
            let p = matrix.row_idx[t] as usize;
            mirror[next[p]] = index32(t);
            next[p] += 1;
        }
    }
    mirror
}

/// A matrix index as the 32-bit index of the CSR layout.
///
/// # Panics
/// Past 2³² unknowns, which the memory estimate refuses long before (`crate::resources`).
fn index32(i: usize) -> u32 {
    u32::try_from(i).expect("fewer than 2^32 unknowns")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::la::{gmres, GmresParams, Ilu0, QuasiDefiniteLdlt};

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
    fn ldlt_of_the_symmetric_form_and_gmres_on_its_rows_agree() {
        let (s, n_w) = small_s();
        let b = [1.0, -2.0, 0.5, 3.0, 1.0, -1.0];
        // The direct solve: S x = J b.
        let mut xd = b.to_vec();
        xd[n_w..].iter_mut().for_each(|v| *v = -*v);
        QuasiDefiniteLdlt::new(&s).unwrap().solve_in_place(&mut xd, 1);
        // The iterative one: GMRES + ILU(0) on A.
        let a = rows_of_symmetric_form(&s, n_w);
        let params = GmresParams {
            rtol: 1e-13,
            ..GmresParams::default()
        };
        let mut xi = vec![0.0; 6];
        let info = gmres(&a, &Ilu0::new(&a).unwrap(), &b, &mut xi, &params).unwrap();
        assert!(info.iterations > 0 && info.residual <= 1e-13, "{info:?}");
        for (d, i) in xd.iter().zip(&xi) {
            assert!((d - i).abs() <= 1e-12, "{xd:?} {xi:?}");
        }
        // A x = b for A = J S.
        let mut ax = vec![0.0; 6];
        a.mul(&xd, &mut ax);
        for (ax, b) in ax.iter().zip(&b) {
            assert!((ax - b).abs() <= 1e-12);
        }
    }

    /// The rows of [`ordered_rows`] are the columns of [`assemble_by_columns`] (sign-flipped in
    /// the temperature rows), to the bit, on 1, 2 and 3 threads, in a scattered order (each row
    /// its own node's pattern) and in the unknowns' own order (a node's velocities consecutive
    /// rows that share one pattern): the blocks, the node patterns and the dense rows change
    /// nothing.
    #[test]
    fn ordered_rows_are_the_columns_on_any_number_of_threads() {
        let problem = crate::model::samples::paper_3d([4, 2, 2], 64).unwrap();
        let (k, n_w) = (problem.time_step(), problem.velocity.n_free);
        let n = n_w + problem.temperature.n_free;
        assert!(!n.is_multiple_of(7919), "a permutation");
        for order in [(0..n).map(|i| (i * 7919) % n).collect::<Vec<usize>>(), (0..n).collect()] {
            let mut columns = Vec::new();
            assemble_by_columns(&problem, k, &order, |column| columns.push(column.to_vec()));
            assert_eq!(columns.len(), n);
            for threads in [1, 2, 3] {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                // Blocks of 7 rows: many blocks, a node's rows across two, a last one cut short.
                let (a, _) = pool.install(|| ordered_rows_in_blocks(&problem, k, &order, 7));
                for (j, column) in columns.iter().enumerate() {
                    let sign = if order[j] < n_w { 1.0 } else { -1.0 };
                    let (cols, vals) = a.row(j);
                    assert!(cols.iter().map(|&c| c as usize).eq(column.iter().map(|&(r, _)| r)));
                    let bits = |v: f64| v.to_bits();
                    assert!(vals
                        .iter()
                        .map(|&v| bits(v))
                        .eq(column.iter().map(|&(_, v)| bits(sign * v))));
                }
            }
        }
    }

    /// The rows assembled alone are [`ordered_rows`]'s, bit for bit; the others are empty.
    #[test]
    fn rows_assembled_alone_are_the_rows_of_the_whole() {
        let problem = crate::model::samples::paper_3d([4, 2, 2], 64).unwrap();
        let k = problem.time_step();
        let n = problem.velocity.n_free + problem.temperature.n_free;
        let order: Vec<usize> = (0..n).map(|i| (i * 7919) % n).collect();
        let (whole, _) = ordered_rows(&problem, k, &order);
        let rows: Vec<usize> = (0..n).filter(|r| r % 3 != 1).collect();
        let (some, _) = ordered_rows_at(&problem, k, &order, &rows);
        for i in 0..n {
            let bits = |(c, v): (&[u32], &[f64])| (c.to_vec(), v.iter().map(|v| v.to_bits()).collect::<Vec<_>>());
            if i % 3 == 1 {
                assert!(some.row(i).0.is_empty(), "row {i}");
            } else {
                assert_eq!(bits(some.row(i)), bits(whole.row(i)), "row {i}");
            }
        }
    }

    /// G's rows read in place through the node graph's mirrors are G's rows: every entry of
    /// its pattern, in the order of its columns.
    #[test]
    fn coupling_rows_read_through_the_mirrors_are_the_rows_of_g() {
        let problem = crate::model::samples::paper_3d([4, 2, 2], 64).unwrap();
        let order: Vec<usize> = (0..problem.velocity.n_free + problem.temperature.n_free).collect();
        let source = ColumnSource::new(&problem, problem.time_step(), &order);
        let coupling = &problem.matrices.coupling;
        let mut by_rows = vec![Vec::new(); coupling.n_rows];
        for (f, q, g) in coupling.triplets() {
            by_rows[f].push((q, g.to_bits()));
        }
        for (f, row) in by_rows.iter().enumerate() {
            let read: Vec<(usize, u64)> = source.coupling_row(f).map(|(q, g)| (q, g.to_bits())).collect();
            assert_eq!(&read, row, "row {f}");
        }
        assert!(by_rows.iter().flatten().any(|&(_, g)| f64::from_bits(g) != 0.0));
    }

    /// The ordered form is P A Pᵀ: entry (i, j) is A's entry (order[i], order[j]).
    #[test]
    fn ordered_form_permutes_rows_and_columns() {
        let (s, n_w) = small_s();
        let a = rows_of_symmetric_form(&s, n_w);
        let order = [2, 5, 0, 4, 1, 3];
        let p = rows_of_symmetric_form_ordered(&s, n_w, &order);
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
}
