//! Output files: the format from the file name, checks that every output can be
//! written before any work starts, the names of a partial (interrupted) result, and
//! writing every output even when one fails.

use frepray::preview::Look;
use frepray::value_png::Values;
use frepray::{Film, Image, RenderState, RenderStats, Tonemap};
use std::path::{Path, PathBuf};

/// How PNG outputs show the image: `--exposure` and `--tonemap` (EXR and state files
/// stay linear).
#[derive(clap::Args, Clone, Debug, Default)]
pub struct FilmArgs {
    /// PNG only: scale radiance by 2^EV before encoding (+1 doubles, −1 halves) [scenes:
    /// the scene's `[film] exposure`, else 0]. EXR files stay linear.
    #[arg(long, value_name = "EV", allow_negative_numbers = true)]
    pub exposure: Option<f64>,
    /// PNG only: clamp (values ≥ 1 clip to white), reinhard (v/(1+v): nothing clips)
    /// or aces (filmic: soft shoulder, white from 7.2) [scenes: the scene's
    /// `[film] tonemap`, else clamp].
    #[arg(long, value_name = "CURVE", value_parser = parse_tonemap)]
    pub tonemap: Option<Tonemap>,
}

fn parse_tonemap(s: &str) -> Result<Tonemap, String> {
    s.parse().map_err(|e: frepray::UnknownName| e.to_string())
}

impl FilmArgs {
    /// The film of these flags over `base` (a scene's `[film]`); errors on an
    /// exposure that is not finite.
    pub fn over(&self, base: Film) -> Result<Film, String> {
        if let Some(e) = self.exposure {
            if !e.is_finite() {
                return Err(format!("--exposure {e}: expected a finite number of stops"));
            }
        }
        Ok(Film {
            exposure: self.exposure.unwrap_or(base.exposure),
            tonemap: self.tonemap.unwrap_or(base.tonemap),
        })
    }
}

/// The warning on an image with NaN or infinite pixels, and the note on a PNG whose
/// pixels clip (1 % or more), with the fraction and what helps.
pub fn clip_note(outs: &[PathBuf], formats: &[Format], img: &Image, film: &Film) {
    // Pixels the transport could not represent (overflowed sums): said, not hidden.
    let channels = img.channels();
    let bad = img
        .data()
        .chunks_exact(channels)
        .filter(|p| p.iter().any(|v| !v.is_finite()))
        .count();
    if bad > 0 {
        note!(
            "warning: {bad} of {} pixels are not finite (NaN or infinite): the light \
             transport overflowed; look for very large values in the scene (powers, \
             radiances, sizes)",
            img.width() as u64 * img.height() as u64
        );
    }
    let Some(png) = outs.iter().zip(formats).find(|(_, f)| **f == Format::Png) else {
        return;
    };
    let f = img.clipped_fraction(film);
    if f >= 0.01 {
        note!(
            "note: {}: {:.1} % of pixels clip (a channel ≥ 1 after exposure {} and tone \
             mapping {}); --exposure -1 halves the brightness, --tonemap reinhard or aces \
             compresses highlights",
            png.0.display(),
            100.0 * f,
            film.exposure,
            film.tonemap
        );
    }
}

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

/// The format for a model preview (no state files).
pub fn format_for_model(path: &Path) -> Result<Format, String> {
    match format_for_scene(path) {
        Ok(Format::State) | Err(_) => Err(format!(
            "{}: unknown output format for a model (expected a .png or .exr file name)",
            path.display()
        )),
        Ok(f) => Ok(f),
    }
}

/// What a model preview's colour channels hold: values for depth and normals.
pub fn model_values(look: Look) -> Option<Values> {
    match look {
        Look::Shaded => None,
        Look::Depth => Some(Values::Depth),
        Look::Normals => Some(Values::Normals),
    }
}

