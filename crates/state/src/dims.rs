//! The fixed dimension layout of a sample: which random dimension every draw uses.
//!
//! A draw's dimensions depend only on (depth, technique, draw index), never on what the
//! sample did before, so the random numbers of every sample are fixed before any branch
//! (DESIGN.md §4; pbrt-v4 `wavefront/samples.cpp`) and a GPU kernel that handles one
//! depth of many samples computes exactly the CPU's values. Layout, with D = Σ n_k draws
//! per vertex:
//!
//! | dimensions | use |
//! |---|---|
//! | 0, 1 | position in the pixel |
//! | 2, 3, 4 | the albedo AOV's BSDF draw |
//! | 5, 6 | the point on a thin lens |
//! | 8 + d·S + 3j … +2 | draw slot j of vertex d: `(uc, u.x, u.y)`; slots 0…D−1 are the techniques' draws in list order, slot D the extra BSDF draw (delta lobes and the continuation when no BSDF technique is listed) |
//! | 8 + d·S + 3(D + 1) | Russian roulette after vertex d |
//! | 8 + M·S + 2d, +1 | free flight of the ray that reaches vertex d through media: the channel, the distance |
//!
//! with the stride `S = 3(D + 1) + 1` rounded up to a multiple of 4, so that each vertex
//! starts a new Philox block ([`crate::sampler`]), and M the maximum depth (at least 1).
//! The free-flight numbers come after every vertex's, so that scenes without media use
//! the same dimensions as before they existed.

use crate::options_error::OptionsError;
use crate::sampler::SampleStream;
use glam::DVec2;

/// Dimensions of the position in the pixel.
pub const PIXEL: u32 = 0;
/// First dimension of the albedo AOV's draw.
pub const ALBEDO: u32 = 2;
/// Dimensions of the point on a thin lens.
pub const LENS: u32 = 5;
/// First dimension of vertex 0.
const FIRST_VERTEX: u32 = 8;

/// The dimension layout of one integrator configuration (module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Dims {
    /// First draw slot of each technique.
    first_slot: Vec<u32>,
    /// Draws per vertex D.
    draws: u32,
    /// Dimensions per vertex S.
    stride: u32,
    /// First free-flight dimension.
    flight: u32,
}

/// The three numbers of one draw.
#[derive(Clone, Copy, Debug)]
pub struct Draw {
    /// Picks a lobe or a light.
    pub uc: f64,
    /// Picks a direction or a point.
    pub u: DVec2,
}

impl Dims {
    /// The layout for techniques drawn `counts[k]` times per vertex and paths of at most
    /// `max_depth` vertices; errors when the dimensions would not fit in 32 bits.
    pub fn new(counts: &[u32], max_depth: u32) -> Result<Dims, OptionsError> {
        let draws: u64 = counts.iter().map(|&n| u64::from(n)).sum();
        let stride = (3 * (draws + 1) + 1).div_ceil(4) * 4;
        let flight = u64::from(FIRST_VERTEX) + u64::from(max_depth.max(1)) * stride;
        let last = flight + 2 * u64::from(max_depth.max(1));
        if last > u64::from(u32::MAX) {
            return Err(OptionsError::TooManyDimensions {
                draws,
                max_depth,
                needed: last,
            });
        }
        let mut first_slot = Vec::with_capacity(counts.len());
        let mut at = 0;
        for &n in counts {
            first_slot.push(at);
            at += n;
        }
        Ok(Dims {
            first_slot,
            draws: draws as u32,
            stride: stride as u32,
            flight: flight as u32,
        })
    }

    fn base(&self, depth: usize) -> u32 {
        FIRST_VERTEX + depth as u32 * self.stride
    }

    fn slot(&self, rng: &SampleStream, depth: usize, slot: u32) -> Draw {
        let d = self.base(depth) + 3 * slot;
        Draw {
            uc: rng.get(d),
            u: rng.get_2d(d + 1),
        }
    }

    /// Draw `j` of technique `k` at vertex `depth`.
    pub fn technique(&self, rng: &SampleStream, depth: usize, k: usize, j: u32) -> Draw {
        self.slot(rng, depth, self.first_slot[k] + j)
    }

    /// The extra BSDF draw at vertex `depth`.
    pub fn extra(&self, rng: &SampleStream, depth: usize) -> Draw {
        self.slot(rng, depth, self.draws)
    }

    /// The free-flight numbers (channel, distance) of the ray that reaches vertex
    /// `depth` (0: the camera ray).
    pub fn flight(&self, rng: &SampleStream, depth: usize) -> (f64, f64) {
        let d = self.flight + 2 * depth as u32;
        (rng.get(d), rng.get(d + 1))
    }

    /// The roulette number after vertex `depth`.
    pub fn roulette(&self, rng: &SampleStream, depth: usize) -> f64 {
        rng.get(self.base(depth) + 3 * (self.draws + 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every draw of every vertex has dimensions of its own, and vertices start on a
    /// Philox block.
    #[test]
    fn dimensions_never_overlap() {
        let d = Dims::new(&[2, 1, 3], 4).unwrap();
        let mut used = std::collections::HashSet::new();
        for p in [PIXEL, PIXEL + 1, ALBEDO, ALBEDO + 1, ALBEDO + 2] {
            assert!(used.insert(p));
        }
        for depth in 0..4 {
            assert_eq!(d.base(depth) % 4, 0);
            for slot in 0..=d.draws {
                for k in 0..3 {
                    assert!(used.insert(d.base(depth) + 3 * slot + k), "{depth} {slot}");
                }
            }
            assert!(used.insert(d.base(depth) + 3 * (d.draws + 1)));
        }
        for depth in 0..4 {
            assert!(used.insert(d.flight + 2 * depth));
            assert!(used.insert(d.flight + 2 * depth + 1));
        }
        assert_eq!(d.first_slot, vec![0, 2, 3]);
        assert!(Dims::new(&[u32::MAX / 2], 1000).is_err());
    }
}
