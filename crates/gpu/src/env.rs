//! The environment light on the GPU: a constant dome, or a lat-long map importance-sampled
//! by its piecewise-constant distribution (`render::light::environment`, pbrt-v4 §12.5;
//! `render::distribution`, pbrt-v4 §A.5). [`GpuEnv`] and its tables, the WGSL functions
//! ([`ENV_WGSL`]), and the CPU f32 twin written operation for operation as the kernel,
//! which it equals bit for bit on lavapipe (GPU.md §3.5).
//!
//! Differences from the f64 code, each needed for f32 or for an exact twin:
//! - atan2 is a polynomial ([`atan2`]: one reduction to [0, tan π/8], Taylor to x¹⁵,
//!   truncation below 2e-8) and sin, cos are `light::sincos_2pi`'s, written identically
//!   in WGSL and Rust: WGSL's and libm's transcendentals differ;
//! - the distributions' tables hold f32 CDFs and densities (func / integral) rounded from
//!   the resolved scene's f64 ones ([`table`]).

use crate::f4;
use crate::light::{cdf_find, sincos_2pi};
use bytemuck::{Pod, Zeroable};
use scene::{Distribution1D, EnvMapTable, EnvironmentData, SceneData};
use std::cmp::Ordering;

/// The WGSL of the environment functions, mirroring this module (with the `GpuEnv`
/// struct); needs `light::LIGHT_WGSL` and a storage array `sel_buf: array<f32>` holding
/// the tables and pixels.
pub const ENV_WGSL: &str = include_str!("shaders/env.wgsl");

/// [`GpuEnv::kind`] without an environment.
pub const NONE: u32 = 0;
/// [`GpuEnv::kind`] of a constant dome.
pub const CONSTANT: u32 = 1;
/// [`GpuEnv::kind`] of a lat-long map.
pub const MAP: u32 = 2;

/// The environment, 96 B: its kind, a map's size and where its pixels and tables start
/// in the f32 table buffer, the dome's radiance, and the map's rotation to the scene.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuEnv {
    /// [`NONE`], [`CONSTANT`] or [`MAP`].
    pub kind: u32,
    /// Map columns.
    pub width: u32,
    /// Map rows.
    pub height: u32,
    /// Offset of the map's row-major RGB pixels.
    pub pixels: u32,
    /// Offset of the marginal [`table`] over rows.
    pub marginal: u32,
    /// Offset of row 0's conditional [`table`] over columns.
    pub rows: u32,
    /// Words of one row's table (2·width + 2).
    pub row_words: u32,
    /// Padding.
    pub pad: u32,
    /// The dome's radiance.
    pub radiance: [f32; 4],
    /// The map's rotation to the scene: its columns (the map's x, y and z axes).
    pub x: [f32; 4],
    /// Second column.
    pub y: [f32; 4],
    /// Third column.
    pub z: [f32; 4],
}

impl GpuEnv {
    /// The scene's environment, its map's pixels and tables appended to `tables` (the
    /// f32 buffer the kernels read as `sel_buf`).
    pub fn pack(data: &SceneData, tables: &mut Vec<f32>) -> Self {
        match &data.environment {
            None => Self::default(),
            Some(EnvironmentData::Constant { radiance }) => Self::constant(*radiance),
            Some(EnvironmentData::Map { map, to_world }) => {
                Self::map(&data.maps[map.index()], to_world, tables)
            }
        }
    }

    /// A constant dome.
    pub fn constant(radiance: [f64; 3]) -> Self {
        Self {
            kind: CONSTANT,
            radiance: f4(radiance, 0.0),
            ..Self::default()
        }
    }

    /// A map turned by `to_world` (columns), its pixels and tables appended to `tables`.
    pub fn map(m: &EnvMapTable, to_world: &[[f64; 3]; 3], tables: &mut Vec<f32>) -> Self {
        let mut e = Self {
            kind: MAP,
            width: m.width as u32,
            height: m.height as u32,
            x: f4(to_world[0], 0.0),
            y: f4(to_world[1], 0.0),
            z: f4(to_world[2], 0.0),
            ..Self::default()
        };
        e.pixels = tables.len() as u32;
        tables.extend(m.pixels.iter().flat_map(|p| p.map(|c| c as f32)));
        e.marginal = tables.len() as u32;
        tables.extend(table(&m.distribution.marginal));
        e.rows = tables.len() as u32;
        e.row_words = 2 * e.width + 2;
        for row in &m.distribution.conditional {
            tables.extend(table(row));
        }
        e
    }
}

/// A continuous 1-D distribution in the f32 buffer: n, then the CDF (n + 1 values from 0
/// to 1), then the density func / integral (n values), from `scene::Distribution1D`
/// rounded to f32.
pub fn table(d: &Distribution1D) -> Vec<f32> {
    let n = d.func.len();
    let mut t = vec![f32::from_bits(n as u32)];
    t.extend(d.cdf.iter().map(|&c| c as f32));
    t.extend(d.func.iter().map(|&f| (f / d.integral) as f32));
    t
}

