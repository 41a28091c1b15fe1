//! Expression tapes on the GPU (GPU.md §6.2): frep's register bytecode
//! ([`frep::Bytecode`]) run by a WGSL interpreter in two flavours, F at a point and F with
//! dF/dt as outward-rounded intervals, and their CPU f32 twins, equal bit for bit on
//! lavapipe (GPU.md §3.5). The ray tracer built on them is [`crate::tape_trace`].
//!
//! **Outward rounding** (GPU.md §6.2.3). WGSL has no rounding modes, so each interval
//! result is widened by whole ulps with bit steps: 1 ulp after `+ − ×` and `square`, 4 after
//! `/` and `sqrt`, 16 after `powi`; `neg`, `abs`, `min`, `max` are exact. A step from zero
//! or a subnormal goes to the smallest normal f32 (a GPU may flush subnormals). With
//! round-to-nearest (lavapipe) half an ulp would do; the margin covers WGSL's looser
//! `/` and `sqrt` on real GPUs (unverified there).
//!
//! **Ops.** Every operation of frep's bytecode. var, const, `powi` with |n| ≤ 255
//! ([`MAX_POWI`]; 1/xⁿ for n < 0, as compiler-rt's `__powisf2`), neg, abs, sqrt, square,
//! `+ − × /`, min, max, and `sin`, `cos` and `atan2` (HyperFun's gyroid and twist,
//! smooth_blob): WGSL's builtins are not libm's, so these are polynomials written alike
//! in WGSL and Rust ([`sin_cos`], [`crate::env::atan2`]), within a few ulps of libm for
//! |x| < 10⁴. Their intervals are their values at the ends, widened by the polynomials'
//! error bound ([`TRIG_ERR`]), and ±1 where an extremum lies inside (sin, cos), or by the
//! corners of the box where it neither holds the origin nor crosses the cut along the
//! negative x axis, else [−π, π] (atan2). exp, ln, tan, asin, acos, atan, floor, ceil,
//! round, mod, compare, and, or and not are [`crate::elementary`]'s.

use crate::elementary as el;
use crate::r_bound;
use frep::bytecode::{Bytecode, Instr, IMM};
use frep::{BinaryOp, UnaryOp};
use std::fmt;

/// The interpreter's WGSL (`eval_point`, `eval_interval`, interval helpers,
/// [`crate::elementary`]'s operations and [`crate::r_bound`]'s narrowing); see
/// [`crate::tape_trace::TapeSolid::scene_wgsl`] for the constants it needs, [`tape_consts_wgsl`] among them.
pub const TAPE_WGSL: &str = concat!(
    include_str!("shaders/tape.wgsl"),
    include_str!("shaders/elementary.wgsl"),
    include_str!("shaders/r_bound.wgsl")
);

/// The interpreter's opcodes (`OP_VAR`, `OP_ADD`, …: its `case` labels) and the
/// operand register that reads the immediate (`IMM`), from frep's encoding
/// ([`frep::bytecode`]), so that no shader repeats them by hand.
pub fn tape_consts_wgsl() -> String {
    use frep::bytecode::{binary_opcode, unary_opcode, Op};
    let ops = [
        ("OP_VAR", Op::Var as u8),
        ("OP_CONST", Op::Const as u8),
        ("OP_POWI", Op::PowI as u8),
        ("OP_NEG", unary_opcode(UnaryOp::Neg)),
        ("OP_ABS", unary_opcode(UnaryOp::Abs)),
        ("OP_SQRT", unary_opcode(UnaryOp::Sqrt)),
        ("OP_SQUARE", unary_opcode(UnaryOp::Square)),
        ("OP_ADD", binary_opcode(BinaryOp::Add)),
        ("OP_SUB", binary_opcode(BinaryOp::Sub)),
        ("OP_MUL", binary_opcode(BinaryOp::Mul)),
        ("OP_DIV", binary_opcode(BinaryOp::Div)),
        ("OP_MIN", binary_opcode(BinaryOp::Min)),
        ("OP_MAX", binary_opcode(BinaryOp::Max)),
        ("OP_SIN", unary_opcode(UnaryOp::Sin)),
        ("OP_COS", unary_opcode(UnaryOp::Cos)),
        ("OP_ATAN2", binary_opcode(BinaryOp::Atan2)),
        ("OP_EXP", unary_opcode(UnaryOp::Exp)),
        ("OP_LN", unary_opcode(UnaryOp::Ln)),
        ("OP_TAN", unary_opcode(UnaryOp::Tan)),
        ("OP_ASIN", unary_opcode(UnaryOp::Asin)),
        ("OP_ACOS", unary_opcode(UnaryOp::Acos)),
        ("OP_ATAN", unary_opcode(UnaryOp::Atan)),
        ("OP_FLOOR", unary_opcode(UnaryOp::Floor)),
        ("OP_CEIL", unary_opcode(UnaryOp::Ceil)),
        ("OP_ROUND", unary_opcode(UnaryOp::Round)),
        ("OP_NOT", unary_opcode(UnaryOp::Not)),
        ("OP_MOD", binary_opcode(BinaryOp::Mod)),
        ("OP_COMPARE", binary_opcode(BinaryOp::Compare)),
        ("OP_AND", binary_opcode(BinaryOp::And)),
        ("OP_OR", binary_opcode(BinaryOp::Or)),
        ("IMM", IMM),
    ];
    ops.iter()
        .map(|(name, v)| format!("const {name}: u32 = {v}u;\n"))
        .collect()
}

