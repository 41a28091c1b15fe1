//! The additive sufficient statistics of optimal MIS: the technique matrix `Â` and the
//! contribution vectors `b̂` (one per channel), kept as plain sums over samples.
//!
//! For every sample X (Kondapaneni et al. 2019, eqs. 15–16):
//! `Â_ik += p_i(X) p_k(X) / s(X)²` and `b̂_ci += f_c(X) p_i(X) / s(X)²`, with
//! `s = Σ_k n_k p_k`. Divided by the iteration count N they estimate
//! `A_ik = ∫ p_i p_k / s` and `b_i = ∫ f p_i / s`. Sums rather than means, so that two
//! states merge by addition (threads, tiles, separate runs).
//!
//! **Storage.** `Moments<S>` is a view over any `f64` storage: `Moments` (the default,
//! `Vec<f64>`) owns its sums, `Moments<&mut [f64]>` and `Moments<&[f64]>` are views over
//! a slice of [`Moments::len`] words, so that a renderer can keep the sums of every pixel
//! and depth in one flat array (`[Â packed (T(T+1)/2) | b̂ (channels × T)]`).
//!
//! **Failed samples.** A technique t that produces no sample (or a sample with zero own
//! pdf) has lost probability mass `1 − m_t`. Treat the failure as a point `⊥_t` of an
//! extended domain where `p_t = 1 − m_t`, every other pdf is 0 and f = 0: every pdf then
//! integrates to 1 again, so `A·n = 1` and `Σα = F` hold. At that point `s = n_t(1 − m_t)`
//! and the sample adds exactly `1/n_t²` to `Â_tt` and nothing else — the unknown mass
//! cancels.

use crate::linalg::{packed_index, packed_len};
use crate::Layout;

/// Sums `Â` (packed symmetric) and `b̂` (channel-major), for one problem layout, over
/// storage `S` (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Moments<S = Vec<f64>> {
    t: usize,
    /// `[Â packed (T(T+1)/2) | b̂ (channels × T)]`.
    data: S,
}

impl Moments {
    /// Zero sums for a layout.
    pub fn new(layout: &Layout) -> Moments {
        Moments {
            t: layout.techniques(),
            data: vec![0.0; Moments::<()>::len(layout)],
        }
    }
}

impl Moments<()> {
    /// Words of storage the sums of `layout` take: `T(T+1)/2 + channels·T`.
    pub fn len(layout: &Layout) -> usize {
        let t = layout.techniques();
        packed_len(t) + layout.channels() * t
    }
}

impl<'a> Moments<&'a [f64]> {
    /// A read-only view over `data` (exactly [`Moments::len`] words).
    pub fn view(layout: &Layout, data: &'a [f64]) -> Self {
        assert_eq!(data.len(), Moments::len(layout), "moments storage size");
        Moments {
            t: layout.techniques(),
            data,
        }
    }
}

impl<'a> Moments<&'a mut [f64]> {
    /// A mutable view over `data` (exactly [`Moments::len`] words).
    pub fn view_mut(layout: &Layout, data: &'a mut [f64]) -> Self {
        assert_eq!(data.len(), Moments::len(layout), "moments storage size");
        Self::view_mut_sized(layout, data)
    }

    /// [`Self::view_mut`] for a caller that has checked the size (a kernel's block of
    /// its own length): the per-sample path, where the check cost a few percent of
    /// optimal-direct's overhead. Indexing stays bounds-checked.
    #[inline(always)]
    pub(crate) fn view_mut_sized(layout: &Layout, data: &'a mut [f64]) -> Self {
        debug_assert_eq!(data.len(), Moments::len(layout), "moments storage size");
        Moments {
            t: layout.techniques(),
            data,
        }
    }
}

