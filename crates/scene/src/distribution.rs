//! Piecewise-constant distributions as plain tables (pbrt-v4 §A.5.1 and §A.5.2,
//! `PiecewiseConstant1D` / `PiecewiseConstant2D`): the numbers every back end samples
//! from, computed once when a scene is resolved. Sampling lives with the renderers.

use serde::Serialize;

/// A piecewise-constant density on [0, 1) from n non-negative values, also a discrete
/// distribution over n items: `cdf[i] ≤ u < cdf[i + 1]` picks item i.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Distribution1D {
    /// The values, negatives replaced by 0 (all 1 when every value was 0).
    pub func: Vec<f64>,
    /// n + 1 entries from 0 to exactly 1.
    pub cdf: Vec<f64>,
    /// ∫₀¹ f = Σ func / n.
    pub integral: f64,
}

impl Distribution1D {
    /// The distribution proportional to `f` (negative values count as 0). When every
    /// value is 0, the distribution is uniform. `f` must not be empty.
    pub fn new(f: &[f64]) -> Self {
        assert!(!f.is_empty(), "empty distribution");
        let n = f.len();
        let mut func: Vec<f64> = f.iter().map(|&v| if v > 0.0 { v } else { 0.0 }).collect();
        let mut cdf = vec![0.0; n + 1];
        for i in 0..n {
            cdf[i + 1] = cdf[i] + func[i] / n as f64;
        }
        let mut integral = cdf[n];
        if integral <= 0.0 || !integral.is_finite() {
            func.iter_mut().for_each(|v| *v = 1.0);
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f64 / n as f64;
            }
            integral = 1.0;
        } else {
            for c in cdf.iter_mut() {
                *c /= integral;
            }
        }
        cdf[n] = 1.0;
        Self {
            func,
            cdf,
            integral,
        }
    }

    /// Number of pieces.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Always false (a distribution has at least one piece).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The probability of item i: f_i / Σf.
    pub fn pmf(&self, i: usize) -> f64 {
        self.func[i] / (self.integral * self.len() as f64)
    }
}

/// A piecewise-constant density on [0,1)² from an nu × nv grid (row v, column u): a
/// marginal over rows and a conditional over columns for each row.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Distribution2D {
    /// One distribution over u per row.
    pub conditional: Vec<Distribution1D>,
    /// The distribution over rows, ∝ each row's mean.
    pub marginal: Distribution1D,
}

impl Distribution2D {
    /// The distribution proportional to `f`, row-major with `nu` values a row.
    pub fn new(f: &[f64], nu: usize, nv: usize) -> Self {
        assert_eq!(f.len(), nu * nv, "grid size");
        let conditional: Vec<Distribution1D> = f.chunks(nu).map(Distribution1D::new).collect();
        let row: Vec<f64> = f
            .chunks(nu)
            .map(|r| r.iter().map(|&v| v.max(0.0)).sum::<f64>() / nu as f64)
            .collect();
        let marginal = Distribution1D::new(&row);
        Self {
            conditional,
            marginal,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pmf_and_cdf() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, -2.0]);
        assert_eq!(d.pmf(0), 0.25);
        assert_eq!(d.pmf(2), 0.75);
        assert_eq!(d.pmf(3), 0.0);
        assert_eq!(d.cdf, vec![0.0, 0.25, 0.25, 1.0, 1.0]);
        let z = Distribution1D::new(&[0.0, 0.0]);
        assert_eq!((z.pmf(1), z.integral), (0.5, 1.0));
        let g = Distribution2D::new(&[1.0, 1.0, 0.0, 2.0], 2, 2);
        assert_eq!(g.marginal.func, vec![1.0, 1.0]);
        assert_eq!(g.conditional[1].pmf(1), 1.0);
    }
}
