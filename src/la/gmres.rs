//! Restarted GMRES, right-preconditioned, over any [`Preconditioner`].
//!
//! The step matrix A = [[ℳ/k + 𝒦_A + k𝒦_B, G], [−Gᵀ, ℳ_θ/k + 𝒦_θ]] is not symmetric, but its
//! symmetric part is block-diagonal with SPD blocks (A is positive real), so GMRES converges and
//! ILU(0) needs no pivoting. Why this pair and when it pays (the study that chose it):
//! docs/krylov-study.md. In short: at the paper's time step (k = 1/64) the mass term dominates
//! and GMRES + ILU(0) needs 5–7 iterations at 10⁵–10⁶ unknowns; the iteration count grows with
//! k (≈ 20 at k = 1/8), where an AMG coarse correction of the velocities keeps it bounded
//! (`crate::step`'s iterative back-end builds it on [`super::petsc`]).
//!
//! **The residual after a cycle.** x moves by M⁻¹V_j y, so the residual moves by A M⁻¹ V_j y =
//! V_{j+1} H̄ y (the Arnoldi relation, which holds to rounding whatever the basis's
//! orthogonality), and r − V_{j+1} H̄ y = V_{j+1} Qᵀ (0, …, 0, g_j) with the Givens rotations Q
//! undone on the last entry of the rotated right-hand side g: j + 1 vector updates instead of
//! a product with A, the most expensive part of an iteration (12 bytes per matrix entry against
//! the ILU(0) sweeps' 8). A solve that takes j iterations then costs j products instead of
//! j + 1. The residual so updated differs from b − A x by rounding only, and the next solve of
//! a Newton iteration starts from it (its changed rows recomputed, `crate::step`); each step's
//! first solve computes it. Measured at 972k unknowns (the 3D example on the iterative path, 4
//! steps, 303 Krylov iterations in 64 solves, 2026-11-28, three interleaved pairs): the solves
//! 11.0–11.9 s → 10.3–11.5 s; the same iterations at every step, fields within 2·10⁻¹³ of the
//! product's (16 steps of the 3D example), and the same hard case (47k unknowns, k = 1/8: the
//! same 646 Newton and 7 306 Krylov iterations, the same step finished by Newton on the law).
//!
//! **Inexact solves.** [`Gmres::solve_inexact`] also stops at a fraction η (the forcing term) of
//! the residual it starts from: a Newton iteration's correction solved as far as the Newton
//! residual it starts from warrants (`crate::step`'s Newton–Krylov solver, whose header has the
//! measurements).

use super::error::LaError as Error;
use super::sparse::CsrMatrix;
use super::vector::{par_axpy as axpy, par_dot as dot, par_norm as norm};

/// Tolerance and caps of a GMRES solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresParams {
    /// Stop when ‖b − A x‖ ≤ rtol ‖b‖ (the unpreconditioned residual, carried through each
    /// cycle by the Arnoldi relation, as the module header of `la::gmres` derives).
    pub rtol: f64,
    /// Iteration cap (products with A).
    pub max_iterations: usize,
    /// Restart length.
    pub restart: usize,
}

impl Default for GmresParams {
    fn default() -> Self {
        GmresParams {
            rtol: 1e-10,
            max_iterations: 500,
            restart: 30,
        }
    }
}

/// What a solve did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveInfo {
    /// Krylov iterations.
    pub iterations: usize,
    /// ‖b − A x‖ / ‖b‖ at the end as the method estimates it.
    pub residual: f64,
}

/// A fixed linear approximation M⁻¹ of A⁻¹ for right-preconditioned GMRES.
pub trait Preconditioner {
    /// z = M⁻¹ r, every entry of z written (GMRES hands it a vector of an earlier solve).
    fn apply(&self, r: &[f64], z: &mut [f64]) -> Result<(), Error>;

    /// The method's name with this preconditioner, for the error of a solve that fails.
    fn method(&self) -> &'static str;
}

/// Restarted GMRES(m), right-preconditioned (so its residual estimate is the unpreconditioned
/// residual's), modified Gram–Schmidt, Givens rotations. `x` holds the initial guess.
///
/// Fails with [`Error::KrylovNotConverged`] (with the residual history) at the iteration cap.
/// A caller that solves again and again keeps a [`Gmres`] instead (its vectors are kept).
pub fn gmres(
    a: &CsrMatrix,
    pc: &dyn Preconditioner,
    b: &[f64],
    x: &mut [f64],
    params: &GmresParams,
) -> Result<SolveInfo, Error> {
    Gmres::new(*params).solve(a, pc, b, x, &mut Vec::new())
}