impl<S: AsRef<[f64]> + AsMut<[f64]>> Moments<S> {
    /// Adds one sample of technique `t`; returns its mixture density `s`, or `None` when the
    /// sample is counted as failed (own pdf zero, or `s` not finite). O(T²/2 + C·T).
    #[inline(always)]
    pub fn add(&mut self, layout: &Layout, t: usize, f: &[f64], pdfs: &[f64]) -> Option<f64> {
        debug_assert_eq!(f.len(), layout.channels(), "one f value per channel");
        debug_assert!(pdfs.iter().all(|&p| p >= 0.0), "pdfs must be non-negative");
        let (data, n) = (self.data.as_mut(), layout.counts());
        // The common sizes with constant bounds, so that the loops unroll: this is most of
        // the optimal estimators' cost per sample (+12 % over balance with the loops
        // general, bench/overhead). The same operations in the same order: bit for bit.
        let s = match (self.t, f.len()) {
            (2, 3) => add_sums(data, n, 2, 3, t, f, pdfs),
            (3, 3) => add_sums(data, n, 3, 3, t, f, pdfs),
            (4, 3) => add_sums(data, n, 4, 3, t, f, pdfs),
            (tt, c) => add_sums_any(data, n, tt, c, t, f, pdfs),
        };
        if s.is_none() {
            self.add_failed(layout, t);
        }
        s
    }

    /// [`Self::add`] for a sample whose `f` is 0 in every channel (an occluded or unlit
    /// draw, which the optimal estimators count where the heuristics skip it): `Â` only,
    /// since `b̂` would gain nothing. The same sums bit for bit.
    #[inline(always)]
    pub fn add_zero_valued(
        &mut self,
        layout: &Layout,
        t: usize,
        f: &[f64],
        pdfs: &[f64],
    ) -> Option<f64> {
        debug_assert!(f.iter().all(|&x| x == 0.0), "f must be 0");
        let (data, n) = (self.data.as_mut(), layout.counts());
        // The sizes `Self::add` unrolls, without channels.
        let s = match (self.t, f.len()) {
            (2, 3) => add_sums(data, n, 2, 0, t, &[], pdfs),
            (3, 3) => add_sums(data, n, 3, 0, t, &[], pdfs),
            (4, 3) => add_sums(data, n, 4, 0, t, &[], pdfs),
            _ => return self.add(layout, t, f, pdfs),
        };
        if s.is_none() {
            self.add_failed(layout, t);
        }
        s
    }

    /// Counts a failed sample of technique `t`: `Â_tt += 1/n_t²` (see the module docs).
    #[inline]
    pub fn add_failed(&mut self, layout: &Layout, t: usize) {
        add_failed_sums(self.data.as_mut(), layout.counts(), t);
    }

    /// Adds another state's sums.
    pub fn merge<O: AsRef<[f64]>>(&mut self, other: &Moments<O>) {
        let (a, b) = (self.data.as_mut(), other.data.as_ref());
        assert_eq!(a.len(), b.len(), "moments of different sizes");
        for (a, b) in a.iter_mut().zip(b) {
            *a += b;
        }
    }
}

impl<S: AsRef<[f64]>> Moments<S> {
    /// `Â`, packed symmetric (see [`crate::linalg::packed_index`]).
    #[inline]
    pub fn matrix(&self) -> &[f64] {
        &self.data.as_ref()[..packed_len(self.t)]
    }

    /// `b̂`, one length-T column per channel.
    #[inline]
    pub fn vectors(&self) -> &[f64] {
        &self.data.as_ref()[packed_len(self.t)..]
    }

    /// `Â n` (length T): its mean over iterations estimates `A n = 1`.
    pub fn matrix_times_counts(&self, layout: &Layout) -> Vec<f64> {
        let mut out = vec![0.0; self.t];
        self.matrix_times_counts_into(layout, &mut out);
        out
    }

    /// [`Moments::matrix_times_counts`] into `out` (length T), without allocating.
    pub fn matrix_times_counts_into(&self, layout: &Layout, out: &mut [f64]) {
        matrix_times_counts_sized(self.matrix(), layout.counts(), self.t, out);
    }

