//! The resolved scene: plain data, handles not owners (DESIGN.md §3, GPU.md §5).
//!
//! Everything a renderer reads is here once, validated, with every reference an index
//! into a pool: objects name a solid and a material, materials name textures, the
//! environment names a map. Distributions (light selection, the environment map's
//! marginal and conditional CDFs) are computed here, once, so that every back end
//! samples from the same numbers. Vectors are `[f64; 3]` (x, y, z or r, g, b).

use crate::distribution::{Distribution1D, Distribution2D};
use crate::images::ImagePool;
use crate::meshes::MeshPool;
use crate::solids::SolidPool;
use glam::{DMat3, DVec3};
use serde::Serialize;

macro_rules! id {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
        #[serde(transparent)]
        pub struct $name(pub u32);

        impl $name {
            /// The index into its pool.
            pub fn index(self) -> usize {
                self.0 as usize
            }
        }
    };
}

id!(
    /// A texture: an index into [`SceneData::textures`].
    TextureId
);
id!(
    /// A material: an index into [`SceneData::materials`].
    MaterialId
);
id!(
    /// A solid: an index into [`SceneData::solids`].
    SolidId
);
id!(
    /// A triangle mesh: an index into [`SceneData::meshes`].
    MeshId
);
id!(
    /// An image texture's image: an index into [`SceneData::images`].
    ImageId
);
id!(
    /// An environment map: an index into [`SceneData::maps`].
    MapId
);
id!(
    /// A participating medium: an index into [`SceneData::media`].
    MediumId
);

/// A whole resolved scene (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneData {
    /// The camera.
    pub camera: CameraData,
    /// Texture pool.
    pub textures: Vec<TextureData>,
    /// The images of image textures (left out of the JSON when there are none).
    #[serde(skip_serializing_if = "ImagePool::is_empty")]
    pub images: ImagePool,
    /// Material pool, in the order of their names.
    pub materials: Vec<MaterialData>,
    /// The name of each material, for messages.
    pub material_names: Vec<String>,
    /// Per material, a texture whose first channel is the GGX α at each point, where any
    /// material's roughness is textured (else empty, and left out of the JSON); the
    /// material's own `roughness` is then unused.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub roughness: Vec<Option<TextureId>>,
    /// Emitted radiance per material, where any material emits (else empty, and left
    /// out of the JSON).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub emission: Vec<[f64; 3]>,
    /// Solid pool (one per solid object).
    pub solids: SolidPool,
    /// Triangle-mesh pool (one per mesh object; left out of the JSON when empty).
    #[serde(skip_serializing_if = "MeshPool::is_empty")]
    pub meshes: MeshPool,
    /// The objects: a solid with a material.
    pub objects: Vec<ObjectData>,
    /// Participating media, in the order of their names (left out of the JSON when
    /// there are none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub media: Vec<MediumData>,
    /// The name of each medium, for messages.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub medium_names: Vec<String>,
    /// The medium the camera sits in (None: vacuum; left out of the JSON then).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub camera_medium: Option<MediumId>,
    /// Area, point and spot lights, with their selection distributions.
    pub lights: LightData,
    /// Light from infinitely far away.
    pub environment: Option<EnvironmentData>,
    /// Environment-map pool.
    pub maps: Vec<EnvMapTable>,
    /// Radius of a ball holding the objects and lights; it sets the environment's power
    /// for light selection (π r² ∫ L dω, pbrt-v4 §12.5).
    pub scene_radius: f64,
    /// The files the scene reads besides itself (models, environment maps), as found:
    /// outputs must not replace them. Not part of the scene's content (nor its hash).
    #[serde(skip)]
    pub inputs: Vec<std::path::PathBuf>,
}

/// A camera's projection.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CameraKind {
    /// A pinhole at `eye` with a vertical field of view `fov`.
    #[default]
    Perspective,
    /// Parallel rays along the view direction over a rectangle `scale` tall.
    Orthographic,
}

impl CameraKind {
    /// Whether this is the default (perspective), which the resolved scene leaves out
    /// (so that the hashes of perspective scenes are those they always had).
    pub fn is_perspective(&self) -> bool {
        *self == CameraKind::Perspective
    }
}

