//! A process's share of the problem's matrices in a distributed run: the columns its rows read,
//! assembled only while its step matrix is summed, and its cells.
//!
//! Rank r of a distributed run assembles the rows of the step matrix Ã at its own unknowns and
//! at Γ_C's (`crate::step`'s ranks), and forms the right-hand side in the same rows. Every one
//! of those rows is a sum over the columns of the row node's neighbours (the matrices are
//! stored by columns, and ℳ, 𝒦_A, 𝒦_B, 𝒦_θ are symmetric: `step_matrix` reads a row as its
//! column; G's row (p, ·) lies in the columns of p's neighbours). So a rank needs only the
//! columns of the **kept** nodes: its own, Γ_C's, and their neighbours (the nodes of the cells
//! that hold one of them), and a sum over those columns gives its rows of Ã to the bit.
//!
//! **What a rank keeps.** 𝒦_A, 𝒦_B and G hold 90 % of the six P1 matrices' values (9 + 9 + 3
//! per node pair in 3D, against 1 each for ℳ's scalar M_ρ, ℳ_θ and 𝒦_θ, which stay whole: their
//! pattern is the node graph by which the step matrix's rows are laid out, and the run's checks
//! weigh the rigid motions with ℳ). A rank keeps none of the three past the problem's build
//! (which takes the contact pressure's rows and the reference load from them): the step
//! matrix's sum assembles the kept columns for its while and drops them
//! ([`crate::fem::assembly::assemble_stiffness_columns`], the same bits), and the two other
//! users, the right-hand side's −𝒦_B U_{n−1} and the energies, are summed cell by cell from the
//! kernels ([`ColumnShare::stiffness_mul_add`],
//! [`ColumnShare::stiffness_forms`]): the same sums as the matrices', to rounding. One pass a
//! step serves both: the energies' pass over the cells also forms 𝒦_B U_n from the gradients
//! of u it takes, and the next step's right-hand side reads it from the state
//! ([`super::State::elastic_force`]; a product of its own only from a state made anew).
//!
//! **The energies** ([`crate::model::energy`]) are sums over cells and nodes. A rank sums the
//! stiffness forms over the cells whose lowest node it owns, ℳ's forms and the terms of G and
//! F over its **own** nodes, and one reduction over the ranks gives the totals
//! ([`ColumnShare::sum`]): each cell and each node counted once. The terms read from the whole
//! matrices and the laws on Γ_C are computed on every rank as before.
//!
//! Measured at 972k unknowns on 2 ranks: docs/distributed.md ("The problem's matrices by
//! columns", and "No stiffness kept on the ranks").

use super::error::ModelError;
use crate::fem::kernels;
use crate::material::{CellMaterials, Isotropic, Material};
use crate::mesh::simplex::Simplex;
use crate::mesh::Mesh;

/// The nodes whose columns of 𝒦_A, 𝒦_B and G a process reads, its cells, and the nodes and
/// cells whose terms it sums into the energies (module docs).
#[derive(Debug, Clone)]
pub struct ColumnShare {
    /// The nodes this process owns: their columns' terms are its part of the energies.
    owned: Vec<bool>,
    /// The nodes whose columns its rows read: its own, Γ_C's, and their neighbours.
    kept: Vec<bool>,
    /// The cells that hold one of its rows' nodes (its own and Γ_C's): a product over them is
    /// the whole product in those rows ([`ColumnShare::stiffness_mul_add`]).
    row_cells: Vec<u32>,
    /// How the parts of the energies are summed.
    sum: Sum,
}

/// How [`ColumnShare::sum`] adds the processes' parts.
#[derive(Debug, Clone, Copy)]
enum Sum {
    /// Not at all: this process's part alone (a share built for a test).
    Alone,
    /// Over the ranks of a distributed run.
    #[cfg(feature = "mpi")]
    Ranks(crate::la::mpi::Communicator),
}

