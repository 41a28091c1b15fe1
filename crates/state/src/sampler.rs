//! Deterministic random numbers: value `dim` of sample `index` of pixel (x, y) is a pure
//! function of (seed, x, y, index, dim), independent of threads, tile order and control
//! flow (DESIGN.md §4), and computed with 32-bit integer operations only, so that a GPU
//! reproduces it bit for bit.
//!
//! The generator is Philox4x32-10 (Salmon et al. 2011, "Parallel random numbers: as easy as
//! 1, 2, 3"; Random123), a counter-based generator: the 64-bit seed is its key, the counter
//! is `(x, y, index, dim / 4)`, and each evaluation gives four 32-bit outputs, dimensions
//! `4⌊dim/4⌋ … +3`. It passes TestU01's BigCrush for any counter pattern. A 32-bit output u
//! maps to `u · 2⁻³²` ∈ [0, 1), exact in f64; the GPU's f32 form is `(u >> 8) · 2⁻²⁴`.
//!
//! Which dimension each draw of a sample uses is fixed in advance by the integrator's
//! dimension layout (`state::dims`: per depth, technique and draw), so a sample's
//! random numbers never depend on which branches it took (the pattern of pbrt-v4's
//! `wavefront/samples.cpp`, where they are generated before the kernels that use them).

use glam::DVec2;
use std::cell::Cell;

/// Philox4x32 multipliers and Weyl key increments (Salmon et al. 2011, Table 2).
const M0: u32 = 0xD251_1F53;
const M1: u32 = 0xCD9E_8D57;
const W0: u32 = 0x9E37_79B9;
const W1: u32 = 0xBB67_AE85;

/// The high and low 32 bits of a·b.
#[inline]
fn mulhilo(a: u32, b: u32) -> (u32, u32) {
    let p = u64::from(a) * u64::from(b);
    ((p >> 32) as u32, p as u32)
}

/// Philox4x32-10: ten rounds of the Philox S-box on counter `c` under key `k`.
#[inline]
pub fn philox4x32_10(c: [u32; 4], k: [u32; 2]) -> [u32; 4] {
    #[cfg(target_arch = "x86_64")]
    {
        philox_sse2(c, k)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        philox_scalar(c, k)
    }
}

/// [`philox4x32_10`] with the four words in one SSE2 register (part of every x86-64):
/// one `pmuludq` gives both products of a round, a shift and a shuffle place the words.
/// The same integer operations as [`philox_scalar`], so the same bits
/// (`sse2_philox_equals_the_scalar_one`), at about half the instructions.
#[cfg(target_arch = "x86_64")]
#[inline]
fn philox_sse2(c: [u32; 4], k: [u32; 2]) -> [u32; 4] {
    let [out] = philox_sse2_n([c], k);
    out
}

/// [`philox_sse2`] on `N` counters at once, their rounds interleaved: each round of one
/// counter waits on the last (a multiply, a shuffle and an exclusive or: about 5 cycles,
/// 50 for the ten), and the other counters' rounds fill those waits, so four cost little
/// more time than one (docs/notebook/2026-12-02-cpu-speed-round-11-time-profile.md).
#[cfg(target_arch = "x86_64")]
#[inline]
fn philox_sse2_n<const N: usize>(c: [[u32; 4]; N], k: [u32; 2]) -> [[u32; 4]; N] {
    use std::arch::x86_64::{
        __m128i, _mm_add_epi32, _mm_loadu_si128, _mm_mul_epu32, _mm_set_epi32, _mm_shuffle_epi32,
        _mm_srli_epi64, _mm_storeu_si128, _mm_xor_si128,
    };
    // SAFETY: SSE2 is part of the x86-64 baseline; the loads and stores are unaligned
    // ones of 16-byte arrays.
    unsafe {
        let mut x = c.map(|c| _mm_loadu_si128(c.as_ptr().cast::<__m128i>()));
        // Lanes 0 and 2 carry the multipliers and the key words (1 and 3 are unused).
        let m = _mm_set_epi32(0, M1 as i32, 0, M0 as i32);
        let w = _mm_set_epi32(0, W1 as i32, 0, W0 as i32);
        let mut key = _mm_set_epi32(0, k[1] as i32, 0, k[0] as i32);
        for round in 0..10 {
            if round > 0 {
                key = _mm_add_epi32(key, w);
            }
            for x in &mut x {
                // [lo0, hi0, lo1, hi1]: the products c0·M0 and c2·M1.
                let p = _mm_mul_epu32(*x, m);
                // [c1 ^ k0, 0, c3 ^ k1, 0].
                let odd = _mm_xor_si128(_mm_srli_epi64(*x, 32), key);
                // [hi1, lo1, hi0, lo0] ^ odd.
                *x = _mm_xor_si128(_mm_shuffle_epi32(p, 0b00_01_10_11), odd);
            }
        }
        x.map(|x| {
            let mut out = [0u32; 4];
            _mm_storeu_si128(out.as_mut_ptr().cast::<__m128i>(), x);
            out
        })
    }
}

