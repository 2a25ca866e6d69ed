//! Conversions between Python objects and the library's values: numbers in, numpy arrays
//! (float64) out, and JSON values (a report serialised by serde) into Python objects.
//!
//! Every f64 crosses unchanged: a Python float and a numpy float64 are IEEE doubles, and
//! serde_json's `Value` keeps the f64 it was given (no text round trip).

use nalgebra::{Matrix3, Matrix6, Vector3};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyByteArray, PyBytes, PyDict, PyList, PyMemoryView, PyString};

/// numpy.asarray, imported once.
static ASARRAY: PyOnceLock<Py<PyAny>> = PyOnceLock::new();

/// `numpy.asarray(obj, dtype)`.
pub fn asarray<'py>(
    py: Python<'py>,
    obj: Bound<'py, PyAny>,
    dtype: &str,
) -> PyResult<Bound<'py, PyAny>> {
    ASARRAY.import(py, "numpy", "asarray")?.call1((obj, dtype))
}

/// A 1-D float64 array of `v`.
pub fn array1<'py>(py: Python<'py>, v: &[f64]) -> PyResult<Bound<'py, PyAny>> {
    asarray(py, PyList::new(py, v)?.into_any(), "float64")
}

/// A 2-D float64 array of `rows` (each row one list).
pub fn array2<'py>(py: Python<'py>, rows: &[Vec<f64>]) -> PyResult<Bound<'py, PyAny>> {
    let list = PyList::empty(py);
    for r in rows {
        list.append(PyList::new(py, r)?)?;
    }
    asarray(py, list.into_any(), "float64")
}

/// A float64 array of `shape` from `v` in row-major order (`v.len()` = the product of
/// `shape`; an empty array keeps its shape).
pub fn array3<'py>(py: Python<'py>, v: &[f64], shape: [usize; 3]) -> PyResult<Bound<'py, PyAny>> {
    debug_assert_eq!(v.len(), shape.iter().product::<usize>());
    array1(py, v)?.call_method1("reshape", (shape[0], shape[1], shape[2]))
}

/// A 3-vector as a float64 array of shape (3,).
pub fn vector3<'py>(py: Python<'py>, v: &Vector3<f64>) -> PyResult<Bound<'py, PyAny>> {
    array1(py, v.as_slice())
}

/// A 3 × 3 matrix as a float64 array of shape (3, 3), row by row.
pub fn matrix3<'py>(py: Python<'py>, m: &Matrix3<f64>) -> PyResult<Bound<'py, PyAny>> {
    let rows: Vec<Vec<f64>> = m.row_iter().map(|r| r.iter().copied().collect()).collect();
    array2(py, &rows)
}

/// The leading `dim` × `dim` block of a 6 × 6 matrix as a float64 array, row by row.
pub fn matrix6<'py>(py: Python<'py>, m: &Matrix6<f64>, dim: usize) -> PyResult<Bound<'py, PyAny>> {
    let rows: Vec<Vec<f64>> = (0..dim)
        .map(|i| (0..dim).map(|j| m[(i, j)]).collect())
        .collect();
    array2(py, &rows)
}

/// Refuses `bytes`, `bytearray`, `memoryview` and `str`: sequences that are not of numbers,
/// though bytes iterate as small integers (`bytearray(b'\0\0\1')` was taken as the position
/// (0, 0, 1) m).
pub fn refuse_non_number_sequence(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<()> {
    if obj.is_instance_of::<PyBytes>()
        || obj.is_instance_of::<PyByteArray>()
        || obj.is_instance_of::<PyMemoryView>()
        || obj.is_instance_of::<PyString>()
    {
        let t = obj.get_type().name()?;
        return Err(PyTypeError::new_err(format!(
            "{what}: expected numbers, got {t} (bytes and text are not numbers)"
        )));
    }
    Ok(())
}

/// `N` numbers from any Python sequence of numbers (list, tuple, numpy array; not bytes,
/// bytearray, memoryview or str); `what` names the argument and its unit in the error.
/// Non-finite values pass: the caller decides.
pub fn floats<const N: usize>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<[f64; N]> {
    refuse_non_number_sequence(obj, what)?;
    let v: Vec<f64> = obj
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("{what}: expected a sequence of {N} numbers")))?;
    <[f64; N]>::try_from(v.as_slice()).map_err(|_| {
        PyValueError::new_err(format!("{what}: expected {N} numbers, got {}", v.len()))
    })
}

