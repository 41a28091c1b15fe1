//! `frepray merge A.state B.state … -o OUT`: adds render states of disjoint sample ranges
//! of one render (same scene, size, integrator, estimator, techniques and seed) and
//! writes the result as an image or as a state.

use crate::output::{self, Format};
use frepray::RenderState;
use std::path::PathBuf;

/// Arguments of `frepray merge`.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// Render states written by `frepray render … -o NAME.state`.
    #[arg(required = true)]
    states: Vec<PathBuf>,
    /// Output: .png, .exr (the resolved image) or .state (the merged sums); repeatable.
    #[arg(short, long, required = true)]
    output: Vec<PathBuf>,
    #[command(flatten)]
    film: output::FilmArgs,
}

/// Reads, merges and writes; errors name the file that does not fit.
pub fn run(args: MergeArgs) -> Result<(), String> {
    let formats: Vec<Format> = output::check_scene_outputs(&args.output)?;
    let film = args.film.over(frepray::Film::default())?;
    let mut merged: Option<RenderState> = None;
    for path in &args.states {
        let s = RenderState::read(path).map_err(|e| e.to_string())?;
        match &mut merged {
            None => merged = Some(s),
            Some(m) => m
                .merge(&s)
                .map_err(|e| format!("{}: {e}", path.display()))?,
        }
    }
    let merged = merged.expect("clap requires one state");
    let from = output::list(&args.states);
    output::write_state(&args.output, &formats, &merged, &film, &|img| {
        img.set_attribute(
            &format!("{}merged_from", frepray::ATTRIBUTE_PREFIX),
            from.as_str(),
        )
    })?;
    note!(
        "merged {} state(s): {}; written {}",
        args.states.len(),
        merged.summary(),
        output::list(&args.output)
    );
    Ok(())
}
