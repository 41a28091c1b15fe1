//! `frepray check`: read a model or a scene, build it, and summarise it.

use std::path::Path;

/// The kinds of file `check` and `render` read, for messages.
pub const KINDS: &str = "a scene (.toml, .json) or a model (.frep, .hf, .vm)";

/// Checks `file` by its kind: a scene is resolved (models, maps and settings
/// validated), a model read, lowered and bounded; prints what it found.
pub fn run(file: &Path) -> Result<(), String> {
    let ext = file
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("toml" | "json") => scene(file),
        Some("frep" | "hf" | "vm") => model(file),
        _ => Err(format!(
            "{}: unknown kind of file; expected {KINDS}",
            file.display()
        )),
    }
}

/// Resolves a scene file and summarises it.
fn scene(file: &Path) -> Result<(), String> {
    let scene = crate::scene_flags::load(file, &Default::default())?;
    let (data, settings) = (scene.data(), scene.settings());
    out!("file:          {}", file.display());
    out!(
        "resolution:    {}×{}",
        data.camera.width,
        data.camera.height
    );
    out!(
        "objects:       {} ({} materials)",
        data.objects.len(),
        data.materials.len()
    );
    out!(
        "lights:        {} area, {} point/spot, environment: {}",
        data.lights.area.len(),
        data.lights.delta.len(),
        if data.environment.is_some() {
            "yes"
        } else {
            "no"
        }
    );
    out!(
        "render:        {} {} spp, {}",
        settings.integrator,
        settings.spp,
        settings.method.name()
    );
    Ok(())
}

/// Reads, lowers and bounds a model file ([`frepray::model_info`]) and prints it.
fn model(file: &Path) -> Result<(), String> {
    let m = frepray::model_info(file).map_err(|e| e.to_string())?;
    out!("file:          {}", file.display());
    if let Some(n) = &m.name {
        out!("model:         {n}");
    }
    out!("nodes:         {} (deduplicated expression DAG)", m.nodes);
    out!(
        "perturbed quadrics: {}, perturbations: {}",
        m.perturbed.0,
        m.perturbed.1
    );
    out!(
        "dimensions:    {}",
        match m.planar {
            true => "2-D (F does not depend on z; rendered from the top, parallel rays)",
            false => "3-D",
        }
    );
    // How rays search its expression solids: a polynomial of low degree in Bernstein
    // form, anything else by interval arithmetic.
    let poly = &m.polynomial_degrees;
    if !poly.is_empty() || m.by_intervals > 0 {
        out!(
            "expression solids: {} polynomial (Bernstein search{}), {} by intervals",
            poly.len(),
            match poly.is_empty() {
                true => String::new(),
                false => format!(
                    ", degree {}",
                    poly.iter()
                        .map(u8::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            },
            m.by_intervals
        );
    }
    match m.bounds {
        None => out!("bounds:        empty (F < 0 everywhere in the search domain)"),
        Some((lo, hi)) => out!(
            "bounds:        [{:.6}, {:.6}, {:.6}] .. [{:.6}, {:.6}, {:.6}]",
            lo[0],
            lo[1],
            lo[2],
            hi[0],
            hi[1],
            hi[2]
        ),
    }
    Ok(())
}
