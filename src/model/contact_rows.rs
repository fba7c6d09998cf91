//! The contact state at the nodes of Γ_C, as output and summaries read it: w_τ and ξ in each
//! node's tangent coordinates, the friction bound, slip or stick, θ.
//!
//! Depends on: [`super::problem`], [`super::state`], [`crate::la::vector`].

use serde::Serialize;

use super::laws::ContactLaws;
use super::problem::Problem;
use super::state::State;
use crate::la::vector::norm2;

/// Tangential velocities at the contact nodes from a full velocity vector: node-major, in each
/// node's tangent coordinates.
pub fn contact_tangential(problem: &Problem, w_full: &[f64]) -> Vec<f64> {
    let d = problem.dim();
    problem
        .contact
        .iter()
        .flat_map(|node| {
            let w = &w_full[node.node * d..(node.node + 1) * d];
            node.tangents.iter().map(move |t| (0..d).map(|c| t[c] * w[c]).sum())
        })
        .collect()
}

/// The contact state at one node of Γ_C.
#[derive(Debug, Clone, Serialize)]
pub struct ContactRow {
    /// Mesh node.
    pub node: usize,
    /// Position in the reference configuration.
    pub x: [f64; 3],
    /// ν_i, the node's unit outward normal.
    pub normal: [f64; 3],
    /// The node's tangent basis t_1 … t_{d−1} (2D: ν turned by +90°, the x direction for the
    /// paper's Γ_C).
    pub tangents: Vec<[f64; 3]>,
    /// w_τ − v_F,τ, the slip relative to the foundation, in the node's tangent coordinates
    /// (d − 1): w_τ itself where the foundation is at rest.
    pub w_tau: Vec<f64>,
    /// ξ, the friction stress, in the node's tangent coordinates (d − 1).
    pub xi: Vec<f64>,
    /// The friction bound μ(|w_τ|) S at this node.
    pub bound: f64,
    /// |w_τ − v_F,τ| > slip tolerance.
    pub slip: bool,
    /// θ at the node.
    pub theta: f64,
    /// s_n, the slip distance so far, where a friction law weakens with it (`None` otherwise,
    /// and the outputs leave the column out).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slip_distance: Option<f64>,
    /// p_n, the contact pressure, where a friction law scales with it (Coulomb; `None`
    /// otherwise, and the outputs leave the column out).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pressure: Option<f64>,
}

impl ContactRow {
    /// ξ as a vector in global coordinates, Σ_k ξ_k t_k.
    pub fn friction_vector(&self) -> [f64; 3] {
        combine(&self.tangents, &self.xi)
    }

    /// w_τ as a vector in global coordinates, Σ_k w_{τ,k} t_k.
    pub fn slip_vector(&self) -> [f64; 3] {
        combine(&self.tangents, &self.w_tau)
    }

    /// |w_τ|.
    pub fn slip_rate(&self) -> f64 {
        norm2(&self.w_tau)
    }
}

fn combine(tangents: &[[f64; 3]], coordinates: &[f64]) -> [f64; 3] {
    let mut v = [0.0; 3];
    for (t, a) in tangents.iter().zip(coordinates) {
        (0..3).for_each(|c| v[c] += a * t[c]);
    }
    v
}

/// The contact rows of a state; a node slips when |w_τ| exceeds `slip_tolerance`.
///
/// The bound is the law's at the state's time and slip distance.
pub fn contact_rows(problem: &Problem, state: &State, slip_tolerance: f64) -> Vec<ContactRow> {
    let tangential = problem.dim() - 1;
    let laws = ContactLaws::of_state(problem, state);
    let uses_slip_distance = problem.uses_slip_distance();
    let w_tau = match &laws {
        Ok(laws) => laws.slip(&state.w),
        Err(_) => contact_tangential(problem, &state.w),
    };
    problem
        .contact
        .iter()
        .zip(w_tau.chunks_exact(tangential))
        .zip(state.xi.chunks_exact(tangential))
        .enumerate()
        .map(|(i, ((node, w), xi))| {
            let speed = norm2(w);
            ContactRow {
                node: node.node,
                x: problem.mesh.coords[node.node],
                normal: node.normal,
                tangents: node.tangents.clone(),
                w_tau: w.to_vec(),
                xi: xi.to_vec(),
                bound: laws.as_ref().map_or(f64::NAN, |laws| laws.bound(i, speed)),
                slip: speed > slip_tolerance,
                theta: state.theta[node.node],
                slip_distance: uses_slip_distance.then(|| state.slip_distance.get(i).copied().unwrap_or(0.0)),
                pressure: state.pressure.get(i).copied(),
            }
        })
        .collect()
}
