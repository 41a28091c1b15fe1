//! Per-pixel comparison maps: where in the image an estimator gains on the baseline.
//! A ratio of whole-image MSEs can be carried by a few pixels; the median of the
//! per-pixel ratios and the map show whether most of the image gains.

use super::{exr_io, image_file, metrics, stats, ExperimentError, Image};
use std::collections::HashMap;
use std::path::Path;

/// Per pixel, the squared error averaged over channels and over the renders `files`
/// (relative to `out`); `None` if one cannot be read or has another size.
fn mean_errors(out: &Path, files: &[String], reference: &Image) -> Option<Vec<f64>> {
    let mut sum = vec![0.0; reference.rgb.len()];
    for f in files {
        let img = exr_io::read(&out.join(f)).ok()?;
        let (_, sq) = metrics::measure(&img, reference).ok()?;
        for (s, e) in sum.iter_mut().zip(&sq) {
            *s += (e[0] + e[1] + e[2]) / 3.0;
        }
    }
    let k = files.len() as f64;
    Some(sum.into_iter().map(|s| s / k).collect())
}

/// The map's colour of a ratio r (baseline / method): log₂ r clamped to ±3, green where
/// the method is better, red where worse, white where equal, grey where undefined.
fn colour(r: f64) -> [u8; 3] {
    if r.is_nan() {
        return [128, 128, 128];
    }
    let t = (r.log2() / 3.0).clamp(-1.0, 1.0);
    let towards = if t > 0.0 {
        [30.0, 150.0, 60.0]
    } else {
        [200.0, 30.0, 30.0]
    };
    towards.map(|c| (255.0 + (c - 255.0) * t.abs()).round() as u8)
}

/// Writes `maps/EST-NNNNNspp-vs-BASELINE.{exr,png}` for each complete point of an
/// estimator other than `baseline` (EXR: the ratio in R, G and B) and returns the median
/// per-pixel ratio of each (estimator, spp).
pub fn write(
    out: &Path,
    points: &[(String, u32)],
    seeds: &[u64],
    baseline: &str,
    reference: &Image,
) -> Result<HashMap<(String, u32), f64>, ExperimentError> {
    let dir = out.join("maps");
    std::fs::create_dir_all(&dir).map_err(ExperimentError::io("create", &dir))?;
    let files = |est: &str, spp: u32| -> Vec<String> {
        seeds.iter().map(|&s| image_file(est, spp, s)).collect()
    };
    let mut medians = HashMap::new();
    let mut base_cache: HashMap<u32, Option<Vec<f64>>> = HashMap::new();
    for (est, spp) in points.iter().filter(|(e, _)| e != baseline) {
        let base = base_cache
            .entry(*spp)
            .or_insert_with(|| mean_errors(out, &files(baseline, *spp), reference));
        let (Some(base), Some(own)) = (
            base.as_ref(),
            mean_errors(out, &files(est, *spp), reference),
        ) else {
            continue;
        };
        let ratios: Vec<f64> = base
            .iter()
            .zip(&own)
            .map(|(&b, &m)| {
                if b == 0.0 && m == 0.0 {
                    f64::NAN
                } else {
                    b / m
                }
            })
            .collect();
        let mut defined: Vec<f64> = ratios.iter().copied().filter(|r| !r.is_nan()).collect();
        if !defined.is_empty() {
            medians.insert((est.clone(), *spp), stats::median(&mut defined));
        }
        let stem = dir.join(format!(
            "{}-{spp:05}spp-vs-{}",
            super::variant::label(est),
            super::variant::label(baseline)
        ));
        let map = Image {
            width: reference.width,
            height: reference.height,
            rgb: ratios.iter().map(|&r| [r; 3]).collect(),
        };
        exr_io::write(&stem.with_extension("exr"), &map, None)?;
        let bytes: Vec<u8> = ratios.iter().flat_map(|&r| colour(r)).collect();
        let png = stem.with_extension("png");
        render::output::write_atomically(&png, |f| {
            render::png_io::write_rgb8(f, &bytes, map.width, map.height)
        })
        .map_err(ExperimentError::io("write", &png))?;
    }
    Ok(medians)
}
