//! Why an experiment stopped: its settings, a file, an image to measure, or a render.

use std::path::PathBuf;

/// What is wrong with an image to measure ([`super::Image::validate`], [`super::measure`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ImageError {
    /// No pixels.
    #[error("empty image ({width}x{height})")]
    Empty {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// Not `width × height` values.
    #[error("image of {width}x{height} pixels holds {values} values")]
    Values {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// The values it holds.
        values: usize,
    },
    /// An image and its reference (or its error image) of different sizes.
    #[error("image is {}x{} but the {what} is {}x{}", .image.0, .image.1, .other.0, .other.1)]
    Sizes {
        /// The image's size.
        image: (u32, u32),
        /// What it is compared with ("reference", "error image").
        what: &'static str,
        /// Its size.
        other: (u32, u32),
    },
}

/// Why [`super::run`] stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    /// An estimator name that cannot be part of a file name.
    #[error("{what} {name:?}: use letters, digits, '-', '_' and '.' (at most 64)")]
    Name {
        /// Which name ("baseline", "estimator", "reference estimator").
        what: &'static str,
        /// The name.
        name: String,
    },
    /// No sample count, or one of 0.
    #[error("give at least one sample count, each at least 1")]
    NoSampleCounts,
    /// A budget that is not a positive number of seconds.
    #[error("--budget {0}: expected a positive number of seconds")]
    Budget(f64),
    /// No repeats.
    #[error("repeats must be at least 1")]
    NoRepeats,
    /// The variance decomposition with one repeat.
    #[error("the variance decomposition needs two or more repeats")]
    DecomposeNeedsRepeats,
    /// A reference to render with no samples.
    #[error("the reference needs at least 1 sample per pixel")]
    NoReferenceSamples,
    /// A reference file of another size than the renders.
    #[error(
        "{}: the reference is {}×{}, the renders would be {}×{}",
        .path.display(), .found.0, .found.1, .wanted.0, .wanted.1
    )]
    ReferenceSize {
        /// The reference file.
        path: PathBuf,
        /// Its size.
        found: (u32, u32),
        /// The renders' size.
        wanted: (u32, u32),
    },
    /// A renderer without pixel-centred camera rays asked for the variance decomposition.
    #[error("this renderer cannot trace rays through pixel centres")]
    NoPixelCenters,
    /// A file or folder could not be created, read or written.
    #[error("cannot {action} {}: {source}", .path.display())]
    Io {
        /// "create", "read" or "write".
        action: &'static str,
        /// The file or folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A file that is not what the experiment reads (an EXR image, a manifest of this
    /// format).
    #[error("{}: {message}", .path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// An image unfit to measure; `what` names it.
    #[error("{what}: {source}")]
    Image {
        /// Which image (the render's place in the sweep, "reference").
        what: String,
        /// What is wrong.
        source: ImageError,
    },
    /// A plot could not be drawn (the plotting library's message).
    #[error("{}: {message}", .path.display())]
    Plot {
        /// The plot file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A render failed.
    #[error(transparent)]
    Render(#[from] crate::Error),
}

impl ExperimentError {
    /// An [`ExperimentError::Io`] on `path`.
    pub(super) fn io(
        action: &'static str,
        path: &std::path::Path,
    ) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.to_path_buf();
        move |source| ExperimentError::Io {
            action,
            path,
            source,
        }
    }

    /// An [`ExperimentError::Image`] about `what`.
    pub(super) fn image(what: impl Into<String>) -> impl FnOnce(ImageError) -> Self {
        let what = what.into();
        move |source| ExperimentError::Image { what, source }
    }
}
