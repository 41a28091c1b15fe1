//! Rays against expression solids on the GPU (GPU.md §6.2.4): frep's interval tracer
//! ([`frep::ExprView::trace`]) in f32 with fixed capacities, in WGSL, and its CPU twin
//! [`TapeSolid::trace`], equal bit for bit on lavapipe (GPU.md §3.5).
//!
//! Clip to the bounds grown by the resolution ε = [`RESOLUTION`] × diagonal; the signs at
//! both ends; then segments from an explicit stack of [`STACK`], left half first: dropped
//! where the F interval excludes 0; where dF/dt excludes 0 or the segment is shorter than
//! ε/|d|, decided by the end signs and bisected on the sign down to adjacent f32; else the
//! mean-value test, then halving. Differences from frep's f64 tracer: no per-segment tape
//! simplification, bisection in place of Newton, and budgets in loop iterations (GPU.md
//! §3.1) rather than segments: once an evaluation would pass the soft budget
//! ([`BUDGET`] less a reserve for one bisection and the stack), the segments left are
//! decided by their end signs, as frep does past its `MAX_SEGMENTS`, and the outcome is
//! flagged [`Traced::late`]; an evaluation that would pass [`BUDGET`], or a full stack,
//! ends the ray as [`TapeHit::Undecided`], never as a silent miss.

use crate::tape::{down, i_add, i_mul, up, w1, GpuTape};
use frep::Aabb;
use glam::Vec3;

/// The tracer's WGSL (`trace_tape`); see [`TapeSolid::wgsl`].
pub const TRACE_WGSL: &str = include_str!("shaders/tape_trace.wgsl");

/// Resolution along rays, relative to the bounds' diagonal: frep's 1e-7 (f64) raised
/// for f32 (GPU.md §6.2.4).
pub const RESOLUTION: f32 = 2e-6;

/// Segment stack capacity.
pub const STACK: usize = 32;

/// Loop iterations an invocation may reach (GPU.md §3.1: < 30 000, llvmpipe stops loops
/// at 65 535).
pub const BUDGET: u32 = 24_000;

/// Bisection steps at most (adjacent f32 are reached well before).
pub const MAX_BISECT: u32 = 64;

/// A ray's outcome, as the kernel reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TapeHit {
    /// No crossing in (t_min, t_max).
    Miss,
    /// The first crossing (the first f32 past the sign change).
    Hit(f32),
    /// Budget or stack exhausted: undecided.
    Undecided,
}

/// A traced ray: the outcome, whether segments were decided by end signs past the soft
/// budget, and the loop iterations taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Traced {
    /// The outcome.
    pub hit: TapeHit,
    /// Whether the soft budget ran out (see the module docs).
    pub late: bool,
    /// Loop iterations of the invocation (GPU.md §3.1).
    pub loops: u32,
}

impl Traced {
    /// The kernel's `TraceResult` (status: 0 miss, 1 hit, 2 undecided, plus 4 when late;
    /// t as bits) and its loop count.
    pub fn from_kernel(status: u32, t_bits: u32, loops: u32) -> Self {
        let hit = match status & 3 {
            0 => TapeHit::Miss,
            1 => TapeHit::Hit(f32::from_bits(t_bits)),
            _ => TapeHit::Undecided,
        };
        Self {
            hit,
            late: status & 4 != 0,
            loops,
        }
    }
}

