//! Scenario values between Python and TOML: `sc["mesh.nx"] = 64` becomes the override
//! `mesh.nx=64` of the command line's `--set`, so that a value set from Python meets exactly the
//! checks a scenario file or `--set` meets; `sc["mesh.nx"]` reads the TOML back.
//!
//! A value is read recursively, to at most [`MAX_DEPTH`] levels of lists and dicts: without a
//! bound a self-referencing list (`a = []; a.append(a)`) or one nested 10⁵ deep overflowed the
//! stack and killed the interpreter. No scenario key takes more than a few levels.

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use toml::{Table, Value};

use crate::errors;

/// The deepest nesting of lists and dicts in a value (the same bound as an expression's nesting
/// in the core, which is 100: this one is lower because each level is a native stack frame of
/// several PyO3 calls).
pub const MAX_DEPTH: usize = 64;

/// A Python value as TOML: bool, int, float, str, os.PathLike (a string), dict (a table), list
/// or tuple (an array); NumPy arrays and scalars through `tolist()`. `key` names the value in
/// errors. A value nested deeper than [`MAX_DEPTH`] (a self-referencing one) is refused.
pub fn to_toml(key: &str, object: &Bound<'_, PyAny>) -> PyResult<Value> {
    nested(key, key, object, 0)
}

/// [`to_toml`] of `object` at `key` (`root[1].name`), `depth` levels below the value of `root`.
fn nested(root: &str, key: &str, object: &Bound<'_, PyAny>, depth: usize) -> PyResult<Value> {
    let py = object.py();
    if depth > MAX_DEPTH {
        return Err(errors::invalid(
            py,
            root,
            &format!("lists or dicts nested more than {MAX_DEPTH} levels deep (at {key:.80}…)"),
            &format!(
                "a value of at most {MAX_DEPTH} levels of nested lists and dicts (a list or dict that \
                 contains itself never ends)"
            ),
        ));
    }
    if object.is_instance_of::<PyBool>() {
        return Ok(Value::Boolean(object.extract()?));
    }
    if object.is_instance_of::<PyInt>() {
        return object
            .extract::<i64>()
            .map(Value::Integer)
            .map_err(|_| errors::invalid(py, key, &object.to_string(), "an integer within ±2⁶³"));
    }
    if object.is_instance_of::<PyFloat>() {
        return Ok(Value::Float(object.extract()?));
    }
    if object.is_instance_of::<PyString>() {
        return Ok(Value::String(object.extract()?));
    }
    if let Ok(dict) = object.cast::<PyDict>() {
        let mut table = Table::new();
        for (name, value) in dict.iter() {
            let name: String = name
                .extract()
                .map_err(|_| errors::invalid(py, key, &name.to_string(), "a table with string keys"))?;
            let value = nested(root, &format!("{key}.{name}"), &value, depth + 1)?;
            table.insert(name, value);
        }
        return Ok(Value::Table(table));
    }
    if object.is_instance_of::<PyList>() || object.is_instance_of::<PyTuple>() {
        let items = object
            .try_iter()?
            .enumerate()
            .map(|(i, item)| nested(root, &format!("{key}[{i}]"), &item?, depth + 1))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(Value::Array(items));
    }
    if object.hasattr("tolist")? {
        // NumPy arrays and scalars.
        return nested(root, key, &object.call_method0("tolist")?, depth + 1);
    }
    if object.hasattr("__fspath__")? {
        let path = py.import("os")?.call_method1("fspath", (object,))?;
        return nested(root, key, &path, depth + 1);
    }
    Err(errors::invalid(
        py,
        key,
        &object.repr()?.to_string(),
        "a bool, int, float, str, list or dict (a TOML value)",
    ))
}

/// A TOML value as Python: tables as dicts, arrays as lists, dates as strings.
pub fn to_python<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        Value::Float(x) => x.into_pyobject(py)?.into_any(),
        Value::Boolean(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        Value::Array(items) => {
            let items = items.iter().map(|v| to_python(py, v)).collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Table(table) => table_to_python(py, table)?.into_any(),
    })
}

/// A TOML table as a Python dict.
pub fn table_to_python<'py>(py: Python<'py>, table: &Table) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (key, value) in table {
        dict.set_item(key, to_python(py, value)?)?;
    }
    Ok(dict)
}

/// The value at a dotted path (`mesh.nx`; an integer component indexes an array,
/// `loads.traction.0.part`).
pub fn lookup<'a>(table: &'a Table, path: &str) -> Option<&'a Value> {
    let mut parts = path.split('.');
    let mut current = table.get(parts.next()?)?;
    for part in parts {
        current = match current {
            Value::Table(t) => t.get(part)?,
            Value::Array(items) => items.get(part.parse::<usize>().ok()?)?,
            _ => return None,
        };
    }
    Some(current)
}

/// The override `key=value` of a Python value, as `--set` takes it.
pub fn assignment(key: &str, object: &Bound<'_, PyAny>) -> PyResult<String> {
    let py = object.py();
    let valid = !key.is_empty()
        && key
            .split('.')
            .all(|part| !part.is_empty() && part.chars().all(|c| c.is_alphanumeric() || c == '_' || c == '-'));
    if !valid {
        return Err(errors::invalid(
            py,
            key,
            &object.repr()?.to_string(),
            "a dotted key path such as \"mesh.nx\" (names of letters, digits, _ and -)",
        ));
    }
    let value = to_toml(key, object)?;
    Ok(format!("{key}={value}"))
}
