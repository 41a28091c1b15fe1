//! Symbolic execution of a HyperFun model into one expression tree.
//!
//! Variables hold [`Val`]s: numbers stay numbers, anything computed from `x[i]` becomes a
//! tree. Statements run in order; an `if` whose condition is a known number runs one
//! branch, an `if` whose condition depends on the coordinates runs both branches and
//! merges every variable they leave as `select(c, then, else)` (see `sym`); a `while`
//! runs while its condition is a known non-zero number and is an error when the
//! condition depends on the coordinates (a loop cannot be unrolled a point-dependent
//! number of times). Loops are capped at [`MAX_ITERATIONS`] iterations in all.

use super::lib::{self, Arg, Outcome};
use super::parse::{BinOp, Expr, ModelDef, Pos, Stmt, UnOp};
use crate::csg;
use crate::read::sym::{self, Val, EPS};
use crate::read::ReadError;
use crate::tree::{BinaryOp, Tree};
use std::collections::HashMap;

/// The most loop iterations one model may execute (all loops and calls together).
pub(crate) const MAX_ITERATIONS: usize = 1_000_000;

/// The deepest chain of calls of one model by another.
const MAX_CALL_DEPTH: usize = 64;

/// The most variables and array elements one model may make or copy: arrays are
/// declared up to a million elements each and a branch on the coordinates copies every
/// variable, so 200 arrays took gigabytes and a branch in a loop copied a million-element
/// array a million times (found while fuzzing). Four million take about 100 MB.
pub(crate) const MAX_CELLS: usize = 4_000_000;

/// The variables of one running model.
#[derive(Clone, Default)]
struct Frame {
    scalars: HashMap<String, Val>,
    arrays: HashMap<String, Vec<Option<Val>>>,
    /// Whether the header declares the third array `s[k]` (else `s` is a free name).
    has_s: bool,
}

/// A program being executed.
pub(crate) struct Exec<'a> {
    pub models: &'a [ModelDef],
    pub file: &'a str,
    iterations: usize,
    depth: usize,
    /// Variables and array elements made or copied so far (see [`MAX_CELLS`]).
    cells: usize,
}

impl Frame {
    /// Its variables and array elements.
    fn cells(&self) -> usize {
        self.scalars.len() + self.arrays.values().map(Vec::len).sum::<usize>()
    }
}

impl<'a> Exec<'a> {
    /// An executor of the models of one file.
    pub fn new(models: &'a [ModelDef], file: &'a str) -> Self {
        Self {
            models,
            file,
            iterations: 0,
            depth: 0,
            cells: 0,
        }
    }

    fn charge_cells(&mut self, n: usize, p: Pos) -> Result<(), ReadError> {
        self.cells += n;
        if self.cells > MAX_CELLS {
            return Err(self.err(
                p,
                format!(
                    "expected at most {MAX_CELLS} variables and array elements made or \
                     copied in all, found more"
                ),
            ));
        }
        Ok(())
    }

    fn err(&self, p: Pos, msg: impl Into<String>) -> ReadError {
        ReadError::at(self.file, p.line, p.col, msg)
    }

    /// Runs model `m` with the coordinate array `x` and parameters `a`; the model's value.
    pub fn run(&mut self, m: &ModelDef, x: Vec<Val>, a: Vec<Val>) -> Result<Val, ReadError> {
        let mut f = Frame::default();
        f.arrays
            .insert("x".into(), x.into_iter().map(Some).collect());
        f.arrays
            .insert("a".into(), a.into_iter().map(Some).collect());
        if let Some(k) = m.s_dim {
            self.charge_cells(k, m.pos)?;
            f.arrays.insert("s".into(), vec![Some(Val::Num(0.0)); k]);
            f.has_s = true;
        }
        self.block(&mut f, &m.body)?;
        f.scalars.get(&m.name).cloned().ok_or_else(|| {
            self.err(
                m.end,
                format!(
                    "expected an assignment to the model's name '{}' before '}}', found none",
                    m.name
                ),
            )
        })
    }

    fn block(&mut self, f: &mut Frame, stmts: &[Stmt]) -> Result<(), ReadError> {
        for s in stmts {
            self.stmt(f, s)?;
        }
        Ok(())
    }