/// The largest |n| of a `powi` the interpreter unrolls (eight bits); frep's bytecode
/// holds larger ones only from a model raising to a power beyond 255, refused.
pub const MAX_POWI: i32 = 255;

/// Why a bytecode cannot run on the GPU interpreter.
#[derive(Clone, Debug, PartialEq)]
pub struct Unsupported {
    /// Index of the instruction.
    pub at: usize,
    /// The instruction.
    pub instr: Instr,
}

impl fmt::Display for Unsupported {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "instruction {} ({:?}) is not supported by the GPU tape",
            self.at, self.instr
        )
    }
}

impl std::error::Error for Unsupported {}

/// A bytecode the GPU interpreter runs: its words (GPU.md §5.2's `GpuTapeOp`s) and
/// decoded instructions.
#[derive(Clone, Debug)]
pub struct GpuTape {
    words: Vec<u32>,
    registers: usize,
    instrs: Vec<Instr>,
    /// Each instruction's R-function mark ([`crate::r_bound`]), also in `words`.
    marks: Vec<Option<r_bound::Mark>>,
}

impl GpuTape {
    /// The tape of `code`, or the first instruction the interpreter lacks.
    pub fn new(code: &Bytecode) -> Result<Self, Unsupported> {
        let instrs: Vec<Instr> = (0..code.len())
            .map(|k| code.decode(k).expect("a checked program"))
            .collect();
        for (at, &instr) in instrs.iter().enumerate() {
            if let Instr::PowI(_, _, n) = instr {
                if !(-MAX_POWI..=MAX_POWI).contains(&n) {
                    return Err(Unsupported { at, instr });
                }
            }
        }
        let marks = r_bound::marks(&instrs);
        let mut words = code.words().to_vec();
        for (k, m) in marks.iter().enumerate() {
            if let Some(m) = m {
                debug_assert_eq!(words[2 * k + 1], 0, "a register-register sum");
                words[2 * k + 1] = m.word();
            }
        }
        Ok(Self {
            words,
            registers: code.registers(),
            instrs,
            marks,
        })
    }

    /// The words, two per instruction (the kernel's `tape` binding).
    pub fn words(&self) -> &[u32] {
        &self.words
    }

    /// Whether the tape has one of [`crate::elementary`]'s operations. The kernel's
    /// `ELEMENTARY` constant: without them their cases compile to nothing (Mesa drops a
    /// constant-false branch before its costly back end), so a scene that does not use
    /// them compiles as fast as before they existed.
    pub fn elementary(&self) -> bool {
        self.instrs.iter().any(|i| match *i {
            Instr::Unary(_, op, _) => !matches!(
                op,
                UnaryOp::Neg
                    | UnaryOp::Abs
                    | UnaryOp::Sqrt
                    | UnaryOp::Square
                    | UnaryOp::Sin
                    | UnaryOp::Cos
            ),
            Instr::Binary(_, op, ..) => matches!(
                op,
                BinaryOp::Mod | BinaryOp::Compare | BinaryOp::And | BinaryOp::Or
            ),
            _ => false,
        })
    }

