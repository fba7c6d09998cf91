//! A process's share of the problem's matrices in a distributed run: the columns its rows read.
//!
//! Rank r of a distributed run assembles the rows of the step matrix Ã at its own unknowns and
//! at Γ_C's (`crate::step`'s ranks), and forms the right-hand side in the same rows. Every one
//! of those rows is a sum over the columns of the row node's neighbours (the matrices are
//! stored by columns, and ℳ, 𝒦_A, 𝒦_B, 𝒦_θ are symmetric: `step_matrix` reads a row as its
//! column; G's row (p, ·) lies in the columns of p's neighbours). So a rank needs only the
//! columns of the **kept** nodes: its own, Γ_C's, and their neighbours (the nodes of the cells
//! that hold one of them), and a product over those columns gives its rows to the bit. Of the
//! six P1 matrices it keeps 𝒦_A, 𝒦_B and G so ([`crate::fem::assembly::assemble_columns`]): they hold
//! 90 % of the values (9 + 9 + 3 per node pair in 3D, against 1 each for ℳ's scalar M_ρ, ℳ_θ
//! and 𝒦_θ, which stay whole: their pattern is the node graph by which the step matrix's rows
//! are laid out, and the run's checks weigh the rigid motions with ℳ).
//!
//! **The energies** ([`crate::model::energy`]) are sums over columns and nodes. A rank sums the
//! terms that read the kept matrices over its **own** nodes only, and one reduction over the
//! ranks gives the totals ([`ColumnShare::sum`]): each column counted once. The terms read from
//! the whole matrices and the laws on Γ_C are computed on every rank as before.
//!
//! Measured at 972k unknowns on 2 ranks: docs/distributed.md ("The problem's matrices by
//! columns").

use super::error::ModelError;
use crate::mesh::Mesh;

/// The nodes whose columns of 𝒦_A, 𝒦_B and G a process holds, and those whose terms it sums
/// into the energies (module docs).
#[derive(Debug, Clone)]
pub struct ColumnShare {
    /// The nodes this process owns: their columns' terms are its part of the energies.
    owned: Vec<bool>,
    /// The nodes whose columns it holds: its own, Γ_C's, and their neighbours.
    kept: Vec<bool>,
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
        let mut kept = vec![false; mesh.n_nodes()];
        for e in 0..mesh.n_cells() {
            let nodes = mesh.cell(e);
            if nodes.iter().any(|&p| rows[p]) {
                nodes.iter().for_each(|&p| kept[p] = true);
            }
        }
        ColumnShare {
            owned,
            kept,
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

    /// The nodes whose columns of 𝒦_A, 𝒦_B and G this process holds.
    pub fn kept(&self) -> &[bool] {
        &self.kept
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

#[cfg(test)]
mod tests {
    use super::super::samples::paper_3d_builder;
    use super::super::{ordered_rows, ordered_rows_at, step_energy, Problem, State};

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

    /// A share's rows of the step matrix and of the right-hand side (its own nodes' and
    /// Γ_C's) are the whole problem's, bit for bit, from fewer stored values; its energies'
    /// parts and the complementary share's add up to the whole problem's.
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
        let stored = |p: &Problem| p.matrices.viscosity.nnz() + p.matrices.coupling.nnz();
        assert!(
            stored(share) < 4 * stored(&whole) / 5,
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
        let previous = rough_state(&whole, 1, 0.1875);
        let b_whole = whole_rhs.rhs(&whole, &previous, 0.25, None).unwrap();
        let b_share = share_rhs.rhs(share, &previous, 0.25, None).unwrap();
        for &r in &rows {
            assert_eq!(b_share[r].to_bits(), b_whole[r].to_bits(), "right-hand side row {r}");
        }

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
    }
}
