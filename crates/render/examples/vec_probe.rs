use glam::{DVec2, DVec3};
use render::frame::Frame;
use render::warp::{cosine_hemisphere, sin_cos_turns};
use std::hint::black_box;
use std::time::Instant;

const B: usize = 256;

#[inline(never)]
fn soa_cos(ux: &[f64; B], uy: &[f64; B], x: &mut [f64; B], y: &mut [f64; B], z: &mut [f64; B]) {
    for i in 0..B {
        let d = cosine_hemisphere(DVec2::new(ux[i], uy[i]));
        x[i] = d.x;
        y[i] = d.y;
        z[i] = d.z;
    }
}

#[inline(never)]
fn soa_frame(
    nx: &[f64; B],
    ny: &[f64; B],
    nz: &[f64; B],
    x: &mut [f64; B],
    y: &mut [f64; B],
    z: &mut [f64; B],
) {
    for i in 0..B {
        let f = Frame::from_z(DVec3::new(nx[i], ny[i], nz[i]));
        let w = f.from_local(DVec3::new(x[i], y[i], z[i]));
        x[i] = w.x;
        y[i] = w.y;
        z[i] = w.z;
    }
}

#[inline(never)]
fn soa_turns(u: &[f64; B], s: &mut [f64; B], c: &mut [f64; B]) {
    for i in 0..B {
        let (a, b) = sin_cos_turns(u[i]);
        s[i] = a;
        c[i] = b;
    }
}

fn main() {
    let mut ux = [0.0; B];
    let mut uy = [0.0; B];
    for i in 0..B {
        ux[i] = (i as f64 * 0.618).fract();
        uy[i] = (i as f64 * 0.377).fract();
    }
    let (mut x, mut y, mut z) = ([0.0; B], [0.0; B], [0.0; B]);
    let reps = 20000;
    let t = Instant::now();
    for _ in 0..reps {
        soa_cos(black_box(&ux), black_box(&uy), &mut x, &mut y, &mut z);
        black_box(&x);
    }
    let soa = t.elapsed().as_secs_f64();
    let t = Instant::now();
    for _ in 0..reps {
        for i in 0..B {
            let d = black_box(cosine_hemisphere(black_box(DVec2::new(ux[i], uy[i]))));
            x[i] = d.x;
        }
    }
    let sc = t.elapsed().as_secs_f64();
    println!(
        "cosine_hemisphere ns/elem soa {:.2} scalar {:.2}",
        soa / (reps * B) as f64 * 1e9,
        sc / (reps * B) as f64 * 1e9
    );
    let t = Instant::now();
    for _ in 0..reps {
        soa_frame(
            black_box(&ux),
            black_box(&uy),
            black_box(&ux),
            &mut x,
            &mut y,
            &mut z,
        );
        black_box(&x);
    }
    println!(
        "frame ns/elem {:.2}",
        t.elapsed().as_secs_f64() / (reps * B) as f64 * 1e9
    );
    let (mut s, mut c) = ([0.0; B], [0.0; B]);
    let t = Instant::now();
    for _ in 0..reps {
        soa_turns(black_box(&ux), &mut s, &mut c);
        black_box(&s);
    }
    println!(
        "turns ns/elem {:.2}",
        t.elapsed().as_secs_f64() / (reps * B) as f64 * 1e9
    );
}