    /// Whether the tape has an R-function the kernel narrows ([`crate::r_bound`]): the
    /// kernel's `RBOUND` constant, false to compile the narrowing out.
    pub fn r_functions(&self) -> bool {
        self.marks.iter().any(Option::is_some)
    }

    /// Registers the tape uses.
    pub fn registers(&self) -> usize {
        self.registers
    }

    /// Number of instructions.
    pub fn len(&self) -> usize {
        self.instrs.len()
    }

    /// Loop iterations of one evaluation in the kernel: four instructions per iteration
    /// (GPU.md §6.2.2).
    pub fn eval_loops(&self) -> u32 {
        self.instrs.len().div_ceil(4) as u32
    }

    /// Whether the tape is empty (never, for a compiled expression).
    pub fn is_empty(&self) -> bool {
        self.instrs.is_empty()
    }

    /// F at p: the twin of the kernel's `eval_point`, equal to [`Bytecode::eval_f32`] but
    /// for `sin`, `cos` and `atan2` (polynomials, a few ulps from libm's).
    pub fn eval_point(&self, p: [f32; 3]) -> f32 {
        let mut r = [0f32; 256];
        let mut out = 0;
        for &ins in &self.instrs {
            let (o, v) = match ins {
                Instr::Var(o, v) => (o, p[v as usize]),
                Instr::Const(o, c) => (o, c),
                Instr::PowI(o, a, n) => (o, powi_signed(r[a as usize], n)),
                Instr::Unary(o, op, a) => {
                    let a = r[a as usize];
                    let v = match op {
                        UnaryOp::Neg => -a,
                        UnaryOp::Abs => a.abs(),
                        UnaryOp::Sqrt => a.sqrt(),
                        UnaryOp::Square => a * a,
                        UnaryOp::Sin => sin_cos(a, false),
                        UnaryOp::Cos => sin_cos(a, true),
                        UnaryOp::Exp => el::exp(a),
                        UnaryOp::Ln => el::ln(a),
                        UnaryOp::Tan => el::tan(a),
                        UnaryOp::Asin => el::asin(a),
                        UnaryOp::Acos => el::acos(a),
                        UnaryOp::Atan => el::atan(a),
                        UnaryOp::Floor => a.floor(),
                        UnaryOp::Ceil => a.ceil(),
                        UnaryOp::Round => el::round(a),
                        UnaryOp::Not => el::not(a),
                    };
                    (o, v)
                }
                Instr::Binary(o, op, a, b, imm) => {
                    let get = |x: u8| if x == IMM { imm } else { r[x as usize] };
                    let (a, b) = (get(a), get(b));
                    let v = match op {
                        BinaryOp::Add => a + b,
                        BinaryOp::Sub => a - b,
                        BinaryOp::Mul => a * b,
                        BinaryOp::Div => a / b,
                        BinaryOp::Min => a.min(b),
                        BinaryOp::Max => a.max(b),
                        BinaryOp::Atan2 => crate::env::atan2(a, b),
                        BinaryOp::Mod => el::modulo(a, b),
                        BinaryOp::Compare => el::compare(a, b),
                        BinaryOp::And => el::and(a, b),
                        BinaryOp::Or => el::or(a, b),
                    };
                    (o, v)
                }
            };
            r[o as usize] = v;
            out = o;
        }
        r[out as usize]
    }

    /// F and dF/dt over a box: the twin of the kernel's `eval_interval`. Each coordinate
    /// and the result is `[lo, hi, dlo, dhi]`; NaN bounds mean unknown.
    pub fn eval_interval(&self, x: [f32; 4], y: [f32; 4], z: [f32; 4]) -> [f32; 4] {
        self.eval_interval_wrap(x, y, z).0
    }

