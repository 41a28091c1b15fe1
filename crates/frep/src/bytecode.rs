//! Register bytecode for expressions: what a GPU tape interpreter runs (GPU.md §6.2).
//!
//! An [`Expr`] (a deduplicated DAG in evaluation order) compiles to instructions of two
//! `u32` words each, the layout of GPU.md §5.2's `GpuTapeOp` and of Fidget's
//! `fidget-bytecode` (mkeeter/fidget): word 0 packs `opcode | out << 8 | a << 16 | b << 24`,
//! word 1 holds an immediate (f32 bits; the exponent of `PowI` as i32 bits). An operand
//! register of [`IMM`] (255) reads the immediate instead, so constants take no register.
//!
//! Registers are allocated by a linear scan over the nodes in order (Poletto & Sarkar,
//! "Linear scan register allocation", TOPLAS 1999, on a straight-line tape, as Fidget's
//! `RegisterAllocator` does): an operand's register is freed after its last use, before
//! the result's is taken (an instruction reads its operands before it writes), and the
//! lowest free register is taken. At most [`MAX_REGISTERS`] registers: more is an error.
//! The result is in the last instruction's output register.
//!
//! The interpreters here are the reference a WGSL interpreter matches, one `match` arm
//! per opcode over a fixed register file: [`Bytecode::eval_f32`] gives exactly
//! [`Expr::eval_f32`] (same operations in the same order, bit for bit), and
//! [`Bytecode::eval_interval`] bounds F over a box in f32. Each interval operation is
//! evaluated on the f32 bounds in f64 by [`Interval`] (itself rounded outward), rounded
//! outward to f32, then widened by GPU.md §6.2's margin: 1 ulp, 4 after `/`, `sqrt`,
//! `powi` and transcendentals. So it holds every f32 point value, whose transcendentals
//! may be off by an ulp or two (a shader does the same operations in f32 with the same
//! widening). The shader's own algorithm, operation for operation in f32 with bit-step
//! widening, and its twin are in the `gpu` crate (`gpu::tape`, GPU.md §6.2.3).

use crate::expr::{Expr, Node};
use crate::interval::Interval;
use crate::scalar::Scalar;
use crate::tree::{BinaryOp, UnaryOp, Var};
use std::fmt;

/// The operand register number that reads the instruction's immediate.
pub const IMM: u8 = 255;

/// The most registers a tape may use (register numbers 0 ..= 254; 255 is [`IMM`]).
pub const MAX_REGISTERS: usize = 255;

/// An instruction's opcode (the low byte of its first word).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Op {
    /// out ← coordinate `a` (0 x, 1 y, 2 z).
    Var = 0,
    /// out ← the immediate.
    Const = 1,
    /// out ← aⁿ, n the immediate's i32 bits.
    PowI = 2,
    /// out ← unary(a): [`UnaryOp`] k is opcode 16 + k.
    Unary = 16,
    /// out ← binary(a, b): [`BinaryOp`] k is opcode 48 + k.
    Binary = 48,
}

/// The opcode of a unary operation: [`Op::Unary`] plus its number (the GPU's
/// interpreter takes its `case` labels from here).
pub fn unary_opcode(op: UnaryOp) -> u8 {
    Op::Unary as u8 + op as u8
}

/// The opcode of a binary operation: [`Op::Binary`] plus its number.
pub fn binary_opcode(op: BinaryOp) -> u8 {
    Op::Binary as u8 + op as u8
}

const UNARY: [UnaryOp; 16] = [
    UnaryOp::Neg,
    UnaryOp::Abs,
    UnaryOp::Sqrt,
    UnaryOp::Square,
    UnaryOp::Exp,
    UnaryOp::Ln,
    UnaryOp::Sin,
    UnaryOp::Cos,
    UnaryOp::Tan,
    UnaryOp::Asin,
    UnaryOp::Acos,
    UnaryOp::Atan,
    UnaryOp::Floor,
    UnaryOp::Ceil,
    UnaryOp::Round,
    UnaryOp::Not,
];

const BINARY: [BinaryOp; 11] = [
    BinaryOp::Add,
    BinaryOp::Sub,
    BinaryOp::Mul,
    BinaryOp::Div,
    BinaryOp::Min,
    BinaryOp::Max,
    BinaryOp::Atan2,
    BinaryOp::Mod,
    BinaryOp::Compare,
    BinaryOp::And,
    BinaryOp::Or,
];

