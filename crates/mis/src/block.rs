//! Every estimator's state as one flat block of `f64` words, and the code that runs on it.
//!
//! A renderer keeps one estimator per pixel (and per path depth); as objects with their own
//! allocations these cost memory and cannot be copied to a GPU, written to a file or merged
//! across machines as plain data. A [`Kernel`] is the estimator's code for one method and
//! problem layout; its state is a `&mut [f64]` of [`Kernel::block_len`] words that the
//! caller stores anywhere, e.g. at a fixed stride in one array for a whole image. The
//! object estimators ([`crate::Direct`], …) are the same code over a block they own.
//!
//! Layouts (N: iterations, stored as an exact integer-valued f64; C channels, T techniques,
//! M = [`crate::Moments::len`]):
//!
//! | method | block |
//! |---|---|
//! | heuristics | `[N \| Σ (C)]` |
//! | optimal-direct | `[N \| Â, b̂ (M)]` |
//! | optimal-uncorrelated | `[N_A, N_B \| moments A (M) \| moments B (M)]` |
//! | optimal-progressive, -full | `[N \| Σ F_k (C) \| α (C·T) \| moments (M)]` |
//!
//! **Merging.** Blocks of the heuristics and of the direct and uncorrelated estimators are
//! sums: [`Kernel::merge`] adds them word by word, so two disjoint sample ranges merge into
//! the state of one run over their union (to the rounding of the summation order). The
//! uncorrelated estimator puts the iteration with global key k into set `k mod 2`, so its
//! sets, too, are those of the single run. The progressive estimators merge into an equally
//! valid estimate, not the single run's (see [`crate::progressive`]).
//!
//! ```
//! use mis::{Kernel, Layout, Method, Params};
//! let layout = Layout::new(&[1, 1], 1);
//! let k = Kernel::new(Method::OptimalDirect, &layout, &Params { ridge: Some(0.0), ..Params::default() }).unwrap();
//! // Two halves of a run in separate blocks, merged: the same as one block.
//! let (mut a, mut b, mut whole) = (vec![0.0; k.block_len()], vec![0.0; k.block_len()], vec![0.0; k.block_len()]);
//! for i in 0..8u64 {
//!     let x = (i as f64 + 0.5) / 8.0;
//!     let half = if i < 4 { &mut a } else { &mut b };
//!     for block in [half, &mut whole] {
//!         k.add_sample(block, i, 0, &[3.0 + 2.0 * x], &[1.0, 2.0 * x]);
//!         k.add_sample(block, i, 1, &[3.0 + 2.0 * x.sqrt()], &[1.0, 2.0 * x.sqrt()]);
//!         k.end_iteration(block, i);
//!     }
//! }
//! k.merge(&mut a, &b);
//! assert_eq!(k.iterations(&a), 8);
//! let (mut e, mut w) = ([0.0], [0.0]);
//! k.estimate(&a, &mut e);
//! k.estimate(&whole, &mut w);
//! assert!((e[0] - 4.0).abs() < 1e-12 && (w[0] - 4.0).abs() < 1e-12);
//! ```

use std::sync::Arc;

use crate::progressive::Schedule;
use crate::{direct, progressive, uncorrelated, weighted};
use crate::{Heuristic, Layout, Method, Moments, ParamError, Params};

/// Adds block `b` to block `a` word by word.
pub(crate) fn add(a: &mut [f64], b: &[f64]) {
    assert_eq!(a.len(), b.len(), "blocks of different sizes");
    for (x, y) in a.iter_mut().zip(b) {
        *x += y;
    }
}

/// What a kernel runs.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Code {
    Weighted(Heuristic),
    Direct,
    Uncorrelated,
    Progressive(Schedule),
}

/// One estimator method's code for one layout, over flat blocks (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Kernel {
    method: Method,
    layout: Arc<Layout>,
    params: Params,
    code: Code,
    len: usize,
    /// Per technique, where a failed sample adds and what: the index of `Â_tt` in the
    /// packed matrix and `1/n_t²` (`Moments::add_failed`, computed once: the optimal
    /// estimators count many failed and unlit draws).
    failed: Vec<(usize, f64)>,
}

