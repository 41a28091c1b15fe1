//! HyperFun's built-in functions and its core library (hfSphere, hfBlock, hfShift3D, …).
//!
//! Definitions follow the HyperFun library sources (Pasko, Adzhiev et al.): primitives
//! take the coordinate array and a centre array and return F ≥ 0 inside; the space
//! mappings (hfShift3D, hfScale3D, hfRotate3D*, hfTwist*, hfTaper*) rewrite the
//! coordinate array passed to them in place (the inverse mapping) and return 1.

use crate::csg;
use crate::read::sym::{self, Val, EPS};
use crate::tree::{BinaryOp, Tree, UnaryOp};

/// An argument: a number-valued expression or a whole array.
pub(crate) enum Arg {
    Real(Val),
    Array(Vec<Val>),
}

/// What a call gives back.
pub(crate) enum Outcome {
    /// A value.
    Value(Val),
    /// New contents for the array passed first, and the value 1.
    Remap(Vec<Val>),
}

/// The signature of a built-in (`R` a real, `A` an array) and its display name.
pub(crate) fn signature(name: &str) -> Option<(&'static str, &'static str)> {
    Some(match name {
        "sqrt" => ("R", "sqrt"),
        "exp" => ("R", "exp"),
        "log" => ("R", "log"),
        "logd" => ("R", "logd"),
        "sin" => ("R", "sin"),
        "cos" => ("R", "cos"),
        "tan" => ("R", "tan"),
        "asin" => ("R", "asin"),
        "acos" => ("R", "acos"),
        "atan" => ("R", "atan"),
        "abs" => ("R", "abs"),
        "sinh" => ("R", "sinh"),
        "cosh" => ("R", "cosh"),
        "tanh" => ("R", "tanh"),
        "sign" => ("R", "sign"),
        "ceil" => ("R", "ceil"),
        "floor" => ("R", "floor"),
        "int" => ("R", "int"),
        "frac" => ("R", "frac"),
        "mod" => ("RR", "mod"),
        "max" => ("RR", "max"),
        "min" => ("RR", "min"),
        "atan2" => ("RR", "atan2"),
        "hfsphere" => ("AAR", "hfSphere(x, center, R)"),
        "hfellipsoid" => ("AARRR", "hfEllipsoid(x, center, a, b, c)"),
        "hfcylinderx" => ("AAR", "hfCylinderX(x, center, R)"),
        "hfcylindery" => ("AAR", "hfCylinderY(x, center, R)"),
        "hfcylinderz" => ("AAR", "hfCylinderZ(x, center, R)"),
        "hfconex" => ("AAR", "hfConeX(x, center, R)"),
        "hfconey" => ("AAR", "hfConeY(x, center, R)"),
        "hfconez" => ("AAR", "hfConeZ(x, center, R)"),
        "hftorusx" => ("AARR", "hfTorusX(x, center, R, r0)"),
        "hftorusy" => ("AARR", "hfTorusY(x, center, R, r0)"),
        "hftorusz" => ("AARR", "hfTorusZ(x, center, R, r0)"),
        "hfblock" => ("AARRR", "hfBlock(x, vertex, dx, dy, dz)"),
        "hfsuperell" => ("AARRRRR", "hfSuperell(x, center, a, b, c, s1, s2)"),
        "hfblenduni" => ("RRRRR", "hfBlendUni(f1, f2, a0, a1, a2)"),
        "hfblendint" => ("RRRRR", "hfBlendInt(f1, f2, a0, a1, a2)"),
        "hfshift3d" => ("ARRR", "hfShift3D(xt, dx, dy, dz)"),
        "hfscale3d" => ("ARRR", "hfScale3D(xt, sx, sy, sz)"),
        "hfrotate3dx" => ("AR", "hfRotate3DX(xt, theta)"),
        "hfrotate3dy" => ("AR", "hfRotate3DY(xt, theta)"),
        "hfrotate3dz" => ("AR", "hfRotate3DZ(xt, theta)"),
        "hftwistx" => ("ARRRR", "hfTwistX(xt, x1, x2, theta1, theta2)"),
        "hftwisty" => ("ARRRR", "hfTwistY(xt, y1, y2, theta1, theta2)"),
        "hftwistz" => ("ARRRR", "hfTwistZ(xt, z1, z2, theta1, theta2)"),
        "hftaperx" => ("ARRRR", "hfTaperX(xt, x1, x2, s1, s2)"),
        "hftapery" => ("ARRRR", "hfTaperY(xt, y1, y2, s1, s2)"),
        "hftaperz" => ("ARRRR", "hfTaperZ(xt, z1, z2, s1, s2)"),
        _ => return None,
    })
}

/// The argument values: reals as values, arrays as their first three elements (trees).
struct Args<'a> {
    args: &'a [Arg],
    all_known: bool,
}

