//! Sampling techniques as first-class objects (DESIGN.md §4): each draws a direction
//! at a shading point and reports its solid-angle pdf for any direction, so that an
//! integrator can evaluate every technique's pdf for every sample (Veach 1997, ch. 9;
//! Kondapaneni et al. 2019).

use crate::bsdf::{Bsdf, BsdfSample};
use crate::frame::Frame;
use crate::light::{Crossed, LightSample, Lights, Selection, TrainedSelection};
use crate::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::{DVec2, DVec3};
use std::borrow::Cow;

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
    /// The trained light selection of this render, if it has one (`light-trained`).
    pub trained: Option<&'a TrainedSelection>,
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
    /// A light chosen uniformly, then sampled.
    LightUniform,
    /// A point uniform over the total area of the area lights.
    LightArea,
    /// A light chosen ∝ a bound on its contribution at the shading point
    /// ([`crate::light::importance`]), then sampled.
    LightSpatial,
    /// MIS light k alone (area lights in file order, then the environment).
    Light(usize),
    /// A light chosen by the pmf trained for the shading point's cell
    /// ([`TrainedSelection`]), then sampled; fails without a trained table.
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
            scene::TechniqueKind::Light(k) => Technique::Light(k as usize),
            scene::TechniqueKind::LightTrained => Technique::LightTrained,
            scene::TechniqueKind::Environment => Technique::Environment,
            scene::TechniqueKind::CosineHemisphere => Technique::CosineHemisphere,
        }
    }
}

impl Technique {
    /// Every technique without a parameter (`light#k` is one per light).
    pub const ALL: [Technique; 8] = [
        Technique::Bsdf,
        Technique::LightPower,
        Technique::LightUniform,
        Technique::LightArea,
        Technique::LightSpatial,
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
            Technique::Light(k) => scene::TechniqueKind::Light(k as u32),
            Technique::LightTrained => scene::TechniqueKind::LightTrained,
            Technique::Environment => scene::TechniqueKind::Environment,
            Technique::CosineHemisphere => scene::TechniqueKind::CosineHemisphere,
        }
    }

    /// The light selection of a technique that selects a light and samples it, at
    /// `ctx` (None for the others, and for `light-trained` without a table).
    pub fn selection<'a>(self, ctx: &ShadingPoint<'a>) -> Option<Selection<'a>> {
        match self {
            Technique::LightPower => Some(Selection::Power),
            Technique::LightUniform => Some(Selection::Uniform),
            Technique::LightSpatial => Some(Selection::Spatial),
            Technique::Light(k) => Some(Selection::One(k)),
            Technique::LightTrained => ctx.trained.map(Selection::Trained),
            _ => None,
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
        let s = self.draw(ctx, uc, u)?;
        if !s.pdf.is_nan() {
            return Some(s);
        }
        let pdf = self.pdf(ctx, s.wi);
        (pdf > 0.0 && pdf.is_finite()).then_some(TechniqueSample {
            pdf,
            light: s.light.map(|l| LightSample { pdf, ..l }),
            ..s
        })
    }

    /// [`Self::sample`]'s direction, where the light mixtures (`light-power`,
    /// `light-uniform`, `light-spatial`, `light-trained`, `light#k`, `light-area`) leave
    /// the pdf NaN instead of walking the lights the direction crosses: for an
    /// integrator that evaluates every technique's pdf there anyway ([`pdfs`]), and
    /// counts a draw whose own pdf is not positive as failed, as [`Self::sample`] would
    /// have.
    pub fn draw(self, ctx: &ShadingPoint, uc: f64, u: DVec2) -> Option<TechniqueSample> {
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
            Technique::LightPower
            | Technique::LightUniform
            | Technique::LightSpatial
            | Technique::LightTrained
            | Technique::Light(_) => ctx
                .lights
                .draw_selected(self.selection(ctx)?, ctx.p, ctx.n, uc, u)
                .map(TechniqueSample::from_light),
            Technique::LightArea => ctx
                .lights
                .draw_by_area(ctx.p, uc, u)
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
        self.pdf_over(ctx, wi, None)
    }

    /// [`Self::pdf`], the light mixtures' over the lights `crossed` lists (None: found
    /// here); bit for bit the same.
    fn pdf_over(self, ctx: &ShadingPoint, wi: DVec3, crossed: Option<&Crossed>) -> f64 {
        match self {
            Technique::Bsdf => ctx.bsdf.pdf(ctx.wo, wi),
            Technique::LightPower
            | Technique::LightUniform
            | Technique::LightSpatial
            | Technique::LightTrained
            | Technique::Light(_) => self.selection(ctx).map_or(0.0, |sel| {
                ctx.lights.pdf_selected_over(sel, ctx.p, ctx.n, wi, crossed)
            }),
            Technique::LightArea => ctx.lights.pdf_by_area_over(ctx.p, wi, crossed),
            Technique::Environment => ctx.lights.pdf_environment(wi),
            Technique::CosineHemisphere => cosine_hemisphere_pdf(Self::facing_normal(ctx).dot(wi)),
        }
    }
}

/// Fills `out[k]` with `techniques[k].pdf(ctx, wi)`, the light mixtures' over the lights
/// `crossed` lists where the caller found them ([`Lights::along`]), and the BSDF's
/// `bsdf_pdf` where the caller has it ([`crate::bsdf::Bsdf::f_pdf`]). Otherwise, where
/// two or more techniques mix over the lights the direction crosses, those lights and
/// their pdfs are found once ([`Lights::crossed`]) instead of once per technique.
pub fn pdfs(
    techniques: &[Technique],
    ctx: &ShadingPoint,
    wi: DVec3,
    crossed: Option<&Crossed>,
    bsdf_pdf: Option<f64>,
    out: &mut [f64],
) {
    let fill = |out: &mut [f64], crossed: Option<&Crossed>| {
        for (o, &t) in out.iter_mut().zip(techniques) {
            *o = match (t, bsdf_pdf) {
                (Technique::Bsdf, Some(p)) => p,
                _ => t.pdf_over(ctx, wi, crossed),
            };
        }
    };
    if crossed.is_some() {
        return fill(out, crossed);
    }
    let mixes = |t: &&Technique| {
        matches!(
            t,
            Technique::LightPower
                | Technique::LightUniform
                | Technique::LightSpatial
                | Technique::LightTrained
                | Technique::LightArea
        )
    };
    if techniques.iter().filter(mixes).count() >= 2 {
        let area = techniques.contains(&Technique::LightArea);
        if let Some(c) = ctx.lights.crossed(ctx.p, wi, area) {
            return fill(out, Some(&c));
        }
    }
    fill(out, None)
}

#[cfg(test)]
mod tests;
