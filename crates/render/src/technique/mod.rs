//! Sampling techniques as first-class objects (DESIGN.md §4): each draws a direction
//! at a shading point and reports its solid-angle pdf for any direction, so that an
//! integrator can evaluate every technique's pdf for every sample (Veach 1997, ch. 9;
//! Kondapaneni et al. 2019).

use crate::bsdf::{Bsdf, BsdfSample};
use crate::frame::Frame;
use crate::light::{LightSample, Lights};
use crate::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::{DVec2, DVec3};

/// What a technique needs to know about the point being shaded.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint<'a> {
    /// Position.
    pub p: DVec3,
    /// Unit shading normal.
    pub n: DVec3,
    /// Unit direction toward the viewer.
    pub wo: DVec3,
    /// The BSDF there.
    pub bsdf: &'a Bsdf<'a>,
    /// The scene's lights.
    pub lights: &'a Lights,
}

/// A direction drawn by a technique.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TechniqueSample {
    /// Unit direction from the shading point.
    pub wi: DVec3,
    /// Solid-angle density (for `specular`, the discrete probability of the lobe).
    pub pdf: f64,
    /// From a delta BSDF lobe: no other technique can produce it, so it is weighted
    /// outside MIS.
    pub specular: bool,
    /// The BSDF's own sample, for BSDF sampling.
    pub bsdf: Option<BsdfSample>,
    /// The light's own sample (sampled point, its distance and radiance), for the
    /// light techniques.
    pub light: Option<LightSample>,
}

impl TechniqueSample {
    fn from_light(s: LightSample) -> Self {
        Self {
            wi: s.wi,
            pdf: s.pdf,
            specular: false,
            bsdf: None,
            light: Some(s),
        }
    }
}

/// A way of choosing directions at a shading point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Technique {
    /// Importance sampling of the BSDF.
    Bsdf,
    /// A light chosen ∝ power (area lights and the environment), then sampled.
    LightPower,
    /// A point uniform over the total area of the area lights.
    LightArea,
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
            scene::TechniqueKind::LightArea => Technique::LightArea,
            scene::TechniqueKind::Environment => Technique::Environment,
            scene::TechniqueKind::CosineHemisphere => Technique::CosineHemisphere,
        }
    }
}

impl Technique {
    /// Every technique.
    pub const ALL: [Technique; 5] = [
        Technique::Bsdf,
        Technique::LightPower,
        Technique::LightArea,
        Technique::Environment,
        Technique::CosineHemisphere,
    ];

    /// A short name (for tables and scene files).
    pub fn name(self) -> &'static str {
        match self {
            Technique::Bsdf => "bsdf",
            Technique::LightPower => "light",
            Technique::LightArea => "light-area",
            Technique::Environment => "environment",
            Technique::CosineHemisphere => "cosine",
        }
    }

    /// The scene files' name for this technique.
    pub fn kind(self) -> scene::TechniqueKind {
        match self {
            Technique::Bsdf => scene::TechniqueKind::Bsdf,
            Technique::LightPower => scene::TechniqueKind::LightPower,
            Technique::LightArea => scene::TechniqueKind::LightArea,
            Technique::Environment => scene::TechniqueKind::Environment,
            Technique::CosineHemisphere => scene::TechniqueKind::CosineHemisphere,
        }
    }

    /// The normal turned toward the viewer.
    fn facing_normal(ctx: &ShadingPoint) -> DVec3 {
        if ctx.n.dot(ctx.wo) < 0.0 {
            -ctx.n
        } else {
            ctx.n
        }
    }

    /// Draws a direction from three uniform numbers (`uc` and `u`); None when the
    /// technique yields nothing here (a failed sample, which MIS must still count).
    pub fn sample(self, ctx: &ShadingPoint, uc: f64, u: DVec2) -> Option<TechniqueSample> {
        match self {
            Technique::Bsdf => {
                let s = ctx.bsdf.sample_f(ctx.wo, uc, u)?;
                Some(TechniqueSample {
                    wi: s.wi,
                    pdf: s.pdf,
                    specular: s.specular,
                    bsdf: Some(s),
                    light: None,
                })
            }
            Technique::LightPower => ctx
                .lights
                .sample_by_power(ctx.p, uc, u)
                .map(TechniqueSample::from_light),
            Technique::LightArea => ctx
                .lights
                .sample_by_area(ctx.p, uc, u)
                .map(TechniqueSample::from_light),
            Technique::Environment => ctx
                .lights
                .sample_environment(u)
                .map(TechniqueSample::from_light),
            Technique::CosineHemisphere => {
                let wi = Frame::from_z(Self::facing_normal(ctx)).from_local(cosine_hemisphere(u));
                let pdf = self.pdf(ctx, wi);
                (pdf > 0.0).then_some(TechniqueSample {
                    wi,
                    pdf,
                    specular: false,
                    bsdf: None,
                    light: None,
                })
            }
        }
    }

    /// The solid-angle density with which [`Self::sample`] produces the unit direction
    /// `wi` (delta lobes excluded).
    pub fn pdf(self, ctx: &ShadingPoint, wi: DVec3) -> f64 {
        match self {
            Technique::Bsdf => ctx.bsdf.pdf(ctx.wo, wi),
            Technique::LightPower => ctx.lights.pdf_by_power(ctx.p, wi),
            Technique::LightArea => ctx.lights.pdf_by_area(ctx.p, wi),
            Technique::Environment => ctx.lights.pdf_environment(wi),
            Technique::CosineHemisphere => cosine_hemisphere_pdf(Self::facing_normal(ctx).dot(wi)),
        }
    }
}

/// Fills `out[k]` with `techniques[k].pdf(ctx, wi)`.
pub fn pdfs(techniques: &[Technique], ctx: &ShadingPoint, wi: DVec3, out: &mut [f64]) {
    for (o, t) in out.iter_mut().zip(techniques) {
        *o = t.pdf(ctx, wi);
    }
}

#[cfg(test)]
mod tests;