    /// [`Self::eval_interval`] and where along the box's direction the nearest wrap of a
    /// `mod` lies, as a fraction of the box ([`crate::elementary::wrap_fraction`], the
    /// least over the tape's `mod`s; 2 where there is none): where the tracer splits a
    /// segment (the kernel's `wrap_hint`).
    pub fn eval_interval_wrap(&self, x: [f32; 4], y: [f32; 4], z: [f32; 4]) -> ([f32; 4], f32) {
        let mut wrap = 2f32;
        let mut side = [[f32::NEG_INFINITY, f32::INFINITY]; r_bound::SLOTS];
        let mut r = [[0f32; 4]; 256];
        let mut out = 0;
        let v2 = |a: [f32; 4]| [a[0], a[1]];
        let d2 = |a: [f32; 4]| [a[2], a[3]];
        for (&ins, &mark) in self.instrs.iter().zip(&self.marks) {
            let (o, v, d) = match ins {
                Instr::Var(o, k) => {
                    let c = [x, y, z][k as usize];
                    (o, v2(c), d2(c))
                }
                Instr::Const(o, c) => (o, [c, c], [0.0, 0.0]),
                Instr::PowI(o, a, n) => {
                    let a = r[a as usize];
                    let v = i_powi_signed(v2(a), n);
                    let d = if n != 0 {
                        let nf = n as f32;
                        i_mul(i_mul([nf, nf], i_powi_signed(v2(a), n - 1)), d2(a))
                    } else {
                        [0.0, 0.0]
                    };
                    (o, v, d)
                }
                Instr::Unary(o, op, a) => {
                    let a = r[a as usize];
                    let (av, ad) = (v2(a), d2(a));
                    let (v, d) = match op {
                        UnaryOp::Neg => (i_neg(av), i_neg(ad)),
                        UnaryOp::Abs => {
                            let d = if a[0] >= 0.0 {
                                ad
                            } else if a[1] <= 0.0 {
                                i_neg(ad)
                            } else {
                                hull(ad, i_neg(ad))
                            };
                            (i_abs(av), d)
                        }
                        UnaryOp::Sqrt => {
                            let v = i_sqrt(av);
                            (v, i_div(ad, [2.0 * v[0], 2.0 * v[1]]))
                        }
                        UnaryOp::Square => (i_square(av), i_mul([2.0 * a[0], 2.0 * a[1]], ad)),
                        UnaryOp::Sin => (i_sin_cos(av, false), i_mul(i_sin_cos(av, true), ad)),
                        UnaryOp::Cos => {
                            (i_sin_cos(av, true), i_mul(i_neg(i_sin_cos(av, false)), ad))
                        }
                        _ => el::unary(op, av, ad).expect("elementary's operation"),
                    };
                    (o, v, d)
                }
                Instr::Binary(o, op, a, b, imm) => {
                    let get = |x: u8| {
                        if x == IMM {
                            [imm, imm, 0.0, 0.0]
                        } else {
                            r[x as usize]
                        }
                    };
                    let (a, b) = (get(a), get(b));
                    let (av, ad, bv, bd) = (v2(a), d2(a), v2(b), d2(b));
                    let (v, d) = match op {
                        BinaryOp::Add | BinaryOp::Sub => {
                            let v = if op == BinaryOp::Add {
                                (i_add(av, bv), i_add(ad, bd))
                            } else {
                                (i_sub(av, bv), i_sub(ad, bd))
                            };
                            match mark {
                                Some(r_bound::Mark::Stash { slot, union }) => {
                                    side[slot as usize] = r_bound::corners(av, bv, union);
                                    v
                                }
                                Some(r_bound::Mark::Narrow { slot }) => {
                                    (r_bound::narrow(v.0, side[slot as usize]), v.1)
                                }
                                None => v,
                            }
                        }
                        BinaryOp::Mul => (i_mul(av, bv), i_add(i_mul(ad, bv), i_mul(av, bd))),
                        BinaryOp::Div => {
                            let v = i_div(av, bv);
                            (v, i_div(i_sub(ad, i_mul(v, bd)), bv))
                        }
                        BinaryOp::Min => {
                            if a[1] <= b[0] {
                                (av, ad)
                            } else if b[1] <= a[0] {
                                (bv, bd)
                            } else {
                                (i_min(av, bv), hull(ad, bd))
                            }
                        }
                        BinaryOp::Max => {
                            if a[0] >= b[1] {
                                (av, ad)
                            } else if b[0] >= a[1] {
                                (bv, bd)
                            } else {
                                (i_max(av, bv), hull(ad, bd))
                            }
                        }
                        // d atan2(a, b) = (b·da − a·db)/(a² + b²).
                        BinaryOp::Atan2 => (
                            i_atan2(av, bv),
                            i_div(
                                i_sub(i_mul(bv, ad), i_mul(av, bd)),
                                i_add(i_square(av), i_square(bv)),
                            ),
                        ),
                        BinaryOp::Mod => {
                            wrap = wrap.min(el::wrap_fraction(av, ad, bv));
                            el::i_mod(av, ad, bv, bd)
                        }
                        BinaryOp::Compare => el::i_compare(av, bv),
                        BinaryOp::And => el::i_and_or(av, ad, bv, bd, false),
                        BinaryOp::Or => el::i_and_or(av, ad, bv, bd, true),
                    };
                    (o, v, d)
                }
            };
            r[o as usize] = [v[0], v[1], d[0], d[1]];
            out = o;
        }
        (r[out as usize], wrap)
    }

