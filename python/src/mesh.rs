//! `thermocontact.Mesh`: a simplicial mesh with named boundary parts, from NumPy arrays, a Gmsh
//! file or a generator, always through the core's checks (`Mesh::new`).
//!
//! The arguments are read here, not by PyO3's conversions, because those convert too much: a
//! float array of cells became integers by truncation (1.7 → 1), complex points became real with
//! only NumPy's warning, and a negative cell count was an `OverflowError` that named nothing.
//! Every refusal names the function, the argument, the value (or dtype) and what was expected:
//! a value of the wrong type is a `TypeError`, one out of range a `MeshError` (a `ValueError`).
//! Node indices may be integer arrays, or float arrays whose values are all integers (as
//! `numpy.loadtxt` gives them); boolean, complex, string or object arrays are refused.
//! Coordinates may be float or integer arrays. The generators' sizes are checked by the core
//! (countable, within the machine's memory) before anything is allocated.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::ndarray::Array2;
use numpy::{PyArray, PyArray2, PyReadonlyArray2};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyString};
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

/// `object` as a 2D NumPy array (`numpy.asarray`), with its dtype's kind (`'i'`, `'f'`, ...);
/// `what` names the argument.
fn array2<'py>(object: &Bound<'py, PyAny>, what: &str) -> PyResult<(Bound<'py, PyAny>, String, [usize; 2])> {
    let py = object.py();
    let array = py.import("numpy")?.call_method1("asarray", (object,)).map_err(|e| {
        invalid(
            py,
            format!("{what}: {} cannot be read as an array ({e})", describe(object)),
        )
    })?;
    let dtype = array.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    match shape[..] {
        [rows, columns] => Ok((array, kind, [rows, columns])),
        _ => Err(invalid(
            py,
            format!("{what}: an array of shape {shape:?} ({dtype}), expected a 2D array"),
        )),
    }
}

/// "an int (42)", "a str ('x')": the type and, if short, the repr of a Python value.
pub fn describe(object: &Bound<'_, PyAny>) -> String {
    let name = object
        .get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into());
    let article = if name.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    match object.repr() {
        Ok(repr) if repr.to_string().chars().count() <= 40 => format!("{article} {name} ({repr})"),
        _ => format!("{article} {name}"),
    }
}

/// Node indices (0-based) from an integer array, or a float array of integral values; `what`
/// names the argument. Returns the indices, row-major, and the shape.
fn indices(object: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<usize>, [usize; 2])> {
    let py = object.py();
    let (array, kind, shape) = array2(object, what)?;
    let negative = |i: &dyn std::fmt::Display| invalid(py, format!("{what}: negative node index {i}"));
    let nodes = match kind.as_str() {
        "i" => {
            let array: PyReadonlyArray2<'_, i64> = array.call_method1("astype", ("int64",))?.extract()?;
            let view = array.as_array();
            view.iter()
                .map(|&i| usize::try_from(i).map_err(|_| negative(&i)))
                .collect::<PyResult<Vec<_>>>()?
        }
        "u" => {
            let array: PyReadonlyArray2<'_, u64> = array.call_method1("astype", ("uint64",))?.extract()?;
            let view = array.as_array();
            view.iter().map(|&i| i as usize).collect()
        }
        "f" => {
            let array: PyReadonlyArray2<'_, f64> = array.call_method1("astype", ("float64",))?.extract()?;
            let view = array.as_array();
            let mut nodes = Vec::with_capacity(view.len());
            for ((row, column), &x) in view.indexed_iter() {
                if x < 0.0 {
                    return Err(negative(&x));
                }
                // Below 2⁵³ every integer is exact, and far beyond any node count.
                if !(x.fract() == 0.0 && x < 9.007_199_254_740_992e15) {
                    return Err(invalid(
                        py,
                        format!(
                            "{what}: {x} at [{row}, {column}] is not a node index, expected integer node \
                             indices (0-based; a float array is taken only if all its values are integers)"
                        ),
                    ));
                }
                nodes.push(x as usize);
            }
            nodes
        }
        _ => {
            return Err(PyTypeError::new_err(format!(
                "{what}: an array of dtype {}, expected integer node indices (0-based)",
                array.getattr("dtype")?
            )))
        }
    };
    Ok((nodes, shape))
}