/// One decoded instruction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Instr {
    /// out ← coordinate.
    Var(u8, Var),
    /// out ← constant.
    Const(u8, f32),
    /// out ← op(a).
    Unary(u8, UnaryOp, u8),
    /// out ← op(a, b); either operand may be [`IMM`].
    Binary(u8, BinaryOp, u8, u8, f32),
    /// out ← aⁿ.
    PowI(u8, u8, i32),
}

/// Why a tape cannot be compiled or decoded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BytecodeError {
    /// The tape needs more than [`MAX_REGISTERS`] live values at once.
    TooManyRegisters {
        /// Registers the tape would need (at least).
        needed: usize,
    },
    /// Words that are not a valid program: which instruction, and why.
    Malformed {
        /// Index of the offending instruction.
        at: usize,
        /// What is wrong.
        why: &'static str,
    },
}

impl fmt::Display for BytecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooManyRegisters { needed } => write!(
                f,
                "the expression needs {needed} registers; the bytecode holds {MAX_REGISTERS}"
            ),
            Self::Malformed { at, why } => {
                write!(f, "malformed bytecode at instruction {at}: {why}")
            }
        }
    }
}

impl std::error::Error for BytecodeError {}

/// A register-allocated program (see the module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Bytecode {
    words: Vec<u32>,
    registers: usize,
}

fn pack(op: u8, out: u8, a: u8, b: u8) -> u32 {
    op as u32 | (out as u32) << 8 | (a as u32) << 16 | (b as u32) << 24
}

/// The lowest-numbered free registers first: a 256-bit set.
struct Free([u64; 4]);

impl Free {
    fn take(&mut self) -> Option<u8> {
        let w = self.0.iter().position(|&w| w != 0)?;
        let bit = self.0[w].trailing_zeros() as usize;
        self.0[w] &= !(1 << bit);
        let r = w * 64 + bit;
        (r < MAX_REGISTERS).then_some(r as u8)
    }
    fn give(&mut self, r: u8) {
        self.0[r as usize / 64] |= 1 << (r % 64);
    }
}

impl Bytecode {
    /// Compiles `expr` (see the module docs).
    pub fn compile(expr: &Expr) -> Result<Self, BytecodeError> {
        Self::compile_nodes(expr.nodes())
    }

    /// Compiles a tape of nodes in evaluation order, operands before their users and
    /// the root last (an [`Expr`]'s, or a cell tape of [`crate::occupancy`], simplified
    /// over its cell); not empty.
    pub fn compile_nodes(nodes: &[Node]) -> Result<Self, BytecodeError> {
        let n = nodes.len();
        assert!(n > 0, "a tape has a root");
        let konst = |i: u32| match nodes[i as usize] {
            Node::Const(b) => Some(f64::from_bits(b) as f32),
            _ => None,
        };
        // Last use of every node (the root lives to the end).
        let mut last = vec![0usize; n];
        for (i, node) in nodes.iter().enumerate() {
            match *node {
                Node::Unary(_, a) | Node::PowI(a, _) => last[a as usize] = i,
                Node::Binary(_, a, b) => {
                    last[a as usize] = i;
                    last[b as usize] = i;
                }
                _ => {}
            }
        }
        last[n - 1] = n;
        // A constant is an immediate of its users, unless it is the root or the second
        // constant operand of one instruction (after folding, only the root).
        let mut in_register = vec![false; n];
        in_register[n - 1] = true;
        for node in nodes {
            match *node {
                Node::Unary(_, a) | Node::PowI(a, _) => in_register[a as usize] = true,
                Node::Binary(_, a, b) if konst(a).is_some() && konst(b).is_some() => {
                    in_register[b as usize] = true
                }
                _ => {}
            }
        }
        let mut reg = vec![IMM; n];
        let mut free = Free([u64::MAX; 4]);
        let mut used = 0;
        let mut words = Vec::with_capacity(2 * n);
        for (i, node) in nodes.iter().enumerate() {
            if matches!(node, Node::Const(_)) && !in_register[i] {
                continue;
            }
            let operand = |a: u32| match konst(a).filter(|_| !in_register[a as usize]) {
                Some(v) => (IMM, v.to_bits()),
                None => (reg[a as usize], 0),
            };
            let (op, a, b, imm) = match *node {
                Node::Const(b) => (Op::Const as u8, 0, 0, (f64::from_bits(b) as f32).to_bits()),
                Node::Var(v) => (Op::Var as u8, v as u8, 0, 0),
                Node::Unary(op, a) => (unary_opcode(op), reg[a as usize], 0, 0),
                Node::PowI(a, k) => (Op::PowI as u8, reg[a as usize], 0, k as u32),
                Node::Binary(op, a, b) => {
                    let ((ra, ia), (rb, ib)) = (operand(a), operand(b));
                    (binary_opcode(op), ra, rb, ia | ib)
                }
            };
            // Operands whose last use this is give their registers back first.
            if let Node::Unary(_, x) | Node::PowI(x, _) | Node::Binary(_, x, _) = *node {
                if last[x as usize] == i && reg[x as usize] != IMM {
                    free.give(reg[x as usize]);
                }
            }
            if let Node::Binary(_, x, y) = *node {
                if x != y && last[y as usize] == i && reg[y as usize] != IMM {
                    free.give(reg[y as usize]);
                }
            }
            let out = free.take().ok_or(BytecodeError::TooManyRegisters {
                needed: MAX_REGISTERS + 1,
            })?;
            used = used.max(out as usize + 1);
            reg[i] = out;
            words.push(pack(op, out, a, b));
            words.push(imm);
        }
        Ok(Self {
            words,
            registers: used,
        })
    }

