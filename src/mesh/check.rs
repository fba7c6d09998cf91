//! The checked constructor of [`Mesh`] and the errors of meshes: what a mesh must be for the
//! P1 spaces to make sense, stated once for generated, read and user-built meshes.

use std::path::PathBuf;

use super::{overlap, topology, Mesh};
use crate::mesh::simplex::Simplex;

/// What is wrong with a mesh or a mesh file. Every variant says what and where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// The file cannot be read.
    #[error("cannot read the mesh file {}: {message}", path.display())]
    Read { path: PathBuf, message: String },
    /// The file is not a Gmsh mesh, or a version this reader does not read.
    #[error("{}: {message}", path.display())]
    Format { path: PathBuf, message: String },
    /// A section of the file is truncated or garbled.
    #[error("{}: section ${section}: {message}", path.display())]
    Section {
        path: PathBuf,
        section: String,
        message: String,
    },
    /// An element type thermocontact does not solve on.
    #[error(
        "{}: element type {code} ({name}) in a {dim}D mesh: thermocontact solves on linear \
         triangles (2D) and tetrahedra (3D) with their boundary lines and triangles; {advice}",
        path.display()
    )]
    UnsupportedElement {
        path: PathBuf,
        code: u32,
        name: String,
        dim: usize,
        advice: String,
    },
    /// Something about the mesh as a whole (its dimension, coordinates, sizes).
    #[error("invalid mesh: {0}")]
    Invalid(String),
    /// A cell of (almost) zero measure.
    #[error("cell {cell} is degenerate (measure {measure:e}, vertices {vertices:?})")]
    Degenerate {
        cell: usize,
        measure: f64,
        vertices: Vec<[f64; 3]>,
    },
    /// Nodes that no cell uses.
    #[error("{count} node(s) belong to no cell, e.g. node {first} at {at:?}")]
    UnusedNodes { count: usize, first: usize, at: [f64; 3] },
    /// A face shared by more than two cells.
    #[error("the face {facet:?} is shared by the cells {cells:?} (more than two: not a manifold mesh)")]
    NonManifold { facet: Vec<[f64; 3]>, cells: Vec<usize> },
    /// Two cells on the same side of their common face: one is inverted, or they overlap.
    #[error("cells {} and {} lie on the same side of their common face {facet:?}: a cell is inverted or they overlap", cells[0], cells[1])]
    Tangled { cells: [usize; 2], facet: Vec<[f64; 3]> },
    /// Two cells that share no face overlap: the centre of one lies inside the other.
    #[error(
        "the centre {at:?} of cell {} lies inside cell {}: cells overlap without sharing a face (a cell laid across others, or a volume meshed twice)",
        cells[0], cells[1]
    )]
    Overlapping { cells: [usize; 2], at: [f64; 3] },
    /// A boundary-part facet inside the domain.
    #[error("a facet of part `{part}` lies inside the domain (between two cells), at {facet:?}")]
    FacetInside { part: String, facet: Vec<[f64; 3]> },
    /// A boundary-part facet that is the face of no cell.
    #[error("a facet of part `{part}` is the face of no cell, at {facet:?}")]
    FacetOnNoCell { part: String, facet: Vec<[f64; 3]> },
    /// A mesh too large for the machine's memory, refused before it is built ([`fits_in_memory`]).
    #[error(
        "{what}: {nodes} nodes and {cells} cells need about {needed} of memory to build, but this \
         machine has {available}: use fewer cells"
    )]
    TooLarge {
        /// The mesh asked for: "a rectangle of 100000 × 100000 cells", "a mesh of 3 nodes".
        what: String,
        nodes: usize,
        cells: usize,
        needed: String,
        available: String,
    },
}

/// Bytes that building a mesh takes per node: its coordinates and the per-node flags of the
/// checks, rounded up.
const BYTES_PER_NODE: f64 = 32.0;

/// Bytes per cell vertex: its node index (8), and its face in the sorted face list of
/// [`topology::cell_faces`] (40 bytes, part of them held twice during the parallel collect).
/// Measured (growth of the peak resident memory, ru_maxrss): 340 bytes per node for a rectangle
/// of 700 × 700 cells (2 triangles per node), 1.25 kB for a box of 40³ (6 tetrahedra per node);
/// the estimate is 20–25 % above, 416 and 1 568.
const BYTES_PER_CELL_VERTEX: f64 = 64.0;

