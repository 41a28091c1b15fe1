//! Orthonormal shading frames built from a normal.

use glam::DVec3;

/// An orthonormal basis (s, t, n); local coordinates have n as +z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub s: DVec3,
    /// Second tangent.
    pub t: DVec3,
    /// Normal (local +z).
    pub n: DVec3,
}

impl Frame {
    /// A frame around the unit vector `n` (Duff et al. 2017, "Building an Orthonormal
    /// Basis, Revisited", JCGT 6(1)).
    pub fn from_z(n: DVec3) -> Self {
        let sign = 1f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = DVec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }
    /// World → local.
    #[inline]
    pub fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
    /// Local → world.
    #[inline]
    pub fn from_local(&self, v: DVec3) -> DVec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orthonormal_and_round_trip() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(1.0, -2.0, 0.3).normalize(),
            DVec3::new(0.0, 1e-9, -1.0).normalize(),
        ] {
            let f = Frame::from_z(n);
            for (a, b) in [(f.s, f.t), (f.s, f.n), (f.t, f.n)] {
                assert!(a.dot(b).abs() < 1e-12);
            }
            for v in [f.s, f.t, f.n] {
                assert!((v.length() - 1.0).abs() < 1e-12);
            }
            assert!((f.s.cross(f.t) - f.n).length() < 1e-12, "right-handed");
            let v = DVec3::new(0.3, -0.7, 0.2);
            assert!((f.from_local(f.to_local(v)) - v).length() < 1e-12);
            assert!((f.to_local(n) - DVec3::Z).length() < 1e-12);
        }
    }
}
