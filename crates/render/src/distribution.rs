//! Piecewise-constant distributions in one and two dimensions (pbrt-v4 §A.5.1 and
//! §A.5.2, `PiecewiseConstant1D` / `PiecewiseConstant2D`): sampling over the tables of
//! [`scene::Distribution1D`] / [`scene::Distribution2D`], which compute them (one
//! construction for every back end).

use glam::DVec2;

/// The largest f64 below 1: a remapped uniform number stays in [0, 1).
pub(crate) const ONE_MINUS_EPSILON: f64 = 1.0 - f64::EPSILON / 2.0;

/// A piecewise-constant density on [0, 1) from n non-negative values, also usable as
/// a discrete distribution over n items.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    func: Vec<f64>,
    cdf: Vec<f64>,
    integral: f64,
    /// Guide table (Chen & Asau 1974, indexed search; Devroye 1986, §III.2.4):
    /// `guide[j]` is the piece holding u = j/n. A search starts there and steps over the
    /// cdf points in u's bucket, n + 1 points in n buckets: O(1) expected whatever f, and
    /// the piece the binary search over the cdf finds.
    guide: Vec<u32>,
}

impl Distribution1D {
    /// The distribution proportional to `f` (negative values count as 0). When every
    /// value is 0, the distribution is uniform. `f` must not be empty.
    pub fn new(f: &[f64]) -> Self {
        Self::from(&scene::Distribution1D::new(f))
    }
    /// Number of pieces.
    pub fn len(&self) -> usize {
        self.func.len()
    }
    /// Always false (a distribution has at least one piece).
    pub fn is_empty(&self) -> bool {
        false
    }
    /// ∫₀¹ f (after replacing an all-zero f by 1).
    pub fn integral(&self) -> f64 {
        self.integral
    }
    /// The piece i with cdf[i] ≤ u < cdf[i+1] (the last such, where pieces are empty;
    /// the first piece for u < 0 or NaN, the last for u ≥ 1), from its guide-table
    /// bucket: the same piece as [`Self::find_binary`] for every u.
    #[inline]
    fn find(&self, u: f64) -> usize {
        let n = self.func.len();
        let mut i = self.guide[((u * n as f64) as usize).min(n - 1)] as usize;
        // u·n rounded up past a bucket's edge: step back to the piece holding u.
        while i > 0 && (self.cdf[i] > u || u.is_nan()) {
            i -= 1;
        }
        while i + 1 < n && self.cdf[i + 1] <= u {
            i += 1;
        }
        i
    }
    /// [`Self::find`] by binary search over the cdf, O(log n): what builds the guide.
    fn find_binary(cdf: &[f64], u: f64) -> usize {
        let i = cdf.partition_point(|&c| c <= u);
        i.saturating_sub(1).min(cdf.len() - 2)
    }
    /// A point x of [0, 1) with density f(x)/∫f; returns (x, density, piece).
    pub fn sample_continuous(&self, u: f64) -> (f64, f64, usize) {
        let i = self.find(u);
        let mut du = u - self.cdf[i];
        let width = self.cdf[i + 1] - self.cdf[i];
        if width > 0.0 {
            du /= width;
        }
        let x = ((i as f64 + du) / self.len() as f64).min(ONE_MINUS_EPSILON);
        (x, self.func[i] / self.integral, i)
    }
    /// An index i with probability f_i / Σf; returns (i, probability, u remapped to
    /// [0, 1) within the chosen piece, for reuse).
    pub fn sample_discrete(&self, u: f64) -> (usize, f64, f64) {
        let i = self.find(u);
        let width = self.cdf[i + 1] - self.cdf[i];
        let rest = if width > 0.0 {
            ((u - self.cdf[i]) / width).min(ONE_MINUS_EPSILON)
        } else {
            0.0
        };
        (i, self.pmf(i), rest)
    }
    /// The probability of index i in [`Self::sample_discrete`].
    pub fn pmf(&self, i: usize) -> f64 {
        self.func[i] / (self.integral * self.len() as f64)
    }
    /// The density at x ∈ [0, 1) of [`Self::sample_continuous`].
    pub fn pdf(&self, x: f64) -> f64 {
        if !(0.0..1.0).contains(&x) {
            return 0.0;
        }
        let i = ((x * self.len() as f64) as usize).min(self.len() - 1);
        self.func[i] / self.integral
    }
}

/// A piecewise-constant density on [0,1)² from an nu × nv grid (row v, column u):
/// a marginal over v and a conditional over u for each row.
#[derive(Clone, Debug)]
pub struct Distribution2D {
    conditional: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// The distribution proportional to `f`, row-major with `nu` values a row.
    pub fn new(f: &[f64], nu: usize, nv: usize) -> Self {
        Self::from(&scene::Distribution2D::new(f, nu, nv))
    }
    /// A point (u, v) with density f/∫f; returns the point and its density.
    pub fn sample(&self, u: DVec2) -> (DVec2, f64) {
        let (v, pdf_v, row) = self.marginal.sample_continuous(u.y);
        let (x, pdf_u, _) = self.conditional[row].sample_continuous(u.x);
        (DVec2::new(x, v), pdf_u * pdf_v)
    }
    /// The density at (u, v) of [`Self::sample`].
    pub fn pdf(&self, p: DVec2) -> f64 {
        if !(0.0..1.0).contains(&p.y) {
            return 0.0;
        }
        let row = ((p.y * self.marginal.len() as f64) as usize).min(self.marginal.len() - 1);
        self.marginal.pdf(p.y) * self.conditional[row].pdf(p.x)
    }
}

