//! Global assembly: sum element kernels into matrices whose pattern comes from the node graph,
//! and integrate loads. Full nodal numbering: velocity dof (p, c) ↦ p·d + c, temperature dof
//! p ↦ p. Constraints are applied later by the constrained spaces E^h and V^h (`dofs`).
//!
//! The sweep goes by nodes, not by cells. A node q's columns of each matrix lie one after the
//! other in [`CscMatrix::from_graph`]'s layout (≈ 1 KB per vector matrix in 3D), and entry (p, q)
//! is Σ_e K^e_pq over the cells e holding p and q. For each q, its columns of the eight matrices
//! are summed over q's cells in increasing order, each cell giving its kernels' columns of q
//! (`kernels::*_column`): every entry is summed as a sweep over the cells sums it, term by term
//! in the same order, so the bits are the same on any number of threads, and blocks of 2048
//! nodes balance the two cores. The sums stay in the cache and each of the 1.3 GB of values at
//! 10⁶ unknowns is written once, its page first by a store (a read maps the zero page, and the
//! write after it faults a second time). The kernels are computed a column at a time, four
//! times per cell: the same flops as the whole local matrices once.
//!
//! Measured on the 3D example at 972k unknowns (one step, release, interleaved with the binary
//! before on the shared 2-core machine; docs/performance.md): the assembly 2.9–5.2 s against
//! 6.5–7.1 s at load 3–4. Rejected: the sweep over the cells that added each cell's whole
//! kernels into the columns of its nodes, each thread owning half of the nodes (5.6–6.1 s on
//! the idle machine): 47 % of its time in the scattered `+=` (an entry's column revisited from
//! cells far apart in the sweep, 1.3 GB of values behind 4 KB pages), each page faulted twice;
//! partial matrices per thread, summed at the end, round differently per thread count. What is
//! left is near the floor of this virtual machine: a fresh page costs ≈ 0.85 s per GB on first
//! touch (1.2 GB/s, against 15 GB/s for rewriting touched memory), 1.1 s of CPU for the values
//! alone.

use rayon::prelude::*;

use super::kernels;
use crate::la::{ColumnsMut, CscMatrix, NodeCells, NodeGraph};
use crate::material::{CellMaterials, Material};
use crate::mesh::simplex::{facet_measure, Simplex};
use crate::mesh::Mesh;

/// The P1 matrices of docs/model.md §2 on full nodal dofs.
#[derive(Debug, Clone)]
pub struct Matrices {
    /// ℳ: consistent mass with density ρ, vector: M_ρ ⊗ I_d, kept as M_ρ.
    pub mass: VectorMass,
    /// 𝒦_A: viscous stiffness (𝒜ε(w), ε(v)).
    pub viscosity: CscMatrix,
    /// 𝒦_B: elastic stiffness (ℬε(u), ε(v)).
    pub elasticity: CscMatrix,
    /// G: G_(p,c),q = ∫ c ψ_q div(φ_p e_c) (velocity rows, temperature columns).
    pub coupling: CscMatrix,
    /// ℳ_θ: consistent mass with ρ c_p.
    pub heat_mass: CscMatrix,
    /// 𝒦_θ: conduction (K∇θ, ∇η) plus the Robin part k_e ∫_ΓC θ η (and h ∫ θ η on convection
    /// parts, added by the problem's builder: `crate::model::ThermalCondition`).
    pub conduction: CscMatrix,
}

/// The consistent mass of a vector field, ℳ = M_ρ ⊗ I_d (entry ((p, i), (q, j)) is δ_ij ∫ ρ φ_p φ_q),
/// kept as the scalar M_ρ on the nodal pattern: one value per node pair where the vector
/// pattern has d² (0.22 GB less at 972k unknowns in 3D). Its products add the same terms in
/// the same order as a product with ℳ stored on the vector pattern (the same bits), and
/// [`VectorMass::column`] reads ℳ's entries in a column of that pattern, zeros included, for
/// the loops that sweep it beside 𝒦_A and 𝒦_B.
#[derive(Debug, Clone)]
pub struct VectorMass {
    /// M_ρ: one row and column per node.
    pub scalar: CscMatrix,
    /// d.
    pub dim: usize,
}

