//! The workspace's one EXR reader: every channel of the first layer of a file, as f32.
//! Environment maps (here) and images (`render::Image::read_exr`) both read through it.

use std::path::Path;

/// What is wrong with an EXR file (not its name: callers add it).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ExrError {
    /// A folder, device or pipe.
    #[error("expected an EXR file, found a folder, device or pipe")]
    NotAFile,
    /// The decoder panicked on the file.
    #[error("the EXR decoder failed on this file")]
    DecoderFailed,
    /// The decoder refused the file (its message).
    #[error("not a readable EXR file ({0})")]
    Unreadable(String),
    /// A channel of the wrong size.
    #[error("channel {name} holds {values} of {expected} values")]
    ChannelSize {
        /// The channel.
        name: String,
        /// The values it holds.
        values: usize,
        /// width × height.
        expected: usize,
    },
    /// A channel that is not there.
    #[error("no channel {name} (has {})", .has.join(", "))]
    NoChannel {
        /// The channel asked for.
        name: String,
        /// Those the file has.
        has: Vec<String>,
    },
    /// No pixels.
    #[error("the image is empty")]
    Empty,
    /// Too many pixels along an axis.
    #[error("the image is too {0}")]
    TooLarge(&'static str),
    /// A pixel unfit for an environment map.
    #[error("pixel ({x}, {y}) is negative or not finite")]
    BadPixel {
        /// Column.
        x: usize,
        /// Row.
        y: usize,
    },
}

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
    /// The header's text attributes (name, value), sorted by name: the standard
    /// `software` and any custom ones (frepray's render record, [`ATTRIBUTE_PREFIX`]).
    pub attributes: Vec<(String, String)>,
}

/// The prefix of the header attributes frepray writes about a render.
pub const ATTRIBUTE_PREFIX: &str = "frepray.";

/// The header's text attributes of a layer, sorted by name (values as UTF-8, which
/// OpenEXR's tools print as they are).
fn text_attributes(a: &exr::meta::header::LayerAttributes) -> Vec<(String, String)> {
    let text = |t: &exr::meta::attribute::Text| String::from_utf8_lossy(t.bytes()).into_owned();
    let mut out: Vec<(String, String)> = a
        .other
        .iter()
        .filter_map(|(name, v)| match v {
            exr::meta::attribute::AttributeValue::Text(t) => Some((text(name), text(t))),
            _ => None,
        })
        .collect();
    out.extend(
        a.software_name
            .iter()
            .map(|s| ("software".to_string(), text(s))),
    );
    out.sort();
    out
}

impl ExrChannels {
    /// The index of channel `name` (ASCII case-insensitive), or an error listing those
    /// there are.
    pub fn find(&self, name: &str) -> Result<usize, ExrError> {
        self.names
            .iter()
            .position(|n| n.eq_ignore_ascii_case(name))
            .ok_or_else(|| ExrError::NoChannel {
                name: name.to_string(),
                has: self.names.clone(),
            })
    }
}

/// Reads every channel of the first layer of an EXR file. Errors say what is wrong (not
/// the file name: callers add it); a panic of the decoder on a malformed file is caught
/// and reported as an error.
pub fn read_exr(path: &Path) -> Result<ExrChannels, ExrError> {
    // A FIFO would block the decoder for ever: only plain files are opened.
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
        return Err(ExrError::NotAFile);
    }
    let read = std::panic::catch_unwind(|| exr::prelude::read_first_flat_layer_from_file(path))
        .map_err(|_| ExrError::DecoderFailed)?;
    let img = read.map_err(|e| ExrError::Unreadable(e.to_string()))?;
    let layer = &img.layer_data;
    let (width, height) = (layer.size.width(), layer.size.height());
    let mut out = ExrChannels {
        width,
        height,
        names: Vec::new(),
        values: Vec::new(),
        attributes: text_attributes(&layer.attributes),
    };
    for c in &layer.channel_data.list {
        let v: Vec<f32> = c.sample_data.values_as_f32().collect();
        if v.len() != width * height {
            return Err(ExrError::ChannelSize {
                name: c.name.to_string(),
                values: v.len(),
                expected: width * height,
            });
        }
        out.names.push(c.name.to_string());
        out.values.push(v);
    }
    Ok(out)
}
