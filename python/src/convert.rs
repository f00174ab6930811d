//! Moving f64 vectors between Rust and Python without per-element conversion where it counts.
//!
//! ```text
//! Rust → Python (each callback):  bytearray(8n) filled from the slice → numpy.frombuffer
//!                                 (a fresh, writable float64 array the callee may keep)
//! Python → Rust (each result):    list / tuple → element by element (PyFloat_AsDouble);
//!                                 (scipy's vectorized fun: numpy.ravel of its column first)
//!                                 anything else → numpy.asarray(x, float64), shape checked,
//!                                 .tobytes() copied out
//! bulk results:                   bytearray of native-endian f64 (numpy.frombuffer on the
//!                                 Python side)
//! a run's trajectory columns:     F64Column, the engine's own Vec<f64> behind numpy's array
//!                                 interface (numpy.asarray on the Python side, no copy)
//! ```
//!
//! The extension is built for the stable ABI from Python 3.9 (abi3-py39), where the buffer
//! protocol is not available; these routes use only stable-ABI calls and numpy's Python API.

use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::{PyByteArray, PyBytes, PyDict, PyList, PyTuple};

use crate::errors;

/// Native-endian f64 values from bytes (a trailing partial value is ignored; callers pass
/// `8 · k` bytes).
pub fn f64s_from_bytes(bytes: &[u8]) -> Vec<f64> {
    bytes
        .chunks_exact(8)
        .map(|c| {
            let mut a = [0u8; 8];
            a.copy_from_slice(c);
            f64::from_ne_bytes(a)
        })
        .collect()
}

/// A Python `bytearray` holding `values` as native-endian f64 (a bytearray, so that
/// `numpy.frombuffer` makes a writable array of it without a copy).
pub fn bytearray_from_f64s<'py>(
    py: Python<'py>,
    values: &[f64],
) -> PyResult<Bound<'py, PyByteArray>> {
    PyByteArray::new_with(py, 8 * values.len(), |buf| {
        for (c, v) in buf.chunks_exact_mut(8).zip(values) {
            c.copy_from_slice(&v.to_ne_bytes());
        }
        Ok(())
    })
}

/// A vector of f64 that numpy uses in place: an object with numpy's array interface
/// (version 3) over memory it owns, so that `numpy.asarray(column)` is a writable float64
/// array of the values without a copy, whose base (this object) keeps the memory alive. A
/// run's trajectory columns are handed over from the engine this way (python/lash/_run.py).
#[pyclass(module = "lash._lash", frozen)]
pub struct F64Column {
    /// The vector's buffer, owned (a Vec's raw parts; freed on drop).
    ptr: *mut f64,
    len: usize,
    cap: usize,
}

// SAFETY: the object owns its buffer as a Vec would (nothing else frees it, and Rust never
// reads or writes through `ptr` after construction: only numpy does, under the GIL's rules
// for any array's memory), so it may move to and be dropped on any thread.
unsafe impl Send for F64Column {}
// SAFETY: as above; shared references give out only the address.
unsafe impl Sync for F64Column {}

impl F64Column {
    /// Takes `values` over without copying them.
    pub fn new(values: Vec<f64>) -> F64Column {
        let mut v = std::mem::ManuallyDrop::new(values);
        F64Column {
            ptr: v.as_mut_ptr(),
            len: v.len(),
            cap: v.capacity(),
        }
    }
}

impl Drop for F64Column {
    fn drop(&mut self) {
        // SAFETY: the parts came from a Vec<f64> (F64Column::new) and are freed only here.
        drop(unsafe { Vec::from_raw_parts(self.ptr, self.len, self.cap) });
    }
}

#[pymethods]
impl F64Column {
    /// numpy's array interface: shape `(len,)`, native-endian float64, writable.
    #[getter]
    fn __array_interface__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("version", 3)?;
        d.set_item("shape", (self.len,))?;
        let typestr = if cfg!(target_endian = "little") {
            "<f8"
        } else {
            ">f8"
        };
        d.set_item("typestr", typestr)?;
        d.set_item("data", (self.ptr as usize, false))?;
        Ok(d)
    }

    fn __len__(&self) -> usize {
        self.len
    }
}