/// The soft budget for evaluations of `eval_loops` iterations ([`GpuTape::eval_loops`]):
/// [`BUDGET`] less one bisection and a pass over the stack (0 when the tape is too long).
pub fn soft_budget(eval_loops: u32) -> u32 {
    let reserve = (MAX_BISECT + 2) * (eval_loops + 1) + STACK as u32;
    BUDGET.saturating_sub(reserve)
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

    /// The interpreter and tracer WGSL with this solid's constants (`EPS`, `BLO`, `BHI`,
    /// and the tape's); the kernel declares `tape: array<u32>`.
    pub fn wgsl(&self) -> String {
        let v = |a: [f32; 3]| format!("vec3<f32>({}, {}, {})", hex(a[0]), hex(a[1]), hex(a[2]));
        format!(
            "{}\nconst EPS: f32 = {};\nconst BLO = {};\nconst BHI = {};\n{TRACE_WGSL}",
            self.tape.wgsl(),
            hex(self.eps),
            v(self.lo),
            v(self.hi)
        )
    }

    /// The tracer over several solids in one kernel (a scene's expression solids):
    /// one interpreter of the longest tape's length (the others padded in front,
    /// [`GpuTape::padded_words`], so that its loops keep a constant trip count, GPU.md
    /// §3.4) and `use_tape(k)`, which points `tape_base`, `EPS`, `BLO` and `BHI` at
    /// solid k before a trace or a normal. The words for the `tape` binding are
    /// [`Self::scene_words`]'s.
    pub fn scene_wgsl(solids: &[TapeSolid]) -> String {
        let len = solids.iter().map(|s| s.tape.len()).max().unwrap_or(1);
        let regs = solids.iter().map(|s| s.tape.registers()).max().unwrap_or(1);
        let v = |a: [f32; 3]| format!("vec3<f32>({}, {}, {})", hex(a[0]), hex(a[1]), hex(a[2]));
        let cases: String = solids
            .iter()
            .enumerate()
            .map(|(k, s)| {
                format!(
                    "        case {k}u: {{ tape_base = {}u; EPS = {}; BLO = {}; BHI = {}; }}\n",
                    2 * k * len,
                    hex(s.eps),
                    v(s.lo),
                    v(s.hi)
                )
            })
            .collect();
        format!(
            "const REG_COUNT: u32 = {}u;\nconst TAPE_LEN: u32 = {len}u;\n{}{}{}\n\
             var<private> EPS: f32;\nvar<private> BLO: vec3<f32>;\nvar<private> BHI: vec3<f32>;\n\
             fn use_tape(k: u32) {{\n    switch k {{\n{cases}        default: {{}}\n    }}\n}}\n{TRACE_WGSL}",
            regs.max(1),
            crate::FLOAT_WGSL,
            crate::tape::tape_consts_wgsl(),
            crate::tape::TAPE_WGSL,
        )
    }

    /// The `tape` binding's words for [`Self::scene_wgsl`]: each solid's tape padded to
    /// the longest, in order.
    pub fn scene_words(solids: &[TapeSolid]) -> Vec<u32> {
        let len = solids.iter().map(|s| s.tape.len()).max().unwrap_or(1);
        solids
            .iter()
            .flat_map(|s| s.tape.padded_words(len))
            .collect()
    }

    /// The twin of the kernel's `trace_tape`.
    pub fn trace(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Traced {
        let (mut loops, mut late) = (0u32, false);
        let hit = self.trace_counted(o, d, t_min, t_max, &mut loops, &mut late);
        Traced { hit, late, loops }
    }

    fn trace_counted(
        &self,
        o: Vec3,
        d: Vec3,
        t_min: f32,
        t_max: f32,
        loops: &mut u32,
        late: &mut bool,
    ) -> TapeHit {
        let len_tape = self.tape.eval_loops();
        let eps = Vec3::splat(self.eps);
        let glo = Vec3::from(self.lo) - eps;
        let ghi = Vec3::from(self.hi) + eps;
        let inv = Vec3::new(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
        let ta = (glo - o) * inv;
        let tb = (ghi - o) * inv;
        let t0 = t_min
            .max(ta.x.min(tb.x))
            .max(ta.y.min(tb.y))
            .max(ta.z.min(tb.z));
        let t1 = t_max
            .min(ta.x.max(tb.x))
            .min(ta.y.max(tb.y))
            .min(ta.z.max(tb.z));
        if !(t0.is_finite() && t1.is_finite()) || t0 >= t1 {
            return TapeHit::Miss;
        }
        let len = (d.x * d.x + d.y * d.y + d.z * d.z).sqrt();
        let eps_t = self.eps / len.max(f32::MIN_POSITIVE);
        let mut st = [(0f32, 0f32, false, false); STACK];
        let mut n = 0usize;
        let (mut phase, mut pt) = (0u32, t0);
        let (mut ia0, mut ib0) = (false, false);
        let (mut a, mut b, mut ia, mut ib, mut m) = (0f32, 0f32, false, false, 0f32);
        let mut slope = [0f32; 2];
        let mut steps = 0u32;
        let budget = |loops: u32| loops + len_tape > BUDGET;
        let soft = soft_budget(len_tape);
        let over_soft = |loops: u32| loops + len_tape > soft;
        loop {
            *loops += 1;
            if phase == 2 {
                if n == 0 {
                    return if t1 < t_max && ib0 {
                        TapeHit::Hit(t1)
                    } else {
                        TapeHit::Miss
                    };
                }
                n -= 1;
                (a, b, ia, ib) = st[n];
                if *late || over_soft(*loops) {
                    *late = true;
                    if ia == ib {
                        continue;
                    }
                    phase = 4;
                    steps = 0;
                }
            }
            if phase == 2 {
                let c = |k: usize| {
                    let (ok, dk) = (o[k], d[k]);
                    let (pa_lo, pa_hi) = (ok + down(a * dk), ok + up(a * dk));
                    let (pb_lo, pb_hi) = (ok + down(b * dk), ok + up(b * dk));
                    [down(pa_lo.min(pb_lo)), up(pa_hi.max(pb_hi)), dk, dk]
                };
                *loops += len_tape;
                let r = self.tape.eval_interval(c(0), c(1), c(2));
                if r[0] > 0.0 || r[1] < 0.0 {
                    continue;
                }
                if r[2] > 0.0 || r[3] < 0.0 || b - a <= eps_t {
                    if ia != ib {
                        phase = 4;
                        steps = 0;
                    } else {
                        continue;
                    }
                } else {
                    slope = [r[2], r[3]];
                    m = a + (b - a) * 0.5;
                    pt = m;
                    phase = 3;
                }
            }
            if (phase == 3 || phase < 2) && over_soft(*loops) {
                if phase < 2 {
                    return TapeHit::Undecided;
                }
                *late = true;
                if ia == ib {
                    phase = 2;
                    continue;
                }
                phase = 4;
                steps = 0;
            }
            if phase == 4 {
                let mid = a + (b - a) * 0.5;
                if !(mid > a && mid < b) || steps >= MAX_BISECT {
                    return TapeHit::Hit(b);
                }
                steps += 1;
                pt = mid;
            }
            if budget(*loops) {
                return TapeHit::Undecided;
            }
            *loops += len_tape;
            let p = [o.x + pt * d.x, o.y + pt * d.y, o.z + pt * d.z];
            let f = self.tape.eval_point(p);
            let inside = f >= 0.0;
            match phase {
                0 => {
                    ia0 = inside;
                    if t0 > t_min && ia0 {
                        return TapeHit::Hit(t0);
                    }
                    phase = 1;
                    pt = t1;
                }
                1 => {
                    ib0 = inside;
                    st[0] = (t0, t1, ia0, ib0);
                    n = 1;
                    phase = 2;
                }
                3 => {
                    phase = 2;
                    let mv = i_add([f, f], i_mul(slope, w1(a - m, b - m)));
                    if ia == ib && (mv[0] > 0.0 || mv[1] < 0.0) {
                        continue;
                    }
                    if n + 2 > STACK {
                        return TapeHit::Undecided;
                    }
                    st[n] = (m, b, inside, ib);
                    st[n + 1] = (a, m, ia, inside);
                    n += 2;
                }
                _ => {
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

/// A finite f32 as an exact WGSL hexadecimal literal (`bitcast` is no constant
/// expression in naga 30).
fn hex(x: f32) -> String {
    assert!(x.is_finite(), "{x}");
    if x == 0.0 {
        return if x.is_sign_negative() {
            "-0.0f"
        } else {
            "0.0f"
        }
        .into();
    }
    let b = x.to_bits();
    let sign = if b >> 31 == 1 { "-" } else { "" };
    let (e, m) = ((b >> 23) & 0xff, b & 0x7f_ffff);
    if e == 0 {
        // Subnormal: m × 2^-149.
        return format!("{sign}0x{m:x}p-149f");
    }
    format!("{sign}0x1.{:06x}p{}f", m << 1, e as i32 - 127)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_literals_are_exact() {
        assert_eq!(hex(1.0), "0x1.000000p0f");
        assert_eq!(hex(-0.75), "-0x1.800000p-1f");
        assert_eq!(hex(f32::from_bits(1)), "0x1p-149f");
        assert_eq!(hex(f32::MAX), "0x1.fffffep127f");
    }
}
