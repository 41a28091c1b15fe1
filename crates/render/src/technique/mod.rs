//! Sampling techniques as first-class objects (DESIGN.md §4): each draws a direction
//! at a shading point and reports its solid-angle pdf for any direction, so that an
//! integrator can evaluate every technique's pdf for every sample (Veach 1997, ch. 9;
//! Kondapaneni et al. 2019).

use crate::bsdf::{Bsdf, BsdfSample};
use crate::frame::Frame;
use crate::light::{Crossed, LightSample, Lights, Selection, TrainedSelection};
use crate::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::{DVec2, DVec3};
pub use state::Technique;

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

/// How a technique draws a direction at a shading point and reports its solid-angle pdf
/// (its name and kind are [`state::Technique`]'s).
pub trait Sampling {
    /// The light selection of a technique that selects a light and samples it, at
    /// `ctx` (None for the others, and for `light-trained` without a table).
    fn selection<'a>(self, ctx: &ShadingPoint<'a>) -> Option<Selection<'a>>;

    /// Draws a direction from three uniform numbers (`uc` and `u`); None when the
    /// technique yields nothing here (a failed sample, which MIS must still count).
    fn sample(self, ctx: &ShadingPoint, uc: f64, u: DVec2) -> Option<TechniqueSample>;

    /// [`Sampling::sample`]'s direction, where the light mixtures (`light-power`,
    /// `light-uniform`, `light-spatial`, `light-trained`, `light#k`, `light-area`) leave
    /// the pdf NaN instead of walking the lights the direction crosses: for an
    /// integrator that evaluates every technique's pdf there anyway ([`pdfs`]), and
    /// counts a draw whose own pdf is not positive as failed, as [`Sampling::sample`] would
    /// have.
    fn draw(self, ctx: &ShadingPoint, uc: f64, u: DVec2) -> Option<TechniqueSample>;

    /// The solid-angle density with which [`Sampling::sample`] produces the unit direction
    /// `wi` (delta lobes excluded).
    fn pdf(self, ctx: &ShadingPoint, wi: DVec3) -> f64;
}

