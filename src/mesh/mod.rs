//! Simplicial meshes with named boundary parts and named cell regions.
//!
//! A [`Mesh`] is a conforming triangulation (d = 2) or tetrahedralization (d = 3) of Ω̄. Its
//! boundary facets (edges in 2D, triangles in 3D) carry the index of a named part (`left`,
//! `bottom`, …); a scenario maps parts to Γ_D, Γ_N and Γ_C (and to symmetry planes). Its cells
//! may belong to named **cell regions** ([`CellRegion`]: a Gmsh physical group of dimension d,
//! e.g. a pad's `lining` and `backplate`), which a problem gives their own materials.
//!
//! **Why regions are lists of cells.** A region holds the sorted indices of its cells as `u32`:
//! 4 bytes per cell that is in a region, nothing for a mesh without regions (the generators'),
//! against 24–32 bytes per cell for the connectivity itself. Lists, rather than one region index
//! per cell, keep what the file says when a cell is in two physical groups (Gmsh allows it; a
//! problem that gives both groups a material refuses it, naming the cell) and need no marker
//! for a cell in no region. The problem turns the regions it uses into one small material
//! index per cell (`material::CellMaterials`).
//!
//! Generators: [`rectangle`] (triangles, parts `left`, `right`, `bottom`, `top`), [`cuboid`]
//! (tetrahedra, 6 per hexahedral cell by the Kuhn split, parts `x-`, `x+`, `y-`, `y+`, `z-`,
//! `z+`) and [`annulus`] (triangles, parts `inner`, `outer`), each with a `try_` variant that
//! returns what [`Mesh::new`] finds wrong (too elongated cells) as an error instead of panicking. Files: [`read_msh`] reads Gmsh
//! meshes (MSH 4.1 ASCII and binary, MSH 2.2 ASCII) with their physical groups as parts (dimension
//! d − 1) and cell regions (dimension d), and
//! [`msh_text`] writes one. Every mesh goes through the checks of [`Mesh::new`]. [`chains`]
//! orders 2D boundary curves (the outline, Γ_C) by arc length for figures.
//!
//! Depends on: [`crate::resources`] only (reading input files within limits, and the machine's
//! memory, which every constructor checks a mesh against before building it:
//! [`MeshError::TooLarge`]); the bottom layer.

mod annulus;
pub mod chains;
mod check;
mod cuboid;
mod gmsh;
mod overlap;
pub mod simplex;
mod structured;
pub(crate) mod topology;

pub use annulus::{annulus, annulus_part_names, try_annulus};
pub use check::{fits_in_memory, MeshError};
pub use cuboid::{cuboid, cuboid_part_names, try_cuboid};
pub use gmsh::{msh_text, read_msh};
pub use structured::{rectangle, rectangle_part_names, try_rectangle};

/// A P1 simplicial mesh in d = 2 or 3 dimensions.
#[derive(Debug, Clone)]
pub struct Mesh {
    /// Space dimension d.
    pub dim: usize,
    /// Node coordinates; components beyond `dim` are zero.
    pub coords: Vec<[f64; 3]>,
    /// Cell connectivity, flat, `dim + 1` nodes per cell, positively oriented.
    pub cells: Vec<usize>,
    /// Boundary facet connectivity, flat, `dim` nodes per facet, ordered so that the right-hand
    /// normal points out of Ω ([`Mesh::facet_normal`]).
    pub facets: Vec<usize>,
    /// Boundary part index of each facet.
    pub facet_parts: Vec<usize>,
    /// Names of the boundary parts, indexed by part.
    pub part_names: Vec<String>,
    /// The named cell regions (none for the generators' meshes); set by [`Mesh::with_regions`].
    pub regions: Vec<CellRegion>,
}