const PI: f32 = std::f32::consts::PI;
const HALF_PI: f32 = std::f32::consts::FRAC_PI_2;
const QUARTER_PI: f32 = std::f32::consts::FRAC_PI_4;
const TWO_PI: f32 = std::f32::consts::TAU;
/// 2π².
const TWO_PI2: f32 = f32::from_bits(0x419d_e9e6);
/// 1/(4π).
const INV_4PI: f32 = f32::from_bits(0x3da2_f983);
/// tan(π/8).
const TAN_PI8: f32 = f32::from_bits(0x3ed4_13cd);
/// 1 − 2⁻²⁴, the largest f32 below 1.
const BELOW_ONE: f32 = f32::from_bits(0x3f7f_ffff);

/// atan a for a ∈ [0, 1] (the kernel's `env_atan01`).
pub fn atan01(a: f32) -> f32 {
    let (mut x, mut base) = (a, 0.0);
    if a > TAN_PI8 {
        x = (a - 1.0) / (a + 1.0);
        base = QUARTER_PI;
    }
    let c = |bits: u32| f32::from_bits(bits);
    let x2 = x * x;
    let p = 1.0
        + x2 * (-c(0x3eaa_aaab)
            + x2 * (c(0x3e4c_cccd)
                + x2 * (-c(0x3e12_4925)
                    + x2 * (c(0x3de3_8e39)
                        + x2 * (-c(0x3dba_2e8c) + x2 * (c(0x3d9d_89d9) - x2 * c(0x3d88_8889)))))));
    base + x * p
}

/// atan2(y, x) in [−π, π], 0 at the origin (the kernel's `env_atan2`).
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let hi = ax.max(ay);
    if hi == 0.0 {
        return 0.0;
    }
    let mut r = atan01(ax.min(ay) / hi);
    if ay > ax {
        r = HALF_PI - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 {
        r = -r;
    }
    r
}

/// A direction's map coordinates (u = φ/2π, v = θ/π) and sin θ (`env_uv`).
pub fn uv(e: &GpuEnv, d: [f32; 3]) -> (f32, f32, f32) {
    let mx = e.x[0] * d[0] + e.x[1] * d[1] + e.x[2] * d[2];
    let my = e.y[0] * d[0] + e.y[1] * d[1] + e.y[2] * d[2];
    let mz = e.z[0] * d[0] + e.z[1] * d[1] + e.z[2] * d[2];
    let l = (mx * mx + my * my + mz * mz).sqrt();
    let (qx, qy, qz) = (mx / l, my / l, mz / l);
    let mut phi = atan2(qy, qx);
    if phi < 0.0 {
        phi += TWO_PI;
    }
    let sin_t = (qx * qx + qy * qy).sqrt();
    let theta = atan2(sin_t, qz);
    (phi / TWO_PI, theta / PI, sin_t)
}

/// Radiance arriving from direction d (`env_radiance`); `buf` is the table buffer.
pub fn radiance(e: &GpuEnv, buf: &[f32], d: [f32; 3]) -> [f32; 3] {
    match e.kind {
        CONSTANT => [e.radiance[0], e.radiance[1], e.radiance[2]],
        MAP => {
            let (u, v, _) = uv(e, d);
            let x = ((u * e.width as f32) as u32).min(e.width - 1);
            let y = ((v * e.height as f32) as u32).min(e.height - 1);
            let at = (e.pixels + 3 * (y * e.width + x)) as usize;
            [buf[at], buf[at + 1], buf[at + 2]]
        }
        _ => [0.0; 3],
    }
}

/// The continuous sample of the table at `off` for u: (x, density, i) (`env_continuous`).
pub fn continuous(buf: &[f32], off: u32, u: f32) -> (f32, f32, u32) {
    let n = buf[off as usize].to_bits();
    let cdf = off as usize + 1;
    let i = cdf_find(buf, cdf, n, u);
    let iu = i as usize;
    let mut du = u - buf[cdf + iu];
    let width = buf[cdf + iu + 1] - buf[cdf + iu];
    if width > 0.0 {
        du /= width;
    }
    let x = ((i as f32 + du) / n as f32).min(BELOW_ONE);
    (x, buf[cdf + n as usize + 1 + iu], i)
}

/// The density of the table at `off` at x, 0 outside [0, 1) (`env_density`).
pub fn density(buf: &[f32], off: u32, x: f32) -> f32 {
    if !(0.0..1.0).contains(&x) {
        return 0.0;
    }
    let n = buf[off as usize].to_bits();
    let i = ((x * n as f32) as u32).min(n - 1);
    buf[(off + n + 2 + i) as usize]
}