impl ColumnShare {
    /// The share of a process owning the nodes `owned` on `mesh`, with the rows of Γ_C's nodes
    /// (`on_contact`) too; its sums are its own part alone (`ColumnShare::over_ranks` sums
    /// over the ranks).
    pub fn new(mesh: &Mesh, owned: Vec<bool>, on_contact: &[bool]) -> Self {
        let rows: Vec<bool> = owned.iter().zip(on_contact).map(|(&o, &c)| o || c).collect();
        let (kept, row_cells) = around(mesh, &rows);
        ColumnShare {
            owned,
            kept,
            row_cells,
            sum: Sum::Alone,
        }
    }

    /// The share whose [`ColumnShare::sum`] adds the parts of every rank of `comm`.
    #[cfg(feature = "mpi")]
    pub fn over_ranks(self, comm: crate::la::mpi::Communicator) -> Self {
        ColumnShare {
            sum: Sum::Ranks(comm),
            ..self
        }
    }

    /// Whether this process owns node p (its columns' terms are its part of the energies).
    #[inline]
    pub fn owns(&self, p: usize) -> bool {
        self.owned[p]
    }

    /// The number of nodes of the mesh.
    pub fn n_nodes(&self) -> usize {
        self.owned.len()
    }

    /// The nodes whose columns of 𝒦_A, 𝒦_B and G this process's rows read.
    pub fn kept(&self) -> &[bool] {
        &self.kept
    }

    /// Whether this process sums cell e into the energies: the owner of the cell's lowest node
    /// does, so each cell is summed once over the ranks.
    fn owns_cell(&self, mesh: &Mesh, e: usize) -> bool {
        mesh.cell(e).iter().min().is_some_and(|&p| self.owned[p])
    }

    /// y += α 𝒦 x in the rows of this process's own and Γ_C's nodes (full nodal dofs; the other
    /// rows get partial sums), 𝒦 the stiffness of `law` (`|m| m.viscosity`: 𝒦_A), summed
    /// cell by cell from the kernels (`fem::kernels::isotropic_stiffness_product`): the rows of the
    /// assembled product, to rounding, without the matrix.
    pub fn stiffness_mul_add(
        &self,
        (mesh, materials): (&Mesh, &CellMaterials),
        law: LawOf,
        alpha: f64,
        x: &[f64],
        y: &mut [f64],
    ) {
        let d = mesh.dim;
        for &e in &self.row_cells {
            let (t, nodes) = cell_simplex(mesh, e as usize);
            let kx = kernels::isotropic_stiffness_product(&t, law(materials.of(e as usize)), &nodal(d, nodes, x));
            add_nodal(d, nodes, alpha, &kx, y);
        }
    }

    /// This process's part of the forms x_aᵀ 𝒦 x_b of `forms` (law, a, b) over the vector fields
    /// `fields` (full nodal vectors), 𝒦 the stiffness of the law: the sums over the cells it
    /// owns (the owner of a cell's lowest node sums it) of ∫_T 𝒯ε(x_a) : ε(x_b)
    /// (`fem::kernels::isotropic_energy_density`, each field's gradient taken once a cell), to be
    /// summed over the ranks ([`ColumnShare::sum`]); the same pass, from the same gradients,
    /// also forms the [`RowProducts`] asked for.
    pub fn stiffness_forms<const N: usize, const F: usize>(
        &self,
        (mesh, materials): (&Mesh, &CellMaterials),
        fields: [&[f64]; N],
        forms: [(LawOf, usize, usize); F],
        RowProducts {
            mut coupling,
            mut product,
        }: RowProducts,
    ) -> [f64; F] {
        let d = mesh.dim;
        let mut sums = [0.0; F];
        let every_row_cell = coupling.is_some() || product.is_some();
        for e in self.row_cells.iter().map(|&e| e as usize) {
            let owned = self.owns_cell(mesh, e);
            if !owned && !every_row_cell {
                continue;
            }
            let (t, nodes) = cell_simplex(mesh, e);
            let material = materials.of(e);
            let grads = fields.map(|x| kernels::gradient_of(&t, &nodal(d, nodes, x)));
            if let Some((c, out)) = coupling.as_mut() {
                let div: f64 = (0..d).map(|i| grads[*c][i][i]).sum();
                let share = material.expansion * t.measure * div / (d + 1) as f64;
                nodes.iter().for_each(|&p| out[p] += share);
            }
            if let Some((law, c, out)) = product.as_mut() {
                let kx = kernels::isotropic_stiffness_product_of_gradient(&t, law(material), &grads[*c]);
                add_nodal(d, nodes, 1.0, &kx, out);
            }
            if owned {
                for (sum, &(law, a, b)) in sums.iter_mut().zip(&forms) {
                    *sum += t.measure * kernels::isotropic_energy_density(d, law(material), &grads[a], &grads[b]);
                }
            }
        }
        sums
    }

