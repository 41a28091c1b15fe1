//! The workspace's one EXR reader: every channel of the first layer of a file, as f32.
//! Environment maps (here) and images (`render::Image::read_exr`) both read through it.

use std::path::Path;

/// The channels of an EXR file's first layer.
#[derive(Clone, Debug, PartialEq)]
pub struct ExrChannels {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Channel names, in the file's order.
    pub names: Vec<String>,
    /// One row-major `width × height` array per channel.
    pub values: Vec<Vec<f32>>,
}

impl ExrChannels {
    /// The index of channel `name` (ASCII case-insensitive), or an error listing those
    /// there are.
    pub fn find(&self, name: &str) -> Result<usize, String> {
        self.names
            .iter()
            .position(|n| n.eq_ignore_ascii_case(name))
            .ok_or_else(|| format!("no channel {name} (has {})", self.names.join(", ")))
    }
}

/// Reads every channel of the first layer of an EXR file. Errors say what is wrong (not
/// the file name: callers add it); a panic of the decoder on a malformed file is caught
/// and reported as an error.
pub fn read_exr(path: &Path) -> Result<ExrChannels, String> {
    // A FIFO would block the decoder for ever: only plain files are opened.
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
        return Err("expected an EXR file, found a folder, device or pipe".to_string());
    }
    let read = std::panic::catch_unwind(|| exr::prelude::read_first_flat_layer_from_file(path))
        .map_err(|_| "the EXR decoder failed on this file".to_string())?;
    let img = read.map_err(|e| format!("not a readable EXR file ({e})"))?;
    let layer = &img.layer_data;
    let (width, height) = (layer.size.width(), layer.size.height());
    let mut out = ExrChannels {
        width,
        height,
        names: Vec::new(),
        values: Vec::new(),
    };
    for c in &layer.channel_data.list {
        let v: Vec<f32> = c.sample_data.values_as_f32().collect();
        if v.len() != width * height {
            return Err(format!(
                "channel {} holds {} of {} values",
                c.name,
                v.len(),
                width * height
            ));
        }
        out.names.push(c.name.to_string());
        out.values.push(v);
    }
    Ok(out)
}