/// A position (m) from a sequence of 3 numbers.
pub fn position(obj: &Bound<'_, PyAny>) -> PyResult<Vector3<f64>> {
    Ok(Vector3::from(floats::<3>(obj, "position (x, y, z in m)")?))
}

/// A JSON value as a Python object: objects become dicts (keys in the report's order),
/// numeric arrays numpy arrays (see [`numeric_array`]), other arrays lists, numbers int or
/// float, null None.
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => number_to_py(py, n)?,
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(a) => match numeric_array(py, a)? {
            Some(x) => x,
            None => {
                let list = PyList::empty(py);
                for x in a {
                    list.append(json_to_py(py, x)?)?;
                }
                list.into_any()
            }
        },
        Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// An integer as int, anything else as float (the f64 serde_json holds).
fn number_to_py<'py>(py: Python<'py>, n: &serde_json::Number) -> PyResult<Bound<'py, PyAny>> {
    if let Some(i) = n.as_u64() {
        return Ok(i.into_pyobject(py)?.into_any());
    }
    if let Some(i) = n.as_i64() {
        return Ok(i.into_pyobject(py)?.into_any());
    }
    let x = n
        .as_f64()
        .ok_or_else(|| PyValueError::new_err(format!("number {n} is not an f64")))?;
    Ok(x.into_pyobject(py)?.into_any())
}

/// A numpy array of a JSON array of numbers, or of equally long such arrays (2-D): int64
/// when every element is an integer (counts, indices), else float64 with null read as NaN
/// (serde_json writes non-finite numbers as null). An empty array is an empty float64
/// array. None for anything else (strings, objects, ragged rows).
fn numeric_array<'py>(
    py: Python<'py>,
    a: &[serde_json::Value],
) -> PyResult<Option<Bound<'py, PyAny>>> {
    use serde_json::Value;
    let is_num = |x: &Value| x.is_number() || x.is_null();
    let is_int = |x: &Value| x.is_u64() || x.is_i64();
    let flat = a.iter().all(is_num);
    let rows: Option<Vec<&Vec<Value>>> = a.iter().map(|r| r.as_array()).collect();
    let rows = rows.filter(|r| {
        !r.is_empty()
            && r.iter().all(|x| !x.is_empty() && x.len() == r[0].len())
            && r.iter().all(|x| x.iter().all(is_num))
    });
    if !flat && rows.is_none() {
        return Ok(None);
    }
    let ints = match &rows {
        Some(r) => r.iter().all(|x| x.iter().all(is_int)),
        None => !a.is_empty() && a.iter().all(is_int),
    };
    let list = if flat {
        json_list(py, a)?
    } else {
        let outer = PyList::empty(py);
        for r in rows.into_iter().flatten() {
            outer.append(json_list(py, r)?)?;
        }
        outer
    };
    let dtype = if ints { "int64" } else { "float64" };
    Ok(Some(asarray(py, list.into_any(), dtype)?))
}

/// The Python list of a JSON array of numbers (null as NaN).
fn json_list<'py>(py: Python<'py>, a: &[serde_json::Value]) -> PyResult<Bound<'py, PyList>> {
    let list = PyList::empty(py);
    for x in a {
        match x {
            serde_json::Value::Null => list.append(f64::NAN)?,
            serde_json::Value::Number(n) => list.append(number_to_py(py, n)?)?,
            _ => return Err(PyValueError::new_err("not a number")),
        }
    }
    Ok(list)
}