    fn stmt(&mut self, f: &mut Frame, s: &Stmt) -> Result<(), ReadError> {
        match s {
            Stmt::Array(decls) => {
                for (name, n, p) in decls {
                    let header = name == "x" || name == "a" || (name == "s" && f.has_s);
                    if header || f.scalars.contains_key(name) {
                        return Err(self.err(
                            *p,
                            format!("expected a new array name, found '{name}', already in use"),
                        ));
                    }
                    self.charge_cells(*n, *p)?;
                    f.arrays.insert(name.clone(), vec![None; *n]);
                }
            }
            Stmt::Assign(name, p, e) => {
                if f.arrays.contains_key(name) {
                    return Err(self.err(
                        *p,
                        format!("expected an element 'name[i]' or a list '[…]' to assign to the array '{name}', found an expression"),
                    ));
                }
                let v = self.eval(f, e)?;
                f.scalars.insert(name.clone(), v);
            }
            Stmt::AssignIndex(name, p, i, e) => {
                let k = self.index(f, name, *p, i)?;
                let v = self.eval(f, e)?;
                if let Some(arr) = f.arrays.get_mut(name) {
                    arr[k] = Some(v);
                }
            }
            Stmt::AssignList(name, p, vals) => {
                let Some(arr) = f.arrays.get_mut(name) else {
                    return Err(self.err(
                        *p,
                        format!(
                            "expected an array declared with 'array {name}[{}];', found none",
                            vals.len()
                        ),
                    ));
                };
                if arr.len() != vals.len() {
                    let n = arr.len();
                    return Err(self.err(
                        *p,
                        format!(
                            "expected {n} numbers for the array '{name}', found {}",
                            vals.len()
                        ),
                    ));
                }
                *arr = vals.iter().map(|v| Some(Val::Num(*v))).collect();
            }
            Stmt::If(c, then, other) => {
                let cond = sym::truth(&self.eval(f, c)?);
                match cond.num() {
                    Some(v) if v != 0.0 => self.block(f, then)?,
                    Some(_) => self.block(f, other)?,
                    None => {
                        self.charge_cells(2 * f.cells(), c.pos())?;
                        let mut ft = f.clone();
                        self.block(&mut ft, then)?;
                        let mut fe = f.clone();
                        self.block(&mut fe, other)?;
                        *f = merge(&cond, ft, fe);
                    }
                }
            }
            Stmt::While(c, body, p) => {
                loop {
                    let cond = sym::truth(&self.eval(f, c)?);
                    match cond.num() {
                    Some(v) => {
                        if v == 0.0 {
                            break;
                        }
                    }
                    None => {
                        return Err(self.err(
                            *p,
                            "expected a loop condition that does not depend on x (loops are unrolled), found one that does",
                        ))
                    }
                }
                    self.iterations += 1;
                    if self.iterations > MAX_ITERATIONS {
                        return Err(self.err(*p, format!("expected loops to end within {MAX_ITERATIONS} iterations, found more")));
                    }
                    self.block(f, body)?;
                }
            }
        }
        Ok(())
    }

    /// The 0-based element index of `name[i]`, checked.
    fn index(&mut self, f: &mut Frame, name: &str, p: Pos, i: &Expr) -> Result<usize, ReadError> {
        let Some(n) = f.arrays.get(name).map(|a| a.len()) else {
            return Err(self.err(p, format!("expected an array, found '{name}', which is not one (declare it with 'array {name}[size];')")));
        };
        let v = self.eval(f, i)?;
        let Some(v) = v.num() else {
            return Err(self.err(
                p,
                "expected an index that does not depend on the coordinates, found one that does",
            ));
        };
        // HyperFun rounds an index half up.
        let k = (v + 0.5).floor();
        if !(k >= 1.0 && k <= n as f64) {
            return Err(self.err(
                p,
                format!("expected an index of '{name}' in 1..{n}, found {v}"),
            ));
        }
        Ok(k as usize - 1)
    }

    fn alpha(&self, f: &Frame, p: Pos) -> Result<f64, ReadError> {
        match f.scalars.get("alpha") {
            None => Ok(0.0),
            Some(Val::Num(a)) if (0.0..=1.0).contains(a) => Ok(*a),
            Some(Val::Num(a)) => Err(self.err(p, format!("expected ALPHA in 0..1, found {a}"))),
            Some(_) => Err(self.err(
                p,
                "expected a constant ALPHA, found an expression of the coordinates",
            )),
        }
    }

