//! The sparse factorization of the step matrix, and triangular sweeps over it that may stop at,
//! or start from, the contact unknowns.
//!
//! The step matrix A = [K_w, G; −Gᵀ, K_θ] is not symmetric, but J A with J = diag(I, −I) is:
//!
//! ```text
//! S = J A = [ K_w   G   ]      K_w = ℳ/k + 𝒦_A + k𝒦_B  (SPD on E^h)
//!           [ Gᵀ   −K_θ ]      K_θ = ℳ_θ/k + 𝒦_θ       (SPD on V^h)
//! ```
//!
//! S is symmetric *quasi-definite*, so it has an LDLᵀ factorization for every symmetric
//! ordering, without pivoting (Vanderbei, SIAM J. Optim. 5 (1995)). We factor S once with faer's
//! supernodal LDLᵀ and solve A x = b as S x = J b. Against a general sparse LU of A (the
//! alternative we measured) the factor is symmetric — half the storage — and AMD on the
//! symmetric pattern fills less than COLAMD on the unsymmetric one, so every solve, the cost
//! that dominates a run, reads far fewer bytes.
//!
//! **Trailing unknowns.** The unknowns that the contact terms touch (the tangential velocities
//! and the temperatures of the Γ_C nodes, m of them) are ordered last, the others by AMD on the
//! graph without them. With P S Pᵀ = L D Lᵀ split after the first n − m positions,
//!
//! ```text
//! L = [ L₁₁   0  ]      (P S⁻¹ Pᵀ)₂₂ = (L₂₂ D₂ L₂₂ᵀ)⁻¹,
//!     [ L₂₁  L₂₂ ]
//! ```
//!
//! because L is lower triangular. A solve is three passes, y = L⁻¹ P b, z = D⁻¹ y, x = L⁻ᵀ z
//! (then Pᵀ x), and two of them shrink to the trailing block:
//!
//! * when b is supported on the trailing unknowns, so is y: the forward sweep reads L₂₂ only;
//! * x on the trailing unknowns is L₂₂⁻ᵀ z₂: that backward sweep reads L₂₂ only.
//!
//! So the contact compliances come from the m × m block alone ([`QuasiDefiniteLdlt::trailing_inverse`],
//! milliseconds instead of n_t full solves), and a time step costs one full solve: a full forward
//! sweep of the right-hand side without contact terms and a trailing backward sweep for
//! w_τ^free, then, with the contact terms, a trailing forward sweep and one full backward sweep
//! (`StepSystem::free_step` of `crate::step::direct`). The sweeps are our own loops over faer's
//! supernodal layout (faer 0.24 has no forward/backward split for a supernodal LDLᵀ; measured as
//! fast as its full solve). The price of the constraint on the ordering is a larger factor
//! (+21 % in 2D at 49k unknowns, +47–50 % in 3D, where the dense trailing supernode also doubles
//! the factorization time): a full sweep reads more. The
//! rejected alternatives: AMD on all unknowns with n_t column solves for the compliances (½–1 s
//! in 2D, 12 s in 3D per set-up) and two full solves per step; a simplicial factor, whose
//! trailing block is easier to read but whose numeric factorization is 4–8× slower
//! (docs/linear-algebra-study.md).
//!
//! **What a sweep costs.** On the 2D reference factor (5 025 supernodes, most 4–16 columns
//! wide) a full sweep reads 5.3 M entries, 42 MB, which one core of this machine streams in
//! 1.5 ms. The sweeps took 5.5–5.9 ms: bound not by memory but by 2-wide SSE2 arithmetic (the
//! default x86-64 target) and by supernodes too short for the hardware's stream prefetcher.
//! With [`prefetch`] of the supernode [`PREFETCH_AHEAD`] ahead and the repository's x86-64-v3
//! build (AVX2: `.cargo/config.toml`) a sweep takes 2.0–3.5 ms, the results the same bits
//! (docs/performance.md, "The instruction set and the sweeps' prefetch").
//!
//! **Rejected: L in single precision with iterative refinement.** A copy of L in f32 (D, the
//! vectors and the sums in f64) swept by the same loops, refined against S in f64
//! (x ← x + S̃⁻¹(J b − S x)). Measured on the 2D reference step matrix (49 344 unknowns, 6.2 M
//! entries in L, 49.8 MB in f64 and 24.9 MB in f32; a loaded 2-core machine; three runs of the
//! study at commit 7a55b2b; an earlier measurement gave 0.67× and 1.41×, alike). The f32 solve
//! takes 0.66–0.83× the f64 one (10.5–14.1 ms against 12.8–17.2 ms): the sweeps are not purely
//! bandwidth-bound. A mat-vec with S takes 1.9–2.8 ms. The f32 solve alone is 3–5e-8 off
//! the f64 solution (relative, ∞-norm). Started from the previous step's solution it is still
//! 1e-9–3e-8 off, because the velocities change by 7–100 % from step to step. So every solve
//! needs one refinement to reach the f64 solve's 1e-15, and two f32 solves plus two mat-vecs
//! cost 1.5–1.95× the f64 solve. Without refinement the run's solves take 20–30 % less, but its
//! outputs move by up to 6e-7 and its heat balance closes to 1.3e-5 instead of 6e-13: not the
//! same solution. The condensation would keep an f64 trailing block in any case
//! (docs/linear-algebra-study.md, issue 28 item 3).
//!
//! **Rejected: the full sweeps on both cores by subtrees** (measured 2026-11-27). A supernode's
//! pattern rows are its ancestors', so disjoint subtrees of the supernodal elimination tree
//! can be swept side by side: forward, each adding to its ancestors' positions in a buffer of
//! its own (summed in a fixed order: other bits than one sweep, the same on any thread count);
//! backward, once the top of the tree is done, each reading it (the same bits). On the 2D
//! reference factor (256 × 64), splitting the heaviest subtree while it held more than half of
//! the subtrees' entries gave 20 subtrees with 69 % of L's entries (the largest 2.0 of 6.2 M),
//! the top 31 % (the separators and the trailing block) swept alone. One full solve took 5.56
//! against 6.78 ms (1.22×, the best of five rounds of twenty): the two cores share this
//! machine's memory bandwidth, so the subtrees' part ran 1.35× faster, not 2×. In the runs it
//! was within the noise: the reference run's solves 0.80–0.95 s against 0.90–1.00 s, the 3D
//! example's (direct path) 1.43–1.52 s against 1.55–1.57 s, two or three interleaved runs each.
//! Not kept for that, with the forward sweep's bits changed.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LdltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::SymbolicSparseColMat;
use faer::{Accum, Conj, Mat, MatMut, MatRef, Par, Side};

