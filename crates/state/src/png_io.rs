//! 8-bit RGB PNG files: what frepray writes (tone-mapped images, value images, error
//! maps, plots) and reads back in tests, through the `png` crate alone (the `image`
//! crate, with its colour management, took a quarter of the test build's dependency
//! time for this). Balanced deflate with adaptive filters, as `image` encoded them.

use std::io::{self, BufRead, Seek, Write};

/// Writes `rgb` (`width × height` pixels, 3 bytes each, rows top to bottom) as a PNG.
pub fn write_rgb8(w: impl Write, rgb: &[u8], width: u32, height: u32) -> io::Result<()> {
    if rgb.len() as u64 != u64::from(width) * u64::from(height) * 3 {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "{} bytes for a {width} × {height} RGB image (expected {})",
                rgb.len(),
                u64::from(width) * u64::from(height) * 3
            ),
        ));
    }
    let mut encoder = png::Encoder::new(w, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Balanced);
    encoder.set_filter(png::Filter::Adaptive);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(rgb)?;
    writer.finish()?;
    Ok(())
}

/// An 8-bit RGB PNG as (width, height, 3 bytes per pixel); other colour types and depths
/// are errors.
pub fn read_rgb8(r: impl BufRead + Seek) -> io::Result<(u32, u32, Vec<u8>)> {
    let mut reader = png::Decoder::new(r).read_info().map_err(io::Error::other)?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| io::Error::other("the PNG is too large to read"))?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).map_err(io::Error::other)?;
    if (info.color_type, info.bit_depth) != (png::ColorType::Rgb, png::BitDepth::Eight) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "a {:?} PNG of {:?} depth, not 8-bit RGB",
                info.color_type, info.bit_depth
            ),
        ));
    }
    buf.truncate(info.buffer_size());
    Ok((info.width, info.height, buf))
}

/// [`read_rgb8`] of a file.
pub fn read_rgb8_file(path: impl AsRef<std::path::Path>) -> io::Result<(u32, u32, Vec<u8>)> {
    read_rgb8(io::BufReader::new(std::fs::File::open(path)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What is written reads back; a wrong buffer length is refused.
    #[test]
    fn round_trip() {
        let rgb: Vec<u8> = (0..5 * 3 * 3).map(|i| (i * 37 % 256) as u8).collect();
        let mut bytes = Vec::new();
        write_rgb8(&mut bytes, &rgb, 5, 3).unwrap();
        let (w, h, back) = read_rgb8(io::Cursor::new(bytes)).unwrap();
        assert_eq!((w, h), (5, 3));
        assert_eq!(back, rgb);
        assert!(write_rgb8(Vec::new(), &rgb, 4, 3).is_err());
    }
}