    fn eval(&mut self, f: &mut Frame, e: &Expr) -> Result<Val, ReadError> {
        Ok(match e {
            Expr::Num(v, _) => Val::Num(*v),
            Expr::Name(n, p) => match f.scalars.get(n) {
                Some(v) => v.clone(),
                None if f.arrays.contains_key(n) => {
                    return Err(self.err(*p, format!("expected a number, found the array '{n}' (index it: {n}[i])")))
                }
                None => {
                    return Err(self.err(
                        *p,
                        format!("expected a variable with a value, found '{n}', unassigned here (assign it first, on every branch of an 'if')"),
                    ))
                }
            },
            Expr::Index(n, i, p) => {
                let k = self.index(f, n, *p, i)?;
                match &f.arrays[n][k] {
                    Some(v) => v.clone(),
                    None => return Err(self.err(*p, format!("expected an assigned element, found {n}[{}] unassigned", k + 1))),
                }
            }
            Expr::Call(name, args, p) => self.call(f, name, args, *p)?,
            Expr::Unary(op, a, _) => {
                let v = self.eval(f, a)?;
                match op {
                    UnOp::Plus => v,
                    UnOp::Neg | UnOp::Tilde => sym::unary(crate::tree::UnaryOp::Neg, &v),
                    UnOp::Not => sym::not(&v),
                }
            }
            Expr::Chain(first, rest) => {
                let mut acc = self.eval(f, first)?;
                for (op, p, rhs) in rest {
                    let b = self.eval(f, rhs)?;
                    acc = self.binop(f, *op, *p, &acc, &b)?;
                }
                acc
            }
            Expr::Compare(first, rest) => {
                let mut left = self.eval(f, first)?;
                let mut acc = Val::Num(1.0);
                for (op, _, rhs) in rest {
                    let right = self.eval(f, rhs)?;
                    acc = sym::and(&acc, &sym::compare(*op, &left, &right));
                    left = right;
                }
                acc
            }
        })
    }

    fn binop(&mut self, f: &Frame, op: BinOp, p: Pos, a: &Val, b: &Val) -> Result<Val, ReadError> {
        let r = |g: fn(&Tree, &Tree, f64) -> Tree, alpha: f64| {
            sym::apply(&[a, b], |t| g(&t[0], &t[1], alpha))
        };
        Ok(match op {
            BinOp::Add => sym::binary(BinaryOp::Add, a, b),
            BinOp::Sub => sym::binary(BinaryOp::Sub, a, b),
            BinOp::Mul => sym::binary(BinaryOp::Mul, a, b),
            BinOp::Div => {
                if b.num().is_some_and(|d| d.abs() < EPS) {
                    return Err(self.err(
                        p,
                        format!(
                            "expected a non-zero divisor, found {}",
                            b.num().unwrap_or(0.0)
                        ),
                    ));
                }
                sym::binary(BinaryOp::Div, a, b)
            }
            BinOp::Pow => sym::power(a, b).map_err(|m| self.err(p, m))?,
            BinOp::Union => r(csg::r_union, self.alpha(f, p)?),
            BinOp::Inter => r(csg::r_intersection, self.alpha(f, p)?),
            BinOp::Diff => r(csg::r_difference, self.alpha(f, p)?),
            BinOp::And => sym::and(a, b),
            BinOp::Or => sym::or(a, b),
        })
    }

    /// The contents of the array named by argument `e`, all assigned.
    fn array_arg(
        &self,
        f: &Frame,
        e: &Expr,
        k: usize,
        func: &str,
    ) -> Result<(String, Vec<Val>), ReadError> {
        let (name, p) = match e {
            Expr::Name(n, p) if f.arrays.contains_key(n) => (n, *p),
            Expr::Name(n, p) => {
                return Err(self.err(
                    *p,
                    format!(
                    "expected an array as argument {k} of {func}, found '{n}', which is not one"
                ),
                ))
            }
            _ => {
                let p = expr_pos(e);
                return Err(self.err(
                    p,
                    format!(
                        "expected an array name as argument {k} of {func}, found an expression"
                    ),
                ));
            }
        };
        let mut vals = Vec::new();
        for (i, v) in f.arrays[name].iter().enumerate() {
            match v {
                Some(v) => vals.push(v.clone()),
                None => {
                    return Err(self.err(
                        p,
                        format!(
                        "expected every element of '{name}' assigned, found {name}[{}] unassigned",
                        i + 1
                    ),
                    ))
                }
            }
        }
        Ok((name.clone(), vals))
    }

