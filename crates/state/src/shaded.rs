//! Samples shaded by another back end (the GPU's wavefront kernels), added into the
//! per-pixel records by the same code as the CPU's, so that the two back ends share one
//! [`crate::RenderState`] and its estimators (GPU.md §8). A back end that keeps the
//! per-pixel sums itself forms each sample's terms as [`Tally::add`] would
//! ([`Tally::linear`] describes them) and hands over finished records; the optimal
//! estimators' solves stay the CPU's either way.
//!
//! A back end hands over, per pixel sample, what the CPU integrator would have added
//! (for the AOV integrators only the first hit's AOVs, [`Tally::add_aov_sample`]): the
//! outside-MIS radiance (an emitter seen by the camera) and, for each vertex the path
//! shaded, every technique's draws there in list order (technique k, then draw j), each a
//! failed draw or `(f, pdfs)` with the path throughput in f. [`Tally::add`] replays them
//! through the same calls as the CPU integrator (`add_draw`, `add_failed`, `end_vertex`,
//! `end_sample`), so a GPU sample range and a CPU one merge like two CPU ranges.

use crate::color::Rgb;
use crate::options::MAX_TECHNIQUES;
use crate::record::{Pixel, Record};
use crate::tally::{Combine, Tally};
use scene::IntegratorKind;

/// One technique draw at the first vertex, as shaded elsewhere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShadedDraw<'a> {
    /// The technique produced no direction (counted as a failed draw for MIS).
    Failed,
    /// A direction with integrand `f` (RGB, visibility included) and every technique's
    /// pdf there, in the technique list's order.
    Sample {
        /// `f_s · |cos| · Li`.
        f: [f64; 3],
        /// The techniques' solid-angle pdfs.
        pdfs: &'a [f64],
        /// The MIS light the draw's ray reaches, objects ignored (the nearest area light
        /// along it, else the environment's index): which per-light block the draw
        /// feeds in per-light mode; None reaches none.
        light: Option<usize>,
    },
}

/// One vertex shaded elsewhere: what it adds outside MIS (point and spot lights,
/// throughput included) and its technique draws.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadedVertex<'a> {
    /// Σ β·f·|cos|·I/d² over the point and spot lights that reach the vertex, and
    /// the delta-lobe draws' β·weight·Li/n.
    pub outside: [f64; 3],
    /// Σ n_k draws, technique by technique in list order.
    pub draws: &'a [ShadedDraw<'a>],
    /// False at a purely specular vertex: no technique draws there and no MIS
    /// iteration is counted (`draws` is ignored); its light is all in `outside`.
    pub mis: bool,
}

/// How a draw enters a pixel's record where every record word is a plain sum of
/// per-sample terms (`mis::block`'s layouts).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LinearMis {
    /// `path` with a heuristic: `w_k f / (n_k p_k)` straight into the outside sum.
    Outside(mis::Heuristic),
    /// A heuristic estimator block per depth: `[N | Σ (3)]`.
    Weighted(mis::Heuristic),
    /// An optimal-direct block per depth: `[N | Â packed, b̂ channel-major]`.
    Direct,
    /// An optimal-uncorrelated block per depth: `[N_A, N_B | Â, b̂ of set A | of set B]`,
    /// a sample with global index i going to set `i mod 2`.
    Uncorrelated,
    /// An optimal-progressive (or -full) block per depth, `[N | Σ F (3) | α (3T) | Â, b̂]`,
    /// whose Σ F needs the α of earlier samples, so that it is not a plain sum: a
    /// sample adds its terms to N and the moments as optimal-direct does, and to Σ F_c
    /// `G_c − Σ_i α_ci Q_i` with the α-free `G_c = Σ f_c/s` over its valid draws and
    /// `Q_i = Σ p_i/s` over them `+ Σ 1/n_t` over the failed draws of technique `t = i`
    /// `− 1` per closed iteration (`mis::progressive`'s `F_k` regrouped). A back end
    /// keeps `G` in the Σ F words and `Q` in the first T α words of its terms, applies
    /// α itself, and has α re-solved ([`mis::Kernel::resolve`]) where the schedule says.
    Progressive(mis::Schedule),
}

/// What one sample adds to a pixel's record when every word is a sum of per-sample
/// terms (the progressive estimators' Σ F with α applied, [`LinearMis::Progressive`]):
/// enough for another back end to keep the per-pixel sums itself (GPU.md §8) and hand
/// over only the finished record.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearRecord {
    /// Where each sum lives.
    pub record: Record,
    /// How draws enter it.
    pub mis: LinearMis,
    /// Vertices shallower than this add nothing (but AOVs).
    pub min_depth: u32,
    /// Draws per technique per vertex.
    pub counts: Vec<u32>,
    /// For the AOV integrators, which AOV is the image: 0 depth, 1 normal, 2 albedo.
    pub aov_image: Option<u32>,
}

