//! Readers of model files: frepray's own `.frep` language, HyperFun `.hf` programs and
//! Fidget `.vm` tapes, plus a `.vm` writer so that any frepray solid can be fed to Fidget.
//!
//! Every reader returns a [`Model`] in the FRep convention (F ≥ 0 inside): importers of
//! distance-like formats negate. Malformed input is a [`ReadError`] naming the file, line
//! and column and saying what was expected; no input makes a reader panic or recurse
//! without bound (nesting is capped at [`MAX_DEPTH`] levels).
//!
//! ```
//! use frep::read::{read_str, Format};
//! let m = read_str("let ball = sphere([0, 0, 0], 1)\noutput ball", Format::Frep, "ball.frep")
//!     .unwrap();
//! assert_eq!(m.name.as_deref(), Some("ball"));
//! let f = frep::Expr::new(&m.shape.to_tree().unwrap());
//! assert_eq!(f.eval([0.0, 0.0, 0.0]), 1.0);
//! let err = read_str("output sphere([0, 0, 0]", Format::Frep, "bad.frep").unwrap_err();
//! assert_eq!((err.line, err.column), (1, 24));
//! ```

mod frep;
mod hf;
mod lex;
mod mesh_file;
mod sym;
mod vm;
mod vm_write;

pub use mesh_file::{is_mesh_extension, read_mesh, read_obj, read_ply, MAX_MESH_BYTES};
pub use vm::{view_domain, VM_DOMAIN};
pub use vm_write::write_vm;

use crate::ray::Aabb;
use crate::shape::Shape;
use std::fmt;
use std::path::Path;

/// How deeply brackets, calls and blocks may nest before a reader gives up (a guard
/// against stack exhaustion on hostile input).
pub const MAX_DEPTH: usize = 200;

/// A reader's complaint: where in which file, and what was expected there.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadError {
    /// The file (as given to the reader).
    pub file: String,
    /// 1-based line; 0 when the file could not be read at all.
    pub line: usize,
    /// 1-based column (in characters); 0 when the file could not be read at all.
    pub column: usize,
    /// What was expected and what was found.
    pub message: String,
}

impl ReadError {
    /// An error at a position.
    pub(crate) fn at(file: &str, line: usize, column: usize, message: impl Into<String>) -> Self {
        Self {
            file: file.to_string(),
            line,
            column,
            message: message.into(),
        }
    }
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            // About the whole file (unreadable, unknown kind, too large): no position.
            return write!(f, "{}: {}", self.file, self.message);
        }
        write!(
            f,
            "{}:{}:{}: {}",
            self.file, self.line, self.column, self.message
        )
    }
}

impl std::error::Error for ReadError {}

/// A model file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// frepray's expression language (`.frep`, docs/frep-syntax.md).
    Frep,
    /// A HyperFun program (`.hf`).
    HyperFun,
    /// A Fidget tape (`.vm`), distance-like: negated on import.
    Vm,
}

impl Format {
    /// The format named by a file extension (`frep`, `hf`, `vm`; any case).
    pub fn from_extension(ext: &str) -> Option<Format> {
        match ext.to_ascii_lowercase().as_str() {
            "frep" => Some(Format::Frep),
            "hf" => Some(Format::HyperFun),
            "vm" => Some(Format::Vm),
            _ => None,
        }
    }
}

/// A solid read from a file.
#[derive(Clone, Debug)]
pub struct Model {
    /// The model's name, when the file gives one (HyperFun model name, `.frep` output name).
    pub name: Option<String>,
    /// The solid (F ≥ 0 inside).
    pub shape: Shape,
    /// A declared bounding box, when the file gives one.
    pub domain: Option<Aabb>,
}

/// The largest model file read: 16 MiB (the largest shared model, Fidget's
/// `prospero.vm`, is 149 kB); larger texts take unbounded time and memory to lower.
pub const MAX_MODEL_BYTES: u64 = 16 << 20;

/// Reads a model file, choosing the format from its extension. An unreadable file, an
/// unknown extension or a file over [`MAX_MODEL_BYTES`] is a [`ReadError`] at line 0
/// (shown without a position).
pub fn read_file(path: &Path) -> Result<Model, ReadError> {
    let file = path.display().to_string();
    let format = path
        .extension()
        .and_then(|e| e.to_str())
        .and_then(Format::from_extension)
        .ok_or_else(|| {
            ReadError::at(
                &file,
                0,
                0,
                "expected a file ending in .frep, .hf or .vm, found another extension",
            )
        })?;
    let meta = std::fs::metadata(path)
        .map_err(|e| ReadError::at(&file, 0, 0, format!("cannot read the file: {e}")))?;
    // A device or pipe reports length 0 and may never end (`/dev/zero`) or block for
    // ever (a FIFO with no writer): only plain files are opened.
    if !meta.is_file() {
        return Err(ReadError::at(
            &file,
            0,
            0,
            "expected a model file, found a folder, device or pipe",
        ));
    }
    let len = meta.len();
    if len > MAX_MODEL_BYTES {
        return Err(ReadError::at(
            &file,
            0,
            0,
            format!("the file is {len} bytes, more than the {MAX_MODEL_BYTES} a model may have"),
        ));
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| ReadError::at(&file, 0, 0, format!("cannot read the file: {e}")))?;
    read_str(&text, format, &file)
}

/// Reads a model from text; `file` names it in errors.
pub fn read_str(text: &str, format: Format, file: &str) -> Result<Model, ReadError> {
    match format {
        Format::Frep => frep::read(text, file),
        Format::HyperFun => hf::read(text, file),
        Format::Vm => vm::read(text, file),
    }
}
