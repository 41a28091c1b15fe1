//! Reader of frepray's own `.frep` language (docs/frep-syntax.md): a tiny functional
//! language of numbers, lists, functions of x, y, z and solids, with named definitions,
//! user functions, a declared bounding box and one output.

mod builtins;
mod parse;
mod value;

use super::{Model, ReadError, MAX_DEPTH};
use crate::ray::Aabb;
use crate::shape::Shape;
use crate::tree::Tree;
use builtins::Args;
use parse::{Ast, Pos, Stmt};
use std::collections::HashMap;
use std::rc::Rc;
use value::V;

/// A user function `let f(a, b) = body`.
struct Func {
    params: Vec<String>,
    body: Ast,
}

/// What a global name is bound to.
enum Binding {
    Value(V),
    Func(Rc<Func>),
}

/// Evaluates a program.
struct Interp<'a> {
    file: &'a str,
    globals: HashMap<String, Binding>,
    depth: usize,
    /// Work done so far: expressions evaluated and solid parts made.
    work: u64,
    /// The most work allowed (see [`work_limit`]).
    max_work: u64,
    /// Expressions being evaluated, one inside the other (see [`MAX_NESTING`]).
    nesting: usize,
}

/// How deeply evaluations may nest in all, through expressions and calls together: each
/// is capped at [`MAX_DEPTH`], but a recursive function whose body nests 40 deep, 200
/// calls down, overflowed the stack (found by fuzzing). A thousand levels take about
/// 1 MB of stack.
const MAX_NESTING: usize = 5 * MAX_DEPTH;

/// The most work a model may take to evaluate (expressions evaluated plus the parts of
/// every solid made): a million steps, or eight per byte of a larger file. A few kB of
/// text can otherwise call a function 2^k times or copy a solid into 2^k parts (`let s1 =
/// union(s0, s0)`, `let s2 = union(s1, s1)`, …): found while fuzzing, such files ran for
/// minutes or filled memory; within the limit they fail in about a tenth of a second.
fn work_limit(text: &str) -> u64 {
    (text.len() as u64 * 8).max(1_000_000)
}

/// The parts of a shape, counting at most `cap` of them.
fn parts(s: &Shape, cap: u64) -> u64 {
    let mut n = 0;
    let mut stack = vec![s];
    while let Some(s) = stack.pop() {
        n += 1;
        if n >= cap {
            break;
        }
        match s {
            Shape::Function { .. } | Shape::Perturbed(_) => {}
            Shape::Union(v) | Shape::Intersection(v) => stack.extend(v),
            Shape::Difference(a, b) => stack.extend([&**a, &**b]),
            Shape::Transformed(_, a) => stack.push(a),
        }
    }
    n
}

/// Names that cannot be redefined.
fn reserved(name: &str) -> Option<&'static str> {
    match name {
        "x" | "y" | "z" => Some("a coordinate"),
        "pi" => Some("a constant"),
        _ if builtins::signature(name).is_some() => Some("a built-in function"),
        _ => None,
    }
}

