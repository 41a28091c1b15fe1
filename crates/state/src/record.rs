//! Per-pixel accumulation into a flat record.
//!
//! A pixel's record is `[N | outside-MIS Σ (R, G, B) | AOV Σ (7, if any) | one
//! [`mis::Kernel`] block per vertex depth]` ([`Record`]): plain `f64` words, so that the
//! records of a whole image are one array ([`crate::RenderState`]) that merges, serialises
//! and uploads as data. [`Tally`] is what a render's options make of it, for either back
//! end: the layout, how draws combine, and the calls that add a sample.

use crate::color::Rgb;
use crate::tally::{Combine, Tally};

/// Where each sum lives in a pixel's record (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Record {
    /// AOV words (7: depth, normal, albedo; or 0).
    pub aov: usize,
    /// Vertex depths with MIS blocks.
    pub depths: usize,
    /// MIS blocks per depth: 1, or in per-light mode one per MIS light.
    pub lights: usize,
    /// Words of one MIS block.
    pub block: usize,
}

impl Record {
    /// Offset of the outside-MIS sums.
    pub const OUTSIDE: usize = 1;
    /// Offset of the AOV sums.
    pub const AOV: usize = 4;
    /// Words of one record.
    pub fn stride(&self) -> usize {
        Self::AOV + self.aov + self.blocks() * self.block
    }
    /// MIS blocks per record: depths × lights.
    pub fn blocks(&self) -> usize {
        self.depths * self.lights
    }
    /// [`Record::blocks`], `None` where it overflows.
    pub fn blocks_checked(&self) -> Option<usize> {
        self.depths.checked_mul(self.lights)
    }
    /// The range of block `i` (depth `i / lights`, light `i % lights`).
    pub fn block_range(&self, i: usize) -> std::ops::Range<usize> {
        let at = Self::AOV + self.aov + i * self.block;
        at..at + self.block
    }
    /// The range of the block of depth `d` and light `l` (0 when not per light).
    pub fn depth_light(&self, d: usize, l: usize) -> std::ops::Range<usize> {
        self.block_range(d * self.lights + l)
    }
}

/// One pixel's record while a sample runs: the view the integrators add into. `key` is
/// the sample's global index, which keys the uncorrelated estimator's sets. While
/// `mute` is set (a vertex below [`crate::RenderOptions::min_depth`]) nothing but AOVs
/// is added.
pub struct Pixel<'a> {
    /// The pixel's record.
    pub rec: &'a mut [f64],
    /// The sample's global index.
    pub key: u64,
    /// Whether the vertex being shaded adds nothing (but AOVs).
    pub mute: bool,
}

