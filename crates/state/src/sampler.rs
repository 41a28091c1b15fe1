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
        self.stream_keeping(x, y, index, cached_blocks())
    }

    /// [`Self::stream`] evaluating and keeping `blocks` Philox blocks at a time: 8 where
    /// the CPU has AVX2 and 8 is asked, else 4. The values are the same either way; for
    /// benchmarks and tests that compare the two (`cargo bench -p state --bench
    /// sample_stream`).
    pub fn stream_keeping(&self, x: u32, y: u32, index: u32, blocks: u32) -> SampleStream {
        let window = match blocks {
            MAX_CACHED_BLOCKS => cached_blocks(),
            _ => SSE2_CACHED_BLOCKS,
        };
        SampleStream {
            key: [self.seed as u32, (self.seed >> 32) as u32],
            counter: [x, y, index],
            first: Cell::new(NONE),
            window,
            bits: Default::default(),
        }
    }
}

/// Philox blocks a [`SampleStream`] evaluates at once and keeps on this CPU: eight in
/// one pass of AVX2 lanes where it has AVX2 (found at run time), else four interleaved
/// in SSE2 ([`philox_sse2_n`]). The eight take fewer instructions than the four (261
/// against 288 an evaluation) and less time (`cargo bench -p state --bench
/// sample_stream`), and hold a first vertex of up to six draws with the pixel's
/// dimensions (`state::dims`: 8 to 8 + 3·(D + 1)), where four blocks end at dimension
/// 15 and a third draw (16) needs a second evaluation
/// (docs/notebook/2026-12-07-philox-eight-blocks.md).
#[inline]
fn cached_blocks() -> u32 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        return MAX_CACHED_BLOCKS;
    }
    SSE2_CACHED_BLOCKS
}

impl Sampler {
    /// The streams of `samples` (pixel x, pixel y, sample index), in order, into `out`
    /// (cleared first), each with its first blocks (the camera ray and the first vertex
    /// of most renders) already evaluated: eight blocks in one pass of AVX2 lanes where
    /// the CPU has AVX2 (found at run time). Each stream equals [`Sampler::stream`]'s
    /// once that has read dimension 0.
    pub fn streams_into(&self, samples: &[(u32, u32, u32)], out: &mut Vec<SampleStream>) {
        out.clear();
        out.extend(samples.iter().map(|&(x, y, i)| self.stream(x, y, i)));
        for t in out.iter() {
            t.refill(0);
        }
    }
}

/// [`philox4x32_10`] of each of `counters` under `key` into `out` (of the same length):
/// eight counters per pass in AVX2 lanes where the CPU has AVX2 (found at run time),
/// else one at a time ([`philox4x32_10`]). Integer operations only, so every path gives
/// the same words (`philox_many_equals_one_by_one`).
pub fn philox_many(counters: &[[u32; 4]], key: [u32; 2], out: &mut [[u32; 4]]) {
    assert_eq!(counters.len(), out.len(), "one output per counter");
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        for (c, o) in counters.chunks_exact(8).zip(out.chunks_exact_mut(8)) {
            let soa: [[u32; 8]; 4] = std::array::from_fn(|w| std::array::from_fn(|j| c[j][w]));
            // SAFETY: AVX2 is present (checked above).
            let words = unsafe { philox_avx2_8(&soa, key) };
            for (j, o) in o.iter_mut().enumerate() {
                *o = [words[0][j], words[1][j], words[2][j], words[3][j]];
            }
            done += 8;
        }
    }
    for (c, o) in counters[done..].iter().zip(&mut out[done..]) {
        *o = philox4x32_10(*c, key);
    }
}