/// Node coordinates from a float or integer array, rows of `width` ≤ 3 padded with zeros;
/// `what` names the argument. Complex, boolean, string or object arrays are refused.
fn coordinates(object: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<[f64; 3]>, [usize; 2])> {
    let (array, kind, shape) = array2(object, what)?;
    if !matches!(kind.as_str(), "f" | "i" | "u") {
        return Err(PyTypeError::new_err(format!(
            "{what}: an array of dtype {}, expected real coordinates (a float array)",
            array.getattr("dtype")?
        )));
    }
    let array: PyReadonlyArray2<'_, f64> = array.call_method1("astype", ("float64",))?.extract()?;
    let width = shape[1].min(3);
    let coords = array
        .as_array()
        .rows()
        .into_iter()
        .map(|row| {
            let mut x = [0.0; 3];
            for (k, &c) in row.iter().take(width).enumerate() {
                x[k] = c;
            }
            x
        })
        .collect();
    Ok((coords, shape))
}

/// A count argument `name` of `function`: a Python or NumPy integer (not a bool, not a float)
/// of at least `min`.
fn count(function: &str, name: &str, object: &Bound<'_, PyAny>, min: usize) -> PyResult<usize> {
    let py = object.py();
    let expected = if min == 1 {
        "a positive integer".to_string()
    } else {
        format!("an integer ≥ {min}")
    };
    let index = if object.is_instance_of::<PyBool>() {
        None
    } else {
        py.import("operator")?.call_method1("index", (object,)).ok()
    };
    let Some(index) = index else {
        return Err(PyTypeError::new_err(format!(
            "{function}: {name} is {}, expected {expected}",
            describe(object)
        )));
    };
    match index.extract::<i64>().ok().and_then(|n| usize::try_from(n).ok()) {
        Some(n) if n >= min => Ok(n),
        _ => Err(invalid(
            py,
            format!("{function}: {name} = {index}, expected {expected}"),
        )),
    }
}

/// A length argument `name` of `function`: a real number (not a bool), finite and positive.
fn length(function: &str, name: &str, object: &Bound<'_, PyAny>) -> PyResult<f64> {
    let expected = "a positive finite length";
    let value = match object.is_instance_of::<PyBool>() {
        true => None,
        false => object.extract::<f64>().ok(),
    };
    match value {
        None => Err(PyTypeError::new_err(format!(
            "{function}: {name} is {}, expected {expected} (a float)",
            describe(object)
        ))),
        Some(x) if x.is_finite() && x > 0.0 => Ok(x),
        Some(x) => Err(invalid(
            object.py(),
            format!("{function}: {name} = {x}, expected {expected}"),
        )),
    }
}

/// The three items of a sequence argument `name` of `function` (`Mesh.box`'s lengths and cells).
fn triple<'py>(function: &str, name: &str, object: &Bound<'py, PyAny>) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let items = object
        .try_iter()
        .and_then(|items| items.collect::<PyResult<Vec<_>>>())
        .ok()
        .filter(|items| items.len() == 3 && !object.is_instance_of::<PyString>());
    items.ok_or_else(|| {
        PyTypeError::new_err(format!(
            "{function}: {name} is {}, expected a sequence of 3 numbers (x, y, z)",
            describe(object)
        ))
    })
}

