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
