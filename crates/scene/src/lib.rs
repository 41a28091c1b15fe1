//! # scene — scene files resolved into one flat [`SceneData`]
//!
//! A scene is written in TOML or JSON (one schema, docs/scene-format.md) or given as
//! data (a [`serde_json::Value`], e.g. from a Python dict). It is read into a
//! [`SceneDescription`], patched by [`Overrides`] (command-line flags), then
//! [`resolve`]d once: validated, references followed, transforms folded into the
//! solids, distributions computed. The result is plain data — a [`SceneData`] whose
//! objects, materials, textures, solids and maps refer to each other by index — and
//! one [`RenderSettings`]. The CPU renderer builds from it, and the GPU will read the
//! same numbers (DESIGN.md §3).
//!
//! Every error is a [`SceneError`] naming the key path of the offending entry and,
//! when there is source text, its file, line and column.
//!
//! ```
//! use scene::{load_value, parse, IntegratorKind, SceneFormat};
//! use std::path::Path;
//! let text = r#"
//! camera = { eye = [0, -4, 0], target = [0, 0, 0], resolution = [64, 48] }
//! render = { integrator = "direct", estimator = "optimal-direct" }
//! materials.white = { type = "diffuse", reflectance = 0.8 }
//! objects = [{ solid = "sphere([0, 0, 0], 1)", material = "white" }]
//! lights = [{ type = "sphere", center = [0, 0, 3], radius = 0.5, power = 100 }]
//! "#;
//! let (data, settings) = parse(text, SceneFormat::Toml, Path::new("ball.toml")).unwrap();
//! assert_eq!(settings.integrator, IntegratorKind::Direct);
//! assert_eq!((data.objects.len(), data.lights.area.len()), (1, 1));
//! // One light takes all of light selection.
//! assert_eq!(data.lights.area[0].selection_pmf, 1.0);
//! // The same scene given as data resolves to the same SceneData.
//! let value: serde_json::Value = toml::from_str(text).unwrap();
//! assert_eq!(load_value(value.clone(), Path::new(".")).unwrap().0, data);
//! // An unknown material is reported where it is named: line and column in text,
//! // the key path in data.
//! let bad = text.replace(r#"material = "white""#, r#"material = "black""#);
//! let err = parse(&bad, SceneFormat::Toml, Path::new("ball.toml")).unwrap_err();
//! assert_eq!((err.line, err.column, err.key.as_str()), (5, 57, "objects[0].material"));
//! let mut v = value;
//! v["objects"][0]["material"] = "black".into();
//! let err = load_value(v, Path::new(".")).unwrap_err();
//! assert_eq!(err.to_string(), r#"objects[0].material: unknown material "black"; defined: white"#);
//! ```
#![warn(missing_docs)]

mod check;
mod data;
mod desc;
mod distribution;
mod environment;
mod error;
mod exr_file;
mod images;
mod lights;
mod load;
mod locate;
mod media;
mod meshes;
mod overrides;
mod resolve;
mod settings;
mod solids;
mod training;

pub use data::{
    CameraData, CameraKind, EnvMapTable, EnvironmentData, Geometry, ImageId, Lens, Light,
    LightData, LightKind, LocalFrame, MapId, MaterialData, MaterialId, MediumData, MediumId,
    MeshId, ObjectData, PatternKind, Placement, SceneData, SolidId, TextureData, TextureId,
    TextureSpace, PERLIN_PERM,
};
pub use desc::{
    CameraDesc, CheckerDesc, ColorDesc, EnvironmentDesc, FilmDesc, LightDesc, MaterialDesc,
    MediumDesc, ObjectDesc, PatternDesc, RenderDesc, RgbDesc, RotateDesc, ScaleDesc,
    SceneDescription, TechniqueDesc, TransformDesc, TransformStep,
};
pub use distribution::{Distribution1D, Distribution2D};
pub use environment::{read_exr_rgb, MapError};
pub use error::SceneError;
pub use exr_file::{read_exr, ExrChannels, ExrError, ATTRIBUTE_PREFIX};
pub use images::{read_image, ImagePool, ImageTexture, MAX_IMAGE_PIXELS};
pub use load::{
    description_from_value, load, load_value, load_with, parse, parse_description, parse_with,
    resolve, SceneFormat,
};
pub use meshes::MeshPool;
pub use overrides::{parse_technique_list, Overrides};
pub use resolve::METALS;
pub use settings::{
    Emitters, IntegratorKind, RenderSettings, TechniqueError, TechniqueKind, Tonemap, UnknownName,
    AOV_NAMES,
};
pub use solids::SolidPool;
pub use training::{Training, MAX_TRAINED_GRID};

/// The image size of a scene that gives no `camera.resolution`.
pub const DEFAULT_RESOLUTION: [u32; 2] = [320, 240];