impl Interp<'_> {
    fn err(&self, p: Pos, m: impl Into<String>) -> ReadError {
        ReadError::at(self.file, p.line, p.col, m)
    }

    /// Evaluates `e`, charging it and the solid it makes to the work budget.
    fn eval(&mut self, e: &Ast, locals: &HashMap<String, V>) -> Result<V, ReadError> {
        self.charge(1, e.pos())?;
        if self.nesting >= MAX_NESTING {
            return Err(self.err(
                e.pos(),
                format!(
                    "expected expressions and calls nested at most {MAX_NESTING} deep in all, \
                     found deeper (a recursive function?)"
                ),
            ));
        }
        self.nesting += 1;
        let v = self.eval_node(e, locals);
        self.nesting -= 1;
        let v = v?;
        if let V::Solid(s, _) = &v {
            let n = parts(s, self.max_work + 1 - self.work);
            self.charge(n, e.pos())?;
        }
        Ok(v)
    }

    fn charge(&mut self, n: u64, p: Pos) -> Result<(), ReadError> {
        self.work += n;
        if self.work > self.max_work {
            let m = self.max_work;
            return Err(self.err(
                p,
                format!(
                    "expected the model to evaluate within {m} steps, found more \
                     (a function called or a solid copied exponentially often?)"
                ),
            ));
        }
        Ok(())
    }

    fn eval_node(&mut self, e: &Ast, locals: &HashMap<String, V>) -> Result<V, ReadError> {
        Ok(match e {
            Ast::Num(v, _) => V::Num(*v),
            Ast::Name(n, p) => match n.as_str() {
                "x" => V::Field(Tree::x()),
                "y" => V::Field(Tree::y()),
                "z" => V::Field(Tree::z()),
                "pi" => V::Num(std::f64::consts::PI),
                _ => match (locals.get(n), self.globals.get(n)) {
                    (Some(v), _) | (None, Some(Binding::Value(v))) => v.clone(),
                    (None, Some(Binding::Func(_))) => {
                        return Err(self.err(
                            *p,
                            format!("expected a value, found the function '{n}' (call it: {n}(…))"),
                        ))
                    }
                    (None, None) if builtins::signature(n).is_some() => {
                        return Err(self.err(
                            *p,
                            format!(
                            "expected a value, found the built-in function '{n}' (call it: {n}(…))"
                        ),
                        ))
                    }
                    (None, None) => {
                        return Err(self.err(
                            *p,
                            format!("expected a defined name, found the undefined name '{n}'"),
                        ))
                    }
                },
            },
            Ast::List(items, _) => {
                let mut out = Vec::new();
                for it in items {
                    match self.eval(it, locals)? {
                        V::Num(v) => out.push(v),
                        V::List(l) => out.extend(l),
                        o => {
                            return Err(self.err(
                                it.pos(),
                                format!("expected a number in a list, found {}", o.kind()),
                            ))
                        }
                    }
                }
                V::List(out)
            }
            Ast::Neg(a, p) => value::neg(&self.eval(a, locals)?).map_err(|m| self.err(*p, m))?,
            Ast::Pow(a, b, p) => {
                let (x, y) = (self.eval(a, locals)?, self.eval(b, locals)?);
                value::pow(&x, &y).map_err(|m| self.err(*p, m))?
            }
            Ast::Chain(first, rest) => {
                let mut acc = self.eval(first, locals)?;
                for (op, p, rhs) in rest {
                    let b = self.eval(rhs, locals)?;
                    acc = value::arith(*op, &acc, &b).map_err(|m| self.err(*p, m))?;
                }
                acc
            }
            Ast::Call(name, args, p) => self.call(name, args, *p, locals)?,
        })
    }

    fn call(
        &mut self,
        name: &str,
        args: &[(Option<String>, Ast)],
        p: Pos,
        locals: &HashMap<String, V>,
    ) -> Result<V, ReadError> {
        if let Some(Binding::Func(f)) = self.globals.get(name) {
            let f = f.clone();
            let display = format!("{name}({})", f.params.join(", "));
            let bound = self.bind(&display, &f.params, f.params.len(), false, args, p, locals)?;
            let mut inner = HashMap::new();
            for (k, v) in f.params.iter().zip(bound.fixed) {
                inner.insert(
                    k.clone(),
                    v.expect("every parameter of a user function is required").0,
                );
            }
            self.depth += 1;
            if self.depth > MAX_DEPTH {
                return Err(self.err(p, format!("expected function calls nested at most {MAX_DEPTH} deep, found deeper (a recursive function?)")));
            }
            let r = self.eval(&f.body, &inner);
            self.depth -= 1;
            return r;
        }
        let Some(sig) = builtins::signature(name) else {
            let what = if locals.contains_key(name) || self.globals.contains_key(name) {
                "the value"
            } else {
                "the unknown function"
            };
            return Err(self.err(p, format!("expected a function, found {what} '{name}'")));
        };
        let params: Vec<String> = sig.params.iter().map(|s| s.to_string()).collect();
        let display = format!(
            "{name}({}{})",
            sig.params.join(", "),
            if sig.variadic { ", …" } else { "" }
        );
        let bound = self.bind(
            &display,
            &params,
            sig.required,
            sig.variadic,
            args,
            p,
            locals,
        )?;
        builtins::call(name, &bound).map_err(|(m, at)| self.err(at, format!("{name}: {m}")))
    }

    /// Binds positional and named arguments to parameters.
    #[allow(clippy::too_many_arguments)]
    fn bind(
        &mut self,
        display: &str,
        params: &[String],
        required: usize,
        variadic: bool,
        args: &[(Option<String>, Ast)],
        p: Pos,
        locals: &HashMap<String, V>,
    ) -> Result<Args, ReadError> {
        let mut fixed: Vec<Option<(V, Pos)>> = vec![None; params.len()];
        let mut rest = Vec::new();
        let mut next = 0;
        for (name, e) in args {
            let v = self.eval(e, locals)?;
            let at = e.pos();
            match name {
                None => {
                    while next < params.len() && fixed[next].is_some() {
                        next += 1;
                    }
                    if next < params.len() {
                        fixed[next] = Some((v, at));
                        next += 1;
                    } else if variadic {
                        rest.push((v, at));
                    } else {
                        return Err(self.err(
                            at,
                            format!(
                                "expected at most {} arguments for {display}, found more",
                                params.len()
                            ),
                        ));
                    }
                }
                Some(n) => {
                    let Some(k) = params.iter().position(|q| q == n) else {
                        return Err(self.err(
                            at,
                            format!("expected a parameter of {display}, found '{n}'"),
                        ));
                    };
                    if fixed[k].is_some() {
                        return Err(self.err(
                            at,
                            format!("expected each parameter of {display} once, found '{n}' twice"),
                        ));
                    }
                    fixed[k] = Some((v, at));
                }
            }
        }
        if let Some(k) = (0..required).find(|&k| fixed[k].is_none()) {
            return Err(self.err(
                p,
                format!(
                    "expected an argument '{}' for {display}, found none",
                    params[k]
                ),
            ));
        }
        Ok(Args {
            fixed,
            rest,
            pos: p,
        })
    }
}