impl Pixel<'_> {
    /// Adds `c` outside MIS.
    #[inline]
    pub fn add(&mut self, c: Rgb) {
        if self.mute {
            return;
        }
        let s = &mut self.rec[Record::OUTSIDE..Record::OUTSIDE + 3];
        s[0] += c.x;
        s[1] += c.y;
        s[2] += c.z;
    }

    /// Adds one sample's AOV values (depth, normal, albedo) if the record keeps them.
    #[inline]
    pub fn add_aovs(&mut self, v: &[f64; 7]) {
        if let Some(s) = self.rec.get_mut(Record::AOV..Record::AOV + 7) {
            for (s, v) in s.iter_mut().zip(v) {
                *s += v;
            }
        }
    }

    /// Counts the finished sample.
    #[inline]
    pub fn end_sample(&mut self) {
        self.rec[0] += 1.0;
    }

    /// A draw of technique `k` at vertex `depth` with integrand `f` (throughput included)
    /// and every technique's pdf. `light` is the MIS light the draw's ray reaches
    /// (nearest along it, objects ignored): in per-light mode its block gets the draw
    /// and every other light's block a failed draw (the draw lies outside that light's
    /// domain); None (no light) fails in every block. Ignored otherwise.
    #[inline(always)]
    pub fn add_draw(
        &mut self,
        it: &Tally,
        depth: usize,
        k: usize,
        f: Rgb,
        pdfs: &[f64],
        light: Option<usize>,
    ) {
        if self.mute {
            return;
        }
        match &it.combine {
            Combine::Heuristic(h) => {
                // w_k f / (n_k p_k) (Veach 1997, eq. 9.4); a draw with own pdf 0 adds 0.
                let Some(s) = it.layout.is_valid(k, pdfs) else {
                    return;
                };
                let scale = match h {
                    mis::Heuristic::Balance => 1.0 / s,
                    h => h.scale(k, it.layout.counts(), pdfs),
                };
                if scale != 0.0 {
                    self.add(f * scale);
                }
            }
            Combine::Estimator(kernel) if it.record.lights == 1 => {
                self.add_estimated_one(it, kernel, depth, k, f, pdfs)
            }
            Combine::Estimator(kernel) => {
                self.add_estimated_per_light(it, kernel, depth, k, f, pdfs, light)
            }
        }
    }

    /// [`Pixel::add_draw`] for a draw whose value `f` is 0 (an estimator's, which counts
    /// it), with one block per vertex: the same sums bit for bit, inlined into a caller's
    /// short path ([`mis::Kernel::add_zero_valued`]).
    #[inline(always)]
    pub fn add_zero_valued(&mut self, it: &Tally, depth: usize, k: usize, f: Rgb, pdfs: &[f64]) {
        if self.mute {
            return;
        }
        match &it.combine {
            Combine::Estimator(kernel) if it.record.lights == 1 => {
                let r = it.record.depth_light(depth, 0);
                kernel.add_zero_valued(&mut self.rec[r], self.key, k, &f.to_array(), pdfs);
            }
            _ => self.add_draw(it, depth, k, f, pdfs, None),
        }
    }

    /// [`Pixel::add_zero_valued`] where `kernel` is `it`'s, one block per vertex and its
    /// [`mis::Kernel::zero_valued_size`] is `T`: the same sums bit for bit, without the
    /// dispatch.
    #[inline(always)]
    pub fn add_zero_valued_sized<const T: usize>(
        &mut self,
        it: &Tally,
        kernel: &mis::Kernel,
        depth: usize,
        k: usize,
        pdfs: &[f64; T],
    ) {
        debug_assert_eq!(it.record.lights, 1);
        if self.mute {
            return;
        }
        let r = it.record.depth_light(depth, 0);
        kernel.add_zero_valued_sized(&mut self.rec[r], k, pdfs);
    }

    /// [`Pixel::add_draw`] into a vertex's one estimator block: the sums in a call of
    /// their own, outside the heuristics' short path (which stays inlined in the caller's
    /// loop), and small enough to need few saved registers.
    #[inline(never)]
    fn add_estimated_one(
        &mut self,
        it: &Tally,
        kernel: &mis::Kernel,
        depth: usize,
        k: usize,
        f: Rgb,
        pdfs: &[f64],
    ) {
        let r = it.record.depth_light(depth, 0);
        kernel.add_sample(&mut self.rec[r], self.key, k, &f.to_array(), pdfs);
    }

    /// [`Pixel::add_draw`] in per-light mode: the draw into its light's block, a failed
    /// draw into every other.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn add_estimated_per_light(
        &mut self,
        it: &Tally,
        kernel: &mis::Kernel,
        depth: usize,
        k: usize,
        f: Rgb,
        pdfs: &[f64],
        light: Option<usize>,
    ) {
        for l in 0..it.record.lights {
            let r = it.record.depth_light(depth, l);
            if Some(l) == light {
                kernel.add_sample(&mut self.rec[r], self.key, k, &f.to_array(), pdfs);
            } else {
                kernel.add_failed(&mut self.rec[r], self.key, k);
            }
        }
    }

    /// Technique `k` produced no draw (or a delta-lobe draw) at vertex `depth`.
    #[inline(always)]
    pub fn add_failed(&mut self, it: &Tally, depth: usize, k: usize) {
        if self.mute {
            return;
        }
        if let Combine::Estimator(kernel) = &it.combine {
            // One addition for optimal-direct and -uncorrelated without per-light blocks
            // (most failed and unlit draws), with no block slicing and no call (the
            // optimal estimators count every unlit BSDF draw here).
            if let (1, Some((at, add))) = (it.record.lights, kernel.failed_word(k, self.key)) {
                self.rec[it.record.depth_light(depth, 0).start + at] += add;
                return;
            }
            self.add_failed_blocks(kernel, it, depth, k);
        }
    }

    /// [`Pixel::add_failed`] into every block of the vertex, out of the caller's loop.
    #[inline(never)]
    fn add_failed_blocks(&mut self, kernel: &mis::Kernel, it: &Tally, depth: usize, k: usize) {
        for l in 0..it.record.lights {
            let r = it.record.depth_light(depth, l);
            kernel.add_failed(&mut self.rec[r], self.key, k);
        }
    }

    /// Closes the iteration of vertex `depth`'s estimator.
    #[inline]
    pub fn end_vertex(&mut self, it: &Tally, depth: usize) {
        if self.mute {
            return;
        }
        if let Combine::Estimator(kernel) = &it.combine {
            for l in 0..it.record.lights {
                let r = it.record.depth_light(depth, l);
                kernel.end_iteration(&mut self.rec[r], self.key);
            }
        }
    }
}
