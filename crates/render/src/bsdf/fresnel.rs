//! Fresnel reflectance of dielectric and conducting interfaces (unpolarised light;
//! pbrt-v4 §9.3).

use crate::color::Rgb;

/// Reflectance of a dielectric interface with relative index η = n_inside / n_outside,
/// for cos θi measured against the normal pointing outside (negative: from inside).
pub fn fr_dielectric(cos_theta_i: f64, eta: f64) -> f64 {
    let mut c = cos_theta_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if c < 0.0 {
        eta = 1.0 / eta;
        c = -c;
    }
    let sin2_t = (1.0 - c * c) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * c - cos_t) / (eta * c + cos_t);
    let r_perp = (c - eta * cos_t) / (c + eta * cos_t);
    (r_parl * r_parl + r_perp * r_perp) / 2.0
}

/// Reflectance of a conductor with complex index η + i k (relative to the outside),
/// for cos θi ∈ [0, 1]: the exact unpolarised reflectance in real arithmetic (pbrt-v3
/// §8.2.1, `FrConductor`; Mitsuba 3's `fresnel_conductor`), with a² + b² = |η̃² − sin²θ|
/// and a = Re √(η̃² − sin²θ). Two divisions and two square roots, where pbrt-v4's complex
/// form (`FrComplex`, kept as the tests' reference) takes seven divisions and three roots.
pub fn fr_conductor_scalar(cos_theta_i: f64, eta: f64, k: f64) -> f64 {
    let c = cos_theta_i.clamp(0.0, 1.0);
    let (c2, s2) = (c * c, 1.0 - c * c);
    let (eta2, k2) = (eta * eta, k * k);
    let t0 = eta2 - k2 - s2;
    let a2_plus_b2 = (t0 * t0 + 4.0 * eta2 * k2).sqrt();
    let a = (0.5 * (a2_plus_b2 + t0)).max(0.0).sqrt();
    let (t1, t2) = (a2_plus_b2 + c2, 2.0 * c * a);
    let r_s = (t1 - t2) / (t1 + t2);
    let (t3, t4) = (c2 * a2_plus_b2 + s2 * s2, t2 * s2);
    let r_p = r_s * (t3 - t4) / (t3 + t4);
    0.5 * (r_s + r_p)
}