use super::error::{FactorStage, LaError as Error};
use super::sparse::CscMatrix;

/// One supernode of the factor: columns `begin..end` (positions in the permuted order), whose
/// values are a column-major (width + pattern) × width block at `val`: the top width × width
/// block holds D on its diagonal and the unit lower triangle of L below it (its upper part is
/// not read); the bottom rows are L at the positions `rows[pattern..pattern + n_pattern]`.
#[derive(Debug, Clone, Copy)]
struct Supernode {
    begin: usize,
    end: usize,
    val: usize,
    pattern: usize,
    n_pattern: usize,
}

impl Supernode {
    fn width(&self) -> usize {
        self.end - self.begin
    }

    fn height(&self) -> usize {
        self.width() + self.n_pattern
    }
}

/// LDLᵀ of a symmetric quasi-definite matrix, with the split sweeps described in the module
/// header. Positions are indices in the permuted order; unknowns are indices of S.
pub struct QuasiDefiniteLdlt {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    /// position → unknown.
    fwd: Vec<usize>,
    /// unknown → position.
    inv: Vec<usize>,
    nodes: Vec<Supernode>,
    /// Row positions of the supernodes' bottom blocks, concatenated.
    rows: Vec<usize>,
    /// 1 / D by position.
    inv_diag: Vec<f64>,
    /// First position of the trailing block.
    trailing: usize,
    /// Length of the scratch a single-column sweep needs (the most rows below a supernode).
    scratch: usize,
}