/// Checks, before any work, that `path` can be written: its folder exists and is
/// writable (a probe file is created there and removed) and `path` is not a folder.
pub fn check_writable(path: &Path) -> Result<(), String> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let fail = |why: String| format!("cannot write {}: {why}", path.display());
    if !dir.is_dir() {
        return Err(fail(format!("the folder {} does not exist", dir.display())));
    }
    if path.is_dir() {
        return Err(fail("it is a folder".into()));
    }
    let probe = dir.join(format!(".frepray-probe-{}.tmp", std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .map_err(|e| {
            fail(format!(
                "the folder {} is not writable ({e})",
                dir.display()
            ))
        })?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Checks every output before any work: its format ([`format_for_scene`]) and that it
/// can be written ([`check_writable`]).
pub fn check_scene_outputs(outs: &[PathBuf]) -> Result<Vec<Format>, String> {
    outs.iter()
        .map(|p| {
            let f = format_for_scene(p)?;
            check_writable(p)?;
            Ok(f)
        })
        .collect()
}

/// Where the partial result of an interrupted render goes: `NAME.partial.EXT` next to
/// `NAME.EXT`, so that it never silently replaces a finished file of that name (unless
/// `overwrite`, `--overwrite-partial`).
pub fn partial_path(path: &Path, overwrite: bool) -> PathBuf {
    if overwrite {
        return path.to_path_buf();
    }
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    let name = match path.extension() {
        Some(e) => format!("{stem}.partial.{}", e.to_string_lossy()),
        None => format!("{stem}.partial"),
    };
    path.with_file_name(name)
}

/// Refuses an output that is the scene file or a file it reads (a model, an environment
/// map): writing it would replace what the render was made from.
pub fn check_not_inputs(outs: &[PathBuf], scene: &Path, inputs: &[PathBuf]) -> Result<(), String> {
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    for out in outs {
        for (input, what) in std::iter::once((scene, "the scene file")).chain(
            inputs
                .iter()
                .map(|p| (p.as_path(), "a file the scene reads")),
        ) {
            if same(out, input) {
                return Err(format!(
                    "{}: is {what} ({}); an output must not replace an input, choose another name",
                    out.display(),
                    input.display()
                ));
            }
        }
    }
    Ok(())
}

/// The paths, comma-separated, for messages.
pub fn list(paths: &[std::path::PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Writes an image whole or not at all (not as a state); a PNG through `film`, or as
/// [`render::value_png`] shows `values`.
pub fn write(
    path: &Path,
    img: &Image,
    format: Format,
    film: &Film,
    values: Option<Values>,
) -> Result<(), String> {
    match (format, values) {
        (Format::Png, Some(v)) => img.write_png_values(path, v),
        (Format::Png, None) => img.write_png_film(path, film),
        (Format::Exr | Format::State, _) => img.write_exr(path),
    }
    .map_err(|e| format!("{}: {e}", path.display()))
}

/// Writes a render state's outputs: the state itself to `.state` files, its resolved
/// image to the others (resolved once). Every output is attempted; the error names
/// each that failed.
pub fn write_state(
    outs: &[PathBuf],
    formats: &[Format],
    state: &RenderState,
    film: &Film,
    describe: &dyn Fn(&mut Image),
) -> Result<(), String> {
    let mut image = None;
    let mut failed = Vec::new();
    let values = Values::of(state.header().integrator);
    for (p, &f) in outs.iter().zip(formats) {
        let r = if f == Format::State {
            state.write(p).map_err(|e| e.to_string())
        } else {
            write(
                p,
                image.get_or_insert_with(|| {
                    let mut img = state.image();
                    describe(&mut img);
                    img
                }),
                f,
                film,
                values,
            )
        };
        if let Err(e) = r {
            failed.push(e);
        }
    }
    if let (Some(img), None) = (&image, values) {
        clip_note(outs, formats, img, film);
    }
    written_or(outs.len(), failed)
}

/// Records in an image's EXR attributes how it was rendered, beyond what its state
/// records ([`RenderState::image`]): the input file, the back end (with the GPU's
/// adapter) and the render's statistics.
pub fn describe_render(img: &mut Image, input: &Path, stats: &RenderStats, on_gpu: bool) {
    let p = frepray::ATTRIBUTE_PREFIX;
    img.set_attribute(&format!("{p}input"), input.display().to_string());
    let backend = if on_gpu {
        match frepray::backend::shared_gpu() {
            Ok(g) => format!("gpu ({})", g.info()),
            Err(_) => "gpu".to_string(),
        }
    } else {
        "cpu".to_string()
    };
    img.set_attribute(&format!("{p}backend"), backend);
    stats.describe(img);
}

/// Writes an image to every output; every one is attempted, the error names each that
/// failed.
pub fn write_all(
    outs: &[PathBuf],
    formats: &[Format],
    img: &Image,
    film: &Film,
    values: Option<Values>,
) -> Result<(), String> {
    let failed: Vec<String> = outs
        .iter()
        .zip(formats)
        .filter_map(|(p, &f)| write(p, img, f, film, values).err())
        .collect();
    if values.is_none() {
        clip_note(outs, formats, img, film);
    }
    written_or(outs.len(), failed)
}

fn written_or(total: usize, failed: Vec<String>) -> Result<(), String> {
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{} of {total} output(s) not written (the others were): {}",
            failed.len(),
            failed.join("; ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use frepray::RenderOptions;
    use frepray::StateHeader;

    /// One output that cannot be written does not stop the others; the error names it.
    #[test]
    fn a_failed_write_does_not_stop_the_others() {
        let dir = std::env::temp_dir().join(format!("frepray-out-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let state =
            RenderState::new(StateHeader::new(4, 3, &RenderOptions::default()), 0..1).unwrap();
        let outs = [
            dir.join("a.exr"),
            dir.join("gone/b.state"),
            dir.join("c.png"),
        ];
        let formats: Vec<Format> = outs.iter().map(|p| format_for_scene(p).unwrap()).collect();
        let e = write_state(&outs, &formats, &state, &Film::default(), &|_| {}).unwrap_err();
        assert!(e.contains("1 of 3") && e.contains("b.state"), "{e}");
        assert!(outs[0].is_file() && outs[2].is_file());
        assert!(check_writable(&outs[1])
            .unwrap_err()
            .contains("does not exist"));
        assert!(check_writable(&dir).unwrap_err().contains("is a folder"));
        assert_eq!(
            partial_path(Path::new("out/x.exr"), false),
            Path::new("out/x.partial.exr")
        );
        assert_eq!(partial_path(Path::new("x.exr"), true), Path::new("x.exr"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