impl From<&scene::Distribution1D> for Distribution1D {
    /// The sampler over a table computed at scene resolution.
    fn from(d: &scene::Distribution1D) -> Self {
        let n = d.func.len();
        let guide = (0..n)
            .map(|j| Self::find_binary(&d.cdf, j as f64 / n as f64) as u32)
            .collect();
        Self {
            func: d.func.clone(),
            cdf: d.cdf.clone(),
            integral: d.integral,
            guide,
        }
    }
}

impl From<&scene::Distribution2D> for Distribution2D {
    /// The sampler over a table computed at scene resolution.
    fn from(d: &scene::Distribution2D) -> Self {
        Self {
            conditional: d.conditional.iter().map(Distribution1D::from).collect(),
            marginal: Distribution1D::from(&d.marginal),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Sampler;
    use crate::testutil::chi2_pvalue;

    #[test]
    fn discrete_probabilities_and_remap() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, -2.0]);
        assert_eq!(d.pmf(0), 0.25);
        assert_eq!(d.pmf(1), 0.0);
        assert_eq!(d.pmf(2), 0.75);
        assert_eq!(d.pmf(3), 0.0);
        assert_eq!(d.sample_discrete(0.1).0, 0);
        assert_eq!(d.sample_discrete(0.25).0, 2);
        assert_eq!(d.sample_discrete(0.999_999).0, 2);
        let (_, _, r) = d.sample_discrete(0.625);
        assert!((r - 0.5).abs() < 1e-12);
        let z = Distribution1D::new(&[0.0, 0.0]);
        assert_eq!(z.pmf(1), 0.5);
    }

    /// The guide table finds the piece the binary search finds, for every u: on random
    /// distributions with empty pieces, runs of equal values and one heavy piece, at
    /// random u, at every cdf point and bucket edge and the floats beside them, and
    /// outside [0, 1).
    #[test]
    fn guide_table_finds_the_binary_search_piece() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rand = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let beside = |x: f64| [x, x.next_down(), x.next_up()];
        for case in 0..300 {
            let n = 1 + (rand() * 200.0) as usize;
            let f: Vec<f64> = (0..n)
                .map(|i| match case % 4 {
                    0 => rand(),
                    1 if rand() < 0.5 => 0.0,
                    2 if i == n / 2 => 1e9,
                    3 => (i / 7) as f64,
                    _ => rand() * 10.0,
                })
                .collect();
            let d = Distribution1D::new(&f);
            let mut us: Vec<f64> = (0..400).map(|_| rand()).collect();
            us.extend(d.cdf.iter().flat_map(|&c| beside(c)));
            us.extend((0..=n).flat_map(|j| beside(j as f64 / n as f64)));
            us.extend([-1.0, -0.0, 1.0, 2.0, f64::NAN, ONE_MINUS_EPSILON]);
            for u in us {
                let want = Distribution1D::find_binary(&d.cdf, u);
                assert_eq!(d.find(u), want, "case {case}, n {n}, u {u:e}");
            }
        }
    }

    #[test]
    fn continuous_inverts_cdf() {
        let d = Distribution1D::new(&[1.0, 3.0]);
        // ∫f = 2; cdf(½) = ¼.
        let (x, pdf, i) = d.sample_continuous(0.25);
        assert!((x - 0.5).abs() < 1e-12 && i == 1 && (pdf - 1.5).abs() < 1e-12);
        let (x, pdf, _) = d.sample_continuous(0.125);
        assert!((x - 0.25).abs() < 1e-12 && (pdf - 0.5).abs() < 1e-12);
        assert_eq!(d.pdf(0.75), 1.5);
        assert_eq!(d.pdf(1.0), 0.0);
    }

    /// Samples of a 2-D distribution fall in cells with probability f/Σf:
    /// chi-square, 200 000 samples, significance 1e-3; density integrates to 1.
    #[test]
    fn two_d_matches_function() {
        let (nu, nv) = (8, 5);
        let f: Vec<f64> = (0..nu * nv)
            .map(|i| ((i * 37) % 11) as f64 + if i == 7 { 0.0 } else { 0.5 })
            .collect();
        let d = Distribution2D::new(&f, nu, nv);
        let total: f64 = f.iter().sum();
        let s = Sampler::new(5);
        let n = 200_000u64;
        let mut counts = vec![0u64; nu * nv];
        for i in 0..n {
            let st = s.stream(0, 0, i as u32);
            let (p, pdf) = d.sample(DVec2::new(st.get(0), st.get(1)));
            assert!((pdf - d.pdf(p)).abs() < 1e-9 * pdf);
            counts[(p.y * nv as f64) as usize * nu + (p.x * nu as f64) as usize] += 1;
        }
        let mut stat = 0.0;
        let mut dof = 0;
        for (c, fv) in counts.iter().zip(&f) {
            let e = n as f64 * fv / total;
            if e > 0.0 {
                stat += (*c as f64 - e).powi(2) / e;
                dof += 1;
            } else {
                assert_eq!(*c, 0);
            }
        }
        let p = chi2_pvalue(stat, dof - 1);
        assert!(p > 1e-3, "chi2 {stat} p {p}");
        let mass: f64 = (0..nu * nv)
            .map(|i| {
                let c = DVec2::new(
                    ((i % nu) as f64 + 0.5) / nu as f64,
                    ((i / nu) as f64 + 0.5) / nv as f64,
                );
                d.pdf(c) / (nu * nv) as f64
            })
            .sum();
        assert!((mass - 1.0).abs() < 1e-12);
    }
}
