//! Scenes (a file, or a dict as JSON) and `render`: options from keyword arguments,
//! patched into the scene's description as overrides, so that they are validated with
//! the scene's own values exactly as the CLI's flags are.

use crate::errors::{opt_uint, render_err, to_py, uint};
use crate::interrupt::{self, Cancel};
use crate::state::RenderState;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where a scene came from: what a worker process needs to load it again.
#[derive(Clone)]
enum Source {
    File(PathBuf),
    Json { text: String, base_dir: PathBuf },
}

/// A resolved scene (from `frepray.load` or `frepray.load_dict`), ready to render.
/// Pickles as its source, so that it travels to other processes (Ray workers).
#[pyclass(module = "frepray", frozen)]
pub struct Scene {
    source: Source,
    inner: Arc<frepray::Scene>,
}

impl Scene {
    fn resolve(&self, py: Python<'_>, o: &frepray::Overrides) -> PyResult<frepray::Scene> {
        match &self.source {
            Source::File(path) => frepray::load_with(path, o).map_err(|e| to_py(py, e)),
            Source::Json { text, base_dir } => {
                let value: serde_json::Value =
                    serde_json::from_str(text).map_err(|e| PyValueError::new_err(e.to_string()))?;
                frepray::load_value_with(value, base_dir, o).map_err(|e| to_py(py, e))
            }
        }
    }
}

#[pymethods]
impl Scene {
    /// Image width and height in pixels.
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        self.inner.resolution()
    }
    /// The scene's hash (recorded in render states; states of different scenes refuse
    /// to merge).
    #[getter]
    fn hash(&self) -> u64 {
        self.inner.hash()
    }
    /// The scene's render settings as a dict (integrator, estimator, spp, seed, …).
    #[getter]
    fn settings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let o = self.inner.options().map_err(|e| to_py(py, e))?;
        let d = PyDict::new(py);
        d.set_item("integrator", o.integrator.to_string())?;
        d.set_item("estimator", o.method.name())?;
        d.set_item("spp", o.spp)?;
        d.set_item("seed", o.seed)?;
        let techniques: Vec<(String, u32)> = o
            .techniques
            .iter()
            .map(|(t, n)| (t.name().to_string(), *n))
            .collect();
        d.set_item("techniques", techniques)?;
        d.set_item("max_depth", o.max_depth)?;
        d.set_item("min_depth", o.min_depth)?;
        let aovs: Vec<&str> = o.aovs.iter().map(|a| a.name()).collect();
        d.set_item("aovs", aovs)?;
        Ok(d.into_any())
    }
    /// `(kind, text, base_dir)`: "file" and a path, or "json" and the scene as JSON.
    fn source(&self) -> (String, String, String) {
        match &self.source {
            Source::File(p) => ("file".into(), p.display().to_string(), String::new()),
            Source::Json { text, base_dir } => {
                ("json".into(), text.clone(), base_dir.display().to_string())
            }
        }
    }
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let f = py
            .import("frepray._native")?
            .getattr("_scene_from_source")?;
        let (k, t, b) = self.source();
        Ok((f, PyTuple::new(py, [k, t, b])?))
    }
    fn __repr__(&self) -> String {
        let (w, h) = self.inner.resolution();
        match &self.source {
            Source::File(p) => format!("<frepray.Scene {} {w}x{h}>", p.display()),
            Source::Json { .. } => format!("<frepray.Scene (dict) {w}x{h}>"),
        }
    }
}

/// Loads a scene file (TOML or JSON). Raises `SceneError` with the location.
#[pyfunction]
pub fn load(py: Python<'_>, path: PathBuf) -> PyResult<Scene> {
    let inner = py
        .detach(|| frepray::load(&path))
        .map_err(|e| to_py(py, e))?;
    let path = std::path::absolute(&path).unwrap_or(path);
    Ok(Scene {
        source: Source::File(path),
        inner: Arc::new(inner),
    })
}

/// A scene given as JSON text (the dict of `frepray.load_dict`); relative model and map
/// paths are found in `base_dir`. Raises `SceneError` with the key path.
#[pyfunction]
#[pyo3(signature = (text, base_dir = None))]
pub fn load_json(py: Python<'_>, text: String, base_dir: Option<PathBuf>) -> PyResult<Scene> {
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let base_dir = base_dir.unwrap_or_else(|| PathBuf::from("."));
    let base_dir = std::path::absolute(&base_dir).unwrap_or(base_dir);
    let inner = frepray::load_value(value, &base_dir).map_err(|e| to_py(py, e))?;
    Ok(Scene {
        source: Source::Json { text, base_dir },
        inner: Arc::new(inner),
    })
}