impl VectorMass {
    /// Rows (and columns): d per node.
    pub fn n_rows(&self) -> usize {
        self.scalar.n_rows * self.dim
    }

    /// y += alpha · ℳ x: column (q, j) of ℳ adds M_ρ's column q to the rows (p, j), in the
    /// order of a product over ℳ's columns.
    pub fn mul_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        let (d, m) = (self.dim, &self.scalar);
        debug_assert_eq!(x.len(), self.n_rows());
        debug_assert_eq!(y.len(), self.n_rows());
        for q in 0..m.n_cols {
            for j in 0..d {
                let xc = x[q * d + j];
                if xc == 0.0 {
                    continue;
                }
                let ax = alpha * xc;
                for k in m.col_ptr[q]..m.col_ptr[q + 1] {
                    y[m.row_idx[k] as usize * d + j] += m.values[k] * ax;
                }
            }
        }
    }

    /// ℳ x as a new vector.
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n_rows()];
        self.mul_add(1.0, x, &mut y);
        y
    }

    /// xᵀ ℳ x.
    pub fn quadratic_form(&self, x: &[f64]) -> f64 {
        self.mul(x).iter().zip(x).map(|(a, b)| a * b).sum()
    }

    /// ℳ's column `col` = (q, j) as laid out on the vector pattern of [`CscMatrix::from_graph`]
    /// (d rows per neighbour of q, the neighbours sorted: M_ρ's column q), for the loops that
    /// sweep that pattern.
    #[inline]
    pub fn column(&self, col: usize) -> MassColumn<'_> {
        let (d, q) = (self.dim, col / self.dim);
        MassColumn {
            scalar: &self.scalar.values[self.scalar.col_ptr[q]..self.scalar.col_ptr[q + 1]],
            dim: d,
            component: col % d,
        }
    }
}

/// One column (q, j) of ℳ on the vector pattern ([`VectorMass::column`]).
pub struct MassColumn<'a> {
    /// M_ρ's column q.
    scalar: &'a [f64],
    dim: usize,
    /// j.
    component: usize,
}

impl MassColumn<'_> {
    /// The entry stored `t`-th: row (p, i) with p the (t / d)-th neighbour and i = t mod d,
    /// M_ρ's entry where i = j and zero elsewhere.
    #[inline]
    pub fn entry(&self, t: usize) -> f64 {
        if t % self.dim == self.component {
            self.scalar[t / self.dim]
        } else {
            0.0
        }
    }
}

/// [`assemble_cell_materials`] for a body of one material.
pub fn assemble_matrices(mesh: &Mesh, material: &Material, robin_parts: &[usize], robin_coefficient: f64) -> Matrices {
    assemble_cell_materials(mesh, &CellMaterials::uniform(*material), robin_parts, robin_coefficient)
}

/// Assembles every volume matrix in one parallel sweep over the cells, each cell with its own
/// material, and the Robin term `robin_coefficient · ∫ θ η` on the facets of `robin_parts`.
/// With one material the operations are those of a sweep with that material alone, in the same
/// order: the same bits.
pub fn assemble_cell_materials(
    mesh: &Mesh,
    materials: &CellMaterials,
    robin_parts: &[usize],
    robin_coefficient: f64,
) -> Matrices {
    assemble_columns(mesh, materials, (robin_parts, robin_coefficient), None)
}

