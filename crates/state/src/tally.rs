//! What a render's options make of its per-pixel records, for either back end: the
//! record layout, how a vertex's draws combine (heuristic weights or one [`mis`]
//! estimator block per depth), and the sample-dimension layout. The CPU integrator is
//! built on it, and another back end adds the samples it shaded through it
//! (`shaded.rs`), so that the two fill the same records the same way.

use crate::dims::Dims;
use crate::options::RenderOptions;
use crate::options_error::OptionsError;
use crate::record::Record;
use crate::technique::Technique;
use mis::{Kernel, Layout};
use scene::IntegratorKind;
use std::sync::Arc;

/// How the draws at a vertex are combined.
#[derive(Clone, Debug)]
pub enum Combine {
    /// Heuristic weights applied per draw, summed into the pixel (path, heuristics).
    Heuristic(mis::Heuristic),
    /// One [`mis`] estimator block per pixel and depth, run by this kernel.
    Estimator(Kernel),
}

/// A render's options digested once: what both back ends need to fill its records.
#[derive(Clone, Debug)]
pub struct Tally {
    /// The integrator.
    pub kind: IntegratorKind,
    /// The techniques, in list order.
    pub techniques: Vec<Technique>,
    /// Draws per technique per vertex.
    pub counts: Vec<u32>,
    /// The techniques' layout in the estimators' terms.
    pub layout: Arc<Layout>,
    /// How the draws at a vertex combine.
    pub combine: Combine,
    /// Where each sum lives in a pixel's record.
    pub record: Record,
    /// Which random dimension each draw uses.
    pub dims: Dims,
    /// Vertices shallower than this add nothing ([`RenderOptions::min_depth`]).
    pub min_depth: u32,
    /// Whether AOVs are gathered.
    pub aovs: bool,
}

impl Tally {
    /// Digests `o` (validated first).
    pub fn new(o: &RenderOptions) -> Result<Self, OptionsError> {
        o.validate()?;
        let techniques: Vec<Technique> = o.techniques.iter().map(|t| t.0).collect();
        let counts: Vec<u32> = o.techniques.iter().map(|t| t.1).collect();
        // A layout needs one technique; AOV integrators never use it.
        let layout = if counts.is_empty() {
            Layout::new(&[1], 3)
        } else {
            Layout::new(&counts, 3)
        };
        // `direct` always keeps the per-pixel estimator (the paper's setting); `path`
        // applies heuristic weights per draw and keeps estimators only for optimal MIS.
        let combine = match (o.integrator, o.method.heuristic(&o.params)) {
            (IntegratorKind::Path, Some(h)) => Combine::Heuristic(h),
            _ => Combine::Estimator(Kernel::new(o.method, &layout, &o.params)?),
        };
        let depths = match (&combine, o.integrator) {
            (Combine::Estimator(_), IntegratorKind::Direct) => 1,
            (Combine::Estimator(_), IntegratorKind::Path) => o.max_depth.max(1) as usize,
            _ => 0,
        };
        let record = Record {
            aov: if o.aovs.is_empty() { 0 } else { 7 },
            depths,
            lights: if depths > 0 && o.per_light > 0 {
                o.per_light as usize
            } else {
                1
            },
            block: match &combine {
                Combine::Estimator(k) => k.block_len(),
                Combine::Heuristic(_) => 0,
            },
        };
        // Every later `record.stride()` is then free of overflow.
        record
            .blocks_checked()
            .and_then(|b| b.checked_mul(record.block))
            .and_then(|w| w.checked_add(Record::AOV + record.aov))
            .ok_or(OptionsError::RecordTooLarge {
                depths: record.depths,
                lights: record.lights,
            })?;
        let dims = Dims::new(&counts, o.max_depth)?;
        Ok(Self {
            kind: o.integrator,
            techniques,
            counts,
            layout,
            combine,
            record,
            dims,
            min_depth: o.min_depth,
            aovs: !o.aovs.is_empty(),
        })
    }

    /// The MIS kernel of the per-pixel estimators (None when heuristic weights go straight
    /// into the outside sum, or for AOV integrators).
    pub fn kernel(&self) -> Option<&Kernel> {
        match &self.combine {
            Combine::Estimator(k) if self.record.depths > 0 => Some(k),
            _ => None,
        }
    }
}
