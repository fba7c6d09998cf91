//! Simplicial meshes with named boundary parts.
//!
//! A [`Mesh`] is a conforming triangulation (d = 2) or tetrahedralization (d = 3) of Ω̄. Its
//! boundary facets (edges in 2D, triangles in 3D) carry the index of a named part (`left`,
//! `bottom`, …); a scenario maps parts to Γ_D, Γ_N and Γ_C.

mod structured;

pub use structured::{rectangle, rectangle_part_names};

/// A P1 simplicial mesh in d = 2 or 3 dimensions.
#[derive(Debug, Clone)]
pub struct Mesh {
    /// Space dimension d.
    pub dim: usize,
    /// Node coordinates; components beyond `dim` are zero.
    pub coords: Vec<[f64; 3]>,
    /// Cell connectivity, flat, `dim + 1` nodes per cell, positively oriented.
    pub cells: Vec<usize>,
    /// Boundary facet connectivity, flat, `dim` nodes per facet.
    pub facets: Vec<usize>,
    /// Boundary part index of each facet.
    pub facet_parts: Vec<usize>,
    /// Names of the boundary parts, indexed by part.
    pub part_names: Vec<String>,
}

impl Mesh {
    /// Nodes per cell (d + 1).
    pub fn nodes_per_cell(&self) -> usize {
        self.dim + 1
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.coords.len()
    }

    /// Number of cells.
    pub fn n_cells(&self) -> usize {
        self.cells.len() / self.nodes_per_cell()
    }

    /// Number of boundary facets.
    pub fn n_facets(&self) -> usize {
        self.facet_parts.len()
    }

    /// Node indices of cell `e`.
    pub fn cell(&self, e: usize) -> &[usize] {
        let npc = self.nodes_per_cell();
        &self.cells[e * npc..(e + 1) * npc]
    }

    /// Node indices of boundary facet `f`.
    pub fn facet(&self, f: usize) -> &[usize] {
        &self.facets[f * self.dim..(f + 1) * self.dim]
    }

    /// Index of the boundary part called `name`.
    pub fn part_index(&self, name: &str) -> Option<usize> {
        self.part_names.iter().position(|p| p == name)
    }

    /// Facets belonging to any of the given parts.
    pub fn facets_of(&self, parts: &[usize]) -> impl Iterator<Item = usize> + '_ {
        let parts = parts.to_vec();
        (0..self.n_facets()).filter(move |&f| parts.contains(&self.facet_parts[f]))
    }

    /// Marks every node lying on a facet of the given parts (the closure of their union).
    pub fn nodes_on(&self, parts: &[usize]) -> Vec<bool> {
        let mut on = vec![false; self.n_nodes()];
        for f in self.facets_of(parts) {
            for &i in self.facet(f) {
                on[i] = true;
            }
        }
        on
    }

    /// Coordinates of the vertices of cell `e`.
    pub fn cell_coords(&self, e: usize) -> Vec<[f64; 3]> {
        self.cell(e).iter().map(|&i| self.coords[i]).collect()
    }

    /// Measure |Ω| (sum of cell measures).
    pub fn volume(&self) -> f64 {
        (0..self.n_cells())
            .map(|e| crate::fem::simplex::Simplex::new(self.dim, &self.cell_coords(e)).measure)
            .sum()
    }
}