    /// This process's part of the forms x_aᵀ ℳ x_b of `forms` (a, b) over the vector fields
    /// `fields`: the rows of its own nodes, each (ℳ x_b)_p from M_ρ's column p (M_ρ is
    /// symmetric and whole on every process), to be summed over the ranks.
    pub fn mass_forms<const N: usize, const F: usize>(
        &self,
        mass: &crate::fem::assembly::VectorMass,
        fields: [&[f64]; N],
        forms: [(usize, usize); F],
    ) -> [f64; F] {
        let (m, d) = (&mass.scalar, mass.dim);
        let mut sums = [0.0; F];
        for p in (0..self.owned.len()).filter(|&p| self.owned[p]) {
            for (sum, &(a, b)) in sums.iter_mut().zip(&forms) {
                let (x, y) = (fields[a], fields[b]);
                let mut row = 0.0;
                for k in m.col_ptr[p]..m.col_ptr[p + 1] {
                    let q = m.row_idx[k] as usize;
                    let xy: f64 = (0..d).map(|j| x[p * d + j] * y[q * d + j]).sum();
                    row += m.values[k] * xy;
                }
                *sum += row;
            }
        }
        sums
    }

    /// `parts` summed over the processes, in place (collective over the ranks: every rank
    /// calls it at the same point with as many values).
    pub fn sum(&self, parts: &mut [f64]) -> Result<(), ModelError> {
        match self.sum {
            Sum::Alone => {
                let _ = parts;
                Ok(())
            }
            #[cfg(feature = "mpi")]
            Sum::Ranks(comm) => {
                comm.all_reduce_f64(parts, crate::la::mpi::Reduction::Sum)
                    .map_err(|e| ModelError::Ranks {
                        operation: "the sum of the energies over the ranks",
                        detail: e.to_string(),
                    })
            }
        }
    }
}

/// The nodes of the cells that hold one of the nodes `rows` (the columns those nodes' rows
/// read), and those cells.
fn around(mesh: &Mesh, rows: &[bool]) -> (Vec<bool>, Vec<u32>) {
    let mut kept = vec![false; mesh.n_nodes()];
    let mut cells = Vec::new();
    for e in 0..mesh.n_cells() {
        let nodes = mesh.cell(e);
        if nodes.iter().any(|&p| rows[p]) {
            nodes.iter().for_each(|&p| kept[p] = true);
            cells.push(crate::la::row_index(e));
        }
    }
    cells.shrink_to_fit();
    (kept, cells)
}

/// The nodes within `hops` hops of `nodes`, a node one hop from every node of a cell it is in:
/// the rows a rank assembles around Γ_C for the predicted bounds' condensation (its layers of
/// the body, `crate::step`'s `contact_condensation`).
pub fn nodes_within(mesh: &Mesh, nodes: Vec<bool>, hops: usize) -> Vec<bool> {
    (0..hops).fold(nodes, |nodes, _| columns_read_by(mesh, &nodes))
}

/// The columns that the rows of the nodes `rows` read: the nodes of the cells that hold one of
/// them (a share's own and Γ_C's rows, [`ColumnShare::kept`]; Γ_C's alone for the contact
/// pressure's rows).
pub(super) fn columns_read_by(mesh: &Mesh, rows: &[bool]) -> Vec<bool> {
    around(mesh, rows).0
}

