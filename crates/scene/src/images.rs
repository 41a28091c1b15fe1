//! Image textures (PNG, EXR) that materials project onto solids by triplanar mapping
//! (`render::texture`): the pool of decoded images, linear RGB. A PNG's 8-bit values are
//! sRGB-encoded and decoded to linear (IEC 61966-2-1); an EXR is linear already.

use crate::data::ImageId;
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};
use std::path::Path;
use std::sync::Arc;

/// The most pixels an image texture may have (8192²).
pub const MAX_IMAGE_PIXELS: usize = 8192 * 8192;

/// A decoded image: `width × height` linear RGB values, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTexture {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Row-major linear RGB.
    pub pixels: Vec<[f32; 3]>,
}

/// The images of a scene's textures.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImagePool {
    images: Vec<Arc<ImageTexture>>,
}

impl ImagePool {
    /// Adds an image; returns its id.
    pub fn push(&mut self, image: ImageTexture) -> ImageId {
        self.images.push(Arc::new(image));
        ImageId(self.images.len() as u32 - 1)
    }
    /// The image of `id`.
    pub fn image(&self, id: ImageId) -> &Arc<ImageTexture> {
        &self.images[id.index()]
    }
    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.images.is_empty()
    }
}

impl Serialize for ImagePool {
    /// Per image: its size and a content hash (FNV-1a 64 of its values), so that a dump
    /// stays small and the scene's hash still follows every pixel.
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        struct One<'a>(&'a ImageTexture);
        impl Serialize for One<'_> {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                let mut fnv = crate::meshes::Fnv::default();
                for p in &self.0.pixels {
                    for x in p {
                        fnv.eat(&x.to_le_bytes());
                    }
                }
                let h = fnv.0;
                let mut m = s.serialize_map(Some(3))?;
                m.serialize_entry("width", &self.0.width)?;
                m.serialize_entry("height", &self.0.height)?;
                m.serialize_entry("content", &format!("{h:016x}"))?;
                m.end()
            }
        }
        s.collect_seq(self.images.iter().map(|i| One(i)))
    }
}

/// sRGB's decoding of an 8-bit value to linear.
fn srgb_to_linear(v: u8) -> f32 {
    let c = f32::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads a PNG (8- or 16-bit grey, grey with alpha, RGB or RGBA; alpha dropped) or an
/// EXR (channels R, G, B) as linear RGB. Errors say what is wrong (not the file name:
/// callers add it).
pub fn read_image(path: &Path) -> Result<ImageTexture, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let img = match ext.as_deref() {
        Some("png") => read_png(path)?,
        Some("exr") => {
            let (width, height, px) =
                crate::environment::read_exr_rgb(path, 1.0).map_err(|e| e.to_string())?;
            ImageTexture {
                width,
                height,
                pixels: px.into_iter().map(|p| p.map(|x| x as f32)).collect(),
            }
        }
        _ => return Err("expected an image file ending in .png or .exr".into()),
    };
    if img.width == 0 || img.height == 0 {
        return Err("the image is empty".into());
    }
    Ok(img)
}

fn read_png(path: &Path) -> Result<ImageTexture, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read the file: {e}"))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("not a readable PNG ({e})"))?;
    let (w, h) = (reader.info().width as usize, reader.info().height as usize);
    if w.saturating_mul(h) > MAX_IMAGE_PIXELS {
        return Err(format!(
            "{w}×{h} pixels, more than an image texture may have"
        ));
    }
    let size = reader
        .output_buffer_size()
        .ok_or("the PNG is too large to read")?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("not a readable PNG ({e})"))?;
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        other => return Err(format!("a {other:?} PNG; expected grey or RGB")),
    };
    let pixels = buf[..w * h * channels]
        .chunks_exact(channels)
        .map(|p| match channels {
            1 | 2 => [srgb_to_linear(p[0]); 3],
            _ => [
                srgb_to_linear(p[0]),
                srgb_to_linear(p[1]),
                srgb_to_linear(p[2]),
            ],
        })
        .collect();
    Ok(ImageTexture {
        width: w,
        height: h,
        pixels,
    })
}
