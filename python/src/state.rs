//! Render states: per-pixel sums over sample ranges (docs/render-state.md), their
//! images as numpy arrays, merging and the serialised form.

use crate::errors::render_err;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};
use std::path::PathBuf;

/// The sums of a render over one or more sample ranges (`frepray.render`). States of
/// disjoint ranges of one render merge into the render of their union.
#[pyclass(module = "frepray")]
pub struct RenderState {
    inner: frepray::RenderState,
}

impl RenderState {
    /// The library's state.
    pub fn inner(&self) -> &frepray::RenderState {
        &self.inner
    }
}

impl From<frepray::RenderState> for RenderState {
    fn from(inner: frepray::RenderState) -> Self {
        RenderState { inner }
    }
}

/// An image's channels `first..first + n` as a float32 array `(h, w, n)`.
fn channels(img: &frepray::Image, first: usize, n: usize) -> Array3<f32> {
    let (w, h, c) = (img.width() as usize, img.height() as usize, img.channels());
    let v: Vec<f32> = img
        .data()
        .chunks_exact(c)
        .flat_map(|p| p[first..first + n].iter().map(|&x| x as f32))
        .collect();
    Array3::from_shape_vec((h, w, n), v).expect("image size")
}

/// `(rgb, {aov: array})` of an image, in float32 as the EXR holds them.
fn image_arrays<'py>(
    py: Python<'py>,
    img: &frepray::Image,
) -> PyResult<(Bound<'py, PyArray3<f32>>, Bound<'py, PyDict>)> {
    let rgb = channels(img, 0, 3).into_pyarray(py);
    let aovs = PyDict::new(py);
    for (k, name) in img.aov_names().iter().enumerate() {
        let a = channels(img, 3 + k, 1);
        let (h, w) = (a.shape()[0], a.shape()[1]);
        let a = a.into_shape_with_order((h, w)).expect("one channel");
        aovs.set_item(name, a.into_pyarray(py))?;
    }
    Ok((rgb, aovs))
}

#[pymethods]
impl RenderState {
    /// The image: linear RGB as float32 `(height, width, 3)` (the values an EXR holds).
    fn image<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let img = py.detach(|| self.inner.image());
        Ok(image_arrays(py, &img)?.0)
    }
    /// The AOV channels (e.g. `depth`, `normal.X`, `albedo.R`) as float32 `(h, w)`.
    fn aovs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let img = py.detach(|| self.inner.image());
        Ok(image_arrays(py, &img)?.1)
    }
    /// What an EXR of this state records in its header (`frepray.settings`,
    /// `frepray.scene_hash`, …), as a dict of strings.
    fn attributes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let img = py.detach(|| self.inner.image());
        let out = PyDict::new(py);
        for (name, value) in img.attributes() {
            out.set_item(name, value)?;
        }
        Ok(out)
    }
    /// The AOV channel names, in order.
    fn aov_names(&self) -> Vec<String> {
        self.inner.image().aov_names().to_vec()
    }
    /// The image in float64 `(h, w, 3 + AOVs)`, unrounded.
    fn image_f64<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let img = py.detach(|| self.inner.image());
        let (w, h, c) = (img.width() as usize, img.height() as usize, img.channels());
        Array3::from_shape_vec((h, w, c), img.data().to_vec())
            .expect("image size")
            .into_pyarray(py)
    }
    /// The raw per-pixel sums, float64 `(h, w, stride)` (docs/render-state.md).
    fn sums<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let (w, h) = (self.width() as usize, self.height() as usize);
        let d = self.inner.data();
        let stride = d.len().checked_div(w * h).unwrap_or(0);
        Array3::from_shape_vec((h, w, stride), d.to_vec())
            .expect("state size")
            .into_pyarray(py)
    }
    /// Samples each pixel got, uint64 `(h, w)`.
    fn sample_counts<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u64>> {
        let (w, h) = (self.width(), self.height());
        let v = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| self.inner.iterations(x, y))
            .collect();
        Array2::from_shape_vec((h as usize, w as usize), v)
            .expect("state size")
            .into_pyarray(py)
    }
    /// Width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.inner.header().width
    }
    /// Height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.inner.header().height
    }
    /// The sample ranges held, as `[(start, end), …]`.
    #[getter]
    fn samples(&self) -> Vec<(u32, u32)> {
        self.inner
            .samples()
            .iter()
            .map(|r| (r.start, r.end))
            .collect()
    }
    /// Whether the render was interrupted (pixels did not all get the same range).
    #[getter]
    fn partial(&self) -> bool {
        self.inner.is_partial()
    }
    /// Marks the state partial, as a stopped render's is (kept through merges and the
    /// state file): for a merge of the parts that finished when the rest did not.
    fn mark_partial(&mut self) {
        self.inner.set_partial();
    }
    /// The estimator's name.
    #[getter]
    fn estimator(&self) -> &'static str {
        self.inner.header().method.name()
    }
    /// The seed.
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.header().seed
    }
    /// Adds `other` (disjoint samples of the same render) into this state. Raises
    /// `RenderError` when they do not fit together (the message names the difference).
    fn merge(&mut self, py: Python<'_>, other: &RenderState) -> PyResult<()> {
        py.detach(|| self.inner.merge(&other.inner))
            .map_err(render_err)
    }
    /// A copy of the state.
    fn copy(&self) -> RenderState {
        RenderState {
            inner: self.inner.clone(),
        }
    }
    /// The documented serialised form (docs/render-state.md), as bytes.
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.inner.to_bytes())
    }
    /// A state from `to_bytes` output (or a `.state` file's bytes).
    #[staticmethod]
    fn from_bytes(data: &[u8]) -> PyResult<RenderState> {
        Ok(frepray::RenderState::from_bytes(data)
            .map_err(render_err)?
            .into())
    }
    /// Writes the state file (`frepray merge` reads it).
    fn write(&self, path: PathBuf) -> PyResult<()> {
        self.inner.write(path).map_err(render_err)
    }
    /// Reads a state file (`frepray render --samples A..B -o part.state` writes one).
    #[staticmethod]
    fn read(path: PathBuf) -> PyResult<RenderState> {
        Ok(frepray::RenderState::read(path).map_err(render_err)?.into())
    }
    /// Writes the image as a linear float32 EXR (R, G, B and the AOVs).
    fn write_exr(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| self.inner.image().write_exr(&path))
            .map_err(render_err)
    }
    /// Writes the colour as an 8-bit sRGB PNG (for display).
    fn write_png(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| self.inner.image().write_png(&path))
            .map_err(render_err)
    }
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let f = py
            .import("frepray._native")?
            .getattr("RenderState")?
            .getattr("from_bytes")?;
        Ok((f, PyTuple::new(py, [self.to_bytes(py)])?))
    }
    fn __repr__(&self) -> String {
        format!("<frepray.RenderState {}>", self.inner.summary())
    }
}

