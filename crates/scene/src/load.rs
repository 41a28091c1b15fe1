//! Reading scenes: TOML or JSON text, or a JSON value → [`SceneDescription`] →
//! (overrides) → [`SceneData`] and [`RenderSettings`]; every failure a [`SceneError`]
//! with a key path and, where there is text, a position.

use crate::data::SceneData;
use crate::desc::SceneDescription;
use crate::error::{line_column, offset_of, path_string, KeyPath, SceneError, Seg};
use crate::locate::Source;
use crate::overrides::Overrides;
use crate::resolve::resolve_source;
use crate::settings::RenderSettings;
use std::path::Path;

/// The two spellings of a scene file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneFormat {
    /// TOML (`.toml`).
    Toml,
    /// JSON (`.json`).
    Json,
}

impl SceneFormat {
    /// The format named by a path's extension (`toml` or `json`, any case).
    pub fn from_path(path: &Path) -> Option<SceneFormat> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "toml" => Some(SceneFormat::Toml),
            "json" => Some(SceneFormat::Json),
            _ => None,
        }
    }
}

fn key_path(p: &serde_path_to_error::Path) -> KeyPath {
    use serde_path_to_error::Segment;
    p.iter()
        .filter_map(|s| match s {
            Segment::Seq { index } => Some(Seg::Index(*index)),
            Segment::Map { key } => Some(Seg::Key(key.clone())),
            Segment::Enum { variant } => Some(Seg::Key(variant.clone())),
            Segment::Unknown => None,
        })
        .collect()
}

fn error(file: &str, text: &str, offset: usize, key: &[Seg], message: &str) -> SceneError {
    let (line, column) = line_column(text, offset);
    SceneError {
        file: file.to_string(),
        line,
        column,
        key: path_string(key),
        message: message.to_string(),
    }
}

/// Parses the text of a scene file into its description (no files are read).
pub fn parse_description(
    text: &str,
    format: SceneFormat,
    file: &str,
) -> Result<SceneDescription, SceneError> {
    match format {
        SceneFormat::Toml => {
            let toml_error = |e: &toml::de::Error, key: &[Seg]| {
                let at = match e.span() {
                    Some(s) => s.start,
                    None => {
                        Source::new(text, format, file.into())
                            .locate(key)
                            .value
                            .start
                    }
                };
                error(file, text, at, key, e.message())
            };
            let de = toml::Deserializer::parse(text).map_err(|e| toml_error(&e, &[]))?;
            serde_path_to_error::deserialize(de)
                .map_err(|e| toml_error(e.inner(), &key_path(e.path())))
        }
        SceneFormat::Json => {
            let mut de = serde_json::Deserializer::from_str(text);
            let json_error = |e: &serde_json::Error, key: &[Seg]| {
                let shown = e.to_string();
                let message = shown
                    .rsplit_once(" at line ")
                    .map_or(shown.as_str(), |m| m.0);
                let here = offset_of(text, e.line(), e.column());
                if e.is_syntax() || e.is_eof() {
                    return error(file, text, here, &[], message);
                }
                // Data errors: point at the offending key or value where it can be found.
                let l = Source::new(text, format, file.into()).locate(key);
                let at = if l.found < key.len() {
                    here
                } else if message.starts_with("unknown field") {
                    l.key.unwrap_or(l.value).start
                } else {
                    l.value.start
                };
                error(file, text, at, key, message)
            };
            let d = serde_path_to_error::deserialize(&mut de)
                .map_err(|e| json_error(e.inner(), &key_path(e.path())))?;
            de.end().map_err(|e| json_error(&e, &[]))?;
            Ok(d)
        }
    }
}

/// Resolves a description with no source text (errors carry key paths, no positions);
/// relative model and map paths are looked up in `base_dir`.
pub fn resolve(
    d: &SceneDescription,
    base_dir: &Path,
) -> Result<(SceneData, RenderSettings), SceneError> {
    resolve_source(&Source::without_text(String::new()), base_dir, d)
}

/// Resolves a scene given as data (a JSON value, e.g. a Python dict); relative model
/// and map paths are looked up in `base_dir`. Errors name the key path, e.g.
/// `objects[1].solid`.
pub fn load_value(
    value: serde_json::Value,
    base_dir: &Path,
) -> Result<(SceneData, RenderSettings), SceneError> {
    resolve(&description_from_value(value)?, base_dir)
}

/// The description held by a JSON value; errors name the key path.
pub fn description_from_value(value: serde_json::Value) -> Result<SceneDescription, SceneError> {
    serde_path_to_error::deserialize(value)
        .map_err(|e| SceneError::at_key("", &key_path(e.path()), e.inner().to_string()))
}

/// Parses scene text; `path` names the file in errors and anchors relative model and
/// map paths (it is not read).
pub fn parse(
    text: &str,
    format: SceneFormat,
    path: &Path,
) -> Result<(SceneData, RenderSettings), SceneError> {
    parse_with(text, format, path, &Overrides::default())
}

/// [`parse`] with overrides applied to the description before it is resolved. Errors
/// at an overridden key carry no position (the value is not in the text).
pub fn parse_with(
    text: &str,
    format: SceneFormat,
    path: &Path,
    overrides: &Overrides,
) -> Result<(SceneData, RenderSettings), SceneError> {
    let file = path.display().to_string();
    let mut d = parse_description(text, format, &file)?;
    d.apply_overrides(overrides);
    let src = Source::new(text, format, file);
    let base = path.parent().unwrap_or(Path::new(""));
    resolve_source(&src, base, &d).map_err(|e| overrides.blame(e))
}

/// Reads a scene file, `.toml` or `.json`.
pub fn load(path: &Path) -> Result<(SceneData, RenderSettings), SceneError> {
    load_with(path, &Overrides::default())
}

/// [`load`] with overrides (see [`parse_with`]).
pub fn load_with(
    path: &Path,
    overrides: &Overrides,
) -> Result<(SceneData, RenderSettings), SceneError> {
    let file = path.display().to_string();
    let fail = |message: String| SceneError {
        file: file.clone(),
        line: 0,
        column: 0,
        key: String::new(),
        message,
    };
    let format = SceneFormat::from_path(path)
        .ok_or_else(|| fail("expected a file ending in .toml or .json".into()))?;
    let text =
        std::fs::read_to_string(path).map_err(|e| fail(format!("cannot read the file: {e}")))?;
    parse_with(&text, format, path, overrides)
}
