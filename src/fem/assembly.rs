//! Global assembly: scatter element kernels into matrices whose pattern comes from the node
//! graph, and integrate loads. Full nodal numbering: velocity dof (p, c) ↦ p·d + c, temperature
//! dof p ↦ p. Constraints are applied later by the spaces in [`super::dofs`].

use rayon::prelude::*;

use super::kernels;
use super::simplex::{facet_measure, Simplex};
use super::sparse::{CscMatrix, NodeGraph};
use crate::material::{Isotropic, Material};
use crate::mesh::Mesh;

/// The P1 matrices of MODEL.md §2 on full nodal dofs.
#[derive(Debug, Clone)]
pub struct Matrices {
    /// ℳ: consistent mass with density ρ, vector.
    pub mass: CscMatrix,
    /// 𝒦_A: viscous stiffness (𝒜ε(w), ε(v)).
    pub viscosity: CscMatrix,
    /// 𝒦_B: elastic stiffness (ℬε(u), ε(v)).
    pub elasticity: CscMatrix,
    /// G: G_(p,c),q = ∫ c ψ_q div(φ_p e_c) (velocity rows, temperature columns).
    pub coupling: CscMatrix,
    /// ℳ_θ: consistent mass with ρ c_p.
    pub heat_mass: CscMatrix,
    /// 𝒦_θ: conduction (K∇θ, ∇η) plus the Robin part k_e ∫_ΓC θ η.
    pub conduction: CscMatrix,
    /// (ε(u), ε(v)): Gram matrix of the E-norm.
    pub energy_gram: CscMatrix,
    /// (∇θ, ∇η): Gram matrix of the V-norm.
    pub gradient_gram: CscMatrix,
}

/// Assembles every volume matrix in one parallel sweep over the cells, and the Robin term
/// `robin_coefficient · ∫ θ η` on the facets of `robin_parts`.
pub fn assemble_matrices(mesh: &Mesh, material: &Material, robin_parts: &[usize], robin_coefficient: f64) -> Matrices {
    let d = mesh.dim;
    let graph = NodeGraph::new(mesh.n_nodes(), &mesh.cells, mesh.nodes_per_cell());
    let vector = CscMatrix::from_graph(&graph, d, d);
    let scalar = CscMatrix::from_graph(&graph, 1, 1);
    let coupling = CscMatrix::from_graph(&graph, d, 1);
    // Order: mass, viscosity, elasticity, coupling, heat mass, conduction, energy, gradient.
    let templates = vec![
        vector.clone(),
        vector.clone(),
        vector.clone(),
        coupling,
        scalar.clone(),
        scalar.clone(),
        vector,
        scalar,
    ];
    let strain_gram = Isotropic {
        lambda: 0.0,
        two_mu: 1.0,
    };
    let n_threads = rayon::current_num_threads().max(1);
    let n_cells = mesh.n_cells();
    let chunk = n_cells.div_ceil(n_threads).max(1);
    let partials: Vec<Vec<CscMatrix>> = (0..n_cells)
        .step_by(chunk)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|start| {
            let mut mats = templates.clone();
            for e in start..(start + chunk).min(n_cells) {
                let nodes = mesh.cell(e);
                let t = Simplex::new(d, &mesh.cell_coords(e));
                let mass = kernels::scalar_mass(&t);
                let lap = kernels::laplacian(&t);
                let visc = kernels::isotropic_stiffness(&t, material.viscosity);
                let elast = kernels::isotropic_stiffness(&t, material.elasticity);
                let gram = kernels::isotropic_stiffness(&t, strain_gram);
                let div = kernels::divergence_coupling(&t);
                for (a, &p) in nodes.iter().enumerate() {
                    for (b, &q) in nodes.iter().enumerate() {
                        for i in 0..d {
                            mats[0].add(p * d + i, q * d + i, material.density * mass[a][b]);
                            for j in 0..d {
                                let (row, col) = (p * d + i, q * d + j);
                                mats[1].add(row, col, visc[a * d + i][b * d + j]);
                                mats[2].add(row, col, elast[a * d + i][b * d + j]);
                                mats[6].add(row, col, gram[a * d + i][b * d + j]);
                            }
                            mats[3].add(p * d + i, q, material.expansion * div[a * d + i][b]);
                        }
                        mats[4].add(p, q, material.density * material.heat_capacity * mass[a][b]);
                        mats[5].add(p, q, material.conductivity * lap[a][b]);
                        mats[7].add(p, q, lap[a][b]);
                    }
                }
            }
            mats
        })
        .collect();
    let mut sum = templates;
    for partial in partials {
        for (total, part) in sum.iter_mut().zip(partial) {
            total.values.iter_mut().zip(part.values).for_each(|(t, v)| *t += v);
        }
    }
    let [mass, viscosity, elasticity, coupling, heat_mass, mut conduction, energy_gram, gradient_gram]: [CscMatrix; 8] =
        sum.try_into().expect("eight matrices");
    for f in mesh.facets_of(robin_parts) {
        let nodes = mesh.facet(f);
        let verts: Vec<[f64; 3]> = nodes.iter().map(|&i| mesh.coords[i]).collect();
        let m = kernels::facet_mass(d, facet_measure(d, &verts));
        for (a, &p) in nodes.iter().enumerate() {
            for (b, &q) in nodes.iter().enumerate() {
                conduction.add(p, q, robin_coefficient * m[a][b]);
            }
        }
    }
    Matrices {
        mass,
        viscosity,
        elasticity,
        coupling,
        heat_mass,
        conduction,
        energy_gram,
        gradient_gram,
    }
}

