//! The library's [`Error`] as Python exceptions: one class per kind of cause, each carrying the
//! message the CLI prints (`Error`'s `Display`) and the variant's data as attributes (`key`,
//! `value`, `expected` of a scenario value; `step`, `time`, `cutback_depth` of a solver failure).
//!
//! The classes are defined in Python at module initialization, because a bad-input error should
//! also be a `ValueError` (and a file error an `OSError`), which needs multiple inheritance.

use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyDict;
use thermocontact::model::ModelError;
use thermocontact::time::TimeError;
use thermocontact::Error;

/// The exception classes, by name, once the module is initialized.
static CLASSES: PyOnceLock<Py<PyDict>> = PyOnceLock::new();

const DEFINITIONS: &std::ffi::CStr = c"
class Error(Exception):
    '''Base class of thermocontact's errors. str(e) is the message the command line prints.'''
    __module__ = 'thermocontact'

class ScenarioError(Error, ValueError):
    '''A scenario that is not valid: an unknown key, a value of the wrong type or out of range,
    a boundary part the mesh lacks, data that cannot be evaluated, a problem too large for the
    machine's memory. When the error is about one
    key, e.key is its dotted path, e.value the value given and e.expected what was expected.'''
    __module__ = 'thermocontact'

class MeshError(Error, ValueError):
    '''A mesh that cannot be read or is not valid (degenerate or inverted cells, unused nodes, a
    boundary facet inside the domain, ...); the message says what and where.'''
    __module__ = 'thermocontact'

class SolverError(Error, RuntimeError):
    '''A time step that did not converge even after the cutbacks (e.step, e.time,
    e.cutback_depth), a failed factorization or a non-finite solution.'''
    __module__ = 'thermocontact'

class FileError(Error, OSError):
    '''An input file that cannot be read, an output file that cannot be written, an output
    folder that holds another run's results (run(..., overwrite=True)), a checkpoint that does
    not belong to the run.'''
    __module__ = 'thermocontact'

class Interrupted(Error):
    '''A run stopped from outside between two steps (e.step, e.time: the last completed step).'''
    __module__ = 'thermocontact'
";

/// Names of the classes, base first.
pub const NAMES: [&str; 6] = [
    "Error",
    "ScenarioError",
    "MeshError",
    "SolverError",
    "FileError",
    "Interrupted",
];

/// Defines the classes and adds them to the module.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = module.py();
    let namespace = PyDict::new(py);
    py.run(DEFINITIONS, Some(&namespace), None)?;
    let classes = PyDict::new(py);
    for name in NAMES {
        let class = namespace.get_item(name)?.expect("defined just above");
        module.add(name, &class)?;
        classes.set_item(name, class)?;
    }
    let _ = CLASSES.set(py, classes.unbind());
    Ok(())
}

/// The exception class `name` (one of [`NAMES`]).
fn class<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
    let classes = CLASSES
        .get(py)
        .ok_or_else(|| pyo3::exceptions::PyRuntimeError::new_err("thermocontact is not initialized"))?;
    Ok(classes.bind(py).get_item(name)?.expect("registered at initialization"))
}

/// The Python exception of a library error.
pub fn to_py(py: Python<'_>, error: &Error) -> PyErr {
    match build(py, error) {
        Ok(err) => err,
        Err(err) => err,
    }
}

fn build(py: Python<'_>, error: &Error) -> PyResult<PyErr> {
    let name = match error {
        Error::UnknownKey { .. }
        | Error::RemovedKey { .. }
        | Error::MissingKey { .. }
        | Error::InvalidValue { .. }
        | Error::TooLarge { .. }
        | Error::Load(_)
        | Error::Model(ModelError::Load(_))
        | Error::Scenario(_) => "ScenarioError",
        Error::Mesh(_) | Error::Model(ModelError::Mesh(_)) => "MeshError",
        Error::Model(_) => "ScenarioError",
        Error::Time(_) | Error::Step(_) => "SolverError",
        Error::Output(_) | Error::Read { .. } | Error::Folder(_) | Error::Checkpoint(_) => "FileError",
        Error::Interrupted { .. } => "Interrupted",
        // A variant added to the core later: the base class, with its message.
        #[allow(unreachable_patterns)]
        _ => "Error",
    };
    // The scenario layer names the keys behind a failure of the step matrix, as the CLI does.
    let message = match thermocontact::scenario::keys_behind(error) {
        Some(keys) => format!("{error}. {keys}"),
        None => error.to_string(),
    };
    let exception = class(py, name)?.call1((message,))?;
    let set = |attribute: &str, value: Bound<'_, PyAny>| exception.setattr(attribute, value);
    let none = || py.None().into_bound(py);
    // Every instance has the attributes of its class, None where the variant has no value.
    match name {
        "ScenarioError" => {
            let (key, value, expected) = match error {
                Error::InvalidValue { key, value, expected } => (Some(key), Some(value), Some(expected)),
                Error::UnknownKey { key, expected } => (Some(key), None, Some(expected)),
                Error::RemovedKey { key, instead } => (Some(key), None, Some(instead)),
                Error::MissingKey { key } => (Some(key), None, None),
                _ => (None, None, None),
            };
            set("key", key.into_pyobject(py)?.into_any())?;
            set("value", value.into_pyobject(py)?.into_any())?;
            set("expected", expected.into_pyobject(py)?.into_any())?;
        }
        "SolverError" => {
            let (step, time, depth) = match error {
                Error::Time(TimeError::NotConverged {
                    step,
                    time,
                    cutback_depth,
                    ..
                }) => (Some(*step), Some(*time), Some(*cutback_depth)),
                _ => (None, None, None),
            };
            set("step", step.into_pyobject(py)?.into_any())?;
            set("time", time.into_pyobject(py)?.into_any())?;
            set("cutback_depth", depth.into_pyobject(py)?.into_any())?;
        }
        "Interrupted" => {
            if let Error::Interrupted { step, time, .. } = error {
                set("step", step.into_pyobject(py)?.into_any())?;
                set("time", time.into_pyobject(py)?.into_any())?;
            } else {
                set("step", none())?;
                set("time", none())?;
            }
        }
        _ => {}
    }
    Ok(PyErr::from_value(exception))
}

/// A [`thermocontact::mesh::MeshError`] (from building a mesh) as the Python `MeshError`.
pub fn mesh_error(py: Python<'_>, error: thermocontact::mesh::MeshError) -> PyErr {
    to_py(py, &Error::Mesh(error))
}

/// A `ScenarioError` about `key` that the bindings find themselves (a value Python cannot put
/// into TOML, say), shaped as the core's `InvalidValue`.
pub fn invalid(py: Python<'_>, key: &str, value: &str, expected: &str) -> PyErr {
    to_py(
        py,
        &Error::InvalidValue {
            key: key.to_string(),
            value: value.to_string(),
            expected: expected.to_string(),
        },
    )
}
