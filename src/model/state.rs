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
    /// s_n: the slip distance Σ_{m≤n} k ‖w_τ^m‖ at each contact node (the history variable of
    /// slip-distance weakening).
    pub slip_distance: Vec<f64>,
    /// s_{n−1}: the slip distances the law of step n read (what its residual and bounds are
    /// reported against); not checkpointed.
    pub slip_distance_before: Vec<f64>,
    /// p_n: the contact pressure at each contact node where a friction law scales with it
    /// (Coulomb, [`super::ContactPressure`]); empty otherwise.
    pub pressure: Vec<f64>,
    /// 𝒦_B U_n in the rows of a process that holds a share of the matrices (a distributed
    /// run's rank: its own and Γ_C's nodes' entries, the others partial), formed by the
    /// energies' pass over its cells ([`super::step_energy_and_elastic_force`]) and read by the
    /// next step's right-hand side; empty otherwise (one process, whose 𝒦_B is assembled; a
    /// state made or read anew), where the right-hand side forms the product itself. Not
    /// checkpointed.
    pub elastic_force: Vec<f64>,
}

impl State {
    /// s_n from s_{n−1} and the relative slip w_n − v_F over the step from `previous`
    /// (explicit: the step's law read s_{n−1}).
    pub fn accumulate_slip(&mut self, problem: &Problem, previous: &State) {
        let k = self.t - previous.t;
        let w_tau = super::relative_slip(problem, &self.w, self.t);
        let td = problem.dim() - 1;
        self.slip_distance_before = previous.slip_distance.clone();
        // An empty `previous.slip_distance` (a checkpoint older than it) reads as zeros.
        self.slip_distance = (w_tau.chunks_exact(td).enumerate())
            .map(|(i, w)| previous.slip_distance.get(i).copied().unwrap_or(0.0) + k * crate::la::vector::norm2(w))
            .collect();
    }

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
            slip_distance: vec![0.0; problem.contact.len()],
            slip_distance_before: vec![0.0; problem.contact.len()],
            pressure: if problem.pressure.is_some() {
                vec![0.0; problem.contact.len()]
            } else {
                Vec::new()
            },
            elastic_force: Vec::new(),
        }
    }
}
