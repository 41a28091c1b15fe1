//! Set operations and blends on functions (F ≥ 0 inside).
//!
//! Two families: exact min/max (Ricci 1973), whose zero set is the exact set operation
//! but whose gradient jumps at edges, and R-functions (Rvachev; Pasko et al. 1995,
//! "Function representation in geometric modeling"), smooth away from the edge, with a
//! parameter α ∈ (−1, 1]: α = 1 gives min/max, α = 0 the C¹ "sqrt" form HyperFun uses.

use crate::tree::Tree;

/// Union: max(a, b).
pub fn union(a: &Tree, b: &Tree) -> Tree {
    a.max(b)
}

/// Intersection: min(a, b).
pub fn intersection(a: &Tree, b: &Tree) -> Tree {
    a.min(b)
}

/// The box `b` as a solid: the least of the six distances to its faces' planes,
/// min over the axes of min(x − lo, hi − x) (≥ 0 inside). Intersecting a solid with it
/// cuts the solid at the box and closes it there ([`crate::mesh`]).
pub fn box_tree(b: &crate::ray::Aabb) -> Tree {
    let axes = [Tree::x(), Tree::y(), Tree::z()];
    let slab = |k: usize| (&axes[k] - b.lo[k]).min(&(b.hi[k] - &axes[k]));
    intersection(&intersection(&slab(0), &slab(1)), &slab(2))
}

/// Difference a \ b: min(a, −b).
pub fn difference(a: &Tree, b: &Tree) -> Tree {
    a.min(&-b)
}

/// The R-function root term √(a² + b² − 2αab).
fn r_root(a: &Tree, b: &Tree, alpha: f64) -> Tree {
    let s = a.square() + b.square();
    if alpha == 0.0 {
        s.sqrt()
    } else {
        (s - 2.0 * alpha * (a * b)).sqrt()
    }
}

/// R-union: (a + b + √(a² + b² − 2αab)) / (1 + α).
pub fn r_union(a: &Tree, b: &Tree, alpha: f64) -> Tree {
    let s = a + b + r_root(a, b, alpha);
    if alpha == 0.0 {
        s
    } else {
        s / (1.0 + alpha)
    }
}

/// R-intersection: (a + b − √(a² + b² − 2αab)) / (1 + α).
pub fn r_intersection(a: &Tree, b: &Tree, alpha: f64) -> Tree {
    let s = a + b - r_root(a, b, alpha);
    if alpha == 0.0 {
        s
    } else {
        s / (1.0 + alpha)
    }
}

/// R-difference a \ b: R-intersection of a and −b.
pub fn r_difference(a: &Tree, b: &Tree, alpha: f64) -> Tree {
    r_intersection(a, &-b, alpha)
}

/// The blend displacement a0 / (1 + (a/a1)² + (b/a2)²) (Pasko & Savchenko 1994).
fn blend_term(a: &Tree, b: &Tree, a0: f64, a1: f64, a2: f64) -> Tree {
    a0 / (1.0 + (a / a1).square() + (b / a2).square())
}

/// Blending union, as HyperFun's `hfBlendUni(f1, f2, a0, a1, a2)`: the α = 0 R-union
/// plus a displacement that adds material near the edge.
pub fn blend_union(a: &Tree, b: &Tree, a0: f64, a1: f64, a2: f64) -> Tree {
    r_union(a, b, 0.0) + blend_term(a, b, a0, a1, a2)
}

/// Blending intersection, as HyperFun's `hfBlendInt(f1, f2, a0, a1, a2)`.
pub fn blend_intersection(a: &Tree, b: &Tree, a0: f64, a1: f64, a2: f64) -> Tree {
    r_intersection(a, b, 0.0) + blend_term(a, b, a0, a1, a2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Expr;

    fn ball(cx: f64, r: f64) -> Tree {
        r * r - ((Tree::x() - cx).square() + Tree::y().square() + Tree::z().square())
    }

    /// Every form of each set operation agrees in sign with the min/max form.
    #[test]
    fn set_operations_agree_in_sign() {
        let (a, b) = (ball(-0.3, 1.0), ball(0.4, 0.8));
        let ops: [(Tree, Vec<Tree>); 3] = [
            (
                union(&a, &b),
                vec![r_union(&a, &b, 0.0), r_union(&a, &b, 0.5)],
            ),
            (
                intersection(&a, &b),
                vec![r_intersection(&a, &b, 0.0), r_intersection(&a, &b, -0.3)],
            ),
            (
                difference(&a, &b),
                vec![r_difference(&a, &b, 0.0), r_difference(&a, &b, 0.7)],
            ),
        ];
        for (exact, forms) in ops {
            let e = Expr::new(&exact);
            for f in forms {
                let f = Expr::new(&f);
                for i in 0..41 {
                    for j in 0..41 {
                        let p = [-2.0 + i as f64 * 0.1 + 0.013, -2.0 + j as f64 * 0.1, 0.1];
                        let (u, v) = (e.eval(p), f.eval(p));
                        assert_eq!(u > 1e-9, v > 1e-9, "at {p:?}: {u} vs {v}");
                    }
                }
            }
        }
    }

    #[test]
    fn blend_adds_material_between() {
        let (a, b) = (ball(-1.0, 0.9), ball(1.0, 0.9));
        let p = [0.0, 0.0, 0.0];
        assert!(Expr::new(&union(&a, &b)).eval(p) < 0.0);
        assert!(Expr::new(&blend_union(&a, &b, 1.0, 1.0, 1.0)).eval(p) > 0.0);
    }
}
