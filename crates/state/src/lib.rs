//! What the two back ends share (DESIGN.md §3): the render options, the per-pixel
//! records and how samples enter them, the [`RenderState`] that merges and resumes, the
//! sample streams and their dimension layout, and the images and files a render ends
//! in. `render` (the CPU) and `gpu` stand side by side on it, so that a sample range of
//! one merges with a range of the other.

#![warn(missing_docs)]

pub mod aov;
pub mod color;
pub mod counts;
pub mod dims;
pub mod error;
pub mod host;
pub mod image;
pub mod limits;
pub mod options;
pub mod options_error;
pub mod output;
pub mod png_io;
pub mod record;
pub mod render_state;
pub mod sampler;
pub mod shaded;
pub mod stats;
pub mod tally;
pub mod technique;
pub mod trained;
pub mod value_png;

pub use aov::Aov;
pub use color::Rgb;
pub use counts::{CpuStages, RayCounts, RayKind, TIMED_EVERY};
pub use error::Error;
pub use host::{CoatAlbedo, Host, LightBounds, LightTreeNode, LightTreeTable};
pub use image::{Film, Image, Tonemap};
pub use options::{uses_mis, Engine, RenderOptions, MAX_TECHNIQUES};
pub use options_error::OptionsError;
pub use record::{Pixel, Record};
pub use render_state::{fnv1a, BlockDetail, PixelDetail, RenderState, StateHeader};
pub use sampler::{SampleStream, Sampler};
pub use scene::IntegratorKind;
pub use shaded::{LinearMis, LinearRecord, ShadedDraw, ShadedVertex};
pub use stats::RenderStats;
pub use tally::{Combine, Tally};
pub use technique::Technique;
pub use trained::TrainedSelection;