/// [`fr_conductor_scalar`] per RGB channel.
pub fn fr_conductor(cos_theta_i: f64, eta: Rgb, k: Rgb) -> Rgb {
    Rgb::new(
        fr_conductor_scalar(cos_theta_i, eta.x, k.x),
        fr_conductor_scalar(cos_theta_i, eta.y, k.y),
        fr_conductor_scalar(cos_theta_i, eta.z, k.z),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug)]
    struct Complex {
        re: f64,
        im: f64,
    }

    impl Complex {
        fn new(re: f64, im: f64) -> Self {
            Self { re, im }
        }
        fn add(self, b: Self) -> Self {
            Self::new(self.re + b.re, self.im + b.im)
        }
        fn sub(self, b: Self) -> Self {
            Self::new(self.re - b.re, self.im - b.im)
        }
        fn mul(self, b: Self) -> Self {
            Self::new(
                self.re * b.re - self.im * b.im,
                self.re * b.im + self.im * b.re,
            )
        }
        fn div(self, b: Self) -> Self {
            let d = b.re * b.re + b.im * b.im;
            Self::new(
                (self.re * b.re + self.im * b.im) / d,
                (self.im * b.re - self.re * b.im) / d,
            )
        }
        fn norm(self) -> f64 {
            self.re * self.re + self.im * self.im
        }
        /// Principal square root.
        fn sqrt(self) -> Self {
            let n = self.norm().sqrt();
            if n == 0.0 {
                return Self::new(0.0, 0.0);
            }
            let t1 = (0.5 * (n + self.re.abs())).sqrt();
            let t2 = 0.5 * self.im / t1;
            if self.re >= 0.0 {
                Self::new(t1, t2)
            } else {
                Self::new(t2.abs(), t1.copysign(self.im))
            }
        }
    }

    /// Reflectance of a conductor with complex index η + i k (relative to the outside),
    /// for cos θi ∈ [0, 1] in complex arithmetic (pbrt-v4 `FrComplex`): the reference.
    fn fr_complex(cos_theta_i: f64, eta: f64, k: f64) -> f64 {
        let c = cos_theta_i.clamp(0.0, 1.0);
        let ci = Complex::new(c, 0.0);
        let e = Complex::new(eta, k);
        let sin2_i = Complex::new(1.0 - c * c, 0.0);
        let sin2_t = sin2_i.div(e.mul(e));
        let cos_t = Complex::new(1.0, 0.0).sub(sin2_t).sqrt();
        let r_parl = e.mul(ci).sub(cos_t).div(e.mul(ci).add(cos_t));
        let r_perp = ci.sub(e.mul(cos_t)).div(ci.add(e.mul(cos_t)));
        (r_parl.norm() + r_perp.norm()) / 2.0
    }

    /// The real form equals pbrt-v4's complex one to rounding, over incidence from
    /// grazing to normal and indices from dielectric-like (k = 0, η below and above 1)
    /// to strongly absorbing metals.
    #[test]
    fn real_form_is_the_complex_one() {
        let etas = [0.05, 0.2, 0.5, 0.9, 1.0, 1.1, 1.5, 2.5, 4.0];
        let ks = [0.0, 0.01, 0.5, 1.0, 2.4, 3.9, 8.0];
        for i in 0..=200 {
            let c = f64::from(i) / 200.0;
            for eta in etas {
                for k in ks {
                    if c == 0.0 && eta == 1.0 && k == 0.0 {
                        continue; // no interface, at grazing: 0/0 in both forms
                    }
                    let (a, b) = (fr_conductor_scalar(c, eta, k), fr_complex(c, eta, k));
                    assert!(
                        (a - b).abs() < 1e-12,
                        "c {c}, η {eta}, k {k}: {a} against {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn dielectric_known_values() {
        // Normal incidence: ((η−1)/(η+1))² = 0.04 for η = 1.5, from either side.
        assert!((fr_dielectric(1.0, 1.5) - 0.04).abs() < 1e-12);
        assert!((fr_dielectric(-1.0, 1.5) - 0.04).abs() < 1e-12);
        // Brewster angle tan θ = η: p-polarised reflectance is 0, so F = r_perp²/2.
        let tb = 1.5f64.atan();
        let ct = (1.0 - (tb.sin() / 1.5).powi(2)).sqrt();
        let rs = (tb.cos() - 1.5 * ct) / (tb.cos() + 1.5 * ct);
        assert!((fr_dielectric(tb.cos(), 1.5) - rs * rs / 2.0).abs() < 1e-12);
        // Total internal reflection beyond the critical angle from inside.
        let crit = (1.0f64 / 1.5).asin();
        assert_eq!(fr_dielectric(-(crit + 0.01).cos(), 1.5), 1.0);
        assert!(fr_dielectric(-(crit - 0.01).cos(), 1.5) < 1.0);
        assert_eq!(fr_dielectric(0.0, 1.5), 1.0);
    }

    #[test]
    fn conductor_known_values() {
        // Normal incidence: ((η−1)² + k²) / ((η+1)² + k²).
        let (eta, k) = (0.2, 3.0);
        let r0 = ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k);
        assert!((fr_conductor_scalar(1.0, eta, k) - r0).abs() < 1e-12);
        // k = 0 reduces to the dielectric formula.
        for c in [0.1, 0.5, 0.9] {
            assert!((fr_conductor_scalar(c, 1.5, 0.0) - fr_dielectric(c, 1.5)).abs() < 1e-12);
        }
        assert!((fr_conductor_scalar(0.0, eta, k) - 1.0).abs() < 1e-12);
        let f = fr_conductor(0.5, Rgb::new(0.2, 0.9, 1.1), Rgb::new(3.9, 2.4, 2.2));
        assert!(f.min_element() > 0.0 && f.max_element() < 1.0);
    }
}
