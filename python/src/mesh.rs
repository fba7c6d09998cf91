//! `thermocontact.Mesh`: a simplicial mesh with named boundary parts, from NumPy arrays, a Gmsh
//! file or a generator, always through the core's checks (`Mesh::new`).

use std::path::PathBuf;
use std::sync::Arc;

use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, PyArray, PyArray2, PyArrayLike2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use thermocontact::mesh::{self, Mesh};

use crate::errors;

/// A triangle (2D) or tetrahedron (3D) mesh with named boundary parts.
///
/// Mesh(points, cells, boundary=None)
///
/// points   -- (n, d) float array of node coordinates (a 2D mesh may give (n, 3) with z = 0);
/// cells    -- (m, d + 1) integer array of node indices (0-based), triangles or tetrahedra, in
///             either orientation; d is taken from its width;
/// boundary -- dict: part name -> (f, d) integer array of boundary facets (edges in 2D,
///             triangles in 3D), in any orientation; the names are what a scenario's
///             `boundary.*` keys and tractions refer to.
///
/// The mesh is checked as the command line checks a Gmsh file: degenerate, inverted or
/// overlapping cells, nodes in no cell, boundary facets inside the domain or on no cell are
/// errors (MeshError) that say what and where. Boundary facets are stored oriented outward.
/// Also: Mesh.read(path) for a Gmsh .msh file, Mesh.from_meshio(m) for a meshio/pygmsh mesh,
/// Mesh.rectangle / Mesh.box / Mesh.annulus for the built-in generators.
#[pyclass(name = "Mesh", module = "thermocontact", frozen)]
pub struct PyMesh {
    pub inner: Arc<Mesh>,
}

impl PyMesh {
    pub fn wrap(mesh: Mesh) -> Self {
        PyMesh { inner: Arc::new(mesh) }
    }
}

/// Node indices of an integer array, each checked non-negative; `what` names the array.
fn indices(py: Python<'_>, array: &PyArrayLike2<'_, i64, AllowTypeChange>, what: &str) -> PyResult<Vec<usize>> {
    let view = array.as_array();
    view.iter()
        .map(|&i| {
            usize::try_from(i).map_err(|_| {
                errors::mesh_error(py, mesh::MeshError::Invalid(format!("{what}: negative node index {i}")))
            })
        })
        .collect()
}

fn invalid(py: Python<'_>, message: String) -> PyErr {
    errors::mesh_error(py, mesh::MeshError::Invalid(message))
}