    /// The full-form estimate `Σα + n·(b̂ − Âα)/N` per channel (Kondapaneni et al. 2019,
    /// eq. 13 with the sums of this state), for α from anywhere; α = 0 gives the balance
    /// heuristic `Σ f/s / N`. `an` = [`Moments::matrix_times_counts`].
    pub fn full_form(
        &self,
        layout: &Layout,
        an: &[f64],
        alpha: &[f64],
        iterations: f64,
        out: &mut [f64],
    ) {
        let n = layout.counts();
        full_form_sized(self.vectors(), n, an, alpha, iterations, self.t, out);
    }
}

/// [`Moments::matrix_times_counts_into`] over packed `a`, inlined where `t` is a constant.
#[inline(always)]
pub(crate) fn matrix_times_counts_sized(a: &[f64], n: &[f64], t: usize, out: &mut [f64]) {
    let (a, n) = (&a[..packed_len(t)], &n[..t]);
    for (i, o) in out[..t].iter_mut().enumerate() {
        *o = (0..t).map(|k| a[packed_index(i, k)] * n[k]).sum();
    }
}

/// [`Moments::full_form`] over `b̂` = `vectors`, inlined where `t` is a constant.
#[inline(always)]
pub(crate) fn full_form_sized(
    vectors: &[f64],
    n: &[f64],
    an: &[f64],
    alpha: &[f64],
    iterations: f64,
    t: usize,
    out: &mut [f64],
) {
    let (n, an) = (&n[..t], &an[..t]);
    for ((o, b), al) in out
        .iter_mut()
        .zip(vectors.chunks_exact(t))
        .zip(alpha.chunks_exact(t))
    {
        let nb: f64 = n.iter().zip(b).map(|(x, y)| x * y).sum();
        let an_alpha: f64 = an.iter().zip(al).map(|(x, y)| x * y).sum();
        let sum: f64 = al.iter().sum();
        *o = sum + (nb - an_alpha) / iterations;
    }
}

/// [`add_sums`] for any size, out of line (inlined, its general loops slowed the caller),
/// over the techniques whose pdf is not 0 only: with one technique per light a direction
/// has density under the few lights it crosses, and the dense loops spent most of
/// optimal-direct's cost adding zero products (+31 % over balance at T = 11,
/// bench/overhead). Only additions of +0 are skipped: the same sums bit for bit (where
/// 1/s² is finite).
#[inline(never)]
fn add_sums_any(
    data: &mut [f64],
    counts: &[f64],
    tt: usize,
    c: usize,
    t: usize,
    f: &[f64],
    pdfs: &[f64],
) -> Option<f64> {
    const MAX: usize = 64;
    if tt > MAX {
        return add_sums(data, counts, tt, c, t, f, pdfs);
    }
    let (counts, pdfs, f) = (&counts[..tt], &pdfs[..tt], &f[..c]);
    // The techniques with density, as bits and then as a list in increasing order,
    // with `Layout::is_valid`'s sum as in `add_sums`, less its +0 terms.
    let mut mask = nonzero_bits(pdfs);
    let mut nonzero = [0u8; MAX];
    let (mut m, mut s) = (0, -0.0);
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        nonzero[m] = i as u8;
        s += counts[i] * pdfs[i];
        mask &= mask - 1;
        m += 1;
    }
    let nonzero = &nonzero[..m];
    if !(pdfs[t] > 0.0 && s.is_finite()) {
        return None;
    }
    let inv2 = 1.0 / (s * s);
    let (a, b) = data[..packed_len(tt) + c * tt].split_at_mut(packed_len(tt));
    for (x, &i) in nonzero.iter().enumerate() {
        let i = usize::from(i);
        let (qi, row) = (pdfs[i] * inv2, packed_index(i, 0));
        for &j in &nonzero[..=x] {
            a[row + usize::from(j)] += qi * pdfs[usize::from(j)];
        }
    }
    // Column by column without `chunks_exact_mut`, whose count divides by `tt`.
    for (ch, &fc) in f.iter().enumerate() {
        if fc != 0.0 {
            let (fq, bc) = (fc * inv2, &mut b[ch * tt..][..tt]);
            for &i in nonzero {
                bc[usize::from(i)] += fq * pdfs[usize::from(i)];
            }
        }
    }
    Some(s)
}