/// Merges states of disjoint sample ranges into a new state.
#[pyfunction]
pub fn merge(py: Python<'_>, states: Vec<PyRef<'_, RenderState>>) -> PyResult<RenderState> {
    let mut it = states.iter();
    let first = it.next().ok_or_else(|| render_err("nothing to merge"))?;
    let mut all = first.inner.clone();
    for s in it {
        let other = &s.inner;
        py.detach(|| all.merge(other)).map_err(render_err)?;
    }
    Ok(all.into())
}

/// The header attributes of an EXR as a dict of strings: what `render` and
/// `RenderState.write_exr` record there (`frepray.settings`, `frepray.scene_hash`, …).
#[pyfunction]
pub fn exr_attributes<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let img = frepray::Image::read_exr(&path).map_err(render_err)?;
    let out = PyDict::new(py);
    for (name, value) in img.attributes() {
        out.set_item(name, value)?;
    }
    Ok(out)
}

/// Writes linear RGB `rgb` (float32 `(h, w, 3)`) as an EXR whose header carries
/// `attributes` (a dict of strings), whole or not at all: what `frepray.denoise` writes.
#[pyfunction]
pub fn _write_rgb_exr(
    py: Python<'_>,
    path: PathBuf,
    rgb: numpy::PyReadonlyArray3<'_, f32>,
    attributes: std::collections::BTreeMap<String, String>,
) -> PyResult<()> {
    let a = rgb.as_array();
    let (h, w, c) = (a.shape()[0], a.shape()[1], a.shape()[2]);
    if c != 3 || h == 0 || w == 0 {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "rgb: expected shape (height, width, 3), got {:?}",
            a.shape()
        )));
    }
    let too_big = || pyo3::exceptions::PyValueError::new_err("rgb: the image is too large");
    let (w32, h32) = (
        u32::try_from(w).map_err(|_| too_big())?,
        u32::try_from(h).map_err(|_| too_big())?,
    );
    let mut img = frepray::Image::new(w32, h32, &[]);
    for y in 0..h {
        for x in 0..w {
            let v = [0, 1, 2].map(|k| f64::from(a[[y, x, k]]));
            img.pixel_mut(x as u32, y as u32)[..3].copy_from_slice(&v);
        }
    }
    for (name, value) in &attributes {
        img.set_attribute(name, value.as_str());
    }
    py.detach(|| img.write_exr(&path))
        .map_err(|e| pyo3::exceptions::PyOSError::new_err(format!("{}: {e}", path.display())))
}

/// Reads an EXR: `(rgb float32 (h, w, 3), {aov: float32 (h, w)})`.
#[pyfunction]
pub fn read_exr<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<(Bound<'py, PyArray3<f32>>, Bound<'py, PyDict>)> {
    let img = frepray::Image::read_exr(&path).map_err(render_err)?;
    image_arrays(py, &img)
}