impl Sampling for Technique {
    fn selection<'a>(self, ctx: &ShadingPoint<'a>) -> Option<Selection<'a>> {
        match self {
            Technique::LightPower => Some(Selection::Power),
            Technique::LightUniform => Some(Selection::Uniform),
            Technique::LightSpatial => Some(Selection::Spatial),
            Technique::LightBvh => Some(Selection::Bvh),
            Technique::Light(k) => Some(Selection::One(k)),
            Technique::LightTrained => ctx.trained.map(Selection::Trained),
            _ => None,
        }
    }

    fn sample(self, ctx: &ShadingPoint, uc: f64, u: DVec2) -> Option<TechniqueSample> {
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

    fn draw(self, ctx: &ShadingPoint, uc: f64, u: DVec2) -> Option<TechniqueSample> {
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
            | Technique::LightBvh
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
            // No hemisphere inside a medium (n = 0): the technique draws nothing there.
            Technique::CosineHemisphere if ctx.n == DVec3::ZERO => None,
            Technique::CosineHemisphere => {
                let wi = Frame::from_z(facing_normal(ctx)).from_local(cosine_hemisphere(u));
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

    fn pdf(self, ctx: &ShadingPoint, wi: DVec3) -> f64 {
        pdf_over(self, ctx, wi, None)
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

/// [`Sampling::pdf`], the light mixtures' over the lights `crossed` lists (None: found
/// here); bit for bit the same. Out of line: its frame holds every technique's.
#[inline(never)]
fn pdf_over(t: Technique, ctx: &ShadingPoint, wi: DVec3, crossed: Option<&Crossed>) -> f64 {
    match t {
        Technique::Bsdf => ctx.bsdf.pdf(ctx.wo, wi),
        Technique::LightPower
        | Technique::LightUniform
        | Technique::LightSpatial
        | Technique::LightBvh
        | Technique::LightTrained
        | Technique::Light(_) => t.selection(ctx).map_or(0.0, |sel| {
            ctx.lights.pdf_selected_over(sel, ctx.p, ctx.n, wi, crossed)
        }),
        Technique::LightArea => ctx.lights.pdf_by_area_over(ctx.p, wi, crossed),
        Technique::Environment => ctx.lights.pdf_environment(wi),
        Technique::CosineHemisphere => cosine_hemisphere_pdf(facing_normal(ctx).dot(wi)),
    }
}

/// Whether `t` mixes over the area lights a direction crosses (with the environment):
/// the selections by power, uniformly, spatially and trained, and by area.
fn mixes(t: Technique) -> bool {
    matches!(
        t,
        Technique::LightPower
            | Technique::LightUniform
            | Technique::LightSpatial
            | Technique::LightBvh
            | Technique::LightTrained
            | Technique::LightArea
    )
}

/// Whether `t` draws only directions toward lights (a mixture over them, one light, or
/// the environment): its pdf is 0 along a direction that crosses no light.
pub(crate) fn samples_lights(t: Technique) -> bool {
    mixes(t) || matches!(t, Technique::Light(_) | Technique::Environment)
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
    let one = match techniques.iter().any(|t| matches!(t, Technique::Light(_))) {
        true => OneLight::Search,
        false => OneLight::None,
    };
    pdfs_known(one, techniques, ctx, wi, crossed, bsdf_pdf, out)
}

/// Whether a technique list holds one light's techniques (`light#k`), and where.
#[derive(Clone, Copy, Debug)]
pub(crate) enum OneLight<'a> {
    /// None does.
    None,
    /// Some do; their pdfs come from the general dispatch.
    Search,
    /// Some do, each light's at most once ([`one_light_map`]).
    Map(&'a OneLightMap),
}

/// Where a technique list's one-light techniques (`light#k`) are ([`one_light_map`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct OneLightMap {
    /// `of_light[k]`: the index of light k's technique (`u32::MAX` for none).
    pub of_light: Box<[u32]>,
    /// The indices of the other techniques, in order.
    pub others: Box<[u32]>,
}

/// For a technique list with one light's techniques (`light#k`), each light's technique
/// index and the other techniques'; None where there is none, or a light has two.
pub(crate) fn one_light_map(techniques: &[Technique]) -> Option<OneLightMap> {
    let lights = techniques.iter().filter_map(|t| match t {
        Technique::Light(k) => Some(*k),
        _ => None,
    });
    let mut map = vec![u32::MAX; lights.max()? + 1];
    let mut others = Vec::new();
    for (m, t) in techniques.iter().enumerate() {
        match *t {
            Technique::Light(k) if map[k] != u32::MAX => return None,
            Technique::Light(k) => map[k] = m as u32,
            _ => others.push(m as u32),
        }
    }
    Some(OneLightMap {
        of_light: map.into_boxed_slice(),
        others: others.into_boxed_slice(),
    })
}

/// [`pdfs`] for a caller that knows where the one-light techniques are (`one`).
#[inline(never)]
pub(crate) fn pdfs_known(
    one: OneLight,
    techniques: &[Technique],
    ctx: &ShadingPoint,
    wi: DVec3,
    crossed: Option<&Crossed>,
    bsdf_pdf: Option<f64>,
    out: &mut [f64],
) {
    // A direction that crosses no area light (most BSDF draws), without an environment:
    // the mixtures over the lights have no term to sum, 0.0 exactly. The optimal
    // estimators need the pdfs of such draws too, where the heuristics skip them.
    let none_crossed =
        crossed.is_some_and(|c| c.lights().is_empty()) && ctx.lights.environment().is_none();
    let fill = |out: &mut [f64], crossed: Option<&Crossed>| {
        for (o, &t) in out.iter_mut().zip(techniques) {
            *o = match (t, bsdf_pdf) {
                (Technique::Bsdf, Some(p)) => p,
                _ if none_crossed && mixes(t) => 0.0,
                _ => pdf_over(t, ctx, wi, crossed),
            };
        }
    };
    if let Some(c) = crossed {
        let (lights, p) = (ctx.lights, ctx.p);
        let listed = match one {
            OneLight::None => {
                pdfs_listed::<false>(techniques, lights, c, p, wi, bsdf_pdf, None, out)
            }
            OneLight::Map(m) => {
                pdfs_listed::<true>(techniques, lights, c, p, wi, bsdf_pdf, Some(m), out)
            }
            OneLight::Search => false,
        };
        if listed {
            return;
        }
        return fill(out, crossed);
    }
    if techniques.iter().filter(|&&t| mixes(t)).count() >= 2 {
        let area = techniques.contains(&Technique::LightArea);
        if let Some(c) = ctx.lights.crossed(ctx.p, wi, area) {
            return fill(out, Some(&c));
        }
    }
    fill(out, None)
}

/// Fills `out` as [`pdfs`] does where every technique's pdf at `wi` from `p` comes from
/// the lights `crossed` lists or is the BSDF's `bsdf_pdf`, bit for bit, without
/// [`pdf_over`]'s dispatch; false (`out` partly written) where one does not, or the
/// scene has an environment. The mixtures' from [`Lights::pdf_listed`]; with `ONE` and
/// the list's `map`, `light#k`'s as `pdf_selected_over` gives it: its own pdf from `p`
/// where the list holds light k, else 0 (all of them set to 0 at once, then the others
/// and the crossed lights' written: a match per technique cost about 18 instructions
/// each with `light#*`).
/// No calls in the loop over the techniques: one that called [`pdf_over`] for the
/// others kept values alive across the calls (+2.7 % with `light#*`), and one that
/// called the one light's pdf copied the list to the stack (+80 instructions a call).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn pdfs_listed<const ONE: bool>(
    techniques: &[Technique],
    lights: &Lights,
    crossed: &Crossed,
    p: DVec3,
    wi: DVec3,
    bsdf_pdf: Option<f64>,
    map: Option<&OneLightMap>,
    out: &mut [f64],
) -> bool {
    if lights.environment().is_some() {
        return false;
    }
    let listed = |t: Technique| match (t, bsdf_pdf) {
        (Technique::Bsdf, Some(pdf)) => Some(pdf),
        _ => lights.pdf_listed(t, crossed),
    };
    match map.filter(|_| ONE) {
        Some(map) => {
            out.fill(0.0);
            for &m in &map.others {
                let m = m as usize;
                match listed(techniques[m]) {
                    Some(pdf) => out[m] = pdf,
                    None => return false,
                }
            }
            for &k in crossed.lights() {
                if let Some(&m) = map.of_light.get(k as usize).filter(|&&m| m != u32::MAX) {
                    out[m as usize] = lights.pdf_one(p, k as usize, wi);
                }
            }
        }
        None => return pdfs_mixtures(techniques, lights, crossed, bsdf_pdf, out),
    }
    true
}

/// [`pdfs_listed`] where every technique is the BSDF (with `bsdf_pdf`) or a light
/// mixture, whose sums come from one pass over `crossed`'s list
/// ([`Lights::pdf_listed_mixtures`]); false where one is not, or the scene has an
/// environment.
#[inline(always)]
pub(crate) fn pdfs_mixtures(
    techniques: &[Technique],
    lights: &Lights,
    crossed: &Crossed,
    bsdf_pdf: Option<f64>,
    out: &mut [f64],
) -> bool {
    let Some((power, area)) = lights.pdf_listed_mixtures(crossed) else {
        return false;
    };
    for (o, &t) in out.iter_mut().zip(techniques) {
        *o = match (t, bsdf_pdf, area) {
            (Technique::Bsdf, Some(pdf), _) => pdf,
            (Technique::LightPower, ..) => power,
            (Technique::LightArea, _, Some(area)) => area,
            _ => return false,
        };
    }
    true
}

#[cfg(test)]
mod tests;
