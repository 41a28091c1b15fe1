//! Triangle meshes beside the solids: a scene object may be a mesh read from an OBJ or
//! PLY file ([`crate::read::read_mesh`]), intersected triangle by triangle through a
//! BVH ([`crate::Bvh`]) with the Möller–Trumbore test in f64 (Möller & Trumbore 1997,
//! "Fast, minimum storage ray-triangle intersection").
//!
//! A triangle's front is the side its corners turn counter-clockwise around (the OBJ
//! and PLY convention), or where the mesh has vertex normals, the side they point to;
//! the hit's normal is that side's, as a solid's outward normal is.
//! A closed, consistently wound mesh is a solid's boundary; an open one is a surface
//! seen from both sides, whose back reflects as a solid's inside would. Meshes do not
//! take part in CSG: a set operation on a mesh would be exact only with a robust
//! inside test on every query, which the solids' crossing walk does not have.

use crate::bvh::Bvh;
use crate::ray::{Aabb, Ray};
use crate::transform::Affine;
use glam::{DVec2, DVec3};

/// Triangles a mesh may have.
pub const MAX_TRIANGLES: usize = 50_000_000;

/// A triangle mesh with its BVH.
#[derive(Clone, Debug)]
pub struct Triangles {
    positions: Vec<DVec3>,
    /// Per-vertex normals, or empty.
    normals: Vec<DVec3>,
    /// Per-vertex surface parameters, or empty.
    uvs: Vec<DVec2>,
    indices: Vec<[u32; 3]>,
    bvh: Bvh,
    bounds: Aabb,
}

/// A ray's nearest crossing of a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter.
    pub t: f64,
    /// The triangle.
    pub triangle: usize,
    /// The front's unit normal: the interpolated vertex normals where the mesh has them
    /// (they say which side is the front, as in pbrt-v4), else the triangle's own.
    pub normal: DVec3,
    /// The interpolated surface parameters (0 where the mesh has none).
    pub uv: DVec2,
}