    /// Bounds of F over the box `lo..hi` (the value part of [`GpuTape::eval_interval`]).
    pub fn eval_box(&self, lo: [f32; 3], hi: [f32; 3]) -> (f32, f32) {
        let c = |k: usize| [lo[k], hi[k], 0.0, 0.0];
        let r = self.eval_interval(c(0), c(1), c(2));
        (r[0], r[1])
    }
}

/// An interval (lo, hi).
pub(crate) type I2 = [f32; 2];
pub(crate) const NAN2: I2 = [f32::NAN, f32::NAN];

/// |x| below which [`sin_cos`] reduces exactly enough (k·π/2 with k < 2¹⁶, the high
/// part of π/2 having 8 significant bits); past it, NaN (and [−1, 1] for intervals).
pub const TRIG_MAX: f32 = 1.0e4;

/// A bound on the error of [`sin_cos`] (reduction below 10⁻⁷ at |x| < 10⁴, Taylor
/// truncation 3·10⁻⁸, Horner's rounding a few ulps of 1) and of [`crate::env::atan2`]
/// (two ulps of π): the widening of their intervals.
pub const TRIG_ERR: f32 = 1.0e-6;

/// sin x (`cos` false) or cos x for |x| < [`TRIG_MAX`], else NaN: the nearest quarter
/// turn k·π/2 taken out in two parts (Cody & Waite 1980), the rest to
/// [`crate::light::sincos_small`]. The kernel's `t_sin_cos`, operation for operation.
pub fn sin_cos(x: f32, cos: bool) -> f32 {
    // (NaN fails the test too.)
    let reduced = x.abs() < TRIG_MAX;
    if !reduced {
        return f32::NAN;
    }
    let k = (x * f32::from_bits(0x3f22_f983) + 0.5).floor();
    let r = (x - k * f32::from_bits(0x3fc9_0000)) - k * f32::from_bits(0x39fd_aa22);
    let (s, c) = crate::light::sincos_small(r);
    let q = (k as i32).wrapping_add(i32::from(cos)) & 3;
    match q {
        0 => s,
        1 => c,
        2 => -s,
        _ => -c,
    }
}

/// sin (`cos` false) or cos over `a`: the values at the ends widened by [`TRIG_ERR`],
/// reaching 1 (−1) where a maximum (minimum) lies within the ends (widened by the same
/// margin), clamped to [−1, 1]; [−1, 1] for a span of 2π or more or past [`TRIG_MAX`].
pub(crate) fn i_sin_cos(a: I2, cos: bool) -> I2 {
    if any_nan(a) {
        return NAN2;
    }
    let big = a[0].abs().max(a[1].abs());
    let narrow = a[1] - a[0] < 6.0 && big < TRIG_MAX;
    if !narrow {
        return [-1.0, 1.0];
    }
    let (va, vb) = (sin_cos(a[0], cos), sin_cos(a[1], cos));
    let mut lo = va.min(vb) - TRIG_ERR;
    let mut hi = va.max(vb) + TRIG_ERR;
    // Maxima at p + 2πm, minima at p + π + 2πm (p = π/2 for sin, 0 for cos).
    let two_pi = f32::from_bits(0x40c9_0fdb);
    let margin = TRIG_ERR * (1.0 + big);
    let p = if cos {
        0.0
    } else {
        f32::from_bits(0x3fc9_0fdb)
    };
    let holds = |p: f32| {
        let m = ((a[0] - margin - p) / two_pi).ceil();
        p + two_pi * m <= a[1] + margin
    };
    if holds(p) {
        hi = 1.0;
    }
    if holds(p + f32::from_bits(0x4049_0fdb)) {
        lo = -1.0;
    }
    [lo.max(-1.0), hi.min(1.0)]
}