/// A perspective or orthographic camera with a box filter.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CameraData {
    /// The projection (left out of the JSON when perspective).
    #[serde(rename = "type", skip_serializing_if = "CameraKind::is_perspective")]
    pub kind: CameraKind,
    /// Orthographic: the image's full height in scene units (left out when
    /// perspective).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// Position of the pinhole (orthographic: the centre of the image rectangle).
    pub eye: [f64; 3],
    /// A point the camera looks at (not the eye).
    pub target: [f64; 3],
    /// The image's up direction (not parallel to the view direction).
    pub up: [f64; 3],
    /// Full vertical field of view in degrees, in (0, 180).
    pub fov: f64,
    /// Image width in pixels (≥ 1).
    pub width: u32,
    /// Image height in pixels (≥ 1).
    pub height: u32,
    /// A thin lens (left out of the JSON for a pinhole, so that scenes without one keep
    /// their hash).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lens: Option<Lens>,
}

/// A thin lens (pbrt-v4 §5.2.3): rays leave a disk of this radius around the eye and
/// meet, for each point of the image, on the plane in focus.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Lens {
    /// The lens's radius (> 0).
    pub radius: f64,
    /// The distance along the view direction of the plane in focus (> 0).
    pub focus_distance: f64,
}

/// The domain of a checker texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TextureSpace {
    /// 3-D cells over the hit point.
    Point,
    /// 2-D cells over the surface parameters (u, v).
    Uv,
}

/// A colour that may vary over a surface.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "kebab-case")]
pub enum TextureData {
    /// The same colour everywhere.
    Constant {
        /// The colour.
        rgb: [f64; 3],
    },
    /// Colour `a` where the sum of the cell indices is even, `b` where it is odd.
    Checker {
        /// Even cells.
        a: [f64; 3],
        /// Odd cells.
        b: [f64; 3],
        /// Checks per unit length (> 0).
        scale: f64,
        /// Point or uv cells.
        space: TextureSpace,
    },
    /// An image projected onto the surface from the three axes, blended by the normal
    /// (triplanar mapping; `render::texture`).
    Image {
        /// The image.
        image: ImageId,
        /// Image repeats per unit length.
        scale: f64,
        /// The blend's sharpness k: weights ∝ |n_axis|^k.
        sharpness: f64,
    },
    /// Colours `a` and `b` blended by a solid pattern of the hit point (in the object's
    /// own space).
    Pattern {
        /// The pattern.
        kind: PatternKind,
        /// Colour where the pattern is 0.
        a: [f64; 3],
        /// Colour where it is 1.
        b: [f64; 3],
        /// Pattern cells per unit length (> 0).
        scale: f64,
        /// Octaves of the fractal patterns.
        octaves: u32,
    },
}

/// A solid pattern (noise and what is built on it: `render::noise`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PatternKind {
    /// Perlin's gradient noise.
    Noise,
    /// Fractal Brownian motion.
    Fbm,
    /// Turbulence (a sum of |noise|).
    Turbulence,
    /// Marble veins.
    Marble,
    /// Wood rings.
    Wood,
}

impl PatternKind {
    /// Every pattern.
    pub const ALL: [PatternKind; 5] = [
        PatternKind::Noise,
        PatternKind::Fbm,
        PatternKind::Turbulence,
        PatternKind::Marble,
        PatternKind::Wood,
    ];
    /// Its name in scene files.
    pub const fn name(self) -> &'static str {
        match self {
            PatternKind::Noise => "noise",
            PatternKind::Fbm => "fbm",
            PatternKind::Turbulence => "turbulence",
            PatternKind::Marble => "marble",
            PatternKind::Wood => "wood",
        }
    }
}

/// Perlin's permutation of 0..256 (Perlin 2002): the hash of the noise patterns
/// ([`PatternKind`]), one table for every back end.
pub const PERLIN_PERM: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69,
    142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219,
    203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175,
    74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122, 60, 211, 133, 230,
    220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76,
    132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173,
    186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
    59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163,
    70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232,
    178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162,
    241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204,
    176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141,
    128, 195, 78, 66, 215, 61, 156, 180,
];

