//! The exception hierarchy: `frepray.Error` and its subclasses, and the conversion of
//! the library's errors into them.

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;

create_exception!(frepray, Error, PyException, "Any frepray error.");
create_exception!(
    frepray,
    SceneError,
    Error,
    "A malformed scene: `.file`, `.line`, `.column` (0 when unknown), `.key` (key path, \
     e.g. `objects[1].solid`) and `.message`."
);
create_exception!(
    frepray,
    RenderError,
    Error,
    "Rendering, a render state or a render option failed."
);
create_exception!(
    frepray,
    Cancelled,
    Error,
    "A render stopped by its `frepray.Cancel` handle: `.state` holds what it rendered (a \
     partial state; None for an experiment)."
);
create_exception!(
    frepray,
    ModelError,
    Error,
    "A model could not be read or built."
);

/// `techniques` text (`name:count,…`, as the command line takes it) parsed; a
/// malformed list is a `frepray.SceneError`.
pub fn techniques(
    py: Python<'_>,
    text: Option<&str>,
) -> PyResult<Option<Vec<frepray::TechniqueDesc>>> {
    text.map(frepray::parse_technique_list)
        .transpose()
        .map_err(|e| scene_error(py, &e))
}

/// A [`frepray::SceneError`] as `frepray.SceneError` with its location as attributes.
pub fn scene_error(py: Python<'_>, e: &frepray::SceneError) -> PyErr {
    let err = SceneError::new_err(e.to_string());
    let v = err.value(py);
    let set = |k: &str, val: Bound<'_, PyAny>| {
        let _ = v.setattr(k, val);
    };
    set("file", e.file.clone().into_pyobject(py).unwrap().into_any());
    set("line", e.line.into_pyobject(py).unwrap().into_any());
    set("column", e.column.into_pyobject(py).unwrap().into_any());
    set("key", e.key.clone().into_pyobject(py).unwrap().into_any());
    set(
        "message",
        e.message.clone().into_pyobject(py).unwrap().into_any(),
    );
    err
}

/// A library error as the matching exception.
pub fn to_py(py: Python<'_>, e: frepray::Error) -> PyErr {
    match e {
        frepray::Error::Scene(s) => scene_error(py, &s),
        frepray::Error::Render(r) => RenderError::new_err(r.to_string()),
        e @ (frepray::Error::Model { .. } | frepray::Error::Read(_)) => {
            ModelError::new_err(e.to_string())
        }
        frepray::Error::Invalid(m) => RenderError::new_err(m),
        frepray::Error::Gpu(g) => RenderError::new_err(g.to_string()),
    }
}

/// A render-crate error as `frepray.RenderError`.
pub fn render_err(e: impl std::fmt::Display) -> PyErr {
    RenderError::new_err(e.to_string())
}

/// An integer argument in `T`'s range, or ValueError naming it. Arguments are taken as
/// `i128` and converted here because pyo3's own conversion raises OverflowError without
/// the argument's name for `spp=-1`.
pub fn uint<T: TryFrom<i128>>(name: &str, v: i128) -> PyResult<T> {
    T::try_from(v).map_err(|_| {
        PyValueError::new_err(if v < 0 {
            format!("{name}: expected a non-negative integer, found {v}")
        } else {
            format!("{name}: {v} is too large")
        })
    })
}

/// [`uint`] of an optional argument.
pub fn opt_uint<T: TryFrom<i128>>(name: &str, v: Option<i128>) -> PyResult<Option<T>> {
    v.map(|v| uint(name, v)).transpose()
}
