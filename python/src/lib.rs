//! # frepray-py — the `frepray._native` extension module
//!
//! Python bindings of the `frepray` library: scenes (files or dicts), renders of sample
//! ranges into mergeable render states (numpy images), bare models (evaluation and
//! preview), the `mis` estimators over numpy sample arrays, and estimator experiments.
//! The Python package `frepray` (python/frepray) re-exports these and adds what is
//! easier in Python (dicts as JSON, pandas tables, Ray). Renders run with the GIL
//! released; Ctrl-C, a `Cancel` handle or the interpreter's exit stop them (modules
//! `interrupt`, `sigint`).
#![warn(missing_docs)]

mod bench;
mod errors;
mod experiment;
mod gpu;
mod interrupt;
mod mis_py;
mod model;
mod scene;
mod sigint;
mod state;
mod view;

use pyo3::prelude::*;

/// The module: classes, functions and exceptions.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<errors::Error>())?;
    m.add("SceneError", py.get_type::<errors::SceneError>())?;
    m.add("RenderError", py.get_type::<errors::RenderError>())?;
    m.add("ModelError", py.get_type::<errors::ModelError>())?;
    m.add("Cancelled", py.get_type::<errors::Cancelled>())?;
    m.add_class::<interrupt::Cancel>()?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<state::RenderState>()?;
    m.add_class::<model::Model>()?;
    m.add_class::<view::Viewer>()?;
    m.add_function(wrap_pyfunction!(scene::load, m)?)?;
    m.add_function(wrap_pyfunction!(scene::load_json, m)?)?;
    m.add_function(wrap_pyfunction!(scene::render, m)?)?;
    m.add_function(wrap_pyfunction!(scene::_scene_from_source, m)?)?;
    m.add_function(wrap_pyfunction!(state::merge, m)?)?;
    m.add_function(wrap_pyfunction!(state::read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(state::exr_attributes, m)?)?;
    m.add_function(wrap_pyfunction!(state::_write_rgb_exr, m)?)?;
    m.add_function(wrap_pyfunction!(model::model, m)?)?;
    m.add_function(wrap_pyfunction!(mis_py::mis_estimate, m)?)?;
    m.add_function(wrap_pyfunction!(mis_py::mis_methods, m)?)?;
    m.add_function(wrap_pyfunction!(experiment::experiment, m)?)?;
    m.add_function(wrap_pyfunction!(experiment::measure, m)?)?;
    m.add_function(wrap_pyfunction!(experiment::summarize, m)?)?;
    m.add("gpu_available", gpu::GpuAvailable)?;
    m.add_function(wrap_pyfunction!(gpu::configure_gpu, m)?)?;
    m.add_function(wrap_pyfunction!(gpu::gpu_adapters, m)?)?;
    m.add_function(wrap_pyfunction!(bench::bench, m)?)?;
    let at_exit = wrap_pyfunction!(interrupt::_at_exit, m)?;
    py.import("atexit")?.call_method1("register", (&at_exit,))?;
    m.add_function(at_exit)?;
    Ok(())
}