/// atan2 over the box y × x: [−π, π] where the box meets x ≤ 0 with y spanning 0 (the
/// origin or the cut), else the corners' angles widened by [`TRIG_ERR`] (over a box
/// that holds neither, the angle is continuous and its extremes lie at corners).
fn i_atan2(y: I2, x: I2) -> I2 {
    if any_nan(y) || any_nan(x) {
        return NAN2;
    }
    let pi = f32::from_bits(0x4049_0fdb) + TRIG_ERR;
    if x[0] <= 0.0 && y[0] <= 0.0 && y[1] >= 0.0 {
        return [-pi, pi];
    }
    let c = [
        crate::env::atan2(y[0], x[0]),
        crate::env::atan2(y[0], x[1]),
        crate::env::atan2(y[1], x[0]),
        crate::env::atan2(y[1], x[1]),
    ];
    [
        rmin(rmin(c[0], c[1]), rmin(c[2], c[3])) - TRIG_ERR,
        rmax(rmax(c[0], c[1]), rmax(c[2], c[3])) + TRIG_ERR,
    ]
}

/// x^n as compiler-rt's `__powisf2` computes it (Rust's `f32::powi`), n ≤ [`MAX_POWI`]:
/// square and multiply from the lowest bit.
pub fn powi(x: f32, n: u32) -> f32 {
    let (mut a, mut r) = (x, 1f32);
    for bit in 0..8 {
        if n & (1 << bit) != 0 {
            r *= a;
        }
        if n < 2 << bit {
            return r;
        }
        a *= a;
    }
    r
}

/// x^n for |n| ≤ [`MAX_POWI`]: 1/x^|n| for n < 0, as `__powisf2` does.
pub fn powi_signed(x: f32, n: i32) -> f32 {
    let r = powi(x, n.unsigned_abs());
    if n < 0 {
        1.0 / r
    } else {
        r
    }
}

/// The next f32 above x; zero and subnormals step to the smallest normal (GPU.md §6.2.3).
pub fn up(x: f32) -> f32 {
    if x.is_nan() || x == f32::INFINITY {
        return x;
    }
    if (-f32::MIN_POSITIVE..f32::MIN_POSITIVE).contains(&x) {
        return f32::MIN_POSITIVE;
    }
    let b = x.to_bits();
    f32::from_bits(if x > 0.0 { b + 1 } else { b - 1 })
}

/// The next f32 below x (`-up(-x)`).
pub fn down(x: f32) -> f32 {
    -up(-x)
}

fn up4(x: f32) -> f32 {
    up(up(up(up(x))))
}

fn down4(x: f32) -> f32 {
    down(down(down(down(x))))
}

/// WGSL's `min` after the NaN checks: Rust's `f32::min`.
fn rmin(a: f32, b: f32) -> f32 {
    a.min(b)
}

fn rmax(a: f32, b: f32) -> f32 {
    a.max(b)
}

pub(crate) fn any_nan(a: I2) -> bool {
    a[0].is_nan() || a[1].is_nan()
}

/// `[lo, hi]` widened by one ulp each way.
pub fn w1(lo: f32, hi: f32) -> I2 {
    [down(lo), up(hi)]
}

fn w4(lo: f32, hi: f32) -> I2 {
    [down4(lo), up4(hi)]
}

/// Interval sum.
pub fn i_add(a: I2, b: I2) -> I2 {
    w1(a[0] + b[0], a[1] + b[1])
}

pub(crate) fn i_sub(a: I2, b: I2) -> I2 {
    w1(a[0] - b[1], a[1] - b[0])
}

fn i_neg(a: I2) -> I2 {
    [-a[1], -a[0]]
}

/// Interval product (a NaN product, 0·∞, is ignored).
pub fn i_mul(a: I2, b: I2) -> I2 {
    let p = [a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1]];
    w1(
        rmin(rmin(p[0], p[1]), rmin(p[2], p[3])),
        rmax(rmax(p[0], p[1]), rmax(p[2], p[3])),
    )
}