/// ∫_Ω f · φ for a constant vector f: a full velocity-dof load vector.
pub fn body_load(mesh: &Mesh, f: &[f64]) -> Vec<f64> {
    let d = mesh.dim;
    let mut load = vec![0.0; mesh.n_nodes() * d];
    for e in 0..mesh.n_cells() {
        let t = Simplex::new(d, &mesh.cell_coords(e));
        let share = t.measure / (d + 1) as f64;
        for &p in mesh.cell(e) {
            for c in 0..d {
                load[p * d + c] += f[c] * share;
            }
        }
    }
    load
}

/// ∫_Ω g η for a constant g: a full temperature load vector.
pub fn scalar_body_load(mesh: &Mesh, g: f64) -> Vec<f64> {
    let d = mesh.dim;
    let mut load = vec![0.0; mesh.n_nodes()];
    for e in 0..mesh.n_cells() {
        let share = g * Simplex::new(d, &mesh.cell_coords(e)).measure / (d + 1) as f64;
        for &p in mesh.cell(e) {
            load[p] += share;
        }
    }
    load
}

/// ℓ_p = ∫_{parts} φ_p: the nodal weights of a boundary part (zero off it).
pub fn boundary_weights(mesh: &Mesh, parts: &[usize]) -> Vec<f64> {
    let d = mesh.dim;
    let mut weights = vec![0.0; mesh.n_nodes()];
    for f in mesh.facets_of(parts) {
        let nodes = mesh.facet(f);
        let verts: Vec<[f64; 3]> = nodes.iter().map(|&i| mesh.coords[i]).collect();
        let share = facet_measure(d, &verts) / d as f64;
        for &p in nodes {
            weights[p] += share;
        }
    }
    weights
}

/// ∫_{parts} f₂ · φ for a constant traction f₂: a full velocity-dof load vector.
pub fn traction_load(mesh: &Mesh, parts: &[usize], f: &[f64]) -> Vec<f64> {
    let d = mesh.dim;
    let weights = boundary_weights(mesh, parts);
    let mut load = vec![0.0; mesh.n_nodes() * d];
    for (p, w) in weights.iter().enumerate() {
        for c in 0..d {
            load[p * d + c] = f[c] * w;
        }
    }
    load
}