/// Refuses a mesh of `nodes` nodes and `cells` cells in `dim` dimensions whose building would
/// need more memory than the machine has ([`crate::resources::machine_memory`]): the one check
/// of every constructor, called by the generators before they allocate anything and by
/// [`Mesh::new`] before its face lists. Without it a request of 10¹⁰ nodes aborts the process
/// (a failed allocation is not an error in Rust), and a Python interpreter with it. `what` names
/// the mesh in the error. Nothing is allocated here.
pub fn fits_in_memory(what: &str, dim: usize, nodes: usize, cells: usize) -> Result<(), MeshError> {
    let needed = BYTES_PER_NODE * nodes as f64 + BYTES_PER_CELL_VERTEX * (dim + 1) as f64 * cells as f64;
    // Without /proc/meminfo, the bound of the scenario's check: one no machine passes.
    let available = crate::resources::machine_memory().unwrap_or(1e15);
    if needed > available {
        return Err(MeshError::TooLarge {
            what: what.to_string(),
            nodes,
            cells,
            needed: crate::resources::human(needed),
            available: crate::resources::human(available),
        });
    }
    Ok(())
}

impl MeshError {
    /// The error with the file it came from (for errors found after reading).
    pub(crate) fn in_file(self, path: &std::path::Path) -> MeshError {
        match self {
            MeshError::Read { .. } | MeshError::Format { .. } | MeshError::Section { .. } => self,
            MeshError::UnsupportedElement { .. } => self,
            other => MeshError::Format {
                path: path.to_path_buf(),
                message: other.to_string(),
            },
        }
    }
}

/// Whether [`Mesh::checked`] searches for cells that overlap without a common face.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Overlaps {
    Search,
    /// For the generators, whose cells tile their shape by construction.
    Skip,
}

impl Mesh {
    /// A mesh from its parts, checked: d = 2 or 3; finite coordinates (z = 0 in 2D); cells of
    /// d + 1 and facets of d valid node indices; no degenerate cell; every node in some cell; every
    /// face shared by at most two cells, lying on opposite sides of it (no inverted or
    /// overlapping cells); no cell's centre inside another cell (overlaps without a common
    /// face); every boundary-part facet the face of exactly one cell; distinct part names. The
    /// boundary facets are then oriented outward. Cells may have either orientation.
    pub fn new(
        dim: usize,
        coords: Vec<[f64; 3]>,
        cells: Vec<usize>,
        facets: Vec<usize>,
        facet_parts: Vec<usize>,
        part_names: Vec<String>,
    ) -> Result<Mesh, MeshError> {
        Self::checked(dim, coords, cells, facets, facet_parts, part_names, Overlaps::Search)
    }

    /// [`Mesh::new`], or for the generators' meshes without the overlap search (about 1 s at
    /// 10⁶ tetrahedra): their cells tile the box or the ring by construction, and their meshes
    /// pass the search in its tests (`overlap::tests`). Every other check runs.
    pub(super) fn checked(
        dim: usize,
        coords: Vec<[f64; 3]>,
        cells: Vec<usize>,
        facets: Vec<usize>,
        facet_parts: Vec<usize>,
        part_names: Vec<String>,
        overlaps: Overlaps,
    ) -> Result<Mesh, MeshError> {
        let invalid = |message: String| Err(MeshError::Invalid(message));
        if dim != 2 && dim != 3 {
            return invalid(format!("dimension {dim}: expected 2 or 3"));
        }
        let n_cells = cells.len() / (dim + 1);
        fits_in_memory("the mesh", dim, coords.len(), n_cells)?;
        if let Some(p) = coords.iter().position(|x| x.iter().any(|c| !c.is_finite())) {
            return invalid(format!("node {p} has non-finite coordinates {:?}", coords[p]));
        }
        if dim == 2 {
            if let Some(p) = coords.iter().position(|x| x[2] != 0.0) {
                return invalid(format!("node {p} of a 2D mesh is off the plane z = 0: {:?}", coords[p]));
            }
        }
        if cells.is_empty() || !cells.len().is_multiple_of(dim + 1) {
            return invalid(format!(
                "{} cell node indices: expected a positive multiple of {}",
                cells.len(),
                dim + 1
            ));
        }
        if facets.len() != dim * facet_parts.len() {
            return invalid(format!(
                "{} facet node indices for {} facets of {dim} nodes",
                facets.len(),
                facet_parts.len()
            ));
        }
        if let Some(&p) = cells.iter().chain(&facets).find(|&&p| p >= coords.len()) {
            return invalid(format!("node index {p} out of range ({} nodes)", coords.len()));
        }
        if let Some(&part) = facet_parts.iter().find(|&&q| q >= part_names.len()) {
            return invalid(format!("facet part {part} out of range ({} parts)", part_names.len()));
        }
        for (i, name) in part_names.iter().enumerate() {
            if part_names[..i].contains(name) {
                return invalid(format!("the part name `{name}` appears twice"));
            }
        }
        let mut mesh = Mesh {
            dim,
            coords,
            cells,
            facets,
            facet_parts,
            part_names,
            regions: Vec::new(),
        };
        mesh.check_cells()?;
        let faces = topology::cell_faces(&mesh);
        topology::check_cells(&mesh, &faces)?;
        if overlaps == Overlaps::Search {
            overlap::check_overlap(&mesh)?;
        }
        topology::orient_boundary(&mut mesh, &faces)?;
        Ok(mesh)
    }