pub(crate) fn i_div(a: I2, b: I2) -> I2 {
    if b[0] <= 0.0 && b[1] >= 0.0 {
        return [f32::NEG_INFINITY, f32::INFINITY];
    }
    let p = [a[0] / b[0], a[0] / b[1], a[1] / b[0], a[1] / b[1]];
    w4(
        rmin(rmin(p[0], p[1]), rmin(p[2], p[3])),
        rmax(rmax(p[0], p[1]), rmax(p[2], p[3])),
    )
}

fn i_abs(a: I2) -> I2 {
    if a[0] >= 0.0 {
        a
    } else if a[1] <= 0.0 {
        i_neg(a)
    } else {
        [0.0, rmax(-a[0], a[1])]
    }
}

pub(crate) fn i_square(a: I2) -> I2 {
    if any_nan(a) {
        return NAN2;
    }
    let b = i_abs(a);
    w1(b[0] * b[0], b[1] * b[1])
}

pub(crate) fn i_sqrt(a: I2) -> I2 {
    if any_nan(a) || a[1] < 0.0 {
        return NAN2;
    }
    w4(rmax(a[0], 0.0).sqrt(), a[1].sqrt())
}

fn i_powi(a: I2, n: u32) -> I2 {
    if any_nan(a) {
        return NAN2;
    }
    if n == 0 {
        return [1.0, 1.0];
    }
    let b = if n & 1 == 0 { i_abs(a) } else { a };
    let (lo, hi) = (powi(b[0], n), powi(b[1], n));
    if n <= 15 {
        return [down4(down4(down4(down4(lo)))), up4(up4(up4(up4(hi))))];
    }
    // n − 1 roundings: a relative error below (n − 1)·2⁻²⁴, widened by n·2⁻²³ (exact
    // factors) and an ulp.
    let f = n as f32 * f32::from_bits(0x3400_0000);
    let (lo_f, hi_f) = (
        if lo >= 0.0 { 1.0 - f } else { 1.0 + f },
        if hi >= 0.0 { 1.0 + f } else { 1.0 - f },
    );
    [down(lo * lo_f), up(hi * hi_f)]
}

/// x^n over a for |n| ≤ [`MAX_POWI`]: 1/a^|n| for n < 0.
fn i_powi_signed(a: I2, n: i32) -> I2 {
    let v = i_powi(a, n.unsigned_abs());
    if n < 0 {
        i_div([1.0, 1.0], v)
    } else {
        v
    }
}

fn i_min(a: I2, b: I2) -> I2 {
    [rmin(a[0], b[0]), rmin(a[1], b[1])]
}

fn i_max(a: I2, b: I2) -> I2 {
    [rmax(a[0], b[0]), rmax(a[1], b[1])]
}

