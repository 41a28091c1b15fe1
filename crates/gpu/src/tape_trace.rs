//! Rays against expression solids on the GPU (GPU.md §6.2.4): frep's interval tracer
//! ([`frep::ExprView::trace`]) in f32 with fixed capacities, in WGSL, and its CPU twin
//! [`TapeSolid::trace`], equal bit for bit on lavapipe (GPU.md §3.5).
//!
//! Clip to the bounds grown by the resolution ε = [`RESOLUTION`] × diagonal; the signs at
//! both ends; then segments from an explicit stack of [`STACK`], left half first: dropped
//! where the F interval excludes 0; where dF/dt excludes 0 or the segment is shorter than
//! ε/|d|, decided by the end signs and bisected on the sign; else the mean-value test, then
//! halving. Differences from frep's f64 tracer: tapes simplified per cell of the grid
//! (below), not per segment; bisection in place of Newton; and a budget in loop
//! iterations (GPU.md §3.1) rather than in segments.
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
//! A segment shorter than ε with the same sign at both ends whose F interval holds 0 and
//! whose dF/dt is finite and holds 0 (a kink, or a sliver thinner than ε: one of
//! prospero's letter corners was 0.3 ε thick) is decided by the sign at its middle and
//! the mean-value test, else undecided; one whose dF/dt is not finite holds a jump of F
//! (a `mod`'s wrap, an `if`) and is decided by its end signs, as f32 places the jump no
//! closer than ε.
//!
//! (With an f32 value's sign, colonnade.vm at 62 208 pixel centres gave 81 false hits,
//! 503 misses and 15 depths off by over 10⁻³ against frep; 505 of them from deciding
//! segments by their end signs once a soft budget ran low. `examples/pixel_centres.rs`
//! measures it.)
//!
//! **Walking the cells.** A solid [`TapeSolid::with_cells`] carries frep's occupancy grid
//! ([`frep::occupancy`]), built with [`WALK_MARGIN`], and a tape per occupied cell
//! ([`CellTapes`]). The tracer walks the window cell by cell (Amanatides & Woo 1987, each
//! face's t computed afresh from the ray in cell units, not accumulated): an empty cell
//! gives F's sign across it; a run of occupied cells that share a tape is searched as
//! above with that tape, over the window [where the run starts, where it ends], its end
//! signs from the empty cells beside it, or from an evaluation of the run's tape where it
//! meets a run of another tape or the window's end. A cell's tape and sign hold within
//! [`WALK_MARGIN`] of a cell; the walk's f32 rounding is at most 2⁻²¹ of the ray's and
//! grid's magnitudes in cells, so a ray whose magnitudes pass [`WALK_REACH`] cells (far
//! from a small solid) searches its whole window with the whole tape instead. On
//! prospero.vm (6 363 instructions; the loop budget fits about a dozen evaluations) a
//! pixel centre then takes 217 loop iterations on average instead of 16 600 and 0.6 % of
//! them go to the CPU instead of 63 % (`examples/pixel_centres.rs`, 27 views at 16²).

use crate::cell_tapes::{CellTapeError, CellTapes, INSIDE};
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
pub const SOLID_WORDS: usize = 10;

/// Words of a walk grid's header in the `tape` binding, before its cells: n, the grid's
/// lower corner, its cells per unit, its reach, where its tape table starts.
pub const GRID_WORDS: usize = 9;

/// How far, as a fraction of a cell, a walk grid's cells hold (their emptiness, signs
/// and tapes; [`frep::occupancy::build_with_margin`]): room for the walk's f32 rounding.
pub const WALK_MARGIN: f64 = 1.0 / 256.0;

/// The walk serves a ray whose magnitudes in cells (|o − lo|·scale per axis, and the
/// grid's [`WalkGrid::reach`]) sum to at most this: its rounding, at most 2⁻²¹ of that
/// sum in cells (module docs), then stays within a quarter of [`WALK_MARGIN`].
pub const WALK_REACH: f32 = 2048.0;

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
    /// The cells a ray walks, each searched with its own tape (None: every ray searches
    /// its whole window with the whole tape).
    pub walk: Option<Box<WalkGrid>>,
}

