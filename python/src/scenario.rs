//! `thermocontact.Scenario`: every parameter of a run, as the command line reads it. Setting a
//! key is the command line's `--set key=value`: the scenario is loaded again from its TOML with
//! that override, so a value set from Python meets exactly the checks of a file or `--set`, and
//! an error names the dotted key, the value and what was expected.

use std::path::PathBuf;
use std::sync::Arc;

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyMapping};
use thermocontact::mesh::Mesh;
use thermocontact::Scenario;
use toml::Table;

use crate::mesh::{describe, PyMesh};
use crate::{errors, values};

/// A complete, validated scenario (the paper's Section 6 example by default).
///
/// Scenario(text=None, overrides=None, mesh=None)
///
/// text      -- TOML laid over the built-in default (it may hold only the keys it changes);
/// overrides -- dict of dotted keys to values, applied after the text (`--set` on the
///              command line): {"mesh.nx": 64, "time.steps": 32};
/// mesh      -- a Mesh to run on instead of the structured generator (as `mesh.file` does:
///              the text may then hold no `geometry` or `mesh` keys, and the default's
///              tractions, which act on the rectangle's parts, are dropped).
///
/// Keys by dotted path: sc["mesh.nx"] = 64, sc["friction.law"], sc.update({...}). Tables are
/// set whole with dicts: sc["friction"] = {"law": "tresca", "bound": 100.0} (the law's keys
/// depend on the law). str(sc) is the TOML a run saves beside its results.
#[pyclass(name = "Scenario", module = "thermocontact")]
#[derive(Clone)]
pub struct PyScenario {
    pub inner: Scenario,
    /// The mesh given in memory, if any (it is not part of the TOML).
    pub given: Option<Arc<Mesh>>,
}

impl PyScenario {
    /// Loads `text` over the default with `overrides`, on the mesh `given` if any; the GIL is
    /// released (a `mesh.file` is read).
    fn load(py: Python<'_>, text: Option<&str>, overrides: &[String], given: Option<Arc<Mesh>>) -> PyResult<Self> {
        let loaded = py.detach(|| match &given {
            Some(mesh) => Scenario::load_with_mesh(text, overrides, mesh.clone()),
            None => Scenario::load(text, overrides),
        });
        loaded
            .map(|inner| PyScenario { inner, given })
            .map_err(|e| errors::to_py(py, &e))
    }

    /// This scenario with `overrides` applied (validated as a whole).
    fn with_overrides(&self, py: Python<'_>, overrides: &[String]) -> PyResult<Self> {
        PyScenario::load(py, Some(&self.inner.to_toml()), overrides, self.given.clone())
    }

    fn table(&self) -> Table {
        self.inner.to_toml().parse().expect("a scenario's TOML parses")
    }
}

/// `key=value` overrides from a mapping of dotted keys to Python values; `function` names the
/// method in the errors (a non-mapping or a non-string key is a `TypeError` naming `overrides`).
fn assignments(function: &str, overrides: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(overrides) = overrides else {
        return Ok(Vec::new());
    };
    let mapping = overrides.cast::<PyMapping>().map_err(|_| {
        PyTypeError::new_err(format!(
            "{function}: overrides is {}, expected a mapping of dotted keys to values, such as \
             {{\"mesh.nx\": 32}}",
            describe(overrides)
        ))
    })?;
    mapping
        .items()?
        .iter()
        .map(|item| {
            let (key, value): (Bound<'_, PyAny>, Bound<'_, PyAny>) = item.extract()?;
            let key: String = key.extract().map_err(|_| {
                PyTypeError::new_err(format!(
                    "{function}: overrides has a key that is {}, expected dotted key strings such as \"mesh.nx\"",
                    describe(&key)
                ))
            })?;
            values::assignment(&key, &value)
        })
        .collect()
}

#[pymethods]
impl PyScenario {
    #[new]
    #[pyo3(signature = (text = None, overrides = None, mesh = None))]
    fn new(
        py: Python<'_>,
        text: Option<&str>,
        overrides: Option<&Bound<'_, PyAny>>,
        mesh: Option<PyRef<'_, PyMesh>>,
    ) -> PyResult<Self> {
        let overrides = assignments("Scenario", overrides)?;
        PyScenario::load(py, text, &overrides, mesh.map(|m| m.inner.clone()))
    }

    /// Scenario.default() -> Scenario: the paper's Section 6 example (`thermocontact scenario`
    /// prints it with comments; thermocontact.DEFAULT_TOML holds that text).
    #[staticmethod]
    fn default(py: Python<'_>) -> PyResult<Self> {
        PyScenario::load(py, None, &[], None)
    }

    /// Scenario.load(path, overrides=None) -> Scenario: a scenario file laid over the default,
    /// then the overrides; a relative `mesh.file` in it is taken relative to the file's folder.
    #[staticmethod]
    #[pyo3(name = "load", signature = (path, overrides = None))]
    fn load_file(py: Python<'_>, path: PathBuf, overrides: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let overrides = assignments("Scenario.load", overrides)?;
        py.detach(|| Scenario::load_file(&path, &overrides))
            .map(|inner| PyScenario { inner, given: None })
            .map_err(|e| errors::to_py(py, &e))
    }

