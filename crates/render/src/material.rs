//! Materials: textured parameters that become a [`Bsdf`] at a surface point.
//! Roughness is the GGX α (not remapped).

use crate::bsdf::microfacet::TrowbridgeReitz;
use crate::bsdf::{Bsdf, Bxdf, CoatTable, ConductorBxdf, DielectricBxdf, DiffuseBxdf, PlasticBxdf};
use crate::texture::{TexCoord, Texture};
use glam::DVec3;

/// A surface's scattering, before evaluation at a point.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// Lambertian reflection.
    Diffuse {
        /// Reflectance in [0, 1]³.
        reflectance: Texture,
    },
    /// Metal with complex index η + i k (per channel) and GGX roughness α (0: mirror).
    Conductor {
        /// Real part of the index.
        eta: Texture,
        /// Absorption coefficient.
        k: Texture,
        /// GGX α.
        roughness: f64,
    },
    /// Glass with index η (inside over outside) and GGX roughness α (0: smooth).
    Dielectric {
        /// Relative index of refraction.
        eta: f64,
        /// GGX α.
        roughness: f64,
    },
    /// A diffuse base under a dielectric coat (see [`crate::bsdf::PlasticBxdf`]).
    Plastic {
        /// Base reflectance in [0, 1]³.
        diffuse: Texture,
        /// The coat (index and roughness, with its precomputed albedo).
        coat: CoatTable,
    },
    /// No surface: an index-matched boundary between media. Integrators pass through
    /// it; where it is shaded anyway (the AOVs' first hit) it is smooth glass of η = 1,
    /// which lets light through unchanged.
    Interface,
}

/// A material's roughness as a texture: the GGX α at each point is its first channel,
/// clamped to [0, 1]. Plastic's coat albedo is tabulated per α ([`CoatTable`]), so a
/// textured plastic keeps tables at α = k/32, k = 0…32, and uses the nearest: its α
/// is rounded to a multiple of 1/32.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughnessMap {
    /// α in the first channel.
    pub texture: Texture,
    /// Plastic: the coat tables at α = k/32 (empty for other materials).
    pub coats: Vec<CoatTable>,
}

/// Steps of α per unit of a textured plastic's coat tables.
pub const COAT_STEPS: usize = 32;

impl RoughnessMap {
    /// The map of `texture` for `material` (with the coat tables a plastic needs).
    pub fn new(texture: Texture, material: &Material) -> Self {
        let coats = match material {
            Material::Plastic { coat, .. } => (0..=COAT_STEPS)
                .map(|k| CoatTable::new(coat.eta, k as f64 / COAT_STEPS as f64))
                .collect(),
            _ => Vec::new(),
        };
        Self { texture, coats }
    }
}

impl Material {
    /// Plastic with base `diffuse`, coat index η and coat roughness α.
    pub fn plastic(diffuse: Texture, eta: f64, roughness: f64) -> Self {
        Material::Plastic {
            diffuse,
            coat: CoatTable::new(eta, roughness),
        }
    }
    /// [`Self::bsdf`] with the roughness read from `map` at `tc` (materials without a
    /// roughness ignore it).
    pub fn bsdf_rough<'a>(&'a self, tc: &TexCoord, n: DVec3, map: &'a RoughnessMap) -> Bsdf<'a> {
        let alpha = map.texture.eval(tc).x.clamp(0.0, 1.0);
        let mut b = self.bsdf(tc, n);
        match &mut b.bxdf {
            Bxdf::Conductor(c) => c.distrib = TrowbridgeReitz::isotropic(alpha),
            Bxdf::Dielectric(d) => d.distrib = TrowbridgeReitz::isotropic(alpha),
            Bxdf::Plastic(p) => {
                let k = (alpha * COAT_STEPS as f64).round() as usize;
                if let Some(coat) = map.coats.get(k) {
                    *p = PlasticBxdf::new(p.rho, coat);
                }
            }
            Bxdf::Diffuse(_) | Bxdf::Phase(_) => {}
        }
        b
    }
    /// The BSDF at `tc` with unit shading normal `n`.
    pub fn bsdf(&self, tc: &TexCoord, n: DVec3) -> Bsdf<'_> {
        let bxdf = match self {
            Material::Diffuse { reflectance } => Bxdf::Diffuse(DiffuseBxdf {
                r: reflectance.eval(tc),
            }),
            Material::Conductor { eta, k, roughness } => Bxdf::Conductor(ConductorBxdf {
                distrib: TrowbridgeReitz::isotropic(*roughness),
                eta: eta.eval(tc),
                k: k.eval(tc),
            }),
            Material::Dielectric { eta, roughness } => Bxdf::Dielectric(DielectricBxdf {
                distrib: TrowbridgeReitz::isotropic(*roughness),
                eta: *eta,
            }),
            Material::Plastic { diffuse, coat } => {
                Bxdf::Plastic(PlasticBxdf::new(diffuse.eval(tc), coat))
            }
            Material::Interface => Bxdf::Dielectric(DielectricBxdf {
                distrib: TrowbridgeReitz::isotropic(0.0),
                eta: 1.0,
            }),
        };
        Bsdf::new(n, bxdf)
    }
}
