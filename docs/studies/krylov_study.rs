//! Which Krylov solver and preconditioner for the 3D step matrix, and from which dependency?
//! (A measured study for issue 11, item 4; the numbers and the recommendation are in
//! docs/krylov-study.md.)
//!
//! ```text
//! cp docs/studies/krylov_study.rs examples/
//! # Cargo.toml: [dev-dependencies] kryst = { version = "4.3", default-features = false, features = ["backend-faer"] }
//! RAYON_NUM_THREADS=1 cargo run --release --example krylov_study -- \
//!     --set mesh.nx=72 --set mesh.ny=18 --set mesh.nz=18 --set time.steps=64 [--direct] [--export DIR]
//! ```
//!
//! It builds the problem of `scenarios/paper3d.toml` (further `--set`s are laid over it) and
//! assembles the step matrix A = [[ℳ/k + 𝒦_A + k𝒦_B, G], [−Gᵀ, ℳ_θ/k + 𝒦_θ]] on the unknowns
//! exactly as `StepSystem::with_step` does (same triplets; A itself, not the sign-flipped S = J A,
//! and without factoring it). Right-hand sides (`A x = b`):
//!
//! * `step1`: the right-hand side of step 1 from the initial state;
//! * `step5`: that of step 5 after four contact-free steps (solved to 1e-12 by GMRES + ILU(0));
//! * `unit`: a unit tangential load at the middle contact node (one condensation column).
//!
//! Candidates, every one from x₀ = 0 to ‖b − A x‖ ≤ tol ‖b‖ (the unpreconditioned, true
//! residual; right preconditioning for GMRES and BiCGStab):
//!
//! * hand-written on CSR (this file): GMRES(30) and BiCGStab with Jacobi, ILU(0) of A (stored
//!   interleaved in A's rows, `ilu`, or split into L and U with 32-bit indices, `ilu-split`), the
//!   block-diagonal ILU(0) (ILU(0) of K_w and of K_θ, coupling dropped); CG with Jacobi and IC(0)
//!   (= ILU(0) of the symmetric K_w) on the velocity block K_w alone;
//! * `kryst` 4.3 (pure Rust): its GMRES + ILU(0) on A through `KspContext`; its smoothed-
//!   aggregation AMG (nodal, block size 3, the six rigid-body modes as near-nullspace) on K_w as the
//!   preconditioner of our CG, and as the velocity block of a block-diagonal preconditioner of A;
//! * PETSc: `--export DIR` writes A, K_w (padded to 3 unknowns per node), the right-hand sides and
//!   the rigid-body modes in PETSc's binary format for `krylov_petsc.c` (beside this file).
//!
//! `micro` times the kernels alone (products with A, ILU(0) sweeps in both layouts).
//!
//! Times are wall-clock seconds; a solve is repeated `--reps` times (default 5) and min / median
//! are printed. The machine is shared: run with `RAYON_NUM_THREADS=1` (PETSc runs serial).
//! Memory: the growth of the peak resident set (VmHWM, reset through /proc/self/clear_refs).

use std::io::Write;
use std::sync::Arc;
use std::time::Instant;

use kryst::preconditioner::amg::{AMGBuilder, CoarseSolve, InterpType, RelaxPhase, RelaxType};
use kryst::preconditioner::{PcSide, Preconditioner};
use thermocontact::fem::sparse::CscMatrix;
use thermocontact::solver::system::{State, StepSystem};
use thermocontact::{Problem, Scenario};

/// Krylov restart length of GMRES.
const RESTART: usize = 30;
/// Iteration cap of every Krylov run.
const MAX_IT: usize = 2000;

// ---------------------------------------------------------------------------------------------
// CSR matrices and the hand-written preconditioners.

/// A square CSR matrix with sorted column indices in each row.
#[derive(Clone)]
struct Csr {
    n: usize,
    ptr: Vec<usize>,
    col: Vec<usize>,
    val: Vec<f64>,
}

impl Csr {
    fn nnz(&self) -> usize {
        self.val.len()
    }

    /// y = A x.
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        for (i, y) in y.iter_mut().enumerate().take(self.n) {
            let (s, e) = (self.ptr[i], self.ptr[i + 1]);
            *y = sparse_dot(&self.col[s..e], &self.val[s..e], x);
        }
    }

    /// The block rows × cols of a range pair (both ranges contiguous).
    fn block(&self, rows: std::ops::Range<usize>, cols: std::ops::Range<usize>) -> Csr {
        let mut ptr = vec![0];
        let (mut col, mut val) = (Vec::new(), Vec::new());
        for i in rows.clone() {
            for p in self.ptr[i]..self.ptr[i + 1] {
                let j = self.col[p];
                if cols.contains(&j) {
                    col.push(j - cols.start);
                    val.push(self.val[p]);
                }
            }
            ptr.push(col.len());
        }
        Csr {
            n: rows.len(),
            ptr,
            col,
            val,
        }
    }

    fn diagonal(&self) -> Vec<f64> {
        (0..self.n)
            .map(|i| {
                (self.ptr[i]..self.ptr[i + 1])
                    .find(|&p| self.col[p] == i)
                    .map_or(0.0, |p| self.val[p])
            })
            .collect()
    }

    fn to_kryst(&self) -> kryst::matrix::sparse::CsrMatrix<f64> {
        kryst::matrix::sparse::CsrMatrix::from_csr(self.n, self.n, self.ptr.clone(), self.col.clone(), self.val.clone())
    }
}

