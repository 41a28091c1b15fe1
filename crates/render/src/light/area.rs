//! Area lights with analytic shapes: sphere, parallelogram ("rect") and disk
//! (pbrt-v4 §6.2, §6.5 and §12.2). Emission is uniform radiance `L` on the side of the
//! outward normal (both sides when `two_sided`; spheres emit outward).

use super::LightSample;
use crate::color::Rgb;
use crate::frame::Frame;
use crate::warp::{safe_sqrt, spherical_direction, uniform_disk_concentric, uniform_sphere};
use frep::{Aabb, Ray};
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// The geometry of an area light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A sphere.
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
    },
    /// The parallelogram `corner + a·edge_u + b·edge_v`, a, b ∈ [0, 1]; normal along
    /// edge_u × edge_v.
    Rect {
        /// One corner.
        corner: DVec3,
        /// First edge.
        edge_u: DVec3,
        /// Second edge.
        edge_v: DVec3,
    },
    /// A disk.
    Disk {
        /// Centre.
        center: DVec3,
        /// Unit normal (the emitting side).
        normal: DVec3,
        /// Radius.
        radius: f64,
    },
    /// The triangle `p0`, `p0 + e1`, `p0 + e2` (a mesh light's); normal along e1 × e2.
    Triangle {
        /// One corner.
        p0: DVec3,
        /// First edge.
        e1: DVec3,
        /// Second edge.
        e2: DVec3,
    },
}

/// A surface crossing of a ray with a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Ray parameter.
    pub t: f64,
    /// Outward unit normal there.
    pub n: DVec3,
}

/// A shape with uniform emitted radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLight {
    /// The emitting surface.
    pub shape: Shape,
    /// Emitted radiance.
    pub radiance: Rgb,
    /// Whether planar shapes emit on both sides.
    pub two_sided: bool,
    /// Whether the shape only stands in for an emitting object in light sampling (its
    /// bounding sphere): light techniques sample directions toward it and count its
    /// density, but rays never meet it (the object's surface emits, `Scene::emission`).
    pub proxy: bool,
}