    /// No degenerate cell, and every node in some cell.
    fn check_cells(&self) -> Result<(), MeshError> {
        let d = self.dim;
        let mut used = vec![false; self.n_nodes()];
        for e in 0..self.n_cells() {
            let vertices = self.cell_coords(e);
            let measure = Simplex::new(d, &vertices).measure;
            let mut longest: f64 = 0.0;
            for (a, x) in vertices.iter().enumerate() {
                for y in &vertices[a + 1..] {
                    longest =
                        longest.max(((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt());
                }
            }
            // (NaN measures fail too.)
            if measure.is_nan() || measure <= 1e-12 * longest.powi(d as i32) {
                return Err(MeshError::Degenerate {
                    cell: e,
                    measure,
                    vertices,
                });
            }
            self.cell(e).iter().for_each(|&p| used[p] = true);
        }
        let unused: Vec<usize> = (0..self.n_nodes()).filter(|&p| !used[p]).collect();
        if let Some(&first) = unused.first() {
            return Err(MeshError::UnusedNodes {
                count: unused.len(),
                first,
                at: self.coords[first],
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shared size check: a mesh of the examples passes, one of 10¹² nodes does not, and
    /// its error says what was asked for and how much it needs (issue 26).
    #[test]
    fn meshes_beyond_the_memory_are_refused_by_their_size() {
        assert!(fits_in_memory("a box", 3, 300_000, 1_700_000).is_ok());
        let e = fits_in_memory("the mesh", 3, 1 << 40, 6 << 40).unwrap_err();
        assert!(
            matches!(e, MeshError::TooLarge { nodes, .. } if nodes == 1 << 40),
            "{e}"
        );
        let message = e.to_string();
        assert!(message.starts_with("the mesh: 1099511627776 nodes"), "{message}");
        assert!(
            message.contains("GiB") && message.contains("use fewer cells"),
            "{message}"
        );
    }

    fn square() -> (Vec<[f64; 3]>, Vec<usize>) {
        let coords = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        (coords, vec![0, 1, 2, 0, 2, 3])
    }

    #[test]
    fn a_valid_mesh_is_accepted_and_its_facets_turned_outward() {
        let (coords, cells) = square();
        // The bottom edge given clockwise (inward normal): it comes back turned.
        let mesh = Mesh::new(2, coords, cells, vec![1, 0], vec![0], vec!["bottom".into()]).unwrap();
        assert_eq!(mesh.facet_normal(0), [0.0, -1.0, 0.0]);
    }

    #[test]
    fn bad_meshes_are_refused_naming_what_and_where() {
        let (coords, cells) = square();
        let mut flat = coords.clone();
        flat[2] = [2.0, 0.0, 0.0]; // on the line through nodes 0 and 1: cell 0 has zero area
        let e = Mesh::new(2, flat, cells.clone(), vec![], vec![], vec![]).unwrap_err();
        assert!(matches!(e, MeshError::Degenerate { cell: 0, .. }), "{e}");

        let mut extra = coords.clone();
        extra.push([5.0, 5.0, 0.0]);
        let e = Mesh::new(2, extra, cells.clone(), vec![], vec![], vec![]).unwrap_err();
        assert!(matches!(e, MeshError::UnusedNodes { count: 1, first: 4, .. }), "{e}");

        // Two triangles on the same side of the diagonal 0–2: overlapping.
        let mut folded = coords.clone();
        folded[3] = [0.6, 0.2, 0.0];
        let e = Mesh::new(2, folded, cells.clone(), vec![], vec![], vec![]).unwrap_err();
        assert!(matches!(e, MeshError::Tangled { .. }), "{e}");

        let e = Mesh::new(
            2,
            coords.clone(),
            cells.clone(),
            vec![0, 2],
            vec![0],
            vec!["cut".into()],
        )
        .unwrap_err();
        assert!(
            e.to_string().contains("`cut`") && e.to_string().contains("inside"),
            "{e}"
        );

        let mut lifted = coords;
        lifted[1][2] = 1.0;
        let e = Mesh::new(2, lifted, cells, vec![], vec![], vec![]).unwrap_err();
        assert!(e.to_string().contains("z = 0"), "{e}");
    }

    #[test]
    fn a_face_of_three_cells_is_not_a_manifold() {
        let coords = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -1.0, 0.0],
            [0.5, 2.0, 0.0],
        ];
        let e = Mesh::new(2, coords, vec![0, 1, 2, 0, 1, 3, 0, 1, 4], vec![], vec![], vec![]).unwrap_err();
        assert!(matches!(e, MeshError::NonManifold { .. }), "{e}");
    }
}