/// Reads a `.frep` program.
pub(crate) fn read(text: &str, file: &str) -> Result<Model, ReadError> {
    let stmts = parse::parse(text, file)?;
    let mut it = Interp {
        file,
        globals: HashMap::new(),
        depth: 0,
        work: 0,
        max_work: work_limit(text),
        nesting: 0,
    };
    let mut output: Option<(Option<String>, Shape)> = None;
    let mut domain = None;
    let none = HashMap::new();
    let mut last = Pos { line: 1, col: 1 };
    for s in &stmts {
        match s {
            Stmt::Let(name, params, body, p, is_fn) => {
                if let Some(what) = reserved(name) {
                    return Err(it.err(*p, format!("expected a new name, found '{name}', {what}")));
                }
                if it.globals.contains_key(name) {
                    return Err(it.err(
                        *p,
                        format!("expected a new name, found '{name}', already defined"),
                    ));
                }
                if let Some((q, what)) = params.iter().find_map(|q| reserved(q).map(|w| (q, w))) {
                    return Err(it.err(
                        *p,
                        format!("expected a new parameter name, found '{q}', {what}"),
                    ));
                }
                let b = if *is_fn {
                    Binding::Func(Rc::new(Func {
                        params: params.clone(),
                        body: body.clone(),
                    }))
                } else {
                    Binding::Value(it.eval(body, &none)?)
                };
                it.globals.insert(name.clone(), b);
                last = *p;
            }
            Stmt::Bounds(lo, hi, p) => {
                let l = value::vec3(&it.eval(lo, &none)?).map_err(|m| it.err(lo.pos(), m))?;
                let h = value::vec3(&it.eval(hi, &none)?).map_err(|m| it.err(hi.pos(), m))?;
                if !(l.cmple(h).all() && l.is_finite() && h.is_finite()) {
                    return Err(it.err(
                        *p,
                        "expected finite bounds with lo ≤ hi on every axis, found others",
                    ));
                }
                if domain.is_some() {
                    return Err(it.err(*p, "expected one 'bounds' statement, found a second"));
                }
                domain = Some(Aabb::new(l, h));
                last = *p;
            }
            Stmt::Output(e, p) => {
                if output.is_some() {
                    return Err(it.err(*p, "expected one 'output' statement, found a second"));
                }
                let v = it.eval(e, &none)?;
                let shape = v.shape().map_err(|m| it.err(e.pos(), m))?;
                let name = match e {
                    Ast::Name(n, _) => Some(n.clone()),
                    _ => None,
                };
                output = Some((name, shape));
                last = *p;
            }
        }
    }
    let Some((name, mut shape)) = output else {
        return Err(it.err(
            last,
            "expected an 'output' statement naming the solid, found none",
        ));
    };
    if let (Shape::Function { domain: d, .. }, Some(b)) = (&mut shape, domain) {
        *d = Some(b);
    }
    Ok(Model {
        name,
        shape,
        domain,
    })
}
