//! The `environment` table of a scene file: a constant dome, or a lat-long EXR map read
//! here (frepray's one environment-map reader) into a pool table with its sampling
//! distribution.
//!
//! Map convention: in the map's frame, θ is measured from +z and φ = atan2(y, x) ∈
//! [0, 2π); column u = φ/2π, row v = θ/π (row 0 at +z, the top of the image).

use crate::check::{check_keys, number, rotation};
use crate::data::{EnvMapTable, EnvironmentData, MapId};
use crate::desc::EnvironmentDesc;
use crate::distribution::Distribution2D;
use crate::error::{kp, SceneError};
use crate::lights::rgb;
use crate::locate::Source;
use glam::{DMat3, DVec3};
use std::f64::consts::PI;
use std::path::Path;

/// Why an environment map could not be read.
pub use crate::exr_file::ExrError as MapError;

/// Reads the R, G, B channels of the first layer of a lat-long EXR file, times `scale`,
/// into row-major pixels (row 0 at the top): (width, height, pixels).
pub fn read_exr_rgb(file: &Path, scale: f64) -> Result<(usize, usize, Vec<[f64; 3]>), MapError> {
    let img = crate::exr_file::read_exr(file)?;
    let (w, h) = (img.width, img.height);
    let channel = |name: &str| -> Result<&Vec<f32>, MapError> { Ok(&img.values[img.find(name)?]) };
    let (r, g, b) = (channel("R")?, channel("G")?, channel("B")?);
    if w == 0 || h == 0 {
        return Err(MapError::Empty);
    }
    let mut pixels = Vec::with_capacity(w * h);
    for i in 0..w * h {
        let p = DVec3::new(r[i] as f64, g[i] as f64, b[i] as f64) * scale;
        if !(p.is_finite() && p.min_element() >= 0.0) {
            return Err(MapError::BadPixel { x: i % w, y: i / w });
        }
        pixels.push(p.to_array());
    }
    Ok((w, h, pixels))
}

impl EnvMapTable {
    /// A map from row-major pixels (row 0 at the top), with its sampling distribution
    /// ∝ average(L) · sin θ at each pixel's centre (pbrt-v4 §12.5) and its integral.
    pub fn new(width: usize, height: usize, pixels: Vec<[f64; 3]>) -> Self {
        assert!(
            width > 0 && height > 0 && pixels.len() == width * height,
            "map size"
        );
        let weights: Vec<f64> = (0..width * height)
            .map(|i| {
                let theta = PI * ((i / width) as f64 + 0.5) / height as f64;
                let p = DVec3::from_array(pixels[i]).max(DVec3::ZERO);
                (p.x + p.y + p.z) / 3.0 * theta.sin()
            })
            .collect();
        let distribution = Distribution2D::new(&weights, width, height);
        // ∫ L dω, exact for the piecewise-constant map: each row spans a band of solid
        // angle 2π/width · (cos θ0 − cos θ1) per pixel.
        let mut integral = DVec3::ZERO;
        for y in 0..height {
            let c0 = (PI * y as f64 / height as f64).cos();
            let c1 = (PI * (y + 1) as f64 / height as f64).cos();
            let dw = 2.0 * PI / width as f64 * (c0 - c1);
            for x in 0..width {
                integral += DVec3::from_array(pixels[y * width + x]) * dw;
            }
        }
        Self {
            width,
            height,
            pixels,
            distribution,
            integral: integral.to_array(),
        }
    }
}

/// The environment: a constant dome or a map read beside the scene file (`base`),
/// added to `maps`.
pub(crate) fn environment(
    src: &Source,
    base: &Path,
    e: &EnvironmentDesc,
    maps: &mut Vec<EnvMapTable>,
) -> Result<EnvironmentData, SceneError> {
    let at = kp!["environment"];
    let key = |k: &str| kp!["environment", k];
    match (&e.radiance, &e.map) {
        (Some(c), None) => {
            let present = [("scale", e.scale.is_some()), ("rotate", e.rotate.is_some())];
            check_keys(src, &at, "a constant environment", &present, &["radiance"])?;
            Ok(EnvironmentData::Constant {
                radiance: rgb(src, &key("radiance"), c)?.to_array(),
            })
        }
        (None, Some(file)) => {
            let scale = number(
                src,
                &key("scale"),
                e.scale.unwrap_or(1.0),
                0.0,
                f64::INFINITY,
            )?;
            let mut to_world = DMat3::IDENTITY;
            if let Some(r) = &e.rotate {
                to_world = rotation(src, &key("rotate"), r)?.m;
            }
            let full = base.join(file);
            let (w, h, pixels) = read_exr_rgb(&full, scale)
                .map_err(|m| src.at_value(&key("map"), format!("{}: {m}", full.display())))?;
            maps.push(EnvMapTable::new(w, h, pixels));
            Ok(EnvironmentData::Map {
                map: MapId(maps.len() as u32 - 1),
                to_world: to_world.to_cols_array_2d(),
            })
        }
        (Some(_), Some(_)) => Err(src.at_key(&key("map"), "give either radiance or map, not both")),
        (None, None) => Err(src.at_key(&at, "an environment needs radiance or map")),
    }
}