/// A material: plain parameters and texture ids. Roughness is the GGX α.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "kebab-case")]
pub enum MaterialData {
    /// Lambertian reflection.
    Diffuse {
        /// Reflectance in [0, 1]³.
        reflectance: TextureId,
    },
    /// Metal with complex index η + i k per channel.
    Conductor {
        /// Real part of the index.
        eta: TextureId,
        /// Absorption.
        k: TextureId,
        /// GGX α in [0, 1].
        roughness: f64,
    },
    /// Glass.
    Dielectric {
        /// Index of refraction (inside over outside).
        eta: f64,
        /// GGX α in [0, 1].
        roughness: f64,
    },
    /// A diffuse base under a dielectric coat.
    Plastic {
        /// Base reflectance in [0, 1]³.
        diffuse: TextureId,
        /// Coat index of refraction.
        eta: f64,
        /// Coat GGX α in [0, 1].
        roughness: f64,
    },
    /// No surface: an index-matched boundary between media, which light crosses
    /// unchanged (pbrt-v4's `interface`, Mitsuba 3's `null`).
    Interface,
}

/// A participating medium of constant extinction (coefficients per unit length, per RGB
/// channel): σ_t everywhere, σ_s = albedo · σ_t with the albedo a texture of the point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MediumData {
    /// Extinction coefficient σ_t = σ_a + σ_s ≥ 0.
    pub sigma_t: [f64; 3],
    /// Single-scattering albedo σ_s/σ_t in [0, 1]: a constant, a point-space checker
    /// or a pattern, read in world space.
    pub albedo: TextureId,
    /// Henyey–Greenstein asymmetry g in [−0.99, 0.99].
    pub g: f64,
}

/// One object: a solid or a mesh of the pools with a material.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectData {
    /// Name, for messages (default `objects[i]`).
    pub name: String,
    /// Its geometry (transforms folded in): `"solid": id` or `"mesh": id` in JSON.
    #[serde(flatten)]
    pub geometry: Geometry,
    /// Its material.
    pub material: MaterialId,
    /// The object's transform, where it has one: pattern and image textures are read in
    /// the object's own space (the transform undone), so that they move with it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub placement: Option<Placement>,
    /// The medium inside (None: vacuum).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interior: Option<MediumId>,
    /// The medium around it (None: vacuum).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exterior: Option<MediumId>,
}

/// An object's transform x ↦ M·x + t (M row-major).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Placement {
    /// The linear part, row by row.
    pub m: [f64; 9],
    /// The translation.
    pub t: [f64; 3],
}

impl Placement {
    /// The frame that undoes this transform (None where M is singular): where an
    /// object's textures are read, on every back end.
    pub fn local_frame(&self) -> Option<LocalFrame> {
        let m = DMat3::from_cols_array(&self.m).transpose();
        LocalFrame::undoing(m, DVec3::from_array(self.t))
    }
}

/// The inverse of an object's transform: points by `m·x + t`, normals by `normals·n`
/// (the inverse transpose of `m`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalFrame {
    /// Linear part.
    pub m: DMat3,
    /// Translation.
    pub t: DVec3,
    /// The normals' matrix.
    pub normals: DMat3,
}

impl LocalFrame {
    /// The frame undoing x ↦ `forward`·x + `t` (None where it is singular).
    pub fn undoing(forward: DMat3, t: DVec3) -> Option<LocalFrame> {
        let det = forward.determinant();
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let m = forward.inverse();
        Some(LocalFrame {
            m,
            t: -(m * t),
            normals: forward.transpose(),
        })
    }
    /// A world point and unit normal in the object's space.
    pub fn apply(&self, p: DVec3, n: DVec3) -> (DVec3, DVec3) {
        (self.m * p + self.t, (self.normals * n).normalize_or_zero())
    }
}

/// What an object is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Geometry {
    /// A solid of [`SceneData::solids`].
    Solid(SolidId),
    /// A triangle mesh of [`SceneData::meshes`].
    Mesh(MeshId),
}

impl Geometry {
    /// The solid, where the object is one.
    pub fn solid(self) -> Option<SolidId> {
        match self {
            Geometry::Solid(s) => Some(s),
            Geometry::Mesh(_) => None,
        }
    }
}

