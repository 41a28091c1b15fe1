//! `frepray.Viewer`: the live preview of `frepray view` from Python — a local page that
//! renders a scene or model progressively (`frepray::view`), served from a background
//! thread until `close()`.

use frepray::view::Viewer as Server;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A running viewer: `url` is the page's address (127.0.0.1, with its token).
#[pyclass(module = "frepray")]
pub struct Viewer {
    url: String,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

#[pymethods]
impl Viewer {
    /// Serves `path` (a scene or model file) on 127.0.0.1:`port` (0: a free port),
    /// with the scene's settings; `decompose` also renders through pixel centres for the
    /// inspector's variance split.
    #[new]
    #[pyo3(signature = (path, port = 0, decompose = false))]
    fn new(path: PathBuf, port: u16, decompose: bool) -> PyResult<Self> {
        let server = Server::bind(&path, frepray::Settings::default(), port, decompose)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let url = server.url();
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::spawn(move || {
            let _ = server.run(&flag);
        });
        Ok(Viewer {
            url,
            stop,
            thread: Some(thread),
        })
    }
    /// The page's address.
    #[getter]
    fn url(&self) -> String {
        self.url.clone()
    }
    /// Stops the render and the server (and waits for them).
    fn close(&mut self, py: Python<'_>) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            py.detach(|| {
                let _ = t.join();
            });
        }
    }
    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }
    #[pyo3(signature = (*_args))]
    fn __exit__(&mut self, py: Python<'_>, _args: &Bound<'_, pyo3::types::PyTuple>) {
        self.close(py);
    }
    fn __repr__(&self) -> String {
        format!("frepray.Viewer({})", self.url)
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
    }
}
