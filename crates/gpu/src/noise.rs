//! Solid noise patterns on the GPU (`shaders/noise.wgsl`): Perlin's improved gradient
//! noise, fBm, turbulence, marble and wood in f32, the twins of `render::noise`'s f64
//! patterns (Perlin 2002; Ebert et al., "Texturing and Modeling", ch. 2). This module is
//! the kernel's CPU twin, operation for operation; the kernels read Perlin's
//! permutation ([`scene::PERLIN_PERM`]) from the scene's tables.

use scene::PERLIN_PERM;

/// The patterns' kernel (after TRIG_WGSL; the includer defines `noise_perm` and the
/// `loops` counter).
pub const NOISE_WGSL: &str = include_str!("shaders/noise.wgsl");

fn perm(i: u32) -> u32 {
    u32::from(PERLIN_PERM[(i & 255) as usize])
}

fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

fn grad(hash: u32, x: f32, y: f32, z: f32) -> f32 {
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

fn lerp(t: f32, a: f32, b: f32) -> f32 {
    a + t * (b - a)
}

/// An integer-valued f modulo 256, in 0..256 (exact: f/256 is).
fn wrap(f: f32) -> u32 {
    (f - 256.0 * (f / 256.0).floor()) as u32
}

/// Improved Perlin noise at `p` (the kernel's `n_perlin`).
pub fn perlin(p: [f32; 3]) -> f32 {
    let f = p.map(f32::floor);
    let (x, y, z) = (p[0] - f[0], p[1] - f[1], p[2] - f[2]);
    let (xi, yi, zi) = (wrap(f[0]), wrap(f[1]), wrap(f[2]));
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

/// fBm (`absolute` false) or turbulence over `octaves` (the kernel's `n_fractal`).
pub fn fractal(p: [f32; 3], octaves: u32, absolute: bool) -> f32 {
    let (mut sum, mut norm, mut a) = (0.0f32, 0.0f32, 1.0f32);
    let shift = [19.19f32, 7.31, 3.77];
    for i in 0..octaves.max(1) {
        let s = (1u32 << i) as f32;
        let q = [0, 1, 2].map(|k| p[k] * s + shift[k] * i as f32);
        let mut n = perlin(q);
        if absolute {
            n = n.abs();
        }
        sum += a * n;
        norm += a;
        a *= 0.5;
    }
    sum / norm
}

/// Pattern `kind` ([`scene::PatternKind`]'s order) at `p` (scaled), in [0, 1] (the
/// kernel's `pattern_value`).
pub fn pattern_value(kind: u32, p: [f32; 3], octaves: u32) -> f32 {
    let v = match kind {
        0 => 0.5 + 0.5 * perlin(p),
        1 => 0.5 + 0.5 * fractal(p, octaves, false),
        2 => fractal(p, octaves, true),
        3 => {
            let turns = p[0] - p[0].floor();
            let arg = 6.283_185_5 * turns + 6.0 * fractal(p, octaves, true);
            0.5 + 0.5 * crate::tape::sin_cos(arg, false)
        }
        _ => {
            let r = (p[0] * p[0] + p[1] * p[1]).sqrt() + 0.3 * fractal(p, octaves, false);
            let q = 4.0 * r;
            (q - q.trunc()).abs()
        }
    };
    v.clamp(0.0, 1.0)
}

/// The kernels' code of a pattern (`GpuMaterial::tex_code`).
pub fn pattern_code(kind: scene::PatternKind) -> u32 {
    scene::PatternKind::ALL
        .iter()
        .position(|&k| k == kind)
        .expect("every pattern is listed") as u32
}
