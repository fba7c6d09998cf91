//! The error norms of the estimate (73) of Corollary 16,
//!
//! ```text
//! max_{1≤n≤N} { ‖u_n − u_n^{hk}‖_E + ‖w_n − w_n^{hk}‖_H + ‖θ_n − θ_n^{hk}‖_L²(Ω) + k Σ_{j≤n} ‖θ_j − θ_j^{hk}‖²_V } ≤ c(h + k),
//! ```
//!
//! with ‖v‖_E = ‖ε(v)‖_L², ‖·‖_H = ‖·‖_L²(Ω;ℝ^d) and ‖η‖_V = ‖∇η‖_L². Two ways to measure them:
//!
//! * against a finer discrete solution (self-convergence, Fig. 4): the coarse fields are
//!   prolonged exactly ([`super::nested`]) and the differences measured on the fine mesh —
//!   ‖ε(u)‖ and ‖∇θ‖ by sums over its cells, the L² norms by its consistent masses divided by ρ
//!   and ρc_p — which is exact for P1 fields;
//! * against an exact solution ([`ExactSolution`]): the true error, integrated on every cell with
//!   the degree-5 rule of [`super::quadrature`] (ε(u^{hk}) and ∇θ^{hk} are constant per cell).
//!
//! [`ErrorHistory`] collects the per-time-level errors into the norms of (73). The last term of
//! (73) is a square, (k Σ ‖·‖²_V); we report its square root, the discrete L²(0, T; V) norm, so
//! that every reported error scales like c(h + k) when (73) holds.

use serde::Serialize;

use super::quadrature::for_each_cell_point;
use crate::model::Problem;
use crate::model::State;

/// The errors of one time level.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct LevelErrors {
    /// ‖u_n − u_n^{hk}‖_E.
    pub u_energy: f64,
    /// ‖w_n − w_n^{hk}‖_L².
    pub w_l2: f64,
    /// ‖θ_n − θ_n^{hk}‖_L².
    pub theta_l2: f64,
    /// ‖θ_n − θ_n^{hk}‖_V = ‖∇(θ_n − θ_n^{hk})‖_L².
    pub theta_v: f64,
}

/// Errors between two discrete states on the same mesh (the coarse one already prolonged):
/// exact norms of P1 fields on the mesh of `problem` (cell sums, and its mass matrices). The L² norms divide ℳ and
/// ℳ_θ by the body's ρ and ρ c_p: exact for a body of one material (the verification family's);
/// with cell regions of other densities they are weighted by ρ_cell/ρ.
pub fn discrete_errors(problem: &Problem, u: &[f64], w: &[f64], theta: &[f64], reference: &State) -> LevelErrors {
    let m = &problem.matrices;
    let diff = |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x - y).collect() };
    let (du, dw, dtheta) = (
        diff(u, &reference.u),
        diff(w, &reference.w),
        diff(theta, &reference.theta),
    );
    let rho = problem.material.density;
    let rho_cp = rho * problem.material.heat_capacity;
    LevelErrors {
        u_energy: crate::model::norms::energy(&problem.mesh, &du),
        w_l2: (m.mass.quadratic_form(&dw) / rho).max(0.0).sqrt(),
        theta_l2: (m.heat_mass.quadratic_form(&dtheta) / rho_cp).max(0.0).sqrt(),
        theta_v: crate::model::norms::gradient(&problem.mesh, &dtheta),
    }
}

/// An exact solution's fields at one point and time, as the error norms need them.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ExactFields {
    /// u.
    pub u: [f64; 2],
    /// ∂_j u_i at `[i][j]`.
    pub grad_u: [[f64; 2]; 2],
    /// w = u̇.
    pub w: [f64; 2],
    /// θ.
    pub theta: f64,
    /// ∇θ.
    pub grad_theta: [f64; 2],
}

/// A solution (u, θ) known in closed form (2D).
pub trait ExactSolution: Sync {
    /// The fields at x and t.
    fn fields(&self, x: [f64; 3], t: f64) -> ExactFields;
}

/// The true errors of a discrete state against an exact solution at time t: each norm is the
/// square root of Σ_T ∫_T |·|², integrated with the degree-5 rule.
pub fn exact_errors(problem: &Problem, state: &State, exact: &dyn ExactSolution, t: f64) -> LevelErrors {
    let mesh = &problem.mesh;
    let mut sums = [0.0; 4];
    let mut cell = usize::MAX;
    let (mut strain_h, mut grad_theta_h) = ([[0.0; 2]; 2], [0.0; 2]);
    for_each_cell_point(mesh, |e, simplex, point| {
        let nodes = mesh.cell(e);
        if e != cell {
            // ε(u^{hk}) and ∇θ^{hk} are constant on the cell.
            cell = e;
            strain_h = [[0.0; 2]; 2];
            grad_theta_h = [0.0; 2];
            for (a, &p) in nodes.iter().enumerate() {
                let g = simplex.grads[a];
                for i in 0..2 {
                    for j in 0..2 {
                        strain_h[i][j] += 0.5 * (state.u[p * 2 + i] * g[j] + state.u[p * 2 + j] * g[i]);
                    }
                    grad_theta_h[i] += state.theta[p] * g[i];
                }
            }
        }
        let value = |field: &[f64], components: usize, c: usize| -> f64 {
            nodes
                .iter()
                .enumerate()
                .map(|(a, &p)| point.basis[a] * field[p * components + c])
                .sum()
        };
        let f = exact.fields(point.x, t);
        let mut strain = 0.0;
        for i in 0..2 {
            for j in 0..2 {
                let exact_strain = 0.5 * (f.grad_u[i][j] + f.grad_u[j][i]);
                strain += (exact_strain - strain_h[i][j]).powi(2);
            }
        }
        let velocity: f64 = (0..2).map(|c| (f.w[c] - value(&state.w, 2, c)).powi(2)).sum();
        let theta = (f.theta - value(&state.theta, 1, 0)).powi(2);
        let gradient: f64 = (0..2).map(|i| (f.grad_theta[i] - grad_theta_h[i]).powi(2)).sum();
        for (sum, v) in sums.iter_mut().zip([strain, velocity, theta, gradient]) {
            *sum += point.weight * v;
        }
    });
    LevelErrors {
        u_energy: sums[0].sqrt(),
        w_l2: sums[1].sqrt(),
        theta_l2: sums[2].sqrt(),
        theta_v: sums[3].sqrt(),
    }
}

