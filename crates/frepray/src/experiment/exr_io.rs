//! Reading a reference EXR and writing rendered images with their per-pixel error.

use super::{ExperimentError, Image, ImageError};
use render::Rgb;
use std::path::Path;

/// The channels of the per-pixel squared error (x − ref)² beside R, G, B: a layer
/// named "error" in viewers such as tev.
pub const ERROR_CHANNELS: [&str; 3] = ["error.R", "error.G", "error.B"];

/// Writes `img` as a linear f32 EXR with channels R, G, B and, if given, the squared
/// error in [`ERROR_CHANNELS`]; whole or not at all.
pub fn write(path: &Path, img: &Image, error: Option<&[[f64; 3]]>) -> Result<(), ExperimentError> {
    let what = || path.display().to_string();
    img.validate().map_err(ExperimentError::image(what()))?;
    if let Some(e) = error.filter(|e| e.len() != img.rgb.len()) {
        return Err(ExperimentError::Image {
            what: what(),
            source: ImageError::Values {
                width: img.width,
                height: img.height,
                values: e.len(),
            },
        });
    }
    let aovs: &[&str] = if error.is_some() {
        &ERROR_CHANNELS
    } else {
        &[]
    };
    let mut film = render::Image::new(img.width, img.height, aovs);
    for y in 0..img.height {
        for x in 0..img.width {
            let i = y as usize * img.width as usize + x as usize;
            let p = img.rgb[i];
            film.set_rgb(x, y, Rgb::new(p[0], p[1], p[2]));
            if let Some(e) = error {
                for (c, v) in e[i].iter().enumerate() {
                    film.set_aov(x, y, c, *v);
                }
            }
        }
    }
    film.write_exr(path)
        .map_err(ExperimentError::io("write", path))
}

/// Reads channels R, G and B of the first layer of an EXR file.
pub fn read(path: &Path) -> Result<Image, ExperimentError> {
    let img = render::Image::read_exr(path).map_err(|e| ExperimentError::File {
        path: e.path,
        message: e.source.to_string(),
    })?;
    let (width, height) = (img.width(), img.height());
    let rgb = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| img.rgb(x, y).to_array())
        .collect();
    let img = Image { width, height, rgb };
    img.validate()
        .map_err(ExperimentError::image(path.display().to_string()))?;
    Ok(img)
}
