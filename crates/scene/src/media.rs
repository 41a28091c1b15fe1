//! Participating media: `[media.NAME]` tables resolved to σ_a, σ_s and g, and the
//! objects' `medium` / `exterior` references (docs/scene-format.md, "Media").

use crate::check::number;
use crate::data::{MediumData, MediumId};
use crate::desc::{MediumDesc, SceneDescription};
use crate::error::{kp, SceneError, Seg};
use crate::locate::Source;

/// The media of a description in the order of their names, and the names.
pub(crate) fn media(
    src: &Source,
    d: &SceneDescription,
) -> Result<(Vec<MediumData>, Vec<String>), SceneError> {
    let mut list = Vec::with_capacity(d.media.len());
    for (name, m) in &d.media {
        list.push(medium(src, name, m)?);
    }
    Ok((list, d.media.keys().cloned().collect()))
}

fn medium(src: &Source, name: &str, m: &MediumDesc) -> Result<MediumData, SceneError> {
    let at = kp!["media", name];
    let key = |k: &str| [at.clone(), kp![k]].concat();
    let coefficients = m.sigma_a.is_some() || m.sigma_s.is_some();
    let albedo_form = m.albedo.is_some() || m.mean_free_path.is_some();
    if coefficients && albedo_form {
        let k = if m.albedo.is_some() {
            "albedo"
        } else {
            "mean_free_path"
        };
        return Err(src.at_key(
            &key(k),
            "give sigma_a and sigma_s, or albedo and mean_free_path, not both",
        ));
    }
    let scale = number(
        src,
        &key("scale"),
        m.scale.unwrap_or(1.0),
        0.0,
        f64::INFINITY,
    )?;
    let g = m.g.unwrap_or(0.0);
    // pbrt-v4 clamps g to ±0.99, where sampling the phase function stays stable.
    if !(g.is_finite() && g.abs() <= 0.99) {
        return Err(src.at_value(
            &key("g"),
            format!("expected a number in [-0.99, 0.99], found {g}"),
        ));
    }
    let channels = |k: &str, v: [f64; 3], lo: f64, hi: f64| -> Result<[f64; 3], SceneError> {
        for x in v {
            number(src, &key(k), x, lo, hi)?;
        }
        Ok(v)
    };
    let (sigma_a, sigma_s) = if albedo_form {
        let (Some(albedo), Some(mfp)) = (m.albedo, m.mean_free_path) else {
            let missing = if m.albedo.is_none() {
                "albedo"
            } else {
                "mean_free_path"
            };
            return Err(src.at_key(
                &at,
                format!("a medium given by albedo and mean_free_path needs {missing} too"),
            ));
        };
        let albedo = channels("albedo", albedo.0, 0.0, 1.0)?;
        let mfp = channels("mean_free_path", mfp.0, 0.0, f64::INFINITY)?;
        if mfp.contains(&0.0) {
            return Err(src.at_value(&key("mean_free_path"), "a mean free path must be positive"));
        }
        let sigma_t = mfp.map(|l| scale / l);
        (
            [0, 1, 2].map(|c| sigma_t[c] * (1.0 - albedo[c])),
            [0, 1, 2].map(|c| sigma_t[c] * albedo[c]),
        )
    } else {
        let (Some(a), Some(s)) = (m.sigma_a, m.sigma_s) else {
            let missing = match (m.sigma_a, m.sigma_s) {
                (None, Some(_)) => "needs sigma_a too",
                (Some(_), None) => "needs sigma_s too",
                _ => "needs sigma_a and sigma_s, or albedo and mean_free_path",
            };
            return Err(src.at_key(&at, format!("a medium {missing}")));
        };
        let a = channels("sigma_a", a.0, 0.0, f64::INFINITY)?;
        let s = channels("sigma_s", s.0, 0.0, f64::INFINITY)?;
        (a.map(|x| x * scale), s.map(|x| x * scale))
    };
    Ok(MediumData {
        sigma_a,
        sigma_s,
        g,
    })
}

/// The medium an object names at `key` (`medium` or `exterior`), if it names one.
pub(crate) fn medium_ref(
    src: &Source,
    at: &[Seg],
    name: Option<&String>,
    names: &[String],
) -> Result<Option<MediumId>, SceneError> {
    let Some(name) = name else { return Ok(None) };
    match names.iter().position(|n| n == name) {
        Some(i) => Ok(Some(MediumId(i as u32))),
        None => {
            let list = if names.is_empty() {
                "none".to_string()
            } else {
                names.join(", ")
            };
            Err(src.at_value(at, format!("unknown medium {name:?}; defined: {list}")))
        }
    }
}
