//! `render --denoised NAME.exr|.png`: a denoised copy of the render beside its unbiased
//! outputs ([`frepray::denoise`]), never over one of them.

use crate::output::{self, Format};
use frepray::denoise::Oidn;
use frepray::{Film, Image};
use std::path::{Path, PathBuf};

/// Where a denoised copy goes, and the library that makes it.
pub struct Denoised {
    path: PathBuf,
    format: Format,
    oidn: Oidn,
}

impl Denoised {
    /// Checks `--denoised` before any work: a .exr or .png name, none of the outputs
    /// `outs`, writable, and Open Image Denoise found.
    pub fn prepare(path: Option<&Path>, outs: &[PathBuf]) -> Result<Option<Denoised>, String> {
        let Some(path) = path else {
            return Ok(None);
        };
        let format = match output::format_for_scene(path)? {
            Format::State => {
                return Err(format!(
                    "--denoised {}: a denoised image is a picture, .exr or .png, not a state",
                    path.display()
                ))
            }
            f => f,
        };
        let same = |o: &PathBuf| {
            o == path || matches!((o.canonicalize(), path.canonicalize()), (Ok(a), Ok(b)) if a == b)
        };
        if let Some(o) = outs.iter().find(|o| same(o)) {
            return Err(format!(
                "--denoised {}: is also an -o output; the denoised image never replaces the \
                 unbiased one, choose another name",
                o.display()
            ));
        }
        output::check_writable(path)?;
        let oidn = Oidn::load().map_err(|e| format!("--denoised: {e}"))?;
        Ok(Some(Denoised {
            path: path.to_path_buf(),
            format,
            oidn,
        }))
    }

    /// Denoises `img` (guided by its albedo and normal AOVs where it has them) and
    /// writes the copy, labelled in an EXR's header.
    pub fn write(&self, img: &Image, film: &Film) -> Result<(), String> {
        let guided = img.aov_index("albedo.R").is_some() && img.aov_index("normal.X").is_some();
        if !guided {
            note!(
                "note: --denoised without the albedo and normal AOVs denoises the colour \
                 alone; --aovs albedo,normal guides it"
            );
        }
        let clean = self.oidn.denoise(img).map_err(|e| e.to_string())?;
        output::write(&self.path, &clean, self.format, film, None)?;
        note!(
            "{} written (denoised by {}: for looking at, not for measuring)",
            self.path.display(),
            self.oidn.path().display()
        );
        Ok(())
    }
}
