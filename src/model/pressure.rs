//! The contact pressure at the nodes of Γ_C, from the reaction of the bilateral constraint.
//!
//! The step's equations hold for test functions with v_ν = 0 on Γ_C; tested with the normal
//! hat function ν_i φ_i of a contact node instead, the momentum equation leaves the nodal
//! normal force the constraint carries (nodal quadrature, as for the friction):
//!
//! ```text
//! λ_i = ν_i · [ℳ(W_n − W_{n−1})/k + 𝒦_A W_n + 𝒦_B U_n + G Θ_n − F_n]_i = ℓ_i σ_ν,i
//! ```
//!
//! (the friction stress is tangential, so it has no part in ν_i · […]). The contact pressure is
//! p_i = max(0, −σ_ν,i) = max(0, −λ_i)/ℓ_i: compression only. Where the constraint pulls
//! (σ_ν > 0, a body that would lift off) p = 0 and the node carries no friction; the bilateral
//! constraint still holds it (the model has no lift-off).
//!
//! The rows ν_i·[ℳ]_i, ν_i·[𝒦_A]_i, ν_i·[𝒦_B]_i and ν_i·[G]_i are extracted once, when the
//! problem is built (a few dozen entries per contact node); a pressure then costs one sparse
//! product over them and the load vector F_n the step has already formed.
//!
//! Depends on: [`crate::fem`] (the matrices), [`super::state`].

use std::collections::BTreeMap;

use super::problem::{ContactNode, Problem};
use super::state::State;
use crate::fem::assembly::Matrices;
use crate::mesh::Mesh;

/// The normal rows of the step's operators at the contact nodes.
#[derive(Debug, Clone)]
pub struct ContactPressure {
    /// Per contact node i, its velocity entries `velocity_ptr[i]..velocity_ptr[i + 1]`.
    velocity_ptr: Vec<usize>,
    /// Full velocity dof of each entry.
    velocity_cols: Vec<usize>,
    /// ν_i·[ℳ]_i, ν_i·[𝒦_A]_i, ν_i·[𝒦_B]_i at each entry.
    velocity_values: Vec<[f64; 3]>,
    /// Per contact node i, its temperature entries `theta_ptr[i]..theta_ptr[i + 1]`.
    theta_ptr: Vec<usize>,
    /// Node of each temperature entry.
    theta_cols: Vec<usize>,
    /// ν_i·[G]_i at each temperature entry.
    theta_values: Vec<f64>,
}

impl ContactPressure {
    /// The normal rows of ℳ, 𝒦_A, 𝒦_B (symmetric: a row is its column) and G at `contact`.
    pub fn new(mesh: &Mesh, matrices: &Matrices, contact: &[ContactNode]) -> Self {
        let d = mesh.dim;
        let mut pressure = ContactPressure {
            velocity_ptr: vec![0],
            velocity_cols: Vec::new(),
            velocity_values: Vec::new(),
            theta_ptr: vec![0],
            theta_cols: Vec::new(),
            theta_values: Vec::new(),
        };
        // ℳ, 𝒦_A, 𝒦_B on 𝒦_A's (vector) pattern, ℳ's entries read through it.
        let pattern = &matrices.viscosity;
        let values = |m: usize, dof: usize, k: usize| match m {
            0 => matrices.mass.column(dof).entry(k - pattern.col_ptr[dof]),
            1 => matrices.viscosity.values[k],
            _ => matrices.elasticity.values[k],
        };
        for node in contact {
            let p = node.node;
            let mut velocity: BTreeMap<usize, [f64; 3]> = BTreeMap::new();
            let mut theta: BTreeMap<usize, f64> = BTreeMap::new();
            for c in 0..d {
                let dof = p * d + c;
                for m in 0..3 {
                    for k in pattern.col_ptr[dof]..pattern.col_ptr[dof + 1] {
                        velocity.entry(pattern.row_idx[k] as usize).or_default()[m] +=
                            node.normal[c] * values(m, dof, k);
                    }
                }
            }
            // G's row (p, c) lies in the columns of the nodes next to p: those of ℳ's row.
            for q in velocity.keys().map(|&j| j / d) {
                if theta.contains_key(&q) {
                    continue;
                }
                let g: f64 = (0..d)
                    .map(|c| node.normal[c] * matrices.coupling.get(p * d + c, q))
                    .sum();
                theta.insert(q, g);
            }
            for (col, values) in velocity {
                pressure.velocity_cols.push(col);
                pressure.velocity_values.push(values);
            }
            for (col, value) in theta {
                pressure.theta_cols.push(col);
                pressure.theta_values.push(value);
            }
            pressure.velocity_ptr.push(pressure.velocity_cols.len());
            pressure.theta_ptr.push(pressure.theta_cols.len());
        }
        pressure
    }

    /// λ_i = ℓ_i σ_ν,i at every contact node for the step from `previous` to `state` with the
    /// load vector `force` = F_n (full velocity dofs, [`Problem::force`]).
    pub fn normal_forces(&self, problem: &Problem, previous: &State, state: &State, force: &[f64]) -> Vec<f64> {
        let d = problem.dim();
        let k = state.t - previous.t;
        (problem.contact.iter().enumerate())
            .map(|(i, node)| {
                let entries = self.velocity_ptr[i]..self.velocity_ptr[i + 1];
                let mut lambda = 0.0;
                for (&j, v) in self.velocity_cols[entries.clone()]
                    .iter()
                    .zip(&self.velocity_values[entries])
                {
                    lambda += v[0] * (state.w[j] - previous.w[j]) / k + v[1] * state.w[j] + v[2] * state.u[j];
                }
                let entries = self.theta_ptr[i]..self.theta_ptr[i + 1];
                for (&q, g) in self.theta_cols[entries.clone()].iter().zip(&self.theta_values[entries]) {
                    lambda += g * state.theta[q];
                }
                let p = node.node;
                lambda - (0..d).map(|c| node.normal[c] * force[p * d + c]).sum::<f64>()
            })
            .collect()
    }

    /// p_i = max(0, −λ_i)/ℓ_i ([`ContactPressure::normal_forces`]).
    pub fn pressures(&self, problem: &Problem, previous: &State, state: &State, force: &[f64]) -> Vec<f64> {
        let lambda = self.normal_forces(problem, previous, state, force);
        (problem.contact.iter().zip(lambda))
            .map(|(node, lambda)| (-lambda).max(0.0) / node.weight)
            .collect()
    }
}
