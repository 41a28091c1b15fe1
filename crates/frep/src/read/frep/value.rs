//! `.frep` values, their conversions and arithmetic.
//!
//! Numbers, lists, functions of x, y, z, quadrics, perturbation terms and solids are all
//! values. Quadrics stay quadrics under linear combinations (so that `sphere(…) - 0.1`
//! keeps the exact intersection path), `q^3` of a quadric is a perturbation term, and any
//! other arithmetic lowers its operands to expression trees.

use crate::perturbed::PerturbedQuadric;
use crate::quadric::Quadric;
use crate::read::sym::powi_tree;
use crate::shape::Shape;
use crate::tree::{Tree, TreeOp};
use std::sync::{Arc, OnceLock};

/// A `.frep` value.
#[derive(Clone, Debug)]
pub(crate) enum V {
    Num(f64),
    /// Numbers in brackets (nested brackets are flattened).
    List(Vec<f64>),
    /// A function of x, y, z.
    Field(Tree),
    Quadric(Quadric),
    /// f · q³, a perturbation (compact, q ≥ 0 only, inside `perturb`).
    Term(f64, Quadric),
    /// A solid, with its expression tree once one was asked for.
    Solid(Shape, Lowered),
}

/// A solid's expression tree, made the first time it is asked for and shared by every
/// copy of the value: a solid bound by `let` and used N times in arithmetic (`-b`,
/// `b * 2`) was otherwise lowered N times, quadratic in the file (a 60 kB model took a
/// second; found by fuzzing).
#[derive(Clone, Debug, Default)]
pub(crate) struct Lowered(Arc<OnceLock<Result<Tree, String>>>);

impl V {
    /// A solid value.
    pub fn solid(s: Shape) -> V {
        V::Solid(s, Lowered::default())
    }

    /// The kind of value, for "expected …, found …" errors.
    pub fn kind(&self) -> &'static str {
        match self {
            V::Num(_) => "a number",
            V::List(_) => "a list",
            V::Field(_) => "a function of x, y, z",
            V::Quadric(_) => "a quadric",
            V::Term(..) => "a perturbation term f * q^3",
            V::Solid(..) => "a solid",
        }
    }

    /// The value as a solid (F ≥ 0 inside); numbers and lists are not solids.
    pub fn shape(&self) -> Result<Shape, String> {
        Ok(match self {
            V::Field(t) => Shape::function(t.clone()),
            V::Quadric(q) => Shape::Perturbed(PerturbedQuadric::new(*q)),
            V::Term(..) => Shape::function(self.tree()?),
            V::Solid(s, _) => s.clone(),
            V::Num(_) | V::List(_) => {
                return Err(format!("expected a solid, found {}", self.kind()))
            }
        })
    }

    /// The value as an expression tree (numbers are constants).
    pub fn tree(&self) -> Result<Tree, String> {
        Ok(match self {
            V::Num(v) => Tree::constant(*v),
            V::Field(t) => t.clone(),
            V::Quadric(q) => q.to_tree(),
            V::Term(f, q) => *f * q.to_tree().powi(3),
            V::Solid(s, l) => {
                l.0.get_or_init(|| s.to_tree().map_err(|e| e.to_string()))
                    .clone()?
            }
            V::List(_) => {
                return Err("expected a number or a function of x, y, z, found a list".into())
            }
        })
    }

    /// The value as a number.
    pub fn num(&self) -> Result<f64, String> {
        match self {
            V::Num(v) => Ok(*v),
            _ => Err(format!("expected a number, found {}", self.kind())),
        }
    }
}

