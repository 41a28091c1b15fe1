//! Deterministic random numbers: one stream per (seed, pixel, sample index), one value
//! per dimension, independent of threads and tile order (DESIGN.md §4).
//!
//! A counter-based generator in the spirit of Random123 (Salmon et al. 2011) and PCG's
//! output permutations (O'Neill 2014): the stream key is a hash of (seed, pixel, index),
//! and value `d` of a stream is the SplitMix64 output (Steele et al. 2014) at position
//! `d` from that key. Any value can be computed in O(1) without the ones before it.

use glam::DVec2;

/// The SplitMix64 finaliser (Stafford's "Mix13"): a bijection on u64 with full avalanche.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The Weyl increment of SplitMix64 (2⁶⁴ / φ, odd).
const GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// A u64 as a uniform f64 in [0, 1) from its 53 high bits.
#[inline]
pub fn to_unit(bits: u64) -> f64 {
    (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// The source of every random number in a render: a seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sampler {
    /// The render's seed.
    pub seed: u64,
}

impl Sampler {
    /// A sampler with the given seed.
    pub fn new(seed: u64) -> Self {
        Self { seed }
    }

    /// The stream of sample `index` of pixel `(x, y)`.
    pub fn stream(&self, x: u32, y: u32, index: u64) -> SampleStream {
        let pixel = (u64::from(y) << 32) | u64::from(x);
        let mut k = mix64(self.seed.wrapping_add(GAMMA));
        k = mix64(k ^ pixel.wrapping_mul(0xd6e8_feb8_6659_fd93));
        k = mix64(k ^ index.wrapping_mul(0xa076_1d64_78bd_642f));
        SampleStream { key: k, dim: 0 }
    }
}

/// The random values of one sample, dimension by dimension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleStream {
    key: u64,
    dim: u64,
}

impl SampleStream {
    /// The value of dimension `dim` in [0, 1), whatever was drawn before.
    #[inline]
    pub fn get(&self, dim: u64) -> f64 {
        to_unit(mix64(
            self.key
                .wrapping_add(dim.wrapping_add(1).wrapping_mul(GAMMA)),
        ))
    }
    /// The next dimension's value in [0, 1).
    #[inline]
    pub fn next_1d(&mut self) -> f64 {
        let v = self.get(self.dim);
        self.dim += 1;
        v
    }
    /// The next two dimensions as a point of [0, 1)².
    #[inline]
    pub fn next_2d(&mut self) -> DVec2 {
        let x = self.next_1d();
        DVec2::new(x, self.next_1d())
    }
    /// The next dimension to be drawn.
    pub fn dimension(&self) -> u64 {
        self.dim
    }
    /// Moves to dimension `dim` (so that a fixed layout of dimensions can be kept).
    pub fn set_dimension(&mut self, dim: u64) {
        self.dim = dim;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::chi2_pvalue;

    /// Pearson chi-square of counts against equal expected counts.
    fn chi2_uniform(counts: &[u64]) -> (f64, usize) {
        let n: u64 = counts.iter().sum();
        let e = n as f64 / counts.len() as f64;
        let s = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
        (s, counts.len() - 1)
    }

    #[test]
    fn deterministic_and_order_independent() {
        let s = Sampler::new(7);
        let mut a = s.stream(3, 4, 10);
        let v: Vec<f64> = (0..8).map(|_| a.next_1d()).collect();
        // Drawing other streams in between changes nothing.
        let _ = s.stream(9, 9, 9).next_2d();
        let b = s.stream(3, 4, 10);
        for (d, &x) in v.iter().enumerate() {
            assert_eq!(b.get(d as u64), x);
        }
        assert_ne!(s.stream(4, 3, 10).get(0), v[0]);
        assert_ne!(Sampler::new(8).stream(3, 4, 10).get(0), v[0]);
    }

    /// 1-D uniformity of each of the first dimensions over many pixels and samples:
    /// chi-square over 100 bins, rejected at significance 1e-3 (per dimension).
    #[test]
    fn uniform_chi_square() {
        let s = Sampler::new(1234);
        for dim in 0..4 {
            let mut counts = vec![0u64; 100];
            for y in 0..64 {
                for x in 0..64 {
                    for i in 0..50 {
                        let u = s.stream(x, y, i).get(dim);
                        assert!((0.0..1.0).contains(&u));
                        counts[(u * 100.0) as usize] += 1;
                    }
                }
            }
            let (stat, dof) = chi2_uniform(&counts);
            let p = chi2_pvalue(stat, dof);
            assert!(p > 1e-3, "dim {dim}: chi2 {stat} dof {dof} p {p}");
        }
    }

    /// Independence: pairs (stream A, stream B) of neighbouring pixels, neighbouring
    /// sample indices and neighbouring dimensions fill [0,1)² uniformly (chi-square over
    /// 32 × 32 cells, significance 1e-3 each), and their correlation is below 4σ.
    #[test]
    fn streams_independent() {
        let s = Sampler::new(99);
        type Pair = fn(&Sampler, u32, u32, u64) -> (f64, f64);
        let pairs: [(&str, Pair); 4] = [
            ("pixel x", |s, x, y, i| {
                (s.stream(x, y, i).get(0), s.stream(x + 1, y, i).get(0))
            }),
            ("pixel y", |s, x, y, i| {
                (s.stream(x, y, i).get(0), s.stream(x, y + 1, i).get(0))
            }),
            ("index", |s, x, y, i| {
                (s.stream(x, y, i).get(0), s.stream(x, y, i + 1).get(0))
            }),
            ("dimension", |s, x, y, i| {
                let t = s.stream(x, y, i);
                (t.get(0), t.get(1))
            }),
        ];
        for (name, f) in pairs {
            let mut counts = vec![0u64; 32 * 32];
            let (mut sxy, mut n) = (0.0, 0.0);
            for y in 0..40 {
                for x in 0..40 {
                    for i in 0..64 {
                        let (a, b) = f(&s, x, y, i);
                        counts[(a * 32.0) as usize * 32 + (b * 32.0) as usize] += 1;
                        sxy += (a - 0.5) * (b - 0.5);
                        n += 1.0;
                    }
                }
            }
            let (stat, dof) = chi2_uniform(&counts);
            let p = chi2_pvalue(stat, dof);
            assert!(p > 1e-3, "{name}: chi2 {stat} dof {dof} p {p}");
            // Var((a−½)(b−½)) = 1/144 for independent uniforms.
            let corr = sxy / n * 12.0;
            assert!(corr.abs() < 4.0 / n.sqrt(), "{name}: correlation {corr}");
        }
    }
}
