//! `frepray.gpu_available`: whether `backend="gpu"` can render here, probed (it was a
//! constant `False` while `backend="gpu"` worked).

use pyo3::prelude::*;

/// Whether `backend="gpu"` finds a GPU adapter (Mesa's lavapipe counts): call
/// `frepray.gpu_available()`, or test it as a truth value (`if frepray.gpu_available:`),
/// as the constant it replaces was read. The first probe opens the device, without the
/// GIL, and keeps it for the renders; later probes answer at once.
#[pyclass(module = "frepray", frozen)]
pub struct GpuAvailable;

impl GpuAvailable {
    fn probe(py: Python<'_>) -> bool {
        py.detach(|| frepray::backend::shared_gpu().is_ok())
    }
}

#[pymethods]
impl GpuAvailable {
    fn __call__(&self, py: Python<'_>) -> bool {
        Self::probe(py)
    }
    fn __bool__(&self, py: Python<'_>) -> bool {
        Self::probe(py)
    }
    fn __repr__(&self) -> &'static str {
        "<frepray.gpu_available: call it; True where backend=\"gpu\" finds an adapter>"
    }
}

/// Sets the features the process's GPU opens with, before it opens (over the
/// `FREPRAY_GPU_*` variables): each keyword True or False, None leaves it. `f64`,
/// `int64`, `subgroups` and `sums` are on where the adapter has them; `checked` turns
/// the kernels' runtime bounds checks on (a diagnostic; off); `adapter` opens the N-th
/// adapter of [`gpu_adapters`] (None: the first high-performance one). Raises ValueError
/// once the GPU has opened with other options (it opens once per process). Returns the
/// options in force as a dict.
#[pyfunction]
#[pyo3(signature = (*, f64 = None, int64 = None, subgroups = None, sums = None, checked = None, adapter = None))]
#[allow(clippy::too_many_arguments)]
pub fn configure_gpu<'py>(
    py: Python<'py>,
    f64: Option<bool>,
    int64: Option<bool>,
    subgroups: Option<bool>,
    sums: Option<bool>,
    checked: Option<bool>,
    adapter: Option<usize>,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    let mut list: Vec<String> = [
        ("f64", f64),
        ("int64", int64),
        ("subgroups", subgroups),
        ("sums", sums),
        ("checked", checked),
    ]
    .iter()
    .filter_map(|(k, v)| v.map(|on| format!("{k}={}", if on { "on" } else { "off" })))
    .collect();
    list.extend(adapter.map(|n| format!("adapter={n}")));
    let o = frepray::backend::configure_gpu(&list.join(","))
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    let d = pyo3::types::PyDict::new(py);
    d.set_item("f64", o.f64)?;
    d.set_item("int64", o.int64)?;
    d.set_item("subgroups", o.subgroups)?;
    d.set_item("sums", o.sums)?;
    d.set_item("checked", o.checked)?;
    d.set_item("adapter", o.adapter)?;
    Ok(d)
}

/// The GPU adapters the environment offers, a line each (`N: name (backend, type); f64
/// yes, …`), as `frepray gpu list` prints them: N is what `configure_gpu(adapter=N)`
/// takes. Raises RuntimeError in a build without the GPU back end.
#[pyfunction]
pub fn gpu_adapters(py: Python<'_>) -> PyResult<Vec<String>> {
    py.detach(frepray::backend::gpu_adapters)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))
}
