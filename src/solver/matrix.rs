//! The linear part of one time step of Problem 14: the step matrix and its right-hand side,
//! shared by the direct path ([`super::system::StepSystem`], which factors it) and the iterative
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

use crate::error::Error;
use crate::fem::sparse::CscMatrix;
use crate::problem::Problem;

use super::system::State;

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
    /// Contributions of θ_D to the right-hand side (moved over from the matrix).
    lift: Vec<f64>,
    n_w: usize,
    k: f64,
}

impl StepMatrix {
    /// Assembles the reduced step matrix for a step size k.
    pub fn assemble(problem: &Problem, k: f64) -> Self {
        let (vel, temp) = (&problem.velocity, &problem.temperature);
        let n_w = vel.n_free;
        let n = n_w + temp.n_free;
        let mats = &problem.matrices;
        let theta_d = &problem.theta_dirichlet;
        let mut lift = vec![0.0; n];
        let mut triplets = Vec::with_capacity(mats.mass.nnz() * 2 + mats.coupling.nnz() * 2 + mats.heat_mass.nnz());

        // Mechanical block ℳ/k + 𝒦_A + k𝒦_B (the three share one pattern).
        for (idx, (row, col, _)) in mats.mass.triplets().enumerate() {
            let value = mats.mass.values[idx] / k + mats.viscosity.values[idx] + k * mats.elasticity.values[idx];
            for &(r, a) in vel.row(row) {
                for &(c, b) in vel.row(col) {
                    triplets.push((r, c, a * b * value));
                }
            }
        }
        // Coupling G and −Gᵀ.
        for (row, q, g) in mats.coupling.triplets() {
            for &(r, a) in vel.row(row) {
                match temp.free[q] {
                    Some(c) => {
                        // G in the velocity rows; −(−Gᵀ) = Gᵀ in the (negated) temperature rows.
                        triplets.push((r, n_w + c, a * g));
                        triplets.push((n_w + c, r, a * g));
                    }
                    None => lift[r] += a * g * theta_d[q],
                }
            }
        }
        // Thermal block ℳ_θ/k + 𝒦_θ.
        for (idx, (p, q, _)) in mats.heat_mass.triplets().enumerate() {
            let value = mats.heat_mass.values[idx] / k + mats.conduction.values[idx];
            if let Some(r) = temp.free[p] {
                match temp.free[q] {
                    Some(c) => triplets.push((n_w + r, n_w + c, -value)),
                    None => lift[n_w + r] += value * theta_d[q],
                }
            }
        }
        let matrix = CscMatrix::from_triplets(n, n, triplets);
        StepMatrix {
            matrix,
            rhs: StepRhs { lift, n_w, k },
        }
    }
}

impl StepRhs {
    /// The step size k the matrix was made for.
    pub fn step_size(&self) -> f64 {
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
    /// (ℳW_{n−1}/k − 𝒦_B U_{n−1} + F_n, ℳ_θΘ_{n−1}/k + G_n) seen by the unknowns.
    pub fn rhs(&self, problem: &Problem, previous: &State, t: f64) -> Result<Vec<f64>, Error> {
        let mats = &problem.matrices;
        let mut mech = problem.force(t)?;
        mats.mass.mul_add(1.0 / self.k, &previous.w, &mut mech);
        mats.elasticity.mul_add(-1.0, &previous.u, &mut mech);
        let mut heat = problem.heat_load(t)?;
        mats.heat_mass.mul_add(1.0 / self.k, &previous.theta, &mut heat);

        let mut rhs = vec![0.0; self.n_unknowns()];
        problem.velocity.restrict_add(&mech, &mut rhs[..self.n_w]);
        for (p, free) in problem.temperature.free.iter().enumerate() {
            if let Some(r) = free {
                rhs[self.n_w + r] = heat[p];
            }
        }
        rhs.iter_mut().zip(&self.lift).for_each(|(b, l)| *b -= l);
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
            xi,
        }
    }
}
