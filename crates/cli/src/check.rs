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
        Some("exr") => image(file),
        Some("state") => state(file),
        _ => Err(format!(
            "{}: unknown kind of file; expected {KINDS}, an image (.exr) or a state (.state)",
            file.display()
        )),
    }
}

/// Reads an EXR image and prints its size, channels, mean colour and header attributes
/// (what `render` records there: settings, scene hash, version, statistics).
fn image(file: &Path) -> Result<(), String> {
    let img = frepray::Image::read_exr(file).map_err(|e| e.to_string())?;
    out!("file:          {}", file.display());
    out!("size:          {}×{}", img.width(), img.height());
    let mut channels = vec!["R".to_string(), "G".into(), "B".into()];
    channels.extend(img.aov_names().iter().cloned());
    out!("channels:      {}", channels.join(", "));
    let n = (img.width() as f64 * img.height() as f64).max(1.0);
    let mut mean = [0.0; 3];
    for p in img.data().chunks_exact(img.channels()) {
        for c in 0..3 {
            mean[c] += p[c] / n;
        }
    }
    out!(
        "mean:          {:.6} {:.6} {:.6}",
        mean[0],
        mean[1],
        mean[2]
    );
    if img.attributes().is_empty() {
        out!("attributes:    none (not written by frepray)");
    }
    for (name, value) in img.attributes() {
        out!("{name}: {value}");
    }
    Ok(())
}

/// Reads a render state and prints its summary and settings.
fn state(file: &Path) -> Result<(), String> {
    let s = frepray::RenderState::read(file).map_err(|e| e.to_string())?;
    out!("file:          {}", file.display());
    out!("state:         {}", s.summary());
    for (name, value) in s.image().attributes() {
        out!("{name}: {value}");
    }
    Ok(())
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
    let meshes = data
        .objects
        .iter()
        .filter(|o| o.geometry.solid().is_none())
        .count();
    out!(
        "objects:       {} ({} materials{}{})",
        data.objects.len(),
        data.materials.len(),
        match meshes {
            0 => String::new(),
            n => format!("; {n} triangle meshes"),
        },
        match data.media.len() {
            0 => String::new(),
            n => format!("; {n} media: {}", data.medium_names.join(", ")),
        }
    );
    let emitting = data
        .lights
        .area
        .iter()
        .filter(|l| l.kind == frepray::LightKind::Solid)
        .count();
    out!(
        "lights:        {} area{}, {} point/spot, environment: {}",
        data.lights.area.len(),
        match emitting {
            0 => String::new(),
            n => format!(" ({n} of them emitting objects)"),
        },
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
        // Solids whose polynomial parts fold into leaves along rays: fewer nodes a ray.
        let leaves = match m.with_leaves.as_slice() {
            [] => String::new(),
            w => format!(
                " ({} with polynomial leaves: {} nodes a ray)",
                w.len(),
                w.iter()
                    .map(|(a, b)| format!("{a} → {b}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        out!(
            "expression solids: {} polynomial (Bernstein search{}), {} by intervals{leaves}",
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