/// [`philox4x32_10`] of eight counters given word by word (`c[w][j]`: word w of counter
/// j), returned the same way: word w of all eight in one AVX2 register. A round is two
/// 32×32→64-bit multiplies per word pair (even and odd lanes), blends to split high and
/// low halves, and exclusive ors: about 18 instructions for the eight counters, where
/// [`philox_sse2`] takes about 7 per counter.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn philox_avx2_8(c: &[[u32; 8]; 4], k: [u32; 2]) -> [[u32; 8]; 4] {
    use std::arch::x86_64::{__m256i, _mm256_loadu_si256, _mm256_storeu_si256};
    // SAFETY: unaligned loads of 32-byte arrays.
    let c = c.map(|w| unsafe { _mm256_loadu_si256(w.as_ptr().cast::<__m256i>()) });
    let words = philox_avx2_lanes(c, k);
    let mut out = [[0u32; 8]; 4];
    for (w, v) in out.iter_mut().zip(words) {
        // SAFETY: an unaligned store into a 32-byte array.
        unsafe { _mm256_storeu_si256(w.as_mut_ptr().cast::<__m256i>(), v) };
    }
    out
}

/// [`philox_avx2_8`] on registers: word w of the eight counters in `c[w]`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn philox_avx2_lanes(
    c: [std::arch::x86_64::__m256i; 4],
    k: [u32; 2],
) -> [std::arch::x86_64::__m256i; 4] {
    use std::arch::x86_64::{
        _mm256_add_epi32, _mm256_blend_epi32, _mm256_mul_epu32, _mm256_set1_epi32,
        _mm256_slli_epi64, _mm256_srli_epi64, _mm256_xor_si256,
    };
    let [mut c0, mut c1, mut c2, mut c3] = c;
    let (m0, m1) = (_mm256_set1_epi32(M0 as i32), _mm256_set1_epi32(M1 as i32));
    let (w0, w1) = (_mm256_set1_epi32(W0 as i32), _mm256_set1_epi32(W1 as i32));
    let (mut k0, mut k1) = (
        _mm256_set1_epi32(k[0] as i32),
        _mm256_set1_epi32(k[1] as i32),
    );
    for round in 0..10 {
        if round > 0 {
            k0 = _mm256_add_epi32(k0, w0);
            k1 = _mm256_add_epi32(k1, w1);
        }
        // The 64-bit products of the even lanes, then of the odd lanes.
        let (e0, o0) = (
            _mm256_mul_epu32(c0, m0),
            _mm256_mul_epu32(_mm256_srli_epi64::<32>(c0), m0),
        );
        let (e1, o1) = (
            _mm256_mul_epu32(c2, m1),
            _mm256_mul_epu32(_mm256_srli_epi64::<32>(c2), m1),
        );
        // Their high and low halves, back in lane order.
        let hi0 = _mm256_blend_epi32::<0b1010_1010>(_mm256_srli_epi64::<32>(e0), o0);
        let lo0 = _mm256_blend_epi32::<0b1010_1010>(e0, _mm256_slli_epi64::<32>(o0));
        let hi1 = _mm256_blend_epi32::<0b1010_1010>(_mm256_srli_epi64::<32>(e1), o1);
        let lo1 = _mm256_blend_epi32::<0b1010_1010>(e1, _mm256_slli_epi64::<32>(o1));
        (c0, c1, c2, c3) = (
            _mm256_xor_si256(_mm256_xor_si256(hi1, c1), k0),
            lo1,
            _mm256_xor_si256(_mm256_xor_si256(hi0, c3), k1),
            lo0,
        );
    }
    [c0, c1, c2, c3]
}

/// Philox blocks of four dimensions that [`SampleStream`] evaluates at once and keeps
/// without AVX2: a vertex's dimensions (`state::dims`: three per draw and one more,
/// from a multiple of 4) mostly lie within 16 consecutive ones, and four interleaved
/// evaluations take little more time than one ([`philox_sse2_n`]).
const SSE2_CACHED_BLOCKS: u32 = 4;

/// The most blocks a [`SampleStream`] keeps ([`cached_blocks`]).
const MAX_CACHED_BLOCKS: u32 = 8;

