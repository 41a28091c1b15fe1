//! Perspective (pinhole) and orthographic cameras (pbrt-v4 §5.1–5.2) with a box pixel
//! filter.

use frep::Ray;
use glam::{DVec2, DVec3};

/// How a camera maps pixels to rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Rays from the eye through an image plane: tan of half the vertical field of view.
    Perspective {
        /// tan(vfov / 2).
        tan_half_fov: f64,
    },
    /// Parallel rays along the view direction from a rectangle through the eye,
    /// perpendicular to it, `2 · half_height` scene units tall (pbrt-v4's
    /// OrthographicCamera with a screen window of ± `half_height`).
    Orthographic {
        /// Half the image's height in scene units.
        half_height: f64,
    },
}

/// A camera looking from `eye` toward a target, perspective or orthographic; pixel
/// (0, 0) is the top-left corner of the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Position of the pinhole (perspective) or the centre of the image rectangle
    /// (orthographic).
    pub eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    projection: Projection,
    /// A thin lens: its radius and the distance of the plane in focus (None: a pinhole).
    lens: Option<(f64, f64)>,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// A camera at `eye` looking at `target`, `up` giving the image's vertical,
    /// `vfov_degrees` the full vertical field of view.
    pub fn look_at(
        eye: DVec3,
        target: DVec3,
        up: DVec3,
        vfov_degrees: f64,
        width: u32,
        height: u32,
    ) -> Self {
        assert!(width > 0 && height > 0, "empty image");
        assert!(vfov_degrees > 0.0 && vfov_degrees < 180.0, "field of view");
        let forward = (target - eye).normalize();
        let right = forward.cross(up).normalize();
        assert!(right.is_finite(), "up is parallel to the view direction");
        let up = right.cross(forward);
        Self {
            eye,
            forward,
            right,
            up,
            projection: Projection::Perspective {
                tan_half_fov: (vfov_degrees.to_radians() / 2.0).tan(),
            },
            lens: None,
            width,
            height,
        }
    }
    /// An orthographic camera: rays parallel to `target − eye`, starting on the plane
    /// through `eye` perpendicular to it, over a rectangle `view_height` scene units tall
    /// (and `view_height · width / height` wide) centred on `eye`.
    pub fn orthographic(
        eye: DVec3,
        target: DVec3,
        up: DVec3,
        view_height: f64,
        width: u32,
        height: u32,
    ) -> Self {
        assert!(
            view_height > 0.0 && view_height.is_finite(),
            "orthographic view height"
        );
        Self {
            projection: Projection::Orthographic {
                half_height: 0.5 * view_height,
            },
            ..Self::look_at(eye, target, up, 90.0, width, height)
        }
    }
    /// Unit view direction.
    pub fn forward(&self) -> DVec3 {
        self.forward
    }
    /// The projection.
    pub fn projection(&self) -> Projection {
        self.projection
    }
    /// The ray through pixel (x, y) at sub-pixel `offset` ∈ [0,1)² (box filter:
    /// offsets uniform over the pixel), with a unit direction.
    pub fn ray(&self, x: u32, y: u32, offset: DVec2) -> Ray {
        let aspect = self.width as f64 / self.height as f64;
        let (scale, ortho) = match self.projection {
            Projection::Perspective { tan_half_fov } => (tan_half_fov, false),
            Projection::Orthographic { half_height } => (half_height, true),
        };
        let sx = (2.0 * (x as f64 + offset.x) / self.width as f64 - 1.0) * scale * aspect;
        let sy = (1.0 - 2.0 * (y as f64 + offset.y) / self.height as f64) * scale;
        if ortho {
            return Ray::new(self.eye + sx * self.right + sy * self.up, self.forward);
        }
        Ray::new(
            self.eye,
            (self.forward + sx * self.right + sy * self.up).normalize(),
        )
    }

    /// This perspective camera with a thin lens of `radius` focused at `focus_distance`
    /// along the view direction (pbrt-v4 §5.2.3).
    pub fn with_lens(self, radius: f64, focus_distance: f64) -> Self {
        assert!(
            matches!(self.projection, Projection::Perspective { .. }),
            "a thin lens needs a perspective camera"
        );
        assert!(radius > 0.0 && focus_distance > 0.0, "lens");
        Self {
            lens: Some((radius, focus_distance)),
            ..self
        }
    }

    /// The thin lens's radius and focus distance, if the camera has one.
    pub fn lens(&self) -> Option<(f64, f64)> {
        self.lens
    }

    /// [`Self::ray`] through the lens point `lens_u` ∈ [0,1)² (concentric disk map): from
    /// that point of the lens toward where the pinhole ray meets the plane in focus. A
    /// pinhole camera ignores `lens_u`.
    pub fn ray_through_lens(&self, x: u32, y: u32, offset: DVec2, lens_u: DVec2) -> Ray {
        let r = self.ray(x, y, offset);
        let Some((radius, focus)) = self.lens else {
            return r;
        };
        let focus_point = r.o + r.d * (focus / r.d.dot(self.forward));
        let d = radius * crate::warp::uniform_disk_concentric(lens_u);
        let o = self.eye + d.x * self.right + d.y * self.up;
        Ray::new(o, (focus_point - o).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_span_the_field_of_view() {
        let c = Camera::look_at(
            DVec3::new(0.0, -5.0, 1.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::Z,
            60.0,
            200,
            100,
        );
        let centre = c.ray(100, 50, DVec2::ZERO);
        assert_eq!(centre.o, c.eye);
        assert!((centre.d - DVec3::Y).length() < 1e-12);
        // Top edge at +30° elevation, at image centre horizontally.
        let top = c.ray(100, 0, DVec2::ZERO).d;
        assert!((top.z.asin().to_degrees() - 30.0).abs() < 1e-9);
        // Left edge: tan(h/2) = aspect · tan(30°); left is −x for a camera looking along +y, up +z.
        let left = c.ray(0, 50, DVec2::ZERO).d;
        let expect = (2.0 * 30f64.to_radians().tan()).atan();
        assert!(left.x < 0.0 && ((-left.x / left.y).atan() - expect).abs() < 1e-9);
        // Bottom-right corner at offset (1, 1) of the last pixel.
        let br = c.ray(199, 99, DVec2::ONE).d;
        assert!(br.x > 0.0 && br.z < 0.0);
        assert!((br.z / br.y + 30f64.to_radians().tan()).abs() < 1e-9);
        assert!((br.x / br.y - 2.0 * 30f64.to_radians().tan()).abs() < 1e-9);
    }

    /// Orthographic rays are parallel to the view direction and start on the plane
    /// through the eye perpendicular to it, over a rectangle of the given height.
    #[test]
    fn orthographic_rays_are_parallel_from_the_image_plane() {
        let (eye, target) = (DVec3::new(1.0, -5.0, 2.0), DVec3::new(1.0, 0.0, 2.0));
        let c = Camera::orthographic(eye, target, DVec3::Z, 3.0, 200, 100);
        assert!(matches!(
            c.projection(),
            Projection::Orthographic { half_height } if half_height == 1.5
        ));
        let mut corners = Vec::new();
        for (x, y, o) in [
            (0, 0, DVec2::ZERO),
            (199, 99, DVec2::ONE),
            (100, 50, DVec2::ZERO),
            (37, 81, DVec2::new(0.3, 0.7)),
        ] {
            let r = c.ray(x, y, o);
            assert!((r.d - DVec3::Y).length() < 1e-15, "{r:?}");
            assert!((r.o - eye).dot(DVec3::Y).abs() < 1e-12, "{r:?}");
            corners.push(r.o);
        }
        // Top-left (−x, +z) and bottom-right corners span 6 × 3 (aspect 2); the centre
        // pixel's corner is the eye.
        assert!((corners[0] - (eye + DVec3::new(-3.0, 0.0, 1.5))).length() < 1e-12);
        assert!((corners[1] - (eye + DVec3::new(3.0, 0.0, -1.5))).length() < 1e-12);
        assert!((corners[2] - eye).length() < 1e-12);
    }
}
