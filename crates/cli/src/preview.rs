//! First pictures of a bare model: a camera that frames the model's bounds and simple
//! shading, plus the depth and normal AOVs.
//!
//! This is the picture `frepray render MODEL` makes for a model file with no scene
//! around it: a look at the geometry, not a light-transport estimate.

use frep::{Aabb, Solid, Surface};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use render::{Camera, Image};
use std::sync::atomic::{AtomicBool, Ordering};

/// The vertical axis of a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Up {
    /// x up.
    X,
    /// y up.
    Y,
    /// z up (the default; Fidget's colonnade.vm is modelled z-up too).
    Z,
}

impl Up {
    /// The axis as a vector.
    pub fn vector(self) -> DVec3 {
        match self {
            Up::X => DVec3::X,
            Up::Y => DVec3::Y,
            Up::Z => DVec3::Z,
        }
    }
}

/// What each pixel shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Look {
    /// Diffuse shading under a key light and a headlight.
    Shaded,
    /// Distance along the camera ray (EXR channel `Z`; +∞ where the ray misses).
    Depth,
    /// Outward unit normal (EXR channels `N.X`, `N.Y`, `N.Z`; 0 where the ray misses).
    Normals,
}

/// A camera that frames a box: from the front-right-above diagonal (with `up` the
/// vertical axis), far enough that the box's bounding sphere fits the narrower field of
/// view.
pub fn framing(b: &Aabb, up: DVec3, width: u32, height: u32) -> Camera {
    let fov = 30.0f64;
    let c = b.center();
    let r = (0.5 * b.extent().length()).max(1e-9);
    let aspect = width as f64 / height as f64;
    let half = (fov.to_radians() * 0.5).tan();
    let half_min = if aspect < 1.0 { half * aspect } else { half };
    let dist = r / half_min.atan().sin();
    // Right, front and up in a right-handed frame around `up`.
    let front = if up.z.abs() > 0.5 {
        -DVec3::Y
    } else {
        DVec3::Z
    };
    let right = front.cross(up).normalize();
    let offset = (0.55 * right + front + 0.6 * up).normalize();
    Camera::look_at(c + offset * dist, c, up, fov, width, height)
}

/// The AOV channels each look writes beside R, G, B.
pub fn aov_names(look: Look) -> &'static [&'static str] {
    match look {
        Look::Shaded => &[],
        Look::Depth => &["Z"],
        Look::Normals => &["N.X", "N.Y", "N.Z"],
    }
}

/// Renders one sample per pixel centre into a film (rows in parallel; each pixel
/// depends only on its position, so the image is the same at any thread count). Rows
/// not reached before `stop` is set keep no samples.
pub fn render(
    solid: &Solid,
    cam: &Camera,
    look: Look,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> Image {
    let names = aov_names(look);
    let key = DVec3::new(-0.4, -0.6, 1.0).normalize();
    let rows: Vec<Image> = (0..cam.height)
        .into_par_iter()
        .map(|y| {
            let mut row = Image::new(cam.width, 1, names);
            if stop.load(Ordering::Relaxed) {
                return row;
            }
            for x in 0..cam.width {
                let ray = cam.ray(x, y, DVec2::splat(0.5));
                let (rgb, depth, n) = match solid.intersect(&ray, 0.0, f64::INFINITY) {
                    Some(h) => {
                        let n = h.normal;
                        let diffuse = 0.7 * n.dot(key).max(0.0) + 0.3 * n.dot(-ray.d).max(0.0);
                        let base = DVec3::new(0.85, 0.78, 0.62);
                        (base * (0.08 + diffuse), h.t, n)
                    }
                    None => {
                        let s = 0.5 * (ray.d.z + 1.0);
                        (
                            DVec3::new(0.18, 0.2, 0.24) * (0.6 + 0.4 * s),
                            f64::INFINITY,
                            DVec3::ZERO,
                        )
                    }
                };
                row.set_rgb(x, 0, rgb);
                match look {
                    Look::Shaded => {}
                    Look::Depth => row.set_aov(x, 0, 0, depth),
                    Look::Normals => (0..3).for_each(|k| row.set_aov(x, 0, k, n[k])),
                }
            }
            progress(1);
            row
        })
        .collect();
    let mut img = Image::new(cam.width, cam.height, names);
    for (y, row) in rows.iter().enumerate() {
        img.set_rows(y as u32, row);
    }
    img
}

/// A box that always has some extent (a point or flat model still gets a view).
pub fn view_bounds(solid: &Solid) -> Aabb {
    let b = solid.bounds();
    if b.is_empty() || !b.is_finite() {
        return Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
    }
    let pad = (b.extent().max_element() * 1e-3).max(1e-6);
    Aabb::new(b.lo - pad, b.hi + pad)
}