/// Rebuilds a pickled scene.
#[pyfunction]
pub fn _scene_from_source(
    py: Python<'_>,
    kind: &str,
    text: String,
    base_dir: String,
) -> PyResult<Scene> {
    match kind {
        "file" => load(py, PathBuf::from(text)),
        "json" => load_json(py, text, Some(PathBuf::from(base_dir))),
        _ => Err(PyValueError::new_err(format!(
            "unknown scene source {kind:?}"
        ))),
    }
}

/// `techniques` as the CLI's `name:count,...` text: a string, a dict `{name: count}` or
/// a sequence of names or `(name, count)` pairs.
fn technique_text(t: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(s) = t.extract::<String>() {
        return Ok(s);
    }
    if let Ok(d) = t.cast::<PyDict>() {
        let mut parts = vec![];
        for (k, v) in d.iter() {
            let n: u32 = uint("techniques", v.extract()?)?;
            parts.push(format!("{}:{n}", k.extract::<String>()?));
        }
        return Ok(parts.join(","));
    }
    let mut parts = vec![];
    for item in t.try_iter()? {
        let item = item?;
        if let Ok(s) = item.extract::<String>() {
            parts.push(s);
        } else {
            let (name, n): (String, i128) = item.extract()?;
            parts.push(format!("{name}:{}", uint::<u32>("techniques", n)?));
        }
    }
    Ok(parts.join(","))
}

/// Renders samples `samples = (start, end)` (default `(0, spp)`) of every pixel of
/// `scene` into a `RenderState`. Keyword options override the scene's settings:
/// `spp`, `seed`, `estimator` (balance, power, maximum, cutoff, optimal-direct, …),
/// `techniques` ("light:1,bsdf:1", a dict or a list), `integrator`, `width`, `height`,
/// `max_depth`, `min_depth` (only paths of at least this many bounces, as `--min-depth`), `aovs`, `hide_emitters`, `beta`, `cutoff`, `ridge`, `per_light` (one MIS
/// estimator per light, as `--per-light`), `pixel_center` (camera rays through pixel
/// centres, as `--pixel-center`), `trained_grid`, `trained_floor`, `trained_spp` (how
/// `light-trained` is trained, as `--trained-grid` …); `threads` (0: all
/// cores); `engine` ("per-ray" or "batched": how the CPU runs the samples, as
/// `--engine`; the same state either way); `backend` "cpu", "gpu" (wgpu: `direct` and `path`; a scene it does not cover
/// raises RenderError naming what) or "auto" (the GPU where it can, else the CPU, with a
/// warning saying why). The GIL is released while
/// rendering; Ctrl-C (in any thread) stops the render and raises KeyboardInterrupt with
/// the partial state as its `state` attribute; `cancel` (a `frepray.Cancel`) stops it
/// from another thread with `frepray.Cancelled`, which carries the state likewise.
/// `resume` (the partial state of a stopped render, with that render's options) renders
/// what it lacks, on the CPU: the result is the uninterrupted render's, bit for bit.
#[pyfunction]
#[pyo3(signature = (scene, spp = None, seed = None, samples = None, estimator = None,
    techniques = None, integrator = None, threads = 0, backend = "cpu", width = None,
    height = None, max_depth = None, aovs = None, hide_emitters = false, beta = None,
    cutoff = None, ridge = None, per_light = false, pixel_center = false, min_depth = None,
    trained_grid = None, trained_floor = None, trained_spp = None, cancel = None, resume = None,
    engine = "per-ray"))]
