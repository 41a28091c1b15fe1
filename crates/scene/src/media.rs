//! Participating media: `[media.NAME]` tables resolved to σ_t, an albedo texture and g,
//! and the objects' `medium` / `exterior` references (docs/scene-format.md, "Media").

use crate::check::number;
use crate::data::{MediumData, MediumId, TextureData, TextureId};
use crate::desc::{ColorDesc, MediumDesc, SceneDescription};
use crate::error::{kp, SceneError, Seg};
use crate::locate::Source;

/// Resolves an albedo colour at a key into the scene's texture pool: its id and data.
pub(crate) type AlbedoTexture<'a> =
    dyn FnMut(&[Seg], &ColorDesc) -> Result<(TextureId, TextureData), SceneError> + 'a;

/// The media of a description in the order of their names, and the names; `texture`
/// resolves an albedo colour into the scene's texture pool (values in [0, 1]).
pub(crate) fn media(
    src: &Source,
    d: &SceneDescription,
    texture: &mut AlbedoTexture,
) -> Result<(Vec<MediumData>, Vec<String>), SceneError> {
    let mut list = Vec::with_capacity(d.media.len());
    for (name, m) in &d.media {
        list.push(medium(src, name, m, texture)?);
    }
    Ok((list, d.media.keys().cloned().collect()))
}

fn medium(
    src: &Source,
    name: &str,
    m: &MediumDesc,
    texture: &mut AlbedoTexture,
) -> Result<MediumData, SceneError> {
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
    let (sigma_t, albedo) = if albedo_form {
        let (Some(albedo), Some(mfp)) = (&m.albedo, m.mean_free_path) else {
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
        let mfp = channels("mean_free_path", mfp.0, 0.0, f64::INFINITY)?;
        if mfp.contains(&0.0) {
            return Err(src.at_value(&key("mean_free_path"), "a mean free path must be positive"));
        }
        if matches!(albedo, ColorDesc::Image(_)) {
            return Err(src.at_value(
                &key("albedo"),
                "a medium's albedo may be a colour, a point-space checker or a pattern \
                 (an image needs a surface)",
            ));
        }
        let (id, data) = texture(&key("albedo"), albedo)?;
        if let TextureData::Checker {
            space: crate::data::TextureSpace::Uv,
            ..
        } = data
        {
            return Err(src.at_value(
                &key("albedo"),
                "a medium has no uv coordinates: use a point-space checker",
            ));
        }
        (mfp.map(|l| scale / l), id)
    } else {
        let (Some(a), Some(s)) = (m.sigma_a, m.sigma_s) else {
            let missing = match (m.sigma_a, m.sigma_s) {
                (None, Some(_)) => "needs sigma_a too",
                (Some(_), None) => "needs sigma_s too",
                _ => "needs sigma_a and sigma_s, or albedo and mean_free_path",
            };
            return Err(src.at_key(&at, format!("a medium {missing}")));
        };
        let a = channels("sigma_a", a.0, 0.0, f64::INFINITY)?.map(|x| x * scale);
        let s = channels("sigma_s", s.0, 0.0, f64::INFINITY)?.map(|x| x * scale);
        let t = [0, 1, 2].map(|c| a[c] + s[c]);
        let albedo = [0, 1, 2].map(|c| if t[c] > 0.0 { s[c] / t[c] } else { 0.0 });
        let (id, _) = texture(&key("sigma_s"), &ColorDesc::Rgb(albedo))?;
        (t, id)
    };
    Ok(MediumData { sigma_t, albedo, g })
}

/// The medium an object names at `at` (`medium` or `exterior`), if it names one.
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