#[pymethods]
impl PyMesh {
    #[new]
    #[pyo3(signature = (points, cells, boundary = None))]
    fn new(
        py: Python<'_>,
        points: PyArrayLike2<'_, f64, AllowTypeChange>,
        cells: PyArrayLike2<'_, i64, AllowTypeChange>,
        boundary: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let nodes_per_cell = cells.shape()[1];
        let dim = nodes_per_cell.wrapping_sub(1);
        if dim != 2 && dim != 3 {
            return Err(invalid(
                py,
                format!(
                    "cells: shape {:?}, expected (m, 3) triangles or (m, 4) tetrahedra",
                    cells.shape()
                ),
            ));
        }
        let width = points.shape()[1];
        if width != dim && width != 3 {
            return Err(invalid(
                py,
                format!(
                    "points: shape {:?}, expected (n, {dim}) for {}",
                    points.shape(),
                    if dim == 2 {
                        "triangles (or (n, 3) with z = 0)"
                    } else {
                        "tetrahedra"
                    }
                ),
            ));
        }
        let coords: Vec<[f64; 3]> = points
            .as_array()
            .rows()
            .into_iter()
            .map(|row| {
                let mut x = [0.0; 3];
                x[..width].copy_from_slice(&row.to_vec());
                x
            })
            .collect();
        let cells = indices(py, &cells, "cells")?;
        let (mut facets, mut facet_parts, mut part_names) = (Vec::new(), Vec::new(), Vec::new());
        if let Some(boundary) = boundary {
            for (name, array) in boundary.iter() {
                let name: String = name
                    .extract()
                    .map_err(|_| invalid(py, format!("boundary: part name {name}, expected a string")))?;
                let array: PyArrayLike2<'_, i64, AllowTypeChange> = array.extract().map_err(|e| {
                    invalid(
                        py,
                        format!("boundary[{name:?}]: expected a (f, {dim}) integer array of facets ({e})"),
                    )
                })?;
                if array.shape()[1] != dim {
                    return Err(invalid(
                        py,
                        format!(
                            "boundary[{name:?}]: shape {:?}, expected (f, {dim}): {dim} nodes per boundary facet",
                            array.shape()
                        ),
                    ));
                }
                let part = part_names.len();
                let nodes = indices(py, &array, &format!("boundary[{name:?}]"))?;
                facet_parts.extend(std::iter::repeat_n(part, nodes.len() / dim));
                facets.extend(nodes);
                part_names.push(name);
            }
        }
        let mesh = py
            .detach(|| Mesh::new(dim, coords, cells, facets, facet_parts, part_names))
            .map_err(|e| errors::mesh_error(py, e))?;
        Ok(PyMesh::wrap(mesh))
    }

    /// Mesh.read(path) -> Mesh: a Gmsh mesh (MSH 4.1 ASCII or binary, MSH 2.2 ASCII; linear
    /// triangles or tetrahedra); its boundary parts are the physical groups of dimension d − 1.
    #[staticmethod]
    fn read(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let mesh = py
            .detach(|| mesh::read_msh(&path))
            .map_err(|e| errors::mesh_error(py, e))?;
        Ok(PyMesh::wrap(mesh))
    }

    /// Mesh.from_meshio(m, prune=True) -> Mesh: a meshio.Mesh (as read by meshio or made by
    /// pygmsh). Cells are its triangle blocks (2D) or tetra blocks (3D); boundary parts are its
    /// named sets of facets: `cell_sets` (pygmsh, meshio ≥ 5) or else the Gmsh physical groups
    /// (`field_data` with `cell_data["gmsh:physical"]`). With prune, nodes in no cell (Gmsh's
    /// geometry points) are dropped and the rest renumbered.
    #[staticmethod]
    #[pyo3(signature = (mesh, prune = true))]
    fn from_meshio<'py>(py: Python<'py>, mesh: &Bound<'py, PyAny>, prune: bool) -> PyResult<Bound<'py, PyAny>> {
        py.import("thermocontact._meshio")?
            .call_method1("from_meshio", (mesh, prune))
    }

    /// Mesh.rectangle(lx, ly, nx, ny) -> Mesh: (0, lx) × (0, ly) in nx × ny cells, each cut
    /// into two triangles; parts "left", "right", "bottom", "top" (the default scenario's mesh).
    #[staticmethod]
    fn rectangle(py: Python<'_>, lx: f64, ly: f64, nx: usize, ny: usize) -> PyResult<Self> {
        if !(lx > 0.0 && ly > 0.0 && nx > 0 && ny > 0) {
            return Err(invalid(
                py,
                format!("rectangle({lx}, {ly}, {nx}, {ny}): expected positive lengths and cell counts"),
            ));
        }
        mesh::try_rectangle(lx, ly, nx, ny)
            .map(PyMesh::wrap)
            .map_err(|e| errors::mesh_error(py, e))
    }

    /// Mesh.box(lengths, cells) -> Mesh: the box (0, L₁) × (0, L₂) × (0, L₃) in n₁ × n₂ × n₃
    /// hexahedra of 6 tetrahedra each; parts "x-", "x+", "y-", "y+", "z-", "z+".
    #[staticmethod]
    #[pyo3(name = "box")]
    fn cuboid(py: Python<'_>, lengths: [f64; 3], cells: [usize; 3]) -> PyResult<Self> {
        if !(lengths.iter().all(|&l| l > 0.0) && cells.iter().all(|&n| n > 0)) {
            return Err(invalid(
                py,
                format!("box({lengths:?}, {cells:?}): expected positive lengths and cell counts"),
            ));
        }
        mesh::try_cuboid(lengths, cells)
            .map(PyMesh::wrap)
            .map_err(|e| errors::mesh_error(py, e))
    }

    /// Mesh.annulus(inner_radius, outer_radius, n_radial, n_around) -> Mesh: a ring of
    /// triangles; parts "inner", "outer".
    #[staticmethod]
    fn annulus(
        py: Python<'_>,
        inner_radius: f64,
        outer_radius: f64,
        n_radial: usize,
        n_around: usize,
    ) -> PyResult<Self> {
        if !(inner_radius > 0.0 && outer_radius > inner_radius && n_radial > 0 && n_around >= 3) {
            return Err(invalid(
                py,
                format!(
                    "annulus({inner_radius}, {outer_radius}, {n_radial}, {n_around}): expected 0 < inner < outer, \
                     n_radial ≥ 1, n_around ≥ 3"
                ),
            ));
        }
        mesh::try_annulus(inner_radius, outer_radius, n_radial, n_around)
            .map(PyMesh::wrap)
            .map_err(|e| errors::mesh_error(py, e))
    }

    /// Space dimension d (2 or 3).
    #[getter]
    fn dim(&self) -> usize {
        self.inner.dim
    }

    /// Number of nodes.
    #[getter]
    fn n_nodes(&self) -> usize {
        self.inner.n_nodes()
    }

    /// Number of cells.
    #[getter]
    fn n_cells(&self) -> usize {
        self.inner.n_cells()
    }

    /// Number of boundary facets (over all parts).
    #[getter]
    fn n_facets(&self) -> usize {
        self.inner.n_facets()
    }

    /// Names of the boundary parts, in part order.
    #[getter]
    fn part_names(&self) -> Vec<String> {
        self.inner.part_names.clone()
    }

    /// (n, d) float64 array of node coordinates (a new array).
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let d = self.inner.dim;
        let flat: Vec<f64> = self.inner.coords.iter().flat_map(|x| x[..d].to_vec()).collect();
        matrix(py, flat, d)
    }

    /// (m, d + 1) int64 array of cell node indices, as the core stores them (a new array).
    #[getter]
    fn cells<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let flat = self.inner.cells.iter().map(|&i| i as i64).collect();
        matrix(py, flat, self.inner.dim + 1)
    }

    /// dict: part name -> (f, d) int64 array of its boundary facets, oriented so that the
    /// right-hand normal points out of the domain (new arrays).
    #[getter]
    fn boundary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let mesh = &self.inner;
        let dict = PyDict::new(py);
        for (part, name) in mesh.part_names.iter().enumerate() {
            let flat: Vec<i64> = mesh
                .facets_of(&[part])
                .flat_map(|f| mesh.facet(f).iter().map(|&i| i as i64).collect::<Vec<_>>())
                .collect();
            dict.set_item(name, matrix(py, flat, mesh.dim))?;
        }
        Ok(dict)
    }

    /// |Ω|, the sum of the cell measures.
    fn volume(&self) -> f64 {
        self.inner.volume()
    }

    /// Writes the mesh as a Gmsh MSH 4.1 ASCII file (boundary parts as physical groups), which
    /// a scenario's `mesh.file` and Mesh.read take back.
    fn write_msh(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let text = mesh::msh_text(&self.inner);
        py.detach(|| std::fs::write(&path, text)).map_err(|source| {
            errors::to_py(
                py,
                &thermocontact::Error::Output(thermocontact::output::OutputError::Io { path, source }),
            )
        })
    }

    fn __repr__(&self) -> String {
        let m = &self.inner;
        format!(
            "<thermocontact.Mesh {}D: {} nodes, {} {}, parts {:?}>",
            m.dim,
            m.n_nodes(),
            m.n_cells(),
            if m.dim == 2 { "triangles" } else { "tetrahedra" },
            m.part_names
        )
    }
}

/// A flat row-major vector as an (len / columns, columns) array, without copying.
pub fn matrix<T: numpy::Element>(py: Python<'_>, flat: Vec<T>, columns: usize) -> Bound<'_, PyArray2<T>> {
    let rows = flat.len().checked_div(columns).unwrap_or(0);
    let array = Array2::from_shape_vec((rows, columns), flat).expect("the length is rows × columns");
    PyArray::from_owned_array(py, array)
}
