//! R-functions in GPU tapes: the CPU's [`frep::Scalar::r_bound`] for the kernel's
//! interval evaluation. An R-union a + b + √(a² + b²) (or R-intersection, − √) is
//! nondecreasing in a and b, so over a box its range is [f(a.lo, b.lo), f(a.hi, b.hi)];
//! plain interval arithmetic sees a and b twice each and, where one is large (a part
//! far away, F ≈ −100 cancelled by the root), gives a bound 10⁻³ wide at a point, which
//! leaves the ray to the CPU.
//!
//! frep's register bytecode has no such operation, and a and b's registers are reused
//! before the final sum. So [`marks`] finds the pattern by value numbering, as frep's
//! `r_pattern` finds it among nodes (a + b first, then the root of a² + b², operands of
//! each sum in either order), and marks two instructions in their free immediate word
//! (both operands are registers): the sum a + b, where a and b are at hand, *stashes*
//! the corner values in one of [`SLOTS`] side registers, and the final ± *narrows* its
//! interval to them, as the CPU does (kept where the two cross). The kernel reads the
//! marks (`r_mark` in `shaders/tape.wgsl`); the twin reads [`Mark`]s.

use crate::tape::{i_add, i_div, i_mul, i_sqrt, i_square, i_sub, I2};
use frep::bytecode::{Instr, IMM};
use frep::{BinaryOp, UnaryOp};

/// Side registers: R-functions narrowed per tape; later ones are evaluated plainly.
pub const SLOTS: usize = 16;

/// The mark of one instruction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mark {
    /// The sum a + b of an R-function: store its corners.
    Stash {
        /// The side register.
        slot: u8,
        /// Whether the R-function is the union (+ √), else the intersection (− √).
        union: bool,
    },
    /// The R-function's final ±: narrow to the corners.
    Narrow {
        /// The side register.
        slot: u8,
    },
}

impl Mark {
    /// The immediate word the kernel reads: bit 31 set, bit 30 for a narrowing, bit 29
    /// for a union, the slot in the low byte.
    pub fn word(self) -> u32 {
        match self {
            Mark::Stash { slot, union } => 0x8000_0000 | u32::from(union) << 29 | u32::from(slot),
            Mark::Narrow { slot } => 0xc000_0000 | u32::from(slot),
        }
    }
}

/// What one instruction computes, by the instructions that produced its operands
/// (None: an immediate or a variable).
#[derive(Clone, Copy)]
enum Value {
    Other,
    Unary(UnaryOp, Option<usize>),
    Binary(BinaryOp, Option<usize>, Option<usize>),
}

/// Each instruction's mark (module docs).
pub fn marks(instrs: &[Instr]) -> Vec<Option<Mark>> {
    let mut writer: [Option<usize>; 256] = [None; 256];
    let mut values = Vec::with_capacity(instrs.len());
    let mut out = vec![None; instrs.len()];
    let mut slots = 0u8;
    let src =
        |writer: &[Option<usize>; 256], r: u8| (r != IMM).then(|| writer[r as usize]).flatten();
    for (k, &ins) in instrs.iter().enumerate() {
        let (o, value) = match ins {
            Instr::Var(o, _) | Instr::Const(o, _) | Instr::PowI(o, ..) => (o, Value::Other),
            Instr::Unary(o, op, a) => (o, Value::Unary(op, src(&writer, a))),
            Instr::Binary(o, op, a, b, _) => {
                (o, Value::Binary(op, src(&writer, a), src(&writer, b)))
            }
        };
        values.push(value);
        writer[o as usize] = Some(k);
        let Value::Binary(op @ (BinaryOp::Add | BinaryOp::Sub), Some(s), Some(r)) = value else {
            continue;
        };
        // Both sums' operands are registers, so their immediate words are free.
        if !is_r_function(&values, s, r) {
            continue;
        }
        let union = op == BinaryOp::Add;
        let slot = match out[s] {
            Some(Mark::Stash { slot, union: u }) if u == union => slot,
            None if usize::from(slots) < SLOTS => {
                slots += 1;
                out[s] = Some(Mark::Stash {
                    slot: slots - 1,
                    union,
                });
                slots - 1
            }
            _ => continue,
        };
        out[k] = Some(Mark::Narrow { slot });
    }
    out
}

/// Whether instruction s is a + b and r is √(a² + b²) (squares in either order).
fn is_r_function(values: &[Value], s: usize, r: usize) -> bool {
    let Value::Binary(BinaryOp::Add, Some(a), Some(b)) = values[s] else {
        return false;
    };
    let Value::Unary(UnaryOp::Sqrt, Some(q)) = values[r] else {
        return false;
    };
    let Value::Binary(BinaryOp::Add, Some(p), Some(p2)) = values[q] else {
        return false;
    };
    let (Value::Unary(UnaryOp::Square, Some(pa)), Value::Unary(UnaryOp::Square, Some(qa))) =
        (values[p], values[p2])
    else {
        return false;
    };
    (pa, qa) == (a, b) || (pa, qa) == (b, a)
}

