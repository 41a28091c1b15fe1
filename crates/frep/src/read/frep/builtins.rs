//! The `.frep` library: mathematics, quadrics, perturbations, set operations, blends and
//! transforms (docs/frep-syntax.md lists them with their parameters).

use super::parse::Pos;
use super::value::{axis, vec3, V};
use crate::csg;
use crate::perturbed::PerturbedQuadric;
use crate::quadric::Quadric;
use crate::shape::Shape;
use crate::transform::Affine;
use crate::tree::{BinaryOp, Tree, UnaryOp};
use glam::{DMat3, DVec3};

/// A built-in's parameters: the first `required` must be given; `variadic` ones take any
/// number of further positional arguments.
pub(crate) struct Sig {
    pub params: &'static [&'static str],
    pub required: usize,
    pub variadic: bool,
}

const fn sig(params: &'static [&'static str], required: usize, variadic: bool) -> Sig {
    Sig {
        params,
        required,
        variadic,
    }
}

/// The signature of built-in `name`.
pub(crate) fn signature(name: &str) -> Option<Sig> {
    Some(match name {
        "sqrt" | "abs" | "exp" | "log" | "sin" | "cos" | "tan" | "asin" | "acos" | "atan"
        | "floor" | "ceil" | "round" => sig(&["a"], 1, false),
        "atan2" => sig(&["y", "x"], 2, false),
        "mod" => sig(&["a", "b"], 2, false),
        "pow" => sig(&["a", "b"], 2, false),
        "min" | "max" => sig(&["a"], 1, true),
        "sphere" => sig(&["center", "radius"], 2, false),
        "ellipsoid" => sig(&["center", "radii"], 2, false),
        "cylinder" => sig(&["axis", "radius", "center"], 2, false),
        "cone" => sig(&["axis", "angle", "apex"], 2, false),
        "paraboloid" => sig(&["axis", "k", "apex"], 2, false),
        "plane" => sig(&["normal", "offset"], 1, false),
        "quadric" => sig(&["c"], 1, true),
        "box" => sig(&["center", "size"], 2, false),
        "torus" => sig(&["major", "minor", "center", "axis"], 2, false),
        "perturb" => sig(&["base"], 1, true),
        "union" | "intersection" | "difference" => sig(&["a"], 1, true),
        "r_union" | "r_intersection" | "r_difference" => sig(&["a", "b", "alpha"], 2, false),
        "blend_union" | "blend_intersection" => sig(&["a", "b", "a0", "a1", "a2"], 5, false),
        "translate" => sig(&["offset", "solid"], 2, false),
        "rotate" => sig(&["axis", "angle", "solid"], 3, false),
        "rotate_x" | "rotate_y" | "rotate_z" => sig(&["angle", "solid"], 2, false),
        "scale" => sig(&["factor", "solid"], 2, false),
        "affine" => sig(&["matrix", "offset", "solid"], 3, false),
        _ => return None,
    })
}

/// Bound arguments of one call.
pub(crate) struct Args {
    /// The fixed parameters (None when an optional one was not given).
    pub fixed: Vec<Option<(V, Pos)>>,
    /// Further positional arguments of a variadic built-in.
    pub rest: Vec<(V, Pos)>,
    /// The call.
    pub pos: Pos,
}

type R<T> = Result<T, (String, Pos)>;

