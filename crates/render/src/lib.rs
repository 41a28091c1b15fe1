//! Light transport on the CPU for frepray: sampler, camera, textures, materials and
//! BSDFs, lights, sampling techniques, the per-pixel render state and the image.
//!
//! Every sampling routine reports its density in solid angle for any direction, so
//! that an integrator can draw samples from several [`technique::Technique`]s and
//! evaluate every technique's pdf for every sample, as multiple importance sampling
//! with optimal weights needs (Kondapaneni et al. 2019).
//!
//! ```
//! use render::{bsdf::{Bsdf, Bxdf, DiffuseBxdf}, color::Rgb, light::*, technique::*};
//! use glam::{DVec2, DVec3};
//!
//! // A white diffuse point under a sphere light of radiance 1 subtending 30°.
//! let lights = Lights::new(
//!     vec![AreaLight::new(Shape::Sphere { center: DVec3::new(0.0, 0.0, 2.0), radius: 1.0 }, Rgb::ONE)],
//!     vec![], None, 3.0);
//! let bsdf = Bsdf::new(DVec3::Z, Bxdf::Diffuse(DiffuseBxdf { r: Rgb::ONE }));
//! let ctx = ShadingPoint { p: DVec3::ZERO, n: DVec3::Z, wo: DVec3::Z, bsdf: &bsdf, lights: &lights, trained: None };
//! let s = Technique::LightPower.sample(&ctx, 0.5, DVec2::new(0.3, 0.7)).unwrap();
//! // The sample's pdf is the technique's pdf for its direction: uniform over the cone.
//! let cone = 1.0 / (2.0 * std::f64::consts::PI * (1.0 - 0.75f64.sqrt()));
//! assert!((s.pdf - cone).abs() < 1e-12);
//! assert_eq!(Technique::LightPower.pdf(&ctx, s.wi), s.pdf);
//! assert_eq!(Technique::LightPower.pdf(&ctx, -DVec3::Z), 0.0);
//! ```
#![warn(missing_docs)]

pub mod bsdf;
// What both back ends share, at the paths this crate has always given them.
pub use state::{color, error, image, limits, output, png_io, sampler, value_png};
pub mod camera;
pub mod distribution;
pub mod frame;
pub mod integrator;
pub mod light;
pub mod material;
pub mod medium;
pub mod noise;
pub mod render_loop;
#[cfg(test)]
mod sampler_tests;
pub mod scene;
pub mod technique;
#[cfg(test)]
mod testutil;
pub mod texture;
pub mod warp;

pub use camera::{Camera, Projection};
pub use color::Rgb;
pub use error::Error;
pub use image::{Film, Image, Tonemap};
pub use material::Material;
pub use render_loop::{render, render_range, resume};
pub use sampler::{SampleStream, Sampler};
pub use state::{fnv1a, BlockDetail, PixelDetail, RenderState, RenderStats, StateHeader};
pub use technique::{Sampling, ShadingPoint, Technique, TechniqueSample};
pub use texture::{TexCoord, Texture};