/// The norms of (73) over a run, and Fig. 4's error at t = T.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ErrorNorms {
    /// max_n ‖u_n − u_n^{hk}‖_E.
    pub u_energy_max: f64,
    /// max_n ‖w_n − w_n^{hk}‖_L².
    pub w_l2_max: f64,
    /// max_n ‖θ_n − θ_n^{hk}‖_L².
    pub theta_l2_max: f64,
    /// (k Σ_n ‖θ_n − θ_n^{hk}‖²_V)^{1/2}: the discrete L²(0, T; V) error.
    pub theta_l2_v: f64,
    /// The left side of (73) with the square root on its last term: max_n of the sum.
    pub estimate_73: f64,
    /// ‖u(T) − u_N^{hk}‖_E: the quantity of Fig. 4.
    pub u_energy_final: f64,
}

impl ErrorNorms {
    /// The norms as (name, value) pairs, in table order.
    pub fn entries(&self) -> [(&'static str, f64); 6] {
        [
            ("u_energy_final", self.u_energy_final),
            ("u_energy_max", self.u_energy_max),
            ("w_l2_max", self.w_l2_max),
            ("theta_l2_max", self.theta_l2_max),
            ("theta_l2_v", self.theta_l2_v),
            ("estimate_73", self.estimate_73),
        ]
    }

    /// Observed orders p = log(e_coarse / e_fine) / log(h_coarse / h_fine), norm by norm.
    pub fn rates(coarse: &ErrorNorms, fine: &ErrorNorms, h_ratio: f64) -> ErrorNorms {
        let rate = |a: f64, b: f64| (a / b).ln() / h_ratio.ln();
        ErrorNorms {
            u_energy_max: rate(coarse.u_energy_max, fine.u_energy_max),
            w_l2_max: rate(coarse.w_l2_max, fine.w_l2_max),
            theta_l2_max: rate(coarse.theta_l2_max, fine.theta_l2_max),
            theta_l2_v: rate(coarse.theta_l2_v, fine.theta_l2_v),
            estimate_73: rate(coarse.estimate_73, fine.estimate_73),
            u_energy_final: rate(coarse.u_energy_final, fine.u_energy_final),
        }
    }
}

/// Accumulates the errors of the time levels t_n (n = 1, 2, …, in order) of a level with step k.
#[derive(Debug, Clone, Default)]
pub struct ErrorHistory {
    k: f64,
    theta_v_squared: f64,
    norms: ErrorNorms,
    levels: usize,
}

impl ErrorHistory {
    /// An empty history for time step k.
    pub fn new(k: f64) -> Self {
        ErrorHistory {
            k,
            ..Default::default()
        }
    }

    /// Adds the errors of the next time level.
    pub fn push(&mut self, e: &LevelErrors) {
        let n = &mut self.norms;
        self.theta_v_squared += self.k * e.theta_v * e.theta_v;
        n.u_energy_max = n.u_energy_max.max(e.u_energy);
        n.w_l2_max = n.w_l2_max.max(e.w_l2);
        n.theta_l2_max = n.theta_l2_max.max(e.theta_l2);
        n.theta_l2_v = self.theta_v_squared.sqrt();
        n.estimate_73 = n
            .estimate_73
            .max(e.u_energy + e.w_l2 + e.theta_l2 + self.theta_v_squared.sqrt());
        n.u_energy_final = e.u_energy;
        self.levels += 1;
    }

    /// Number of time levels pushed.
    pub fn len(&self) -> usize {
        self.levels
    }

    /// No time level pushed yet.
    pub fn is_empty(&self) -> bool {
        self.levels == 0
    }

    /// The norms of (73) so far (`u_energy_final` is the last level's).
    pub fn norms(&self) -> ErrorNorms {
        self.norms
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn history_takes_maxima_and_the_discrete_l2_in_time() {
        let mut h = ErrorHistory::new(0.5);
        let e = |u, w, th, v| LevelErrors {
            u_energy: u,
            w_l2: w,
            theta_l2: th,
            theta_v: v,
        };
        h.push(&e(1.0, 4.0, 0.5, 2.0));
        h.push(&e(3.0, 1.0, 0.25, 2.0));
        let n = h.norms();
        assert_eq!((n.u_energy_max, n.w_l2_max, n.theta_l2_max), (3.0, 4.0, 0.5));
        assert!((n.theta_l2_v - 2.0).abs() < 1e-15); // (0.5·4 + 0.5·4)^{1/2}
        assert_eq!(n.u_energy_final, 3.0);
        // max(1 + 4 + 0.5 + √2, 3 + 1 + 0.25 + 2)
        assert!((n.estimate_73 - (5.5 + 2f64.sqrt())).abs() < 1e-15);
        let halved = ErrorNorms {
            u_energy_final: 1.5,
            ..n
        };
        assert!((ErrorNorms::rates(&n, &halved, 2.0).u_energy_final - 1.0).abs() < 1e-15);
    }
}