/// A named set of cells: a Gmsh physical group of dimension d.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CellRegion {
    /// The group's name (its tag as a decimal string when the file names it not).
    pub name: String,
    /// Its cells, ascending, each once.
    pub cells: Vec<u32>,
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

    /// Index of the cell region called `name`.
    pub fn region_index(&self, name: &str) -> Option<usize> {
        self.regions.iter().position(|r| r.name == name)
    }

    /// The names of the cell regions.
    pub fn region_names(&self) -> Vec<String> {
        self.regions.iter().map(|r| r.name.clone()).collect()
    }

    /// The mesh with the cell regions `regions` (replacing any it had): each region's cells are
    /// sorted and repeats dropped; a cell index out of range, a name given twice or a mesh of
    /// more than 2³² cells is an error.
    pub fn with_regions(mut self, mut regions: Vec<CellRegion>) -> Result<Mesh, MeshError> {
        let n_cells = self.n_cells();
        if !regions.is_empty() && u32::try_from(n_cells).is_err() {
            return Err(MeshError::Invalid(format!(
                "{n_cells} cells: cell regions index at most 2³² cells"
            )));
        }
        for (k, name) in regions.iter().map(|r| &r.name).enumerate() {
            if regions[..k].iter().any(|r| &r.name == name) {
                return Err(MeshError::Invalid(format!("the region name `{name}` appears twice")));
            }
        }
        for region in &mut regions {
            region.cells.sort_unstable();
            region.cells.dedup();
            if let Some(&e) = region.cells.last().filter(|&&e| e as usize >= n_cells) {
                return Err(MeshError::Invalid(format!(
                    "cell {e} of region `{}` out of range ({n_cells} cells)",
                    region.name
                )));
            }
        }
        self.regions = regions;
        Ok(self)
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

    /// The unit normal line of a flat boundary part (the sign is arbitrary): `None` if the part
    /// has no facets or its facets are not all parallel.
    pub fn part_normal(&self, part: usize) -> Option<[f64; 3]> {
        let mut normal: Option<[f64; 3]> = None;
        for f in self.facets_of(&[part]) {
            let x: Vec<[f64; 3]> = self.facet(f).iter().map(|&i| self.coords[i]).collect();
            let e = [x[1][0] - x[0][0], x[1][1] - x[0][1], x[1][2] - x[0][2]];
            let n = if self.dim == 2 {
                [-e[1], e[0], 0.0]
            } else {
                let g = [x[2][0] - x[0][0], x[2][1] - x[0][1], x[2][2] - x[0][2]];
                [
                    e[1] * g[2] - e[2] * g[1],
                    e[2] * g[0] - e[0] * g[2],
                    e[0] * g[1] - e[1] * g[0],
                ]
            };
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let n = n.map(|c| c / len);
            match normal {
                None => normal = Some(n),
                Some(m) => {
                    // Parallel: |n · m| = 1 up to round-off.
                    if (n[0] * m[0] + n[1] * m[1] + n[2] * m[2]).abs() < 1.0 - 1e-9 {
                        return None;
                    }
                }
            }
        }
        normal
    }

    /// The normal of facet `f` by the right-hand rule on its node order, scaled by the facet's
    /// measure (2D: the edge x₀x₁ turned by −90°; 3D: ½ (x₁ − x₀) × (x₂ − x₀)). Boundary facets
    /// are stored oriented, so this points out of Ω.
    pub fn facet_area_vector(&self, f: usize) -> [f64; 3] {
        let x: Vec<[f64; 3]> = self.facet(f).iter().map(|&i| self.coords[i]).collect();
        let e = [x[1][0] - x[0][0], x[1][1] - x[0][1], x[1][2] - x[0][2]];
        if self.dim == 2 {
            [e[1], -e[0], 0.0]
        } else {
            let g = [x[2][0] - x[0][0], x[2][1] - x[0][1], x[2][2] - x[0][2]];
            [
                0.5 * (e[1] * g[2] - e[2] * g[1]),
                0.5 * (e[2] * g[0] - e[0] * g[2]),
                0.5 * (e[0] * g[1] - e[1] * g[0]),
            ]
        }
    }

    /// The measure of facet `f` (length in 2D, area in 3D).
    pub fn facet_measure(&self, f: usize) -> f64 {
        let a = self.facet_area_vector(f);
        (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
    }

    /// The unit outward normal ν of boundary facet `f`.
    pub fn facet_normal(&self, f: usize) -> [f64; 3] {
        let a = self.facet_area_vector(f);
        let len = self.facet_measure(f);
        a.map(|c| c / len)
    }

    /// Measure |Ω| (sum of cell measures).
    pub fn volume(&self) -> f64 {
        (0..self.n_cells())
            .map(|e| crate::mesh::simplex::Simplex::new(self.dim, &self.cell_coords(e)).measure)
            .sum()
    }
}