/// The products that [`ColumnShare::stiffness_forms`]' pass forms along the forms, at the
/// process's own and Γ_C's nodes (the others partial), from every cell that holds one of those
/// nodes.
#[derive(Default)]
pub struct RowProducts<'o> {
    /// (c, out): Gᵀx_c in `out` (a vector of the mesh's nodes; each node of a cell gets
    /// c_T ∫_T div x_c / (d + 1)).
    pub coupling: Option<(usize, &'o mut [f64])>,
    /// (law, c, out): 𝒦 x_c added to `out` (a vector field), 𝒦 the stiffness of the law: the
    /// rows of [`ColumnShare::stiffness_mul_add`]'s product, each cell's the same numbers.
    pub product: Option<(LawOf, usize, &'o mut [f64])>,
}

/// Which of a material's isotropic laws a stiffness is of (`|m| m.viscosity`: 𝒦_A,
/// `|m| m.elasticity`: 𝒦_B).
pub type LawOf = fn(&Material) -> Isotropic;

/// Cell e as a simplex, with its nodes.
fn cell_simplex(mesh: &Mesh, e: usize) -> (Simplex, &[usize]) {
    let nodes = mesh.cell(e);
    let mut vertices = [[0.0; 3]; 4];
    nodes.iter().zip(&mut vertices).for_each(|(&p, v)| *v = mesh.coords[p]);
    (Simplex::new(mesh.dim, &vertices[..nodes.len()]), nodes)
}

/// y += α v at `nodes` of a full nodal vector field with d components a node (a cell's nodal
/// values `v[a]`, as [`nodal`] gathers them).
fn add_nodal(d: usize, nodes: &[usize], alpha: f64, v: &[[f64; 3]; 4], y: &mut [f64]) {
    for (a, &p) in nodes.iter().enumerate() {
        for i in 0..d {
            y[p * d + i] += alpha * v[a][i];
        }
    }
}

/// The nodal values at `nodes` of a full nodal vector field with d components a node.
fn nodal(d: usize, nodes: &[usize], v: &[f64]) -> [[f64; 3]; 4] {
    match d {
        2 => nodal_in::<2>(nodes, v),
        _ => nodal_in::<3>(nodes, v),
    }
}

/// [`nodal`] in D dimensions.
#[inline(always)]
fn nodal_in<const D: usize>(nodes: &[usize], v: &[f64]) -> [[f64; 3]; 4] {
    let mut out = [[0.0; 3]; 4];
    for (a, &p) in nodes.iter().enumerate().take(D + 1) {
        out[a][..D].copy_from_slice(&v[p * D..(p + 1) * D]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::samples::paper_3d_builder;
    use super::super::{ordered_rows, ordered_rows_at, step_energy, step_energy_and_elastic_force, Problem, State};

    /// A state with every field rough (not a solution: the energies are sums of its terms).
    fn rough_state(problem: &Problem, seed: usize, t: f64) -> State {
        let rough = |s: usize, len: usize| -> Vec<f64> {
            (0..len)
                .map(|i| (((i + s) * 7919) % 1000) as f64 / 500.0 - 1.0)
                .collect()
        };
        let mut state = State::initial(problem);
        state.t = t;
        state.w = problem.velocity.prolong(&rough(seed, problem.velocity.n_free));
        state.u = problem.velocity.prolong(&rough(seed + 1, problem.velocity.n_free));
        state.theta = rough(seed + 2, state.theta.len());
        state.xi = rough(seed + 3, state.xi.len());
        state
    }

    /// A share keeps none of 𝒦_A, 𝒦_B and G; its rows of the step matrix (its own nodes' and
    /// Γ_C's) are the whole problem's, bit for bit, from the columns it assembles for them;
    /// its rows of the right-hand side, summed over its cells, are the whole problem's to
    /// rounding; its energies' parts and the complementary share's add up to the whole
    /// problem's.
    #[test]
    fn a_share_has_the_rows_of_the_whole_and_half_the_energies() {
        let (cells, steps) = ([12, 2, 4], 16);
        let whole = paper_3d_builder(cells, steps).build().unwrap();
        let n_nodes = whole.mesh.n_nodes();
        let left: Vec<bool> = (0..n_nodes).map(|p| whole.mesh.coords[p][0] < 20.0).collect();
        let right: Vec<bool> = left.iter().map(|&l| !l).collect();
        let shares =
            [left.clone(), right].map(|owned| paper_3d_builder(cells, steps).owned_nodes(owned).build().unwrap());
        let share = &shares[0];
        let stored = |p: &Problem| {
            let m = &p.matrices;
            m.viscosity.nnz() + m.elasticity.nnz() + m.coupling.nnz()
        };
        assert!(
            stored(&whole) > 0 && stored(share) == 0,
            "{} of {}",
            stored(share),
            stored(&whole)
        );

        // Its rows: those of its own nodes and of Γ_C's.
        let k = whole.time_step();
        let n = whole.n_unknowns();
        let on_contact = whole.mesh.nodes_on(&whole.parts.contact);
        let mut rows = Vec::new();
        for p in (0..n_nodes).filter(|&p| left[p] || on_contact[p]) {
            rows.extend(whole.velocity.node_unknowns(p));
            rows.extend(whole.temperature.free[p].map(|r| whole.velocity.n_free + r));
        }
        rows.sort_unstable();
        let order: Vec<usize> = (0..n).collect();
        let (all, whole_rhs) = ordered_rows(&whole, k, &order);
        let (some, share_rhs) = ordered_rows_at(share, k, &order, &rows);
        let bits = |(c, v): (&[u32], &[f64])| (c.to_vec(), v.iter().map(|v| v.to_bits()).collect::<Vec<_>>());
        for &r in &rows {
            assert_eq!(bits(some.row(r)), bits(all.row(r)), "row {r}");
        }
        // The share's right-hand side (from `from`) in its rows: the whole problem's to rounding.
        let rows_agree = |b_share: &[f64], b_whole: &[f64], from: &str| {
            let scale = b_whole.iter().fold(0.0f64, |s, b| s.max(b.abs()));
            for &r in &rows {
                assert!(
                    (b_share[r] - b_whole[r]).abs() <= 1e-13 * scale,
                    "right-hand side row {r} {from}: {} against {}",
                    b_share[r],
                    b_whole[r]
                );
            }
        };
        let previous = rough_state(&whole, 1, 0.1875);
        let b_whole = whole_rhs.rhs(&whole, &previous, 0.25, None).unwrap();
        let b_share = share_rhs.rhs(share, &previous, 0.25, None).unwrap();
        rows_agree(&b_share, &b_whole, "from the cells");

        // The energies: the shared terms are parts, the others whole on each share.
        let state = rough_state(&whole, 5, 0.25);
        let total = step_energy(&whole, &previous, &state).unwrap();
        let [a, b] = [&shares[0], &shares[1]].map(|s| step_energy(s, &previous, &state).unwrap());
        let parts = |e: &crate::model::StepEnergy| {
            [
                e.kinetic,
                e.elastic,
                e.kinetic_change,
                e.elastic_change,
                e.numerical,
                e.viscous,
                e.thermal_stress,
                e.loads,
                e.heat_coupling,
                e.heat_dirichlet,
            ]
        };
        for ((x, y), t) in parts(&a).iter().zip(parts(&b)).zip(parts(&total)) {
            assert!((x + y - t).abs() <= 1e-12 * t.abs().max(1.0), "{x} + {y} against {t}");
        }
        for e in [&a, &b] {
            assert_eq!(e.frictional.to_bits(), total.frictional.to_bits());
            assert_eq!(e.thermal.to_bits(), total.thermal.to_bits());
            assert_eq!(e.heat_exchange.to_bits(), total.heat_exchange.to_bits());
        }

        // The elastic force the share's pass for the energies forms on the way is the next
        // step's −𝒦_B U_n: the right-hand side that reads it has the whole problem's rows.
        let (_, force) = step_energy_and_elastic_force(&whole, &previous, &state).unwrap();
        assert!(force.is_empty(), "the whole problem forms 𝒦_B U_n with its matrix");
        let (_, force) = step_energy_and_elastic_force(share, &previous, &state).unwrap();
        assert_eq!(force.len(), state.u.len());
        let b_whole = whole_rhs.rhs(&whole, &state, 0.3125, None).unwrap();
        let mut kept = state.clone();
        kept.elastic_force = force;
        let b_share = share_rhs.rhs(share, &kept, 0.3125, None).unwrap();
        rows_agree(&b_share, &b_whole, "from the kept force");
    }
}
