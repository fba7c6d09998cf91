//! The norms of the stop criteria (77)–(80) and of the error estimate (73).
//!
//! ‖v‖_E = ‖ε(v)‖_L², ‖θ‖_V = ‖∇θ‖_L², exact for P1: sums over the cells ([`energy`],
//! [`gradient`]; outputs, studies), or the quadratic forms of their Gram matrices where a solver
//! evaluates them at every iterate ([`relative_increments`] of the paper's solver); on Γ_C the
//! nodal fields ξ and ζ use the same nodal quadrature as the contact terms:
//! ‖ξ‖²_L²(ΓC) ≈ Σ_i ℓ_i |ξ_i|².

use super::problem::Problem;
use super::state::State;
use crate::fem::assembly::{gradient_norm, strain_norm, NormGrams};
use crate::mesh::Mesh;

/// ‖ε(v)‖_L² of a full nodal vector field.
pub fn energy(mesh: &Mesh, v: &[f64]) -> f64 {
    strain_norm(mesh, v)
}

/// ‖∇θ‖_L² of a full nodal scalar field.
pub fn gradient(mesh: &Mesh, theta: &[f64]) -> f64 {
    gradient_norm(mesh, theta)
}

/// L²(Γ_C) norm of a nodal field on the frictional contact nodes: `field` node-major with the
/// same number of components at every node (d − 1 tangent coordinates, or 1 for a scalar).
pub fn contact_l2(problem: &Problem, field: &[f64]) -> f64 {
    let n = problem.contact.len();
    if n == 0 {
        return 0.0;
    }
    let width = field.len() / n;
    problem
        .contact
        .iter()
        .zip(field.chunks_exact(width))
        .map(|(node, v)| node.weight * v.iter().map(|x| x * x).sum::<f64>())
        .sum::<f64>()
        .sqrt()
}

/// ζ_i = −∂j(θ_i) at the contact nodes at time t (the heat-exchange multiplier of Problem 14).
pub fn heat_exchange_multiplier(problem: &Problem, t: f64, theta: &[f64]) -> Vec<f64> {
    problem
        .contact
        .iter()
        .map(|node| {
            let at = crate::contact::LawPoint {
                x: problem.mesh.coords[node.node],
                t,
                slip_distance: 0.0,
            };
            -problem.exchange.flux(&at, theta[node.node])
        })
        .collect()
}

/// Relative increments (77)–(80) between two iterates of one time step, the E- and V-norms by
/// `grams` (of `problem`'s mesh).
pub fn relative_increments(problem: &Problem, grams: &NormGrams, old: &State, new: &State) -> [f64; 4] {
    let diff = |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x - y).collect() };
    let ratio = |num: f64, den: f64| {
        if num == 0.0 {
            0.0
        } else if den == 0.0 {
            f64::INFINITY
        } else {
            num / den
        }
    };
    let du = grams.strain_norm(&diff(&new.u, &old.u));
    let dtheta = grams.gradient_norm(&diff(&new.theta, &old.theta));
    let dxi = contact_l2(problem, &diff(&new.xi, &old.xi));
    let zeta_new = heat_exchange_multiplier(problem, new.t, &new.theta);
    let zeta_old = heat_exchange_multiplier(problem, old.t, &old.theta);
    let zeta_diff = diff(&zeta_new, &zeta_old);
    let zeta_ref = zeta_old;
    [
        ratio(du, grams.strain_norm(&old.u)),
        ratio(dtheta, grams.gradient_norm(&old.theta)),
        ratio(dxi, contact_l2(problem, &old.xi)),
        ratio(contact_l2(problem, &zeta_diff), contact_l2(problem, &zeta_ref)),
    ]
}