/// Σ v·x[c] with four partial sums (a single sequential sum makes each row of a triangular
/// solve one long chain of dependent additions).
#[inline]
fn sparse_dot(cols: &[usize], vals: &[f64], x: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (c4, v4) = (cols.chunks_exact(4), vals.chunks_exact(4));
    let (cr, vr) = (c4.remainder(), v4.remainder());
    for (c, v) in c4.zip(v4) {
        for k in 0..4 {
            acc[k] += v[k] * x[c[k]];
        }
    }
    let tail: f64 = cr.iter().zip(vr).map(|(&c, v)| v * x[c]).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// z = M⁻¹ r.
trait Pc {
    fn apply(&self, r: &[f64], z: &mut [f64]);
}

struct Jacobi(Vec<f64>);
impl Pc for Jacobi {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        for ((z, r), d) in z.iter_mut().zip(r).zip(&self.0) {
            *z = r / d;
        }
    }
}

/// ILU(0): L (unit) and U on the pattern of A, in one CSR.
struct Ilu0 {
    lu: Csr,
    diag: Vec<usize>,
}

impl Ilu0 {
    fn new(a: &Csr) -> Ilu0 {
        let mut lu = a.clone();
        let n = a.n;
        let diag: Vec<usize> = (0..n)
            .map(|i| {
                (a.ptr[i]..a.ptr[i + 1])
                    .find(|&p| a.col[p] == i)
                    .expect("a structural diagonal")
            })
            .collect();
        let mut pos = vec![usize::MAX; n];
        for i in 0..n {
            let (s, e) = (lu.ptr[i], lu.ptr[i + 1]);
            for p in s..e {
                pos[lu.col[p]] = p;
            }
            for p in s..diag[i] {
                let k = lu.col[p];
                let l = lu.val[p] / lu.val[diag[k]];
                lu.val[p] = l;
                for q in diag[k] + 1..lu.ptr[k + 1] {
                    let t = pos[lu.col[q]];
                    if t != usize::MAX {
                        lu.val[t] -= l * lu.val[q];
                    }
                }
            }
            for p in s..e {
                pos[lu.col[p]] = usize::MAX;
            }
        }
        Ilu0 { lu, diag }
    }
}

impl Pc for Ilu0 {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let lu = &self.lu;
        for i in 0..lu.n {
            let (s, d) = (lu.ptr[i], self.diag[i]);
            let l = sparse_dot(&lu.col[s..d], &lu.val[s..d], z);
            z[i] = r[i] - l;
        }
        for i in (0..lu.n).rev() {
            let (d, e) = (self.diag[i], lu.ptr[i + 1]);
            let u = sparse_dot(&lu.col[d + 1..e], &lu.val[d + 1..e], z);
            z[i] = (z[i] - u) / lu.val[d];
        }
    }
}

/// The same ILU(0) factor stored for its sweeps: L and U in separate arrays (each sweep streams
/// only its half), 32-bit column indices, the inverse of U's diagonal.
struct Ilu0Split {
    l_ptr: Vec<usize>,
    l_col: Vec<u32>,
    l_val: Vec<f64>,
    u_ptr: Vec<usize>,
    u_col: Vec<u32>,
    u_val: Vec<f64>,
    inv_diag: Vec<f64>,
}

impl Ilu0Split {
    fn new(a: &Csr) -> Ilu0Split {
        let f = Ilu0::new(a);
        let lu = &f.lu;
        let n = lu.n;
        let mut s = Ilu0Split {
            l_ptr: vec![0],
            l_col: Vec::new(),
            l_val: Vec::new(),
            u_ptr: vec![0],
            u_col: Vec::new(),
            u_val: Vec::new(),
            inv_diag: Vec::with_capacity(n),
        };
        for i in 0..n {
            for p in lu.ptr[i]..f.diag[i] {
                s.l_col.push(lu.col[p] as u32);
                s.l_val.push(lu.val[p]);
            }
            s.l_ptr.push(s.l_col.len());
            for p in f.diag[i] + 1..lu.ptr[i + 1] {
                s.u_col.push(lu.col[p] as u32);
                s.u_val.push(lu.val[p]);
            }
            s.u_ptr.push(s.u_col.len());
            s.inv_diag.push(1.0 / lu.val[f.diag[i]]);
        }
        s
    }
}

#[inline]
fn sparse_dot32(cols: &[u32], vals: &[f64], x: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (c4, v4) = (cols.chunks_exact(4), vals.chunks_exact(4));
    let (cr, vr) = (c4.remainder(), v4.remainder());
    for (c, v) in c4.zip(v4) {
        for k in 0..4 {
            acc[k] += v[k] * x[c[k] as usize];
        }
    }
    let tail: f64 = cr.iter().zip(vr).map(|(&c, v)| v * x[c as usize]).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

impl Pc for Ilu0Split {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let n = self.inv_diag.len();
        for i in 0..n {
            let (s, e) = (self.l_ptr[i], self.l_ptr[i + 1]);
            z[i] = r[i] - sparse_dot32(&self.l_col[s..e], &self.l_val[s..e], z);
        }
        for i in (0..n).rev() {
            let (s, e) = (self.u_ptr[i], self.u_ptr[i + 1]);
            z[i] = (z[i] - sparse_dot32(&self.u_col[s..e], &self.u_val[s..e], z)) * self.inv_diag[i];
        }
    }
}

/// A with 32-bit column indices (the product of the "split" variant).
struct Csr32 {
    ptr: Vec<usize>,
    col: Vec<u32>,
    val: Vec<f64>,
}

impl Csr32 {
    fn new(a: &Csr) -> Csr32 {
        Csr32 {
            ptr: a.ptr.clone(),
            col: a.col.iter().map(|&c| c as u32).collect(),
            val: a.val.clone(),
        }
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        for (i, y) in y.iter_mut().enumerate() {
            let (s, e) = (self.ptr[i], self.ptr[i + 1]);
            *y = sparse_dot32(&self.col[s..e], &self.val[s..e], x);
        }
    }
}

