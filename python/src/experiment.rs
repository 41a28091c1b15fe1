//! `frepray.experiment`: the estimator comparison of `frepray experiment`, and the
//! metrics it uses (`measure`) for images made elsewhere (e.g. on a Ray cluster).

use crate::errors::{opt_uint, render_err, to_py, uint};
use crate::interrupt::{self, Cancel};
use crate::scene::{keyword, resolved, scene_path, warn, Scene};
use frepray::experiment::{self as exp, ExperimentConfig, Image, SceneRenderer};
use numpy::PyReadonlyArray3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

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
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let d = PyDict::new(py);
    d.set_item("mse", m.mse)?;
    d.set_item("rmse", m.mse.sqrt())?;
    d.set_item("relmse", m.relmse)?;
    d.set_item("trimmed_mse", m.trimmed_mse)?;
    d.set_item("nonfinite", m.nonfinite)?;
    Ok(d)
}

/// The tables of renders measured elsewhere (e.g. Ray tasks): `renders` is a list of
/// dicts with estimator, spp, seed, time_s and `measure`'s mse, relmse, trimmed_mse;
/// returns `experiment`'s records (points averaged over seeds, with intervals from two
/// seeds on, and Improvement / Speed Up / Overhead against `baseline`), computed by the
/// same code.
#[pyfunction]
#[pyo3(signature = (renders, baseline = "balance", reference_noise = None))]
pub fn summarize<'py>(
    py: Python<'py>,
    renders: Vec<Bound<'py, PyDict>>,
    baseline: &str,
    reference_noise: Option<f64>,
) -> PyResult<Bound<'py, PyList>> {
    let get = |d: &Bound<'py, PyDict>, k: &str| -> PyResult<Bound<'py, PyAny>> {
        d.get_item(k)?
            .ok_or_else(|| PyValueError::new_err(format!("a render without {k:?}")))
    };
    let canon = |e: &str| exp::canonical(e).map_err(|e| PyValueError::new_err(e.to_string()));
    let measured = renders
        .iter()
        .map(|d| {
            let mse: f64 = get(d, "mse")?.extract()?;
            Ok(exp::Measured {
                estimator: canon(&get(d, "estimator")?.extract::<String>()?)?,
                spp: uint("spp", get(d, "spp")?.extract()?)?,
                seed: uint("seed", get(d, "seed")?.extract()?)?,
                time_s: get(d, "time_s")?.extract()?,
                metrics: exp::Metrics {
                    mse,
                    relmse: get(d, "relmse")?.extract()?,
                    trimmed_mse: match d.get_item("trimmed_mse")? {
                        Some(v) => v.extract()?,
                        None => f64::NAN,
                    },
                    nonfinite: match d.get_item("nonfinite")? {
                        Some(v) => v.extract()?,
                        None => 0,
                    },
                },
            })
        })
        .collect::<PyResult<Vec<_>>>()?;
    let summary = exp::summarize(&measured, &canon(baseline)?, reference_noise);
    records(py, &summary)
}

/// Runs the comparison: a reference (`reference_spp` samples, or the EXR `reference`),
/// then every estimator at every spp, written to `out` (results.json, results.csv,
/// summary.md, plots, images; a rerun resumes). Returns one dict per (estimator, spp):
/// estimator, spp, time_s, mse, rmse, relmse, mse_ci, rmse_ci, trimmed_mse, net_mse,
/// cpu_s, improvement, improvement_ci, improvement_trimmed, median_pixel_ratio,
/// speed_up, speed_up_ci, overhead (intervals as [lo, hi] or None with one seed), and
/// with `decompose` variance_jittered, variance_centered, direction_share. With
/// `budget` (processor seconds) each estimator renders the spp that fill it and is
/// compared at equal time (`spp` is not used). An estimator may bring its own
/// techniques (`power@light-bvh+bsdf`); `practice` adds the best heuristic practice as
/// baselines (the CLI's `--practice`). The other
/// arguments are the CLI's flags of the same names (`per_light` is `--per-light`, and so
/// on); `threads` 0 uses every core. Ctrl-C and `cancel` stop it (KeyboardInterrupt,
/// `frepray.Cancelled`) with what finished written to `out`, as the CLI does.
#[pyfunction]
#[pyo3(signature = (scene, out, estimators, spp, reference_spp = 256, reference = None,
    reference_estimator = None, baseline = "balance", seed = 0, repeats = i128::from(exp::DEFAULT_REPEATS),
    techniques = None, integrator = None, width = None, height = None, per_light = false,
    pixel_center = false, decompose = false, max_depth = None, min_depth = None,
    hide_emitters = false, beta = None, cutoff = None, ridge = None, trained_grid = None,
    trained_floor = None, trained_spp = None, threads = 0, cancel = None, budget = None,
    practice = false))]
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
    budget: Option<f64>,
    practice: bool,
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
    let o = frepray::Overrides {
        techniques: crate::errors::techniques(py, techniques.as_deref())?,
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
    let settings = frepray::Settings {
        overrides: o,
        threads,
        pixel_center,
        ..Default::default()
    };
    let (base, _) = s.options_with(&settings).map_err(|e| to_py(py, e))?;
    // An estimator, or a variant with its own techniques (`power@light-bvh+bsdf`).
    let parse = |e: &str| {
        exp::variant::parse(e)
            .map(|v| v.method)
            .map_err(|e| PyValueError::new_err(e.to_string()))
    };
    let methods = estimators
        .iter()
        .map(|e| parse(e))
        .collect::<PyResult<Vec<_>>>()?;
    parse(baseline)?;
    reference_estimator.as_deref().map(parse).transpose()?;
    for u in frepray::settings::unused_in_sweep(&settings.overrides, &base, &methods) {
        warn(py, &u.message(keyword))?;
    }
    let estimators = match practice {
        true => exp::variant::with_practice(&s, &estimators),
        false => estimators,
    };
    let mut cfg = ExperimentConfig::for_scene(
        &s,
        &base,
        scene_path(scene),
        out,
        &estimators,
        baseline,
        reference_estimator.as_deref(),
    )
    .map_err(|e| to_py(py, e))?;
    cfg.command_line = "frepray.experiment (Python)".into();
    cfg.spp = spp;
    cfg.reference_spp = reference_spp;
    cfg.reference = reference;
    cfg.seed = seed;
    cfg.repeats = repeats;
    cfg.decompose = decompose;
    cfg.budget = budget;
    let (result, interrupted) = interrupt::run(py, cancel.as_deref(), |stop| {
        let mut r = SceneRenderer::new(&s, base.clone(), stop, &|_| {});
        exp::run(&cfg, &mut r, &|_| {})
    });
    if let Some(err) = interrupted {
        return Err(err);
    }
    let summary = result.map_err(render_err)?;
    records(py, &summary)
}

/// One dict per (estimator, spp) point of a summary, with its comparison.
fn records<'py>(py: Python<'py>, summary: &exp::Summary) -> PyResult<Bound<'py, PyList>> {
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