impl Kernel {
    /// The kernel of `method` with `params` (checked) for `layout`.
    pub fn new(
        method: Method,
        layout: &Arc<Layout>,
        params: &Params,
    ) -> Result<Kernel, ParamError> {
        params.validate()?;
        // The ridge made explicit: `params()` and the blocks' solves use the same λ.
        let params = &params.resolved(method);
        let code = match method {
            Method::OptimalDirect => Code::Direct,
            Method::OptimalUncorrelated => Code::Uncorrelated,
            Method::OptimalProgressive | Method::OptimalFull => {
                Code::Progressive(method.schedule(params).expect("progressive methods"))
            }
            m => Code::Weighted(m.heuristic(params).expect("heuristic methods")),
        };
        let len = match code {
            Code::Weighted(_) => weighted::block_len(layout),
            Code::Direct => direct::block_len(layout),
            Code::Uncorrelated => uncorrelated::block_len(layout),
            Code::Progressive(_) => progressive::block_len(layout),
        };
        let failed = layout
            .counts()
            .iter()
            .enumerate()
            .map(|(t, &n)| (crate::linalg::packed_index(t, t), 1.0 / (n * n)))
            .collect();
        Ok(Kernel {
            method,
            layout: Arc::clone(layout),
            params: *params,
            code,
            len,
            failed,
        })
    }

    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The problem layout.
    pub fn layout(&self) -> &Arc<Layout> {
        &self.layout
    }

    /// The method's parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The ridge λ of the solves (made explicit by [`Kernel::new`]).
    fn ridge(&self) -> f64 {
        self.params.ridge_for(self.method)
    }

    /// Whether a sample whose integrand is 0 changes the estimate: not under a heuristic
    /// weighting (its term is w·0 and it adds nothing, Veach 1997, eq. 9.4), but under
    /// the optimal estimators, whose technique matrix `A_ik = ∫ p_i p_k / s` takes every
    /// sample's pdfs (Kondapaneni et al. 2019; RESEARCH.md). A caller may skip such
    /// samples where it is false.
    pub fn counts_zero_samples(&self) -> bool {
        !matches!(self.code, Code::Weighted(_))
    }

    /// Words of one block. A zero-filled block is an empty estimator.
    pub fn block_len(&self) -> usize {
        self.len
    }

    /// One sample of `technique` in the iteration with global key `key` (the sample
    /// index: it picks the uncorrelated estimator's set); see [`crate::Estimator::add_sample`].
    #[inline(always)]
    pub fn add_sample(
        &self,
        block: &mut [f64],
        key: u64,
        technique: usize,
        f: &[f64],
        pdfs: &[f64],
    ) {
        debug_assert_eq!(block.len(), self.len);
        let l = &*self.layout;
        match self.code {
            Code::Weighted(h) => weighted::add_sample(l, h, block, technique, f, pdfs),
            Code::Direct => {
                Moments::view_mut_sized(l, &mut block[1..]).add(l, technique, f, pdfs);
            }
            Code::Uncorrelated => {
                uncorrelated::set_mut(l, block, (key & 1) as usize).add(l, technique, f, pdfs);
            }
            Code::Progressive(_) => progressive::add_sample(l, block, technique, f, pdfs),
        }
    }

    /// [`Self::add_sample`] for a sample whose `f` is 0 in every channel: the same sums
    /// bit for bit, where the optimal estimators add to `Â` only
    /// ([`Moments::add_zero_valued`]).
    #[inline(always)]
    pub fn add_zero_valued(
        &self,
        block: &mut [f64],
        key: u64,
        technique: usize,
        f: &[f64],
        pdfs: &[f64],
    ) {
        debug_assert_eq!(block.len(), self.len);
        let l = &*self.layout;
        match self.code {
            Code::Direct => {
                Moments::view_mut_sized(l, &mut block[1..]).add_zero_valued(l, technique, f, pdfs);
            }
            Code::Uncorrelated => {
                uncorrelated::set_mut(l, block, (key & 1) as usize)
                    .add_zero_valued(l, technique, f, pdfs);
            }
            Code::Progressive(_) => progressive::add_zero_valued(l, block, technique, f, pdfs),
            _ => self.add_sample_out_of_line(block, key, technique, f, pdfs),
        }
    }