impl AreaLight {
    /// A light of radiance `radiance` on `shape`, one-sided.
    pub fn new(shape: Shape, radiance: Rgb) -> Self {
        Self {
            shape,
            radiance,
            two_sided: false,
            proxy: false,
        }
    }
    /// Surface area.
    pub fn area(&self) -> f64 {
        match self.shape {
            Shape::Sphere { radius, .. } => 4.0 * PI * radius * radius,
            Shape::Rect { edge_u, edge_v, .. } => edge_u.cross(edge_v).length(),
            Shape::Disk { radius, .. } => PI * radius * radius,
            Shape::Triangle { e1, e2, .. } => 0.5 * e1.cross(e2).length(),
        }
    }
    /// A box holding the surface, grown by a hair (1e-9 of its size, and of its distance
    /// from the origin) so that every crossing [`Self::crossings`] reports, edges
    /// included, lies inside it; a flat shape's box has a thickness.
    pub fn bounds(&self) -> Aabb {
        let (lo, hi) = match self.shape {
            Shape::Sphere { center, radius } => (center - radius, center + radius),
            Shape::Rect {
                corner,
                edge_u,
                edge_v,
            } => {
                let corners = [corner + edge_u, corner + edge_v, corner + edge_u + edge_v];
                corners
                    .iter()
                    .fold((corner, corner), |(lo, hi), &c| (lo.min(c), hi.max(c)))
            }
            Shape::Disk {
                center,
                normal,
                radius,
            } => {
                // A disk's extent along axis i is r·√(1 − n_i²).
                let half = (DVec3::ONE - normal * normal).max(DVec3::ZERO);
                let half = DVec3::new(half.x.sqrt(), half.y.sqrt(), half.z.sqrt()) * radius;
                (center - half, center + half)
            }
            Shape::Triangle { p0, e1, e2 } => {
                let (a, b) = (p0 + e1, p0 + e2);
                (p0.min(a).min(b), p0.max(a).max(b))
            }
        };
        let pad = 1e-9 * (1.0 + (hi - lo).max_element() + lo.abs().max(hi.abs()).max_element());
        Aabb::new(lo - pad, hi + pad)
    }
    /// Emitted power Φ = π A L (twice that when two-sided).
    pub fn power(&self) -> Rgb {
        let sides = if self.two_sided && !matches!(self.shape, Shape::Sphere { .. }) {
            2.0
        } else {
            1.0
        };
        self.radiance * (PI * self.area() * sides)
    }
    /// Radiance leaving a point of normal `n` in direction `w`.
    pub fn emitted(&self, n: DVec3, w: DVec3) -> Rgb {
        let c = n.dot(w);
        if c > 0.0 || (self.two_sided && c < 0.0 && !matches!(self.shape, Shape::Sphere { .. })) {
            self.radiance
        } else {
            Rgb::ZERO
        }
    }
    /// Every crossing of the line `o + t d` (d unit) with t > 0, nearest first.
    #[inline(always)]
    pub fn crossings(&self, o: DVec3, d: DVec3) -> ([Option<Crossing>; 2], usize) {
        let mut out = [None, None];
        let mut k = 0;
        match self.shape {
            Shape::Sphere { center, radius } => {
                let oc = o - center;
                let b = d.dot(oc);
                let c = oc.length_squared() - radius * radius;
                let disc = b * b - c;
                if disc < 0.0 {
                    return (out, 0);
                }
                let s = disc.sqrt();
                // Stable roots: q = −(b + sign(b)·s), t = q and c/q.
                let q = -(b + s.copysign(b));
                let (mut t0, mut t1) = (q, if q != 0.0 { c / q } else { -b });
                if t0 > t1 {
                    std::mem::swap(&mut t0, &mut t1);
                }
                for t in [t0, t1] {
                    if t > 0.0 {
                        out[k] = Some(Crossing {
                            t,
                            n: (o + d * t - center) / radius,
                        });
                        k += 1;
                    }
                }
            }
            Shape::Rect {
                corner,
                edge_u,
                edge_v,
            } => {
                let nn = edge_u.cross(edge_v);
                let denom = d.dot(nn);
                if denom != 0.0 {
                    let t = (corner - o).dot(nn) / denom;
                    let q = o + d * t - corner;
                    let l2 = nn.length_squared();
                    let a = q.cross(edge_v).dot(nn) / l2;
                    let b = edge_u.cross(q).dot(nn) / l2;
                    // Edges widened by 1e-12 so that points sampled on them are found.
                    let inside = |x: f64| (-1e-12..=1.0 + 1e-12).contains(&x);
                    if t > 0.0 && inside(a) && inside(b) {
                        out[0] = Some(Crossing {
                            t,
                            n: nn / l2.sqrt(),
                        });
                        k = 1;
                    }
                }
            }
            Shape::Disk {
                center,
                normal,
                radius,
            } => {
                let denom = d.dot(normal);
                if denom != 0.0 {
                    let t = (center - o).dot(normal) / denom;
                    let r2 = radius * radius * (1.0 + 1e-12);
                    if t > 0.0 && (o + d * t - center).length_squared() <= r2 {
                        out[0] = Some(Crossing { t, n: normal });
                        k = 1;
                    }
                }
            }
            Shape::Triangle { p0, e1, e2 } => {
                // Möller–Trumbore, edges widened by 1e-12 as the rect's are.
                let pv = d.cross(e2);
                let det = e1.dot(pv);
                if det != 0.0 {
                    let inv = 1.0 / det;
                    let s = o - p0;
                    let (u, q) = (s.dot(pv) * inv, s.cross(e1));
                    let v = d.dot(q) * inv;
                    let t = e2.dot(q) * inv;
                    let slack = 1e-12;
                    if t > 0.0 && u >= -slack && v >= -slack && u + v <= 1.0 + slack {
                        out[0] = Some(Crossing {
                            t,
                            n: e1.cross(e2).normalize(),
                        });
                        k = 1;
                    }
                }
            }
        }
        (out, k)
    }
    /// The nearest crossing with t in (t_min, t_max), for a ray with a unit direction.
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<Crossing> {
        let (c, k) = self.crossings(ray.o, ray.d);
        c[..k]
            .iter()
            .flatten()
            .find(|c| c.t > t_min && c.t < t_max)
            .copied()
    }
    /// A point uniform over the surface, and its outward normal.
    pub fn sample_point(&self, u: DVec2) -> (DVec3, DVec3) {
        match self.shape {
            Shape::Sphere { center, radius } => {
                let n = uniform_sphere(u);
                (center + radius * n, n)
            }
            Shape::Rect {
                corner,
                edge_u,
                edge_v,
            } => (
                corner + u.x * edge_u + u.y * edge_v,
                edge_u.cross(edge_v).normalize(),
            ),
            Shape::Disk {
                center,
                normal,
                radius,
            } => {
                let f = Frame::from_z(normal);
                let d = uniform_disk_concentric(u) * radius;
                (center + d.x * f.s + d.y * f.t, normal)
            }
            Shape::Triangle { p0, e1, e2 } => {
                let [_, b1, b2] = uniform_triangle(u);
                (p0 + b1 * e1 + b2 * e2, e1.cross(e2).normalize())
            }
        }
    }
    /// The sample toward point `q` (normal `n`) from `p`, its pdf given by `pdf(wi)`.
    fn toward(
        &self,
        p: DVec3,
        q: DVec3,
        n: DVec3,
        pdf: impl FnOnce(DVec3) -> f64,
    ) -> Option<LightSample> {
        let v = q - p;
        let dist = v.length();
        if dist == 0.0 {
            return None;
        }
        let wi = v / dist;
        let pdf = pdf(wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(LightSample {
            wi,
            dist,
            radiance: self.emitted(n, -wi),
            pdf,
            delta: false,
            light: None,
        })
    }
    /// Uniform area sampling seen from `p`; the pdf (solid angle) is [`Self::pdf_area`],
    /// which sums over every crossing of the direction with the shape. A flat shape is
    /// crossed once, at the point sampled: its pdf is that crossing's term, dist² /
    /// (A |cos θ_light|) (pbrt-v4 §6.5, `ShapeSample` to solid angle), without finding
    /// the crossing again.
    pub fn sample_area(&self, p: DVec3, u: DVec2) -> Option<LightSample> {
        let (q, n) = self.sample_point(u);
        match self.shape {
            Shape::Sphere { .. } => self.toward(p, q, n, |wi| self.pdf_area(p, wi)),
            Shape::Rect { .. } | Shape::Disk { .. } | Shape::Triangle { .. } => {
                let dist2 = p.distance_squared(q);
                self.toward(p, q, n, |wi| {
                    let cos = n.dot(wi).abs();
                    if cos > 0.0 {
                        dist2 / (self.area() * cos)
                    } else {
                        0.0
                    }
                })
            }
        }
    }
    /// Σ over crossings of t² / (A |cos θ_light|): the solid-angle density of
    /// [`Self::sample_area`] at direction `wi` (unit).
    pub fn pdf_area(&self, p: DVec3, wi: DVec3) -> f64 {
        let (c, k) = self.crossings(p, wi);
        self.pdf_area_over(wi, &c[..k])
    }
    /// [`Self::pdf_area`] from the crossings of the line from p along `wi`
    /// ([`Self::crossings`]), already found.
    pub fn pdf_area_over(&self, wi: DVec3, crossings: &[Option<Crossing>]) -> f64 {
        let a = self.area();
        crossings
            .iter()
            .flatten()
            .map(|c| {
                let cos = c.n.dot(wi).abs();
                if cos > 0.0 {
                    c.t * c.t / (a * cos)
                } else {
                    0.0
                }
            })
            // From +0 (`sum` starts at −0): no crossing is a density of +0.
            .fold(0.0, |s, x| s + x)
    }
    /// The light's preferred sampling: the cone of directions subtended by a sphere
    /// seen from outside (uniform in solid angle, pbrt-v4 §6.2.4); uniform area
    /// otherwise.
    pub fn sample_li(&self, p: DVec3, u: DVec2) -> Option<LightSample> {
        if let Shape::Triangle { p0, e1, e2 } = self.shape {
            let corners = [p0, p0 + e1, p0 + e2];
            let Some(omega) = spherical_triangle_area(corners, p) else {
                return self.sample_area(p, u);
            };
            let [b0, b1, b2] = sample_spherical_triangle(corners, p, u)?;
            let q = corners[0] * b0 + corners[1] * b1 + corners[2] * b2;
            return self.toward(p, q, e1.cross(e2).normalize(), |_| 1.0 / omega);
        }
        let Shape::Sphere { center, radius } = self.shape else {
            return self.sample_area(p, u);
        };
        let dc2 = p.distance_squared(center);
        if dc2 <= radius * radius {
            return self.sample_area(p, u);
        }
        let sin2_max = radius * radius / dc2;
        // 1 − cos θ without cancellation: sin²θ / (1 + cos θ); likewise below.
        let one_minus_cos_max = sin2_max / (1.0 + safe_sqrt(1.0 - sin2_max));
        let w = u.x * one_minus_cos_max;
        let (cos_t, sin2_t) = (1.0 - w, w * (2.0 - w));
        // The point on the sphere along the sampled cone direction.
        let cos_alpha = sin2_t / sin2_max.sqrt() + cos_t * safe_sqrt(1.0 - sin2_t / sin2_max);
        let sin_alpha = safe_sqrt(1.0 - cos_alpha * cos_alpha);
        let w = spherical_direction(sin_alpha, cos_alpha, u.y);
        let frame = Frame::from_z((center - p).normalize());
        let n = frame.from_local(-w);
        self.toward(p, center + radius * n, n, |_| {
            1.0 / (2.0 * PI * one_minus_cos_max)
        })
    }
    /// The solid-angle density of [`Self::sample_li`] at direction `wi` (unit).
    pub fn pdf_li(&self, p: DVec3, wi: DVec3) -> f64 {
        self.pdf_li_with(p, wi, || self.pdf_area(p, wi))
    }
    /// [`Self::pdf_li`] with [`Self::pdf_area`] from the crossings of the line from p
    /// along `wi`, already found: the same value bit for bit.
    pub fn pdf_li_over(&self, p: DVec3, wi: DVec3, crossings: &[Option<Crossing>]) -> f64 {
        self.pdf_li_with(p, wi, || self.pdf_area_over(wi, crossings))
    }
    /// [`Self::pdf_li`], taking [`Self::pdf_area`] from `area` where it is needed.
    #[inline]
    fn pdf_li_with(&self, p: DVec3, wi: DVec3, area: impl FnOnce() -> f64) -> f64 {
        if let Shape::Triangle { p0, e1, e2 } = self.shape {
            return match spherical_triangle_area([p0, p0 + e1, p0 + e2], p) {
                // Uniform over the triangle's solid angle: wherever the line meets it.
                Some(omega) => match self.crossings(p, wi).1 {
                    0 => 0.0,
                    _ => 1.0 / omega,
                },
                None => area(),
            };
        }
        let Shape::Sphere { center, radius } = self.shape else {
            return area();
        };
        let dc2 = p.distance_squared(center);
        if dc2 <= radius * radius {
            return area();
        }
        let sin2_max = radius * radius / dc2;
        let one_minus_cos_max = sin2_max / (1.0 + safe_sqrt(1.0 - sin2_max));
        // Inside the cone ⇔ the line meets the sphere: distance² from the centre ≤ r².
        let pc = center - p;
        let along = pc.dot(wi);
        if along > 0.0 && (dc2 - along * along) <= radius * radius {
            1.0 / (2.0 * PI * one_minus_cos_max)
        } else {
            0.0
        }
    }
}

/// Barycentrics (b0, b1, b2) uniform over a triangle's area, by pbrt-v4's
/// low-distortion mapping (`SampleUniformTriangle`, Heitz 2019).
pub fn uniform_triangle(u: DVec2) -> [f64; 3] {
    let (b0, b1) = if u.x < u.y {
        let b0 = u.x / 2.0;
        (b0, u.y - b0)
    } else {
        let b1 = u.y / 2.0;
        (u.x - b1, b1)
    };
    [b0, b1, 1.0 - b0 - b1]
}

/// The solid angle a triangle subtends at `p` (Van Oosterom & Strackee 1983), where
/// sampling it is worth while: None outside pbrt-v4's range [3·10⁻⁴, 6.22] sr, where
/// the triangle is small or far (area sampling is as good and cheaper) or covers
/// nearly a hemisphere (the spherical sampling loses precision).
pub fn spherical_triangle_area(corners: [DVec3; 3], p: DVec3) -> Option<f64> {
    let [a, b, c] = corners.map(|v| (v - p).normalize_or_zero());
    let omega = (2.0
        * a.dot(b.cross(c))
            .atan2(1.0 + a.dot(b) + a.dot(c) + b.dot(c)))
    .abs();
    (3e-4..=6.22).contains(&omega).then_some(omega)
}

/// The angle between unit vectors, accurate near 0 and π (pbrt-v4 `AngleBetween`).
fn angle_between(v1: DVec3, v2: DVec3) -> f64 {
    if v1.dot(v2) < 0.0 {
        PI - 2.0 * ((v1 + v2).length() / 2.0).clamp(-1.0, 1.0).asin()
    } else {
        2.0 * ((v2 - v1).length() / 2.0).clamp(-1.0, 1.0).asin()
    }
}

/// Barycentrics of a direction from `p` uniform over the solid angle of the triangle
/// `corners` (Arvo 1995, "Stratified sampling of spherical triangles", as pbrt-v4's
/// `SampleSphericalTriangle`); None for a degenerate spherical triangle.
pub fn sample_spherical_triangle(corners: [DVec3; 3], p: DVec3, u: DVec2) -> Option<[f64; 3]> {
    let [a, b, c] = corners.map(|v| (v - p).normalize_or_zero());
    let (n_ab, n_bc, n_ca) = (
        a.cross(b).try_normalize()?,
        b.cross(c).try_normalize()?,
        c.cross(a).try_normalize()?,
    );
    let alpha = angle_between(n_ab, -n_ca);
    let beta = angle_between(n_bc, -n_ab);
    let gamma = angle_between(n_ca, -n_bc);
    // The sub-triangle's area A' (plus π), uniform in [0, A].
    let ap_pi = PI + u.x * (alpha + beta + gamma - PI);
    let (cos_alpha, sin_alpha) = (alpha.cos(), alpha.sin());
    let (sin_ap, cos_ap) = ap_pi.sin_cos();
    let sin_phi = sin_ap * cos_alpha - cos_ap * sin_alpha;
    let cos_phi = cos_ap * cos_alpha + sin_ap * sin_alpha;
    let k1 = cos_phi + cos_alpha;
    let k2 = sin_phi - sin_alpha * a.dot(b);
    let cos_bp = ((k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha)
        / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha))
        .clamp(-1.0, 1.0);
    if cos_bp.is_nan() {
        return None;
    }
    let sin_bp = safe_sqrt(1.0 - cos_bp * cos_bp);
    let cp = cos_bp * a + sin_bp * (c - c.dot(a) * a).try_normalize()?;
    let cos_t = 1.0 - u.y * (1.0 - cp.dot(b));
    let sin_t = safe_sqrt(1.0 - cos_t * cos_t);
    let w = cos_t * b + sin_t * (cp - cp.dot(b) * b).try_normalize()?;
    // Where w meets the triangle's plane, as barycentrics.
    let (e1, e2) = (corners[1] - corners[0], corners[2] - corners[0]);
    let s1 = w.cross(e2);
    let divisor = s1.dot(e1);
    if divisor == 0.0 {
        return Some([1.0 / 3.0; 3]);
    }
    let s = p - corners[0];
    let mut b1 = (s.dot(s1) / divisor).clamp(0.0, 1.0);
    let mut b2 = (w.dot(s.cross(e1)) / divisor).clamp(0.0, 1.0);
    if b1 + b2 > 1.0 {
        let sum = b1 + b2;
        (b1, b2) = (b1 / sum, b2 / sum);
    }
    Some([1.0 - b1 - b2, b1, b2])
}