impl QuasiDefiniteLdlt {
    /// Factors S (both triangles stored; the lower one is read) under AMD, with no trailing
    /// block.
    pub fn new(s: &CscMatrix) -> Result<Self, Error> {
        Self::with_trailing(s, &[])
    }

    /// Factors S with the unknowns `trailing` ordered last, in the order given (a repeated
    /// unknown counts once), the others by AMD on the graph of S without them.
    pub fn with_trailing(s: &CscMatrix, trailing: &[usize]) -> Result<Self, Error> {
        let n = s.n_rows;
        let mut last = vec![false; n];
        let tail: Vec<usize> = trailing
            .iter()
            .copied()
            .filter(|&i| !std::mem::replace(&mut last[i], true))
            .collect();
        let fwd = constrained_amd(s, &last, &tail)?;
        let mut inv = vec![0; n];
        for (position, &unknown) in fwd.iter().enumerate() {
            inv[unknown] = position;
        }
        let faer_s = s.to_faer();
        let symbolic = factorize_symbolic_cholesky(
            faer_s.symbolic(),
            Side::Lower,
            SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&fwd, &inv, n)),
            CholeskySymbolicParams {
                // The sweeps read the supernodal layout only.
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| Error::Factorization {
            stage: FactorStage::Symbolic,
            detail: format!("{e:?}"),
        })?;
        let mut values = vec![0.0; symbolic.len_val()];
        let par = Par::Seq;
        let mut mem = MemBuffer::new(symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()));
        symbolic
            .factorize_numeric_ldlt(
                &mut values,
                faer_s.as_ref(),
                Side::Lower,
                LdltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| Error::Factorization {
                stage: FactorStage::Numeric,
                detail: format!("{e:?}"),
            })?;

        let mut nodes = Vec::new();
        let mut rows = Vec::new();
        match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(sn) => {
                for k in 0..sn.n_supernodes() {
                    let pattern = sn.supernode(k).pattern();
                    nodes.push(Supernode {
                        begin: sn.supernode_begin()[k],
                        end: sn.supernode_end()[k],
                        val: sn.col_ptr_for_val()[k],
                        pattern: rows.len(),
                        n_pattern: pattern.len(),
                    });
                    rows.extend_from_slice(pattern);
                }
            }
            SymbolicCholeskyRaw::Simplicial(_) if n == 0 => {}
            SymbolicCholeskyRaw::Simplicial(_) => {
                return Err(Error::Factorization {
                    stage: FactorStage::Layout,
                    detail: "simplicial, where the sweeps expect supernodes".into(),
                });
            }
        }
        let mut inv_diag = vec![0.0; n];
        for node in &nodes {
            let h = node.height();
            for j in 0..node.width() {
                inv_diag[node.begin + j] = 1.0 / values[node.val + j * h + j];
            }
        }
        let scratch = nodes.iter().map(|node| node.n_pattern).max().unwrap_or(0);
        Ok(QuasiDefiniteLdlt {
            symbolic,
            values,
            fwd,
            inv,
            nodes,
            rows,
            inv_diag,
            trailing: n - tail.len(),
            scratch,
        })
    }

    /// faer's symbolic factorization (its supernodes, its permutation).
    pub fn symbolic(&self) -> &SymbolicCholesky<usize> {
        &self.symbolic
    }

    /// Stored entries of the factor L.
    pub fn factor_nnz(&self) -> usize {
        self.values.len()
    }

    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.fwd.len()
    }

    /// First position of the trailing block (n − m).
    pub fn trailing_start(&self) -> usize {
        self.trailing
    }

    /// The position of an unknown in the factor's order.
    pub fn position(&self, unknown: usize) -> usize {
        self.inv[unknown]
    }

    /// The unknown at a position of the factor's order.
    pub fn unknown_at(&self, position: usize) -> usize {
        self.fwd[position]
    }

    /// Length of the `scratch` the sweeps need.
    pub fn scratch_len(&self) -> usize {
        self.scratch
    }

    /// Solves S X = B in place for a column-major block with `n_cols` columns (faer's own
    /// supernodal solve).
    pub fn solve_in_place(&self, block: &mut [f64], n_cols: usize) {
        let n = self.symbolic.nrows();
        let par = Par::Seq;
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(n_cols, par));
        LdltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(block, n, n_cols),
            par,
            MemStack::new(&mut mem),
        );
    }

    /// The same with the split sweeps: `permuted` (length n) and `scratch` (at least
    /// [`Self::scratch_len`]) are work space.
    pub fn solve_split_in_place(&self, b: &mut [f64], permuted: &mut [f64], scratch: &mut [f64]) {
        self.permute(b, permuted);
        self.forward(permuted, scratch, 0);
        self.diagonal(permuted, 0);
        self.backward(permuted, scratch, 0);
        self.unpermute(permuted, b);
    }

    /// y = P b: `y[position] = b[unknown]`.
    pub fn permute(&self, b: &[f64], y: &mut [f64]) {
        for (y, &unknown) in y.iter_mut().zip(&self.fwd) {
            *y = b[unknown];
        }
    }

    /// x = Pᵀ y.
    pub fn unpermute(&self, y: &[f64], x: &mut [f64]) {
        for (x, &position) in x.iter_mut().zip(&self.inv) {
            *x = y[position];
        }
    }

    /// Forward sweep y ← L⁻¹ y over the columns from position `from` on; y must vanish before
    /// `from` (then it does after: L is lower triangular).
    pub fn forward(&self, y: &mut [f64], scratch: &mut [f64], from: usize) {
        let first = self.nodes.partition_point(|node| node.end <= from);
        let nodes = &self.nodes[first..];
        for (k, node) in nodes.iter().enumerate() {
            if let Some(ahead) = nodes.get(k + PREFETCH_AHEAD) {
                prefetch(self.node_values(ahead));
            }
            let (w, h, p) = (node.width(), node.height(), node.n_pattern);
            let skip = from.saturating_sub(node.begin);
            let values = &self.values[node.val..node.val + h * w];
            let rows = &self.rows[node.pattern..node.pattern + p];
            let top = &mut y[node.begin..node.end];
            // The unit lower triangle, column by column: y_i −= L_ij y_j below the diagonal.
            for j in skip..w {
                let (done, rest) = top.split_at_mut(j + 1);
                let yj = done[j];
                for (r, l) in rest.iter_mut().zip(&values[j * h + j + 1..j * h + w]) {
                    *r -= l * yj;
                }
            }
            // The bottom rows: u = L_bottom y_top into the scratch, then scattered.
            let top = &y[node.begin..node.end];
            let update = &mut scratch[..p];
            update.fill(0.0);
            let mut j = skip;
            while j + 4 <= w {
                let c = |q: usize| &values[(j + q) * h + w..(j + q) * h + w + p];
                let (c0, c1, c2, c3) = (c(0), c(1), c(2), c(3));
                let (y0, y1, y2, y3) = (top[j], top[j + 1], top[j + 2], top[j + 3]);
                let update = &mut update[..p];
                for i in 0..p {
                    update[i] += c0[i] * y0 + c1[i] * y1 + c2[i] * y2 + c3[i] * y3;
                }
                j += 4;
            }
            for j in j..w {
                let yj = top[j];
                for (u, l) in update.iter_mut().zip(&values[j * h + w..(j + 1) * h]) {
                    *u += l * yj;
                }
            }
            for (&row, u) in rows.iter().zip(update.iter()) {
                y[row] -= u;
            }
        }
    }

    /// z ← D⁻¹ z on the positions from `from` on.
    pub fn diagonal(&self, z: &mut [f64], from: usize) {
        for (z, d) in z[from..].iter_mut().zip(&self.inv_diag[from..]) {
            *z *= d;
        }
    }

    /// Backward sweep x ← L⁻ᵀ x for the positions from `to` on: they depend on x there only, and
    /// the positions before `to` are left as they are.
    pub fn backward(&self, x: &mut [f64], scratch: &mut [f64], to: usize) {
        let first = self.nodes.partition_point(|node| node.end <= to);
        let nodes = &self.nodes[first..];
        for (k, node) in nodes.iter().enumerate().rev() {
            if let Some(ahead) = k.checked_sub(PREFETCH_AHEAD).map(|a| &nodes[a]) {
                prefetch(self.node_values(ahead));
            }
            let (w, h, p) = (node.width(), node.height(), node.n_pattern);
            let skip = to.saturating_sub(node.begin);
            let values = &self.values[node.val..node.val + h * w];
            let rows = &self.rows[node.pattern..node.pattern + p];
            let below = &mut scratch[..p];
            for (b, &row) in below.iter_mut().zip(rows) {
                *b = x[row];
            }
            let top = &mut x[node.begin..node.end];
            // The bottom rows: x_top −= L_bottomᵀ x_below, four columns at a time.
            let mut j = skip;
            while j + 4 <= w {
                let c = |q: usize| &values[(j + q) * h + w..(j + q + 1) * h];
                let sums = dot4([c(0), c(1), c(2), c(3)], below);
                for (q, sum) in sums.iter().enumerate() {
                    top[j + q] -= sum;
                }
                j += 4;
            }
            for j in j..w {
                top[j] -= super::vector::dot(&values[j * h + w..(j + 1) * h], below);
            }
            // The unit upper triangle L_topᵀ, from the last column back.
            for j in (skip..w).rev() {
                let sum = super::vector::dot(&values[j * h + j + 1..j * h + w], &top[j + 1..]);
                top[j] -= sum;
            }
        }
    }

    /// A supernode's values (its column-major block).
    fn node_values(&self, node: &Supernode) -> &[f64] {
        &self.values[node.val..node.val + node.height() * node.width()]
    }

    /// Columns of (L₂₂ D₂ L₂₂ᵀ)⁻¹, the trailing block of P S⁻¹ Pᵀ, for the given trailing
    /// positions: column-major, m rows (row r is position n − m + r), one column per position.
    pub fn trailing_inverse(&self, positions: &[usize]) -> Vec<f64> {
        let t0 = self.trailing;
        let m = self.n() - t0;
        let k = positions.len();
        let mut block = vec![0.0; m * k];
        for (j, &p) in positions.iter().enumerate() {
            assert!(p >= t0, "position {p} is not in the trailing block");
            block[j * m + p - t0] = 1.0;
        }
        if k == 0 {
            return block;
        }
        let mut x = MatMut::from_column_major_slice_mut(&mut block, m, k);
        let first = self.nodes.partition_point(|node| node.end <= t0);
        let nodes = &self.nodes[first..];
        let max_pattern = nodes.iter().map(|node| node.n_pattern).max().unwrap_or(0);
        let mut tmp = Mat::<f64>::zeros(max_pattern, k);
        // The same three passes as a single column, with faer's dense kernels per supernode.
        for node in nodes {
            let (skip, l_top, l_bottom, rows) = self.trailing_parts(node);
            let top = node.begin + skip - t0;
            let width = node.end - node.begin - skip;
            let mut x_top = x.rb_mut().subrows_mut(top, width);
            faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(l_top, x_top.rb_mut(), Par::Seq);
            let mut t = tmp.as_mut().subrows_mut(0, rows.len());
            faer::linalg::matmul::matmul(t.rb_mut(), Accum::Replace, l_bottom, x_top.rb(), 1.0, Par::Seq);
            for c in 0..k {
                for (i, &row) in rows.iter().enumerate() {
                    x[(row - t0, c)] -= t[(i, c)];
                }
            }
        }
        for c in 0..k {
            for r in 0..m {
                x[(r, c)] *= self.inv_diag[t0 + r];
            }
        }
        for node in nodes.iter().rev() {
            let (skip, l_top, l_bottom, rows) = self.trailing_parts(node);
            let mut t = tmp.as_mut().subrows_mut(0, rows.len());
            for c in 0..k {
                for (i, &row) in rows.iter().enumerate() {
                    t[(i, c)] = x[(row - t0, c)];
                }
            }
            let top = node.begin + skip - t0;
            let width = node.end - node.begin - skip;
            let mut x_top = x.rb_mut().subrows_mut(top, width);
            faer::linalg::matmul::matmul(x_top.rb_mut(), Accum::Add, l_bottom.transpose(), t.rb(), -1.0, Par::Seq);
            faer::linalg::triangular_solve::solve_unit_upper_triangular_in_place(
                l_top.transpose(),
                x_top.rb_mut(),
                Par::Seq,
            );
        }
        block
    }

    /// A supernode's part on the trailing block: the columns it skips before the block, its top
    /// (unit lower) block and its bottom block on the remaining columns, and its bottom rows.
    fn trailing_parts(&self, node: &Supernode) -> (usize, MatRef<'_, f64>, MatRef<'_, f64>, &[usize]) {
        let (w, h) = (node.width(), node.height());
        let skip = self.trailing.saturating_sub(node.begin);
        let all = MatRef::from_column_major_slice(&self.values[node.val..node.val + h * w], h, w);
        let columns = all.subcols(skip, w - skip);
        let l_top = columns.subrows(skip, w - skip);
        let l_bottom = columns.subrows(w, node.n_pattern);
        (
            skip,
            l_top,
            l_bottom,
            &self.rows[node.pattern..node.pattern + node.n_pattern],
        )
    }
}

