//! `frepray.experiment`: the estimator comparison of `frepray experiment`, and the
//! metrics it uses (`measure`) for images made elsewhere (e.g. on a Ray cluster).

use crate::errors::{opt_uint, render_err, to_py, uint};
use crate::interrupt::{self, Cancel};
use crate::scene::{resolved, scene_path, Scene};
use frepray::experiment::{self as exp, ExperimentConfig, Image, Renderer};
use frepray::RenderOptions;
use numpy::PyReadonlyArray3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// Renders the scene for the experiment driver.
struct SceneRenderer<'a> {
    scene: Arc<frepray::Scene>,
    base: RenderOptions,
    stop: &'a AtomicBool,
}

impl SceneRenderer<'_> {
    fn run(&mut self, o: RenderOptions) -> Result<Option<(Image, f64)>, String> {
        let spp = o.spp;
        let (state, stats) = self
            .scene
            .render_with(&o, 0..spp, self.stop, &|_, _| {})
            .map_err(|e| e.to_string())?;
        if stats.stopped {
            return Ok(None);
        }
        Ok(Some((to_image(&state.image()), stats.wall.as_secs_f64())))
    }

    fn options(&self, estimator: &str, spp: u32, seed: u64) -> Result<RenderOptions, String> {
        Ok(RenderOptions {
            method: mis::Method::from_str(estimator).map_err(|e| e.to_string())?,
            spp,
            seed,
            ..self.base.clone()
        })
    }
}

impl Renderer for SceneRenderer<'_> {
    fn render(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, String> {
        let o = self.options(estimator, spp, seed)?;
        self.run(o)
    }

    fn render_pixel_centers(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, String> {
        let o = RenderOptions {
            pixel_center: true,
            ..self.options(estimator, spp, seed)?
        };
        self.run(o)
    }
}

/// The colour of a render image.
fn to_image(img: &render::Image) -> Image {
    let (w, h) = (img.width(), img.height());
    Image {
        width: w,
        height: h,
        rgb: (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| img.rgb(x, y).to_array())
            .collect(),
    }
}

/// An `(h, w, ≥3)` array's first three channels as an experiment image.
fn array_image(a: &PyReadonlyArray3<'_, f64>) -> PyResult<Image> {
    let a = a.as_array();
    let (h, w, c) = a.dim();
    if c < 3 {
        return Err(PyValueError::new_err("expected an (h, w, 3) image"));
    }
    let rgb = (0..h)
        .flat_map(|y| (0..w).map(move |x| (y, x)))
        .map(|(y, x)| [a[[y, x, 0]], a[[y, x, 1]], a[[y, x, 2]]])
        .collect();
    Ok(Image {
        width: w as u32,
        height: h as u32,
        rgb,
    })
}

/// MSE, RMSE and relMSE of `image` against `reference` (float64 `(h, w, 3)`), with the
/// definitions of `frepray experiment` (DESIGN.md §4).
#[pyfunction]
pub fn measure<'py>(
    py: Python<'py>,
    image: PyReadonlyArray3<'py, f64>,
    reference: PyReadonlyArray3<'py, f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let (m, _) = exp::measure(&array_image(&image)?, &array_image(&reference)?)
        .map_err(PyValueError::new_err)?;
    let d = PyDict::new(py);
    d.set_item("mse", m.mse)?;
    d.set_item("rmse", m.mse.sqrt())?;
    d.set_item("relmse", m.relmse)?;
    d.set_item("nonfinite", m.nonfinite)?;
    Ok(d)
}

/// Runs the comparison: a reference (`reference_spp` samples, or the EXR `reference`),
/// then every estimator at every spp, written to `out` (results.json, results.csv,
/// summary.md, plots, images; a rerun resumes). Returns one dict per (estimator, spp):
/// estimator, spp, time_s, mse, rmse, relmse, mse_ci, rmse_ci, trimmed_mse, net_mse,
/// cpu_s, improvement, improvement_ci, improvement_trimmed, median_pixel_ratio,
/// speed_up, speed_up_ci, overhead (intervals as [lo, hi] or None with one seed), and
/// with `decompose` variance_jittered, variance_centered, direction_share. The other
/// arguments are the CLI's flags of the same names (`per_light` is `--per-light`, and so
/// on); `threads` 0 uses every core. Ctrl-C and `cancel` stop it (KeyboardInterrupt,
/// `frepray.Cancelled`) with what finished written to `out`, as the CLI does.
#[pyfunction]
#[pyo3(signature = (scene, out, estimators, spp, reference_spp = 256, reference = None,
    reference_estimator = None, baseline = "balance", seed = 0, repeats = i128::from(exp::DEFAULT_REPEATS),
    techniques = None, integrator = None, width = None, height = None, per_light = false,
    pixel_center = false, decompose = false, max_depth = None, min_depth = None,
    hide_emitters = false, beta = None, cutoff = None, ridge = None, trained_grid = None,
    trained_floor = None, trained_spp = None, threads = 0, cancel = None))]
