//! Statistical helpers for the tests: chi-square p-values and a binned sphere
//! (Pearson's test with low-expectation cells pooled, as in Mitsuba's `chi2` tests).

use crate::sampler::Sampler;
use glam::DVec3;
use std::f64::consts::PI;

/// ln Γ(x) for x > 0 (Lanczos approximation, g = 7, n = 9; error < 1e-13).
pub fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, &c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The upper regularised incomplete gamma function Q(a, x) (series or continued
/// fraction, Numerical Recipes §6.2).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let gln = ln_gamma(a);
    if x < a + 1.0 {
        let (mut ap, mut sum) = (a, 1.0 / a);
        let mut del = sum;
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - gln).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - gln).exp() * h
    }
}

/// P(χ²_dof ≥ stat).
pub fn chi2_pvalue(stat: f64, dof: usize) -> f64 {
    gamma_q(dof as f64 / 2.0, stat / 2.0)
}

/// The sphere cut into cells of equal solid angle: `nz` bands of cos θ ∈ [−1, 1]
/// times `nphi` sectors of φ.
pub struct SphereBins {
    /// Bands of cos θ.
    pub nz: usize,
    /// Sectors of φ.
    pub nphi: usize,
}

impl SphereBins {
    /// nz × nphi cells.
    pub fn new(nz: usize, nphi: usize) -> Self {
        Self { nz, nphi }
    }
    /// The cell of a unit direction.
    pub fn cell(&self, w: DVec3) -> usize {
        let z = ((w.z.clamp(-1.0, 1.0) + 1.0) * 0.5 * self.nz as f64) as usize;
        let mut phi = w.y.atan2(w.x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let p = (phi / (2.0 * PI) * self.nphi as f64) as usize;
        z.min(self.nz - 1) * self.nphi + p.min(self.nphi - 1)
    }
    /// ∫ pdf over each cell, adaptively: a rectangle of (θ, φ) whose 4 × 4 midpoint
    /// estimate differs from the 8 × 8 one by more than `eps` (absolute) is split in
    /// four, down to 14 levels; this resolves discontinuities (light silhouettes) and
    /// integrable singularities (grazing area sampling).
    pub fn integrate_adaptive(&self, eps: f64, pdf: &dyn Fn(DVec3) -> f64) -> Vec<f64> {
        // `coarse` is the 4 × 4 midpoint estimate of `r`, which the caller has already
        // computed (a parent's fine estimate is made of its children's coarse ones).
        fn rec(pdf: &dyn Fn(DVec3) -> f64, r: [f64; 4], coarse: f64, eps: f64, depth: u32) -> f64 {
            let [t0, t1, p0, p1] = r;
            let (tm, pm) = ((t0 + t1) / 2.0, (p0 + p1) / 2.0);
            let quads = [
                [t0, tm, p0, pm],
                [t0, tm, pm, p1],
                [tm, t1, p0, pm],
                [tm, t1, pm, p1],
            ];
            let parts = quads.map(|q| midpoint(pdf, q[0], q[1], q[2], q[3], 4));
            let fine: f64 = parts.iter().sum();
            if (fine - coarse).abs() <= eps || depth == 14 {
                fine
            } else {
                quads
                    .iter()
                    .zip(parts)
                    .map(|(&q, c)| rec(pdf, q, c, eps / 2.0, depth + 1))
                    .sum()
            }
        }
        self.cells()
            .map(|(t0, t1, p0, p1)| {
                // Start from 4 × 4 pieces so that features inside a cell are seen.
                let mut sum = 0.0;
                for a in 0..4 {
                    for b in 0..4 {
                        let (dt, dp) = ((t1 - t0) / 4.0, (p1 - p0) / 4.0);
                        let r = [
                            t0 + a as f64 * dt,
                            t0 + (a + 1) as f64 * dt,
                            p0 + b as f64 * dp,
                            p0 + (b + 1) as f64 * dp,
                        ];
                        let coarse = midpoint(pdf, r[0], r[1], r[2], r[3], 4);
                        sum += rec(pdf, r, coarse, eps / 16.0, 0);
                    }
                }
                sum
            })
            .collect()
    }
    /// (θ0, θ1, φ0, φ1) of every cell, in the order of [`Self::cell`].
    fn cells(&self) -> impl Iterator<Item = (f64, f64, f64, f64)> + '_ {
        (0..self.nz * self.nphi).map(move |c| {
            let (row, sector) = (c / self.nphi, c % self.nphi);
            // Row counts from z = −1 upward: z ∈ [z0, z1] ⇔ θ ∈ [acos z1, acos z0].
            let z0 = (-1.0 + 2.0 * row as f64 / self.nz as f64).clamp(-1.0, 1.0);
            let z1 = (-1.0 + 2.0 * (row + 1) as f64 / self.nz as f64).clamp(-1.0, 1.0);
            let dphi = 2.0 * PI / self.nphi as f64;
            (
                z1.acos(),
                z0.acos(),
                sector as f64 * dphi,
                (sector + 1) as f64 * dphi,
            )
        })
    }
}