    /// Checks words from elsewhere: whole instructions, known opcodes, registers below
    /// `registers` (≤ [`MAX_REGISTERS`]), every register written before it is read.
    pub fn from_words(words: Vec<u32>, registers: usize) -> Result<Self, BytecodeError> {
        let bad = |at, why| Err(BytecodeError::Malformed { at, why });
        if registers > MAX_REGISTERS {
            return Err(BytecodeError::TooManyRegisters { needed: registers });
        }
        if words.is_empty() {
            return bad(0, "empty program");
        }
        if !words.len().is_multiple_of(2) {
            return bad(words.len() / 2, "an instruction is two words");
        }
        let code = Self { words, registers };
        let mut written = [false; 256];
        for k in 0..code.len() {
            let Some(ins) = code.decode(k) else {
                return bad(k, "unknown opcode");
            };
            let (out, reads): (u8, [u8; 2]) = match ins {
                Instr::Var(o, _) | Instr::Const(o, _) => (o, [IMM; 2]),
                Instr::Unary(o, _, a) | Instr::PowI(o, a, _) => {
                    if a == IMM {
                        return bad(k, "a unary operand cannot be an immediate");
                    }
                    (o, [a, IMM])
                }
                Instr::Binary(o, _, a, b, _) => (o, [a, b]),
            };
            for r in reads {
                if r != IMM && (r as usize >= registers || !written[r as usize]) {
                    return bad(k, "reads a register not written before");
                }
            }
            if out as usize >= registers {
                return bad(k, "writes a register beyond the register count");
            }
            written[out as usize] = true;
        }
        Ok(code)
    }

    /// The words, two per instruction.
    pub fn words(&self) -> &[u32] {
        &self.words
    }

    /// Registers used (the highest register number plus one).
    pub fn registers(&self) -> usize {
        self.registers
    }

    /// Number of instructions.
    pub fn len(&self) -> usize {
        self.words.len() / 2
    }

    /// Whether there is no instruction (never, for a compiled tape).
    pub fn is_empty(&self) -> bool {
        self.words.is_empty()
    }

    /// Instruction k, or None for an unknown opcode.
    pub fn decode(&self, k: usize) -> Option<Instr> {
        let (w, imm) = (self.words[2 * k], self.words[2 * k + 1]);
        let [op, out, a, b] = w.to_le_bytes();
        let f = f32::from_bits(imm);
        Some(match op {
            0 => Instr::Var(out, [Var::X, Var::Y, Var::Z].get(a as usize).copied()?),
            1 => Instr::Const(out, f),
            2 => Instr::PowI(out, a, imm as i32),
            16..=31 => Instr::Unary(out, UNARY[op as usize - 16], a),
            48..=58 => Instr::Binary(out, BINARY[op as usize - 48], a, b, f),
            _ => return None,
        })
    }

