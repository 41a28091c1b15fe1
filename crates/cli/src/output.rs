//! Choosing the output format from the file name.

use crate::preview::Look;
use render::Film;
use std::path::Path;

/// An image format frepray writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// 8-bit sRGB PNG (display only).
    Png,
    /// Linear f32 OpenEXR with AOV channels.
    Exr,
}

/// The format for a scene render's output, or an error naming what is expected —
/// checked before any work is done.
pub fn format_for_scene(path: &Path) -> Result<Format, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("exr") => Ok(Format::Exr),
        Some("png") => Ok(Format::Png),
        _ => Err(format!(
            "{}: unknown output format (expected a .png or .exr file name)",
            path.display()
        )),
    }
}

/// The format for a model preview: depth and normals are EXR channels.
pub fn format_for(path: &Path, look: Look) -> Result<Format, String> {
    match format_for_scene(path)? {
        Format::Png if look != Look::Shaded => Err(format!(
            "{}: --integrator {} writes EXR channels; use a .exr output",
            path.display(),
            format!("{look:?}").to_lowercase()
        )),
        f => Ok(f),
    }
}

/// The paths, comma-separated, for messages.
pub fn list(paths: &[std::path::PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Writes the film whole or not at all.
pub fn write(path: &Path, film: &Film, format: Format) -> Result<(), String> {
    match format {
        Format::Png => film.write_png(path),
        Format::Exr => film.write_exr(path),
    }
    .map_err(|e| format!("{}: {e}", path.display()))
}