/// [`philox4x32_10`] word by word.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline]
fn philox_scalar(mut c: [u32; 4], mut k: [u32; 2]) -> [u32; 4] {
    for round in 0..10 {
        if round > 0 {
            k = [k[0].wrapping_add(W0), k[1].wrapping_add(W1)];
        }
        let (hi0, lo0) = mulhilo(M0, c[0]);
        let (hi1, lo1) = mulhilo(M1, c[2]);
        c = [hi1 ^ c[1] ^ k[0], lo1, hi0 ^ c[3] ^ k[1], lo0];
    }
    c
}

/// A 32-bit output as a uniform f64 in [0, 1): `u · 2⁻³²`.
#[inline]
pub fn to_unit(bits: u32) -> f64 {
    f64::from(bits) * (1.0 / 4_294_967_296.0)
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
    pub fn stream(&self, x: u32, y: u32, index: u32) -> SampleStream {
        SampleStream {
            key: [self.seed as u32, (self.seed >> 32) as u32],
            counter: [x, y, index],
            first: Cell::new(NONE),
            bits: Default::default(),
        }
    }
}

/// Philox blocks of four dimensions that [`SampleStream`] evaluates at once and keeps: a
/// vertex's dimensions (`state::dims`: three per draw and one more, from a
/// multiple of 4) mostly lie within 16 consecutive ones, and four interleaved
/// evaluations take little more time than one ([`philox_sse2_n`]).
const CACHED_BLOCKS: u32 = 4;

/// [`SampleStream`]'s first cached block when none is: `block − NONE` (wrapping) is at
/// least 9 for every block (blocks are below 2³⁰), so no block reads as cached.
const NONE: u32 = u32::MAX - 8;

/// The random values of one sample, addressed by dimension. The last four Philox
/// blocks computed are kept (16 dimensions, evaluated together), so that reading a
/// vertex's dimensions in order costs about one evaluation per 16 dimensions.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SampleStream {
    key: [u32; 2],
    counter: [u32; 3],
    /// The first block kept ([`NONE`]: none yet).
    first: Cell<u32>,
    /// Dimensions `4·first …`, as 32-bit integers.
    bits: [Cell<u32>; 4 * CACHED_BLOCKS as usize],
}

