//! The render crate's integration tests in one binary (one link instead of 6; the
//! tests of every module run in parallel).

#[path = "integrators/common.rs"]
mod common;
mod emitting;
mod image_textures;
mod integrators;
mod media;
mod meshes;
mod min_depth;
mod per_light;
mod roughness;
mod scene_format;
mod state_merge;
mod trained;
