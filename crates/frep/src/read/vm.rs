//! Reader of Fidget's `.vm` tapes.
//!
//! One instruction a line, `NAME OPCODE ARGS…`; `#` starts a comment; the last
//! instruction is the output. Fidget's values are distance-like (< 0 inside), so the
//! output is negated into the FRep convention. Reading is one pass over the lines with a
//! name table, so a 7,866-line tape (prospero.vm) loads without recursion.

use super::{Model, ReadError};
use crate::ray::Aabb;
use crate::shape::Shape;
use crate::tree::{BinaryOp, Tree, UnaryOp};
use std::collections::HashMap;

/// What an opcode builds.
enum Op {
    Const,
    Var(Tree),
    Unary(UnaryOp),
    Recip,
    Binary(BinaryOp),
}

fn opcode(name: &str) -> Option<Op> {
    use BinaryOp as B;
    use UnaryOp as U;
    Some(match name {
        "const" => Op::Const,
        "var-x" => Op::Var(Tree::x()),
        "var-y" => Op::Var(Tree::y()),
        "var-z" => Op::Var(Tree::z()),
        "neg" => Op::Unary(U::Neg),
        "abs" => Op::Unary(U::Abs),
        "square" => Op::Unary(U::Square),
        "sqrt" => Op::Unary(U::Sqrt),
        "sin" => Op::Unary(U::Sin),
        "cos" => Op::Unary(U::Cos),
        "tan" => Op::Unary(U::Tan),
        "asin" => Op::Unary(U::Asin),
        "acos" => Op::Unary(U::Acos),
        "atan" => Op::Unary(U::Atan),
        "exp" => Op::Unary(U::Exp),
        "ln" => Op::Unary(U::Ln),
        "floor" => Op::Unary(U::Floor),
        "ceil" => Op::Unary(U::Ceil),
        "round" => Op::Unary(U::Round),
        "not" => Op::Unary(U::Not),
        "recip" => Op::Recip,
        "add" => Op::Binary(B::Add),
        "sub" => Op::Binary(B::Sub),
        "mul" => Op::Binary(B::Mul),
        "div" => Op::Binary(B::Div),
        "min" => Op::Binary(B::Min),
        "max" => Op::Binary(B::Max),
        "atan2" => Op::Binary(B::Atan2),
        "mod" => Op::Binary(B::Mod),
        "compare" => Op::Binary(B::Compare),
        "and" => Op::Binary(B::And),
        "or" => Op::Binary(B::Or),
        _ => return None,
    })
}

impl Op {
    fn arity(&self) -> usize {
        match self {
            Op::Var(_) => 0,
            Op::Const | Op::Unary(_) | Op::Recip => 1,
            Op::Binary(_) => 2,
        }
    }
}

/// Reads a `.vm` tape (see the module docs).
pub(crate) fn read(text: &str, file: &str) -> Result<Model, ReadError> {
    let mut names: HashMap<&str, Tree> = HashMap::new();
    let mut last: Option<Tree> = None;
    let mut last_line = 0;
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        last_line = line;
        let code = raw.split('#').next().unwrap_or("");
        let words = split_words(code);
        if words.is_empty() {
            continue;
        }
        let err = |col: usize, msg: String| ReadError::at(file, line, col, msg);
        let end_col = code.chars().count() + 1;
        let (_, name) = words[0];
        let Some(&(op_col, op_name)) = words.get(1) else {
            return Err(err(
                end_col,
                format!("expected an opcode after '{name}', found the end of the line"),
            ));
        };
        let op = opcode(op_name).ok_or_else(|| {
            err(op_col, format!("expected an opcode (const, var-x, add, …), found the unknown opcode '{op_name}'"))
        })?;
        let args = &words[2..];
        let n = op.arity();
        if args.len() != n {
            let col = args.get(n).map_or(end_col, |a| a.0);
            let what = match n {
                0 => "no arguments".to_string(),
                1 => "1 argument".to_string(),
                _ => format!("{n} arguments"),
            };
            return Err(err(
                col,
                format!("expected {what} for '{op_name}', found {}", args.len()),
            ));
        }
        let arg = |i: usize| -> Result<Tree, ReadError> {
            let (col, a) = args[i];
            names
                .get(a)
                .cloned()
                .ok_or_else(|| err(col, format!("expected the name of an earlier instruction, found the undefined name '{a}'")))
        };
        let t = match op {
            Op::Const => {
                let (col, a) = args[0];
                let v: f64 = a
                    .parse()
                    .map_err(|_| err(col, format!("expected a number, found '{a}'")))?;
                Tree::constant(v)
            }
            Op::Var(v) => v,
            Op::Unary(u) => Tree::unary(u, arg(0)?),
            Op::Recip => Tree::constant(1.0) / arg(0)?,
            Op::Binary(b) => Tree::binary(b, arg(0)?, arg(1)?),
        };
        names.insert(name, t.clone());
        last = Some(t);
    }
    let out = last.ok_or_else(|| {
        ReadError::at(
            file,
            last_line.max(1),
            1,
            "expected at least one instruction, found none",
        )
    })?;
    let domain = Some(view_domain(text));
    Ok(Model {
        name: None,
        shape: Shape::Function { tree: -out, domain },
        domain,
    })
}

/// The region Fidget renders by default, [-1, 1]³.
pub const VM_DOMAIN: Aabb = Aabb {
    lo: glam::DVec3::splat(-1.0),
    hi: glam::DVec3::splat(1.0),
};

/// The region a `.vm` model is meant to be seen in: Fidget's view [-1, 1]³, divided by
/// the `--scale S` of a "Recommended settings" comment when the file has one (e.g.
/// tanglecube.vm's `--scale 0.222` shows ±4.5). Some models (colonnade's ground)
/// extend beyond it; it is their declared domain.
pub fn view_domain(text: &str) -> Aabb {
    let scale = text
        .lines()
        .filter_map(|l| l.trim_start().strip_prefix('#'))
        .find_map(|c| {
            let mut words = c.split_whitespace();
            words.find(|w| *w == "--scale")?;
            words.next()?.parse::<f64>().ok()
        })
        .filter(|s| s.is_finite() && *s > 0.0)
        .unwrap_or(1.0);
    Aabb {
        lo: VM_DOMAIN.lo / scale,
        hi: VM_DOMAIN.hi / scale,
    }
}

/// The whitespace-separated words of a line with their 1-based character columns.
fn split_words(code: &str) -> Vec<(usize, &str)> {
    let mut words = Vec::new();
    let mut start: Option<(usize, usize)> = None;
    for (col, (bi, c)) in code.char_indices().enumerate() {
        match (c.is_whitespace(), start) {
            (true, Some((s, scol))) => {
                words.push((scol + 1, &code[s..bi]));
                start = None;
            }
            (false, None) => start = Some((bi, col)),
            _ => {}
        }
    }
    if let Some((s, scol)) = start {
        words.push((scol + 1, &code[s..]));
    }
    words
}