/// diag(M_w⁻¹, M_θ⁻¹) for the 2 × 2 block system.
struct BlockDiag<'a> {
    n_w: usize,
    w: &'a dyn Pc,
    theta: &'a dyn Pc,
}

impl Pc for BlockDiag<'_> {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let (rw, rt) = r.split_at(self.n_w);
        let (zw, zt) = z.split_at_mut(self.n_w);
        self.w.apply(rw, zw);
        self.theta.apply(rt, zt);
    }
}

/// A kryst preconditioner set up on the padded K_w (3 unknowns per node), applied to the
/// unknowns of K_w.
struct PaddedKryst {
    pc: Box<dyn Preconditioner>,
    /// Padded index of each unknown of K_w.
    map: Vec<usize>,
    n_padded: usize,
}

impl Pc for PaddedKryst {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let mut rp = vec![0.0; self.n_padded];
        let mut zp = vec![0.0; self.n_padded];
        for (j, &p) in self.map.iter().enumerate() {
            rp[p] = r[j];
        }
        self.pc.apply(PcSide::Left, &rp, &mut zp).expect("kryst apply");
        for (j, &p) in self.map.iter().enumerate() {
            z[j] = zp[p];
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Krylov methods (x₀ = 0; relative true residual ‖b − A x‖ / ‖b‖ as the stopping test).

struct Outcome {
    iterations: usize,
    x: Vec<f64>,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

fn residual(a: &Csr, b: &[f64], x: &[f64]) -> f64 {
    let mut ax = vec![0.0; a.n];
    a.apply(x, &mut ax);
    let r: Vec<f64> = b.iter().zip(&ax).map(|(b, ax)| b - ax).collect();
    norm(&r) / norm(b)
}

/// Right-preconditioned restarted GMRES(m), modified Gram–Schmidt, Givens rotations.
fn gmres(a: &Csr, pc: &dyn Pc, b: &[f64], tol: f64) -> Outcome {
    let n = a.n;
    let m = RESTART;
    let bnorm = norm(b);
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let mut it = 0;
    let mut v: Vec<Vec<f64>> = (0..=m).map(|_| vec![0.0; n]).collect();
    let mut z = vec![0.0; n];
    let mut w = vec![0.0; n];
    'outer: loop {
        let beta = norm(&r);
        if beta <= tol * bnorm || it >= MAX_IT {
            break;
        }
        v[0].iter_mut().zip(&r).for_each(|(v, r)| *v = r / beta);
        let mut h = vec![vec![0.0; m]; m + 1];
        let (mut cs, mut sn) = (vec![0.0; m], vec![0.0; m]);
        let mut g = vec![0.0; m + 1];
        g[0] = beta;
        let mut j_done = 0;
        for j in 0..m {
            pc.apply(&v[j], &mut z);
            a.apply(&z, &mut w);
            for i in 0..=j {
                let hij = dot(&w, &v[i]);
                h[i][j] = hij;
                w.iter_mut().zip(&v[i]).for_each(|(w, v)| *w -= hij * v);
            }
            let hn = norm(&w);
            h[j + 1][j] = hn;
            if hn > 0.0 {
                v[j + 1].iter_mut().zip(&w).for_each(|(v, w)| *v = w / hn);
            }
            for i in 0..j {
                let t = cs[i] * h[i][j] + sn[i] * h[i + 1][j];
                h[i + 1][j] = -sn[i] * h[i][j] + cs[i] * h[i + 1][j];
                h[i][j] = t;
            }
            let d = (h[j][j] * h[j][j] + h[j + 1][j] * h[j + 1][j]).sqrt();
            cs[j] = h[j][j] / d;
            sn[j] = h[j + 1][j] / d;
            h[j][j] = d;
            h[j + 1][j] = 0.0;
            g[j + 1] = -sn[j] * g[j];
            g[j] *= cs[j];
            it += 1;
            j_done = j + 1;
            let rel = g[j + 1].abs() / bnorm;
            if rel <= tol || it >= MAX_IT {
                break;
            }
        }
        // y = H⁻¹ g, x += M⁻¹ V y.
        let mut y = vec![0.0; j_done];
        for i in (0..j_done).rev() {
            let mut s = g[i];
            for k in i + 1..j_done {
                s -= h[i][k] * y[k];
            }
            y[i] = s / h[i][i];
        }
        w.fill(0.0);
        for (i, yi) in y.iter().enumerate() {
            w.iter_mut().zip(&v[i]).for_each(|(w, v)| *w += yi * v);
        }
        pc.apply(&w, &mut z);
        x.iter_mut().zip(&z).for_each(|(x, z)| *x += z);
        a.apply(&x, &mut w);
        r.iter_mut().zip(b.iter().zip(&w)).for_each(|(r, (b, ax))| *r = b - ax);
        if norm(&r) <= tol * bnorm || it >= MAX_IT {
            break 'outer;
        }
    }
    Outcome { iterations: it, x }
}

/// Right-preconditioned BiCGStab (one iteration = two products and two preconditioner solves).
fn bicgstab(a: &Csr, pc: &dyn Pc, b: &[f64], tol: f64) -> Outcome {
    let n = a.n;
    let bnorm = norm(b);
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let r0 = r.clone();
    let (mut p, mut v) = (vec![0.0; n], vec![0.0; n]);
    let (mut ph, mut sh, mut t) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut rho, mut alpha, mut omega) = (1.0, 1.0, 1.0);
    let mut it = 0;
    while norm(&r) > tol * bnorm && it < MAX_IT {
        let rho_new = dot(&r0, &r);
        let beta = (rho_new / rho) * (alpha / omega);
        rho = rho_new;
        for i in 0..n {
            p[i] = r[i] + beta * (p[i] - omega * v[i]);
        }
        pc.apply(&p, &mut ph);
        a.apply(&ph, &mut v);
        alpha = rho / dot(&r0, &v);
        let mut s = r.clone();
        s.iter_mut().zip(&v).for_each(|(s, v)| *s -= alpha * v);
        pc.apply(&s, &mut sh);
        a.apply(&sh, &mut t);
        omega = dot(&t, &s) / dot(&t, &t);
        for i in 0..n {
            x[i] += alpha * ph[i] + omega * sh[i];
            r[i] = s[i] - omega * t[i];
        }
        it += 1;
    }
    Outcome { iterations: it, x }
}

/// Preconditioned CG (A and M SPD).
fn cg(a: &Csr, pc: &dyn Pc, b: &[f64], tol: f64) -> Outcome {
    let n = a.n;
    let bnorm = norm(b);
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let mut z = vec![0.0; n];
    pc.apply(&r, &mut z);
    let mut p = z.clone();
    let mut q = vec![0.0; n];
    let mut rz = dot(&r, &z);
    let mut it = 0;
    while norm(&r) > tol * bnorm && it < MAX_IT {
        a.apply(&p, &mut q);
        let alpha = rz / dot(&p, &q);
        x.iter_mut().zip(&p).for_each(|(x, p)| *x += alpha * p);
        r.iter_mut().zip(&q).for_each(|(r, q)| *r -= alpha * q);
        pc.apply(&r, &mut z);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        p.iter_mut().zip(&z).for_each(|(p, z)| *p = z + beta * *p);
        it += 1;
    }
    Outcome { iterations: it, x }
}

// ---------------------------------------------------------------------------------------------
// The step matrix and its right-hand sides (as in StepSystem, without the factorization).

struct Step {
    a: Csr,
    lift: Vec<f64>,
    n_w: usize,
    k: f64,
}

fn assemble(problem: &Problem, k: f64) -> Step {
    let (vel, temp) = (&problem.velocity, &problem.temperature);
    let n_w = vel.n_free;
    let n = n_w + temp.n_free;
    let mats = &problem.matrices;
    let theta_d = &problem.theta_dirichlet;
    let mut lift = vec![0.0; n];
    // Triplets of Aᵀ (col, row, value): CscMatrix of Aᵀ is the CSR of A.
    let mut t = Vec::with_capacity(mats.mass.nnz() * 2 + mats.coupling.nnz() * 2 + mats.heat_mass.nnz());
    for (idx, (row, col, _)) in mats.mass.triplets().enumerate() {
        let value = mats.mass.values[idx] / k + mats.viscosity.values[idx] + k * mats.elasticity.values[idx];
        for &(r, a) in vel.row(row) {
            for &(c, b) in vel.row(col) {
                t.push((c, r, a * b * value));
            }
        }
    }
    for (row, q, g) in mats.coupling.triplets() {
        for &(r, a) in vel.row(row) {
            match temp.free[q] {
                Some(c) => {
                    t.push((n_w + c, r, a * g)); // G in the velocity rows
                    t.push((r, n_w + c, -a * g)); // −Gᵀ in the temperature rows
                }
                None => lift[r] += a * g * theta_d[q],
            }
        }
    }
    for (idx, (p, q, _)) in mats.heat_mass.triplets().enumerate() {
        let value = mats.heat_mass.values[idx] / k + mats.conduction.values[idx];
        if let Some(r) = temp.free[p] {
            match temp.free[q] {
                Some(c) => t.push((n_w + c, n_w + r, value)),
                None => lift[n_w + r] += value * theta_d[q],
            }
        }
    }
    let at = CscMatrix::from_triplets(n, n, t);
    Step {
        a: Csr {
            n,
            ptr: at.col_ptr,
            col: at.row_idx,
            val: at.values,
        },
        lift,
        n_w,
        k,
    }
}

impl Step {
    /// `StepSystem::rhs` (A x = b form; the lift of θ_D moved over).
    fn rhs(&self, problem: &Problem, previous: &State, t: f64) -> Vec<f64> {
        let mats = &problem.matrices;
        let mut mech = problem.force(t).expect("force");
        mats.mass.mul_add(1.0 / self.k, &previous.w, &mut mech);
        mats.elasticity.mul_add(-1.0, &previous.u, &mut mech);
        let mut heat = problem.heat_load(t).expect("heat");
        mats.heat_mass.mul_add(1.0 / self.k, &previous.theta, &mut heat);
        let mut rhs = vec![0.0; self.a.n];
        problem.velocity.restrict_add(&mech, &mut rhs[..self.n_w]);
        for (p, free) in problem.temperature.free.iter().enumerate() {
            if let Some(r) = free {
                rhs[self.n_w + r] = heat[p];
            }
        }
        rhs.iter_mut().zip(&self.lift).for_each(|(b, l)| *b -= l);
        rhs
    }