/// Bit i set where `pdfs[i] != 0` (NaN included), for at most 64 pdfs: two per SSE2
/// comparison on x86-64, where the compiler's own form of the loop shifted each bit
/// into place with vector shifts (about 100 instructions for 11 pdfs).
#[inline(always)]
pub(crate) fn nonzero_bits(pdfs: &[f64]) -> u64 {
    debug_assert!(pdfs.len() <= 64);
    let mut mask = 0u64;
    let mut pairs = pdfs.chunks_exact(2);
    let mut i = 0;
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cmpneq_pd, _mm_movemask_pd, _mm_set_pd, _mm_setzero_pd};
        for p in &mut pairs {
            // cmpneqpd is true for unordered operands, as `!=` is for NaN.
            // SAFETY: SSE2 is part of the x86-64 baseline.
            let bits =
                unsafe { _mm_movemask_pd(_mm_cmpneq_pd(_mm_set_pd(p[1], p[0]), _mm_setzero_pd())) };
            mask |= (bits as u64) << i;
            i += 2;
        }
    }
    // The pairs left (all of them off x86-64), then the odd one.
    let rest = pairs.remainder();
    for p in pairs.flatten().chain(rest) {
        mask |= u64::from(*p != 0.0) << i;
        i += 1;
    }
    mask
}

/// [`Moments::add_zero_valued`] over `data` = `[Â packed | b̂]` for `T` techniques, a
/// failed sample's `1/n_t²` ([`Moments::add_failed`]) included: the same sums bit for bit.
#[inline(always)]
pub(crate) fn add_zero_valued_sized<const T: usize>(
    data: &mut [f64],
    counts: &[f64],
    t: usize,
    pdfs: &[f64; T],
) {
    if add_sums(data, counts, T, 0, t, &[], pdfs).is_none() {
        add_failed_sums(data, counts, t);
    }
}

/// [`Moments::add_failed`] over `data` = `[Â packed | b̂]`: `Â_tt += 1/n_t²`.
#[inline(always)]
fn add_failed_sums(data: &mut [f64], counts: &[f64], t: usize) {
    let n = counts[t];
    data[packed_index(t, t)] += 1.0 / (n * n);
}

