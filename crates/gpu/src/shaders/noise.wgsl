// Solid noise patterns in f32 (render::noise, f64): Perlin's improved gradient noise,
// fBm, turbulence, marble and wood, each a value in [0, 1] that blends a texture's two
// colours. The twin is gpu::noise, operation for operation. `noise_perm(i)` (Perlin's
// permutation at i in 0..256) comes from the including kernel.
//
// Needs t_sin_cos (TAPE_WGSL) before it.

fn n_fade(t: f32) -> f32 { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

fn n_grad(hash: u32, x: f32, y: f32, z: f32) -> f32 {
    let h = hash & 15u;
    let u = select(y, x, h < 8u);
    var v = z;
    if (h < 4u) { v = y; } else if (h == 12u || h == 14u) { v = x; }
    return select(-u, u, (h & 1u) == 0u) + select(-v, v, (h & 2u) == 0u);
}

fn n_lerp(t: f32, a: f32, b: f32) -> f32 { return a + t * (b - a); }

fn n_perm(i: u32) -> u32 { return noise_perm(i & 255u); }

// The lattice coordinate f (an integer) modulo 256 in 0..256, as rem_euclid: exact, as
// f/256 is.
fn n_wrap(f: f32) -> u32 { return u32(f - 256.0 * floor(f / 256.0)); }

// Improved Perlin noise (render::noise::perlin).
fn n_perlin(p: vec3<f32>) -> f32 {
    let f = floor(p);
    let x = p.x - f.x;
    let y = p.y - f.y;
    let z = p.z - f.z;
    let xi = n_wrap(f.x);
    let yi = n_wrap(f.y);
    let zi = n_wrap(f.z);
    let u = n_fade(x);
    let v = n_fade(y);
    let w = n_fade(z);
    let a = n_perm(xi) + yi;
    let aa = n_perm(a) + zi;
    let ab = n_perm(a + 1u) + zi;
    let b = n_perm(xi + 1u) + yi;
    let ba = n_perm(b) + zi;
    let bb = n_perm(b + 1u) + zi;
    return n_lerp(w,
        n_lerp(v,
            n_lerp(u, n_grad(n_perm(aa), x, y, z), n_grad(n_perm(ba), x - 1.0, y, z)),
            n_lerp(u, n_grad(n_perm(ab), x, y - 1.0, z), n_grad(n_perm(bb), x - 1.0, y - 1.0, z))),
        n_lerp(v,
            n_lerp(u, n_grad(n_perm(aa + 1u), x, y, z - 1.0), n_grad(n_perm(ba + 1u), x - 1.0, y, z - 1.0)),
            n_lerp(u, n_grad(n_perm(ab + 1u), x, y - 1.0, z - 1.0),
                n_grad(n_perm(bb + 1u), x - 1.0, y - 1.0, z - 1.0))));
}

// Σᵢ 2⁻ⁱ noise(octave i) (or its |noise| for turbulence) over Σ 2⁻ⁱ
// (render::noise::fbm, turbulence); octave i at 2ⁱ p + (19.19, 7.31, 3.77)·i.
fn n_fractal(p: vec3<f32>, octaves: u32, absolute: bool) -> f32 {
    var sum = 0.0;
    var norm = 0.0;
    var a = 1.0;
    for (var i = 0u; i < max(octaves, 1u); i++) {
        loops++;
        let q = p * f32(1u << i) + vec3<f32>(19.19, 7.31, 3.77) * f32(i);
        var n = n_perlin(q);
        if (absolute) { n = abs(n); }
        sum += a * n;
        norm += a;
        a *= 0.5;
    }
    return sum / norm;
}

// Pattern `kind` (scene::PatternKind's order: noise, fbm, turbulence, marble, wood) at
// p (already scaled), in [0, 1] (render::noise::Pattern::value). Marble's
// sin(2π x + 6 t) is taken at 2π fract(x) + 6 t, the same angle less whole turns.
fn pattern_value(kind: u32, p: vec3<f32>, octaves: u32) -> f32 {
    var v = 0.0;
    if (kind == 0u) {
        v = 0.5 + 0.5 * n_perlin(p);
    } else if (kind == 1u) {
        v = 0.5 + 0.5 * n_fractal(p, octaves, false);
    } else if (kind == 2u) {
        v = n_fractal(p, octaves, true);
    } else if (kind == 3u) {
        let turns = p.x - floor(p.x);
        v = 0.5 + 0.5 * t_sin_cos(6.2831855 * turns + 6.0 * n_fractal(p, octaves, true), false);
    } else {
        let r = sqrt(p.x * p.x + p.y * p.y) + 0.3 * n_fractal(p, octaves, false);
        let q = 4.0 * r;
        v = abs(q - trunc(q));
    }
    return clamp(v, 0.0, 1.0);
}
