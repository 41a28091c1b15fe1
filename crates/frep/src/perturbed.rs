//! Perturbed quadrics: F' = F + Σ f_i·r_i, r_i = q_i³ where q_i ≥ 0, else 0.
//!
//! The paper's solids (Vyatkin & Dolgovesov; RESEARCH.md §1): a base quadric F plus
//! compact cubic perturbations. r = q³ has zero value, slope and curvature where q = 0,
//! so F' is C² and each perturbation only acts inside its support q_i ≥ 0.
//! [`PerturbedSurface`] intersects rays with such a solid exactly.

pub(crate) mod along;
mod ordered;
mod scan;
mod surface;

pub use scan::{GPU_ACTIVE, GPU_SPLITS, MAX_ACTIVE};
pub use surface::{PerturbedSurface, PerturbedView};

use crate::quadric::Quadric;
use crate::transform::Affine;
use crate::tree::Tree;
use glam::DVec3;

/// One perturbation f·max(q, 0)³.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Perturbation {
    /// Form factor f (positive adds material, negative removes it).
    pub f: f64,
    /// Perturbing function q; the perturbation acts where q ≥ 0.
    pub q: Quadric,
}

/// A base quadric plus perturbations (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct PerturbedQuadric {
    base: Quadric,
    perturbations: Vec<Perturbation>,
}

impl PerturbedQuadric {
    /// The unperturbed base quadric.
    pub fn new(base: Quadric) -> Self {
        Self {
            base,
            perturbations: Vec::new(),
        }
    }
    /// Adds the perturbation f·max(q, 0)³.
    pub fn push(&mut self, f: f64, q: Quadric) {
        self.perturbations.push(Perturbation { f, q });
    }
    /// Builder form of [`push`](Self::push).
    pub fn with(mut self, f: f64, q: Quadric) -> Self {
        self.push(f, q);
        self
    }
    /// The base quadric F.
    pub fn base(&self) -> &Quadric {
        &self.base
    }
    /// The perturbations.
    pub fn perturbations(&self) -> &[Perturbation] {
        &self.perturbations
    }
    /// F' at p, by direct summation over every perturbation (the reference value).
    pub fn eval(&self, p: DVec3) -> f64 {
        let mut v = self.base.eval(p);
        for pt in &self.perturbations {
            let q = pt.q.eval(p);
            if q > 0.0 {
                v += pt.f * q * q * q;
            }
        }
        v
    }
    /// The solid moved by the affine map `a` (F'∘A⁻¹: the base and every q_i moved, the
    /// form factors kept). None for a singular map.
    pub fn transformed(&self, a: &Affine) -> Option<PerturbedQuadric> {
        let mut out = PerturbedQuadric::new(self.base.transformed(a)?);
        for p in &self.perturbations {
            out.push(p.f, p.q.transformed(a)?);
        }
        Some(out)
    }
    /// The solid prepared for ray intersection (see [`PerturbedSurface::new`]).
    pub fn surface(&self) -> PerturbedSurface {
        PerturbedSurface::new(self)
    }
    /// F' as an expression tree: F + Σ f_i·max(q_i, 0)³.
    pub fn to_tree(&self) -> Tree {
        let mut e = self.base.to_tree();
        for pt in &self.perturbations {
            let r = pt.q.to_tree().max(&Tree::constant(0.0)).powi(3);
            e = e + pt.f * r;
        }
        e
    }
}