/// [`assemble_cell_materials`] with the columns of 𝒦_A, 𝒦_B and G only at the nodes `kept`
/// marks (all where `None`; the others empty, [`CscMatrix::from_graph_columns`]); ℳ, ℳ_θ and
/// 𝒦_θ whole (their pattern is the node graph the step matrix's rows are laid out by). The
/// kept columns are the whole matrices' to the bit: a rank of a distributed run assembles the
/// columns its rows read (`crate::model::ColumnShare`), the ninety per cent of the values that
/// sit in those three matrices.
pub fn assemble_columns(
    mesh: &Mesh,
    materials: &CellMaterials,
    (robin_parts, robin_coefficient): (&[usize], f64),
    kept: Option<&[bool]>,
) -> Matrices {
    let d = mesh.dim;
    let nodes_per_cell = mesh.nodes_per_cell();
    let node_cells = NodeCells::new(mesh.n_nodes(), &mesh.cells, nodes_per_cell);
    let graph = NodeGraph::from_node_cells(&node_cells, &mesh.cells, nodes_per_cell);
    let vector = CscMatrix::from_graph_columns(&graph, d, d, kept);
    let scalar = CscMatrix::from_graph(&graph, 1, 1);
    let coupling = CscMatrix::from_graph_columns(&graph, d, 1, kept);
    // Order: mass (M_ρ: scalar), viscosity, elasticity, coupling, heat mass, conduction. Fresh zeros share the
    // pattern and are not copied: the pages are mapped zero and written once, by the sweep (a
    // clone of the zero template read and wrote 0.5 GB more at 291k unknowns). The norms' Gram
    // matrices are not assembled: the norms are sums over the cells ([`crate::model::norms`]),
    // which saved a vector and a scalar matrix (290 MB at 972k unknowns) and their sweep.
    let mut mats = vec![
        scalar.zeros_like(),
        vector.zeros_like(),
        vector,
        coupling,
        scalar.zeros_like(),
        scalar,
    ];
    // Blocks of consecutive nodes, each block's columns summed by one thread: every entry is
    // summed in the same order (its cells' in increasing order, as a sequential sweep over the
    // cells adds them), so the matrices (and the whole run) are bitwise the same on any number
    // of threads. (Partial matrices per thread, summed at the end, round differently per
    // thread count.)
    let n_nodes = mesh.n_nodes();
    let bounds: Vec<usize> = (0..n_nodes).step_by(NODES_PER_BLOCK).chain([n_nodes]).collect();
    // Columns per node: vector matrices d, the coupling and scalar matrices 1 (temperature).
    let cols_per_node = [1, d, d, 1, 1, 1];
    let mut blocks: Vec<Vec<ColumnsMut>> = (1..bounds.len()).map(|_| Vec::with_capacity(6)).collect();
    for (mat, &c) in mats.iter_mut().zip(&cols_per_node) {
        for (block, columns) in blocks.iter_mut().zip(mat.split_columns_mut(&bounds, c)) {
            block.push(columns);
        }
    }
    blocks.into_par_iter().enumerate().for_each(|(b, mut m)| {
        for q in bounds[b]..bounds[b + 1] {
            let mut node: Vec<&mut [f64]> = (m.iter_mut().zip(&cols_per_node))
                .map(|(columns, &c)| columns.columns(q * c..(q + 1) * c))
                .collect();
            // Stored zeros: each page is first written, not read (a read maps the zero page,
            // and the write after it faults a second time).
            node.iter_mut().for_each(|columns| columns.fill(0.0));
            let vector_columns = kept.is_none_or(|kept| kept[q]);
            add_node_columns(
                mesh,
                materials,
                (graph.neighbours(q), node_cells.of(q)),
                (q, vector_columns),
                &mut node,
            );
        }
    });
    let [mass, viscosity, elasticity, coupling, heat_mass, mut conduction]: [CscMatrix; 6] =
        mats.try_into().expect("six matrices");
    add_boundary_mass(mesh, robin_parts, robin_coefficient, &mut conduction);
    Matrices {
        mass: VectorMass { scalar: mass, dim: d },
        viscosity,
        elasticity,
        coupling,
        heat_mass,
        conduction,
    }
}

/// 𝒦_A, 𝒦_B and G alone: what a process that keeps none of them assembles for the while it
/// sums the step matrix's rows ([`assemble_stiffness_columns`]).
#[derive(Debug, Clone)]
pub struct StiffnessColumns {
    /// 𝒦_A.
    pub viscosity: CscMatrix,
    /// 𝒦_B.
    pub elasticity: CscMatrix,
    /// G.
    pub coupling: CscMatrix,
}