    fn state_from(&self, problem: &Problem, previous: &State, t: f64, x: &[f64]) -> State {
        let w = problem.velocity.prolong(&x[..self.n_w]);
        let u = previous.u.iter().zip(&w).map(|(u, w)| u + self.k * w).collect();
        let theta = problem
            .temperature
            .free
            .iter()
            .zip(&problem.theta_dirichlet)
            .map(|(free, &fixed)| free.map_or(fixed, |r| x[self.n_w + r]))
            .collect();
        State {
            n: previous.n + 1,
            t,
            w,
            u,
            theta,
            xi: previous.xi.clone(),
        }
    }
}

/// K_w padded to 3 unknowns per non-clamped node (a contact node's missing normal unknown becomes
/// an identity row scaled to its diagonal), the padded index of each unknown, and the six
/// rigid-body modes in padded coordinates, orthonormalized.
fn padded_velocity_block(problem: &Problem, kw: &Csr) -> (Csr, Vec<usize>, Vec<Vec<f64>>) {
    let vel = &problem.velocity;
    let coords = &problem.mesh.coords;
    let n_nodes = coords.len();
    let count = |p: usize| {
        let next = if p + 1 < n_nodes {
            vel.unknown(p + 1, 0)
        } else {
            vel.n_free
        };
        next - vel.unknown(p, 0)
    };
    let mut map = vec![0; vel.n_free];
    let mut dummies = Vec::new(); // (padded index, node's first padded index)
    let mut next = 0;
    for p in 0..n_nodes {
        let c = count(p);
        if c == 0 {
            continue;
        }
        for s in 0..3 {
            if s < c {
                map[vel.unknown(p, s)] = next + s;
            } else {
                dummies.push(next + s);
            }
        }
        next += 3;
    }
    let n_padded = next;
    let diag = kw.diagonal();
    let mean = diag.iter().sum::<f64>() / diag.len() as f64;
    let mut t = Vec::with_capacity(kw.nnz() + dummies.len());
    for i in 0..kw.n {
        for q in kw.ptr[i]..kw.ptr[i + 1] {
            t.push((map[kw.col[q]], map[i], kw.val[q]));
        }
    }
    for &d in &dummies {
        t.push((d, d, mean));
    }
    let m = CscMatrix::from_triplets(n_padded, n_padded, t);
    let padded = Csr {
        n: n_padded,
        ptr: m.col_ptr,
        col: m.row_idx,
        val: m.values,
    };
    // Rigid-body modes: 3 translations, 3 rotations about the centroid.
    let centre = coords
        .iter()
        .fold([0.0; 3], |c, x| [c[0] + x[0], c[1] + x[1], c[2] + x[2]]);
    let centre = centre.map(|c| c / n_nodes as f64);
    let mut modes = Vec::new();
    for mode in 0..6 {
        let full: Vec<f64> = coords
            .iter()
            .flat_map(|x| {
                let (dx, dy, dz) = (x[0] - centre[0], x[1] - centre[1], x[2] - centre[2]);
                match mode {
                    0 => [1.0, 0.0, 0.0],
                    1 => [0.0, 1.0, 0.0],
                    2 => [0.0, 0.0, 1.0],
                    3 => [-dy, dx, 0.0],
                    4 => [0.0, -dz, dy],
                    _ => [dz, 0.0, -dx],
                }
            })
            .collect();
        let reduced = vel.restrict_values(&full);
        let mut v = vec![0.0; n_padded];
        for (j, &p) in map.iter().enumerate() {
            v[p] = reduced[j];
        }
        modes.push(v);
    }
    for i in 0..6 {
        for j in 0..i {
            let d = dot(&modes[i], &modes[j]);
            let mj = modes[j].clone();
            modes[i].iter_mut().zip(&mj).for_each(|(a, b)| *a -= d * b);
        }
        let nn = norm(&modes[i]);
        modes[i].iter_mut().for_each(|a| *a /= nn);
    }
    (padded, map, modes)
}

// ---------------------------------------------------------------------------------------------
// Measurement helpers.

fn reset_peak() -> u64 {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    status_kb("VmRSS")
}

fn peak_kb() -> u64 {
    status_kb("VmHWM")
}

fn status_kb(key: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l[key.len() + 1..].trim().trim_end_matches("kB").trim().parse().ok())
        })
        .unwrap_or(0)
}

