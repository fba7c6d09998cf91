//! Derived fields for output: the stress σ = 𝒜ε(w) + ℬε(u) + C(θ − θ_ref) per cell (eq. (1),
//! with the cell's material), its von Mises norm, and the contact status and friction stress per
//! node.

use crate::mesh::simplex::Simplex;
use crate::model::ContactRow;
use crate::model::Problem;
use crate::model::State;

/// The symmetric-tensor components written per cell, in VTK's order for 6-component arrays
/// (xx, yy, zz, xy, yz, xz), which ParaView reads as a symmetric tensor, in 2D as in 3D.
///
/// In 2D the body is in plane strain (the paper's ℬ is the plane-strain Lamé form): ε_zz = 0,
/// so σ_zz = λ_𝒜 tr ε(w) + λ_ℬ tr ε(u) + c(θ − θ_ref), which the 2D equations never use but a
/// von Mises stress must include; σ_yz = σ_xz = 0. Written as (xx, yy, xy) the 2D tensor was a
/// 3-vector to ParaView (glyphs and warps of a stress make no sense).
pub const STRESS_COMPONENTS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)];

/// σ per cell, 6 components in the order of [`STRESS_COMPONENTS`] (P1 strains are constant
/// per cell; θ is averaged over the cell's vertices).
pub fn cell_stress(problem: &Problem, state: &State) -> Vec<f64> {
    cell_stress_of(problem, state, 0..problem.mesh.n_cells())
}

/// σ of [`cell_stress`] on `cells` only, in their order (the piece of a distributed run's
/// frame).
pub fn cell_stress_of(problem: &Problem, state: &State, cells: impl ExactSizeIterator<Item = usize>) -> Vec<f64> {
    let mesh = &problem.mesh;
    let d = mesh.dim;
    let mut out = Vec::with_capacity(cells.len() * STRESS_COMPONENTS.len());
    for e in cells {
        let material = problem.materials.of(e);
        let t = Simplex::new(d, &mesh.cell_coords(e));
        let nodes = mesh.cell(e);
        // A full 3 × 3 strain with zero z rows in 2D (plane strain).
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
        let viscous = material.viscosity.apply(3, &strain(&state.w));
        let elastic = material.elasticity.apply(3, &strain(&state.u));
        let theta = nodes.iter().map(|&p| state.theta[p]).sum::<f64>() / nodes.len() as f64;
        let thermal = material.expansion * (theta - material.reference_temperature);
        for (i, j) in STRESS_COMPONENTS {
            let isotropic = if i == j { thermal } else { 0.0 };
            out.push(viscous[i][j] + elastic[i][j] + isotropic);
        }
    }
    out
}

/// The von Mises stress √(3 J₂) of each cell's σ (6 components per cell, [`STRESS_COMPONENTS`]).
pub fn von_mises(stress: &[f64]) -> Vec<f64> {
    stress
        .chunks_exact(STRESS_COMPONENTS.len())
        .map(|s| {
            let [xx, yy, zz, xy, yz, xz] = [s[0], s[1], s[2], s[3], s[4], s[5]];
            (0.5 * ((xx - yy).powi(2) + (yy - zz).powi(2) + (zz - xx).powi(2)) + 3.0 * (xy * xy + yz * yz + xz * xz))
                .sqrt()
        })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A hydrostatic stress has no von Mises part; a pure shear τ has √3 τ; a uniaxial σ has σ.
    #[test]
    fn von_mises_of_known_states() {
        let states = [
            [-4.0, -4.0, -4.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 2.0, 0.0, 0.0],
            [0.0, 0.0, 5.0, 0.0, 0.0, 0.0],
        ];
        let vm = von_mises(&states.concat());
        let expected = [0.0, 3f64.sqrt() * 2.0, 5.0];
        for (v, e) in vm.iter().zip(expected) {
            assert!((v - e).abs() < 1e-14, "{v} against {e}");
        }
    }
}