/// [`SampleStream`]'s first cached block when none is: `block − NONE` (wrapping) is at
/// least 9 for every block (blocks are below 2³⁰), so no block reads as cached.
const NONE: u32 = u32::MAX - 8;

/// The random values of one sample, addressed by dimension. The last Philox blocks
/// computed are kept (32 dimensions, evaluated together in AVX2 lanes where the CPU has
/// AVX2, else 16 in SSE2), so that reading a vertex's dimensions in order costs about
/// one evaluation per vertex.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SampleStream {
    key: [u32; 2],
    counter: [u32; 3],
    /// The first block kept ([`NONE`]: none yet).
    first: Cell<u32>,
    /// Blocks evaluated at once and kept ([`cached_blocks`]).
    window: u32,
    /// Dimensions `4·first …`, as 32-bit integers.
    bits: [Cell<u32>; 4 * MAX_CACHED_BLOCKS as usize],
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
        if block.wrapping_sub(self.first.get()) >= self.window {
            self.refill(block);
        }
        let at = dim.wrapping_sub(4 * self.first.get()) as usize;
        to_unit(self.bits[at % self.bits.len()].get())
    }
    /// Evaluates and keeps blocks `block … block + window − 1` (no counter overflows:
    /// blocks are below 2³⁰).
    #[inline(never)]
    fn refill(&self, block: u32) {
        let [x, y, i] = self.counter;
        #[cfg(target_arch = "x86_64")]
        if self.window == MAX_CACHED_BLOCKS {
            // SAFETY: a window of eight is chosen only where the CPU has AVX2
            // (`cached_blocks`).
            unsafe { self.refill_avx2(block) };
            return;
        }
        let counters: [[u32; 4]; SSE2_CACHED_BLOCKS as usize] =
            std::array::from_fn(|j| [x, y, i, block + j as u32]);
        #[cfg(target_arch = "x86_64")]
        let blocks = philox_sse2_n(counters, self.key);
        #[cfg(not(target_arch = "x86_64"))]
        let blocks = counters.map(|c| philox_scalar(c, self.key));
        self.keep(block, |j, w| blocks[j][w]);
    }

    /// [`Self::refill`] of eight blocks in one pass of AVX2 lanes, lane j for block
    /// `block + j`: the words come out a register per word and are transposed in
    /// registers into the kept blocks' order, four stores of 32 bytes.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn refill_avx2(&self, block: u32) {
        use std::arch::x86_64::{
            __m256i, _mm256_add_epi32, _mm256_permute2x128_si256, _mm256_set1_epi32,
            _mm256_setr_epi32, _mm256_storeu_si256, _mm256_unpackhi_epi32, _mm256_unpackhi_epi64,
            _mm256_unpacklo_epi32, _mm256_unpacklo_epi64,
        };
        let [x, y, i] = self.counter.map(|v| _mm256_set1_epi32(v as i32));
        let blocks = _mm256_add_epi32(
            _mm256_set1_epi32(block as i32),
            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
        );
        let [w0, w1, w2, w3] = philox_avx2_lanes([x, y, i, blocks], self.key);
        // Per 128-bit half: [w0 w1 w0 w1] of lanes 0, 1 (and 4, 5), then of 2, 3 (6, 7).
        let (a, b) = (_mm256_unpacklo_epi32(w0, w1), _mm256_unpacklo_epi32(w2, w3));
        let (c, d) = (_mm256_unpackhi_epi32(w0, w1), _mm256_unpackhi_epi32(w2, w3));
        // Blocks 0 and 4, 1 and 5, 2 and 6, 3 and 7, each a half.
        let (b04, b15) = (_mm256_unpacklo_epi64(a, b), _mm256_unpackhi_epi64(a, b));
        let (b26, b37) = (_mm256_unpacklo_epi64(c, d), _mm256_unpackhi_epi64(c, d));
        let out = [
            _mm256_permute2x128_si256::<0x20>(b04, b15),
            _mm256_permute2x128_si256::<0x20>(b26, b37),
            _mm256_permute2x128_si256::<0x31>(b04, b15),
            _mm256_permute2x128_si256::<0x31>(b26, b37),
        ];
        // The cells are 32 contiguous u32 (`Cell` is `repr(transparent)`) and may be
        // written through a shared reference (`UnsafeCell`).
        let cells = self.bits.as_ptr().cast::<__m256i>().cast_mut();
        for (k, v) in out.into_iter().enumerate() {
            // SAFETY: an unaligned store of 32 bytes within the 128 of `bits`.
            unsafe { _mm256_storeu_si256(cells.add(k), v) };
        }
        self.first.set(block);
    }

    /// Keeps `word(j, w)`, word w of block `first + j`, for the window's blocks.
    #[inline(always)]
    fn keep(&self, first: u32, word: impl Fn(usize, usize) -> u32) {
        for (j, cells) in self
            .bits
            .chunks_exact(4)
            .take(self.window as usize)
            .enumerate()
        {
            for (w, cell) in cells.iter().enumerate() {
                cell.set(word(j, w));
            }
        }
        self.first.set(first);
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
    /// through the cache of [`cached_blocks`] blocks evaluated together.
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

    /// Streams that keep four blocks and streams that keep eight (AVX2, where the CPU
    /// has it) read the same value for every dimension, whatever was read before.
    #[test]
    fn windows_of_four_and_eight_blocks_read_the_same_values() {
        let mut word = words(21);
        let s = Sampler::new(0x0bad_cafe_f00d_d00d);
        let windows: &[u32] = match cached_blocks() {
            MAX_CACHED_BLOCKS => &[SSE2_CACHED_BLOCKS, MAX_CACHED_BLOCKS],
            _ => &[SSE2_CACHED_BLOCKS],
        };
        for round in 0..200 {
            let (x, y) = (word(), word());
            let t: Vec<SampleStream> = windows
                .iter()
                .map(|&w| s.stream_keeping(x, y, round, w))
                .collect();
            let mut dims: Vec<u32> = (0..70).collect();
            dims.extend((0..70).rev());
            dims.extend((0..300).map(|_| word() % 128));
            dims.extend([u32::MAX, u32::MAX - 31, 0, 31, 32, 33]);
            for d in dims {
                let want = to_unit(t[0].block_bits(d / 4)[(d % 4) as usize]);
                for t in &t {
                    assert_eq!(t.get(d), want, "dimension {d}, window {}", t.window);
                }
            }
        }
    }

    /// Many counters at once (AVX2 lanes where the CPU has them, single counters for
    /// the rest) give each counter's words bit for bit, for every count from 0 to 40
    /// (whole and partial passes), and [`Sampler::streams_into`]'s streams (odd and
    /// even counts) equal [`Sampler::stream`]'s after a read.
    #[test]
    fn philox_many_equals_one_by_one() {
        let mut word = words(8);
        for n in 0..=40 {
            let key = [word(), word()];
            let counters: Vec<[u32; 4]> =
                (0..n).map(|_| [word(), word(), word(), word()]).collect();
            let mut out = vec![[0; 4]; n];
            philox_many(&counters, key, &mut out);
            for (c, o) in counters.iter().zip(&out) {
                assert_eq!(*o, philox_scalar(*c, key), "{n} counters");
            }
        }
        let s = Sampler::new(0xfeed_beef_0123_4567);
        let mut streams = Vec::new();
        for n in [0, 1, 12, 13] {
            let samples: Vec<(u32, u32, u32)> = (0..n).map(|i| (word() % 640, i, word())).collect();
            s.streams_into(&samples, &mut streams);
            assert_eq!(streams.len(), samples.len());
            for (&(x, y, i), t) in samples.iter().zip(&streams) {
                let fresh = s.stream(x, y, i);
                assert_eq!(fresh.get(0), t.get(0));
                assert_eq!(&fresh, t);
                for d in 0..64 {
                    assert_eq!(s.stream(x, y, i).get(d), t.get(d), "dimension {d}");
                }
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
