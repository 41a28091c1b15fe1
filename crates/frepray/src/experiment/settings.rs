//! The renderer settings an experiment records: a rerun into the same folder renders
//! anew when they differ, and reuses its renders when they agree. The CLI and the Python
//! API write them alike, so either resumes the other's experiment.

use render::integrator::RenderOptions;

/// The settings of every render of an experiment whose base options are `base` (its
/// `scene_hash` set) at `width` × `height`. Settings added later are written only when
/// they differ from their default, so that earlier experiments still read as before.
pub fn renderer_settings(base: &RenderOptions, width: u32, height: u32) -> String {
    let mut s = format!(
        "integrator {} techniques {:?} max_depth {} rr_depth {} hide_emitters {}{} resolution {}x{} params {:?} scene-hash {:016x}",
        base.integrator,
        base.techniques
            .iter()
            .map(|(t, n)| format!("{}:{n}", t.name()))
            .collect::<Vec<_>>(),
        base.max_depth,
        base.rr_depth,
        base.hide_emitters,
        if base.pixel_center { " pixel-centres" } else { "" },
        width,
        height,
        base.params,
        base.scene_hash
    );
    if base.per_light > 0 {
        s += &format!(" per-light {}", base.per_light);
    }
    if base.min_depth > 0 {
        s += &format!(" min-depth {}", base.min_depth);
    }
    if base.training != scene::Training::default() {
        let t = base.training;
        s += &format!(" trained grid {} floor {} spp {}", t.grid, t.floor, t.spp);
    }
    s
}