/// ∫∫ pdf(θ, φ) sin θ dθ dφ over a rectangle by the k × k midpoint rule.
fn midpoint(pdf: &dyn Fn(DVec3) -> f64, t0: f64, t1: f64, p0: f64, p1: f64, k: usize) -> f64 {
    let (dt, dp) = ((t1 - t0) / k as f64, (p1 - p0) / k as f64);
    let mut s = 0.0;
    for i in 0..k {
        let (st, ct) = (t0 + (i as f64 + 0.5) * dt).sin_cos();
        for j in 0..k {
            let (sp, cp) = (p0 + (j as f64 + 0.5) * dp).sin_cos();
            s += pdf(DVec3::new(st * cp, st * sp, ct)) * st;
        }
    }
    s * dt * dp
}

/// The outcome of [`sphere_chi2`].
#[derive(Debug)]
#[allow(dead_code)] // stat and dof are read through Debug in failure messages
pub struct Chi2 {
    /// Pearson's statistic.
    pub stat: f64,
    /// Degrees of freedom.
    pub dof: usize,
    /// P(χ² ≥ stat).
    pub p_value: f64,
    /// ∫ pdf over the sphere (quadrature).
    pub mass: f64,
    /// Fraction of draws that returned a direction.
    pub valid: f64,
}

/// Draws `n` directions (random numbers from `Sampler::new(seed)`), bins them, and
/// compares the counts with the pdf integrated over each cell (adaptive quadrature,
/// absolute tolerance 1e-6 a cell),
/// normalised to the valid draws; cells expecting fewer than 5 are pooled.
pub fn sphere_chi2(
    bins: &SphereBins,
    n: u64,
    seed: u64,
    mut sample: impl FnMut([f64; 3]) -> Option<DVec3>,
    pdf: impl Fn(DVec3) -> f64,
) -> Chi2 {
    let s = Sampler::new(seed);
    let mut counts = vec![0u64; bins.nz * bins.nphi];
    let mut valid = 0u64;
    for i in 0..n {
        let st = s.stream(0, 0, i as u32);
        if let Some(w) = sample([st.get(0), st.get(1), st.get(2)]) {
            assert!((w.length() - 1.0).abs() < 1e-9, "not unit: {w}");
            counts[bins.cell(w)] += 1;
            valid += 1;
        }
    }
    let m = bins.integrate_adaptive(1e-6, &pdf);
    let mass: f64 = m.iter().sum();
    let mut cells: Vec<(f64, f64)> = m
        .iter()
        .zip(&counts)
        .map(|(&mi, &c)| {
            let e = if mass > 0.0 {
                valid as f64 * mi / mass
            } else {
                0.0
            };
            (e, c as f64)
        })
        .collect();
    cells.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap());
    let (mut stat, mut dof) = (0.0, 0usize);
    let (mut pe, mut po) = (0.0, 0.0);
    for (e, o) in cells {
        if e < 5.0 {
            pe += e;
            po += o;
        } else {
            stat += (o - e).powi(2) / e;
            dof += 1;
        }
    }
    if pe >= 5.0 {
        stat += (po - pe).powi(2) / pe;
        dof += 1;
    } else if po > pe + 10.0 * pe.sqrt().max(1.0) {
        // Many samples where the pdf has almost no mass: fail outright.
        stat = f64::INFINITY;
    }
    let dof = dof.saturating_sub(1).max(1);
    Chi2 {
        stat,
        dof,
        p_value: chi2_pvalue(stat, dof),
        mass,
        valid: valid as f64 / n as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_chi2_quantiles() {
        // Tabulated: χ²₁ at 3.841 → 0.05; χ²₁₀ at 23.209 → 0.01; χ²₁₀₀ at 135.807 → 0.01.
        assert!((chi2_pvalue(3.841_458_8, 1) - 0.05).abs() < 1e-6);
        assert!((chi2_pvalue(23.209_251, 10) - 0.01).abs() < 1e-6);
        assert!((chi2_pvalue(135.806_7, 100) - 0.01).abs() < 1e-5);
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
    }
}
