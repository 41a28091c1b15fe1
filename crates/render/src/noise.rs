//! Solid noise for procedural textures: Perlin's improved gradient noise (Perlin 2002,
//! "Improving Noise": the quintic fade 6t⁵ − 15t⁴ + 10t³ and the twelve cube-edge
//! gradients), its fractal sums — fBm and turbulence (Perlin 1985; Ebert et al.,
//! "Texturing and Modeling", ch. 2) — and the marble and wood patterns built on them,
//! as HyperFun's and libfive's modellers use them. Every pattern maps a point to a
//! value in [0, 1] that blends a texture's two colours.

use glam::DVec3;

/// Perlin's permutation (Perlin 2002), shared with the GPU's copy of these patterns.
use ::scene::PERLIN_PERM as PERM;

fn perm(i: usize) -> usize {
    PERM[i & 255] as usize
}

/// The quintic fade 6t⁵ − 15t⁴ + 10t³: C² at the lattice, so no creases show.
fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// The dot product of one of the twelve cube-edge gradients (chosen by `hash`) with
/// (x, y, z) (Perlin 2002's `grad`).
fn grad(hash: usize, x: f64, y: f64, z: f64) -> f64 {
    let h = hash & 15;
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h == 12 || h == 14 {
        x
    } else {
        z
    };
    (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
}

fn lerp(t: f64, a: f64, b: f64) -> f64 {
    a + t * (b - a)
}

/// Improved Perlin noise at `p`: 0 at every lattice point, about [−1, 1], period 256.
pub fn perlin(p: DVec3) -> f64 {
    let f = p.floor();
    let (x, y, z) = (p.x - f.x, p.y - f.y, p.z - f.z);
    let (xi, yi, zi) = (
        f.x.rem_euclid(256.0) as usize,
        f.y.rem_euclid(256.0) as usize,
        f.z.rem_euclid(256.0) as usize,
    );
    let (u, v, w) = (fade(x), fade(y), fade(z));
    let a = perm(xi) + yi;
    let (aa, ab) = (perm(a) + zi, perm(a + 1) + zi);
    let b = perm(xi + 1) + yi;
    let (ba, bb) = (perm(b) + zi, perm(b + 1) + zi);
    lerp(
        w,
        lerp(
            v,
            lerp(u, grad(perm(aa), x, y, z), grad(perm(ba), x - 1.0, y, z)),
            lerp(
                u,
                grad(perm(ab), x, y - 1.0, z),
                grad(perm(bb), x - 1.0, y - 1.0, z),
            ),
        ),
        lerp(
            v,
            lerp(
                u,
                grad(perm(aa + 1), x, y, z - 1.0),
                grad(perm(ba + 1), x - 1.0, y, z - 1.0),
            ),
            lerp(
                u,
                grad(perm(ab + 1), x, y - 1.0, z - 1.0),
                grad(perm(bb + 1), x - 1.0, y - 1.0, z - 1.0),
            ),
        ),
    )
}

/// Octave `i`'s point: frequency 2ⁱ, shifted so that octaves' lattices do not line up
/// (their zeros would add up at the coarse lattice's points).
fn octave(p: DVec3, i: u32) -> DVec3 {
    p * f64::from(1u32 << i) + DVec3::new(19.19, 7.31, 3.77) * f64::from(i)
}

/// Fractal Brownian motion: Σᵢ 2⁻ⁱ noise(2ⁱ p) over `octaves`, divided by Σ 2⁻ⁱ so
/// that it stays in about [−1, 1].
pub fn fbm(p: DVec3, octaves: u32) -> f64 {
    let (mut sum, mut norm) = (0.0, 0.0);
    for i in 0..octaves.max(1) {
        let a = 0.5f64.powi(i as i32);
        sum += a * perlin(octave(p, i));
        norm += a;
    }
    sum / norm
}

/// Turbulence: Σᵢ 2⁻ⁱ |noise(2ⁱ p)|, normalised as [`fbm`]: in about [0, 1].
pub fn turbulence(p: DVec3, octaves: u32) -> f64 {
    let (mut sum, mut norm) = (0.0, 0.0);
    for i in 0..octaves.max(1) {
        let a = 0.5f64.powi(i as i32);
        sum += a * perlin(octave(p, i)).abs();
        norm += a;
    }
    sum / norm
}

/// A procedural pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pattern {
    /// Gradient noise, mapped from [−1, 1] to [0, 1].
    Noise,
    /// fBm, mapped from [−1, 1] to [0, 1].
    Fbm,
    /// Turbulence.
    Turbulence,
    /// Marble: veins ½ + ½ sin(2π x + 6 · turbulence), along x.
    Marble,
    /// Wood: rings around the z axis, the radius perturbed by noise.
    Wood,
}

