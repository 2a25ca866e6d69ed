//! Python values as the TOML text of a scene file, for `Scene.from_arrays`: the arrays are
//! written as a scene file would hold them and read back through the same parser and
//! validation, so a bad value gives the scene file's error message.
//!
//! Numbers are written so that they read back as the same f64 (Rust's shortest round-trip
//! form; `nan`, `inf`, `-inf` as TOML spells them); integers as integers, booleans as
//! booleans, strings as TOML basic strings, sequences and numpy arrays as TOML arrays.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyString};

/// Deepest nesting of arrays written (a 3 × 3 inertia is 2).
const MAX_DEPTH: usize = 4;

/// True for a sequence (list, tuple, numpy array), false for a number or a string.
pub fn is_sequence(obj: &Bound<'_, PyAny>) -> bool {
    if obj.is_instance_of::<PyString>() {
        return false;
    }
    // A numpy array or scalar by its dimension (a 0-d array is one number).
    if let Ok(d) = obj.getattr("ndim") {
        return d.extract::<usize>().is_ok_and(|d| d > 0);
    }
    obj.cast::<pyo3::types::PySequence>().is_ok()
}

/// The TOML text of a Python value.
pub fn value(obj: &Bound<'_, PyAny>) -> PyResult<String> {
    value_at(obj, 0)
}

fn value_at(obj: &Bound<'_, PyAny>, depth: usize) -> PyResult<String> {
    if obj.is_instance_of::<PyBool>() {
        return Ok(if obj.extract::<bool>()? {
            "true"
        } else {
            "false"
        }
        .into());
    }
    if obj.is_instance_of::<PyInt>() {
        return Ok(obj.extract::<i64>()?.to_string());
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(float(obj.extract::<f64>()?));
    }
    if obj.is_instance_of::<PyString>() {
        let s: String = obj.extract()?;
        // A JSON string literal is a TOML basic string (the same escapes).
        return serde_json::to_string(&s).map_err(|e| PyValueError::new_err(e.to_string()));
    }
    if obj.hasattr("tolist")? {
        // A numpy array or scalar: its Python value (float64 → float, int64 → int, bool).
        let v = obj.call_method0("tolist")?;
        if !v.is(obj) {
            return value_at(&v, depth);
        }
    }
    if depth < MAX_DEPTH {
        if let Ok(seq) = obj.cast::<pyo3::types::PySequence>() {
            let mut parts = Vec::new();
            for x in seq.try_iter()? {
                parts.push(value_at(&x?, depth + 1)?);
            }
            return Ok(format!("[{}]", parts.join(", ")));
        }
    }
    if let Ok(x) = obj.extract::<f64>() {
        return Ok(float(x));
    }
    Err(PyTypeError::new_err(format!(
        "expected numbers, booleans, strings or arrays of them, got {}",
        obj.get_type().name()?
    )))
}

/// An f64 as TOML: reads back as the same number.
fn float(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        // Debug is Rust's shortest round-trip form, always with a `.` or an exponent.
        format!("{x:?}")
    }
}

/// The TOML text of each row of a sequence (`what` names the argument in errors).
pub fn rows(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<String>> {
    let list = if obj.hasattr("tolist")? {
        obj.call_method0("tolist")?
    } else {
        obj.clone()
    };
    if list.is_instance_of::<PyString>() {
        return Err(PyTypeError::new_err(format!(
            "{what}: expected a sequence, got str"
        )));
    }
    let seq = list
        .cast::<pyo3::types::PySequence>()
        .map_err(|_| PyTypeError::new_err(format!("{what}: expected a sequence")))?;
    let mut out = Vec::new();
    for x in seq.try_iter()? {
        out.push(value(&x?).map_err(|e| PyTypeError::new_err(format!("{what}: {e}")))?);
    }
    Ok(out)
}

/// One `[table]` of a scene file: keys in the order set, absent values left out.
pub struct Table {
    /// The table's name (empty: the top level).
    pub name: &'static str,
    lines: Vec<String>,
}

impl Table {
    /// An empty table.
    pub fn new(name: &'static str) -> Table {
        Table {
            name,
            lines: Vec::new(),
        }
    }
    /// `key = value` when `obj` is given.
    pub fn set(&mut self, key: &str, obj: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        if let Some(o) = obj {
            let v = value(o).map_err(|e| PyTypeError::new_err(format!("{key}: {e}")))?;
            self.raw(key, v);
        }
        Ok(())
    }
    /// `key = text`.
    pub fn raw(&mut self, key: &str, text: String) {
        self.lines.push(format!("{key} = {text}"));
    }
    /// No key set.
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }
    /// The table's text.
    pub fn text(&self) -> String {
        let mut s = if self.name.is_empty() {
            String::new()
        } else {
            format!("\n[{}]\n", self.name)
        };
        for l in &self.lines {
            s.push_str(l);
            s.push('\n');
        }
        s
    }
}