#[allow(clippy::too_many_arguments)]
pub fn experiment<'py>(
    py: Python<'py>,
    scene: &Scene,
    out: PathBuf,
    estimators: Vec<String>,
    spp: Vec<i128>,
    reference_spp: i128,
    reference: Option<PathBuf>,
    reference_estimator: Option<String>,
    baseline: &str,
    seed: i128,
    repeats: i128,
    techniques: Option<String>,
    integrator: Option<String>,
    width: Option<i128>,
    height: Option<i128>,
    per_light: bool,
    pixel_center: bool,
    decompose: bool,
    max_depth: Option<i128>,
    min_depth: Option<i128>,
    hide_emitters: bool,
    beta: Option<f64>,
    cutoff: Option<f64>,
    ridge: Option<f64>,
    trained_grid: Option<i128>,
    trained_floor: Option<f64>,
    trained_spp: Option<i128>,
    threads: i128,
    cancel: Option<PyRef<'_, Cancel>>,
) -> PyResult<Bound<'py, PyList>> {
    let spp: Vec<u32> = spp
        .into_iter()
        .map(|n| uint("spp", n))
        .collect::<PyResult<_>>()?;
    let reference_spp: u32 = uint("reference_spp", reference_spp)?;
    let seed: u64 = uint("seed", seed)?;
    let repeats: u32 = uint("repeats", repeats)?;
    let width = opt_uint("width", width)?;
    let height = opt_uint("height", height)?;
    let max_depth = opt_uint("max_depth", max_depth)?;
    let min_depth = opt_uint("min_depth", min_depth)?;
    let trained_grid = opt_uint("trained_grid", trained_grid)?;
    let trained_spp = opt_uint("trained_spp", trained_spp)?;
    let threads: usize = uint("threads", threads)?;
    let canon = |s: &str| {
        mis::Method::from_str(s)
            .map(|m| m.name().to_string())
            .map_err(|e| PyValueError::new_err(e.to_string()))
    };
    let o = scene::Overrides {
        techniques: techniques
            .as_deref()
            .map(scene::parse_technique_list)
            .transpose()
            .map_err(|e| crate::errors::scene_error(py, &e))?,
        integrator,
        width,
        height,
        per_light,
        max_depth,
        min_depth,
        hide_emitters,
        beta,
        cutoff,
        ridge,
        trained_grid,
        trained_floor,
        trained_spp,
        ..Default::default()
    };
    let s = resolved(py, scene, &o)?;
    let mut base = s.options().map_err(|e| to_py(py, e))?;
    base.pixel_center = pixel_center;
    base.threads = threads;
    base.validate().map_err(PyValueError::new_err)?;
    let mut cfg = ExperimentConfig::new(scene_path(scene), out);
    cfg.command_line = "frepray.experiment (Python)".into();
    let (width, height) = s.resolution();
    cfg.renderer_settings = exp::renderer_settings(&base, width, height);
    cfg.size = Some((width, height));
    cfg.estimators = estimators
        .iter()
        .map(|e| canon(e))
        .collect::<PyResult<_>>()?;
    cfg.spp = spp;
    cfg.reference_spp = reference_spp;
    cfg.reference = reference;
    cfg.reference_estimator = reference_estimator.as_deref().map(canon).transpose()?;
    cfg.baseline = canon(baseline)?;
    cfg.seed = seed;
    cfg.repeats = repeats;
    cfg.decompose = decompose;
    let (result, interrupted) = interrupt::run(py, cancel.as_deref(), |stop| {
        let mut r = SceneRenderer {
            scene: s.clone(),
            base: base.clone(),
            stop,
        };
        exp::run(&cfg, &mut r, &|_| {})
    });
    if let Some(err) = interrupted {
        return Err(err);
    }
    let summary = result.map_err(render_err)?;
    let list = PyList::empty(py);
    for row in &summary.rows {
        let d = PyDict::new(py);
        d.set_item("estimator", &row.estimator)?;
        d.set_item("spp", row.spp)?;
        d.set_item("time_s", row.time_s)?;
        d.set_item("mse", row.mse)?;
        d.set_item("rmse", row.rmse)?;
        d.set_item("relmse", row.relmse)?;
        d.set_item("mse_ci", row.mse_ci.map(|c| c.to_vec()))?;
        d.set_item("rmse_ci", row.rmse_ci.map(|c| c.to_vec()))?;
        d.set_item("trimmed_mse", row.trimmed_mse)?;
        d.set_item("net_mse", row.net_mse)?;
        d.set_item("cpu_s", row.cpu_s)?;
        // With `decompose`: the variance with jittered and centred rays, and the share
        // MIS weights act on.
        d.set_item("variance_jittered", row.variance.map(|v| v.jittered))?;
        d.set_item("variance_centered", row.variance.map(|v| v.centered))?;
        d.set_item("direction_share", row.variance.map(|v| v.direction_share))?;
        let c = summary
            .comparisons
            .iter()
            .find(|c| c.estimator == row.estimator && c.spp == row.spp);
        d.set_item("improvement", c.and_then(|c| c.improvement))?;
        d.set_item(
            "improvement_ci",
            c.and_then(|c| c.improvement_ci).map(|c| c.to_vec()),
        )?;
        d.set_item("improvement_trimmed", c.and_then(|c| c.improvement_trimmed))?;
        d.set_item("median_pixel_ratio", c.and_then(|c| c.median_pixel_ratio))?;
        d.set_item("speed_up", c.and_then(|c| c.speed_up))?;
        d.set_item(
            "speed_up_ci",
            c.and_then(|c| c.speed_up_ci).map(|c| c.to_vec()),
        )?;
        d.set_item("overhead", c.and_then(|c| c.overhead))?;
        list.append(d)?;
    }
    Ok(list)
}
