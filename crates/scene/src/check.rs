//! Checks shared by every part of resolution: finite vectors, numbers in a range, keys a
//! `type` takes, rotations and transforms. Errors point at the offending key.

use crate::desc::{RotateDesc, TransformDesc};
use crate::error::{kp, SceneError, Seg};
use crate::locate::Source;
use frep::Affine;
use glam::DVec3;

/// The largest magnitude a number in a scene may have: beyond it, products in the light
/// transport (a power times a BSDF times a squared distance, the optimal estimators' sums
/// of squares) overflow to infinity and the pixels turn NaN without a word.
pub const MAX_MAGNITUDE: f64 = 1e30;

/// The error for a finite `v` beyond [`MAX_MAGNITUDE`].
fn too_large(src: &Source, at: &[Seg], v: f64) -> SceneError {
    src.at_value(
        at,
        format!(
            "{v:e} is too large: scene numbers are at most {MAX_MAGNITUDE:e} in magnitude \
             (larger ones overflow the light transport's sums)"
        ),
    )
}

/// A finite vector.
pub(crate) fn vec3(src: &Source, at: &[Seg], v: [f64; 3]) -> Result<DVec3, SceneError> {
    let d = DVec3::from_array(v);
    if !d.is_finite() {
        return Err(src.at_value(at, "expected finite numbers"));
    }
    match v.iter().find(|x| x.abs() > MAX_MAGNITUDE) {
        Some(&x) => Err(too_large(src, at, x)),
        None => Ok(d),
    }
}

/// A finite, non-zero vector, normalised.
pub(crate) fn unit(src: &Source, at: &[Seg], v: [f64; 3]) -> Result<DVec3, SceneError> {
    let d = vec3(src, at, v)?;
    if d.length() == 0.0 {
        return Err(src.at_value(at, "expected a non-zero direction"));
    }
    Ok(d.normalize())
}

/// A finite number within `lo..=hi`.
pub(crate) fn number(
    src: &Source,
    at: &[Seg],
    v: f64,
    lo: f64,
    hi: f64,
) -> Result<f64, SceneError> {
    if v.is_finite() && v >= lo && v <= hi {
        if v.abs() > MAX_MAGNITUDE {
            return Err(too_large(src, at, v));
        }
        Ok(v)
    } else {
        let what = match (lo == f64::NEG_INFINITY, hi == f64::INFINITY) {
            (true, true) => "a finite number".to_string(),
            // The smallest positive double stands for "> 0": say so, not its 300 digits.
            (false, true) if lo == f64::MIN_POSITIVE => "a positive number".to_string(),
            (false, false) if lo == f64::MIN_POSITIVE => format!("a number in (0, {hi}]"),
            (false, true) => format!("a number ≥ {lo}"),
            (true, false) => format!("a number ≤ {hi}"),
            (false, false) => format!("a number in [{lo}, {hi}]"),
        };
        Err(src.at_value(at, format!("expected {what}, found {v}")))
    }
}

/// Rejects keys given for a `kind` that does not take them.
pub(crate) fn check_keys(
    src: &Source,
    at: &[Seg],
    what: &str,
    present: &[(&str, bool)],
    allowed: &[&str],
) -> Result<(), SceneError> {
    for &(key, given) in present {
        if given && !allowed.contains(&key) {
            let mut p = at.to_vec();
            p.push(key.into());
            let valid = allowed.join(", ");
            return Err(src.at_key(
                &p,
                format!("{what} takes no key {key:?} (its keys: {valid})"),
            ));
        }
    }
    Ok(())
}

/// A rotation by `degrees` about `axis`.
pub(crate) fn rotation(src: &Source, at: &[Seg], r: &RotateDesc) -> Result<Affine, SceneError> {
    let key = |k: &str| [at.to_vec(), kp![k]].concat();
    let axis = vec3(src, &key("axis"), r.axis)?;
    if axis.length() == 0.0 {
        return Err(src.at_value(&key("axis"), "the rotation axis is zero"));
    }
    let deg = number(
        src,
        &key("degrees"),
        r.degrees,
        f64::NEG_INFINITY,
        f64::INFINITY,
    )?;
    Ok(Affine::rotate(axis, deg.to_radians()))
}

/// Steps applied first to last.
pub(crate) fn transform(src: &Source, at: &[Seg], t: &TransformDesc) -> Result<Affine, SceneError> {
    let mut acc = Affine::IDENTITY;
    for (j, s) in t.steps.iter().enumerate() {
        let mut p = at.to_vec();
        if t.list {
            p.push(j.into());
        }
        let key = |k: &str| [p.clone(), kp![k]].concat();
        let step = match (s.translate, s.rotate, s.scale) {
            (Some(v), None, None) => Affine::translate(vec3(src, &key("translate"), v)?),
            (None, Some(r), None) => rotation(src, &key("rotate"), &r)?,
            (None, None, Some(sc)) => {
                let v = vec3(src, &key("scale"), sc.0)?;
                if v.x * v.y * v.z == 0.0 {
                    return Err(src.at_value(&key("scale"), "a scale factor is zero"));
                }
                Affine::scale(v)
            }
            _ => {
                return Err(src.at_value(&p, "a transform step takes exactly one of translate, rotate, scale (use a list for several)"))
            }
        };
        acc = acc.then(&step);
    }
    Ok(acc)
}
