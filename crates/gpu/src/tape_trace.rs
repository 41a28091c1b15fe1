//! Rays against expression solids on the GPU (GPU.md §6.2.4): frep's interval tracer
//! ([`frep::ExprView::trace`]) in f32 with fixed capacities, in WGSL, and its CPU twin
//! [`TapeSolid::trace`], equal bit for bit on lavapipe (GPU.md §3.5).
//!
//! Clip to the bounds grown by the resolution ε = [`RESOLUTION`] × diagonal; the signs at
//! both ends; then segments from an explicit stack of [`STACK`], left half first: dropped
//! where the F interval excludes 0; where dF/dt excludes 0 or the segment is shorter than
//! ε/|d|, decided by the end signs and bisected on the sign; else the mean-value test, then
//! halving. Differences from frep's f64 tracer: no per-segment tape simplification,
//! bisection in place of Newton, and a budget in loop iterations (GPU.md §3.1) rather than
//! in segments.
//!
//! **Never a wrong answer.** Every sign is read from an interval evaluation of the point
//! (a box rounded outward around o + t·d), not from an f32 value: a sign the interval
//! leaves open — a point within f32 rounding of F = 0, a grazing touch, a near-zero
//! sheet — ends the ray [`TapeHit::Undecided`], as do a ring that dropped a farther
//! segment before anything nearer was found and an evaluation that would pass
//! [`BUDGET`], and the caller hands the ray to the CPU's f64 tracer. A midpoint whose
//! sign is open while a segment is split (a crossing at a kink, where dF/dt spans 0) is
//! replaced by the points half an ε to either side, and the segment split in three. A
//! bisection's ends have proven opposite signs, so its crossing is certain; where its
//! midpoint's sign turns open it goes on by the sign of the interval's middle, so that t
//! lands within f32's rounding zone of the crossing, unless that zone may reach farther
//! than [`OPEN_ZONE`]·ε: both the bracket and, for a monotone segment, the Newton bound
//! |F(pt)|/min|F'| are wider.
//!
//! (With an f32 value's sign, colonnade.vm at 62 208 pixel centres gave 81 false hits,
//! 503 misses and 15 depths off by over 10⁻³ against frep; 505 of them from deciding
//! segments by their end signs once a soft budget ran low. `examples/pixel_centres.rs`
//! measures it.)

use crate::tape::{down, i_add, i_mul, up, w1, GpuTape};
use frep::Aabb;
use glam::Vec3;

/// The tracer's WGSL (`trace_tape`); see [`TapeSolid::scene_wgsl`].
pub const TRACE_WGSL: &str = include_str!("shaders/tape_trace.wgsl");

/// Resolution along rays, relative to the bounds' diagonal: frep's 1e-7 (f64) raised
/// for f32 (GPU.md §6.2.4).
pub const RESOLUTION: f32 = 2e-6;

/// Segment stack capacity.
pub const STACK: usize = 32;

/// Loop iterations an invocation may reach (GPU.md §3.1: < 30 000, llvmpipe stops loops
/// at 65 535).
pub const BUDGET: u32 = 24_000;

/// How far, in ε, the rounding zone around a bisection's crossing may reach (the bracket
/// or the Newton bound, where a midpoint's sign turns open) for it to answer: 256·ε is 5·10⁻⁴ of the
/// bounds' diagonal, half the tolerance of the tests against frep's f64 tracer.
pub const OPEN_ZONE: f32 = 256.0;

/// Bisection steps at most (an open sign or adjacent f32 are reached well before).
pub const MAX_BISECT: u32 = 64;

/// Words per solid at the start of a scene's `tape` binding ([`TapeSolid::scene_words`]).
pub const SOLID_WORDS: usize = 9;

/// The interpreter's register file for a tape of `n` registers: the next power of two.
pub fn register_class(n: usize) -> usize {
    n.max(1).next_power_of_two()
}