/// `a op b` for `op` one of `+ - * /`.
pub(crate) fn arith(op: char, a: &V, b: &V) -> Result<V, String> {
    use V::*;
    type Q = crate::quadric::Quadric;
    let qop = |p: &Q, q: &Q, s: f64| {
        let mut c = p.c;
        for (k, v) in c.iter_mut().enumerate() {
            *v += s * q.c[k];
        }
        Q::new(c)
    };
    let qscale = |q: &Q, s: f64| Q::new(q.c.map(|v| v * s));
    let qconst = |q: &Q, k: f64| {
        let mut c = q.c;
        c[9] += k;
        Q::new(c)
    };
    Ok(match (op, a, b) {
        ('+', Num(x), Num(y)) => Num(x + y),
        ('-', Num(x), Num(y)) => Num(x - y),
        ('*', Num(x), Num(y)) => Num(x * y),
        ('/', Num(x), Num(y)) => Num(x / y),
        ('+', Quadric(p), Quadric(q)) => Quadric(qop(p, q, 1.0)),
        ('-', Quadric(p), Quadric(q)) => Quadric(qop(p, q, -1.0)),
        ('+', Quadric(q), Num(k)) | ('+', Num(k), Quadric(q)) => Quadric(qconst(q, *k)),
        ('-', Quadric(q), Num(k)) => Quadric(qconst(q, -k)),
        ('-', Num(k), Quadric(q)) => Quadric(qconst(&qscale(q, -1.0), *k)),
        ('*', Quadric(q), Num(k)) | ('*', Num(k), Quadric(q)) => Quadric(qscale(q, *k)),
        ('/', Quadric(q), Num(k)) => Quadric(qscale(q, 1.0 / k)),
        ('*', Term(f, q), Num(k)) | ('*', Num(k), Term(f, q)) => Term(f * k, *q),
        ('/', Term(f, q), Num(k)) => Term(f / k, *q),
        (_, List(_), _) | (_, _, List(_)) => {
            return Err(format!(
                "expected numbers or functions on both sides of '{op}', found a list"
            ))
        }
        _ => {
            let (x, y) = (a.tree()?, b.tree()?);
            Field(match op {
                '+' => x + y,
                '-' => x - y,
                '*' => x * y,
                _ => x / y,
            })
        }
    })
}

/// −a.
pub(crate) fn neg(a: &V) -> Result<V, String> {
    Ok(match a {
        V::Num(v) => V::Num(-v),
        V::Quadric(q) => V::Quadric(Quadric::new(q.c.map(|v| -v))),
        V::Term(f, q) => V::Term(-f, *q),
        V::List(l) => V::List(l.iter().map(|v| -v).collect()),
        _ => V::Field(-a.tree()?),
    })
}

/// a ^ b: b must be a number; for anything but a number, a whole number.
pub(crate) fn pow(a: &V, b: &V) -> Result<V, String> {
    let e = match b {
        V::Num(e) => *e,
        _ => {
            return Err(format!(
                "expected a number as the exponent, found {} (use pow(a, b))",
                b.kind()
            ))
        }
    };
    if let V::Num(x) = a {
        return Ok(V::Num(x.powf(e)));
    }
    if e.fract() != 0.0 || e.abs() > 1e6 {
        return Err(format!(
            "expected a whole-number exponent, found {e} (use pow(a, b) for others)"
        ));
    }
    let n = e as i64;
    Ok(match (a, n) {
        (V::Quadric(q), 3) => V::Term(1.0, *q),
        (V::Quadric(q), 1) => V::Quadric(*q),
        _ => V::Field(powi_tree(&a.tree()?, n)),
    })
}

/// The unit axis named by a coordinate (`x`, `y`, `z`) or given as a list of 3 numbers.
pub(crate) fn axis(v: &V) -> Result<glam::DVec3, String> {
    if let V::Field(t) = v {
        if let TreeOp::Var(var) = t.op() {
            return Ok(match var {
                crate::tree::Var::X => glam::DVec3::X,
                crate::tree::Var::Y => glam::DVec3::Y,
                crate::tree::Var::Z => glam::DVec3::Z,
            });
        }
    }
    let d = vec3(v)?;
    if d.length() == 0.0 || !d.is_finite() {
        return Err("expected a non-zero axis, found [0, 0, 0]".into());
    }
    Ok(d.normalize())
}

/// A list of exactly 3 numbers.
pub(crate) fn vec3(v: &V) -> Result<glam::DVec3, String> {
    match v {
        V::List(l) if l.len() == 3 => Ok(glam::DVec3::new(l[0], l[1], l[2])),
        V::List(l) => Err(format!(
            "expected a list of 3 numbers, found a list of {}",
            l.len()
        )),
        _ => Err(format!("expected a list of 3 numbers, found {}", v.kind())),
    }
}
