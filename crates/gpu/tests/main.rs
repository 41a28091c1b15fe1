//! The gpu crate's integration tests in one binary (one link instead of 12; the
//! tests of every module run in parallel).

mod bsdf_twin;
mod common;
mod device;
mod direct_image;
mod env_twin;
mod layout;
mod light_tree_twin;
mod light_twin;
mod noise_twin;
mod perturbed_twin;
mod quadric_twin;
mod record_twin;
mod sampler_twin;
mod sums_twin;
mod tape_twin;