/// The columns of the nodes `kept` of 𝒦_A, 𝒦_B and G, the others empty: [`assemble_columns`]'
/// columns of those matrices to the bit (the same sums, in the same order), without ℳ, ℳ_θ and
/// 𝒦_θ. A rank of a distributed run keeps no stiffness between its step matrix's assemblies
/// (`crate::model::ColumnShare`) and assembles them here each time it sums the rows of a step
/// size's matrix.
pub fn assemble_stiffness_columns(mesh: &Mesh, materials: &CellMaterials, kept: &[bool]) -> StiffnessColumns {
    let d = mesh.dim;
    let nodes_per_cell = mesh.nodes_per_cell();
    let node_cells = NodeCells::new(mesh.n_nodes(), &mesh.cells, nodes_per_cell);
    let graph = NodeGraph::from_node_cells(&node_cells, &mesh.cells, nodes_per_cell);
    let vector = CscMatrix::from_graph_columns(&graph, d, d, Some(kept));
    let coupling = CscMatrix::from_graph_columns(&graph, d, 1, Some(kept));
    let mut mats = [vector.zeros_like(), vector, coupling];
    let n_nodes = mesh.n_nodes();
    let bounds: Vec<usize> = (0..n_nodes).step_by(NODES_PER_BLOCK).chain([n_nodes]).collect();
    let cols_per_node = [d, d, 1];
    let mut blocks: Vec<Vec<ColumnsMut>> = (1..bounds.len()).map(|_| Vec::with_capacity(3)).collect();
    for (mat, &c) in mats.iter_mut().zip(&cols_per_node) {
        for (block, columns) in blocks.iter_mut().zip(mat.split_columns_mut(&bounds, c)) {
            block.push(columns);
        }
    }
    blocks.into_par_iter().enumerate().for_each(|(b, mut m)| {
        // The scalar matrices' columns of a node, summed and dropped.
        let mut scalar = [Vec::new(), Vec::new(), Vec::new()];
        for q in (bounds[b]..bounds[b + 1]).filter(|&q| kept[q]) {
            let neighbours = graph.neighbours(q);
            scalar.iter_mut().for_each(|v| v.resize(neighbours.len(), 0.0));
            let [viscosity, elasticity, coupling] = &mut m[..] else {
                unreachable!("three matrices")
            };
            let [mass, heat_mass, conduction] = &mut scalar;
            let mut node: Vec<&mut [f64]> = vec![
                mass,
                viscosity.columns(q * d..(q + 1) * d),
                elasticity.columns(q * d..(q + 1) * d),
                coupling.columns(q..q + 1),
                heat_mass,
                conduction,
            ];
            node.iter_mut().for_each(|columns| columns.fill(0.0));
            add_node_columns(mesh, materials, (neighbours, node_cells.of(q)), (q, true), &mut node);
        }
    });
    let [viscosity, elasticity, coupling] = mats;
    StiffnessColumns {
        viscosity,
        elasticity,
        coupling,
    }
}

/// Nodes per block of the assembly's sweep: a block's columns are summed by one thread, and
/// many blocks balance the two cores of a shared machine.
const NODES_PER_BLOCK: usize = 2048;

/// Adds to node q's columns of the six matrices (`m`: each matrix's columns of q, one after
/// the other, in [`Matrices`]' order) the kernels' columns of q in each of q's cells, in
/// increasing cell order. `neighbours` are q's sorted neighbours: node p's rows in a column of
/// q are at k·r, k the place of p among them and r the rows per node ([`CscMatrix::from_graph`]).
/// Without `vector_columns`, q's columns of 𝒦_A, 𝒦_B and G are not kept ([`assemble_columns`]).
fn add_node_columns(
    mesh: &Mesh,
    materials: &CellMaterials,
    (neighbours, cells): (&[usize], &[usize]),
    (q, vector_columns): (usize, bool),
    m: &mut [&mut [f64]],
) {
    let d = mesh.dim;
    // The length of a column of q: nodal rows d (vector, coupling) or 1 (scalar).
    let column = neighbours.len() * d;
    for &e in cells {
        let nodes = mesh.cell(e);
        let bq = nodes.iter().position(|&p| p == q).expect("a node of its cell");
        let material = materials.of(e);
        let t = Simplex::new(d, &mesh.cell_coords(e));
        let mass = kernels::scalar_mass_column(&t, bq);
        let lap = kernels::laplacian_column(&t, bq);
        // A node whose vector columns are not kept sums the three scalar matrices alone. (One
        // loop with the vector kernels optional was 10–25 % slower at 972k unknowns in one
        // process: 1.60–1.91 s against 1.43–1.78 s.)
        if !vector_columns {
            for (a, &p) in nodes.iter().enumerate() {
                let k = neighbours.binary_search(&p).expect("cell nodes are neighbours");
                m[0][k] += material.density * mass[a];
                m[4][k] += material.density * material.heat_capacity * mass[a];
                m[5][k] += material.conductivity * lap[a];
            }
            continue;
        }
        let visc = kernels::isotropic_stiffness_columns(&t, material.viscosity, bq);
        let elast = kernels::isotropic_stiffness_columns(&t, material.elasticity, bq);
        let div = kernels::divergence_coupling_column(&t, bq);
        for (a, &p) in nodes.iter().enumerate() {
            let k = neighbours.binary_search(&p).expect("cell nodes are neighbours");
            m[0][k] += material.density * mass[a];
            for i in 0..d {
                let (row, ai) = (k * d + i, a * d + i);
                for j in 0..d {
                    let entry = j * column + row;
                    m[1][entry] += visc[ai][j];
                    m[2][entry] += elast[ai][j];
                }
                m[3][row] += material.expansion * div[ai];
            }
            m[4][k] += material.density * material.heat_capacity * mass[a];
            m[5][k] += material.conductivity * lap[a];
        }
    }
}