    /// The technique count `T` for which a zero-valued sample may take
    /// [`Self::add_zero_valued_sized`]: optimal-direct's, with 2 to 4 techniques (the
    /// sizes whose sums unroll); None for the other estimators and sizes.
    pub fn zero_valued_size(&self) -> Option<usize> {
        let t = self.layout.techniques();
        match self.code {
            Code::Direct if (2..=4).contains(&t) => Some(t),
            _ => None,
        }
    }

    /// [`Self::add_zero_valued`] where [`Self::zero_valued_size`] is `T`, with the pdfs
    /// in an array of that length: the same sums bit for bit, without the dispatch on
    /// the estimator and its size (a sixth of such a sample's cost in a short path).
    #[inline(always)]
    pub fn add_zero_valued_sized<const T: usize>(
        &self,
        block: &mut [f64],
        technique: usize,
        pdfs: &[f64; T],
    ) {
        debug_assert_eq!(self.zero_valued_size(), Some(T));
        crate::moments::add_zero_valued_sized(
            &mut block[1..],
            self.layout.counts(),
            technique,
            pdfs,
        );
    }

    /// [`Self::add_sample`] in a call of its own, for the short paths' rare cases.
    #[inline(never)]
    fn add_sample_out_of_line(
        &self,
        block: &mut [f64],
        key: u64,
        technique: usize,
        f: &[f64],
        pdfs: &[f64],
    ) {
        self.add_sample(block, key, technique, f, pdfs);
    }

    /// Where in a block a failed sample of `technique` in the iteration with key `key`
    /// adds, and what, for the estimators whose failed sample is one addition
    /// (optimal-direct: `Â_tt` after the count, `1/n_t²`; optimal-uncorrelated: the same
    /// in the key's set); None for the others. A caller's short path for
    /// [`Self::add_failed`], bit for bit.
    #[inline]
    pub fn failed_word(&self, technique: usize, key: u64) -> Option<(usize, f64)> {
        let (at, add) = self.failed[technique];
        match self.code {
            Code::Direct => Some((1 + at, add)),
            // `uncorrelated::set_mut`: after the two counts, set k at k sets' length.
            Code::Uncorrelated => {
                let set = (key & 1) as usize * Moments::len(&self.layout);
                Some((2 + set + at, add))
            }
            _ => None,
        }
    }

    /// `technique` produced no sample in the iteration with key `key`.
    #[inline]
    pub fn add_failed(&self, block: &mut [f64], key: u64, technique: usize) {
        let l = &*self.layout;
        match self.code {
            Code::Weighted(_) => {}
            // `Moments::add_failed` on the block's sums (after its count), bit for bit.
            Code::Direct => {
                let (at, add) = self.failed[technique];
                block[1 + at] += add;
            }
            Code::Uncorrelated => {
                uncorrelated::set_mut(l, block, (key & 1) as usize).add_failed(l, technique)
            }
            Code::Progressive(_) => progressive::add_failed(l, block, technique),
        }
    }

    /// Closes the iteration with key `key`.
    #[inline]
    pub fn end_iteration(&self, block: &mut [f64], key: u64) {
        match self.code {
            Code::Weighted(_) | Code::Direct => block[0] += 1.0,
            Code::Uncorrelated => block[(key & 1) as usize] += 1.0,
            Code::Progressive(s) => {
                progressive::end_iteration(&self.layout, self.ridge(), s, block)
            }
        }
    }

    /// The re-solve schedule of the progressive estimators (None for the others).
    pub fn schedule(&self) -> Option<Schedule> {
        match self.code {
            Code::Progressive(s) => Some(s),
            _ => None,
        }
    }

    /// Re-solves a progressive block's α from its moments and N, as
    /// [`Kernel::end_iteration`] does where the schedule says: for a back end that closes
    /// the iterations itself (adds Σα and counts N, GPU.md §8) and leaves the solves to
    /// this crate. The solve depends on the moments and N alone, so solving twice at the
    /// same N gives the same α. Does nothing for the other methods.
    pub fn resolve(&self, block: &mut [f64]) {
        if let Code::Progressive(_) = self.code {
            progressive::resolve_block(&self.layout, self.ridge(), block);
        }
    }