/// min and median of `reps` runs of f (which returns something to report from the last run).
fn timed<R>(reps: usize, mut f: impl FnMut() -> R) -> (f64, f64, R) {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..reps {
        let clock = Instant::now();
        let r = f();
        times.push(clock.elapsed().as_secs_f64());
        last = Some(r);
    }
    times.sort_by(f64::total_cmp);
    (times[0], times[times.len() / 2], last.expect("at least one run"))
}

/// Setup of a preconditioner: seconds and the peak memory it added (MiB).
fn setup<P>(f: impl FnOnce() -> P) -> (P, f64, f64) {
    let before = reset_peak();
    let clock = Instant::now();
    let p = f();
    let secs = clock.elapsed().as_secs_f64();
    let added = peak_kb().saturating_sub(before) as f64 / 1024.0;
    (p, secs, added)
}

type Solver = fn(&Csr, &dyn Pc, &[f64], f64) -> Outcome;

/// Runs one (matrix, preconditioner, method) on every right-hand side and prints a row per RHS.
fn measure(
    label: &str,
    a: &Csr,
    pc: &dyn Pc,
    method: Solver,
    rhss: &[(&str, Vec<f64>)],
    reps: usize,
    setup_s: f64,
    setup_mb: f64,
) {
    for (name, b) in rhss {
        let (tmin, tmed, out) = timed(reps, || method(a, pc, b, 1e-8));
        let tight = method(a, pc, b, 1e-10);
        println!(
            "ROW | {label:<28} | {name:<6} | setup {setup_s:>7.3} s {setup_mb:>7.0} MiB | it(1e-8) {:>4} | it(1e-10) {:>4} | solve min {tmin:>7.3} med {tmed:>7.3} s | res {:.1e} / {:.1e}",
            out.iterations,
            tight.iterations,
            residual(a, b, &out.x),
            residual(a, b, &tight.x)
        );
        let _ = std::io::stdout().flush();
    }
}

// ---------------------------------------------------------------------------------------------
// PETSc binary export.

fn write_be_i32(w: &mut impl Write, v: i32) {
    w.write_all(&v.to_be_bytes()).expect("write");
}