/// An expression solid's occupancy grid for the tracer's walk: per cell its tape or,
/// empty, F's sign ([`CellTapes`]), over a box holding the tracer's window.
#[derive(Clone, Debug)]
pub struct WalkGrid {
    /// The cells and their tapes.
    pub cells: CellTapes,
    /// The grid's lower corner.
    pub lo: [f32; 3],
    /// Cells per unit length along each axis.
    pub scale: [f32; 3],
    /// n + max |lo·scale|: the grid's part of the magnitudes the walk's rounding scales
    /// with ([`WALK_REACH`]).
    pub reach: f32,
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
        Self {
            tape,
            lo,
            hi,
            eps,
            walk: None,
        }
    }

    /// The solid with a walk grid for `nodes` (the expression `tape` was compiled from):
    /// frep's occupancy grid built with [`WALK_MARGIN`] over the tracer's window box
    /// grown by ε, and its cell tapes. Unchanged where frep builds no grid (a
    /// polynomial, a build past its budget) or cells without tapes of their own.
    pub fn with_cells(mut self, nodes: &[frep::Node]) -> Result<Self, CellTapeError> {
        if frep::poly_trace::degree(nodes).is_some() {
            return Ok(self);
        }
        let pad = 2.0 * f64::from(self.eps);
        let lo = glam::DVec3::from(self.lo.map(f64::from)) - pad;
        let hi = glam::DVec3::from(self.hi.map(f64::from)) + pad;
        let grid = frep::occupancy::build_with_margin(nodes, &Aabb::new(lo, hi), WALK_MARGIN);
        let Some(cells) = CellTapes::new(&grid.view())? else {
            return Ok(self);
        };
        let n = cells.n as f64;
        let lo32 = lo.to_array().map(|v| v as f32);
        let scale = [0, 1, 2].map(|k| (n / (hi[k] - lo[k])) as f32);
        let reach = cells.n as f32
            + (0..3)
                .map(|k| (lo32[k] * scale[k]).abs())
                .fold(0.0f32, f32::max);
        self.walk = Some(Box::new(WalkGrid {
            cells,
            lo: lo32,
            scale,
            reach,
        }));
        Ok(self)
    }

    /// The tapes the kernel may run for this solid: its own, then its cells'.
    fn all_tapes(&self) -> impl Iterator<Item = &GpuTape> {
        std::iter::once(&self.tape).chain(self.walk.iter().flat_map(|w| w.cells.tapes.iter()))
    }

    /// The tracer over several solids in one kernel (a scene's expression solids): one
    /// interpreter whose register file is the power-of-two class of the most registers
    /// ([`register_class`]) and whose trip count is the tape's length at run time, and
    /// `use_tape(k)`, which points `tape_base`, `tape_ops`, `EPS`, `BLO`, `BHI` and
    /// `GRID_AT` at solid k before a trace or a normal, from the header of the `tape`
    /// binding ([`Self::scene_words`]). The source depends on the register class and on
    /// which kinds of operation the tapes use, not on the tapes, their lengths, the
    /// solids' bounds or grids: another scene of the same class reuses the compiled
    /// kernels (the driver's pipeline cache, Mesa's on-disk shader cache).
    pub fn scene_wgsl(solids: &[TapeSolid]) -> String {
        let tapes = || solids.iter().flat_map(TapeSolid::all_tapes);
        let regs = register_class(tapes().map(GpuTape::registers).max().unwrap_or(1));
        format!(
            "const REG_COUNT: u32 = {regs}u;\nvar<private> tape_ops: u32;\nconst ELEMENTARY: bool = {};\nconst RBOUND: bool = {};\n{}{}{}{}\n\
             var<private> EPS: f32;\nvar<private> BLO: vec3<f32>;\nvar<private> BHI: vec3<f32>;\nvar<private> GRID_AT: u32;\n\
             // Solid k's words at {SOLID_WORDS}k of the `tape` binding: its tape's first word, its length, ε, lo, hi, its walk grid's first word (0: none).\n\
             fn use_tape(k: u32) {{\n    let h = {SOLID_WORDS}u * k;\n    tape_base = tape[h];\n    tape_ops = tape[h + 1u];\n    EPS = bitcast<f32>(tape[h + 2u]);\n    \
             BLO = vec3<f32>(bitcast<f32>(tape[h + 3u]), bitcast<f32>(tape[h + 4u]), bitcast<f32>(tape[h + 5u]));\n    \
             BHI = vec3<f32>(bitcast<f32>(tape[h + 6u]), bitcast<f32>(tape[h + 7u]), bitcast<f32>(tape[h + 8u]));\n    GRID_AT = tape[h + 9u];\n}}\n{TRACE_WGSL}",
            tapes().any(GpuTape::elementary),
            tapes().any(GpuTape::r_functions),
            crate::FLOAT_WGSL,
            crate::TRIG_WGSL,
            crate::tape::tape_consts_wgsl(),
            crate::tape::TAPE_WGSL,
        )
    }

    /// The `tape` binding's words for [`Self::scene_wgsl`]: per solid its
    /// [`SOLID_WORDS`] (where its tape starts, its length in instructions, ε, the bounds'
    /// lo and hi as f32 bits, where its walk grid starts or 0), then per solid its tape
    /// and its walk grid: [`GRID_WORDS`] (n, the corner, the scale, the reach as f32
    /// bits, where its tape table starts), a word per cell (its tape's index, or
    /// [`crate::cell_tapes::NO_TAPE`] or [`INSIDE`]), the tape table (first word and
    /// length of each cell tape), the cell tapes.
    pub fn scene_words(solids: &[TapeSolid]) -> Vec<u32> {
        let mut words = vec![0u32; SOLID_WORDS * solids.len()];
        for (k, s) in solids.iter().enumerate() {
            let h = SOLID_WORDS * k;
            words[h] = words.len() as u32;
            words[h + 1] = s.tape.len() as u32;
            words[h + 2] = s.eps.to_bits();
            for (j, v) in s.lo.iter().chain(&s.hi).enumerate() {
                words[h + 3 + j] = v.to_bits();
            }
            words.extend_from_slice(s.tape.words());
            let Some(w) = &s.walk else {
                continue;
            };
            words[h + 9] = words.len() as u32;
            let table = words.len() + GRID_WORDS + w.cells.cell.len();
            words.push(w.cells.n as u32);
            words.extend(w.lo.iter().chain(&w.scale).map(|v| v.to_bits()));
            words.push(w.reach.to_bits());
            words.push(table as u32);
            words.extend_from_slice(&w.cells.cell);
            let mut at = table + 2 * w.cells.tapes.len();
            for t in &w.cells.tapes {
                words.push(at as u32);
                words.push(t.len() as u32);
                at += t.words().len();
            }
            for t in &w.cells.tapes {
                words.extend_from_slice(t.words());
            }
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
        let mut cur = &self.tape;
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
        let mut short_seg = false;
        let (mut retried, mut retried_end) = (false, false);
        // Whether the window starts where the ray enters the bounds and ends where it
        // leaves them (before t_max), fixed before either end moves in by ε.
        let (entered, exits) = (t0 > t_min, t1 < t_max);
        // The walk (the kernel's): where it stands and F's sign there, the open run.
        let mut walk = self.walk.as_deref().and_then(|g| Walk::new(g, o, d, t0));
        let (mut tw, mut last_in) = (t0, false);
        let mut run: Option<(f32, u32, bool)> = None;
        let (mut pending, mut walk_done) = (0u32, false);
        if let Some(w) = &walk {
            let s0 = w.cell();
            if s0 >= INSIDE {
                ia0 = s0 == INSIDE;
                if entered && ia0 {
                    return TapeHit::Hit(t0);
                }
                last_in = ia0;
                phase = Phase::Walk;
            } else {
                cur = w.tape(s0);
            }
        }
        loop {
            *loops += 1;
            if let (Phase::Walk, Some(w)) = (phase, walk.as_mut()) {
                if *loops + 4 > BUDGET {
                    return TapeHit::Undecided;
                }
                let s = w.cell();
                let (mut ax, mut tf) = (0, w.nx[0]);
                if w.nx[1] < tf {
                    (ax, tf) = (1, w.nx[1]);
                }
                if w.nx[2] < tf {
                    (ax, tf) = (2, w.nx[2]);
                }
                let t_out = tf.min(t1);
                if s >= INSIDE {
                    let s_in = s == INSIDE;
                    if let Some((ra, rt, r_in)) = run.take() {
                        // The run ends where this empty cell starts, with its sign.
                        st.push((ra, tw, r_in, s_in));
                        *loops += 1;
                        cur = w.tape(rt);
                        phase = Phase::Segment;
                    }
                    last_in = s_in;
                } else if let Some((_, rt, _)) = run.filter(|r| r.1 != s) {
                    // Another tape: the sign here by the run's own, then this cell again.
                    pending = s;
                    cur = w.tape(rt);
                    pt = tw;
                    phase = Phase::RunEnd;
                    continue;
                } else if run.is_none() {
                    run = Some((tw, s, last_in));
                }
                if t_out >= t1 || !w.step(ax) {
                    walk_done = true;
                } else {
                    tw = t_out.max(tw);
                }
                if walk_done && phase == Phase::Walk {
                    match run {
                        Some((_, rt, _)) => {
                            cur = w.tape(rt);
                            pt = t1;
                            phase = Phase::WalkEnd;
                        }
                        None if exits && last_in => return TapeHit::Hit(t1),
                        None => return TapeHit::Miss,
                    }
                }
                continue;
            }
            // One loop iteration (and one more per segment pushed, the kernel's push
            // loop), one evaluation per iteration (the kernel's one call site): the segment
            // [a, b] in `Segment`, else the point at `pt`.
            let (lo, hi) = match phase {
                Phase::Segment => {
                    let Some(top) = st.pop() else {
                        if st.lost {
                            return TapeHit::Undecided;
                        }
                        if walk.is_some() {
                            if !walk_done {
                                phase = Phase::Walk;
                                continue;
                            }
                            return if exits && last_in {
                                TapeHit::Hit(t1)
                            } else {
                                TapeHit::Miss
                            };
                        }
                        return if exits && ib0 {
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
            if *loops + cur.eval_loops() + 4 > BUDGET {
                return TapeHit::Undecided;
            }
            *loops += cur.eval_loops();
            let c = |k: usize| {
                let (ok, dk) = (o[k], d[k]);
                let (pa_lo, pa_hi) = (ok + down(lo * dk), ok + up(lo * dk));
                let (pb_lo, pb_hi) = (ok + down(hi * dk), ok + up(hi * dk));
                [down(pa_lo.min(pb_lo)), up(pa_hi.max(pb_hi)), dk, dk]
            };
            let (r, wrap) = cur.eval_interval_wrap(c(0), c(1), c(2));
            if phase == Phase::Segment {
                if r[0] > 0.0 || r[1] < 0.0 {
                    continue;
                }
                slope = [r[2], r[3]];
                let monotone = r[2] > 0.0 || r[3] < 0.0;
                if monotone || b - a <= eps_t {
                    if ia != ib {
                        phase = Phase::Bisect;
                        steps = 0;
                    } else if !monotone && r[2].is_finite() && r[3].is_finite() {
                        // Shorter than ε, the same sign at both ends, F continuous and
                        // turning in between: the sign at the middle and the mean-value
                        // test decide it, else it may hold a sliver thinner than f32
                        // resolves (a letter's corner in prospero was 0.3 ε thick),
                        // for the CPU. (A piece holding a jump of F, a mod's wrap or
                        // an `if`, is decided by its end signs: f32 places the jump no
                        // closer.)
                        short_seg = true;
                        m = a + (b - a) * 0.5;
                        pt = m;
                        phase = Phase::Split;
                    }
                } else {
                    short_seg = false;
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
                (Phase::Split, None) if short_seg => return TapeHit::Undecided,
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
                (Phase::WalkEnd, None)
                    if !retried_end && run.is_some_and(|r| t1 - eps_t > r.0) && t1 - eps_t < t1 =>
                {
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
                    if walk.is_some() {
                        (last_in, tw) = (ia0, t0);
                        phase = Phase::Walk;
                    } else {
                        phase = Phase::End;
                        pt = t1;
                    }
                }
                (Phase::RunEnd | Phase::WalkEnd, Some(inside)) => {
                    // The run ends here (at tw, or at t1 ending the walk); after RunEnd
                    // the next starts here (its cell examined again).
                    let (ra, _, r_in) = run.take().expect("a run ends");
                    let next = phase == Phase::RunEnd;
                    st.push((ra, if next { tw } else { t1 }, r_in, inside));
                    *loops += 1;
                    run = next.then_some((tw, pending, inside));
                    last_in = inside;
                    phase = Phase::Segment;
                }
                (Phase::Walk, _) => unreachable!("the walk continues above"),
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
                    if short_seg && inside == ia {
                        return TapeHit::Undecided;
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
    /// The next cell of the walk (the kernel's 7).
    Walk,
    /// The sign where a run meets a run of another tape (8).
    RunEnd,
    /// The sign at t1 ending the last run (9).
    WalkEnd,
}

/// A ray's walk through a [`WalkGrid`] (the kernel's, bit for bit): the ray in cell
/// units g0 + t·gd, the cell, the t of its next face per axis.
struct Walk<'g> {
    grid: &'g WalkGrid,
    g0: Vec3,
    gd: Vec3,
    c: [i32; 3],
    nx: [f32; 3],
}

impl<'g> Walk<'g> {
    /// The walk from t0, or None where the ray's magnitudes in cells pass [`WALK_REACH`]
    /// (the grid's signs and tapes might not hold where its rounding puts a point).
    fn new(grid: &'g WalkGrid, o: Vec3, d: Vec3, t0: f32) -> Option<Self> {
        let (lo, scale) = (Vec3::from(grid.lo), Vec3::from(grid.scale));
        let g0 = (o - lo) * scale;
        let gd = d * scale;
        let mag = g0.x.abs().max(g0.y.abs()).max(g0.z.abs()) + grid.reach;
        // NaN fails it too.
        (mag <= WALK_REACH).then_some(())?;
        let u = g0 + t0 * gd;
        let top = (grid.cells.n - 1) as f32;
        let c = [u.x, u.y, u.z].map(|v| v.floor().max(0.0).min(top) as i32);
        let nx = [0, 1, 2].map(|k| face(c[k], g0[k], gd[k]));
        Some(Self {
            grid,
            g0,
            gd,
            c,
            nx,
        })
    }

    /// The cell's word: its tape's index, or `NO_TAPE`, [`INSIDE`].
    fn cell(&self) -> u32 {
        let n = self.grid.cells.n;
        let [x, y, z] = self.c.map(|v| v as usize);
        self.grid.cells.cell[(z * n + y) * n + x]
    }

    fn tape(&self, j: u32) -> &'g GpuTape {
        &self.grid.cells.tapes[j as usize]
    }

    /// To the next cell along axis `ax`; false where that leaves the grid.
    fn step(&mut self, ax: usize) -> bool {
        self.c[ax] += if self.gd[ax] > 0.0 { 1 } else { -1 };
        if self.c[ax] < 0 || self.c[ax] >= self.grid.cells.n as i32 {
            return false;
        }
        self.nx[ax] = face(self.c[ax], self.g0[ax], self.gd[ax]);
        true
    }
}

/// The t where the walk leaves cell c along an axis (∞ where the ray does not move
/// along it), from the ray in cell units: computed afresh, not accumulated.
fn face(c: i32, g0: f32, gd: f32) -> f32 {
    if gd == 0.0 {
        return f32::INFINITY;
    }
    ((c + i32::from(gd > 0.0)) as f32 - g0) / gd
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
