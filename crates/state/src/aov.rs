//! First-hit arbitrary output variables (AOVs) by name: which extra film channels a
//! render keeps, and where their sums lie in a pixel's record (how they are computed:
//! `render::integrator::aov`).

use crate::options_error::OptionsError;

/// An extra film channel group.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Aov {
    /// Channel `depth`.
    Depth,
    /// Channels `normal.X`, `normal.Y`, `normal.Z`.
    Normal,
    /// Channels `albedo.R`, `albedo.G`, `albedo.B`.
    Albedo,
}

impl Aov {
    /// Every AOV.
    pub const ALL: [Aov; 3] = [Aov::Depth, Aov::Normal, Aov::Albedo];
    /// The name (for scene files and the CLI).
    pub const fn name(self) -> &'static str {
        match self {
            Aov::Depth => "depth",
            Aov::Normal => "normal",
            Aov::Albedo => "albedo",
        }
    }
    /// Its film channel names.
    pub const fn channels(self) -> &'static [&'static str] {
        match self {
            Aov::Depth => &["depth"],
            Aov::Normal => &["normal.X", "normal.Y", "normal.Z"],
            Aov::Albedo => &["albedo.R", "albedo.G", "albedo.B"],
        }
    }
    /// Index of its first value in the per-pixel AOV sums.
    pub const fn offset(self) -> usize {
        match self {
            Aov::Depth => 0,
            Aov::Normal => 1,
            Aov::Albedo => 4,
        }
    }
}

impl std::str::FromStr for Aov {
    type Err = OptionsError;
    fn from_str(s: &str) -> Result<Self, OptionsError> {
        let key = s.trim().to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|a| a.name() == key || (key == "normals" && *a == Aov::Normal))
            .ok_or_else(|| OptionsError::UnknownAov(s.to_string()))
    }
}