/// A ray's outcome, as the kernel reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TapeHit {
    /// No crossing in (t_min, t_max).
    Miss,
    /// The first crossing (an f32 past the sign change, within ε of it).
    Hit(f32),
    /// A sign within rounding, or the budget or stack exhausted: for the CPU.
    Undecided,
}

/// A traced ray: the outcome and the loop iterations taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Traced {
    /// The outcome.
    pub hit: TapeHit,
    /// Loop iterations of the invocation (GPU.md §3.1).
    pub loops: u32,
}

impl Traced {
    /// The kernel's `TraceResult` (status: 0 miss, 1 hit, 2 undecided; t as bits) and
    /// its loop count.
    pub fn from_kernel(status: u32, t_bits: u32, loops: u32) -> Self {
        let hit = match status {
            0 => TapeHit::Miss,
            1 => TapeHit::Hit(f32::from_bits(t_bits)),
            _ => TapeHit::Undecided,
        };
        Self { hit, loops }
    }
}

/// An expression solid for the GPU tracer: its tape, bounds rounded outward to f32
/// (GPU.md §5.1) and resolution ε.
#[derive(Clone, Debug)]
pub struct TapeSolid {
    /// The tape.
    pub tape: GpuTape,
    /// Lower bounds.
    pub lo: [f32; 3],
    /// Upper bounds.
    pub hi: [f32; 3],
    /// ε = [`RESOLUTION`] × diagonal.
    pub eps: f32,
}

impl TapeSolid {
    /// The solid of `tape` in `bounds` (finite; every point with F ≥ 0 inside).
    pub fn new(tape: GpuTape, bounds: &Aabb) -> Self {
        let out = |v: f64, up: bool| {
            let f = v as f32;
            match (up, (f as f64) < v, (f as f64) > v) {
                (true, true, _) => f.next_up(),
                (false, _, true) => f.next_down(),
                _ => f,
            }
        };
        let lo = bounds.lo.to_array().map(|v| out(v, false));
        let hi = bounds.hi.to_array().map(|v| out(v, true));
        let e = Vec3::from(hi) - Vec3::from(lo);
        let eps = RESOLUTION * e.length().max(1e-12);
        Self { tape, lo, hi, eps }
    }

    /// The tracer over several solids in one kernel (a scene's expression solids): one
    /// interpreter whose register file is the power-of-two class of the most registers
    /// ([`register_class`]) and whose trip count is the tape's length at run time, and
    /// `use_tape(k)`, which points `tape_base`, `tape_ops`, `EPS`, `BLO` and `BHI` at
    /// solid k before a trace or a normal, from the header of the `tape` binding
    /// ([`Self::scene_words`]). The source depends on the register class and on which
    /// kinds of operation the tapes use, not on the tapes, their lengths or the solids'
    /// bounds: another scene of the same class reuses the compiled kernels (the driver's
    /// pipeline cache, Mesa's on-disk shader cache).
    pub fn scene_wgsl(solids: &[TapeSolid]) -> String {
        let regs = register_class(solids.iter().map(|s| s.tape.registers()).max().unwrap_or(1));
        format!(
            "const REG_COUNT: u32 = {regs}u;\nvar<private> tape_ops: u32;\nconst ELEMENTARY: bool = {};\nconst RBOUND: bool = {};\n{}{}{}{}\n\
             var<private> EPS: f32;\nvar<private> BLO: vec3<f32>;\nvar<private> BHI: vec3<f32>;\n\
             // Solid k's words at {SOLID_WORDS}k of the `tape` binding: its tape's first word, its length, ε, lo, hi.\n\
             fn use_tape(k: u32) {{\n    let h = {SOLID_WORDS}u * k;\n    tape_base = tape[h];\n    tape_ops = tape[h + 1u];\n    EPS = bitcast<f32>(tape[h + 2u]);\n    \
             BLO = vec3<f32>(bitcast<f32>(tape[h + 3u]), bitcast<f32>(tape[h + 4u]), bitcast<f32>(tape[h + 5u]));\n    \
             BHI = vec3<f32>(bitcast<f32>(tape[h + 6u]), bitcast<f32>(tape[h + 7u]), bitcast<f32>(tape[h + 8u]));\n}}\n{TRACE_WGSL}",
            solids.iter().any(|s| s.tape.elementary()),
            solids.iter().any(|s| s.tape.r_functions()),
            crate::FLOAT_WGSL,
            crate::TRIG_WGSL,
            crate::tape::tape_consts_wgsl(),
            crate::tape::TAPE_WGSL,
        )
    }