/// A generator's error, with the call that asked for the mesh.
fn generated(py: Python<'_>, call: String, error: mesh::MeshError) -> PyErr {
    match error {
        // Its message names the shape; the call names the arguments.
        mesh::MeshError::TooLarge { .. } | mesh::MeshError::Invalid(_) => invalid(py, format!("{call}: {error}")),
        other => errors::mesh_error(py, other),
    }
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
        points: &Bound<'_, PyAny>,
        cells: &Bound<'_, PyAny>,
        boundary: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let (cells, cells_shape) = indices(cells, "cells")?;
        let dim = cells_shape[1].wrapping_sub(1);
        if dim != 2 && dim != 3 {
            return Err(invalid(
                py,
                format!("cells: shape {cells_shape:?}, expected (m, 3) triangles or (m, 4) tetrahedra"),
            ));
        }
        let (coords, points_shape) = coordinates(points, "points")?;
        let width = points_shape[1];
        if width != dim && width != 3 {
            return Err(invalid(
                py,
                format!(
                    "points: shape {points_shape:?}, expected (n, {dim}) for {}",
                    if dim == 2 {
                        "triangles (or (n, 3) with z = 0)"
                    } else {
                        "tetrahedra"
                    }
                ),
            ));
        }
        let (mut facets, mut facet_parts, mut part_names) = (Vec::new(), Vec::new(), Vec::new());
        if let Some(boundary) = boundary {
            for (name, array) in boundary.iter() {
                let name: String = name
                    .extract()
                    .map_err(|_| invalid(py, format!("boundary: part name {name}, expected a string")))?;
                let what = format!("boundary[{name:?}]");
                let (nodes, shape) = indices(&array, &what)?;
                if shape[1] != dim {
                    return Err(invalid(
                        py,
                        format!("{what}: shape {shape:?}, expected (f, {dim}): {dim} nodes per boundary facet"),
                    ));
                }
                let part = part_names.len();
                facet_parts.extend(std::iter::repeat_n(part, shape[0]));
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
    fn rectangle(
        py: Python<'_>,
        lx: &Bound<'_, PyAny>,
        ly: &Bound<'_, PyAny>,
        nx: &Bound<'_, PyAny>,
        ny: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        const F: &str = "Mesh.rectangle";
        let (lx, ly) = (length(F, "lx", lx)?, length(F, "ly", ly)?);
        let (nx, ny) = (count(F, "nx", nx, 1)?, count(F, "ny", ny, 1)?);
        py.detach(|| mesh::try_rectangle(lx, ly, nx, ny))
            .map(PyMesh::wrap)
            .map_err(|e| generated(py, format!("{F}(lx={lx}, ly={ly}, nx={nx}, ny={ny})"), e))
    }

    /// Mesh.box(lengths, cells) -> Mesh: the box (0, L₁) × (0, L₂) × (0, L₃) in n₁ × n₂ × n₃
    /// hexahedra of 6 tetrahedra each; parts "x-", "x+", "y-", "y+", "z-", "z+".
    #[staticmethod]
    #[pyo3(name = "box")]
    fn cuboid(py: Python<'_>, lengths: &Bound<'_, PyAny>, cells: &Bound<'_, PyAny>) -> PyResult<Self> {
        const F: &str = "Mesh.box";
        let mut l = [0.0; 3];
        for (i, item) in triple(F, "lengths", lengths)?.iter().enumerate() {
            l[i] = length(F, &format!("lengths[{i}]"), item)?;
        }
        let mut n = [0; 3];
        for (i, item) in triple(F, "cells", cells)?.iter().enumerate() {
            n[i] = count(F, &format!("cells[{i}]"), item, 1)?;
        }
        py.detach(|| mesh::try_cuboid(l, n))
            .map(PyMesh::wrap)
            .map_err(|e| generated(py, format!("{F}(lengths={l:?}, cells={n:?})"), e))
    }

    /// Mesh.annulus(inner_radius, outer_radius, n_radial, n_around) -> Mesh: a ring of
    /// triangles; parts "inner", "outer".
    #[staticmethod]
    fn annulus(
        py: Python<'_>,
        inner_radius: &Bound<'_, PyAny>,
        outer_radius: &Bound<'_, PyAny>,
        n_radial: &Bound<'_, PyAny>,
        n_around: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        const F: &str = "Mesh.annulus";
        let a = length(F, "inner_radius", inner_radius)?;
        let b = length(F, "outer_radius", outer_radius)?;
        if b <= a {
            return Err(invalid(
                py,
                format!("{F}: outer_radius = {b}, expected more than inner_radius = {a}"),
            ));
        }
        let n_radial = count(F, "n_radial", n_radial, 1)?;
        let n_around = count(F, "n_around", n_around, 3)?;
        py.detach(|| mesh::try_annulus(a, b, n_radial, n_around))
            .map(PyMesh::wrap)
            .map_err(|e| {
                let call = format!("{F}(inner_radius={a}, outer_radius={b}, n_radial={n_radial}, n_around={n_around})");
                generated(py, call, e)
            })
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

    /// dict: cell region name (a Gmsh physical group of dimension d) -> int64 array of its
    /// cells, ascending (new arrays); empty for the generators' meshes.
    #[getter]
    fn regions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for region in &self.inner.regions {
            let cells: Vec<i64> = region.cells.iter().map(|&e| i64::from(e)).collect();
            dict.set_item(&region.name, PyArray::from_vec(py, cells))?;
        }
        Ok(dict)
    }

    /// |Ω|, the sum of the cell measures.
    fn volume(&self) -> f64 {
        self.inner.volume()
    }

    /// Writes the mesh as a Gmsh MSH 4.1 ASCII file (boundary parts and cell regions as physical groups), which
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