    /// F at p in f32: exactly [`Expr::eval_f32`] of the compiled expression.
    pub fn eval_f32(&self, p: [f32; 3]) -> f32 {
        let mut r = [0f32; 256];
        let mut out = 0;
        for k in 0..self.len() {
            let ins = self.decode(k).expect("a checked program");
            let (o, v) = match ins {
                Instr::Var(o, v) => (o, p[v as usize]),
                Instr::Const(o, c) => (o, c),
                Instr::PowI(o, a, n) => (o, r[a as usize].powi(n)),
                Instr::Unary(o, op, a) => (o, unary(op, r[a as usize])),
                Instr::Binary(o, op, a, b, imm) => {
                    let get = |x: u8| if x == IMM { imm } else { r[x as usize] };
                    (o, binary(op, get(a), get(b)))
                }
            };
            r[o as usize] = v;
            out = o;
        }
        r[out as usize]
    }

    /// Bounds of F over the box `lo..hi` in f32 (see the module docs): `(lo, hi)`, NaN
    /// when unknown.
    pub fn eval_interval(&self, lo: [f32; 3], hi: [f32; 3]) -> (f32, f32) {
        let mut r = [(0f32, 0f32); 256];
        let mut out = 0;
        let wide = |i: (f32, f32)| Interval::new(i.0 as f64, i.1 as f64);
        for k in 0..self.len() {
            let ins = self.decode(k).expect("a checked program");
            let (o, v, ulps) = match ins {
                Instr::Var(o, v) => (o, (lo[v as usize], hi[v as usize]), 0),
                Instr::Const(o, c) => (o, (c, c), 0),
                Instr::PowI(o, a, n) => {
                    let v = wide(r[a as usize]).powi(n);
                    (o, narrow(v), 4u32.max(n.unsigned_abs().min(64)))
                }
                Instr::Unary(o, op, a) => {
                    let v = unary(op, wide(r[a as usize]));
                    (o, narrow(v), unary_ulps(op))
                }
                Instr::Binary(o, op, a, b, imm) => {
                    let get = |x: u8| if x == IMM { (imm, imm) } else { r[x as usize] };
                    let v = binary(op, wide(get(a)), wide(get(b)));
                    (o, narrow(v), binary_ulps(op))
                }
            };
            r[o as usize] = widen(v, ulps);
            out = o;
        }
        r[out as usize]
    }
}

#[inline]
fn unary<S: Scalar>(op: UnaryOp, a: S) -> S {
    match op {
        UnaryOp::Neg => -a,
        UnaryOp::Abs => a.abs(),
        UnaryOp::Sqrt => a.sqrt(),
        UnaryOp::Square => a.square(),
        UnaryOp::Exp => a.exp(),
        UnaryOp::Ln => a.ln(),
        UnaryOp::Sin => a.sin(),
        UnaryOp::Cos => a.cos(),
        UnaryOp::Tan => a.tan(),
        UnaryOp::Asin => a.asin(),
        UnaryOp::Acos => a.acos(),
        UnaryOp::Atan => a.atan(),
        UnaryOp::Floor => a.floor(),
        UnaryOp::Ceil => a.ceil(),
        UnaryOp::Round => a.round(),
        UnaryOp::Not => a.not(),
    }
}

#[inline]
fn binary<S: Scalar>(op: BinaryOp, a: S, b: S) -> S {
    match op {
        BinaryOp::Add => a + b,
        BinaryOp::Sub => a - b,
        BinaryOp::Mul => a * b,
        BinaryOp::Div => a / b,
        BinaryOp::Min => a.min(b),
        BinaryOp::Max => a.max(b),
        BinaryOp::Atan2 => a.atan2(b),
        BinaryOp::Mod => a.modulo(b),
        BinaryOp::Compare => a.compare(b),
        BinaryOp::And => a.and(b),
        BinaryOp::Or => a.or(b),
    }
}

/// The widening after a unary operation, in f32 ulps (GPU.md §6.2).
fn unary_ulps(op: UnaryOp) -> u32 {
    match op {
        UnaryOp::Neg | UnaryOp::Abs | UnaryOp::Floor | UnaryOp::Ceil | UnaryOp::Round => 0,
        UnaryOp::Not | UnaryOp::Square => 1,
        _ => 4,
    }
}

