//! The errors of rendering and of render states, typed at the crate's boundary.

use crate::options_error::OptionsError;
use std::ops::Range;
use std::path::PathBuf;

/// What can go wrong in a render or with a render state.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The render options are invalid.
    #[error(transparent)]
    Options(#[from] OptionsError),
    /// A state that cannot be resumed: not the one sample range of a stopped render,
    /// or a whole one.
    #[error("{0}")]
    Resume(String),
    /// The worker threads could not be started.
    #[error("thread pool: {0}")]
    ThreadPool(String),
    /// A render that would exceed a resource limit (memory, threads): the message gives
    /// the estimate and the limit.
    #[error("{0}")]
    Limit(String),
    /// A render of no samples was asked for.
    #[error("empty sample range {}..{}", .0.start, .0.end)]
    EmptyRange(Range<u32>),
    /// Two states of different renders (the message names the first difference).
    #[error("cannot merge render states of different renders: {0}")]
    Mismatch(String),
    /// Two states share samples.
    #[error(
        "cannot merge render states whose samples overlap ({}..{} and {}..{}): the same \
         samples would count twice", .0.start, .0.end, .1.start, .1.end
    )]
    Overlap(Range<u32>, Range<u32>),
    /// Bytes that are not a render state of this version.
    #[error("not a valid frepray render state: {0}")]
    Corrupt(String),
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// An error in a named file.
    #[error("{}: {source}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        source: Box<Error>,
    },
}
