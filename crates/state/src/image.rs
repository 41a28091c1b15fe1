//! A resolved image: per-pixel values of R, G, B and any number of named arbitrary output
//! variable (AOV) channels, stored contiguously per pixel, written as linear EXR or sRGB
//! PNG and read back from EXR.
//!
//! An image holds estimates, never sums: it is what [`crate::RenderState::image`] resolves
//! from the per-pixel sums when an image is written (DESIGN.md §4: never merge estimates;
//! merge the states). Pixel (0, 0) is the top-left corner.

use crate::color::{srgb_u8, Rgb};
use crate::output::write_atomically;
use exr::meta::attribute::{AttributeValue, Text};
use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Layer, LayerAttributes, SmallVec, WritableImage,
};
pub use scene::Tonemap;
use std::io;
use std::path::Path;

/// An EXR file that does not read as an image ([`Image::read_exr`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}: {source}", .path.display())]
pub struct ReadExrError {
    /// The file.
    pub path: std::path::PathBuf,
    /// What is wrong with it.
    pub source: scene::ExrError,
}

/// Pixel values of R, G, B and the AOV channels (module docs).
#[derive(Clone, Debug)]
pub struct Image {
    width: u32,
    height: u32,
    aov_names: Vec<String>,
    /// `[R, G, B, AOVs…]` per pixel, row by row.
    data: Vec<f64>,
    /// Header attributes written to EXR files (name, value), sorted by name.
    attributes: Vec<(String, String)>,
}

/// How a PNG shows linear radiance: scaled by 2^`exposure` (stops), then mapped by
/// `tonemap`, then clamped to [0, 1] and sRGB-encoded. EXR files stay linear (as pbrt
/// and Mitsuba write them); the default (0 stops, clamp) is the plain clamp frepray
/// always wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Film {
    /// Stops of exposure: +1 doubles, −1 halves.
    pub exposure: f64,
    /// The tone curve.
    pub tonemap: Tonemap,
}

impl Film {
    /// The display value of a linear value (before the clamp and the sRGB curve).
    pub fn map(&self, v: f64) -> f64 {
        self.tonemap.apply(v * self.exposure.exp2())
    }
}

/// Equal when the sizes, channels and pixel values are: the header attributes (what
/// made the image, [`Image::attributes`]) are not compared, so that the same pixels
/// from two renders (a `direct` and a one-vertex `path`) are the same image.
impl PartialEq for Image {
    fn eq(&self, o: &Self) -> bool {
        (self.width, self.height) == (o.width, o.height)
            && self.aov_names == o.aov_names
            && self.data == o.data
    }
}