/// How many supernodes ahead of the one being swept [`prefetch`] asks for: the 2D reference
/// factor's (5 025 supernodes, most 4–16 columns wide) sweeps are shortest with 2–4.
const PREFETCH_AHEAD: usize = 4;

/// Asks the memory system for `values` ahead of their use, one request per 64-byte line. A
/// hint only: it changes no result. A sweep walks the factor once, a supernode at a time, and
/// most supernodes are a few kB, too short for the hardware's stream prefetcher to run ahead
/// of the columns they read.
#[inline]
fn prefetch(values: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    for line in values.chunks(8) {
        // SAFETY: a prefetch neither reads nor writes memory as far as the program can tell,
        // and does not fault, whatever the address; this one is inside `values` besides.
        unsafe { core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(line.as_ptr().cast()) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = values;
}

/// The four dot products c_q · v, q = 0…3 (the c_q as long as v), with two partial sums each
/// so that the loop vectorizes.
fn dot4(c: [&[f64]; 4], v: &[f64]) -> [f64; 4] {
    let n = v.len();
    let c = c.map(|c| &c[..n]);
    let mut lanes = [[0.0f64; 4]; 2];
    let pairs = n / 2;
    for k in 0..pairs {
        for (l, lane) in lanes.iter_mut().enumerate() {
            let i = 2 * k + l;
            let vi = v[i];
            for q in 0..4 {
                lane[q] += c[q][i] * vi;
            }
        }
    }
    let mut sums = [0.0; 4];
    for q in 0..4 {
        sums[q] = lanes[0][q] + lanes[1][q];
        if n % 2 == 1 {
            sums[q] += c[q][n - 1] * v[n - 1];
        }
    }
    sums
}

/// The order (position → unknown): the unknowns not in `last` by faer's AMD on the graph of S
/// without the unknowns in `last`, then `tail` as given.
fn constrained_amd(s: &CscMatrix, last: &[bool], tail: &[usize]) -> Result<Vec<usize>, Error> {
    let n = s.n_rows;
    let rest: Vec<usize> = (0..n).filter(|&i| !last[i]).collect();
    let mut local = vec![usize::MAX; n];
    for (k, &i) in rest.iter().enumerate() {
        local[i] = k;
    }
    let mut col_ptr = Vec::with_capacity(rest.len() + 1);
    let mut row_idx = Vec::with_capacity(s.nnz());
    col_ptr.push(0);
    for &j in &rest {
        for k in s.col_ptr[j]..s.col_ptr[j + 1] {
            let r = local[s.row_idx[k] as usize];
            if r != usize::MAX {
                row_idx.push(r);
            }
        }
        col_ptr.push(row_idx.len());
    }
    let m = rest.len();
    let nnz = row_idx.len();
    let graph = SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
    let mut perm = vec![0usize; m];
    let mut perm_inv = vec![0usize; m];
    let mut mem = MemBuffer::new(amd::order_maybe_unsorted_scratch::<usize>(m, nnz));
    amd::order_maybe_unsorted(
        &mut perm,
        &mut perm_inv,
        graph.as_ref(),
        amd::Control::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|e| Error::Factorization {
        stage: FactorStage::Ordering,
        detail: format!("AMD: {e:?}"),
    })?;
    Ok(perm.iter().map(|&k| rest[k]).chain(tail.iter().copied()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> CscMatrix {
        // [ 4 1 | 1 ]
        // [ 1 3 | 0 ]
        // [ 1 0 |-2 ]
        CscMatrix::from_triplets(
            3,
            3,
            vec![
                (0, 0, 4.0),
                (1, 0, 1.0),
                (0, 1, 1.0),
                (1, 1, 3.0),
                (2, 0, 1.0),
                (0, 2, 1.0),
                (2, 2, -2.0),
            ],
        )
    }

    #[test]
    fn solves_a_quasi_definite_system() {
        let s = small();
        let x = [1.0, -2.0, 0.5];
        for trailing in [&[][..], &[0], &[2, 1], &[1, 2, 0]] {
            let ldlt = QuasiDefiniteLdlt::with_trailing(&s, trailing).unwrap();
            assert_eq!(ldlt.trailing_start(), 3 - trailing.len());
            let mut b = s.mul(&x);
            ldlt.solve_in_place(&mut b, 1);
            let mut c = s.mul(&x);
            let (mut permuted, mut scratch) = (vec![0.0; 3], vec![0.0; ldlt.scratch_len()]);
            ldlt.solve_split_in_place(&mut c, &mut permuted, &mut scratch);
            for ((a, c), e) in b.iter().zip(&c).zip(x) {
                assert!((a - e).abs() < 1e-14);
                assert!((c - e).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn the_trailing_inverse_is_the_block_of_the_inverse() {
        let s = small();
        let ldlt = QuasiDefiniteLdlt::with_trailing(&s, &[2, 0]).unwrap();
        // Columns of S⁻¹ by full solves.
        let mut inverse = vec![0.0; 9];
        for j in 0..3 {
            inverse[j * 3 + j] = 1.0;
        }
        ldlt.solve_in_place(&mut inverse, 3);
        let positions = [ldlt.position(0), ldlt.position(2)];
        let block = ldlt.trailing_inverse(&positions);
        for (c, &unknown_c) in [0usize, 2].iter().enumerate() {
            for r in 0..2 {
                let unknown_r = ldlt.fwd[1 + r];
                assert!((block[c * 2 + r] - inverse[unknown_c * 3 + unknown_r]).abs() < 1e-14);
            }
        }
    }
}