/// numpy's functions the conversions call, looked up once per solve.
pub struct Numpy<'py> {
    frombuffer: Bound<'py, PyAny>,
    asarray: Bound<'py, PyAny>,
    ravel: Bound<'py, PyAny>,
    float64: Bound<'py, PyAny>,
}

impl<'py> Numpy<'py> {
    /// Imports numpy's `frombuffer`, `asarray` and `float64`.
    pub fn import(py: Python<'py>) -> PyResult<Self> {
        let np = py.import("numpy")?;
        Ok(Numpy {
            frombuffer: np.getattr("frombuffer")?,
            asarray: np.getattr("asarray")?,
            ravel: np.getattr("ravel")?,
            float64: np.getattr("float64")?,
        })
    }

    /// A fresh writable float64 numpy array holding `y` (shape (n,)).
    pub fn array(&self, y: &[f64]) -> PyResult<Bound<'py, PyAny>> {
        let py = self.frombuffer.py();
        let ba = PyByteArray::new_with(py, 8 * y.len(), |buf| {
            for (c, v) in buf.chunks_exact_mut(8).zip(y) {
                c.copy_from_slice(&v.to_ne_bytes());
            }
            Ok(())
        })?;
        // frombuffer's default dtype is float64; a bytearray gives a writable array.
        self.frombuffer.call1((ba,))
    }

    /// `numpy.ravel(x)`: x as a one-dimensional array (a column (n, 1) of scipy's vectorized
    /// `fun`, a 0-d Jacobian of a one-dimensional system).
    pub fn ravel(&self, obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        self.ravel.call1((obj,))
    }

    /// Reads a vector of length `out.len()` returned by the callback `what` into `out`.
    /// Lists and tuples are read element by element, anything else through
    /// `numpy.asarray(x, float64)`; a value of another shape is a usage error naming `what`.
    pub fn read_vector(
        &self,
        obj: &Bound<'py, PyAny>,
        out: &mut [f64],
        what: &str,
    ) -> PyResult<()> {
        let n = out.len();
        if let Ok(list) = obj.cast::<PyList>() {
            if list.len() != n {
                let got = format!("a list of length {}", list.len());
                return Err(shape_error(obj.py(), what, &got, &[n]));
            }
            for (o, item) in out.iter_mut().zip(list.iter()) {
                *o = item.extract::<f64>()?;
            }
            return Ok(());
        }
        if let Ok(tuple) = obj.cast::<PyTuple>() {
            if tuple.len() != n {
                let got = format!("a tuple of length {}", tuple.len());
                return Err(shape_error(obj.py(), what, &got, &[n]));
            }
            for (o, item) in out.iter_mut().zip(tuple.iter()) {
                *o = item.extract::<f64>()?;
            }
            return Ok(());
        }
        self.read_array(obj, &[n], out, what)
    }

    /// Reads an array of shape `shape` (C order) into `out` (length = product of `shape`)
    /// through `numpy.asarray(x, float64)`.
    pub fn read_array(
        &self,
        obj: &Bound<'py, PyAny>,
        shape: &[usize],
        out: &mut [f64],
        what: &str,
    ) -> PyResult<()> {
        let py = obj.py();
        let arr = self.asarray.call1((obj, &self.float64))?;
        let got: Vec<usize> = arr.getattr(intern!(py, "shape"))?.extract()?;
        if got != shape {
            let desc = format!("shape {}", shape_str(&got));
            return Err(shape_error(py, what, &desc, shape));
        }
        let bytes = arr.call_method0(intern!(py, "tobytes"))?;
        let bytes = bytes.cast::<PyBytes>()?.as_bytes();
        for (o, c) in out.iter_mut().zip(bytes.chunks_exact(8)) {
            let mut a = [0u8; 8];
            a.copy_from_slice(c);
            *o = f64::from_ne_bytes(a);
        }
        Ok(())
    }
}

/// "(2,)" / "(2, 2)": a shape as numpy prints it.
fn shape_str(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

fn shape_error(py: Python<'_>, what: &str, got: &str, expected: &[usize]) -> PyErr {
    errors::usage_error(
        py,
        &format!(
            "{what} returned {got}; expected shape {}",
            shape_str(expected)
        ),
    )
}
