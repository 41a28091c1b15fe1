//! The sampling techniques' names (DESIGN.md §4): what a render's options list, shared by
//! both back ends. How each draws a direction and reports its pdf is the CPU's
//! (`render::technique`) and the GPU's (its WGSL twin).

use std::borrow::Cow;

/// A way of choosing directions at a shading point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Technique {
    /// Importance sampling of the BSDF.
    Bsdf,
    /// A light chosen ∝ power (area lights and the environment), then sampled.
    LightPower,
    /// A light chosen uniformly, then sampled.
    LightUniform,
    /// A point uniform over the total area of the area lights.
    LightArea,
    /// A light chosen ∝ a bound on its contribution at the shading point
    /// (`render::light::importance`), then sampled.
    LightSpatial,
    /// [`Technique::LightSpatial`]'s selection drawn from a light BVH in O(log n)
    /// (`render::light::LightTree`), then sampled.
    LightBvh,
    /// MIS light k alone (area lights in file order, then the environment).
    Light(usize),
    /// A light chosen by the pmf trained for the shading point's cell
    /// ([`crate::TrainedSelection`]), then sampled; fails without a trained table.
    LightTrained,
    /// The environment's own sampling.
    Environment,
    /// Cosine-weighted directions about the normal, on the viewer's side.
    CosineHemisphere,
}

impl From<scene::TechniqueKind> for Technique {
    fn from(k: scene::TechniqueKind) -> Self {
        match k {
            scene::TechniqueKind::Bsdf => Technique::Bsdf,
            scene::TechniqueKind::LightPower => Technique::LightPower,
            scene::TechniqueKind::LightUniform => Technique::LightUniform,
            scene::TechniqueKind::LightArea => Technique::LightArea,
            scene::TechniqueKind::LightSpatial => Technique::LightSpatial,
            scene::TechniqueKind::LightBvh => Technique::LightBvh,
            scene::TechniqueKind::Light(k) => Technique::Light(k as usize),
            scene::TechniqueKind::LightTrained => Technique::LightTrained,
            scene::TechniqueKind::Environment => Technique::Environment,
            scene::TechniqueKind::CosineHemisphere => Technique::CosineHemisphere,
        }
    }
}

impl Technique {
    /// Every technique without a parameter (`light#k` is one per light).
    pub const ALL: [Technique; 9] = [
        Technique::Bsdf,
        Technique::LightPower,
        Technique::LightUniform,
        Technique::LightArea,
        Technique::LightSpatial,
        Technique::LightBvh,
        Technique::LightTrained,
        Technique::Environment,
        Technique::CosineHemisphere,
    ];

    /// A short name (for tables and scene files): the scene files' name.
    pub fn name(self) -> Cow<'static, str> {
        self.kind().name()
    }

    /// The scene files' name for this technique.
    pub fn kind(self) -> scene::TechniqueKind {
        match self {
            Technique::Bsdf => scene::TechniqueKind::Bsdf,
            Technique::LightPower => scene::TechniqueKind::LightPower,
            Technique::LightUniform => scene::TechniqueKind::LightUniform,
            Technique::LightArea => scene::TechniqueKind::LightArea,
            Technique::LightSpatial => scene::TechniqueKind::LightSpatial,
            Technique::LightBvh => scene::TechniqueKind::LightBvh,
            Technique::Light(k) => scene::TechniqueKind::Light(k as u32),
            Technique::LightTrained => scene::TechniqueKind::LightTrained,
            Technique::Environment => scene::TechniqueKind::Environment,
            Technique::CosineHemisphere => scene::TechniqueKind::CosineHemisphere,
        }
    }
}