impl Args {
    fn get(&self, i: usize) -> Option<&(V, Pos)> {
        self.fixed.get(i).and_then(|a| a.as_ref())
    }
    fn v(&self, i: usize) -> &V {
        &self.get(i).expect("required parameters are bound").0
    }
    fn at(&self, i: usize) -> Pos {
        self.get(i).map_or(self.pos, |a| a.1)
    }
    fn with<T>(&self, i: usize, f: impl FnOnce(&V) -> Result<T, String>) -> R<T> {
        f(self.v(i)).map_err(|m| (m, self.at(i)))
    }
    fn num(&self, i: usize) -> R<f64> {
        self.with(i, V::num)
    }
    fn num_or(&self, i: usize, d: f64) -> R<f64> {
        self.get(i).map_or(Ok(d), |_| self.num(i))
    }
    fn vec_or(&self, i: usize, d: DVec3) -> R<DVec3> {
        self.get(i).map_or(Ok(d), |_| self.with(i, vec3))
    }
    fn tree(&self, i: usize) -> R<Tree> {
        self.with(i, V::tree)
    }
    fn shape(&self, i: usize) -> R<Shape> {
        self.with(i, V::shape)
    }
    /// Every argument, fixed then rest, that was given.
    fn all(&self) -> Vec<(V, Pos)> {
        self.fixed
            .iter()
            .flatten()
            .cloned()
            .chain(self.rest.iter().cloned())
            .collect()
    }
}

fn unary_op(name: &str) -> Option<UnaryOp> {
    use UnaryOp as U;
    Some(match name {
        "sqrt" => U::Sqrt,
        "abs" => U::Abs,
        "exp" => U::Exp,
        "log" => U::Ln,
        "sin" => U::Sin,
        "cos" => U::Cos,
        "tan" => U::Tan,
        "asin" => U::Asin,
        "acos" => U::Acos,
        "atan" => U::Atan,
        "floor" => U::Floor,
        "ceil" => U::Ceil,
        "round" => U::Round,
        _ => return None,
    })
}

/// A unary or binary operation, folded to a number when every operand is one.
fn folded(args: &[Tree], t: Tree) -> V {
    if args.iter().all(|a| a.as_const().is_some()) {
        let e = crate::Expr::new(&t);
        return V::Num(e.eval([0.0; 3]));
    }
    V::Field(t)
}

fn moved(a: &Args, m: Affine, solid: usize) -> R<V> {
    if m.inverse().is_none() {
        return Err((
            "expected an invertible transform, found a singular one".into(),
            a.pos,
        ));
    }
    Ok(V::solid(Shape::Transformed(m, Box::new(a.shape(solid)?))))
}