impl SampleStream {
    /// The four values of dimensions `4·block … 4·block + 3` as 32-bit integers.
    #[inline]
    pub fn block_bits(&self, block: u32) -> [u32; 4] {
        let [x, y, i] = self.counter;
        philox4x32_10([x, y, i, block], self.key)
    }
    /// The value of dimension `dim` in [0, 1), whatever was drawn before. The cached
    /// blocks' path is inlined into the caller, the Philox evaluation is not: as one
    /// function, its call cost about 16 instructions of saved registers per value.
    #[inline(always)]
    pub fn get(&self, dim: u32) -> f64 {
        let block = dim / 4;
        if block.wrapping_sub(self.first.get()) >= CACHED_BLOCKS {
            self.refill(block);
        }
        let at = dim.wrapping_sub(4 * self.first.get()) as usize;
        to_unit(self.bits[at % self.bits.len()].get())
    }
    /// Evaluates and keeps blocks `block … block + CACHED_BLOCKS − 1` (no counter
    /// overflows: blocks are below 2³⁰).
    #[inline(never)]
    fn refill(&self, block: u32) {
        let [x, y, i] = self.counter;
        let counters: [[u32; 4]; CACHED_BLOCKS as usize] =
            std::array::from_fn(|j| [x, y, i, block + j as u32]);
        #[cfg(target_arch = "x86_64")]
        let blocks = philox_sse2_n(counters, self.key);
        #[cfg(not(target_arch = "x86_64"))]
        let blocks = counters.map(|c| philox_scalar(c, self.key));
        for (cells, words) in self.bits.chunks_exact(4).zip(blocks) {
            for (cell, w) in cells.iter().zip(words) {
                cell.set(w);
            }
        }
        self.first.set(block);
    }
    /// Dimensions `dim` and `dim + 1` as a point of [0, 1)².
    #[inline]
    pub fn get_2d(&self, dim: u32) -> DVec2 {
        DVec2::new(self.get(dim), self.get(dim + 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// splitmix64 (Steele et al. 2014) from `state`, as a source of test words.
    fn words(mut state: u64) -> impl FnMut() -> u32 {
        move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            (z ^ (z >> 31)) as u32
        }
    }

    /// The SSE2 rounds give the scalar rounds' words bit for bit, on 100 000 random
    /// counters and keys and on the extremes.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn sse2_philox_equals_the_scalar_one() {
        let mut word = words(4);
        let mut cases = vec![([0; 4], [0; 2]), ([u32::MAX; 4], [u32::MAX; 2])];
        for _ in 0..100_000 {
            cases.push(([word(), word(), word(), word()], [word(), word()]));
        }
        for (c, k) in cases {
            assert_eq!(philox_sse2(c, k), philox_scalar(c, k), "{c:x?} {k:x?}");
        }
    }

    /// `get` reads the value of its block's Philox evaluation whatever was read before:
    /// dimensions in order, backwards, repeated, far apart and up to the last block,
    /// through the cache of [`CACHED_BLOCKS`] interleaved evaluations.
    #[test]
    fn cached_blocks_give_each_dimension_its_value() {
        let mut word = words(11);
        let s = Sampler::new(0x1234_5678_9abc_def0);
        let expect = |t: &SampleStream, d: u32| to_unit(t.block_bits(d / 4)[(d % 4) as usize]);
        for round in 0..200 {
            let t = s.stream(word(), word(), round);
            let mut dims: Vec<u32> = (0..40).collect();
            dims.extend((0..40).rev());
            dims.extend([u32::MAX, u32::MAX - 5, 0, u32::MAX - 17, 3, 16, 15, 63, 64]);
            dims.extend((0..200).map(|_| word() % 96));
            dims.extend((0..50).map(|_| word()));
            for d in dims {
                assert_eq!(t.get(d), expect(&t, d), "dimension {d}");
            }
        }
    }

    /// Random123's known-answer vectors for Philox4x32-10 (its `kat_vectors`).
    #[test]
    fn philox_known_answers() {
        assert_eq!(
            philox4x32_10([0; 4], [0; 2]),
            [0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8]
        );
        assert_eq!(
            philox4x32_10([u32::MAX; 4], [u32::MAX; 2]),
            [0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd]
        );
        assert_eq!(
            philox4x32_10(
                [0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344],
                [0xa4093822, 0x299f31d0]
            ),
            [0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1]
        );
    }

    #[test]
    fn deterministic_and_order_independent() {
        let s = Sampler::new(7);
        let a = s.stream(3, 4, 10);
        let v: Vec<f64> = (0..8).map(|d| a.get(d)).collect();
        // Drawing other streams in between changes nothing.
        let _ = s.stream(9, 9, 9).get_2d(0);
        let b = s.stream(3, 4, 10);
        for (d, &x) in v.iter().enumerate() {
            assert_eq!(b.get(d as u32), x);
        }
        assert_ne!(Sampler::new(7 + (1 << 32)).stream(3, 4, 10).get(0), v[0]);
        assert_ne!(s.stream(4, 3, 10).get(0), v[0]);
        assert_ne!(Sampler::new(8).stream(3, 4, 10).get(0), v[0]);
    }
}