/// Adds `coefficient · ∫_{parts} θ η` (the consistent boundary mass) to a scalar matrix on full
/// temperature dofs whose pattern holds every facet's node pairs (the cells' graph does): the
/// Robin term of a heat exchange or a convection condition.
pub fn add_boundary_mass(mesh: &Mesh, parts: &[usize], coefficient: f64, matrix: &mut CscMatrix) {
    let d = mesh.dim;
    for f in mesh.facets_of(parts) {
        let nodes = mesh.facet(f);
        let verts: Vec<[f64; 3]> = nodes.iter().map(|&i| mesh.coords[i]).collect();
        let m = kernels::facet_mass(d, facet_measure(d, &verts));
        for (a, &p) in nodes.iter().enumerate() {
            for (b, &q) in nodes.iter().enumerate() {
                matrix.add(p, q, coefficient * m[a][b]);
            }
        }
    }
}

/// θ_ref G 1 with each cell's own expansion c and reference temperature θ_ref: the load
/// Σ_e c_e θ_ref,e ∫_e div φ of the constant part −Cθ_ref of the thermal stress (full velocity
/// dofs). For one material it is `coupling · (θ_ref 1)`, which the caller computes so.
pub fn reference_load(mesh: &Mesh, materials: &CellMaterials) -> Vec<f64> {
    let d = mesh.dim;
    let mut load = vec![0.0; mesh.n_nodes() * d];
    for e in 0..mesh.n_cells() {
        let material = materials.of(e);
        let scale = material.expansion * material.reference_temperature;
        if scale == 0.0 {
            continue;
        }
        let div = kernels::divergence_coupling(&Simplex::new(d, &mesh.cell_coords(e)));
        let nodes = mesh.cell(e);
        for (a, &p) in nodes.iter().enumerate() {
            for i in 0..d {
                load[p * d + i] += scale * (0..nodes.len()).map(|b| div[a * d + i][b]).sum::<f64>();
            }
        }
    }
    load
}

/// The Gram matrices of the norms ‖ε(v)‖_L² and ‖∇θ‖_L²: for a solver that evaluates them at
/// every iterate (the paper's criteria (77)–(78)), where a quadratic form costs about a third of
/// the cell sums of [`strain_norm`] and [`gradient_norm`] (2D reference run, paper solver:
/// 7.7–8.6 s against 9.8–10.5 s). Other runs do not assemble them (a vector and a scalar matrix,
/// 290 MB at 972k unknowns).
pub struct NormGrams {
    /// (ε(u), ε(v)).
    pub strain: CscMatrix,
    /// (∇θ, ∇η).
    pub gradient: CscMatrix,
}

