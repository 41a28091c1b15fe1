//! Reading a reference EXR and writing rendered images with their per-pixel error.

use super::Image;
use render::{Film, Rgb};
use std::path::Path;

/// The channels of the per-pixel squared error (x − ref)² beside R, G, B: a layer
/// named "error" in viewers such as tev.
pub const ERROR_CHANNELS: [&str; 3] = ["error.R", "error.G", "error.B"];

/// Writes `img` as a linear f32 EXR with channels R, G, B and, if given, the squared
/// error in [`ERROR_CHANNELS`]; whole or not at all.
pub fn write(path: &Path, img: &Image, error: Option<&[[f64; 3]]>) -> Result<(), String> {
    img.validate()?;
    let aovs: &[&str] = if error.is_some() {
        &ERROR_CHANNELS
    } else {
        &[]
    };
    let mut film = Film::new(img.width, img.height, aovs);
    for y in 0..img.height {
        for x in 0..img.width {
            let i = y as usize * img.width as usize + x as usize;
            let p = img.rgb[i];
            film.add_sample(x, y, Rgb::new(p[0], p[1], p[2]));
            if let Some(e) = error {
                let e = e.get(i).ok_or("error image smaller than the image")?;
                for (c, v) in e.iter().enumerate() {
                    film.add_aov(x, y, c, *v);
                }
            }
        }
    }
    film.write_exr(path)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Reads channels R, G and B of the first layer of an EXR file.
pub fn read(path: &Path) -> Result<Image, String> {
    let at = |e: String| format!("{}: {e}", path.display());
    // The exr crate returns errors for malformed files; the guard keeps a panic in a
    // decoder from taking the experiment down with it.
    let read = std::panic::catch_unwind(|| exr::prelude::read_first_flat_layer_from_file(path))
        .map_err(|_| at("the EXR decoder failed on this file".into()))?;
    let img = read.map_err(|e| at(format!("not a readable EXR file ({e})")))?;
    let layer = &img.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let n = w * h;
    let channel = |name: &str| -> Result<Vec<f32>, String> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.eq(name))
            .ok_or_else(|| {
                let names: Vec<String> = layer
                    .channel_data
                    .list
                    .iter()
                    .map(|c| c.name.to_string())
                    .collect();
                at(format!("no channel {name} (has {})", names.join(", ")))
            })?;
        let v: Vec<f32> = c.sample_data.values_as_f32().collect();
        if v.len() != n {
            return Err(at(format!(
                "channel {name} holds {} of {n} values",
                v.len()
            )));
        }
        Ok(v)
    };
    let (r, g, b) = (channel("R")?, channel("G")?, channel("B")?);
    let (width, height) = (
        u32::try_from(w).map_err(|_| at("too wide".into()))?,
        u32::try_from(h).map_err(|_| at("too tall".into()))?,
    );
    let rgb = (0..n)
        .map(|i| [r[i] as f64, g[i] as f64, b[i] as f64])
        .collect();
    let img = Image { width, height, rgb };
    img.validate().map_err(at)?;
    Ok(img)
}