/// The widening after a binary operation, in f32 ulps (GPU.md §6.2).
fn binary_ulps(op: BinaryOp) -> u32 {
    match op {
        BinaryOp::Min | BinaryOp::Max | BinaryOp::Compare | BinaryOp::And | BinaryOp::Or => 0,
        BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul | BinaryOp::Mod => 1,
        BinaryOp::Div | BinaryOp::Atan2 => 4,
    }
}

/// An f64 interval rounded outward to f32 (NaN stays NaN).
fn narrow(v: Interval) -> (f32, f32) {
    if v.is_nan() {
        return (f32::NAN, f32::NAN);
    }
    let (mut lo, mut hi) = (v.lo as f32, v.hi as f32);
    if lo as f64 > v.lo {
        lo = lo.next_down();
    }
    if (hi as f64) < v.hi {
        hi = hi.next_up();
    }
    (lo, hi)
}

/// Widened by `ulps` f32 ulps each way; as GPU.md §6.2 asks of a shader, a step from 0
/// goes to the smallest normal, so that a GPU flushing denormals still widens.
fn widen((mut lo, mut hi): (f32, f32), ulps: u32) -> (f32, f32) {
    for _ in 0..ulps {
        lo = if lo == 0.0 {
            -f32::MIN_POSITIVE
        } else {
            lo.next_down()
        };
        hi = if hi == 0.0 {
            f32::MIN_POSITIVE
        } else {
            hi.next_up()
        };
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Tree;

    #[test]
    fn registers_are_reused_after_last_use() {
        // Σ_k (x + k)²: each term dies into the running sum, so a few registers suffice
        // for any number of terms.
        let mut t = Tree::constant(0.0);
        for k in 1..200 {
            t = t + (Tree::x() + k as f64).square() * (Tree::y() - k as f64);
        }
        let e = Expr::new(&t);
        let code = Bytecode::compile(&e).unwrap();
        assert!(code.registers() <= 5, "{}", code.registers());
        for p in [[0.5f32, -1.0, 2.0], [3.0, 0.25, -7.0]] {
            assert_eq!(code.eval_f32(p).to_bits(), e.eval_f32(p).to_bits());
        }
    }

    #[test]
    fn constants_and_variables_alone() {
        for t in [Tree::constant(2.5), Tree::z(), -Tree::y()] {
            let e = Expr::new(&t);
            let code = Bytecode::compile(&e).unwrap();
            let p = [1.0, -2.0, 3.0];
            assert_eq!(code.eval_f32(p), e.eval_f32(p));
        }
    }

    #[test]
    fn too_many_live_values_is_an_error() {
        // 300 sines, all computed first (by the leading max) and all used again at the
        // end: 300 live values at once.
        let terms: Vec<Tree> = (0..300)
            .map(|k| (Tree::x() * (k as f64 + 1.5)).sin())
            .collect();
        let mut t = Tree::constant(0.0);
        for k in 0..150 {
            t = t + &terms[k] * &terms[299 - k];
        }
        let all = terms.iter().fold(Tree::constant(0.0), |a, b| a.max(b));
        let e = Expr::new(&(all + t));
        match Bytecode::compile(&e) {
            Err(BytecodeError::TooManyRegisters { .. }) => {}
            other => panic!("{:?}", other.map(|c| c.registers())),
        }
    }

    #[test]
    fn malformed_words_are_rejected() {
        let e = Expr::new(&(Tree::x() + Tree::y()));
        let good = Bytecode::compile(&e).unwrap();
        assert!(Bytecode::from_words(good.words().to_vec(), good.registers()).is_ok());
        let cases: [(Vec<u32>, usize, &str); 5] = [
            (vec![], 2, "empty"),
            (vec![pack(0, 0, 0, 0)], 2, "two words"),
            (vec![pack(200, 0, 0, 0), 0], 2, "unknown opcode"),
            (vec![pack(48, 0, 1, 1), 0], 2, "not written"),
            (vec![pack(0, 9, 0, 0), 0], 2, "beyond"),
        ];
        for (words, regs, msg) in cases {
            let e = Bytecode::from_words(words, regs).unwrap_err();
            assert!(e.to_string().contains(msg), "{e} lacks {msg}");
        }
        let e = Bytecode::from_words(good.words().to_vec(), 256).unwrap_err();
        assert_eq!(e, BytecodeError::TooManyRegisters { needed: 256 });
    }
}