impl NormGrams {
    /// Assembled by a sweep over the cells.
    pub fn assemble(mesh: &Mesh) -> Self {
        let d = mesh.dim;
        let graph = NodeGraph::new(mesh.n_nodes(), &mesh.cells, mesh.nodes_per_cell());
        let (mut strain, mut gradient) = (CscMatrix::from_graph(&graph, d, d), CscMatrix::from_graph(&graph, 1, 1));
        let unit_strain = crate::material::Isotropic {
            lambda: 0.0,
            two_mu: 1.0,
        };
        for e in 0..mesh.n_cells() {
            let t = Simplex::new(d, &mesh.cell_coords(e));
            let nodes = mesh.cell(e);
            for (b, &q) in nodes.iter().enumerate() {
                let (columns, lap) = (
                    kernels::isotropic_stiffness_columns(&t, unit_strain, b),
                    kernels::laplacian_column(&t, b),
                );
                for (a, &p) in nodes.iter().enumerate() {
                    for i in 0..d {
                        for j in 0..d {
                            strain.add(p * d + i, q * d + j, columns[a * d + i][j]);
                        }
                    }
                    gradient.add(p, q, lap[a]);
                }
            }
        }
        NormGrams { strain, gradient }
    }

    /// ‖ε(v)‖_L² of a full nodal vector field.
    pub fn strain_norm(&self, v: &[f64]) -> f64 {
        self.strain.quadratic_form(v).max(0.0).sqrt()
    }

    /// ‖∇θ‖_L² of a full nodal scalar field.
    pub fn gradient_norm(&self, theta: &[f64]) -> f64 {
        self.gradient.quadratic_form(theta).max(0.0).sqrt()
    }
}

/// ‖ε(v)‖_L²(Ω) of the P1 vector field with nodal values `v` (node-major, d per node): the sum
/// over the cells of ∫_T ε(v) : ε(v) (`kernels::strain_squared`), exact for P1.
pub fn strain_norm(mesh: &Mesh, v: &[f64]) -> f64 {
    let d = mesh.dim;
    sum_over_cells(mesh, |t, nodes| {
        let mut local = [[0.0; 3]; 4];
        for (value, &p) in local.iter_mut().zip(nodes) {
            value[..d].copy_from_slice(&v[p * d..(p + 1) * d]);
        }
        kernels::strain_squared(t, &local)
    })
    .max(0.0)
    .sqrt()
}

/// ‖∇θ‖_L²(Ω) of the P1 scalar field with nodal values `theta`: the sum over the cells of
/// ∫_T |∇θ|² (`kernels::gradient_squared`), exact for P1.
pub fn gradient_norm(mesh: &Mesh, theta: &[f64]) -> f64 {
    sum_over_cells(mesh, |t, nodes| {
        let mut local = [0.0; 4];
        for (value, &p) in local.iter_mut().zip(nodes) {
            *value = theta[p];
        }
        kernels::gradient_squared(t, &local)
    })
    .max(0.0)
    .sqrt()
}