/// Restarted GMRES(m) with its Krylov basis and preconditioned directions kept from one solve to
/// the next (as a PETSc `KSP` keeps its work vectors).
///
/// **Why keep them.** A solve of N unknowns that takes j iterations needs 2j + 2 vectors of N.
/// Allocated afresh for each solve, each is new memory that the kernel maps and zeroes page by
/// page on first touch (glibc gives a freed block of megabytes back to the system), and the
/// kernel's page clearing was the largest single symbol in the profile of a run at 972k
/// unknowns. Kept, a vector is allocated the first time a solve reaches its iteration and
/// reused after; [`Gmres::release`] gives them back between bursts of solves (the step solvers
/// of `crate::step` give them back whenever a step ends, so that they are not held while its output is
/// written). The 3D example at 972k unknowns on the iterative path, 4 steps (64 solves),
/// 2026-11-27, three interleaved pairs: 1.87 M → 0.89 M page faults, time stepping 14.6–15.8 s
/// → 12.7–13.2 s, the same bits, the same peak memory with frames off (+1 % with them).
#[derive(Debug, Clone)]
pub struct Gmres {
    params: GmresParams,
    /// v_0 … v_j: the orthonormal Krylov basis of the current cycle.
    basis: Vec<Vec<f64>>,
    /// M⁻¹ v_j, kept for the update: x += Σ y_j M⁻¹ v_j costs no further sweep of the factor
    /// (the sweeps are the sequential part of an iteration).
    directions: Vec<Vec<f64>>,
    /// A M⁻¹ v_j, and A x of the initial guess where no residual is given.
    product: Vec<f64>,
}

impl Gmres {
    /// A solver with these tolerance and caps and no vectors yet.
    pub fn new(params: GmresParams) -> Self {
        Gmres {
            params,
            basis: Vec::new(),
            directions: Vec::new(),
            product: Vec::new(),
        }
    }

    /// Gives the kept vectors' memory back (the next solve allocates them again): for a caller
    /// that solves in bursts, between them.
    pub fn release(&mut self) {
        self.basis = Vec::new();
        self.directions = Vec::new();
        self.product = Vec::new();
    }

    /// Solves A x = b from x, with the residual r = b − A x of the initial guess given (when `r`
    /// has A's size; otherwise it is computed), and left in `r` for the solution it returns: a
    /// caller whose next system differs from this one in a few rows updates those rows of r
    /// instead of a product with A (the Newton linearizations of `crate::step`).
    pub fn solve(
        &mut self,
        a: &CsrMatrix,
        pc: &dyn Preconditioner,
        b: &[f64],
        x: &mut [f64],
        r: &mut Vec<f64>,
    ) -> Result<SolveInfo, Error> {
        self.solve_inexact(a, pc, b, x, r, 0.0)
    }

    /// [`Gmres::solve`] for a Newton iteration's correction: it also stops once
    /// ‖b − A x‖ ≤ `forcing` ‖b − A x₀‖ (x₀ the guess it starts from), whichever of that and
    /// rtol ‖b‖ is looser: an inexact Newton method's forcing term η (Eisenstat and Walker,
    /// SIAM J. Sci. Comput. 17, 1996). Where the guess is the last Newton iterate and `r` its
    /// carried residual, ‖b − A x₀‖ is the nonlinear residual there, so the solves are loose
    /// while it is large and tight (rtol) as the iterations converge. `forcing = 0`: `solve`.
    pub fn solve_inexact(
        &mut self,
        a: &CsrMatrix,
        pc: &dyn Preconditioner,
        b: &[f64],
        x: &mut [f64],
        r: &mut Vec<f64>,
        forcing: f64,
    ) -> Result<SolveInfo, Error> {
        let params = self.params;
        let n = a.n();
        let m = params.restart.max(1);
        let Gmres {
            basis,
            directions,
            product: w,
            ..
        } = self;
        w.resize(n, 0.0);
        if r.len() != n {
            a.mul(x, w);
            r.clear();
            r.extend(b.iter().zip(w.iter()).map(|(b, ax)| b - ax));
        }
        let bnorm = norm(b);
        if bnorm == 0.0 {
            x.fill(0.0);
            r.fill(0.0);
            return Ok(SolveInfo::default());
        }
        let mut target = params.rtol * bnorm;
        if forcing > 0.0 {
            target = target.max(forcing * norm(r));
        }
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
            set_scaled(vector(basis, 0, n), r, beta);
            let mut h = vec![vec![0.0; m]; m + 1];
            let (mut cs, mut sn) = (vec![0.0; m], vec![0.0; m]);
            let mut g = vec![0.0; m + 1];
            g[0] = beta;
            let mut used = 0;
            for j in 0..m {
                let z = vector(directions, j, n);
                pc.apply(&basis[j], z)?;
                a.mul(z, w);
                for (i, vi) in basis[..=j].iter().enumerate() {
                    let hij = dot(w, vi);
                    h[i][j] = hij;
                    axpy(-hij, vi, w);
                }
                let hn = norm(w);
                h[j + 1][j] = hn;
                set_scaled(vector(basis, j + 1, n), w, hn);
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
            for (zj, yj) in directions.iter().zip(&y) {
                axpy(*yj, zj, x);
            }
            // r − A M⁻¹ V y = V_{j+1} Qᵀ (0, …, 0, g_j): the rotations undone on the last
            // entry of g ([module docs](self)).
            let mut c = vec![0.0; used + 1];
            c[used] = g[used];
            for i in (0..used).rev() {
                let (ci, cj) = (c[i], c[i + 1]);
                c[i] = cs[i] * ci - sn[i] * cj;
                c[i + 1] = sn[i] * ci + cs[i] * cj;
            }
            r.iter_mut().zip(&basis[0]).for_each(|(r, v)| *r = c[0] * v);
            for (ci, vi) in c.iter().zip(&basis[..=used]).skip(1) {
                axpy(*ci, vi, r);
            }
        }
    }
}