impl Triangles {
    /// A mesh of `indices` into `positions`, with per-vertex `normals` and `uvs` (each
    /// empty or one per position). Errors say what is wrong: an index out of range, a
    /// coordinate that is not finite, lists of the wrong length, no triangles.
    pub fn new(
        positions: Vec<DVec3>,
        normals: Vec<DVec3>,
        uvs: Vec<DVec2>,
        indices: Vec<[u32; 3]>,
    ) -> Result<Self, String> {
        let n = positions.len();
        if indices.is_empty() {
            return Err("the mesh has no triangles".into());
        }
        if indices.len() > MAX_TRIANGLES {
            return Err(format!(
                "the mesh has {} triangles, more than the {MAX_TRIANGLES} a mesh may have",
                indices.len()
            ));
        }
        for (what, len) in [
            ("normals", normals.len()),
            ("texture coordinates", uvs.len()),
        ] {
            if len != 0 && len != n {
                return Err(format!("{len} {what} for {n} vertices"));
            }
        }
        if let Some(k) = positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("vertex {} is not finite", k + 1));
        }
        if let Some((k, t)) = indices
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&i| i as usize >= n))
        {
            return Err(format!(
                "triangle {} names vertex {} of {n}",
                k + 1,
                t.iter().max().unwrap_or(&0) + 1
            ));
        }
        let normals = normals
            .into_iter()
            .map(|v| v.try_normalize().unwrap_or(DVec3::ZERO))
            .collect();
        Ok(Self::build(positions, normals, uvs, indices))
    }

    fn build(
        positions: Vec<DVec3>,
        normals: Vec<DVec3>,
        uvs: Vec<DVec2>,
        indices: Vec<[u32; 3]>,
    ) -> Self {
        let boxes: Vec<Aabb> = indices
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
                // A hair of room, so that hits on an axis-aligned triangle's plane are
                // inside its box.
                let pad =
                    1e-9 * (1.0 + (hi - lo).max_element() + lo.abs().max(hi.abs()).max_element());
                Aabb::new(lo - pad, hi + pad)
            })
            .collect();
        let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(b));
        Self {
            bvh: Bvh::new(&boxes),
            positions,
            normals,
            uvs,
            indices,
            bounds,
        }
    }

    /// The mesh moved by `a`: positions mapped, normals by the inverse transpose, and the
    /// winding reversed where `a` mirrors (so that fronts stay fronts). None when `a` is
    /// singular.
    pub fn transformed(&self, a: &Affine) -> Option<Self> {
        let inv = a.inverse()?;
        let nm = inv.m.transpose();
        let positions = self.positions.iter().map(|&p| a.point(p)).collect();
        let normals = self
            .normals
            .iter()
            .map(|&n| (nm * n).try_normalize().unwrap_or(DVec3::ZERO))
            .collect();
        let mirror = a.m.determinant() < 0.0;
        let indices = self
            .indices
            .iter()
            .map(|&[i, j, k]| if mirror { [i, k, j] } else { [i, j, k] })
            .collect();
        Some(Self::build(positions, normals, self.uvs.clone(), indices))
    }

    /// A box holding every triangle.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether there are no triangles (never, for a mesh [`Self::new`] made).
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// The vertex positions.
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// The triangles, as indices into [`Self::positions`].
    pub fn indices(&self) -> &[[u32; 3]] {
        &self.indices
    }

    /// Whether the mesh has per-vertex normals.
    pub fn has_normals(&self) -> bool {
        !self.normals.is_empty()
    }

    /// Whether the mesh has per-vertex surface parameters.
    pub fn has_uvs(&self) -> bool {
        !self.uvs.is_empty()
    }

    /// Triangle `k`'s corners.
    pub fn triangle(&self, k: usize) -> [DVec3; 3] {
        self.indices[k].map(|i| self.positions[i as usize])
    }

    /// The nearest crossing with t in (t_min, t_max).
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<TriangleHit> {
        let mut best = None;
        self.bvh.nearest(ray, t_min, t_max, |k, t_max| {
            let (t, u, v) = crossing(ray, self.triangle(k), t_min, t_max)?;
            best = Some((k, t, u, v));
            Some(t)
        })?;
        // `best` belongs to the last accepted hit, the nearest (`nearest` only accepts
        // hits below its shrinking t_max).
        let (k, t, u, v) = best?;
        Some(self.hit(k, t, u, v))
    }

    /// A crossing's details from its triangle and barycentrics.
    fn hit(&self, k: usize, t: f64, u: f64, v: f64) -> TriangleHit {
        let [a, b, c] = self.triangle(k);
        let face = (b - a).cross(c - a).normalize();
        let idx = self.indices[k].map(|i| i as usize);
        let w = 1.0 - u - v;
        let normal = if self.normals.is_empty() {
            face
        } else {
            let n = self.normals[idx[0]] * w + self.normals[idx[1]] * u + self.normals[idx[2]] * v;
            n.try_normalize().unwrap_or(face)
        };
        let uv = if self.uvs.is_empty() {
            DVec2::ZERO
        } else {
            self.uvs[idx[0]] * w + self.uvs[idx[1]] * u + self.uvs[idx[2]] * v
        };
        TriangleHit {
            t,
            triangle: k,
            normal,
            uv,
        }
    }

    /// Whether any triangle lies in (t_min, t_max) along the ray.
    pub fn occludes(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        self.bvh.any_hit(ray, t_min, t_max, |k| {
            crossing(ray, self.triangle(k), t_min, t_max).is_some()
        })
    }
}

/// Möller–Trumbore: the ray parameter and barycentrics (u along b − a, v along c − a)
/// where the ray crosses triangle abc with t in (t_min, t_max); edges included.
#[inline]
fn crossing(ray: &Ray, [a, b, c]: [DVec3; 3], t_min: f64, t_max: f64) -> Option<(f64, f64, f64)> {
    let (e1, e2) = (b - a, c - a);
    let p = ray.d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = ray.o - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > t_min && t < t_max).then_some((t, u, v))
}