impl Pattern {
    /// The pattern's value at `p` (already scaled), in [0, 1].
    pub fn value(self, p: DVec3, octaves: u32) -> f64 {
        let v = match self {
            Pattern::Noise => 0.5 + 0.5 * perlin(p),
            Pattern::Fbm => 0.5 + 0.5 * fbm(p, octaves),
            Pattern::Turbulence => turbulence(p, octaves),
            Pattern::Marble => {
                0.5 + 0.5 * (std::f64::consts::TAU * p.x + 6.0 * turbulence(p, octaves)).sin()
            }
            Pattern::Wood => {
                let r = (p.x * p.x + p.y * p.y).sqrt() + 0.3 * fbm(p, octaves);
                (4.0 * r).fract().abs()
            }
        };
        v.clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fixed stream of points (SplitMix64) in [−50, 50]³.
    fn points(n: usize) -> impl Iterator<Item = DVec3> {
        let mut s = 0x1234_5678_9ABC_DEF0u64;
        let mut next = move || {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 * 100.0 - 50.0
        };
        (0..n).map(move |_| DVec3::new(next(), next(), next()))
    }

    /// Gradient noise vanishes at every lattice point (its defining property), has mean
    /// about 0 (|mean| < 0.01 over 200 000 points, whose standard error is ~0.0005),
    /// stays within ±1.04 (Perlin noise's bound in 3-D is below √(3)/2·… ≈ 1.04) and
    /// uses its range (beyond ±0.6 somewhere).
    #[test]
    fn noise_statistics() {
        for p in points(1000) {
            assert_eq!(perlin(p.floor()), 0.0, "{p}");
        }
        let v: Vec<f64> = points(200_000).map(perlin).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let (lo, hi) = v
            .iter()
            .fold((0f64, 0f64), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(mean.abs() < 0.01, "{mean}");
        assert!(lo > -1.04 && hi < 1.04, "[{lo}, {hi}]");
        assert!(lo < -0.6 && hi > 0.6, "[{lo}, {hi}]");
        for pattern in [
            Pattern::Noise,
            Pattern::Fbm,
            Pattern::Turbulence,
            Pattern::Marble,
            Pattern::Wood,
        ] {
            let vals: Vec<f64> = points(20_000).map(|p| pattern.value(p, 5)).collect();
            let m = vals.iter().sum::<f64>() / vals.len() as f64;
            let spread = vals
                .iter()
                .fold((1f64, 0f64), |(a, b), &x| (a.min(x), b.max(x)));
            assert!(vals.iter().all(|x| (0.0..=1.0).contains(x)), "{pattern:?}");
            assert!(
                m > 0.1 && m < 0.9 && spread.1 - spread.0 > 0.5,
                "{pattern:?}: {m} {spread:?}"
            );
        }
    }

    /// No lattice artefacts: along lines in a generic direction, the power spectrum of
    /// the noise (the periodogram averaged over 48 parallel lines, so that a single
    /// bin's chance spikes average out) has no peak at the lattice's frequencies (1 and
    /// 2 per unit along each axis the lines cross): the power there is within 1.5× of
    /// its neighbourhood's.
    #[test]
    fn no_lattice_artefacts_in_the_spectrum() {
        let dir = DVec3::new(0.8, 0.5, 0.33).normalize();
        let (per_unit, units, lines) = (8usize, 128usize, 48usize);
        let n = per_unit * units;
        let samples: Vec<Vec<f64>> = (0..lines)
            .map(|l| {
                let o = DVec3::new(
                    0.37 + 3.1 * l as f64,
                    1.91 + 1.7 * l as f64,
                    4.3 - 2.3 * l as f64,
                );
                (0..n)
                    .map(|k| perlin(o + dir * (k as f64 / per_unit as f64)))
                    .collect()
            })
            .collect();
        // Mean power at frequency f (cycles per unit), by a direct DFT of each line.
        let power = |f: f64| {
            samples
                .iter()
                .map(|v| {
                    let (mut re, mut im) = (0.0, 0.0);
                    for (k, x) in v.iter().enumerate() {
                        let t = std::f64::consts::TAU * f * k as f64 / per_unit as f64;
                        re += x * t.cos();
                        im += x * t.sin();
                    }
                    (re * re + im * im) / n as f64
                })
                .sum::<f64>()
                / lines as f64
        };
        for axis in [dir.x, dir.y, dir.z] {
            for harmonic in [1.0, 2.0] {
                let f = axis * harmonic;
                let peak = power(f);
                let around: f64 = [-0.08, -0.05, 0.05, 0.08]
                    .iter()
                    .map(|d| power(f + d))
                    .sum::<f64>()
                    / 4.0;
                assert!(peak < 1.5 * around, "f = {f}: {peak} vs {around}");
            }
        }
    }
}
