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

impl Material {
    /// Plastic with base `diffuse`, coat index η and coat roughness α.
    pub fn plastic(diffuse: Texture, eta: f64, roughness: f64) -> Self {
        Material::Plastic {
            diffuse,
            coat: CoatTable::new(eta, roughness),
        }
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