    /// sc.with_mesh(mesh, overrides=None) -> Scenario: this scenario on `mesh` instead of its
    /// own (its geometry and cell counts, or its mesh file, go), with `overrides` applied at
    /// the same time — typically the boundary parts and tractions named as in the new mesh:
    /// {"boundary.contact": ["contact"], ...}. The scenario's boundary parts must exist in the
    /// new mesh once the overrides are applied.
    #[pyo3(signature = (mesh, overrides = None))]
    fn with_mesh(
        &self,
        py: Python<'_>,
        mesh: PyRef<'_, PyMesh>,
        overrides: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let overrides = assignments("Scenario.with_mesh", overrides)?;
        let mut table = self.table();
        table.remove("geometry");
        table.remove("mesh");
        let text = toml::to_string(&table).expect("a table serializes");
        PyScenario::load(py, Some(&text), &overrides, Some(mesh.inner.clone()))
    }

    /// sc.update(mapping): sets several keys at once (validated together), e.g.
    /// sc.update({"mesh.nx": 32, "mesh.ny": 8}).
    fn update(&mut self, py: Python<'_>, overrides: &Bound<'_, PyAny>) -> PyResult<()> {
        let overrides = assignments("Scenario.update", Some(overrides))?;
        *self = self.with_overrides(py, &overrides)?;
        Ok(())
    }

    /// A copy (setting keys on it leaves this one as it is).
    fn copy(&self) -> Self {
        self.clone()
    }

    fn __copy__(&self) -> Self {
        self.clone()
    }

    fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Self {
        self.clone()
    }

    fn __setitem__(&mut self, py: Python<'_>, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let assignment = values::assignment(key, value)?;
        *self = self.with_overrides(py, &[assignment])?;
        Ok(())
    }

    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        match values::lookup(&self.table(), key) {
            Some(value) => values::to_python(py, value),
            None => Err(pyo3::exceptions::PyKeyError::new_err(key.to_string())),
        }
    }

    fn __contains__(&self, key: &str) -> bool {
        values::lookup(&self.table(), key).is_some()
    }

    /// The scenario as nested dicts (tables) and lists (arrays).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        values::table_to_python(py, &self.table())
    }

    /// The scenario as TOML: what a run saves as scenario.toml. A mesh given in memory is not
    /// part of it (load the text again with the same mesh).
    fn to_toml(&self) -> String {
        self.inner.to_toml()
    }

    fn __str__(&self) -> String {
        match &self.given {
            Some(mesh) => format!(
                "# mesh: given in memory ({}D, {} nodes, {} cells, parts {:?}), not part of this text\n{}",
                mesh.dim,
                mesh.n_nodes(),
                mesh.n_cells(),
                mesh.part_names,
                self.inner.to_toml()
            ),
            None => self.inner.to_toml(),
        }
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        let mesh = match (&self.given, s.structured(), &s.mesh.file) {
            (Some(m), _, _) => format!("a mesh given in memory ({} cells)", m.n_cells()),
            (None, Some(structured), _) => format!(
                "{} cells over {:?}",
                structured
                    .cells
                    .iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(" × "),
                structured.lengths
            ),
            (None, None, Some(file)) => format!("mesh file {}", file.display()),
            (None, None, None) => "no mesh".into(),
        };
        format!(
            "<thermocontact.Scenario {}D, {mesh}, T = {}, {} steps, {} solver>",
            s.dim(),
            s.time.final_time,
            s.time.steps,
            s.solver.kind.name()
        )
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        match other.cast::<PyScenario>() {
            Ok(other) => {
                let other = other.borrow();
                let same_mesh = match (&self.given, &other.given) {
                    (Some(a), Some(b)) => Arc::ptr_eq(a, b),
                    (None, None) => true,
                    _ => false,
                };
                same_mesh && self.inner == other.inner
            }
            Err(_) => false,
        }
    }

    /// Space dimension d.
    #[getter]
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    /// Time step k = T/N.
    #[getter]
    fn time_step(&self) -> f64 {
        self.inner.time_step()
    }

    /// Time levels n of the output times (each rounded to the nearest level).
    #[getter]
    fn output_steps(&self) -> Vec<usize> {
        self.inner.output_steps()
    }

    /// The scenario's mesh: given, read from `mesh.file` or generated.
    #[getter]
    fn mesh(&self, py: Python<'_>) -> PyResult<PyMesh> {
        if let Some(mesh) = &self.given {
            return Ok(PyMesh { inner: mesh.clone() });
        }
        py.detach(|| self.inner.mesh())
            .map(PyMesh::wrap)
            .map_err(|e| errors::to_py(py, &e))
    }
}
