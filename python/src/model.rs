//! Bare models (.frep, .hf, .vm, or their text): F and ∇F at many points, bounds, and
//! the preview picture `frepray render MODEL` makes.

use crate::errors::{to_py, uint, ModelError};
use crate::interrupt::{self, Cancel};
use crate::state::RenderState;
use frepray::model::{read_file, read_str, Format};
use frepray::model::{Expr, Solid, Surface};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::Path;

/// A solid `F(x, y, z) ≥ 0` read from a model file or text (`frepray.model`).
#[pyclass(module = "frepray", frozen)]
pub struct Model {
    name: Option<String>,
    expr: Expr,
    solid: Solid,
}

/// The points of an `(N, 3)` array.
fn points(p: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<[f64; 3]>> {
    let a = p.as_array();
    if a.ncols() != 3 {
        return Err(PyValueError::new_err(format!(
            "points: expected shape (N, 3), got {:?}",
            a.shape()
        )));
    }
    Ok(a.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
}

#[pymethods]
impl Model {
    /// F at each row of `points` (float64 `(N, 3)`): float64 `(N,)`, ≥ 0 inside.
    fn eval<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let p = self::points(&points)?;
        let v: Vec<f64> = py.detach(|| {
            let mut scratch = Vec::with_capacity(self.expr.len());
            p.iter()
                .map(|q| self.expr.eval_with(q[0], q[1], q[2], &mut scratch))
                .collect()
        });
        Ok(Array1::from(v).into_pyarray(py))
    }
    /// F and ∇F (forward-mode derivatives) at each row of `points`: `(values (N,),
    /// gradients (N, 3))`.
    #[allow(clippy::type_complexity)]
    fn gradient<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>)> {
        let p = self::points(&points)?;
        let (v, g): (Vec<f64>, Vec<[f64; 3]>) =
            py.detach(|| p.iter().map(|q| self.expr.gradient(*q)).unzip());
        let g = Array2::from_shape_vec((g.len(), 3), g.concat()).expect("N x 3");
        Ok((Array1::from(v).into_pyarray(py), g.into_pyarray(py)))
    }
    /// A closed triangle mesh of the surface with `resolution` cubes along the longest
    /// side of the bounds (`frepray mesh`): `(vertices float64 (V, 3), triangles uint32
    /// (T, 3))`, triangles counter-clockwise seen from outside, vertices on F = 0.
    #[pyo3(signature = (resolution = 256))]
    #[allow(clippy::type_complexity)]
    fn mesh<'py>(
        &self,
        py: Python<'py>,
        resolution: i64,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<u32>>)> {
        let resolution = u32::try_from(resolution).unwrap_or(0);
        let bounds = self.solid.bounds();
        let m = py
            .detach(|| frepray::mesh_solid(&self.expr, &bounds, resolution))
            .map_err(|e| PyValueError::new_err(e.to_string()))?
            .mesh;
        let v = Array2::from_shape_vec((m.vertices.len(), 3), m.vertices.concat()).expect("V x 3");
        let t =
            Array2::from_shape_vec((m.triangles.len(), 3), m.triangles.concat()).expect("T x 3");
        Ok((v.into_pyarray(py), t.into_pyarray(py)))
    }
    /// The solid's bounding box `((x0, y0, z0), (x1, y1, z1))`.
    #[getter]
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let b = self.solid.bounds();
        (b.lo.to_array(), b.hi.to_array())
    }
    /// The model's name, when the file gives one.
    #[getter]
    fn name(&self) -> Option<String> {
        self.name.clone()
    }
    /// Nodes of the deduplicated expression DAG.
    #[getter]
    fn nodes(&self) -> usize {
        self.expr.len()
    }
    /// The preview picture (framing camera, key light and sky; `look` "shaded",
    /// "depth" or "normals"; `up` "x", "y" or "z") as a `RenderState`. Ctrl-C and
    /// `cancel` stop it as they stop `frepray.render`.
    #[pyo3(signature = (width = 320, height = 240, spp = 4, look = "shaded", up = "z",
        cancel = None))]
    #[allow(clippy::too_many_arguments)]
    fn preview(
        &self,
        py: Python<'_>,
        width: i128,
        height: i128,
        spp: i128,
        look: &str,
        up: &str,
        cancel: Option<PyRef<'_, Cancel>>,
    ) -> PyResult<RenderState> {
        use frepray::preview::{Look, Up};
        let (width, height, spp): (u32, u32, u32) = (
            uint("width", width)?,
            uint("height", height)?,
            uint("spp", spp)?,
        );
        let look = match look {
            "shaded" => Look::Shaded,
            "depth" => Look::Depth,
            "normals" => Look::Normals,
            l => {
                return Err(PyValueError::new_err(format!(
                    "look {l:?}: shaded, depth or normals"
                )))
            }
        };
        let up = match up {
            "x" => Up::X,
            "y" => Up::Y,
            "z" => Up::Z,
            u => return Err(PyValueError::new_err(format!("up {u:?}: x, y or z"))),
        };
        if width == 0 || height == 0 || spp == 0 {
            return Err(PyValueError::new_err(
                "width, height and spp must be at least 1",
            ));
        }
        let solid = self.solid.clone();
        let (result, interrupted) = interrupt::run(py, cancel.as_deref(), |stop| {
            frepray::preview::render(solid, up, width, height, look, spp, stop, &|_, _| {})
        });
        let state = RenderState::from(result.map_err(|e| to_py(py, e))?.0);
        if let Some(err) = interrupted {
            let _ = err.value(py).setattr("state", Py::new(py, state)?);
            return Err(err);
        }
        Ok(state)
    }
    fn __repr__(&self) -> String {
        format!(
            "<frepray.Model {} ({} nodes)>",
            self.name.as_deref().unwrap_or("unnamed"),
            self.expr.len()
        )
    }
}

/// A model from a file path (.frep, .hf, .vm) or from text (`format` "frep", "hf" or
/// "vm"; default "frep"). Raises `ModelError`.
#[pyfunction]
#[pyo3(signature = (source, format = None))]
pub fn model(py: Python<'_>, source: &str, format: Option<&str>) -> PyResult<Model> {
    let path = Path::new(source);
    let is_file = format.is_none() && !source.contains('\n') && path.is_file();
    let read = if is_file {
        read_file(path)
    } else {
        let f = match format.unwrap_or("frep") {
            "frep" => Format::Frep,
            "hf" => Format::HyperFun,
            "vm" => Format::Vm,
            f => {
                return Err(PyValueError::new_err(format!(
                    "format {f:?}: frep, hf or vm"
                )))
            }
        };
        read_str(source, f, "<text>")
    };
    let m = read.map_err(|e| ModelError::new_err(e.to_string()))?;
    let tree = m
        .shape
        .to_tree()
        .map_err(|e| ModelError::new_err(e.to_string()))?;
    let expr = Expr::new(&tree);
    let solid = py
        .detach(|| Solid::build(&m.shape))
        .map_err(|e| ModelError::new_err(e.to_string()))?;
    Ok(Model {
        name: m.name,
        expr,
        solid,
    })
}