/// A direction and its solid-angle pdf, or None (`env_sample`).
pub fn sample(e: &GpuEnv, buf: &[f32], u: [f32; 2]) -> Option<([f32; 3], f32)> {
    match e.kind {
        CONSTANT => {
            let z = 1.0 - 2.0 * u[0];
            let r = (1.0 - z * z).max(0.0).sqrt();
            let (s, c) = sincos_2pi(u[1]);
            Some(([r * c, r * s, z], INV_4PI))
        }
        MAP => {
            let (v, pdf_v, row) = continuous(buf, e.marginal, u[1]);
            let (x, pdf_u, _) = continuous(buf, e.rows + row * e.row_words, u[0]);
            let pdf_uv = pdf_u * pdf_v;
            let (sin_t, cos_t) = sincos_2pi(0.5 * v);
            // NaN fails too, as in the kernel.
            if sin_t.partial_cmp(&0.0) != Some(Ordering::Greater)
                || pdf_uv.partial_cmp(&0.0) != Some(Ordering::Greater)
            {
                return None;
            }
            let (sp, cp) = sincos_2pi(x);
            let (mx, my, mz) = (sin_t * cp, sin_t * sp, cos_t);
            let wi = [
                e.x[0] * mx + e.y[0] * my + e.z[0] * mz,
                e.x[1] * mx + e.y[1] * my + e.z[1] * mz,
                e.x[2] * mx + e.y[2] * my + e.z[2] * mz,
            ];
            Some((wi, pdf_uv / (TWO_PI2 * sin_t)))
        }
        _ => None,
    }
}

/// The solid-angle density of [`sample`] at the unit direction wi (`env_pdf`).
pub fn pdf(e: &GpuEnv, buf: &[f32], wi: [f32; 3]) -> f32 {
    match e.kind {
        CONSTANT => INV_4PI,
        MAP => {
            let (u, v, sin_t) = uv(e, wi);
            if sin_t.partial_cmp(&0.0) != Some(Ordering::Greater) {
                return 0.0;
            }
            let pv = density(buf, e.marginal, v);
            if pv == 0.0 {
                return 0.0;
            }
            let row = ((v * e.height as f32) as u32).min(e.height - 1);
            let pu = density(buf, e.rows + row * e.row_words, u);
            pv * pu / (TWO_PI2 * sin_t)
        }
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The constants are the WGSL's bit patterns.
    #[test]
    fn wgsl_constants_are_the_rust_ones() {
        for (name, v) in [
            ("e_pi", PI),
            ("e_two_pi", TWO_PI),
            ("e_two_pi2", TWO_PI2),
            ("e_inv_4pi", INV_4PI),
            ("e_below_one", BELOW_ONE),
        ] {
            let line = format!(
                "fn {name}() -> f32 {{ return bitcast<f32>(0x{:08x}u); }}",
                v.to_bits()
            );
            assert!(ENV_WGSL.contains(&line), "{line}");
        }
        // atan's (crate::TRIG_WGSL).
        for v in [PI, HALF_PI, QUARTER_PI, TAN_PI8] {
            let c = format!("bitcast<f32>(0x{:08x}u)", v.to_bits());
            assert!(crate::TRIG_WGSL.contains(&c), "{c}");
        }
        assert_eq!(TWO_PI2, (2.0 * std::f64::consts::PI.powi(2)) as f32);
        assert_eq!(INV_4PI, (0.25 / std::f64::consts::PI) as f32);
        assert_eq!(TAN_PI8, std::f64::consts::FRAC_PI_8.tan() as f32);
        assert_eq!(BELOW_ONE, 1.0f32.next_down());
    }

    /// The polynomial atan2 against libm's f64 one over the whole circle, at radius 1
    /// and 10⁻³: within two f32 ulps of π (4.8e-7 rad; the result's rounding and π's
    /// are half an ulp each, the truncation below 2e-8).
    #[test]
    fn atan2_is_within_f32_rounding_of_libm() {
        let mut worst = 0f64;
        for k in 0..100_000 {
            let a = k as f64 / 100_000.0 * std::f64::consts::TAU - std::f64::consts::PI;
            let r = if k % 2 == 0 { 1.0 } else { 1e-3 };
            let (y, x) = ((r * a.sin()) as f32, (r * a.cos()) as f32);
            let want = f64::from(y).atan2(f64::from(x));
            worst = worst.max((f64::from(atan2(y, x)) - want).abs());
        }
        assert!(worst < 4.8e-7, "worst error {worst}");
        assert_eq!(atan2(0.0, 0.0), 0.0);
        assert_eq!(atan2(0.0, -1.0), PI);
        assert_eq!(atan2(1.0, 0.0), HALF_PI);
    }
}