impl Args<'_> {
    fn real(&self, i: usize) -> Val {
        match &self.args[i] {
            Arg::Real(v) => v.clone(),
            Arg::Array(_) => Val::Num(f64::NAN),
        }
    }
    fn t(&self, i: usize) -> Tree {
        self.real(i).tree()
    }
    /// A known real, for parameters that must not depend on the coordinates.
    fn known(&self, i: usize, what: &str) -> Result<f64, String> {
        self.real(i).num().ok_or_else(|| {
            format!("expected a constant {what}, found an expression of the coordinates")
        })
    }
    fn vec3(&self, i: usize, what: &str) -> Result<[Tree; 3], String> {
        match &self.args[i] {
            Arg::Array(v) if v.len() >= 3 => Ok([v[0].tree(), v[1].tree(), v[2].tree()]),
            Arg::Array(v) => Err(format!(
                "expected {what} with 3 elements, found {}",
                v.len()
            )),
            Arg::Real(_) => Err(format!("expected {what}, found a number")),
        }
    }
    fn value(&self, t: Tree) -> Outcome {
        Outcome::Value(if self.all_known {
            sym::apply(&[], |_| t)
        } else {
            Val::Tree(t)
        })
    }
}

fn known(v: &Val, f: impl Fn(f64) -> Option<String>) -> Result<(), String> {
    match v.num().and_then(f) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Calls built-in `name` (already checked against [`signature`]) with `alpha` the current
/// R-function parameter (used by hfBlock).
pub(crate) fn call(name: &str, args: &[Arg], alpha: f64) -> Result<Outcome, String> {
    let all_known = args.iter().all(|a| match a {
        Arg::Real(v) => v.num().is_some(),
        Arg::Array(v) => v.iter().all(|e| e.num().is_some()),
    });
    let a = Args { args, all_known };
    if !name.starts_with("hf") {
        return math(name, &a).map(Outcome::Value);
    }
    let sq = |t: Tree| t.square();
    Ok(match name {
        "hfsphere" => {
            let ([x, y, z], [cx, cy, cz]) = (a.vec3(0, "x")?, a.vec3(1, "the center")?);
            let r = a.t(2);
            a.value(r.square() - sq(x - cx) - sq(y - cy) - sq(z - cz))
        }
        "hfellipsoid" => {
            let ([x, y, z], [cx, cy, cz]) = (a.vec3(0, "x")?, a.vec3(1, "the center")?);
            for i in 2..5 {
                known(&a.real(i), |v| {
                    (v.abs() < EPS).then(|| format!("expected non-zero half-axes, found {v}"))
                })?;
            }
            a.value(1.0 - sq((x - cx) / a.t(2)) - sq((y - cy) / a.t(3)) - sq((z - cz) / a.t(4)))
        }
        "hfcylinderx" | "hfcylindery" | "hfcylinderz" | "hfconex" | "hfconey" | "hfconez" => {
            let (p, c) = (a.vec3(0, "x")?, a.vec3(1, "the center")?);
            let k = axis(name);
            let d: Vec<Tree> = (0..3).map(|i| &p[i] - &c[i]).collect();
            let (u, v) = ((k + 1) % 3, (k + 2) % 3);
            let r = a.t(2);
            if name.starts_with("hfcyl") {
                a.value(r.square() - sq(d[u].clone()) - sq(d[v].clone()))
            } else {
                a.value(sq(d[k].clone()) - sq(&d[u] / &r) - sq(&d[v] / &r))
            }
        }
        "hftorusx" | "hftorusy" | "hftorusz" => {
            let (p, c) = (a.vec3(0, "x")?, a.vec3(1, "the center")?);
            let k = axis(name);
            let d: Vec<Tree> = (0..3).map(|i| &p[i] - &c[i]).collect();
            let (u, v) = ((k + 1) % 3, (k + 2) % 3);
            let (big, r0) = (a.t(2), a.t(3));
            let ring = (sq(d[u].clone()) + sq(d[v].clone())).sqrt();
            // HyperFun's r0² − |d|² − R² + 2R·ρ is r0² − d_k² − (ρ − R)²: written so,
            // each of d_u, d_v appears once (inside ρ), and intervals bound it exactly
            // where the library's form counts them twice.
            a.value(r0.square() - sq(d[k].clone()) - sq(ring - big))
        }
        "hfblock" => {
            let (p, v) = (a.vec3(0, "x")?, a.vec3(1, "the vertex")?);
            for i in 2..5 {
                known(&a.real(i), |e| {
                    (e < 0.0).then(|| format!("expected non-negative edge lengths, found {e}"))
                })?;
            }
            // HyperFun's (p − v)·(v + e − p) as (e/2)² − (p − v − e/2)²: the same
            // quadratic with p once, so that intervals bound each slab exactly.
            let s: Vec<Tree> = (0..3)
                .map(|i| {
                    let h = a.t(2 + i) * 0.5;
                    h.square() - sq(&p[i] - &v[i] - &h)
                })
                .collect();
            let f = if alpha == 1.0 {
                s[0].min(&s[1]).min(&s[2])
            } else {
                // Without its zero term at α = 0, the form the R-function bound
                // recognises (a + b − √(a² + b²)).
                let r = |f: &Tree, g: &Tree| match alpha {
                    0.0 => f + g - (f.square() + g.square()).sqrt(),
                    _ => f + g - (f.square() + g.square() - 2.0 * alpha * (f * g)).sqrt(),
                };
                r(&r(&s[0], &s[1]), &s[2])
            };
            a.value(f)
        }
        "hfsuperell" => {
            let ([x, y, z], [cx, cy, cz]) = (a.vec3(0, "x")?, a.vec3(1, "the center")?);
            let mut k = [0.0; 5];
            for (i, slot) in k.iter_mut().enumerate() {
                let v = a.known(2 + i, "hfSuperell parameter")?;
                if v.abs() < EPS {
                    return Err(format!(
                        "expected non-zero hfSuperell parameters, found {v}"
                    ));
                }
                *slot = v;
            }
            let [ka, kb, kc, s1, s2] = k;
            let pw = |t: Tree, e: f64| sym::power(&Val::Tree(t), &Val::Num(e)).map(|v| v.tree());
            let xp = pw(((x - cx) / ka).abs(), 2.0 / s2)?;
            let yp = pw(((y - cy) / kb).abs(), 2.0 / s2)?;
            let zp = pw(((z - cz) / kc).abs(), 2.0 / s1)?;
            a.value(1.0 - pw(xp + yp, s2 / s1)? - zp)
        }
        "hfblenduni" | "hfblendint" => {
            let a1 = a.known(3, "blend parameter a1")?;
            let a2 = a.known(4, "blend parameter a2")?;
            let a0 = a.known(2, "blend parameter a0")?;
            if a1.abs() < EPS || a2.abs() < EPS {
                return Err(format!(
                    "expected non-zero blend parameters a1 and a2, found {a1} and {a2}"
                ));
            }
            let (f1, f2) = (a.t(0), a.t(1));
            a.value(if name == "hfblenduni" {
                csg::blend_union(&f1, &f2, a0, a1, a2)
            } else {
                csg::blend_intersection(&f1, &f2, a0, a1, a2)
            })
        }
        _ => return remap(name, &a),
    })
}

/// 0, 1, 2 for names ending in x, y, z.
fn axis(name: &str) -> usize {
    match name.as_bytes().last() {
        Some(b'x') => 0,
        Some(b'y') => 1,
        _ => 2,
    }
}

/// The space mappings: new coordinate array contents.
fn remap(name: &str, a: &Args) -> Result<Outcome, String> {
    let Arg::Array(orig) = &a.args[0] else {
        return Err("expected an array, found a number".into());
    };
    if orig.len() < 3 {
        return Err(format!(
            "expected a coordinate array with 3 elements, found {}",
            orig.len()
        ));
    }
    let p = a.vec3(0, "xt")?;
    let mut out: Vec<Tree> = p.to_vec();
    let k = axis(name);
    // Rotation by theta about axis k (HyperFun's inverse mapping): for X, y' = y c + z s.
    let rotate = |out: &mut Vec<Tree>, theta: &Tree| {
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        let (c, s) = (theta.cos(), theta.sin());
        let nu = &p[u] * &c + &p[v] * &s;
        let nv = -(&p[u] * &s) + &p[v] * &c;
        out[u] = nu;
        out[v] = nv;
    };
    match name {
        "hfshift3d" => {
            for i in 0..3 {
                out[i] = &p[i] - a.t(1 + i);
            }
        }
        "hfscale3d" => {
            for i in 0..3 {
                known(&a.real(1 + i), |v| {
                    (v.abs() < EPS).then(|| format!("expected non-zero scale factors, found {v}"))
                })?;
                out[i] = &p[i] / a.t(1 + i);
            }
        }
        "hfrotate3dx" | "hfrotate3dy" | "hfrotate3dz" => rotate(&mut out, &a.t(1)),
        "hftwistx" | "hftwisty" | "hftwistz" => {
            let t = (&p[k] - a.t(1)) / (a.t(2) - a.t(1));
            let theta = (1.0 - &t) * a.t(3) + t * a.t(4);
            rotate(&mut out, &theta);
        }
        "hftaperx" | "hftapery" | "hftaperz" => {
            for i in 3..5 {
                known(&a.real(i), |v| {
                    (v <= 0.0).then(|| format!("expected positive taper scales, found {v}"))
                })?;
            }
            if let (Some(x1), Some(x2)) = (a.real(1).num(), a.real(2).num()) {
                if x2 <= x1 {
                    return Err(format!("expected the end of the taper interval above its start, found {x1} and {x2}"));
                }
            }
            let t = ((&p[k] - a.t(1)) / (a.t(2) - a.t(1)))
                .max(&Tree::constant(0.0))
                .min(&Tree::constant(1.0));
            let scale = (1.0 - &t) * a.t(3) + t * a.t(4);
            let (u, v) = ((k + 1) % 3, (k + 2) % 3);
            out[u] = &p[u] / &scale;
            out[v] = &p[v] / &scale;
        }
        _ => return Err(format!("'{name}' is not a library function")),
    }
    let mut vals: Vec<Val> = orig.clone();
    for (i, t) in out.into_iter().enumerate() {
        if t.ptr() != p[i].ptr() {
            vals[i] = if a.all_known {
                sym::apply(&[], |_| t)
            } else {
                Val::Tree(t)
            };
        }
    }
    Ok(Outcome::Remap(vals))
}

/// The mathematical built-ins.
fn math(name: &str, a: &Args) -> Result<Val, String> {
    use UnaryOp as U;
    let v = a.real(0);
    let un = |op| sym::unary(op, &v);
    let r = match name {
        "sqrt" => {
            known(&v, |x| {
                (x < 0.0).then(|| format!("expected a non-negative argument of sqrt, found {x}"))
            })?;
            un(U::Sqrt)
        }
        "exp" => un(U::Exp),
        "log" | "logd" => {
            known(&v, |x| {
                (x <= 0.0).then(|| format!("expected a positive argument of {name}, found {x}"))
            })?;
            let l = un(U::Ln);
            if name == "log" {
                l
            } else {
                sym::apply(&[&l], |t| &t[0] / std::f64::consts::LN_10)
            }
        }
        "sin" => un(U::Sin),
        "cos" => un(U::Cos),
        "tan" => un(U::Tan),
        "asin" | "acos" => {
            known(&v, |x| {
                (x.abs() > 1.0)
                    .then(|| format!("expected an argument of {name} in -1..1, found {x}"))
            })?;
            un(if name == "asin" { U::Asin } else { U::Acos })
        }
        "atan" => un(U::Atan),
        "abs" => un(U::Abs),
        "ceil" => un(U::Ceil),
        "floor" => un(U::Floor),
        "sinh" => sym::apply(&[&v], |t| 0.5 * (t[0].exp() - (-&t[0]).exp())),
        "cosh" => sym::apply(&[&v], |t| 0.5 * (t[0].exp() + (-&t[0]).exp())),
        // 1 − 2/(e^{2v} + 1): no overflow to ∞/∞ for large |v|.
        "tanh" => sym::apply(&[&v], |t| 1.0 - 2.0 / ((2.0 * &t[0]).exp() + 1.0)),
        // −1 below zero, else 1; sign(0) = 1 as in HyperFun.
        "sign" => sym::apply(&[&v], |t| {
            let s = Tree::binary(BinaryOp::Compare, t[0].clone(), Tree::constant(0.0));
            &s + Tree::unary(U::Not, s.clone())
        }),
        "int" => sym::apply(&[&v], |t| trunc(&t[0])),
        "frac" => sym::apply(&[&v], |t| &t[0] - trunc(&t[0])),
        "mod" => {
            // HyperFun: fmod of both arguments rounded half up.
            let b = a.real(1);
            known(&b, |y| {
                ((y + 0.5).floor() == 0.0).then(|| {
                    format!("expected a divisor of mod that rounds to non-zero, found {y}")
                })
            })?;
            sym::apply(&[&v, &b], |t| {
                let p = floor(&(&t[0] + 0.5));
                let q = floor(&(&t[1] + 0.5));
                &p - &q * trunc(&(&p / &q))
            })
        }
        "max" => sym::binary(BinaryOp::Max, &v, &a.real(1)),
        "min" => sym::binary(BinaryOp::Min, &v, &a.real(1)),
        "atan2" => sym::binary(BinaryOp::Atan2, &v, &a.real(1)),
        _ => return Err(format!("'{name}' is not a built-in function")),
    };
    Ok(r)
}

/// Rounding toward zero: ⌊|t|⌋ with t's sign.
fn trunc(t: &Tree) -> Tree {
    floor(&t.abs()) * Tree::binary(BinaryOp::Compare, t.clone(), Tree::constant(0.0))
}

/// ⌊t⌋.
fn floor(t: &Tree) -> Tree {
    Tree::unary(UnaryOp::Floor, t.clone())
}
