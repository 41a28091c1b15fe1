//! The film: per-pixel sums of samples (box filter) and of any number of named
//! arbitrary-output-variable (AOV) channels, written as linear EXR or sRGB PNG.
//!
//! Sums, not averages, so that films rendered from different sample ranges merge
//! exactly (DESIGN.md §4). Pixel (0, 0) is the top-left corner.

use crate::color::{srgb_u8, Rgb};
use crate::output::write_atomically;
use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
    WritableImage,
};
use image::ImageEncoder;
use std::io;
use std::path::Path;

/// Accumulated samples of an image.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    aov_names: Vec<String>,
    rgb: Vec<Rgb>,
    weight: Vec<f64>,
    aov: Vec<f64>,
}

impl Film {
    /// An empty film with the named AOV channels (unique, none of "R", "G", "B").
    pub fn new(width: u32, height: u32, aov_names: &[&str]) -> Self {
        for (i, n) in aov_names.iter().enumerate() {
            assert!(!["R", "G", "B"].contains(n), "AOV name {n} is reserved");
            assert!(!aov_names[..i].contains(n), "AOV name {n} given twice");
        }
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            aov_names: aov_names.iter().map(|s| s.to_string()).collect(),
            rgb: vec![Rgb::ZERO; n],
            weight: vec![0.0; n],
            aov: vec![0.0; n * aov_names.len()],
        }
    }
    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }
    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }
    /// The AOV channel names, in channel order.
    pub fn aov_names(&self) -> &[String] {
        &self.aov_names
    }
    /// The index of the AOV channel `name`.
    pub fn aov_index(&self, name: &str) -> Option<usize> {
        self.aov_names.iter().position(|n| n == name)
    }
    fn index(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside the film"
        );
        y as usize * self.width as usize + x as usize
    }
    /// Adds one sample of value `rgb` to pixel (x, y) (box filter: weight 1).
    pub fn add_sample(&mut self, x: u32, y: u32, rgb: Rgb) {
        let i = self.index(x, y);
        self.rgb[i] += rgb;
        self.weight[i] += 1.0;
    }
    /// Adds `value` to AOV channel `channel` of pixel (x, y) (averaged over the pixel's
    /// samples on output).
    pub fn add_aov(&mut self, x: u32, y: u32, channel: usize, value: f64) {
        let i = self.index(x, y);
        let k = self.aov_names.len();
        assert!(channel < k, "no AOV channel {channel}");
        self.aov[i * k + channel] += value;
    }
    /// Adds every sum of `other` (same size and channels) to this film.
    pub fn merge(&mut self, other: &Film) {
        assert_eq!(
            (self.width, self.height),
            (other.width, other.height),
            "film sizes"
        );
        assert_eq!(self.aov_names, other.aov_names, "AOV channels");
        self.rgb
            .iter_mut()
            .zip(&other.rgb)
            .for_each(|(a, b)| *a += *b);
        self.weight
            .iter_mut()
            .zip(&other.weight)
            .for_each(|(a, b)| *a += *b);
        self.aov
            .iter_mut()
            .zip(&other.aov)
            .for_each(|(a, b)| *a += *b);
    }
    /// Adds the sums of `tile` (same channels) to the pixels starting at (x0, y0): how
    /// the tiles rendered by different threads come together.
    pub fn add_tile(&mut self, x0: u32, y0: u32, tile: &Film) {
        assert_eq!(self.aov_names, tile.aov_names, "AOV channels");
        assert!(
            x0 + tile.width <= self.width && y0 + tile.height <= self.height,
            "tile inside the film"
        );
        let k = self.aov_names.len();
        for y in 0..tile.height {
            for x in 0..tile.width {
                let (i, j) = (self.index(x0 + x, y0 + y), tile.index(x, y));
                self.rgb[i] += tile.rgb[j];
                self.weight[i] += tile.weight[j];
                for c in 0..k {
                    self.aov[i * k + c] += tile.aov[j * k + c];
                }
            }
        }
    }
    /// The number of samples of pixel (x, y).
    pub fn samples(&self, x: u32, y: u32) -> f64 {
        self.weight[self.index(x, y)]
    }
    /// The pixel's mean colour (0 without samples).
    pub fn rgb(&self, x: u32, y: u32) -> Rgb {
        let i = self.index(x, y);
        if self.weight[i] > 0.0 {
            self.rgb[i] / self.weight[i]
        } else {
            Rgb::ZERO
        }
    }
    /// The pixel's mean of AOV channel `channel` (0 without samples).
    pub fn aov(&self, x: u32, y: u32, channel: usize) -> f64 {
        let i = self.index(x, y);
        let k = self.aov_names.len();
        if self.weight[i] > 0.0 {
            self.aov[i * k + channel] / self.weight[i]
        } else {
            0.0
        }
    }
    fn channel(&self, f: impl Fn(u32, u32) -> f64) -> Vec<f32> {
        let mut v = Vec::with_capacity(self.rgb.len());
        for y in 0..self.height {
            for x in 0..self.width {
                v.push(f(x, y) as f32);
            }
        }
        v
    }
    /// Writes the pixel means as a linear f32 EXR with channels R, G, B and the AOVs
    /// (lossless compression), whole or not at all.
    pub fn write_exr(&self, path: impl AsRef<Path>) -> io::Result<()> {
        let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
        list.push(AnyChannel::new(
            "R",
            FlatSamples::F32(self.channel(|x, y| self.rgb(x, y).x)),
        ));
        list.push(AnyChannel::new(
            "G",
            FlatSamples::F32(self.channel(|x, y| self.rgb(x, y).y)),
        ));
        list.push(AnyChannel::new(
            "B",
            FlatSamples::F32(self.channel(|x, y| self.rgb(x, y).z)),
        ));
        for (k, name) in self.aov_names.iter().enumerate() {
            let data = self.channel(|x, y| self.aov(x, y, k));
            list.push(AnyChannel::new(name.as_str(), FlatSamples::F32(data)));
        }
        let layer = Layer::new(
            (self.width as usize, self.height as usize),
            LayerAttributes::default(),
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(list),
        );
        let image = Image::from_layer(layer);
        write_atomically(path.as_ref(), |w| {
            image.write().to_buffered(w).map_err(io::Error::other)
        })
    }
    /// Writes the pixel means as an 8-bit sRGB PNG (clamped to [0, 1], for display
    /// only), whole or not at all.
    pub fn write_png(&self, path: impl AsRef<Path>) -> io::Result<()> {
        let mut bytes = Vec::with_capacity(self.rgb.len() * 3);
        for y in 0..self.height {
            for x in 0..self.width {
                let c = self.rgb(x, y);
                bytes.extend([srgb_u8(c.x), srgb_u8(c.y), srgb_u8(c.z)]);
            }
        }
        write_atomically(path.as_ref(), |w| {
            image::codecs::png::PngEncoder::new(w)
                .write_image(
                    &bytes,
                    self.width,
                    self.height,
                    image::ExtendedColorType::Rgb8,
                )
                .map_err(io::Error::other)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;
    use std::path::PathBuf;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("render-film-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn test_film() -> Film {
        let mut f = Film::new(5, 3, &["depth", "normal.X"]);
        for y in 0..3 {
            for x in 0..5 {
                let v = Rgb::new(x as f64 * 0.25, y as f64 * 1.5 - 1.0, 1e-3 * (x * y) as f64);
                f.add_sample(x, y, v);
                f.add_sample(x, y, v * 3.0);
                f.add_aov(x, y, 0, 10.0 + x as f64);
                f.add_aov(x, y, 0, 12.0 + x as f64);
                f.add_aov(x, y, 1, -0.5 * y as f64);
            }
        }
        f
    }

    #[test]
    fn sums_and_merge() {
        let f = test_film();
        assert_eq!(f.rgb(2, 1), Rgb::new(1.0, 1.0, 0.004));
        assert_eq!(f.aov(3, 0, 0), 14.0);
        assert_eq!(f.aov(3, 2, 1), -0.5);
        let mut g = f.clone();
        g.merge(&f);
        assert_eq!(g.samples(0, 0), 4.0);
        assert_eq!(g.rgb(2, 1), f.rgb(2, 1));
        assert_eq!(Film::new(2, 2, &[]).rgb(1, 1), Rgb::ZERO);
    }

    /// Writing then reading back with the exr crate gives exactly the f32 pixel means,
    /// channel by channel, including the AOVs.
    #[test]
    fn exr_round_trip() {
        let d = scratch("exr");
        let path = d.join("img.exr");
        let f = test_film();
        f.write_exr(&path).unwrap();
        let img = exr::prelude::read_first_flat_layer_from_file(&path).unwrap();
        let layer = &img.layer_data;
        assert_eq!((layer.size.width(), layer.size.height()), (5, 3));
        let get = |name: &str| -> Vec<f32> {
            let c = layer
                .channel_data
                .list
                .iter()
                .find(|c| c.name.eq(name))
                .unwrap_or_else(|| panic!("channel {name}"));
            assert!(matches!(c.sample_data, FlatSamples::F32(_)));
            c.sample_data.values_as_f32().collect()
        };
        let (r, g, b) = (get("R"), get("G"), get("B"));
        let (depth, nx) = (get("depth"), get("normal.X"));
        for y in 0..3 {
            for x in 0..5 {
                let i = (y * 5 + x) as usize;
                let c = f.rgb(x, y);
                assert_eq!([r[i], g[i], b[i]], [c.x as f32, c.y as f32, c.z as f32]);
                assert_eq!(depth[i], f.aov(x, y, 0) as f32);
                assert_eq!(nx[i], f.aov(x, y, 1) as f32);
            }
        }
        assert_eq!(fs::read_dir(&d).unwrap().count(), 1);
        fs::remove_dir_all(&d).unwrap();
    }

    /// PNG holds the sRGB codes of the clamped means: 0 → 0, 0.5 → 188, ≥ 1 → 255,
    /// negative → 0.
    #[test]
    fn png_encoding() {
        let d = scratch("png");
        let path = d.join("img.png");
        let mut f = Film::new(2, 2, &[]);
        f.add_sample(0, 0, Rgb::new(0.0, 0.5, 1.0));
        f.add_sample(1, 0, Rgb::new(2.0, -1.0, 0.002));
        f.add_sample(0, 1, Rgb::splat(0.5));
        f.add_sample(0, 1, Rgb::splat(1.5));
        f.write_png(&path).unwrap();
        let img =
            image::load_from_memory_with_format(&fs::read(&path).unwrap(), image::ImageFormat::Png)
                .unwrap()
                .to_rgb8();
        assert_eq!(img.dimensions(), (2, 2));
        assert_eq!(img.get_pixel(0, 0).0, [0, 188, 255]);
        assert_eq!(img.get_pixel(1, 0).0, [255, 0, 7]);
        assert_eq!(img.get_pixel(0, 1).0, [255, 255, 255]);
        assert_eq!(img.get_pixel(1, 1).0, [0, 0, 0]);
        fs::remove_dir_all(&d).unwrap();
    }

    /// Writing into a directory that does not exist fails and creates nothing.
    #[test]
    fn failed_write_leaves_no_file() {
        let d = scratch("fail");
        let f = test_film();
        assert!(f.write_exr(d.join("missing/img.exr")).is_err());
        assert!(f.write_png(d.join("missing/img.png")).is_err());
        assert_eq!(fs::read_dir(&d).unwrap().count(), 0);
        fs::remove_dir_all(&d).unwrap();
    }
}