    /// Completed iterations N of a block.
    pub fn iterations(&self, block: &[f64]) -> u64 {
        match self.code {
            Code::Uncorrelated => (block[0] + block[1]) as u64,
            _ => block[0] as u64,
        }
    }

    /// The words of a block that count samples (the iterations; the uncorrelated
    /// estimator's two sets), for checking a block read from a file.
    pub fn count_words<'a>(&self, block: &'a [f64]) -> &'a [f64] {
        match self.code {
            Code::Uncorrelated => &block[..2],
            _ => &block[..1],
        }
    }

    /// The estimate of a block, one value per channel (0 before the first iteration).
    pub fn estimate(&self, block: &[f64], out: &mut [f64]) {
        let (l, ridge) = (&*self.layout, self.ridge());
        match self.code {
            Code::Weighted(_) => weighted::estimate(block, out),
            Code::Direct => direct::estimate(l, ridge, block, out),
            Code::Uncorrelated => uncorrelated::estimate(l, ridge, block, out),
            Code::Progressive(_) => progressive::estimate(l, block, out),
        }
    }

    /// The α̂ an optimal estimator applies to a block (one length-T column per channel,
    /// channel-major): the direct estimator's solve from the block's moments, the
    /// progressive ones' current α. None for the heuristics (their weights are per
    /// draw) and the uncorrelated estimator (each of its two sets has its own).
    pub fn alpha(&self, block: &[f64]) -> Option<Vec<f64>> {
        let l = &*self.layout;
        match self.code {
            Code::Direct => {
                let mut a = vec![0.0; l.techniques() * l.channels()];
                direct::alpha(l, self.ridge(), block, &mut a);
                Some(a)
            }
            Code::Progressive(_) => Some(progressive::alpha(l, block).to_vec()),
            Code::Weighted(_) | Code::Uncorrelated => None,
        }
    }

    /// Adds block `b` into block `a` (module docs).
    pub fn merge(&self, a: &mut [f64], b: &[f64]) {
        match self.code {
            Code::Progressive(s) => progressive::merge(&self.layout, self.ridge(), s, a, b),
            _ => add(a, b),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Estimator;

    /// Where `failed_word` gives one addition, it is `add_failed`'s bit for bit, for
    /// every method, key parity and technique; the others get None.
    #[test]
    fn failed_words_add_as_add_failed() {
        let layout = Layout::new(&[2, 1, 3], 3);
        for m in Method::ALL {
            let k = Kernel::new(m, &layout, &Params::default()).unwrap();
            for key in 0..4u64 {
                for t in 0..3 {
                    let start: Vec<f64> = (0..k.block_len()).map(|i| i as f64 * 0.25).collect();
                    let mut want = start.clone();
                    k.add_failed(&mut want, key, t);
                    match k.failed_word(t, key) {
                        Some((at, add)) => {
                            let mut got = start.clone();
                            got[at] += add;
                            let bits =
                                |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                            assert_eq!(bits(&got), bits(&want), "{m:?}, key {key}, t {t}");
                        }
                        None => assert!(
                            !matches!(k.code, Code::Direct | Code::Uncorrelated),
                            "{m:?}"
                        ),
                    }
                }
            }
        }
    }

    /// `add_zero_valued_sized` is `add_zero_valued` bit for bit where `zero_valued_size`
    /// allows it (optimal-direct, T = 2–4), failed samples (own pdf 0, ±0 pdfs)
    /// included; the other methods and sizes get None.
    #[test]
    fn sized_zero_valued_samples_add_as_add_zero_valued() {
        use rand::{Rng, SeedableRng};
        fn run<const T: usize>(k: &Kernel, rng: &mut rand_pcg::Pcg64) {
            let (mut short, mut general) = (vec![0.0; k.block_len()], vec![0.0; k.block_len()]);
            for i in 0..400 {
                let t = rng.gen_range(0..T);
                let mut pdfs: [f64; T] = std::array::from_fn(|_| rng.gen::<f64>() * 3.0);
                match i % 5 {
                    0 => pdfs[t] = 0.0,
                    1 => pdfs[(t + 1) % T] = -0.0,
                    _ => {}
                }
                k.add_zero_valued_sized(&mut short, t, &pdfs);
                k.add_zero_valued(&mut general, i, t, &[0.0; 3], &pdfs);
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&short), bits(&general), "T = {T}");
            assert!(short.iter().any(|&v| v > 0.0));
        }
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        for t in 1..=6u32 {
            let layout = Layout::new(&(1..=t).collect::<Vec<_>>(), 3);
            for m in Method::ALL {
                let k = Kernel::new(m, &layout, &Params::default()).unwrap();
                let size = k.zero_valued_size();
                let want = matches!(k.code, Code::Direct) && (2..=4).contains(&t);
                assert_eq!(size, want.then_some(t as usize), "{m:?}, T = {t}");
                match size {
                    Some(2) => run::<2>(&k, &mut rng),
                    Some(3) => run::<3>(&k, &mut rng),
                    Some(4) => run::<4>(&k, &mut rng),
                    _ => {}
                }
            }
        }
    }

    /// The kernel over a block and the object estimator run the same code: equal
    /// estimates bit for bit, for every method, on the same samples.
    #[test]
    fn kernel_matches_the_object_estimators() {
        let layout = Layout::new(&[2, 1, 1], 2);
        for m in Method::ALL {
            let params = Params::default();
            let k = Kernel::new(m, &layout, &params).unwrap();
            let mut obj = m.build(&layout, &params).unwrap();
            let mut block = vec![0.0; k.block_len()];
            let mut key = 0u64;
            for i in 0..20u64 {
                // Uncorrelated objects feed the set with fewer iterations: in one run
                // that is the parity of the iteration, as the kernel's key.
                key = i;
                for (t, reps) in [(0usize, 2), (1, 1), (2, 1)] {
                    for j in 0..reps {
                        let x = ((i * 7 + j * 3 + t as u64) % 11) as f64 / 11.0 + 0.03;
                        let pdfs = [1.0, 2.0 * x, 0.5 + x];
                        let f = [x * x + 0.1, 1.0 - x];
                        if (i + t as u64) % 7 == 3 {
                            obj.add_failed(t);
                            k.add_failed(&mut block, key, t);
                        } else {
                            obj.add_sample(t, &f, &pdfs);
                            k.add_sample(&mut block, key, t, &f, &pdfs);
                        }
                    }
                }
                obj.end_iteration();
                k.end_iteration(&mut block, key);
            }
            let _ = key;
            let mut e = [0.0; 2];
            k.estimate(&block, &mut e);
            assert_eq!(e.to_vec(), obj.estimate_vec(), "{m}");
            assert_eq!(k.iterations(&block), 20);
        }
    }

    /// `resolve` at a milestone gives the α that `end_iteration` solved there, bit for
    /// bit, and solving again changes nothing.
    #[test]
    fn resolve_repeats_the_milestone_solve() {
        let layout = Layout::new(&[1, 2], 1);
        let k = Kernel::new(Method::OptimalProgressive, &layout, &Params::default()).unwrap();
        assert!(k.schedule().unwrap().solves_at(4));
        let mut block = vec![0.0; k.block_len()];
        for i in 0..4u64 {
            let x = (i as f64 + 0.5) / 4.0;
            k.add_sample(&mut block, i, 0, &[1.0 + x], &[1.0, 2.0 * x]);
            for j in 0..2 {
                let y = (x + 0.3 * j as f64) % 1.0;
                k.add_sample(&mut block, i, 1, &[1.0 + y], &[1.0, 2.0 * y]);
            }
            k.end_iteration(&mut block, i);
        }
        let solved = block.clone();
        // α as it was, then re-solved.
        let t = &mut block[2..4];
        t.fill(0.0);
        k.resolve(&mut block);
        assert_eq!(block, solved);
        assert_ne!(&solved[2..4], &[0.0, 0.0]);
        k.resolve(&mut block);
        assert_eq!(block, solved);
        assert_eq!(
            Kernel::new(Method::OptimalDirect, &layout, &Params::default())
                .unwrap()
                .schedule(),
            None
        );
    }
}
