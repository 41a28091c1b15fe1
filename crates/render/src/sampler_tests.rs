//! The sample streams of `state::sampler`: every dimension uniform and neighbouring
//! streams independent (chi-square, with this crate's test helpers).

use crate::testutil::chi2_pvalue;
use state::sampler::Sampler;

/// Pearson chi-square of counts against equal expected counts.
fn chi2_uniform(counts: &[u64]) -> (f64, usize) {
    let n: u64 = counts.iter().sum();
    let e = n as f64 / counts.len() as f64;
    let s = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
    (s, counts.len() - 1)
}

/// 1-D uniformity of each of the first dimensions over many pixels and samples:
/// chi-square over 100 bins, rejected at significance 1e-3 (per dimension).
#[test]
fn uniform_chi_square() {
    let s = Sampler::new(1234);
    for dim in 0..4 {
        let mut counts = vec![0u64; 100];
        for y in 0..64 {
            for x in 0..64 {
                for i in 0..50 {
                    let u = s.stream(x, y, i).get(dim);
                    assert!((0.0..1.0).contains(&u));
                    counts[(u * 100.0) as usize] += 1;
                }
            }
        }
        let (stat, dof) = chi2_uniform(&counts);
        let p = chi2_pvalue(stat, dof);
        assert!(p > 1e-3, "dim {dim}: chi2 {stat} dof {dof} p {p}");
    }
}

/// Independence: pairs (stream A, stream B) of neighbouring pixels, neighbouring
/// sample indices and neighbouring dimensions fill [0,1)² uniformly (chi-square over
/// 32 × 32 cells, significance 1e-3 each), and their correlation is below 4σ.
#[test]
fn streams_independent() {
    let s = Sampler::new(99);
    type Pair = fn(&Sampler, u32, u32, u32) -> (f64, f64);
    let pairs: [(&str, Pair); 4] = [
        ("pixel x", |s, x, y, i| {
            (s.stream(x, y, i).get(0), s.stream(x + 1, y, i).get(0))
        }),
        ("pixel y", |s, x, y, i| {
            (s.stream(x, y, i).get(0), s.stream(x, y + 1, i).get(0))
        }),
        ("index", |s, x, y, i| {
            (s.stream(x, y, i).get(0), s.stream(x, y, i + 1).get(0))
        }),
        ("dimension", |s, x, y, i| {
            let t = s.stream(x, y, i);
            (t.get(0), t.get(1))
        }),
    ];
    for (name, f) in pairs {
        let mut counts = vec![0u64; 32 * 32];
        let (mut sxy, mut n) = (0.0, 0.0);
        for y in 0..40 {
            for x in 0..40 {
                for i in 0..64 {
                    let (a, b) = f(&s, x, y, i);
                    counts[(a * 32.0) as usize * 32 + (b * 32.0) as usize] += 1;
                    sxy += (a - 0.5) * (b - 0.5);
                    n += 1.0;
                }
            }
        }
        let (stat, dof) = chi2_uniform(&counts);
        let p = chi2_pvalue(stat, dof);
        assert!(p > 1e-3, "{name}: chi2 {stat} dof {dof} p {p}");
        // Var((a−½)(b−½)) = 1/144 for independent uniforms.
        let corr = sxy / n * 12.0;
        assert!(corr.abs() < 4.0 / n.sqrt(), "{name}: correlation {corr}");
    }
}
