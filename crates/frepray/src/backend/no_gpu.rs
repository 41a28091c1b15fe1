//! The GPU back end's types in a build without it (`--no-default-features`, no `gpu`
//! feature): the same names, so that front ends compile unchanged. [`super::shared_gpu`]
//! and GPU renders return [`GpuError::NotBuilt`], so none of the others is ever made.

use std::time::Duration;

/// Why there is no GPU: the back end is not built in.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum GpuError {
    /// Built without the `gpu` feature.
    #[error(
        "this frepray was built without the GPU back end (the `gpu` feature, on by \
         default); rebuild with it for --backend gpu"
    )]
    NotBuilt,
}

/// A GPU (never made in this build).
#[derive(Debug)]
pub struct Gpu;

/// What a GPU is (never made in this build).
#[derive(Clone, Debug)]
pub struct GpuInfo;

impl std::fmt::Display for GpuInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("none (built without the GPU back end)")
    }
}

impl Gpu {
    /// The adapter's description.
    pub fn info(&self) -> GpuInfo {
        GpuInfo
    }
}

/// A GPU render's statistics (never made in this build).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GpuStats;

impl GpuStats {
    /// The stages as (name, time).
    pub fn stage_parts(&self) -> [(&'static str, Duration); 6] {
        [("", Duration::ZERO); 6]
    }
    /// The counters a stage table leaves out.
    pub fn counters(&self) -> String {
        String::new()
    }
}

impl std::fmt::Display for GpuStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("no GPU statistics (built without the GPU back end)")
    }
}