/// The R-function's value interval at the point (x, y), outward-rounded, in a form
/// without cancellation: where x + y < 0 the union x + y + r (r = √(x² + y²)) is
/// −2xy/(r − x − y), and where x + y > 0 the intersection x + y − r is 2xy/(x + y + r)
/// (multiply by the conjugate). Next to a far part (y ≈ −100) the direct form loses a
/// few ulps of 100 to the cancellation, 5·10⁻⁵ in f32; these lose a few ulps of the
/// result.
fn at(x: f32, y: f32, union: bool) -> I2 {
    let (px, py) = ([x, x], [y, y]);
    let root = i_sqrt(i_add(i_square(px), i_square(py)));
    let sum = i_add(px, py);
    let two_xy = i_mul([2.0, 2.0], i_mul(px, py));
    match (union, x + y) {
        (true, s) if s < 0.0 => i_div([-two_xy[1], -two_xy[0]], i_sub(root, sum)),
        (true, _) => i_add(sum, root),
        (false, s) if s > 0.0 => i_div(two_xy, i_add(sum, root)),
        (false, _) => i_sub(sum, root),
    }
}

/// The corners a stash stores for a, b: the lower bound at (a.lo, b.lo), the upper at
/// (a.hi, b.hi); (−∞, ∞) where an end is not finite (the kernel's `r_corners`).
pub fn corners(a: I2, b: I2, union: bool) -> I2 {
    let finite = a[0].is_finite() && a[1].is_finite() && b[0].is_finite() && b[1].is_finite();
    if !finite {
        return [f32::NEG_INFINITY, f32::INFINITY];
    }
    [at(a[0], b[0], union)[0], at(a[1], b[1], union)[1]]
}

/// v narrowed to the corners c, kept where the two cross or v is unknown (the
/// kernel's `r_narrow`).
pub fn narrow(v: I2, c: I2) -> I2 {
    if v[0].is_nan() || v[1].is_nan() {
        return v;
    }
    let (lo, hi) = (v[0].max(c[0]), v[1].min(c[1]));
    if lo <= hi {
        [lo, hi]
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use crate::tape::GpuTape;
    use frep::bytecode::Bytecode;
    use frep::{Expr, Tree};

    fn tape(t: &Tree) -> GpuTape {
        GpuTape::new(&Bytecode::compile(&Expr::new(t)).unwrap()).unwrap()
    }

    /// frep's R-union, R-intersection and R-difference (α = 0) are found, a plain sum
    /// is not; and next to a far part (|F| ≈ 120) the narrowed interval at a point box
    /// is within 10⁻⁵·max(1, |F|), where plain interval arithmetic's union is 9·10⁻⁵
    /// wide at F = 0 (and the direct form of its corners as wide).
    #[test]
    fn r_functions_are_found_and_narrowed() {
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let ball = |c: f64| 1.0 - (x.clone() - c).square() - y.square() - z.square();
        for (name, t, found) in [
            (
                "R-union",
                frep::csg::r_union(&ball(0.0), &ball(12.0), 0.0),
                true,
            ),
            (
                "R-intersection",
                frep::csg::r_intersection(&ball(0.0), &ball(12.0), 0.0),
                true,
            ),
            (
                "R-difference",
                frep::csg::r_difference(&ball(0.0), &ball(12.0), 0.0),
                true,
            ),
            ("plain sum", ball(0.0) + ball(12.0), false),
        ] {
            let g = tape(&t);
            assert_eq!(g.r_functions(), found, "{name}");
            if !found {
                continue;
            }
            // A point box on the first ball's surface, 11 units from the second's.
            let c = |v: f32| [v, v.next_up(), 1.0, 1.0];
            let iv = g.eval_interval(c(1.0), c(0.0), c(0.0));
            let width = iv[1] - iv[0];
            let f = Expr::new(&t).eval([1.0, 0.0, 0.0]);
            assert!(
                f64::from(width) < 1e-5 * f.abs().max(1.0),
                "{name}: {iv:?} at F = {f}"
            );
            assert!(
                f64::from(iv[0]) <= f && f <= f64::from(iv[1]),
                "{name}: {f} outside {iv:?}"
            );
        }
    }

    /// The narrowed interval of an R-union holds the f64 function at the corners and
    /// inside of 20 000 random boxes, far and near the parts.
    #[test]
    fn narrowed_intervals_are_sound() {
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let a = 1.0 - x.square() - y.square() - z.square();
        let b = 0.5 - (x.clone() - 3.0).abs() - y.abs();
        let t = frep::csg::r_union(&a, &b, 0.0);
        let (g, e) = (tape(&t), Expr::new(&t));
        let mut seed = 9u64;
        let mut next = || crate::tape::tests::lcg(&mut seed);
        for k in 0..20_000 {
            let half = [2.0, 0.1, 1e-4, 1e-7][k % 4];
            let lo: [f64; 3] = [0, 1, 2].map(|_| next() * 10.0 - 4.0);
            let hi = lo.map(|v| v + half * next());
            let c = |i: usize| [lo[i] as f32, (hi[i] as f32).max(lo[i] as f32), 0.0, 0.0];
            let iv = g.eval_interval(c(0), c(1), c(2));
            for j in 0..9 {
                let p: [f64; 3] = [0, 1, 2].map(|i| {
                    let (l, h) = (f64::from(c(i)[0]), f64::from(c(i)[1]));
                    if j < 8 {
                        if j >> i & 1 == 0 {
                            l
                        } else {
                            h
                        }
                    } else {
                        0.5 * (l + h)
                    }
                });
                let f = e.eval(p);
                assert!(
                    f64::from(iv[0]) <= f && f <= f64::from(iv[1]),
                    "{f} at {p:?} outside {iv:?}"
                );
            }
        }
    }
}