/// The `j`-th of the kept vectors, made (of length n) the first time it is needed.
fn vector(kept: &mut Vec<Vec<f64>>, j: usize, n: usize) -> &mut Vec<f64> {
    if kept.len() <= j {
        kept.resize_with(j + 1, Vec::new);
    }
    let v = &mut kept[j];
    v.resize(n, 0.0);
    v
}

/// out = v / s (0 where s = 0).
fn set_scaled(out: &mut [f64], v: &[f64], s: f64) {
    out.iter_mut()
        .zip(v)
        .for_each(|(o, v)| *o = if s > 0.0 { v / s } else { 0.0 });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::la::ilu::tests::two_domains;
    use crate::la::ilu::Ilu0;

    /// No preconditioner: GMRES then takes several cycles on [`two_domains`].
    struct Unpreconditioned;

    impl Preconditioner for Unpreconditioned {
        fn apply(&self, r: &[f64], z: &mut [f64]) -> Result<(), Error> {
            z.copy_from_slice(r);
            Ok(())
        }

        fn method(&self) -> &'static str {
            "GMRES"
        }
    }

    /// b − A x.
    fn b_minus_a_x(a: &CsrMatrix, b: &[f64], x: &[f64]) -> Vec<f64> {
        let mut ax = vec![0.0; b.len()];
        a.mul(x, &mut ax);
        b.iter().zip(&ax).map(|(b, ax)| b - ax).collect()
    }

    /// Tolerance 10⁻¹² of ‖b‖, at most 100 iterations, restarted every `restart`.
    fn tight(restart: usize) -> GmresParams {
        GmresParams {
            rtol: 1e-12,
            max_iterations: 100,
            restart,
        }
    }

    /// A right-hand side of [`two_domains`]'s size with no zero entry.
    fn smooth_rhs() -> Vec<f64> {
        (0..10).map(|i| (i as f64 * 1.3).sin() + 0.5).collect()
    }

    /// A solver that keeps its vectors gives, solve after solve, the bits of a fresh one: after
    /// a long solve (its kept basis longer than the next needs), from a warm start with the
    /// residual given, and after its vectors are given back.
    #[test]
    fn kept_vectors_give_a_fresh_solvers_bits() {
        let a = two_domains();
        let params = tight(4);
        let rough = |seed: usize| -> Vec<f64> { (0..10).map(|i| ((i * 7 + seed * 3) % 11) as f64 - 5.0).collect() };
        let mut kept = Gmres::new(params);
        let mut x = vec![0.0; 10];
        let mut fresh_x = x.clone();
        let mut lengths = Vec::new();
        // b changed in one entry after a solve: the warm start takes fewer iterations.
        for (seed, nudge, release) in [(1, 0.0, false), (1, 1e-9, false), (3, 0.0, true), (3, 1e-9, false)] {
            let mut b = rough(seed);
            b[9] += nudge;
            // The residual of the warm start, given as a caller carrying it would.
            let mut r = b_minus_a_x(&a, &b, &x);
            let info = kept.solve(&a, &Unpreconditioned, &b, &mut x, &mut r).unwrap();
            let fresh = gmres(&a, &Unpreconditioned, &b, &mut fresh_x, &params).unwrap();
            assert_eq!(info, fresh, "seed {seed}");
            assert_eq!(x, fresh_x, "seed {seed}");
            lengths.push((info.iterations, kept.basis.len()));
            if release {
                kept.release();
                assert!(kept.basis.is_empty() && kept.directions.is_empty());
            }
        }
        // More than one cycle from zero, and a basis kept that is longer than a later solve's.
        assert!(lengths[0].0 > params.restart, "{lengths:?}");
        assert!(lengths.iter().any(|&(its, kept)| its + 1 < kept), "{lengths:?}");
    }

    /// The residual left in r, carried through each cycle by the Arnoldi relation, is b − A x
    /// to rounding: over several restarts from zero, and from a warm start with its residual
    /// given.
    #[test]
    fn the_residual_left_is_b_minus_a_x() {
        let a = two_domains();
        let mut solver = Gmres::new(tight(3));
        let true_residual = |b: &[f64], x: &[f64]| b_minus_a_x(&a, b, x);
        let b = smooth_rhs();
        let (mut x, mut r) = (vec![0.0; 10], Vec::new());
        let info = solver.solve(&a, &Unpreconditioned, &b, &mut x, &mut r).unwrap();
        assert!(info.iterations > 3, "more than one cycle: {info:?}");
        let scale = norm(&b);
        let gap = |r: &[f64], t: &[f64]| r.iter().zip(t).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
        assert!(gap(&r, &true_residual(&b, &x)) <= 1e-14 * scale);
        // A changed right-hand side: its residual updated by the caller, then solved from x.
        let b2: Vec<f64> = b.iter().enumerate().map(|(i, v)| v + 0.1 * i as f64).collect();
        r = true_residual(&b2, &x);
        solver.solve(&a, &Unpreconditioned, &b2, &mut x, &mut r).unwrap();
        assert!(gap(&r, &true_residual(&b2, &x)) <= 1e-14 * scale);
        assert!(norm(&true_residual(&b2, &x)) <= 1e-12 * norm(&b2) * (1.0 + 1e-6));
    }

    /// An inexact Newton iteration's solve: from a warm start whose residual is r₀, forcing η
    /// stops it at ‖b − A x‖ ≤ η ‖r₀‖ (not tighter than it needs: above rtol ‖b‖, in fewer
    /// iterations than the solve to rtol), and the residual it leaves is still b − A x; where
    /// η ‖r₀‖ is below rtol ‖b‖, rtol decides and the solve is `solve`'s, bit for bit.
    #[test]
    fn the_forcing_term_stops_a_solve_at_its_fraction_of_the_starting_residual() {
        let a = two_domains();
        let params = tight(30);
        let true_residual = |b: &[f64], x: &[f64]| b_minus_a_x(&a, b, x);
        let b = smooth_rhs();
        let start: Vec<f64> = (0..10).map(|i| 0.1 * (i as f64 * 0.7).cos()).collect();
        let r0 = true_residual(&b, &start);
        let solve = |forcing: f64| {
            let (mut x, mut r) = (start.clone(), r0.clone());
            let info = Gmres::new(params)
                .solve_inexact(&a, &Unpreconditioned, &b, &mut x, &mut r, forcing)
                .unwrap();
            (info, x, r)
        };
        let (exact, x_exact, _) = solve(0.0);
        let (loose, x, r) = solve(0.1);
        let reached = norm(&true_residual(&b, &x));
        assert!(
            reached <= 0.1 * norm(&r0) * (1.0 + 1e-9),
            "{reached:e} against {:e}",
            norm(&r0)
        );
        assert!(
            reached > 1e3 * params.rtol * norm(&b),
            "stopped by the forcing term: {reached:e}"
        );
        assert!(loose.iterations < exact.iterations, "{loose:?} {exact:?}");
        let gap = r
            .iter()
            .zip(&true_residual(&b, &x))
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
        assert!(gap <= 1e-14 * norm(&b));
        // η ‖r₀‖ below rtol ‖b‖: the solve to rtol.
        let (tiny, x_tiny, _) = solve(1e-14);
        assert_eq!((tiny, x_tiny), (exact, x_exact));
    }

    #[test]
    fn a_capped_solve_is_a_typed_error_with_its_history() {
        let a = two_domains();
        let ilu = Ilu0::new(&a).unwrap();
        let params = GmresParams {
            rtol: 1e-300,
            max_iterations: 2,
            restart: 1,
        };
        let mut x = vec![0.0; 10];
        match gmres(&a, &ilu, &[1.0; 10], &mut x, &params) {
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