#[allow(clippy::too_many_arguments)]
pub fn render(
    py: Python<'_>,
    scene: &Scene,
    spp: Option<i128>,
    seed: Option<i128>,
    samples: Option<(i128, i128)>,
    estimator: Option<String>,
    techniques: Option<Bound<'_, PyAny>>,
    integrator: Option<String>,
    threads: i128,
    backend: &str,
    width: Option<i128>,
    height: Option<i128>,
    max_depth: Option<i128>,
    aovs: Option<Vec<String>>,
    hide_emitters: bool,
    beta: Option<f64>,
    cutoff: Option<f64>,
    ridge: Option<f64>,
    per_light: bool,
    pixel_center: bool,
    min_depth: Option<i128>,
    trained_grid: Option<i128>,
    trained_floor: Option<f64>,
    trained_spp: Option<i128>,
    cancel: Option<PyRef<'_, Cancel>>,
    resume: Option<PyRef<'_, RenderState>>,
    engine: &str,
) -> PyResult<RenderState> {
    let engine = frepray::Engine::parse(engine).ok_or_else(|| {
        PyValueError::new_err(format!(
            "engine {engine:?}: expected \"per-ray\" or \"batched\""
        ))
    })?;
    if resume.is_some() && (samples.is_some() || backend.eq_ignore_ascii_case("gpu")) {
        return Err(PyValueError::new_err(
            "resume continues the state's own sample range on the CPU: leave out samples \
             and backend=\"gpu\"",
        ));
    }
    let spp: Option<u32> = opt_uint("spp", spp)?;
    let seed: Option<u64> = opt_uint("seed", seed)?;
    let samples: Option<(u32, u32)> = match samples {
        Some((a, b)) => Some((uint("samples", a)?, uint("samples", b)?)),
        None => None,
    };
    let threads: usize = uint("threads", threads)?;
    let width = opt_uint("width", width)?;
    let height = opt_uint("height", height)?;
    let max_depth = opt_uint("max_depth", max_depth)?;
    let min_depth = opt_uint("min_depth", min_depth)?;
    let trained_grid = opt_uint("trained_grid", trained_grid)?;
    let trained_spp = opt_uint("trained_spp", trained_spp)?;
    let backend: frepray::Backend = backend.parse().map_err(PyValueError::new_err)?;
    let text = techniques.map(|t| technique_text(&t)).transpose()?;
    let techniques = crate::errors::techniques(py, text.as_deref())?;
    let o = frepray::Overrides {
        spp,
        estimator,
        techniques,
        seed,
        integrator,
        width,
        height,
        max_depth,
        min_depth,
        aovs,
        hide_emitters,
        beta,
        cutoff,
        ridge,
        per_light,
        trained_grid,
        trained_floor,
        trained_spp,
    };
    let reresolve = o.estimator.is_some()
        || o.techniques.is_some()
        || o.integrator.is_some()
        || o.width.is_some()
        || o.height.is_some()
        || o.max_depth.is_some()
        || o.min_depth.is_some()
        || o.aovs.is_some()
        || o.hide_emitters
        || o.beta.is_some()
        || o.cutoff.is_some()
        || o.ridge.is_some()
        || o.per_light
        || o.trained_grid.is_some()
        || o.trained_floor.is_some()
        || o.trained_spp.is_some();
    let resolved = if reresolve {
        Arc::new(scene.resolve(py, &o)?)
    } else {
        scene.inner.clone()
    };
    // spp and seed change no resolved value: they go into the options directly.
    let settings = frepray::Settings {
        overrides: frepray::Overrides {
            spp: None,
            seed: None,
            ..o
        },
        threads,
        pixel_center,
        engine,
        ..Default::default()
    };
    let (mut options, unused) = resolved.options_with(&settings).map_err(|e| to_py(py, e))?;
    if let Some(n) = spp {
        options.spp = n;
    }
    if let Some(s) = seed {
        options.seed = s;
    }
    options.validate().map_err(render_err)?;
    for u in &unused {
        warn(py, &u.message(keyword))?;
    }
    let range = match samples {
        Some((a, b)) if a < b => a..b,
        Some((a, b)) => {
            return Err(PyValueError::new_err(format!(
                "samples ({a}, {b}): expected (start, end) with start < end"
            )))
        }
        None => 0..options.spp,
    };
    let partial = resume.as_deref().map(RenderState::inner);
    let (result, interrupted) = interrupt::run(py, cancel.as_deref(), |stop| match partial {
        Some(p) => resolved
            .resume(&options, p, stop, &|_, _| {})
            .map(|(state, stats)| frepray::Rendered {
                state,
                stats,
                gpu: None,
                fallback: None,
            }),
        None => resolved.render_on(backend, &options, range, stop, &|_, _| {}),
    });
    let rendered = result.map_err(|e| to_py(py, e))?;
    if let Some(why) = &rendered.fallback {
        warn(py, &format!("backend \"auto\" renders on the CPU: {why}"))?;
    }
    let state = RenderState::from(rendered.state);
    if let Some(err) = interrupted {
        let _ = err.value(py).setattr("state", Py::new(py, state)?);
        return Err(err);
    }
    Ok(state)
}

/// A `UserWarning` with `message`.
pub fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let msg = std::ffi::CString::new(message).unwrap_or_default();
    PyErr::warn(
        py,
        &py.get_type::<pyo3::exceptions::PyUserWarning>(),
        &msg,
        1,
    )
}

/// The keyword argument that sets a scene key (`render.beta` → `beta`,
/// `camera.resolution` → `width/height`).
pub fn keyword(key: &str) -> String {
    match key {
        "camera.resolution" => "width/height".into(),
        k => k.rsplit('.').next().unwrap_or(k).to_string(),
    }
}

/// The scene's source path, for experiments (`<dict>` for a scene given as data).
pub fn scene_path(scene: &Scene) -> PathBuf {
    match &scene.source {
        Source::File(p) => p.clone(),
        Source::Json { .. } => Path::new("<dict>").into(),
    }
}

/// The resolved scene with experiment overrides applied.
pub fn resolved(
    py: Python<'_>,
    scene: &Scene,
    o: &frepray::Overrides,
) -> PyResult<Arc<frepray::Scene>> {
    Ok(Arc::new(scene.resolve(py, o)?))
}
