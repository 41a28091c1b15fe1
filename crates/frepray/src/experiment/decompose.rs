//! Whether MIS could help an image at all: each pixel's variance split into the part
//! from where in the pixel the camera ray goes (the footprint) and the part from the
//! directions sampled at its hit point, which is all that MIS weights act on.
//!
//! By the law of total variance, a pixel sample's variance is
//! `Var[E(X | u)] + E[Var(X | u)]` over the sub-pixel position u. Rendering the same
//! seeds with every ray through the pixel centre removes the first term, and leaves the
//! second as it is at the centre, which stands for its average over the pixel. Over the
//! seeds of a point, the per-pixel sample variance of the jittered renders estimates
//! `Var/spp`, that of the centred ones `Var(X | centre)/spp`; summed over pixels and
//! channels, their ratio is the **direction share** and its complement the **footprint
//! share** of the image's variance (measured shares: docs/experiment.md, "Could MIS
//! help at all?").

use super::manifest::{Manifest, RenderRecord, Row};
use super::{exr_io, image_file, ExperimentError, Image, Plan, Renderer};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The decomposition of one point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Variance {
    /// Σ over pixels and channels of the per-pixel variance over seeds, jittered rays.
    pub jittered: f64,
    /// The same with rays through pixel centres.
    pub centered: f64,
    /// `centered / jittered` (clamped to [0, 1]): the share MIS weights act on.
    pub direction_share: f64,
}

/// The image file of a pixel-centred render, relative to the output folder.
pub fn centered_file(estimator: &str, spp: u32, seed: u64) -> String {
    image_file(estimator, spp, seed).replace(".exr", "-centered.exr")
}

/// Σ over pixels and channels of the sample variance over `images` (≥ 2, same size).
pub fn summed_variance(images: &[Image]) -> f64 {
    let k = images.len() as f64;
    let n = images[0].rgb.len();
    let mut total = 0.0;
    for p in 0..n {
        for c in 0..3 {
            let mean = images.iter().map(|i| i.rgb[p][c]).sum::<f64>() / k;
            total += images
                .iter()
                .map(|i| (i.rgb[p][c] - mean).powi(2))
                .sum::<f64>()
                / (k - 1.0);
        }
    }
    total
}

/// Renders the pixel-centred images of `points` (estimator, spp) that the manifest
/// lacks; returns whether stopped.
pub(super) fn render_missing(
    renderer: &mut dyn Renderer,
    out: &Path,
    manifest: &mut Manifest,
    plan: &Plan,
    points: &[(String, u32)],
    progress: &dyn Fn(&str),
) -> Result<bool, ExperimentError> {
    let mut todo = Vec::new();
    let mut spps: Vec<u32> = points.iter().map(|p| p.1).collect();
    spps.sort_unstable();
    spps.dedup();
    for spp in spps {
        for &seed in &plan.seeds {
            for e in &plan.estimators {
                if !points.contains(&(e.clone(), spp)) {
                    continue;
                }
                let file = centered_file(e, spp, seed);
                let have = manifest
                    .centered
                    .iter()
                    .any(|r| r.file == file && out.join(&file).is_file());
                if !have {
                    todo.push((e.clone(), spp, seed, file));
                }
            }
        }
    }
    for (k, (est, spp, seed, file)) in todo.iter().enumerate() {
        let head = format!(
            "[{}/{}] {est} {spp} spp seed {seed}, rays through pixel centres",
            k + 1,
            todo.len()
        );
        progress(&format!("{head}: rendering"));
        let Some((img, time_s)) = renderer.render_pixel_centers(est, *spp, *seed)? else {
            progress(&format!("{head}: interrupted"));
            return Ok(true);
        };
        img.validate().map_err(ExperimentError::image(&head))?;
        exr_io::write(&out.join(file), &img, None)?;
        manifest.centered.retain(|r| &r.file != file);
        manifest.centered.push(RenderRecord {
            estimator: est.clone(),
            spp: *spp,
            seed: *seed,
            file: file.clone(),
            time_s,
            mse: f64::NAN,
            rmse: f64::NAN,
            relmse: f64::NAN,
            trimmed_mse: f64::NAN,
            cpu_s: None,
            nonfinite: 0,
        });
    }
    Ok(false)
}

/// Fills [`Row::variance`] of every row whose jittered and centred images are all there.
pub(super) fn fill(out: &Path, rows: &mut [Row]) -> Result<(), ExperimentError> {
    for row in rows.iter_mut() {
        let read = |f: String| exr_io::read(&out.join(f)).ok();
        let jit: Option<Vec<Image>> = row
            .seeds
            .iter()
            .map(|&s| read(image_file(&row.estimator, row.spp, s)))
            .collect();
        let cen: Option<Vec<Image>> = row
            .seeds
            .iter()
            .map(|&s| read(centered_file(&row.estimator, row.spp, s)))
            .collect();
        let (Some(jit), Some(cen)) = (jit, cen) else {
            continue;
        };
        if jit.len() < 2 || cen.iter().any(|c| c.rgb.len() != jit[0].rgb.len()) {
            continue;
        }
        let (j, c) = (summed_variance(&jit), summed_variance(&cen));
        row.variance = Some(Variance {
            jittered: j,
            centered: c,
            direction_share: if j > 0.0 {
                (c / j).clamp(0.0, 1.0)
            } else {
                f64::NAN
            },
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summed_variance_by_hand() {
        let img = |v: f64| Image {
            width: 1,
            height: 1,
            rgb: vec![[v, 2.0 * v, 0.0]],
        };
        // Values 1, 3: variance 2 (n − 1); channel G doubles them: 8; B constant: 0.
        assert_eq!(summed_variance(&[img(1.0), img(3.0)]), 10.0);
        assert_eq!(
            centered_file("balance", 4, 7),
            "images/balance-00004spp-seed7-centered.exr"
        );
    }
}
