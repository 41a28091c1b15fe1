//! Choosing the output format from the file name.

use frepray::preview::Look;
use render::{Image, RenderState};
use std::path::Path;

/// An image format frepray writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// 8-bit sRGB PNG (display only).
    Png,
    /// Linear f32 OpenEXR with AOV channels.
    Exr,
    /// The render state: every pixel's sums, to merge with other sample ranges
    /// (`frepray merge`).
    State,
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
        Some("state") => Ok(Format::State),
        _ => Err(format!(
            "{}: unknown output format (expected a .png, .exr or .state file name)",
            path.display()
        )),
    }
}

/// The format for a model preview: depth and normals are EXR channels.
pub fn format_for(path: &Path, look: Look) -> Result<Format, String> {
    match format_for_scene(path) {
        Ok(Format::State) | Err(_) => Err(format!(
            "{}: unknown output format for a model (expected a .png or .exr file name)",
            path.display()
        )),
        Ok(f) => Ok(f),
    }
    .and_then(|f| match f {
        Format::Png if look != Look::Shaded => Err(format!(
            "{}: --integrator {} writes EXR channels; use a .exr output",
            path.display(),
            format!("{look:?}").to_lowercase()
        )),
        f => Ok(f),
    })
}

/// The paths, comma-separated, for messages.
pub fn list(paths: &[std::path::PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Writes an image whole or not at all (not as a state).
pub fn write(path: &Path, img: &Image, format: Format) -> Result<(), String> {
    match format {
        Format::Png => img.write_png(path),
        Format::Exr | Format::State => img.write_exr(path),
    }
    .map_err(|e| format!("{}: {e}", path.display()))
}

/// Writes a render state's outputs: the state itself to `.state` files, its resolved
/// image to the others (resolved once).
pub fn write_state(
    outs: &[std::path::PathBuf],
    formats: &[Format],
    state: &RenderState,
) -> Result<(), String> {
    let mut image = None;
    for (p, &f) in outs.iter().zip(formats) {
        if f == Format::State {
            state.write(p).map_err(|e| e.to_string())?;
        } else {
            write(p, image.get_or_insert_with(|| state.image()), f)?;
        }
    }
    Ok(())
}
