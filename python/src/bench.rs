//! `frepray.bench`: `frepray bench`'s measurement (the library's
//! `frepray::bench::bench`): `direct` and `path` on each back end, with the stage times.

use crate::errors::{opt_uint, to_py, uint};
use crate::interrupt::{self, Cancel};
use crate::scene::{keyword, resolved, warn, Scene};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// Renders the scene with `direct` and with `path` on each of `backends` ("cpu",
/// "gpu"; the GPU's kernels are compiled by an untimed first render) and returns one
/// dict per render: backend, integrator, estimator, width, height, spp, time_s,
/// msamples_per_s, mrays_per_s, camera/secondary/shadow_mrays_per_s, threads and
/// `stages` ({stage: seconds}: the CPU's summed over its threads, or the GPU's). The
/// keywords are `render`'s; `cancel` stops it (`frepray.Cancelled`).
#[pyfunction]
#[pyo3(signature = (scene, spp = None, estimator = None, techniques = None, width = None,
    height = None, max_depth = None, backends = vec!["cpu".to_string()], threads = 0,
    cancel = None))]
#[allow(clippy::too_many_arguments)]
pub fn bench<'py>(
    py: Python<'py>,
    scene: &Scene,
    spp: Option<i128>,
    estimator: Option<String>,
    techniques: Option<String>,
    width: Option<i128>,
    height: Option<i128>,
    max_depth: Option<i128>,
    backends: Vec<String>,
    threads: i128,
    cancel: Option<PyRef<'_, Cancel>>,
) -> PyResult<Bound<'py, PyList>> {
    let backends = backends
        .iter()
        .map(|b| b.parse::<frepray::Backend>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(PyValueError::new_err)?;
    let overrides = frepray::Overrides {
        spp: opt_uint("spp", spp)?,
        estimator,
        techniques: crate::errors::techniques(py, techniques.as_deref())?,
        width: opt_uint("width", width)?,
        height: opt_uint("height", height)?,
        max_depth: opt_uint("max_depth", max_depth)?,
        ..Default::default()
    };
    let s = resolved(py, scene, &overrides)?;
    let settings = frepray::Settings {
        overrides,
        threads: uint("threads", threads)?,
        ..Default::default()
    };
    let (options, unused) = s.options_with(&settings).map_err(|e| to_py(py, e))?;
    for u in &unused {
        warn(py, &u.message(keyword))?;
    }
    let (rows, interrupted) = interrupt::run(py, cancel.as_deref(), |stop| {
        frepray::bench::bench(&s, &options, &backends, stop)
    });
    if let Some(err) = interrupted {
        return Err(err);
    }
    let rows = rows.map_err(|e| to_py(py, e))?;
    let (w, h) = s.resolution();
    let list = PyList::empty(py);
    for r in &rows {
        let st = &r.stats;
        let (camera, secondary, shadow) = st.mrays_per_s_by_kind();
        let d = PyDict::new(py);
        d.set_item("backend", r.backend.name())?;
        d.set_item("integrator", r.integrator.to_string())?;
        d.set_item("estimator", options.method.name())?;
        d.set_item("width", w)?;
        d.set_item("height", h)?;
        d.set_item("spp", options.spp)?;
        d.set_item("time_s", st.wall.as_secs_f64())?;
        d.set_item("msamples_per_s", st.msamples_per_s())?;
        d.set_item("mrays_per_s", st.mrays_per_s())?;
        d.set_item("camera_mrays_per_s", camera)?;
        d.set_item("secondary_mrays_per_s", secondary)?;
        d.set_item("shadow_mrays_per_s", shadow)?;
        d.set_item("threads", st.threads)?;
        let stages = PyDict::new(py);
        for (name, t) in r.stage_parts() {
            stages.set_item(name, t.as_secs_f64())?;
        }
        d.set_item("stages", stages)?;
        list.append(d)?;
    }
    Ok(list)
}