/// Σ_e `integral(T_e, nodes of e)`, in blocks of consecutive cells on the threads and the blocks'
/// sums added in order: the same bits on any number of threads.
fn sum_over_cells(mesh: &Mesh, integral: impl Fn(&Simplex, &[usize]) -> f64 + Sync) -> f64 {
    const CELLS_PER_BLOCK: usize = 4096;
    let n = mesh.n_cells();
    let blocks: Vec<f64> = (0..n.div_ceil(CELLS_PER_BLOCK))
        .into_par_iter()
        .map(|b| {
            (b * CELLS_PER_BLOCK..((b + 1) * CELLS_PER_BLOCK).min(n))
                .map(|e| {
                    let nodes = mesh.cell(e);
                    let mut vertices = [[0.0; 3]; 4];
                    for (x, &p) in vertices.iter_mut().zip(nodes) {
                        *x = mesh.coords[p];
                    }
                    integral(&Simplex::new(mesh.dim, &vertices[..nodes.len()]), nodes)
                })
                .sum::<f64>()
        })
        .collect();
    blocks.iter().sum()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Isotropic;

    fn assembled_on(threads: usize, mesh: &Mesh, material: &Material) -> Matrices {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| assemble_matrices(mesh, material, &[0], 2.5))
    }

    /// The matrices of a sequential sweep over the cells that adds each cell's whole local
    /// matrices entry by entry (the assembly before the node-column sweep; `add` searches each
    /// entry), with the body's one material and the Robin term on part 0; then the Gram
    /// matrices of the norms, (ε(u), ε(v)) and (∇θ, ∇η), which the assembly no longer keeps.
    fn scattered_by_cells(mesh: &Mesh, material: &Material) -> Vec<CscMatrix> {
        let d = mesh.dim;
        let graph = NodeGraph::new(mesh.n_nodes(), &mesh.cells, mesh.nodes_per_cell());
        let (vector, scalar) = (CscMatrix::from_graph(&graph, d, d), CscMatrix::from_graph(&graph, 1, 1));
        let mut m = vec![
            vector.clone(),
            vector.clone(),
            vector.clone(),
            CscMatrix::from_graph(&graph, d, 1),
        ];
        m.extend([scalar.clone(), scalar.clone(), vector, scalar]);
        let gram = Isotropic {
            lambda: 0.0,
            two_mu: 1.0,
        };
        for e in 0..mesh.n_cells() {
            let t = Simplex::new(d, &mesh.cell_coords(e));
            let (mass, lap, div) = (
                kernels::scalar_mass(&t),
                kernels::laplacian(&t),
                kernels::divergence_coupling(&t),
            );
            let stiffness =
                [material.viscosity, material.elasticity, gram].map(|law| kernels::isotropic_stiffness(&t, law));
            let nodes = mesh.cell(e);
            for (b, &q) in nodes.iter().enumerate() {
                for (a, &p) in nodes.iter().enumerate() {
                    for i in 0..d {
                        m[0].add(p * d + i, q * d + i, material.density * mass[a][b]);
                        for j in 0..d {
                            for (mat, k) in [1, 2, 6].into_iter().zip(&stiffness) {
                                m[mat].add(p * d + i, q * d + j, k[a * d + i][b * d + j]);
                            }
                        }
                        m[3].add(p * d + i, q, material.expansion * div[a * d + i][b]);
                    }
                    m[4].add(p, q, material.density * material.heat_capacity * mass[a][b]);
                    m[5].add(p, q, material.conductivity * lap[a][b]);
                    m[7].add(p, q, lap[a][b]);
                }
            }
        }
        add_boundary_mass(mesh, &[0], 2.5, &mut m[5]);
        m
    }

    /// The meshes of the sweep tests: a rectangle and a box.
    fn test_meshes() -> [Mesh; 2] {
        [
            crate::mesh::rectangle(3.0, 1.0, 7, 3),
            crate::mesh::cuboid([1.0, 0.5, 0.5], [4, 2, 3]),
        ]
    }

    /// The material of the sweep tests, with the given heat capacity.
    fn test_material(heat_capacity: f64) -> Material {
        Material {
            density: 100.0,
            heat_capacity,
            viscosity: Isotropic::viscosity(100.0, 100.0),
            elasticity: Isotropic::elasticity(10_000.0, 0.3),
            expansion: Material::expansion_from(3e-4, 10_000.0, 0.3),
            conductivity: 0.1,
            reference_temperature: 0.0,
        }
    }

    /// The node-column sweep sums every entry as the sweep over the cells does, to the bit, in
    /// 2D and 3D: the cells of a node in increasing order, each cell's columns of the node.
    #[test]
    fn node_columns_are_the_sums_of_a_sweep_over_the_cells() {
        let material = test_material(1.3);
        for mesh in test_meshes() {
            let swept = assemble_matrices(&mesh, &material, &[0], 2.5);
            let reference = scattered_by_cells(&mesh, &material);
            let bits = |m: &CscMatrix| m.values.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            // ℳ = M_ρ ⊗ I_d: its entries read through the vector pattern, and its products,
            // are the vector matrix's bits.
            let (vector, mass) = (&reference[0], &swept.mass);
            assert_eq!(vector.row_idx, swept.viscosity.row_idx);
            let through: Vec<u64> = (0..vector.n_cols)
                .flat_map(|c| (0..vector.col_ptr[c + 1] - vector.col_ptr[c]).map(move |t| (c, t)))
                .map(|(c, t)| mass.column(c).entry(t).to_bits())
                .collect();
            assert_eq!(through, bits(vector), "mass, d = {}", mesh.dim);
            let x: Vec<f64> = (0..vector.n_cols)
                .map(|i| if i % 5 == 3 { 0.0 } else { (i as f64 * 0.37).sin() })
                .collect();
            let to_bits = |v: Vec<f64>| v.iter().map(|a| a.to_bits()).collect::<Vec<_>>();
            assert_eq!(to_bits(mass.mul(&x)), to_bits(vector.mul(&x)), "ℳx, d = {}", mesh.dim);
            assert_eq!(mass.quadratic_form(&x).to_bits(), vector.quadratic_form(&x).to_bits());
            for (name, (a, b)) in ["viscosity", "elasticity", "coupling", "heat mass", "conduction"]
                .iter()
                .zip(
                    [
                        &swept.viscosity,
                        &swept.elasticity,
                        &swept.coupling,
                        &swept.heat_mass,
                        &swept.conduction,
                    ]
                    .into_iter()
                    .zip(&reference[1..]),
                )
            {
                assert_eq!(a.row_idx, b.row_idx, "{name}");
                assert_eq!(bits(a), bits(b), "{name}, d = {}", mesh.dim);
                assert!(a.values.iter().any(|&v| v != 0.0), "{name}");
            }
        }
    }

    /// The same bits on 1, 2 and 3 threads, in 2D and 3D: a run does not depend on the machine.
    #[test]
    fn matrices_do_not_depend_on_the_thread_count() {
        let material = test_material(1.0);
        for mesh in test_meshes() {
            let one = assembled_on(1, &mesh, &material);
            for threads in [2, 3] {
                let many = assembled_on(threads, &mesh, &material);
                for (a, b) in [
                    (&one.mass.scalar, &many.mass.scalar),
                    (&one.viscosity, &many.viscosity),
                    (&one.elasticity, &many.elasticity),
                    (&one.coupling, &many.coupling),
                    (&one.heat_mass, &many.heat_mass),
                    (&one.conduction, &many.conduction),
                ] {
                    let bits = |m: &CscMatrix| m.values.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(a), bits(b), "{threads} threads");
                }
            }
            // M_ρ's entries sum to ρ|Ω|: the cells were all counted once.
            let total: f64 = one.mass.scalar.values.iter().sum();
            let volume: f64 = (0..mesh.n_cells())
                .map(|e| Simplex::new(mesh.dim, &mesh.cell_coords(e)).measure)
                .sum();
            assert!((total - material.density * volume).abs() < 1e-9 * total);
        }
    }

    /// The norms' sums over the cells are the quadratic forms of their Gram matrices, whose
    /// entries are the bits of the sweep that assembled them with the others before; in 2D and
    /// 3D, and the same bits on 1 and 3 threads.
    #[test]
    fn cell_sums_of_the_norms_are_the_gram_matrices_quadratic_forms() {
        let material = test_material(1.0);
        for mesh in test_meshes() {
            let reference = scattered_by_cells(&mesh, &material);
            let d = mesh.dim;
            let v: Vec<f64> = (0..mesh.n_nodes() * d)
                .map(|i| ((i * 37) % 11) as f64 - 5.0 + 0.1 * i as f64)
                .collect();
            let theta: Vec<f64> = (0..mesh.n_nodes()).map(|i| ((i * 13) % 7) as f64 * 0.3 - 1.0).collect();
            let strain = strain_norm(&mesh, &v);
            let gradient = gradient_norm(&mesh, &theta);
            let grams = NormGrams::assemble(&mesh);
            let bits = |m: &CscMatrix| m.values.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&grams.strain), bits(&reference[6]), "d = {d}");
            assert_eq!(bits(&grams.gradient), bits(&reference[7]), "d = {d}");
            assert!(
                (strain - grams.strain_norm(&v)).abs() <= 1e-13 * strain,
                "d = {d}: {strain}"
            );
            assert!(
                (gradient - grams.gradient_norm(&theta)).abs() <= 1e-13 * gradient,
                "d = {d}: {gradient}"
            );
            assert!(strain > 1.0 && gradient > 0.1);
            // A rigid motion has no strain: the symmetric part is taken.
            let rotation: Vec<f64> = (0..mesh.n_nodes())
                .flat_map(|p| {
                    let x = mesh.coords[p];
                    let mut r = vec![-x[1], x[0], 0.0];
                    r.truncate(d);
                    r
                })
                .collect();
            assert!(strain_norm(&mesh, &rotation) < 1e-12);
            let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
            let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
            assert_eq!(
                pool.install(|| strain_norm(&mesh, &v)).to_bits(),
                one.install(|| strain_norm(&mesh, &v)).to_bits()
            );
        }
    }
}