impl Tally {
    /// Words of one pixel's record.
    pub fn stride(&self) -> usize {
        self.record.stride()
    }

    /// Whether the render is one of the AOV integrators (`depth`, `normals`, `albedo`),
    /// whose samples go to [`Self::add_aov_sample`].
    pub fn aov_integrator(&self) -> bool {
        !matches!(self.kind, IntegratorKind::Direct | IntegratorKind::Path)
    }

    /// The record as sums of per-sample terms ([`LinearRecord`]).
    pub fn linear(&self) -> Option<LinearRecord> {
        let mis = match &self.combine {
            Combine::Heuristic(h) => LinearMis::Outside(*h),
            Combine::Estimator(k) => match (k.method(), k.schedule()) {
                (_, Some(s)) => LinearMis::Progressive(s),
                (mis::Method::OptimalDirect, _) => LinearMis::Direct,
                (mis::Method::OptimalUncorrelated, _) => LinearMis::Uncorrelated,
                (m, _) => LinearMis::Weighted(m.heuristic(k.params())?),
            },
        };
        Some(LinearRecord {
            record: self.record,
            mis,
            min_depth: self.min_depth,
            counts: self.counts.clone(),
            aov_image: match self.kind {
                IntegratorKind::Direct | IntegratorKind::Path => None,
                IntegratorKind::Depth => Some(0),
                IntegratorKind::Normals => Some(1),
                IntegratorKind::Albedo => Some(2),
            },
        })
    }

    /// Adds sample `index` of a pixel of an AOV integrator: the first hit's depth, normal
    /// and albedo (`integrator/aov.rs`'s order), as its image and its AOVs.
    pub fn add_aov_sample(&self, rec: &mut [f64], index: u32, aovs: &[f64; 7]) {
        let mut px = Pixel {
            rec,
            key: u64::from(index),
            mute: false,
        };
        px.add(match self.kind {
            IntegratorKind::Depth => Rgb::splat(aovs[0]),
            IntegratorKind::Normals => Rgb::new(aovs[1], aovs[2], aovs[3]),
            _ => Rgb::new(aovs[4], aovs[5], aovs[6]),
        });
        px.add_aovs(aovs);
        px.end_sample();
    }

    /// Adds sample `index` of a pixel to its record `rec`: `outside` (the emitters the
    /// camera saw) outside MIS, and each vertex the path shaded (vertex d at
    /// `vertices[d]`; none when the camera ray met no surface): its own outside-MIS
    /// light, then its draws technique by technique in list order, with the path
    /// throughput in `f`; and the first hit's AOVs where the render keeps them. Vertices
    /// below the options' `min_depth` add nothing. Panics if a vertex does not have Σ n_k
    /// draws.
    pub fn add(
        &self,
        rec: &mut [f64],
        index: u32,
        outside: [f64; 3],
        vertices: &[ShadedVertex],
        aovs: &[f64; 7],
    ) {
        let mut px = Pixel {
            rec,
            key: u64::from(index),
            mute: false,
        };
        if self.aovs {
            px.add_aovs(aovs);
        }
        // The outside sum holds the emitters the camera saw: depth 0, muted below
        // `min_depth` as in `integrator/path.rs`.
        if self.min_depth == 0 {
            px.add(Rgb::from_array(outside));
        }
        let total: u32 = self.counts.iter().sum();
        let t = self.techniques.len();
        for (depth, v) in vertices.iter().enumerate() {
            px.mute = depth + 1 < self.min_depth as usize;
            px.add(Rgb::from_array(v.outside));
            if !v.mis {
                px.mute = false;
                continue;
            }
            let draws = v.draws;
            assert_eq!(draws.len(), total as usize, "one entry per draw");
            let mut at = 0;
            for (k, &n) in self.counts.iter().enumerate() {
                for _ in 0..n {
                    match draws[at] {
                        ShadedDraw::Failed => px.add_failed(self, depth, k),
                        ShadedDraw::Sample { f, pdfs, light } => {
                            debug_assert!(pdfs.len() == t && t <= MAX_TECHNIQUES);
                            px.add_draw(self, depth, k, Rgb::from_array(f), pdfs, light);
                        }
                    }
                    at += 1;
                }
            }
            px.end_vertex(self, depth);
            px.mute = false;
        }
        px.end_sample();
    }
}
