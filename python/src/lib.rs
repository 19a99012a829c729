//! The native module of envfield's Python package (`envfield._envfield`).
//!
//! Python's side (`python/envfield/`) checks arguments the way scikit-fmm does and shapes the
//! answers (masked arrays, tuples); this side takes C-ordered NumPy arrays without copying
//! them, runs the Rust code with the GIL released, and hands its vectors to NumPy without
//! copying them back. Errors come out as Python exceptions carrying the Rust error's text:
//! `ValueError` for input the marcher refuses, `RuntimeError` where the march itself fails.

use envfield_eikonal::level_set::{self, LevelSet, LevelSetOptions};
use envfield_eikonal::{EikonalError, Order};
use numpy::{IntoPyArray, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

mod rooms;

// The extension's Rust allocations (fields, queues, the arrays handed to NumPy, which frees
// them through this allocator) reuse freed pages rather than fault fresh ones in.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// A march that cannot go on is a `RuntimeError` (as scikit-fmm's); input it refuses, a
/// `ValueError`.
fn to_py(e: EikonalError) -> PyErr {
    match e {
        EikonalError::March(text) => PyRuntimeError::new_err(text),
        other => PyValueError::new_err(other.to_string()),
    }
}

fn slice<'a, T: numpy::Element>(a: &'a PyReadonlyArrayDyn<'_, T>, what: &str) -> PyResult<&'a [T]> {
    a.as_slice()
        .map_err(|_| PyValueError::new_err(format!("{what} must be a C-contiguous array")))
}

/// What one march returns to Python: values, reached, and extension velocities.
type Marching<'py> = (
    Bound<'py, PyArrayDyn<f64>>,
    Bound<'py, PyArrayDyn<bool>>,
    Option<Bound<'py, PyArrayDyn<f64>>>,
);

/// Marches `phi` from its zero contour: `kind` is "distance", "travel_time" or
/// "extension_velocities". Returns the values, where the march reached, and (for the
/// extension) the velocities, each shaped as `phi`.
#[pyfunction]
#[pyo3(signature = (kind, phi, dx, order, narrow, periodic, self_test, mask=None, speed=None, ext_mask=None))]
#[allow(clippy::too_many_arguments)]
fn march<'py>(
    py: Python<'py>,
    kind: &str,
    phi: PyReadonlyArrayDyn<'py, f64>,
    dx: Vec<f64>,
    order: u8,
    narrow: f64,
    periodic: Vec<bool>,
    self_test: bool,
    mask: Option<PyReadonlyArrayDyn<'py, bool>>,
    speed: Option<PyReadonlyArrayDyn<'py, f64>>,
    ext_mask: Option<PyReadonlyArrayDyn<'py, bool>>,
) -> PyResult<Marching<'py>> {
    let shape = phi.shape().to_vec();
    let options = LevelSetOptions {
        dx,
        order: Order::from_number(order).map_err(to_py)?,
        narrow,
        periodic,
        self_test,
    };
    let phi_s = slice(&phi, "phi")?;
    let mask_s = mask.as_ref().map(|m| slice(m, "mask")).transpose()?;
    let speed_s = speed.as_ref().map(|s| slice(s, "speed")).transpose()?;
    let ext_s = ext_mask
        .as_ref()
        .map(|m| slice(m, "ext_mask"))
        .transpose()?;
    let mut set = LevelSet::new(&shape, phi_s);
    if let Some(m) = mask_s {
        set = set.with_mask(m);
    }
    let need_speed =
        || speed_s.ok_or_else(|| PyValueError::new_err(format!("{kind} needs a speed")));
    let (marched, velocity) = match kind {
        "distance" => (py.detach(|| set.distance(&options)).map_err(to_py)?, None),
        "travel_time" => {
            let s = need_speed()?;
            (
                py.detach(|| set.travel_time(s, &options)).map_err(to_py)?,
                None,
            )
        }
        "extension_velocities" => {
            let s = need_speed()?;
            let e = py
                .detach(|| set.extension_velocities(s, ext_s, &options))
                .map_err(to_py)?;
            (e.distance, Some(e.velocity))
        }
        other => {
            return Err(PyValueError::new_err(format!(
                "unknown march kind {other:?}"
            )))
        }
    };
    let values = marched.values.into_pyarray(py).reshape(shape.clone())?;
    let reached = marched.reached.into_pyarray(py).reshape(shape.clone())?;
    let velocity = velocity
        .map(|v| v.into_pyarray(py).reshape(shape))
        .transpose()?;
    Ok((values, reached, velocity))
}

/// The path from `start` (index coordinates) down a marched field to its zero contour, as an
/// array of points (one row per step).
#[pyfunction]
fn descend<'py>(
    py: Python<'py>,
    values: PyReadonlyArrayDyn<'py, f64>,
    reached: PyReadonlyArrayDyn<'py, bool>,
    dx: Vec<f64>,
    start: Vec<f64>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let shape = values.shape().to_vec();
    if reached.shape() != shape.as_slice() {
        return Err(PyValueError::new_err(
            "the field and its reached mask must have the same shape",
        ));
    }
    let v = slice(&values, "the field")?;
    let r = slice(&reached, "the reached mask")?;
    let path = py
        .detach(|| level_set::descend(&shape, v, r, &dx, &start))
        .map_err(to_py)?;
    let rows = path.len();
    let flat: Vec<f64> = path.into_iter().flatten().collect();
    flat.into_pyarray(py).reshape(vec![rows, shape.len()])
}

/// envfield's native module: fast marching and the rooms' planners, called by the pure-Python
/// modules `envfield.fmm` and `envfield.rooms`.
#[pymodule]
fn _envfield(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(march, m)?)?;
    m.add_function(wrap_pyfunction!(descend, m)?)?;
    m.add_class::<rooms::PyScene>()?;
    m.add_class::<rooms::PyRegion>()?;
    m.add_class::<rooms::PyPlan>()?;
    let joints: Vec<&str> = envfield::affordance::Joint::ALL
        .iter()
        .map(|j| j.name())
        .collect();
    m.add("JOINTS", joints)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