    /// The `tape` binding's words for [`Self::scene_wgsl`]: per solid its
    /// [`SOLID_WORDS`] (where its tape starts, its length in instructions, ε, the bounds'
    /// lo and hi as f32 bits), then the solids' tapes one after another.
    pub fn scene_words(solids: &[TapeSolid]) -> Vec<u32> {
        let head = SOLID_WORDS * solids.len();
        let total: usize = solids.iter().map(|s| s.tape.words().len()).sum();
        let mut words = Vec::with_capacity(head + total);
        let mut at = head;
        for s in solids {
            words.push(at as u32);
            words.push(s.tape.len() as u32);
            words.push(s.eps.to_bits());
            words.extend(s.lo.iter().chain(&s.hi).map(|v| v.to_bits()));
            at += s.tape.words().len();
        }
        for s in solids {
            words.extend_from_slice(s.tape.words());
        }
        words
    }

    /// The twin of the kernel's `trace_tape`.
    pub fn trace(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Traced {
        let mut loops = 0u32;
        let hit = self.trace_counted(o, d, t_min, t_max, &mut loops);
        Traced { hit, loops }
    }

    fn trace_counted(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32, loops: &mut u32) -> TapeHit {
        let len_tape = self.tape.eval_loops();
        let eps = Vec3::splat(self.eps);
        let glo = Vec3::from(self.lo) - eps;
        let ghi = Vec3::from(self.hi) + eps;
        let inv = Vec3::new(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
        let ta = (glo - o) * inv;
        let tb = (ghi - o) * inv;
        let mut t0 = t_min
            .max(ta.x.min(tb.x))
            .max(ta.y.min(tb.y))
            .max(ta.z.min(tb.z));
        let mut t1 = t_max
            .min(ta.x.max(tb.x))
            .min(ta.y.max(tb.y))
            .min(ta.z.max(tb.z));
        if !(t0.is_finite() && t1.is_finite()) || t0 >= t1 {
            return TapeHit::Miss;
        }
        let len = (d.x * d.x + d.y * d.y + d.z * d.z).sqrt();
        let eps_t = self.eps / len.max(f32::MIN_POSITIVE);
        let mut st = Ring::default();
        let (mut phase, mut pt) = (Phase::Start, t0);
        let (mut ia0, mut ib0) = (false, false);
        let (mut a, mut b, mut ia, mut ib, mut m) = (0f32, 0f32, false, false, 0f32);
        let mut slope = [0f32; 2];
        let mut steps = 0u32;
        let mut s_lo = false;
        let (mut retried, mut retried_end) = (false, false);
        // Whether the window starts where the ray enters the bounds and ends where it
        // leaves them (before t_max), fixed before either end moves in by ε.
        let (entered, exits) = (t0 > t_min, t1 < t_max);
        loop {
            *loops += 1;
            // One loop iteration (and one more per segment pushed, the kernel's push
            // loop), one evaluation per iteration (the kernel's one call site): the segment
            // [a, b] in `Segment`, else the point at `pt`.
            let (lo, hi) = match phase {
                Phase::Segment => {
                    let Some(top) = st.pop() else {
                        return if st.lost {
                            TapeHit::Undecided
                        } else if exits && ib0 {
                            TapeHit::Hit(t1)
                        } else {
                            TapeHit::Miss
                        };
                    };
                    (a, b, ia, ib) = top;
                    (a, b)
                }
                Phase::Bisect => {
                    let mid = a + (b - a) * 0.5;
                    if !(mid > a && mid < b) || steps >= MAX_BISECT {
                        return TapeHit::Hit(b);
                    }
                    steps += 1;
                    pt = mid;
                    (pt, pt)
                }
                _ => (pt, pt),
            };
            // Room for this evaluation and the next iteration's start (1 + 3 pushes).
            if *loops + len_tape + 4 > BUDGET {
                return TapeHit::Undecided;
            }
            *loops += len_tape;
            let c = |k: usize| {
                let (ok, dk) = (o[k], d[k]);
                let (pa_lo, pa_hi) = (ok + down(lo * dk), ok + up(lo * dk));
                let (pb_lo, pb_hi) = (ok + down(hi * dk), ok + up(hi * dk));
                [down(pa_lo.min(pb_lo)), up(pa_hi.max(pb_hi)), dk, dk]
            };
            let (r, wrap) = self.tape.eval_interval_wrap(c(0), c(1), c(2));
            if phase == Phase::Segment {
                if r[0] > 0.0 || r[1] < 0.0 {
                    continue;
                }
                slope = [r[2], r[3]];
                if r[2] > 0.0 || r[3] < 0.0 || b - a <= eps_t {
                    if ia != ib {
                        phase = Phase::Bisect;
                        steps = 0;
                    }
                } else {
                    // At a mod's wrap where one lies inside (a jump, which halving
                    // would close in on only at ε), kept ε from the ends so that the
                    // piece holding the jump is at most ε; else at the middle.
                    m = a + (b - a) * 0.5;
                    if wrap < 1.0 && b - a > 4.0 * eps_t {
                        m = (a + (b - a) * wrap).max(a + eps_t).min(b - eps_t);
                    }
                    pt = m;
                    phase = Phase::Split;
                }
                continue;
            }
            // The point's sign where its interval decides it (NaN: outside, as F ≥ 0 is
            // false on the CPU); an undecided sign ends the ray undecided, except in a
            // bisection, where the crossing then lies within the interval's reach of pt.
            let sign = if r[0] >= 0.0 {
                Some(true)
            } else if r[1] < 0.0 || r[0].is_nan() || r[1].is_nan() {
                Some(false)
            } else {
                None
            };
            match (phase, sign) {
                (Phase::Bisect, None) => {
                    // Within f32 rounding of the crossing, which the end signs prove:
                    // on by the interval's middle, so that t lies within the rounding
                    // zone, unless the zone may reach farther than OPEN_ZONE·ε (a
                    // grazing crossing), whose t f32 cannot pin down.
                    // The zone's reach: the bracket, or for a monotone segment the
                    // Newton bound |F(pt)|/min|F'| (Moore 1966, §7).
                    let monotone = slope[0] > 0.0 || slope[1] < 0.0;
                    let reach = r[0].abs().max(r[1].abs())
                        / if slope[0] > 0.0 { slope[0] } else { -slope[1] };
                    if b - a > OPEN_ZONE * eps_t && !(monotone && reach <= OPEN_ZONE * eps_t) {
                        return TapeHit::Undecided;
                    }
                    if (r[0] + r[1] >= 0.0) == ia {
                        a = pt;
                    } else {
                        b = pt;
                    }
                }
                (Phase::Split, None) => {
                    // m within rounding of F = 0 (often a crossing at a kink, where dF/dt
                    // spans 0): the signs half an ε to either side instead, and three
                    // segments.
                    phase = Phase::SplitLo;
                    pt = m - 0.5 * eps_t;
                }
                (Phase::Start, None) if !retried && t0 + eps_t < t1 && t0 + eps_t > t0 => {
                    // A window starting within rounding of the surface (a search just
                    // past a crossing, a ray leaving a surface): its first ε is below
                    // the resolution; start one ε in, once.
                    t0 += eps_t;
                    pt = t0;
                    retried = true;
                }
                (Phase::End, None) if !retried_end && t1 - eps_t > t0 && t1 - eps_t < t1 => {
                    t1 -= eps_t;
                    pt = t1;
                    retried_end = true;
                }
                (_, None) => return TapeHit::Undecided,
                (Phase::Start, Some(inside)) => {
                    ia0 = inside;
                    // Inside where the ray enters the bounds: a crossing there (not where
                    // the window starts at t_min, even one moved in by ε).
                    if entered && ia0 {
                        return TapeHit::Hit(t0);
                    }
                    phase = Phase::End;
                    pt = t1;
                }
                (Phase::End, Some(inside)) => {
                    ib0 = inside;
                    st.push((t0, t1, ia0, ib0));
                    *loops += 1;
                    phase = Phase::Segment;
                }
                (Phase::Split, Some(inside)) => {
                    phase = Phase::Segment;
                    // The mean-value form F(m) + F'·([a, b] − m) (Moore 1966, §6).
                    let mv = i_add([r[0], r[1]], i_mul(slope, w1(a - m, b - m)));
                    if ia == ib && (mv[0] > 0.0 || mv[1] < 0.0) {
                        continue;
                    }
                    st.push((m, b, inside, ib));
                    st.push((a, m, ia, inside));
                    *loops += 2;
                }
                (Phase::SplitLo, Some(inside)) => {
                    s_lo = inside;
                    phase = Phase::SplitHi;
                    pt = split_hi(m, eps_t);
                }
                (Phase::SplitHi, Some(inside)) => {
                    phase = Phase::Segment;
                    let (lo, hi) = (m - 0.5 * eps_t, split_hi(m, eps_t));
                    st.push((hi, b, inside, ib));
                    st.push((lo, hi, s_lo, inside));
                    st.push((a, lo, ia, s_lo));
                    *loops += 3;
                }
                (Phase::Segment, _) => unreachable!("segments continue above"),
                (Phase::Bisect, Some(inside)) => {
                    if inside == ia {
                        a = pt;
                    } else {
                        b = pt;
                    }
                }
            }
        }
    }
}

/// The upper end of the piece of at most ε around a split point m whose sign is open
/// (the lower is m − ε/2): the float below (m − ε/2) + ε, so that the piece is never
/// longer than ε once rounded, and is decided by its end signs instead of split again
/// about the same open point.
fn split_hi(m: f32, eps_t: f32) -> f32 {
    down((m - 0.5 * eps_t) + eps_t)
}

/// The segment stack, a ring: when full, a push drops the bottom entry (the farthest
/// segment), and a ray that then finds nothing nearer is undecided.
#[derive(Default)]
struct Ring {
    st: [(f32, f32, bool, bool); STACK],
    n: usize,
    base: usize,
    lost: bool,
}

impl Ring {
    fn push(&mut self, e: (f32, f32, bool, bool)) {
        if self.n == STACK {
            self.base = (self.base + 1) % STACK;
            self.n -= 1;
            self.lost = true;
        }
        self.st[(self.base + self.n) % STACK] = e;
        self.n += 1;
    }

    fn pop(&mut self) -> Option<(f32, f32, bool, bool)> {
        self.n = self.n.checked_sub(1)?;
        Some(self.st[(self.base + self.n) % STACK])
    }
}

/// The tracer's state: the signs at the window's two ends, then segments popped from the
/// stack, a segment's midpoint when it is split, a bisection (the kernel's `phase` 0–4).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Phase {
    Start,
    End,
    Segment,
    Split,
    Bisect,
    SplitLo,
    SplitHi,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Register classes are powers of two holding n.
    #[test]
    fn register_classes_hold_the_registers() {
        for n in 0..300 {
            let r = register_class(n);
            assert!(r >= n.max(1) && r.is_power_of_two() && r < 2 * n.max(1));
        }
    }
}
