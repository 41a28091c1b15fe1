//! A fixed-capacity list on the stack whose unused slots are never written: the one place
//! that holds the crate's hand-written `unsafe` for its per-ray stacks, queues and
//! active sets. Zeroing a few KiB of placeholders per ray cost more than a small walk or
//! a one-perturbation scan (docs/notebook/2026-11-21-perturbed-quadrics-scaling.md), so
//! the slots are `MaybeUninit`, and every method keeps one invariant:
//!
//! **the first `len` slots are written; no other slot is ever read.**
//!
//! Each `unsafe` block below reads only slots below `len`, and every method that raises
//! `len` writes the slots it adds first. The tests check each method against a `Vec`
//! doing the same, on random operations.

use std::mem::MaybeUninit;

/// Up to `N` values of `T` in order, on the stack (see the module docs).
pub struct Fixed<T: Copy, const N: usize> {
    items: [MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Default for Fixed<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Copy, const N: usize> Fixed<T, N> {
    /// An empty list (no slot written).
    #[inline(always)]
    pub const fn new() -> Self {
        Self {
            items: [const { MaybeUninit::uninit() }; N],
            len: 0,
        }
    }

    /// The values held.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether it holds nothing.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether it holds `N` values.
    #[inline(always)]
    pub fn is_full(&self) -> bool {
        self.len == N
    }

    /// Forgets every value (nothing is written).
    #[inline(always)]
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Appends `v`; false (and nothing written) when full.
    #[inline(always)]
    pub fn push(&mut self, v: T) -> bool {
        if self.len == N {
            return false;
        }
        self.items[self.len] = MaybeUninit::new(v);
        self.len += 1;
        true
    }

    /// Appends `v`, for a caller whose bound on the count makes a full list a bug.
    ///
    /// # Panics
    /// When full.
    #[inline(always)]
    pub fn push_within(&mut self, v: T) {
        assert!(self.len < N, "a fixed list of {N} overflowed");
        self.items[self.len] = MaybeUninit::new(v);
        self.len += 1;
    }

    /// Takes the last value.
    #[inline(always)]
    pub fn pop(&mut self) -> Option<T> {
        self.len = self.len.checked_sub(1)?;
        // SAFETY: the slot at the old `len − 1` is below the old `len`: written.
        Some(unsafe { self.items[self.len].assume_init() })
    }

    /// The value at `k`.
    ///
    /// # Panics
    /// When `k ≥ len` (in every build: an unwritten slot is never read).
    #[inline(always)]
    pub fn at(&self, k: usize) -> T {
        assert!(k < self.len, "index {k} of a fixed list of {}", self.len);
        // SAFETY: k < len: written.
        unsafe { self.items[k].assume_init() }
    }

    /// The last value.
    #[inline(always)]
    pub fn last(&self) -> Option<T> {
        self.len.checked_sub(1).map(|k| self.at(k))
    }

    /// The values, in order.
    #[inline(always)]
    pub fn as_slice(&self) -> &[T] {
        // SAFETY: the first `len` slots are written, and MaybeUninit<T> has T's layout.
        unsafe { std::slice::from_raw_parts(self.items.as_ptr().cast::<T>(), self.len) }
    }

    /// The values, in order, to change in place.
    #[inline(always)]
    pub fn as_mut_slice(&mut self) -> &mut [T] {
        // SAFETY: as in `as_slice`; the slice ends at `len`.
        unsafe { std::slice::from_raw_parts_mut(self.items.as_mut_ptr().cast::<T>(), self.len) }
    }

    /// Keeps the values for which `keep` holds, in their order.
    #[inline]
    pub fn retain(&mut self, mut keep: impl FnMut(&T) -> bool) {
        let mut k = 0;
        for j in 0..self.len {
            let v = self.at(j);
            if keep(&v) {
                // k ≤ j < len: overwriting a written slot.
                self.items[k] = MaybeUninit::new(v);
                k += 1;
            }
        }
        self.len = k;
    }

    /// Inserts `v` before the run of values at the end (above index `floor`) for which
    /// `after(value)` holds, moving them up one slot: an insertion sort's step from the
    /// back. False (and nothing moved) when full.
    #[inline(always)]
    pub fn insert_from_back(
        &mut self,
        v: T,
        floor: usize,
        mut after: impl FnMut(&T) -> bool,
    ) -> bool {
        if self.len == N {
            return false;
        }
        let mut k = self.len;
        while k > floor {
            let p = self.at(k - 1);
            if !after(&p) {
                break;
            }
            // k ≤ len < N: the slot is in the array, and becomes written below `len + 1`.
            self.items[k] = MaybeUninit::new(p);
            k -= 1;
        }
        self.items[k] = MaybeUninit::new(v);
        self.len += 1;
        true
    }

    /// Drops the first `n` values (at most `len`), moving the rest down.
    #[inline]
    pub fn drop_front(&mut self, n: usize) {
        let n = n.min(self.len);
        // Slots n..len are written; they move to 0..len − n.
        self.items.copy_within(n..self.len, 0);
        self.len -= n;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// Every method against a `Vec` doing the same, on 20 000 random operations over a
    /// capacity of 8 (so that full lists and empty ones come up often).
    #[test]
    fn every_method_equals_a_vec() {
        let mut rng = Pcg64::seed_from_u64(17);
        let mut f: Fixed<u32, 8> = Fixed::new();
        let mut v: Vec<u32> = Vec::new();
        for _ in 0..20_000 {
            let x = rng.gen_range(0..20u32);
            match rng.gen_range(0..7) {
                0 => assert_eq!(
                    f.push(x),
                    v.len() < 8 && {
                        v.push(x);
                        true
                    }
                ),
                1 => assert_eq!(f.pop(), v.pop()),
                2 => {
                    f.retain(|&y| y % 3 != x % 3);
                    v.retain(|&y| y % 3 != x % 3);
                }
                3 => {
                    // Sorted insertion from the back above a floor.
                    let floor = rng.gen_range(0..=v.len());
                    let ok = f.insert_from_back(x, floor, |&p| p > x);
                    assert_eq!(ok, v.len() < 8);
                    if ok {
                        let mut k = v.len();
                        while k > floor && v[k - 1] > x {
                            k -= 1;
                        }
                        v.insert(k, x);
                    }
                }
                4 => {
                    let n = rng.gen_range(0..=v.len() + 1);
                    f.drop_front(n);
                    v.drain(..n.min(v.len()));
                }
                5 => {
                    if let Some(s) = f.as_mut_slice().first_mut() {
                        *s = x;
                        v[0] = x;
                    }
                }
                _ => {
                    if rng.gen_bool(0.05) {
                        f.clear();
                        v.clear();
                    }
                }
            }
            assert_eq!(f.as_slice(), &v[..]);
            assert_eq!(
                (f.len(), f.is_empty(), f.is_full()),
                (v.len(), v.is_empty(), v.len() == 8)
            );
            assert_eq!(f.last(), v.last().copied());
            for (k, &y) in v.iter().enumerate() {
                assert_eq!(f.at(k), y);
            }
        }
    }

    #[test]
    #[should_panic(expected = "index 0 of a fixed list of 0")]
    fn an_unwritten_slot_is_never_read() {
        Fixed::<f64, 4>::new().at(0);
    }

    #[test]
    #[should_panic(expected = "a fixed list of 2 overflowed")]
    fn push_within_panics_when_full() {
        let mut f = Fixed::<u8, 2>::new();
        for k in 0..3 {
            f.push_within(k);
        }
    }
}
