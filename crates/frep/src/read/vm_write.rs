//! Writer of Fidget `.vm` tapes, so that any frepray solid can be fed to Fidget.
//!
//! Every [`Node`] kind maps to Fidget opcodes: integer powers become chains of `square`
//! and `mul` (binary exponentiation), negative powers a `div` of 1 by the positive power,
//! constants are written in Rust's shortest round-trip form. The output is negated into
//! Fidget's convention (< 0 inside), so reading the tape back gives the same function.

use crate::expr::{Expr, Node};
use crate::tree::{BinaryOp, UnaryOp, Var};
use std::fmt::Write;

fn unary_name(op: UnaryOp) -> &'static str {
    match op {
        UnaryOp::Neg => "neg",
        UnaryOp::Abs => "abs",
        UnaryOp::Sqrt => "sqrt",
        UnaryOp::Square => "square",
        UnaryOp::Exp => "exp",
        UnaryOp::Ln => "ln",
        UnaryOp::Sin => "sin",
        UnaryOp::Cos => "cos",
        UnaryOp::Tan => "tan",
        UnaryOp::Asin => "asin",
        UnaryOp::Acos => "acos",
        UnaryOp::Atan => "atan",
        UnaryOp::Floor => "floor",
        UnaryOp::Ceil => "ceil",
        UnaryOp::Round => "round",
        UnaryOp::Not => "not",
    }
}

fn binary_name(op: BinaryOp) -> &'static str {
    match op {
        BinaryOp::Add => "add",
        BinaryOp::Sub => "sub",
        BinaryOp::Mul => "mul",
        BinaryOp::Div => "div",
        BinaryOp::Min => "min",
        BinaryOp::Max => "max",
        BinaryOp::Atan2 => "atan2",
        BinaryOp::Mod => "mod",
        BinaryOp::Compare => "compare",
        BinaryOp::And => "and",
        BinaryOp::Or => "or",
    }
}

/// Emits numbered single-assignment lines.
struct Tape {
    out: String,
    next: usize,
}

impl Tape {
    fn emit(&mut self, rhs: std::fmt::Arguments) -> String {
        let name = format!("_{:x}", self.next);
        self.next += 1;
        // Writing to a String cannot fail.
        let _ = writeln!(self.out, "{name} {rhs}");
        name
    }
    /// `base`ⁿ for n ≥ 1 by binary exponentiation (square and mul).
    fn pow(&mut self, base: &str, n: u64) -> String {
        if n == 1 {
            return base.to_string();
        }
        let half = self.pow(base, n / 2);
        let sq = self.emit(format_args!("square {half}"));
        if n % 2 == 1 {
            self.emit(format_args!("mul {sq} {base}"))
        } else {
            sq
        }
    }
}

/// The expression as a Fidget `.vm` tape, negated to Fidget's convention (< 0 inside).
pub fn write_vm(expr: &Expr) -> String {
    let mut t = Tape {
        out: String::from("# written by frepray: F ≥ 0 inside, negated to Fidget's < 0 inside\n"),
        next: 0,
    };
    let mut names: Vec<String> = Vec::with_capacity(expr.len());
    for n in expr.nodes() {
        let name = match *n {
            Node::Const(b) => t.emit(format_args!("const {:?}", f64::from_bits(b))),
            Node::Var(Var::X) => t.emit(format_args!("var-x")),
            Node::Var(Var::Y) => t.emit(format_args!("var-y")),
            Node::Var(Var::Z) => t.emit(format_args!("var-z")),
            Node::Unary(op, a) => {
                let a = &names[a as usize];
                t.emit(format_args!("{} {a}", unary_name(op)))
            }
            Node::Binary(op, a, b) => {
                let (a, b) = (&names[a as usize], &names[b as usize]);
                t.emit(format_args!("{} {a} {b}", binary_name(op)))
            }
            Node::PowI(a, k) => {
                let a = names[a as usize].clone();
                if k == 0 {
                    t.emit(format_args!("const 1.0"))
                } else {
                    let p = t.pow(&a, k.unsigned_abs() as u64);
                    if k > 0 {
                        p
                    } else {
                        let one = t.emit(format_args!("const 1.0"));
                        t.emit(format_args!("div {one} {p}"))
                    }
                }
            }
        };
        names.push(name);
    }
    if let Some(root) = names.last() {
        let root = root.clone();
        t.emit(format_args!("neg {root}"));
    }
    t.out
}