impl Image {
    /// A black image with the named AOV channels (unique, none of "R", "G", "B").
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
            data: vec![0.0; n * (3 + aov_names.len())],
            attributes: Vec::new(),
        }
    }
    /// The text attributes an EXR file of this image carries in its header (name,
    /// value), sorted by name: what made it ([`crate::RenderState::image`] records the
    /// render's settings) and what was read back from a file.
    pub fn attributes(&self) -> &[(String, String)] {
        &self.attributes
    }
    /// The value of attribute `name`.
    pub fn attribute(&self, name: &str) -> Option<&str> {
        self.attributes
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }
    /// Sets attribute `name` (replacing a value it had). `software` is OpenEXR's
    /// standard attribute of that name; any other is written as a custom text attribute.
    pub fn set_attribute(&mut self, name: &str, value: impl Into<String>) {
        let value = value.into();
        match self
            .attributes
            .binary_search_by(|(n, _)| n.as_str().cmp(name))
        {
            Ok(i) => self.attributes[i].1 = value,
            Err(i) => self.attributes.insert(i, (name.to_string(), value)),
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
    /// Channels per pixel: 3 + AOVs.
    pub fn channels(&self) -> usize {
        3 + self.aov_names.len()
    }
    /// Every value, `[R, G, B, AOVs…]` per pixel, row by row.
    pub fn data(&self) -> &[f64] {
        &self.data
    }
    fn index(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside the image"
        );
        (y as usize * self.width as usize + x as usize) * self.channels()
    }
    /// The values of pixel (x, y): R, G, B, then the AOVs.
    pub fn pixel(&self, x: u32, y: u32) -> &[f64] {
        let i = self.index(x, y);
        &self.data[i..i + self.channels()]
    }
    /// The values of pixel (x, y), to write.
    pub fn pixel_mut(&mut self, x: u32, y: u32) -> &mut [f64] {
        let (i, c) = (self.index(x, y), self.channels());
        &mut self.data[i..i + c]
    }
    /// The pixel's colour.
    pub fn rgb(&self, x: u32, y: u32) -> Rgb {
        let p = self.pixel(x, y);
        Rgb::new(p[0], p[1], p[2])
    }
    /// Sets the pixel's colour.
    pub fn set_rgb(&mut self, x: u32, y: u32, c: Rgb) {
        self.pixel_mut(x, y)[..3].copy_from_slice(&c.to_array());
    }
    /// The pixel's value of AOV channel `channel`.
    pub fn aov(&self, x: u32, y: u32, channel: usize) -> f64 {
        assert!(channel < self.aov_names.len(), "no AOV channel {channel}");
        self.pixel(x, y)[3 + channel]
    }
    /// Sets the pixel's value of AOV channel `channel`.
    pub fn set_aov(&mut self, x: u32, y: u32, channel: usize, v: f64) {
        assert!(channel < self.aov_names.len(), "no AOV channel {channel}");
        self.pixel_mut(x, y)[3 + channel] = v;
    }
    /// Copies the rows of `part` (same channels) into this image from row `y0` on.
    pub fn set_rows(&mut self, y0: u32, part: &Image) {
        assert_eq!(self.aov_names, part.aov_names, "AOV channels");
        assert!(
            part.width == self.width && y0 + part.height <= self.height,
            "rows inside the image"
        );
        let i = self.index(0, y0);
        self.data[i..i + part.data.len()].copy_from_slice(&part.data);
    }
    fn channel(&self, c: usize) -> Vec<f32> {
        self.data
            .chunks_exact(self.channels())
            .map(|p| p[c] as f32)
            .collect()
    }
    /// Writes the image as a linear f32 EXR with channels R, G, B and the AOVs (lossless
    /// compression), whole or not at all.
    pub fn write_exr(&self, path: impl AsRef<Path>) -> io::Result<()> {
        let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            list.push(AnyChannel::new(name, FlatSamples::F32(self.channel(c))));
        }
        for (k, name) in self.aov_names.iter().enumerate() {
            let data = self.channel(3 + k);
            list.push(AnyChannel::new(name.as_str(), FlatSamples::F32(data)));
        }
        // Text as UTF-8 bytes: OpenEXR stores strings as bytes and its tools print them.
        let text = |s: &str| Text::from_bytes_unchecked(SmallVec::from_slice(s.as_bytes()));
        let mut attributes = LayerAttributes::default();
        for (name, value) in &self.attributes {
            if name == "software" {
                attributes.software_name = Some(text(value));
            } else {
                attributes
                    .other
                    .insert(text(name), AttributeValue::Text(text(value)));
            }
        }
        let layer = Layer::new(
            (self.width as usize, self.height as usize),
            attributes,
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(list),
        );
        let image = exr::prelude::Image::from_layer(layer);
        write_atomically(path.as_ref(), |w| {
            image.write().to_buffered(w).map_err(io::Error::other)
        })
    }
    /// Writes the colour as an 8-bit sRGB PNG (clamped to [0, 1], for display only),
    /// whole or not at all.
    pub fn write_png(&self, path: impl AsRef<Path>) -> io::Result<()> {
        self.write_png_film(path, &Film::default())
    }
    /// Writes the colour as an 8-bit sRGB PNG after `film`'s exposure and tone mapping
    /// (then clamped to [0, 1]), whole or not at all.
    pub fn write_png_film(&self, path: impl AsRef<Path>, film: &Film) -> io::Result<()> {
        let bytes: Vec<u8> = self
            .data
            .chunks_exact(self.channels())
            .flat_map(|p| [0, 1, 2].map(|c| srgb_u8(film.map(p[c]))))
            .collect();
        self.write_png_rgb8(path.as_ref(), &bytes)
    }
    /// Writes a PNG of what the colour channels hold when they hold values (depth,
    /// normals: [`crate::value_png`]), whole or not at all.
    pub fn write_png_values(
        &self,
        path: impl AsRef<Path>,
        values: crate::value_png::Values,
    ) -> io::Result<()> {
        self.write_png_rgb8(path.as_ref(), &values.rgb8(self))
    }
    fn write_png_rgb8(&self, path: &Path, bytes: &[u8]) -> io::Result<()> {
        write_atomically(path, |w| {
            crate::png_io::write_rgb8(w, bytes, self.width, self.height)
        })
    }
    /// The fraction of pixels a PNG written with `film` shows clipped: some channel at
    /// 1 or more after the exposure and tone mapping (white or a saturated colour).
    pub fn clipped_fraction(&self, film: &Film) -> f64 {
        let n = (self.width as usize * self.height as usize).max(1);
        let clipped = self
            .data
            .chunks_exact(self.channels())
            .filter(|p| p[..3].iter().any(|&v| film.map(v) >= 1.0))
            .count();
        clipped as f64 / n as f64
    }
    /// Reads the first layer of an EXR file: channels R, G, B (required) and every other
    /// channel as an AOV, in the file's (alphabetical) order, and the header's text
    /// attributes. Errors name the file and
    /// what is wrong; a decoder panic on a malformed file is caught and reported.
    pub fn read_exr(path: impl AsRef<Path>) -> Result<Image, ReadExrError> {
        let path = path.as_ref();
        let at = |source| ReadExrError {
            path: path.to_path_buf(),
            source,
        };
        let exr = scene::read_exr(path).map_err(at)?;
        let (width, height) = (
            u32::try_from(exr.width).map_err(|_| at(scene::ExrError::TooLarge("wide")))?,
            u32::try_from(exr.height).map_err(|_| at(scene::ExrError::TooLarge("tall")))?,
        );
        let rgb = [
            exr.find("R").map_err(at)?,
            exr.find("G").map_err(at)?,
            exr.find("B").map_err(at)?,
        ];
        let aovs: Vec<usize> = (0..exr.names.len()).filter(|i| !rgb.contains(i)).collect();
        let aov_names: Vec<&str> = aovs.iter().map(|&i| exr.names[i].as_str()).collect();
        let mut out = Image::new(width, height, &aov_names);
        let c = out.channels();
        for (k, &i) in rgb.iter().chain(&aovs).enumerate() {
            for (p, &v) in out.data.chunks_exact_mut(c).zip(&exr.values[i]) {
                p[k] = f64::from(v);
            }
        }
        out.attributes = exr.attributes;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;
    use std::path::PathBuf;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("render-image-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn test_film() -> Image {
        let mut f = Image::new(5, 3, &["depth", "normal.X"]);
        for y in 0..3 {
            for x in 0..5 {
                let v = Rgb::new(x as f64 * 0.5, y as f64 * 3.0 - 2.0, 2e-3 * (x * y) as f64);
                f.set_rgb(x, y, v);
                f.set_aov(x, y, 0, 11.0 + x as f64);
                f.set_aov(x, y, 1, -0.5 * y as f64);
            }
        }
        f
    }

    #[test]
    fn pixels_and_rows() {
        let f = test_film();
        assert_eq!(f.rgb(2, 1), Rgb::new(1.0, 1.0, 0.004));
        assert_eq!(f.aov(3, 0, 0), 14.0);
        assert_eq!(f.aov(3, 1, 1), -0.5);
        assert_eq!(f.pixel(3, 2), &[1.5, 4.0, 0.012, 14.0, -1.0]);
        let mut g = Image::new(5, 4, &["depth", "normal.X"]);
        g.set_rows(1, &f);
        assert_eq!(g.pixel(3, 3), f.pixel(3, 2));
        assert_eq!(g.rgb(4, 0), Rgb::ZERO);
        assert_eq!(Image::new(2, 2, &[]).rgb(1, 1), Rgb::ZERO);
    }

    /// The EXR reader gives back what the writer wrote (as f32), AOVs included.
    #[test]
    fn exr_reader_round_trip() {
        let d = scratch("exr-read");
        let path = d.join("img.exr");
        let f = test_film();
        f.write_exr(&path).unwrap();
        let g = Image::read_exr(&path).unwrap();
        assert_eq!(g.aov_names(), f.aov_names());
        for (a, b) in g.data().iter().zip(f.data()) {
            assert_eq!(*a, *b as f32 as f64);
        }
        let bad = d.join("bad.exr");
        fs::write(&bad, b"not an exr").unwrap();
        let e = Image::read_exr(&bad).unwrap_err();
        assert_eq!(e.path, bad);
        assert!(matches!(e.source, scene::ExrError::Unreadable(_)), "{e}");
        assert!(e.to_string().contains("not a readable EXR"), "{e}");
        assert!(
            e.to_string().starts_with(&format!("{}: ", bad.display())),
            "{e}"
        );
        fs::remove_dir_all(&d).unwrap();
    }

    /// Header attributes survive the file as they were set (UTF-8 text, the standard
    /// `software` attribute among them); a later value replaces an earlier one.
    #[test]
    fn exr_attributes_round_trip() {
        let d = scratch("exr-attributes");
        let path = d.join("img.exr");
        let mut f = test_film();
        f.set_attribute("frepray.size", "5×3");
        f.set_attribute("software", "frepray test");
        f.set_attribute("frepray.b", "first");
        f.set_attribute("frepray.b", "second");
        assert_eq!(f.attribute("frepray.b"), Some("second"));
        f.write_exr(&path).unwrap();
        let g = Image::read_exr(&path).unwrap();
        assert_eq!(g.attributes(), f.attributes());
        assert_eq!(
            g.attributes()
                .iter()
                .map(|(n, _)| n.as_str())
                .collect::<Vec<_>>(),
            ["frepray.b", "frepray.size", "software"]
        );
        let raw = exr::prelude::read_first_flat_layer_from_file(&path).unwrap();
        assert_eq!(
            raw.layer_data
                .attributes
                .software_name
                .as_ref()
                .map(|t| t.to_string()),
            Some("frepray test".to_string())
        );
        // A name OpenEXR reserves for a standard attribute of another type is an error.
        f.set_attribute("dataWindow", "x");
        assert!(f.write_exr(d.join("reserved.exr")).is_err());
        assert!(!d.join("reserved.exr").exists());
        fs::remove_dir_all(&d).unwrap();
    }

    /// Writing then reading back with the exr crate gives exactly the f32 pixel values,
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

    /// PNG holds the sRGB codes of the clamped values: 0 → 0, 0.5 → 188, ≥ 1 → 255,
    /// negative → 0.
    #[test]
    fn png_encoding() {
        let d = scratch("png");
        let path = d.join("img.png");
        let mut f = Image::new(2, 2, &[]);
        f.set_rgb(0, 0, Rgb::new(0.0, 0.5, 1.0));
        f.set_rgb(1, 0, Rgb::new(2.0, -1.0, 0.002));
        f.set_rgb(0, 1, Rgb::splat(1.0));
        f.write_png(&path).unwrap();
        let (w, h, rgb) = crate::png_io::read_rgb8_file(&path).unwrap();
        assert_eq!((w, h), (2, 2));
        assert_eq!(rgb, [0, 188, 255, 255, 0, 7, 255, 255, 255, 0, 0, 0]);
        fs::remove_dir_all(&d).unwrap();
    }

    /// Writing into a directory that does not exist fails and creates nothing.
    /// Exposure scales by 2^EV before the curve; the default film writes the bytes the
    /// plain clamp always wrote; reinhard and aces compress what clamp clips.
    #[test]
    fn exposure_and_tone_mapping() {
        let film = |exposure, tonemap| Film { exposure, tonemap };
        let plain = Film::default();
        for v in [0.0, 0.3, 1.0, 7.0] {
            assert_eq!(plain.map(v), v);
        }
        assert_eq!(film(1.0, Tonemap::Clamp).map(0.25), 0.5);
        assert_eq!(film(-2.0, Tonemap::Clamp).map(2.0), 0.5);
        assert_eq!(film(0.0, Tonemap::Reinhard).map(1.0), 0.5);
        let aces = film(0.0, Tonemap::Aces);
        assert!((aces.map(1.0) - 0.8038).abs() < 1e-3 && aces.map(0.0) == 0.0);
        // White at v ≈ 7.24 (the fit's root of 0.08v² − 0.56v − 0.14).
        assert!(aces.map(7.0) < 1.0 && aces.map(7.5) > 1.0);
        let mut img = Image::new(2, 1, &[]);
        img.set_rgb(0, 0, Rgb::new(0.5, 0.5, 0.5));
        img.set_rgb(1, 0, Rgb::new(3.0, 0.2, 0.2));
        assert_eq!(img.clipped_fraction(&plain), 0.5);
        assert_eq!(img.clipped_fraction(&film(-2.0, Tonemap::Clamp)), 0.0);
        assert_eq!(img.clipped_fraction(&film(0.0, Tonemap::Reinhard)), 0.0);
        let dir = scratch("film");
        let (a, b) = (dir.join("plain.png"), dir.join("film.png"));
        img.write_png(&a).unwrap();
        img.write_png_film(&b, &plain).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        img.write_png_film(&b, &film(-2.0, Tonemap::Clamp)).unwrap();
        assert_ne!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        fs::remove_dir_all(dir).unwrap();
    }

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