/// Calls built-in `name` with bound arguments.
pub(crate) fn call(name: &str, a: &Args) -> R<V> {
    if let Some(op) = unary_op(name) {
        let t = a.tree(0)?;
        let u = Tree::unary(op, t.clone());
        return Ok(folded(std::slice::from_ref(&t), u));
    }
    let bin = |op| -> R<V> {
        let (x, y) = (a.tree(0)?, a.tree(1)?);
        Ok(folded(&[x.clone(), y.clone()], Tree::binary(op, x, y)))
    };
    let deg = |i| -> R<f64> { Ok(a.num(i)?.to_radians()) };
    Ok(match name {
        "atan2" => bin(BinaryOp::Atan2)?,
        "mod" => bin(BinaryOp::Mod)?,
        "pow" => {
            let (x, y) = (a.tree(0)?, a.tree(1)?);
            folded(&[x.clone(), y.clone()], (y * x.ln()).exp())
        }
        "min" | "max" => {
            let all = a.all();
            let mut acc = all[0].0.tree().map_err(|m| (m, all[0].1))?;
            let mut trees = vec![acc.clone()];
            for (v, p) in &all[1..] {
                let t = v.tree().map_err(|m| (m, *p))?;
                trees.push(t.clone());
                acc = if name == "min" {
                    acc.min(&t)
                } else {
                    acc.max(&t)
                };
            }
            folded(&trees, acc)
        }
        "sphere" => V::Quadric(Quadric::sphere(a.with(0, vec3)?, a.num(1)?)),
        "ellipsoid" => {
            let r = a.with(1, vec3)?;
            if r.min_element() <= 0.0 {
                return Err(("expected positive radii, found one ≤ 0".into(), a.at(1)));
            }
            V::Quadric(Quadric::ellipsoid(a.with(0, vec3)?, r))
        }
        "cylinder" => V::Quadric(Quadric::cylinder(
            a.vec_or(2, DVec3::ZERO)?,
            a.with(0, axis)?,
            a.num(1)?,
        )),
        "cone" => V::Quadric(Quadric::cone(
            a.vec_or(2, DVec3::ZERO)?,
            a.with(0, axis)?,
            deg(1)?,
        )),
        "paraboloid" => V::Quadric(Quadric::paraboloid(
            a.vec_or(2, DVec3::ZERO)?,
            a.with(0, axis)?,
            a.num(1)?,
        )),
        "plane" => V::Quadric(Quadric::plane(a.with(0, axis)?, a.num_or(1, 0.0)?)),
        "quadric" => {
            let mut c = Vec::new();
            for (v, p) in a.all() {
                match v {
                    V::Num(x) => c.push(x),
                    V::List(l) => c.extend(l),
                    o => return Err((format!("expected 10 numbers, found {}", o.kind()), p)),
                }
            }
            let c: [f64; 10] = c.try_into().map_err(|c: Vec<f64>| {
                (
                    format!("expected 10 coefficients, found {}", c.len()),
                    a.pos,
                )
            })?;
            V::Quadric(Quadric::new(c))
        }
        "box" => {
            let (c, s) = (a.with(0, vec3)?, a.with(1, vec3)?);
            let h = s * 0.5;
            let faces = [DVec3::X, DVec3::Y, DVec3::Z]
                .into_iter()
                .flat_map(|n| {
                    let (k, hk) = (n.dot(c), n.dot(h));
                    [Quadric::plane(n, k + hk), Quadric::plane(-n, hk - k)]
                })
                .map(|q| Shape::Perturbed(PerturbedQuadric::new(q)))
                .collect();
            V::solid(Shape::Intersection(faces))
        }
        "torus" => {
            let (big, r) = (a.num(0)?, a.num(1)?);
            let c = a.vec_or(2, DVec3::ZERO)?;
            let ax = match a.get(3) {
                Some(_) => a.with(3, axis)?,
                None => DVec3::Z,
            };
            // The squared distance from the axis as (u·d)² + (v·d)² over a frame (u, v)
            // perpendicular to it, not |d|² − (a·d)²: that difference counts every
            // coordinate twice, and interval arithmetic does not cancel it (an axis
            // along z leaves dz² − dz², as wide as dz²'s range, in every box's bound).
            let d = [Tree::x() - c.x, Tree::y() - c.y, Tree::z() - c.z];
            let (u, v) = perpendicular_pair(ax);
            let along = linear(ax, &d);
            let ring = (linear(u, &d).square() + linear(v, &d).square()).sqrt() - big;
            V::Field(r * r - ring.square() - along.square())
        }
        "perturb" => {
            let mut pq = match a.v(0) {
                V::Quadric(q) => PerturbedQuadric::new(*q),
                V::Solid(Shape::Perturbed(p), _) => p.clone(),
                o => {
                    return Err((
                        format!("expected a quadric as the base, found {}", o.kind()),
                        a.at(0),
                    ))
                }
            };
            for (v, p) in &a.rest {
                match v {
                    V::Term(f, q) => pq.push(*f, *q),
                    o => {
                        return Err((
                            format!("expected a perturbation term f * q^3, found {}", o.kind()),
                            *p,
                        ))
                    }
                }
            }
            V::solid(Shape::Perturbed(pq))
        }
        "union" | "intersection" | "difference" => {
            let all = a.all();
            if all.len() < 2 {
                return Err((
                    format!("expected at least 2 solids for {name}, found {}", all.len()),
                    a.pos,
                ));
            }
            let mut shapes = Vec::new();
            for (v, p) in &all {
                shapes.push(v.shape().map_err(|m| (m, *p))?);
            }
            V::solid(match name {
                "union" => Shape::Union(shapes),
                "intersection" => Shape::Intersection(shapes),
                _ => {
                    let first = shapes.remove(0);
                    let cut = if shapes.len() == 1 {
                        shapes.remove(0)
                    } else {
                        Shape::Union(shapes)
                    };
                    Shape::Difference(Box::new(first), Box::new(cut))
                }
            })
        }
        "r_union" | "r_intersection" | "r_difference" => {
            let alpha = a.num_or(2, 0.0)?;
            if !(alpha > -1.0 && alpha <= 1.0) {
                return Err((format!("expected alpha in (-1, 1], found {alpha}"), a.at(2)));
            }
            let (f, g) = (a.tree(0)?, a.tree(1)?);
            V::Field(match name {
                "r_union" => csg::r_union(&f, &g, alpha),
                "r_intersection" => csg::r_intersection(&f, &g, alpha),
                _ => csg::r_difference(&f, &g, alpha),
            })
        }
        "blend_union" | "blend_intersection" => {
            let (a0, a1, a2) = (a.num(2)?, a.num(3)?, a.num(4)?);
            if a1 == 0.0 || a2 == 0.0 {
                return Err((
                    "expected non-zero a1 and a2, found 0".into(),
                    a.at(if a1 == 0.0 { 3 } else { 4 }),
                ));
            }
            let (f, g) = (a.tree(0)?, a.tree(1)?);
            V::Field(if name == "blend_union" {
                csg::blend_union(&f, &g, a0, a1, a2)
            } else {
                csg::blend_intersection(&f, &g, a0, a1, a2)
            })
        }
        "translate" => moved(a, Affine::translate(a.with(0, vec3)?), 1)?,
        "rotate" => moved(a, Affine::rotate(a.with(0, axis)?, deg(1)?), 2)?,
        "rotate_x" => moved(a, Affine::rotate(DVec3::X, deg(0)?), 1)?,
        "rotate_y" => moved(a, Affine::rotate(DVec3::Y, deg(0)?), 1)?,
        "rotate_z" => moved(a, Affine::rotate(DVec3::Z, deg(0)?), 1)?,
        "scale" => {
            let s = match a.v(0) {
                V::Num(k) => DVec3::splat(*k),
                _ => a.with(0, vec3)?,
            };
            moved(a, Affine::scale(s), 1)?
        }
        "affine" => {
            let m = match a.v(0) {
                V::List(l) if l.len() == 9 => {
                    DMat3::from_cols_array(&[l[0], l[1], l[2], l[3], l[4], l[5], l[6], l[7], l[8]])
                        .transpose()
                }
                o => {
                    let found = match o {
                        V::List(l) => format!("a list of {}", l.len()),
                        o => o.kind().to_string(),
                    };
                    return Err((
                        format!("expected a 3×3 matrix (9 numbers, row by row), found {found}"),
                        a.at(0),
                    ));
                }
            };
            moved(
                a,
                Affine {
                    m,
                    t: a.with(1, vec3)?,
                },
                2,
            )?
        }
        _ => {
            return Err((
                format!("expected a known function, found the unknown function '{name}'"),
                a.pos,
            ))
        }
    })
}

/// w·d without the terms whose weight is 0 (0·x is not folded: it is NaN at infinity;
/// the expression builder folds weights of ±1): an axis-aligned w gives one coordinate.
fn linear(w: DVec3, d: &[Tree; 3]) -> Tree {
    let mut terms = (0..3).filter(|&k| w[k] != 0.0).map(|k| w[k] * &d[k]);
    let first = terms.next().unwrap_or_else(|| Tree::constant(0.0));
    terms.fold(first, |acc, t| acc + t)
}

/// Two unit vectors perpendicular to the unit `axis` and to each other: the other two
/// coordinate axes when `axis` is one of them.
fn perpendicular_pair(axis: DVec3) -> (DVec3, DVec3) {
    let units = [DVec3::X, DVec3::Y, DVec3::Z];
    match units.iter().position(|&e| axis == e || axis == -e) {
        Some(k) => (units[(k + 1) % 3], units[(k + 2) % 3]),
        None => axis.any_orthonormal_pair(),
    }
}