pub(crate) fn hull(a: I2, b: I2) -> I2 {
    if any_nan(a) || any_nan(b) {
        return NAN2;
    }
    [a[0].min(b[0]), a[1].max(b[1])]
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn steps_skip_subnormals() {
        assert_eq!(up(0.0), f32::MIN_POSITIVE);
        assert_eq!(up(-0.0), f32::MIN_POSITIVE);
        assert_eq!(down(0.0), -f32::MIN_POSITIVE);
        assert_eq!(up(1.0), 1.0f32.next_up());
        assert_eq!(down(-1.0), (-1.0f32).next_down());
        assert_eq!(up(f32::MAX), f32::INFINITY);
        assert_eq!(up(f32::NEG_INFINITY), f32::MIN);
        assert!(up(f32::NAN).is_nan());
    }

    /// A small deterministic generator for the tests here and in [`crate::elementary`]
    /// and [`crate::r_bound`].
    pub(crate) fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn sin_cos_are_within_their_bound_of_libm() {
        let mut seed = 3;
        let mut worst = 0f64;
        for k in 0..200_000 {
            let scale = [1.0, 10.0, 100.0, 9_999.0][k % 4];
            let x = ((lcg(&mut seed) * 2.0 - 1.0) * scale) as f32;
            let xd = f64::from(x);
            for (cos, want) in [(false, xd.sin()), (true, xd.cos())] {
                let e = (f64::from(sin_cos(x, cos)) - want).abs();
                worst = worst.max(e);
                assert!(e <= f64::from(TRIG_ERR) / 4.0, "{x}: cos {cos}: {e:e}");
            }
        }
        assert!(sin_cos(1e4, false).is_nan() && sin_cos(f32::NAN, true).is_nan());
        eprintln!("sin, cos: largest error {worst:e}");
    }

    #[test]
    fn atan2_is_within_its_bound_of_libm() {
        let mut seed = 4;
        for _ in 0..200_000 {
            let y = ((lcg(&mut seed) * 2.0 - 1.0) * 10.0) as f32;
            let x = ((lcg(&mut seed) * 2.0 - 1.0) * 10.0) as f32;
            let e = (f64::from(crate::env::atan2(y, x)) - f64::from(y).atan2(f64::from(x))).abs();
            assert!(e <= f64::from(TRIG_ERR) / 2.0, "atan2({y}, {x}): {e:e}");
        }
    }

    /// The intervals hold the f64 function at points of random intervals and boxes
    /// (wide, narrow, around extrema, across the cut), and their derivative lanes hold
    /// the f64 derivative.
    #[test]
    fn trig_intervals_are_sound() {
        let mut seed = 5;
        for k in 0..50_000 {
            let scale = [0.01, 1.0, 5.0, 100.0][k % 4];
            let c = (lcg(&mut seed) * 2.0 - 1.0) * [2.0, 10.0, 1_000.0][k % 3];
            let (a, b) = (c as f32, (c + lcg(&mut seed) * scale) as f32);
            if b < a {
                continue;
            }
            for cos in [false, true] {
                let v = i_sin_cos([a, b], cos);
                for j in 0..=16 {
                    let t = f64::from(a) + (f64::from(b) - f64::from(a)) * f64::from(j) / 16.0;
                    let f = if cos { t.cos() } else { t.sin() };
                    assert!(
                        f64::from(v[0]) <= f && f <= f64::from(v[1]),
                        "[{a}, {b}] cos {cos}: {v:?} misses {f} at {t}"
                    );
                }
            }
            let y = [a, b];
            let x0 = (lcg(&mut seed) * 2.0 - 1.0) as f32 * 3.0;
            let x = [x0, x0 + (lcg(&mut seed) as f32) * 0.5];
            let v = i_atan2(y, x);
            for i in 0..=8 {
                for j in 0..=8 {
                    let yy =
                        f64::from(y[0]) + (f64::from(y[1]) - f64::from(y[0])) * f64::from(i) / 8.0;
                    let xx =
                        f64::from(x[0]) + (f64::from(x[1]) - f64::from(x[0])) * f64::from(j) / 8.0;
                    let f = yy.atan2(xx);
                    assert!(
                        f64::from(v[0]) <= f && f <= f64::from(v[1]),
                        "atan2 over {y:?} × {x:?}: {v:?} misses {f}"
                    );
                }
            }
        }
    }

    #[test]
    fn powi_is_rusts() {
        for n in -MAX_POWI..=MAX_POWI {
            for x in [0.3f32, -1.7, 3.1e7, 1.0e-5, -2.5, 1.001, -0.999] {
                // As `Bytecode::eval_f32` calls it, with n known only at run time (a
                // constant n lets LLVM expand the power its own way).
                let want = std::hint::black_box(x).powi(std::hint::black_box(n));
                let got = powi_signed(x, n);
                assert!(
                    got.to_bits() == want.to_bits(),
                    "{x}^{n}: {got} against {want}"
                );
            }
        }
    }

    /// x^n's interval holds the f64 power at its ends and between them, for every n.
    #[test]
    fn powi_intervals_are_sound() {
        let mut seed = 6;
        for n in -MAX_POWI..=MAX_POWI {
            for _ in 0..40 {
                let c = (lcg(&mut seed) * 2.0 - 1.0) * 1.5;
                let a = [c as f32, (c + lcg(&mut seed) * 0.3) as f32];
                let v = i_powi_signed(a, n);
                if any_nan(v) {
                    continue;
                }
                for j in 0..=8 {
                    let x = f64::from(a[0]) + (f64::from(a[1]) - f64::from(a[0])) * j as f64 / 8.0;
                    let f = x.powi(n);
                    if f.is_finite() {
                        let inside = f64::from(v[0]) <= f && f <= f64::from(v[1]);
                        assert!(inside, "{a:?}^{n}: {v:?} misses {f} at {x}");
                    }
                }
            }
        }
    }
}
