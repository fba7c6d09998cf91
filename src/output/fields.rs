//! Derived fields for output: the stress σ = 𝒜ε(w) + ℬε(u) + Cθ per cell (eq. (1)), and the
//! contact status and friction stress per node.

use crate::fem::simplex::Simplex;
use crate::problem::Problem;
use crate::solver::system::State;
use crate::time::ContactRow;

/// Symmetric-tensor components written per cell: (xx, yy, xy) in 2D,
/// (xx, yy, zz, xy, yz, xz) in 3D.
pub fn stress_components(dim: usize) -> &'static [(usize, usize)] {
    if dim == 2 {
        &[(0, 0), (1, 1), (0, 1)]
    } else {
        &[(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)]
    }
}

/// σ per cell (P1 strains are constant per cell; θ is averaged over the cell's vertices).
pub fn cell_stress(problem: &Problem, state: &State) -> Vec<f64> {
    let mesh = &problem.mesh;
    let d = mesh.dim;
    let material = &problem.material;
    let comps = stress_components(d);
    let mut out = Vec::with_capacity(mesh.n_cells() * comps.len());
    for e in 0..mesh.n_cells() {
        let t = Simplex::new(d, &mesh.cell_coords(e));
        let nodes = mesh.cell(e);
        let strain = |field: &[f64]| {
            let mut eps = [[0.0; 3]; 3];
            for (a, &p) in nodes.iter().enumerate() {
                for i in 0..d {
                    for j in 0..d {
                        // ε_ij = ½(∂_j v_i + ∂_i v_j)
                        eps[i][j] += 0.5 * (field[p * d + i] * t.grads[a][j] + field[p * d + j] * t.grads[a][i]);
                    }
                }
            }
            eps
        };
        let viscous = material.viscosity.apply(d, &strain(&state.w));
        let elastic = material.elasticity.apply(d, &strain(&state.u));
        let theta = nodes.iter().map(|&p| state.theta[p]).sum::<f64>() / nodes.len() as f64;
        for &(i, j) in comps {
            let thermal = if i == j { material.expansion * theta } else { 0.0 };
            out.push(viscous[i][j] + elastic[i][j] + thermal);
        }
    }
    out
}

/// Per node: contact status (0 off Γ_C or clamped, 1 stick, 2 slip) and the friction stress ξ
/// as a d-vector in global coordinates (zero off the contact nodes).
pub fn nodal_contact_fields(problem: &Problem, rows: &[ContactRow]) -> (Vec<f64>, Vec<f64>) {
    let d = problem.dim();
    let mut status = vec![0.0; problem.mesh.n_nodes()];
    let mut friction = vec![0.0; problem.mesh.n_nodes() * d];
    for row in rows {
        status[row.node] = if row.slip { 2.0 } else { 1.0 };
        let xi = row.friction_vector();
        friction[row.node * d..(row.node + 1) * d].copy_from_slice(&xi[..d]);
    }
    (status, friction)
}