    fn call(&mut self, f: &mut Frame, name: &str, args: &[Expr], p: Pos) -> Result<Val, ReadError> {
        if let Some((sig, display)) = lib::signature(name) {
            if args.len() != sig.len() {
                return Err(self.err(
                    p,
                    format!(
                        "expected {} arguments for {display}, found {}",
                        sig.len(),
                        args.len()
                    ),
                ));
            }
            let mut vals = Vec::new();
            let mut first_array = None;
            for (k, (kind, e)) in sig.chars().zip(args).enumerate() {
                if kind == 'A' {
                    let (n, v) = self.array_arg(f, e, k + 1, display)?;
                    first_array.get_or_insert(n);
                    vals.push(Arg::Array(v));
                } else {
                    vals.push(Arg::Real(self.eval(f, e)?));
                }
            }
            let alpha = self.alpha(f, p)?;
            return match lib::call(name, &vals, alpha)
                .map_err(|m| self.err(p, format!("{display}: {m}")))?
            {
                Outcome::Value(v) => Ok(v),
                Outcome::Remap(new) => {
                    if let Some(arr) = first_array.and_then(|n| f.arrays.get_mut(&n)) {
                        for (slot, v) in arr.iter_mut().zip(new) {
                            *slot = Some(v);
                        }
                    }
                    Ok(Val::Num(1.0))
                }
            };
        }
        let Some(m) = self.models.iter().find(|m| m.name == name) else {
            return Err(self.err(
                p,
                format!("expected a known function, found the unknown function '{name}'"),
            ));
        };
        let display = format!("{name}(x[{}], a[{}])", m.x_dim, m.a_dim);
        if args.len() != 2 && args.len() != 3 {
            return Err(self.err(
                p,
                format!(
                    "expected 2 or 3 array arguments for the model {display}, found {}",
                    args.len()
                ),
            ));
        }
        let (_, x) = self.array_arg(f, &args[0], 1, &display)?;
        let (_, a) = self.array_arg(f, &args[1], 2, &display)?;
        if x.len() != m.x_dim || a.len() != m.a_dim {
            return Err(self.err(
                p,
                format!(
                    "expected arrays of {} and {} elements for {display}, found {} and {}",
                    m.x_dim,
                    m.a_dim,
                    x.len(),
                    a.len()
                ),
            ));
        }
        self.depth += 1;
        if self.depth > MAX_CALL_DEPTH {
            return Err(self.err(p, format!("expected model calls nested at most {MAX_CALL_DEPTH} deep, found deeper (a recursive model?)")));
        }
        let r = self.run(m, x, a);
        self.depth -= 1;
        r
    }
}

/// Where an expression starts (for errors about arguments).
fn expr_pos(e: &Expr) -> Pos {
    match e {
        Expr::Num(_, p)
        | Expr::Name(_, p)
        | Expr::Index(_, _, p)
        | Expr::Call(_, _, p)
        | Expr::Unary(_, _, p) => *p,
        Expr::Chain(a, _) | Expr::Compare(a, _) => expr_pos(a),
    }
}

/// The state after an `if` whose condition depends on the coordinates: every variable
/// both branches leave becomes select(cond, then, else); one only a branch assigns has
/// no value afterwards.
fn merge(cond: &Val, t: Frame, e: Frame) -> Frame {
    let mut out = Frame {
        has_s: t.has_s,
        ..Frame::default()
    };
    for (k, a) in &t.scalars {
        if let Some(b) = e.scalars.get(k) {
            out.scalars.insert(k.clone(), sym::select(cond, a, b));
        }
    }
    for (k, a) in &t.arrays {
        if let Some(b) = e.arrays.get(k).filter(|b| b.len() == a.len()) {
            let v = a
                .iter()
                .zip(b)
                .map(|(x, y)| match (x, y) {
                    (Some(x), Some(y)) => Some(sym::select(cond, x, y)),
                    _ => None,
                })
                .collect();
            out.arrays.insert(k.clone(), v);
        }
    }
    out
}
