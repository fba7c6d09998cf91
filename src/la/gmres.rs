//! Restarted GMRES, right-preconditioned, over any [`Preconditioner`].
//!
//! The step matrix A = [[ℳ/k + 𝒦_A + k𝒦_B, G], [−Gᵀ, ℳ_θ/k + 𝒦_θ]] is not symmetric, but its
//! symmetric part is block-diagonal with SPD blocks (A is positive real), so GMRES converges and
//! ILU(0) needs no pivoting. Why this pair and when it pays (the study that chose it):
//! docs/krylov-study.md. In short: at the paper's time step (k = 1/64) the mass term dominates
//! and GMRES + ILU(0) needs 5–7 iterations at 10⁵–10⁶ unknowns; the iteration count grows with
//! k (≈ 20 at k = 1/8), where an AMG coarse correction of the velocities keeps it bounded
//! (`crate::step`'s iterative back-end builds it on [`super::petsc`]).

use super::error::LaError as Error;
use super::sparse::CsrMatrix;
use super::vector::{par_axpy as axpy, par_dot as dot, par_norm as norm};

/// Tolerance and caps of a GMRES solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresParams {
    /// Stop when ‖b − A x‖ ≤ rtol ‖b‖ (the true, unpreconditioned residual).
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
    /// z = M⁻¹ r.
    fn apply(&self, r: &[f64], z: &mut [f64]) -> Result<(), Error>;

    /// The method's name with this preconditioner, for the error of a solve that fails.
    fn method(&self) -> &'static str;
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
    params: &GmresParams,
) -> Result<SolveInfo, Error> {
    let mut r = Vec::new();
    gmres_from_residual(a, pc, b, x, &mut r, params)
}

/// [`gmres`] with the residual r = b − A x of the initial guess given (when `r` has A's size;
/// otherwise it is computed), and left in `r` for the solution it returns: a caller whose next
/// system differs from this one in a few rows updates those rows of r instead of a product
/// with A (the Newton linearizations of `crate::step`).
pub fn gmres_from_residual(
    a: &CsrMatrix,
    pc: &dyn Preconditioner,
    b: &[f64],
    x: &mut [f64],
    r: &mut Vec<f64>,
    params: &GmresParams,
) -> Result<SolveInfo, Error> {
    let n = a.n();
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::la::ilu::tests::two_domains;
    use crate::la::ilu::Ilu0;

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
