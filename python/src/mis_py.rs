//! The `mis` estimators over numpy arrays: any integral a researcher samples in numpy
//! (python/frepray/mis.py shapes the arrays and documents the model).

use frepray::estimators::{Estimator, Layout, Method, Params, DEFAULT_TRAIN, DEFAULT_WARMUP};
use numpy::ndarray::Array1;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::str::FromStr;

/// The estimate of `∫ f` by `method` from `f[t]` `(N, n_t, C)` and `pdfs[t]` `(N, n_t,
/// T)`: N iterations of the multi-sample model, each drawing `n_t` samples of every
/// technique t, with f's C channels and all T pdfs at every sample (a sample whose own
/// pdf is 0 counts as failed); `ridge` None: the method's default. Returns float64 `(C,)`.
#[pyfunction]
#[pyo3(signature = (method, f, pdfs, beta = 2.0, cutoff = 0.5, ridge = None,
    warmup = DEFAULT_WARMUP, train = DEFAULT_TRAIN))]
#[allow(clippy::too_many_arguments)]
pub fn mis_estimate<'py>(
    py: Python<'py>,
    method: &str,
    f: Vec<PyReadonlyArray3<'py, f64>>,
    pdfs: Vec<PyReadonlyArray3<'py, f64>>,
    beta: f64,
    cutoff: f64,
    ridge: Option<f64>,
    warmup: u64,
    train: u64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let bad = |m: String| PyValueError::new_err(m);
    let method = Method::from_str(method).map_err(|e| bad(e.to_string()))?;
    let t = f.len();
    if t == 0 || pdfs.len() != t {
        return Err(bad(format!(
            "give f and pdfs for each technique (got {} and {})",
            f.len(),
            pdfs.len()
        )));
    }
    let f: Vec<_> = f.iter().map(|a| a.as_array()).collect();
    let pdfs: Vec<_> = pdfs.iter().map(|a| a.as_array()).collect();
    let (n, c) = (f[0].shape()[0], f[0].shape()[2]);
    let mut counts = vec![];
    for k in 0..t {
        let (fs, ps) = (f[k].shape(), pdfs[k].shape());
        if fs[0] != n || fs[2] != c || fs[1] == 0 || ps != [n, fs[1], t] {
            return Err(bad(format!(
                "technique {k}: f has shape {fs:?} and pdfs {ps:?}; expected ({n}, n_{k}, {c}) \
                 and ({n}, n_{k}, {t}) with n_{k} ≥ 1"
            )));
        }
        counts.push(fs[1] as u32);
    }
    if c == 0 {
        return Err(bad("f needs at least one channel".into()));
    }
    let params = Params {
        beta,
        cutoff,
        ridge,
        warmup,
        train,
    };
    params.validate().map_err(|e| bad(e.to_string()))?;
    let layout = Layout::new(&counts, c);
    let mut e = method
        .build(&layout, &params)
        .map_err(|e| bad(e.to_string()))?;
    let out = py.detach(|| {
        let (mut fv, mut pv) = (vec![0.0; c], vec![0.0; t]);
        for i in 0..n {
            for k in 0..t {
                for j in 0..counts[k] as usize {
                    for (ch, v) in fv.iter_mut().enumerate() {
                        *v = f[k][[i, j, ch]];
                    }
                    for (u, v) in pv.iter_mut().enumerate() {
                        *v = pdfs[k][[i, j, u]];
                    }
                    e.add_sample(k, &fv, &pv);
                }
            }
            e.end_iteration();
        }
        e.estimate_vec()
    });
    Ok(Array1::from(out).into_pyarray(py))
}

/// The estimator names `mis_estimate` accepts.
#[pyfunction]
pub fn mis_methods() -> Vec<&'static str> {
    Method::ALL.iter().map(|m| m.name()).collect()
}
