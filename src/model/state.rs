//! The state carried from time level to time level.
//!
//! Depends on: [`super::problem`].

use super::problem::Problem;

/// The state carried from step to step, as full nodal vectors.
#[derive(Debug, Clone)]
pub struct State {
    /// Time level n (the substeps of a cut-back step do not count).
    pub n: usize,
    /// Its time t_n (a substep's own time inside a cut-back step).
    pub t: f64,
    /// W_n: velocity, d per node.
    pub w: Vec<f64>,
    /// U_n = U_{n−1} + k W_n: displacement, d per node.
    pub u: Vec<f64>,
    /// Θ_n: temperature, one per node.
    pub theta: Vec<f64>,
    /// ξ_n: friction stress at the contact nodes in their tangent coordinates, node-major,
    /// d − 1 per node.
    pub xi: Vec<f64>,
}

impl State {
    /// The initial state (10): u₀, u₁ in E^h, θ₀ at the nodes, no friction stress.
    pub fn initial(problem: &Problem) -> Self {
        let initial = &problem.initial;
        State {
            n: 0,
            t: 0.0,
            w: initial.velocity.clone(),
            u: initial.displacement.clone(),
            theta: initial.temperature.clone(),
            xi: vec![0.0; problem.contact.len() * (problem.dim() - 1)],
        }
    }
}
