//! The solid pool: each object's resolved [`frep::Shape`] (transforms folded in) with
//! its bounds.
//!
//! `frep::Shape` has neither `PartialEq` nor `Serialize` (and its `Debug` expands
//! shared subtrees of a DAG), so the pool compares, prints and serialises solids through
//! a canonical structural form, [`SolidForm`]: the CSG and transform nodes as they are,
//! perturbed quadrics by their coefficients, and every expression as the node list of
//! [`frep::Expr`] (shared and equal subexpressions merged, constants folded), each node
//! written as text such as `"mul %0 %3"`. Two shapes with the same form are the same
//! function. The pool sits behind this small type so that it can later hold frep's flat
//! solid form instead.

use crate::data::SolidId;
use frep::expr::Node;
use frep::{Aabb, Expr, Shape};
use serde::{Serialize, Serializer};
use std::fmt;

/// The solids of a scene (see the module docs).
#[derive(Clone, Default)]
pub struct SolidPool {
    shapes: Vec<Shape>,
    bounds: Vec<Aabb>,
}

impl SolidPool {
    /// Adds a shape whose solid has `bounds`; returns its id.
    pub fn push(&mut self, shape: Shape, bounds: Aabb) -> SolidId {
        self.shapes.push(shape);
        self.bounds.push(bounds);
        SolidId(self.shapes.len() as u32 - 1)
    }

    /// The shape of `id`.
    pub fn shape(&self, id: SolidId) -> &Shape {
        &self.shapes[id.index()]
    }

    /// The bounds of `id`'s solid (possibly infinite for an unbounded solid).
    pub fn bounds(&self, id: SolidId) -> Aabb {
        self.bounds[id.index()]
    }

    /// Number of solids.
    pub fn len(&self) -> usize {
        self.shapes.len()
    }

    /// Whether the pool is empty.
    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// The canonical forms of the solids, in id order.
    pub fn forms(&self) -> Vec<SolidEntry> {
        self.shapes
            .iter()
            .zip(&self.bounds)
            .map(|(s, b)| SolidEntry {
                lo: b.lo.to_array(),
                hi: b.hi.to_array(),
                shape: SolidForm::of(s),
            })
            .collect()
    }
}

impl PartialEq for SolidPool {
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len() && self.forms() == other.forms()
    }
}

impl fmt::Debug for SolidPool {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.forms()).finish()
    }
}

impl Serialize for SolidPool {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.forms().serialize(s)
    }
}

/// One solid of the pool as [`SolidPool`] compares and serialises it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SolidEntry {
    /// Lower corner of the solid's bounds.
    pub lo: [f64; 3],
    /// Upper corner.
    pub hi: [f64; 3],
    /// The shape.
    pub shape: SolidForm,
}

/// The canonical structural form of a [`Shape`] (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SolidForm {
    /// An expression: its nodes in evaluation order, the root last.
    Function {
        /// Nodes such as `"x"`, `"const 2"`, `"sqrt %1"`, `"add %0 %2"`, `"powi %1 3"`.
        nodes: Vec<String>,
        /// The declared domain as (lo, hi), if any.
        domain: Option<[[f64; 3]; 2]>,
    },
    /// A perturbed quadric.
    Perturbed {
        /// Base coefficients `[xx, yy, zz, xy, yz, xz, x, y, z, 1]`.
        base: [f64; 10],
        /// (f, q coefficients) of each perturbation.
        perturbations: Vec<(f64, [f64; 10])>,
    },
    /// Union (max).
    Union(Vec<SolidForm>),
    /// Intersection (min).
    Intersection(Vec<SolidForm>),
    /// Difference.
    Difference(Box<SolidForm>, Box<SolidForm>),
    /// A moved shape: linear part as columns, then the translation.
    Transformed {
        /// Linear part, columns.
        m: [[f64; 3]; 3],
        /// Translation.
        t: [f64; 3],
        /// The shape moved.
        shape: Box<SolidForm>,
    },
}

fn node_text(n: &Node) -> String {
    let lower = |d: &dyn fmt::Debug| format!("{d:?}").to_ascii_lowercase();
    match *n {
        Node::Const(bits) => format!("const {}", f64::from_bits(bits)),
        Node::Var(v) => lower(&v),
        Node::Unary(op, a) => format!("{} %{a}", lower(&op)),
        Node::Binary(op, a, b) => format!("{} %{a} %{b}", lower(&op)),
        Node::PowI(a, k) => format!("powi %{a} {k}"),
    }
}

impl SolidForm {
    /// The form of `shape`.
    pub fn of(shape: &Shape) -> SolidForm {
        let all = |v: &[Shape]| v.iter().map(SolidForm::of).collect();
        match shape {
            Shape::Function { tree, domain } => SolidForm::Function {
                nodes: Expr::new(tree).nodes().iter().map(node_text).collect(),
                domain: domain.map(|d| [d.lo.to_array(), d.hi.to_array()]),
            },
            Shape::Perturbed(p) => SolidForm::Perturbed {
                base: p.base().c,
                perturbations: p.perturbations().iter().map(|q| (q.f, q.q.c)).collect(),
            },
            Shape::Union(v) => SolidForm::Union(all(v)),
            Shape::Intersection(v) => SolidForm::Intersection(all(v)),
            Shape::Difference(a, b) => {
                SolidForm::Difference(Box::new(SolidForm::of(a)), Box::new(SolidForm::of(b)))
            }
            Shape::Transformed(a, s) => SolidForm::Transformed {
                m: a.m.to_cols_array_2d(),
                t: a.t.to_array(),
                shape: Box::new(SolidForm::of(s)),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use frep::Tree;

    #[test]
    fn equal_functions_have_equal_forms() {
        let ball = |r: f64| {
            let t = Tree::constant(r * r)
                - (Tree::x().square() + Tree::y().square() + Tree::z().square());
            Shape::function(t)
        };
        assert_eq!(SolidForm::of(&ball(1.0)), SolidForm::of(&ball(1.0)));
        assert_ne!(SolidForm::of(&ball(1.0)), SolidForm::of(&ball(2.0)));
        let SolidForm::Function { nodes, .. } = SolidForm::of(&ball(1.0)) else {
            panic!()
        };
        assert_eq!(nodes[0], "const 1");
        assert!(nodes.iter().any(|n| n == "square %1"), "{nodes:?}");
        let mut pool = SolidPool::default();
        let id = pool.push(ball(1.0), Aabb::new(-glam::DVec3::ONE, glam::DVec3::ONE));
        assert_eq!((id, pool.len()), (SolidId(0), 1));
        let json = serde_json::to_value(&pool).unwrap();
        assert_eq!(json[0]["hi"], serde_json::json!([1.0, 1.0, 1.0]));
        assert!(json[0]["shape"]["function"]["nodes"].is_array());
    }
}