/// [`Moments::add`] over `data` = `[Â packed | b̂]` for `tt` techniques and `c` channels;
/// None (nothing added) for a failed sample. Inlined where `tt` and `c` are constants.
#[inline(always)]
fn add_sums(
    data: &mut [f64],
    counts: &[f64],
    tt: usize,
    c: usize,
    t: usize,
    f: &[f64],
    pdfs: &[f64],
) -> Option<f64> {
    let (counts, pdfs, f) = (&counts[..tt], &pdfs[..tt], &f[..c]);
    // `Layout::is_valid`, over the constant-length slices.
    let s: f64 = counts.iter().zip(pdfs).map(|(n, p)| n * p).sum();
    if !(pdfs[t] > 0.0 && s.is_finite()) {
        return None;
    }
    let inv2 = 1.0 / (s * s);
    let (a, b) = data[..packed_len(tt) + c * tt].split_at_mut(packed_len(tt));
    let mut idx = 0;
    for (i, &pi) in pdfs.iter().enumerate() {
        let qi = pi * inv2;
        for (aij, &pj) in a[idx..=idx + i].iter_mut().zip(pdfs) {
            *aij += qi * pj;
        }
        idx += i + 1;
    }
    for (&fc, bc) in f.iter().zip(b.chunks_exact_mut(tt)) {
        // Occluded and missed samples (f = 0) are common: they add nothing to b̂.
        if fc != 0.0 {
            let fq = fc * inv2;
            for (bi, &pi) in bc.iter_mut().zip(pdfs) {
                *bi += fq * pi;
            }
        }
    }
    Some(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use std::hint::black_box;

    /// `add_zero_valued` gives the sums `add` gives for f = 0, bit for bit, over the sizes
    /// it unrolls and the others, failed samples included; and it adds nothing to `b̂`.
    #[test]
    fn zero_valued_samples_add_as_add_does() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(8);
        for t in 1..=6 {
            for channels in [1, 3] {
                let layout = Layout::new(&(1..=t as u32).collect::<Vec<_>>(), channels);
                let (mut short, mut full) = (Moments::new(&layout), Moments::new(&layout));
                let zero = vec![0.0; channels];
                for i in 0..300 {
                    let k = rng.gen_range(0..t);
                    let mut pdfs: Vec<f64> = (0..t).map(|_| rng.gen::<f64>() * 3.0).collect();
                    if i % 7 == 0 {
                        pdfs[k] = 0.0;
                    }
                    let a = short.add_zero_valued(&layout, k, &zero, &pdfs);
                    let b = full.add(&layout, k, &zero, &pdfs);
                    assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
                }
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&short.data), bits(&full.data), "T = {t}, {channels}");
                assert!(short.matrix().iter().any(|&x| x > 0.0));
                assert!(short.vectors().iter().all(|&x| x.to_bits() == 0));
            }
        }
    }

    /// `nonzero_bits` sets the bits of the pdfs `!=` 0, NaN included and -0 not, at
    /// every length up to 64 (odd lengths leave one for the scalar loop).
    #[test]
    fn nonzero_bits_mark_the_pdfs_with_density() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let values = [
            0.0,
            -0.0,
            1.0,
            -2.5,
            f64::NAN,
            f64::INFINITY,
            f64::MIN_POSITIVE,
        ];
        for len in 0..=64 {
            for _ in 0..50 {
                let pdfs: Vec<f64> = (0..len)
                    .map(|_| values[rng.gen_range(0..values.len())])
                    .collect();
                let want = pdfs
                    .iter()
                    .enumerate()
                    .fold(0u64, |m, (i, &p)| m | (u64::from(p != 0.0) << i));
                assert_eq!(nonzero_bits(&pdfs), want, "{pdfs:?}");
            }
        }
    }

    /// The sizes `Moments::add` unrolls (T = 2, 3, 4 with RGB) and the sparse loops of
    /// the other sizes give bit for bit the sums of the dense general loops, failed
    /// samples, zero pdfs (of either sign) and zero-valued draws included, up to and past
    /// the sparse loops' 64 techniques.
    #[test]
    fn unrolled_sizes_equal_the_general_loops() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        for t in (1..=6).chain([11, 63, 64, 65, 70]) {
            for channels in [1, 3] {
                let layout = Layout::new(&(1..=t as u32).collect::<Vec<_>>(), channels);
                let mut fast = Moments::new(&layout);
                let mut general = vec![0.0; Moments::len(&layout)];
                for i in 0..500 {
                    let k = rng.gen_range(0..t);
                    let mut pdfs: Vec<f64> = (0..t).map(|_| rng.gen::<f64>() * 3.0).collect();
                    if i % 7 == 0 {
                        pdfs[k] = 0.0; // a failed sample
                    }
                    if i % 5 == 0 {
                        pdfs.iter_mut()
                            .filter(|_| rng.gen::<bool>())
                            .for_each(|p| *p = 0.0);
                    }
                    if i % 11 == 0 {
                        pdfs[rng.gen_range(0..t)] = -0.0;
                    }
                    let f: Vec<f64> = (0..channels)
                        .map(|_| {
                            if i % 3 == 0 {
                                0.0
                            } else {
                                rng.gen::<f64>() - 0.3
                            }
                        })
                        .collect();
                    let a = fast.add(&layout, k, &f, &pdfs);
                    let (tt, c) = (black_box(t), black_box(channels));
                    let b = add_sums(&mut general, layout.counts(), tt, c, k, &f, &pdfs);
                    if b.is_none() {
                        Moments::view_mut(&layout, &mut general).add_failed(&layout, k);
                    }
                    assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
                }
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(
                    bits(&fast.data),
                    bits(&general),
                    "T = {t}, {channels} channels"
                );
            }
        }
    }
}