fn export_mat(path: &str, a: &Csr) {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).expect("create"));
    write_be_i32(&mut w, 1211216);
    write_be_i32(&mut w, a.n as i32);
    write_be_i32(&mut w, a.n as i32);
    write_be_i32(&mut w, a.nnz() as i32);
    for i in 0..a.n {
        write_be_i32(&mut w, (a.ptr[i + 1] - a.ptr[i]) as i32);
    }
    for &c in &a.col {
        write_be_i32(&mut w, c as i32);
    }
    for &v in &a.val {
        w.write_all(&v.to_be_bytes()).expect("write");
    }
}

fn export_vecs(path: &str, vs: &[&[f64]]) {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).expect("create"));
    for v in vs {
        write_be_i32(&mut w, 1211214);
        write_be_i32(&mut w, v.len() as i32);
        for x in v.iter() {
            w.write_all(&x.to_be_bytes()).expect("write");
        }
    }
}

// ---------------------------------------------------------------------------------------------

fn main() -> anyhow::Result<()> {
    let mut overrides: Vec<String> = Vec::new();
    let (mut direct, mut export, mut reps) = (false, None::<String>, 5usize);
    let mut only: Option<String> = None;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--set" => overrides.push(args.next().ok_or_else(|| anyhow::anyhow!("--set needs KEY=VALUE"))?),
            "--direct" => direct = true,
            "--export" => export = args.next(),
            "--reps" => reps = args.next().ok_or_else(|| anyhow::anyhow!("--reps N"))?.parse()?,
            "--only" => only = args.next(),
            other => anyhow::bail!("unknown argument {other}"),
        }
    }
    let wants = |tag: &str| only.as_deref().is_none_or(|o| o.split(',').any(|t| t == tag));
    let scenario = Scenario::load_file(std::path::Path::new("scenarios/paper3d.toml"), &overrides)?;
    let clock = Instant::now();
    let problem = scenario.build()?;
    let k = problem.time_step();
    println!("problem built in {:.2} s, k = {k}", clock.elapsed().as_secs_f64());

    let (step, asm_s, asm_mb) = setup(|| assemble(&problem, k));
    let a = &step.a;
    let n_w = step.n_w;
    let kw = a.block(0..n_w, 0..n_w);
    let kt = a.block(n_w..a.n, n_w..a.n);
    println!(
        "A: {} unknowns ({n_w} velocity + {} temperature), nnz(A) {}, nnz(K_w) {}, nnz(K_θ) {}, assembly {asm_s:.2} s (+{asm_mb:.0} MiB), contact nodes {}, RSS {} MiB",
        a.n,
        a.n - n_w,
        a.nnz(),
        kw.nnz(),
        kt.nnz(),
        problem.contact.len(),
        status_kb("VmRSS") / 1024
    );

    // Right-hand sides. The reference solves of the first four steps: GMRES + ILU(0) to 1e-12.
    let reference = Ilu0::new(a);
    let mut state = State::initial(&problem);
    let rhs1 = step.rhs(&problem, &state, k);
    for s in 1..=4 {
        let t = s as f64 * k;
        let b = step.rhs(&problem, &state, t);
        let out = gmres(a, &reference, &b, 1e-12);
        state = step.state_from(&problem, &state, t, &out.x);
    }
    let rhs5 = step.rhs(&problem, &state, 5.0 * k);
    drop(reference);
    let mut unit = vec![0.0; a.n];
    let middle = &problem.contact[problem.contact.len() / 2];
    unit[middle.tangent_dofs[0].expect("a free tangential unknown")] = 1.0;
    let rhss = vec![("step1", rhs1), ("step5", rhs5), ("unit", unit)];
    let rhss_w: Vec<(&str, Vec<f64>)> = rhss
        .iter()
        .map(|(name, b)| (*name, b[..n_w].to_vec()))
        .filter(|(_, b)| norm(b) > 0.0)
        .collect();

    let (padded, map, modes) = padded_velocity_block(&problem, &kw);

    if let Some(dir) = &export {
        std::fs::create_dir_all(dir)?;
        export_mat(&format!("{dir}/A.bin"), a);
        export_mat(&format!("{dir}/Kw.bin"), &kw);
        export_mat(&format!("{dir}/Kw_padded.bin"), &padded);
        let refs: Vec<&[f64]> = rhss.iter().map(|(_, b)| b.as_slice()).collect();
        export_vecs(&format!("{dir}/rhs.bin"), &refs);
        let refs_w: Vec<&[f64]> = rhss_w.iter().map(|(_, b)| b.as_slice()).collect();
        export_vecs(&format!("{dir}/rhs_w.bin"), &refs_w);
        let padded_rhs: Vec<Vec<f64>> = rhss_w
            .iter()
            .map(|(_, b)| {
                let mut v = vec![0.0; padded.n];
                for (j, &p) in map.iter().enumerate() {
                    v[p] = b[j];
                }
                v
            })
            .collect();
        let refs_p: Vec<&[f64]> = padded_rhs.iter().map(|v| v.as_slice()).collect();
        export_vecs(&format!("{dir}/rhs_w_padded.bin"), &refs_p);
        let refs_m: Vec<&[f64]> = modes.iter().map(|v| v.as_slice()).collect();
        export_vecs(&format!("{dir}/modes.bin"), &refs_m);
        println!("exported to {dir} ({} RHS, {} velocity RHS)", rhss.len(), rhss_w.len());
    }

    // Kernel times: one product with A, one ILU(0) solve with A's factor (min / median of 20).
    if wants("micro") {
        let x = vec![1.0; a.n];
        let mut y = vec![0.0; a.n];
        let (tmin, tmed, _) = timed(20, || a.apply(&x, &mut y));
        println!("KERNEL | y = A x, nnz {} | min {:.4} med {:.4} s", a.nnz(), tmin, tmed);
        // The same product with 32-bit column indices and no bounds checks.
        let col32: Vec<u32> = a.col.iter().map(|&c| c as u32).collect();
        let (tmin, tmed, _) = timed(20, || {
            for (i, yi) in y.iter_mut().enumerate() {
                let (s, e) = (a.ptr[i], a.ptr[i + 1]);
                let mut acc = 0.0;
                for p in s..e {
                    // SAFETY: p < nnz and every column index < n (CSR invariants).
                    unsafe { acc += a.val.get_unchecked(p) * x.get_unchecked(*col32.get_unchecked(p) as usize) };
                }
                *yi = acc;
            }
        });
        println!(
            "KERNEL | y = A x, u32 indices, unchecked | min {:.4} med {:.4} s",
            tmin, tmed
        );
        let ilu = Ilu0::new(a);
        let (tmin, tmed, _) = timed(20, || ilu.apply(&x, &mut y));
        println!(
            "KERNEL | ILU(0) solve with A's factor | min {:.4} med {:.4} s",
            tmin, tmed
        );
        let a32 = Csr32::new(a);
        let (tmin, tmed, _) = timed(20, || a32.apply(&x, &mut y));
        println!(
            "KERNEL | y = A x, u32 indices, 4 partial sums | min {:.4} med {:.4} s",
            tmin, tmed
        );
        let split = Ilu0Split::new(a);
        let (tmin, tmed, _) = timed(20, || split.apply(&x, &mut y));
        println!(
            "KERNEL | ILU(0) solve, L and U split, u32 indices | min {:.4} med {:.4} s",
            tmin, tmed
        );
    }
    // --- Coupled matrix A.
    if wants("jacobi") {
        let (pc, s, mb) = setup(|| Jacobi(a.diagonal()));
        measure("A  GMRES+Jacobi (ours)", a, &pc, gmres, &rhss, reps, s, mb);
    }
    if wants("ilu") {
        let (pc, s, mb) = setup(|| Ilu0::new(a));
        measure("A  GMRES+ILU0 (ours)", a, &pc, gmres, &rhss, reps, s, mb);
        measure("A  BiCGStab+ILU0 (ours)", a, &pc, bicgstab, &rhss, reps, s, mb);
    }
    if wants("ilu-split") {
        let (pc, s, mb) = setup(|| Ilu0Split::new(a));
        measure("A  GMRES+ILU0 split (ours)", a, &pc, gmres, &rhss, reps, s, mb);
    }
    // The crate's own solver (`solver::krylov::IterativeSolver`, GMRES(30) + split ILU(0)), built
    // from S = J A as `StepSystem` stores it.
    if wants("crate") {
        use thermocontact::solver::krylov::{IterativeSolver, KrylovParams, LinearSolver};
        let mut val = a.val.clone();
        for row in n_w..a.n {
            val[a.ptr[row]..a.ptr[row + 1]].iter_mut().for_each(|v| *v = -*v);
        }
        let s_form = CscMatrix {
            n_rows: a.n,
            n_cols: a.n,
            col_ptr: a.ptr.clone(),
            row_idx: a.col.clone(),
            values: val,
        };
        let params = KrylovParams {
            rtol: 1e-8,
            max_iterations: MAX_IT,
            restart: RESTART,
        };
        let (solver, s, mb) = setup(|| IterativeSolver::new(&s_form, n_w, params).expect("setup"));
        for (name, b) in &rhss {
            let (tmin, tmed, (its, x)) = timed(reps, || {
                let mut x = vec![0.0; a.n];
                let info = solver.solve(b, &mut x).expect("solve");
                (info.iterations, x)
            });
            println!(
                "ROW | {:<28} | {name:<6} | setup {s:>7.3} s {mb:>7.0} MiB | it(1e-8) {its:>4} | it(1e-10)    - | solve min {tmin:>7.3} med {tmed:>7.3} s | res {:.1e}",
                "A  solver::krylov (crate)",
                residual(a, b, &x)
            );
        }
    }
    if wants("bilu") {
        let (pcs, s, mb) = setup(|| (Ilu0::new(&kw), Ilu0::new(&kt)));
        let pc = BlockDiag {
            n_w,
            w: &pcs.0,
            theta: &pcs.1,
        };
        measure("A  GMRES+blockILU0 (ours)", a, &pc, gmres, &rhss, reps, s, mb);
    }
    if wants("kryst-ilu") {
        use kryst::context::ksp_context::{KspContext, SolverType};
        use kryst::context::pc_context::PcType;
        use kryst::matrix::op::LinOp;
        let op: Arc<dyn LinOp<S = f64>> = Arc::new(a.to_kryst());
        let (ctx, s, mb) = setup(|| {
            let mut ctx = KspContext::new();
            ctx.set_type(SolverType::Gmres).expect("gmres");
            ctx.set_pc_type(PcType::Ilu0, None).expect("ilu0");
            ctx.set_restart(RESTART);
            ctx.set_pc_side(PcSide::Right);
            ctx.set_tolerances(1e-8, 0.0, 1e30, MAX_IT);
            ctx.try_set_operators(op.clone(), None).expect("operators");
            ctx.setup().expect("kryst setup");
            ctx
        });
        let mut ctx = ctx;
        for (name, b) in &rhss {
            let (tmin, tmed, (its, x)) = timed(reps, || {
                let mut x = vec![0.0; a.n];
                let stats = ctx.solve(b, &mut x).expect("kryst solve");
                (stats.iterations, x)
            });
            println!(
                "ROW | {:<28} | {name:<6} | setup {s:>7.3} s {mb:>7.0} MiB | it(1e-8) {its:>4} | it(1e-10)    - | solve min {tmin:>7.3} med {tmed:>7.3} s | res {:.1e}",
                "A  GMRES+ILU0 (kryst)",
                residual(a, b, &x)
            );
        }
    }

    // kryst's own CG + GAMG (its PETSc-like defaults) through KspContext, on K_w.
    if wants("kryst-gamg") {
        use kryst::context::ksp_context::{KspContext, SolverType};
        use kryst::context::pc_context::PcType;
        use kryst::matrix::op::LinOp;
        let op: Arc<dyn LinOp<S = f64>> = Arc::new(kw.to_kryst());
        let (ctx, s, mb) = setup(|| {
            let mut ctx = KspContext::new();
            ctx.set_type(SolverType::Cg).expect("cg");
            ctx.set_pc_type(PcType::Gamg, None).expect("gamg");
            ctx.set_tolerances(1e-8, 0.0, 1e30, MAX_IT);
            ctx.try_set_operators(op.clone(), None).expect("operators");
            ctx.setup().expect("kryst setup");
            ctx
        });
        let mut ctx = ctx;
        for (name, b) in &rhss_w {
            let (tmin, tmed, (its, x)) = timed(reps, || {
                let mut x = vec![0.0; kw.n];
                let stats = ctx.solve(b, &mut x).expect("kryst solve");
                (stats.iterations, x)
            });
            println!(
                "ROW | {:<28} | {name:<6} | setup {s:>7.3} s {mb:>7.0} MiB | it(1e-8) {its:>4} | it(1e-10)    - | solve min {tmin:>7.3} med {tmed:>7.3} s | res {:.1e}",
                "Kw CG+GAMG (kryst KSP)",
                residual(&kw, b, &x)
            );
        }
    }

    // --- AMG (kryst, smoothed aggregation, nodal bs = 3, rigid-body modes) on K_w.
    let amg = if wants("amg") {
        let op = padded.to_kryst();
        let (amg, s, mb) = setup(|| {
            // KRYST_AMG picks the configuration: "sa" (default: smoothed aggregation, nodal bs 3,
            // rigid-body modes), "sa-scalar" (SA, no nodal/near-nullspace), "classical" (kryst's
            // default BoomerAMG-like HMIS + extended interpolation).
            let variant = std::env::var("KRYST_AMG").unwrap_or_else(|_| "sa".into());
            let mut builder = AMGBuilder::new();
            match variant.as_str() {
                "sa" => {
                    builder = builder
                        .nodal(true, 3)
                        .near_nullspace(modes.clone())
                        .interpolation_type(InterpType::Multipass)
                }
                "sa-scalar" => builder = builder.interpolation_type(InterpType::Multipass),
                _ => {}
            }
            let mut amg = builder
                .relaxation_type(RelaxType::Jacobi)
                .grid_relax_type_all(RelaxType::Jacobi)
                .smoothing_sweeps(1, 1)
                .coarse_threshold(200)
                .max_coarse_size(200)
                .coarse_solve(CoarseSolve::DirectDense)
                .num_grid_sweeps(RelaxPhase::Coarsest, 0)
                .verify_galerkin(false)
                .verify_p_rank(false)
                .build(&faer::Mat::<f64>::zeros(0, 0))
                .expect("AMG build");
            amg.setup(&op).expect("AMG setup");
            amg
        });
        if let Some(stats) = amg.stats() {
            println!(
                "kryst AMG on padded K_w ({} rows): levels {}, operator complexity {:.2}, grid complexity {:.2}",
                padded.n, stats.num_levels, stats.operator_complexity, stats.grid_complexity
            );
            for (level, info) in stats.levels.iter().enumerate() {
                println!("  level {level}: rows {} nnz {}", info.n, info.nnz_a);
            }
        }
        Some((
            PaddedKryst {
                pc: Box::new(amg),
                map: map.clone(),
                n_padded: padded.n,
            },
            s,
            mb,
        ))
    } else {
        None
    };

    // --- Velocity block K_w alone.
    if wants("kw") {
        let (pc, s, mb) = setup(|| Jacobi(kw.diagonal()));
        measure("Kw CG+Jacobi (ours)", &kw, &pc, cg, &rhss_w, reps, s, mb);
        let (pc, s, mb) = setup(|| Ilu0::new(&kw));
        measure("Kw CG+IC0 (ours)", &kw, &pc, cg, &rhss_w, reps, s, mb);
    }
    if let Some((pc, s, mb)) = &amg {
        measure("Kw CG+SA-AMG (kryst)", &kw, pc, cg, &rhss_w, reps, *s, *mb);
        let (ilu_t, s2, mb2) = setup(|| Ilu0::new(&kt));
        let block = BlockDiag {
            n_w,
            w: pc,
            theta: &ilu_t,
        };
        measure(
            "A  GMRES+[AMG,ILU0] (kryst+ours)",
            a,
            &block,
            gmres,
            &rhss,
            reps,
            s + s2,
            mb + mb2,
        );
    }

    // --- Today's direct path: StepSystem (faer LDLᵀ, contact unknowns last).
    if direct {
        let (system, s, mb) = setup(|| StepSystem::with_step(&problem, k).expect("factor"));
        let b_s: Vec<Vec<f64>> = rhss.iter().map(|(_, b)| b.clone()).collect();
        for ((name, _), b) in rhss.iter().zip(&b_s) {
            let (tmin, tmed, x) = timed(reps, || {
                let mut x = b.clone();
                system.solve_in_place(&mut x).expect("solve");
                x
            });
            println!(
                "ROW | {:<28} | {name:<6} | setup {s:>7.3} s {mb:>7.0} MiB | nnz(L) {} | solve min {tmin:>7.3} med {tmed:>7.3} s | res {:.1e}",
                "A  direct LDLT (faer, today)",
                system.factor_nnz(),
                residual(a, b, &x)
            );
        }
    }
    println!("peak RSS {} MiB", peak_kb() / 1024);
    Ok(())
}