impl SceneData {
    /// The bounds of object `i`'s geometry (possibly infinite for an unbounded solid).
    pub fn object_bounds(&self, i: usize) -> frep::Aabb {
        match self.objects[i].geometry {
            Geometry::Solid(s) => self.solids.bounds(s),
            Geometry::Mesh(m) => self.meshes.mesh(m).bounds(),
        }
    }
}

/// What a light is; says which fields of [`Light`] apply.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LightKind {
    /// A sphere emitting outward.
    Sphere,
    /// The parallelogram `p0 + a·e1 + b·e2`, a, b ∈ [0, 1], emitting along e1 × e2.
    Rect,
    /// A disk of centre `p0`, unit normal `e1` (the emitting side) and `radius`.
    Disk,
    /// The triangle `p0`, `p0 + e1`, `p0 + e2`, emitting along e1 × e2 (one of a mesh
    /// light's triangles).
    Triangle,
    /// An isotropic point light at `p0`.
    Point,
    /// A spot light at `p0` with unit axis `e1`.
    Spot,
    /// The bounding sphere (centre `p0`, `radius`) of an emitting object: light
    /// techniques sample directions toward it; the object's surface emits.
    Solid,
}

impl LightKind {
    /// Whether the light has an area (and so takes part in MIS).
    pub fn has_area(self) -> bool {
        matches!(
            self,
            LightKind::Sphere
                | LightKind::Rect
                | LightKind::Disk
                | LightKind::Triangle
                | LightKind::Solid
        )
    }
}

/// One light: a tag and its parameters; fields that a kind does not use are zero.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Light {
    /// What the light is.
    pub kind: LightKind,
    /// Centre (sphere, disk), corner (rect) or position (point, spot).
    pub p0: [f64; 3],
    /// First edge (rect), unit normal (disk) or unit axis (spot).
    pub e1: [f64; 3],
    /// Second edge (rect).
    pub e2: [f64; 3],
    /// Radius (sphere, disk).
    pub radius: f64,
    /// Radiance (area lights) or radiant intensity in W/sr (point, spot).
    pub emission: [f64; 3],
    /// Whether a rect or disk emits on both sides.
    pub two_sided: bool,
    /// Spot: cos of the angle where the falloff starts.
    pub cos_falloff_start: f64,
    /// Spot: cos of the cone's half-angle.
    pub cos_falloff_end: f64,
    /// Surface area (area lights).
    pub area: f64,
    /// Emitted power Φ per channel (π A L, twice for two-sided; 4π I for a point light;
    /// pbrt-v4 §12.1.2 for a spot light).
    pub power: [f64; 3],
    /// Probability of this light in light selection ∝ power (0 for point and spot
    /// lights, which are sampled outside MIS).
    pub selection_pmf: f64,
}

/// The lights and the distributions used to choose among them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LightData {
    /// Area lights (sphere, rect, disk), in file order.
    pub area: Vec<Light>,
    /// Point and spot lights, in file order.
    pub delta: Vec<Light>,
    /// Light selection ∝ luminance of power over the area lights then, last, the
    /// environment (None when there is neither).
    pub by_power: Option<Distribution1D>,
    /// Area lights ∝ area (None without area lights).
    pub by_area: Option<Distribution1D>,
}

/// Light from infinitely far away.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "kebab-case")]
pub enum EnvironmentData {
    /// Uniform radiance from every direction.
    Constant {
        /// The radiance.
        radiance: [f64; 3],
    },
    /// A lat-long map of the pool.
    Map {
        /// The map.
        map: MapId,
        /// Rotation from the map's frame to the scene, as columns.
        to_world: [[f64; 3]; 3],
    },
}

/// A lat-long radiance map (row 0 at the map's +z; column u = φ/2π) with its sampling
/// distribution ∝ average(L) · sin θ, computed once.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EnvMapTable {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Row-major radiance, already multiplied by the scene's `scale`.
    pub pixels: Vec<[f64; 3]>,
    /// Marginal over rows and conditional over columns of each row.
    pub distribution: Distribution2D,
    /// ∫ L dω over the sphere (exact for the piecewise-constant map).
    pub integral: [f64; 3],
}
