//! `frepray`: render functionally defined scenes, check model files.

mod check;
mod output;
mod preview;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// A physically based renderer for functionally defined (FRep) scenes.
#[derive(Parser)]
#[command(name = "frepray", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a model file (.frep, .hf, .vm) to an image (.png or .exr).
    Render(RenderArgs),
    /// Validate a model file and print a summary (bounds, node count, perturbations).
    Check {
        /// The model file.
        file: PathBuf,
    },
}

#[derive(clap::Args)]
struct RenderArgs {
    /// The model file (.frep, .hf or .vm).
    input: PathBuf,
    /// Output image: .png (sRGB) or .exr (linear, with AOV channels).
    #[arg(short, long)]
    output: PathBuf,
    /// What to show: shaded, depth or normals (depth and normals are EXR channels).
    #[arg(long, value_enum, default_value_t = preview::Look::Shaded)]
    integrator: preview::Look,
    /// Image width in pixels.
    #[arg(long, default_value_t = 512)]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 512)]
    height: u32,
    /// The model's vertical axis.
    #[arg(long, value_enum, default_value_t = preview::Up::Z)]
    up: preview::Up,
    /// Worker threads (0: one per core). The image does not depend on it.
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Hide the progress bar.
    #[arg(long)]
    quiet: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render(args),
        Command::Check { file } => check::run(&file),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn render(args: RenderArgs) -> Result<(), String> {
    let format = output::format_for(&args.output, args.integrator)?;
    if args.width == 0 || args.height == 0 {
        return Err("--width and --height must be at least 1".into());
    }
    if args.threads > 0 {
        rayon::ThreadPoolBuilder::new()
            .num_threads(args.threads)
            .build_global()
            .map_err(|e| e.to_string())?;
    }
    let start = std::time::Instant::now();
    let model = frep::read::read_file(&args.input).map_err(|e| e.to_string())?;
    let solid =
        frep::Solid::build(&model.shape).map_err(|e| format!("{}: {e}", args.input.display()))?;
    let setup = start.elapsed();
    let cam = preview::framing(
        &preview::view_bounds(&solid),
        args.up.vector(),
        args.width,
        args.height,
    );

    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    {
        let stop = stop.clone();
        // A second Ctrl-C while the first is honoured falls through to the default.
        let _ = ctrlc::set_handler(move || stop.store(true, std::sync::atomic::Ordering::SeqCst));
    }
    let bar = if args.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(args.height as u64).with_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} rows  {elapsed} (eta {eta})",
            )
            .expect("valid template"),
        )
    };
    let t0 = std::time::Instant::now();
    let film = preview::render(&solid, &cam, args.integrator, &stop, &|n| bar.inc(n));
    let trace = t0.elapsed();
    bar.finish_and_clear();
    let stopped = stop.load(std::sync::atomic::Ordering::SeqCst);
    output::write(&args.output, &film, format)?;
    let rays = args.width as f64 * args.height as f64;
    eprintln!(
        "{}{} {}x{}: setup {:.2} s, trace {:.2} s, {:.3} MRays/s (camera), written {}",
        if stopped { "interrupted: " } else { "" },
        args.input.display(),
        args.width,
        args.height,
        setup.as_secs_f64(),
        trace.as_secs_f64(),
        rays / trace.as_secs_f64().max(1e-9) / 1e6,
        args.output.display()
    );
    Ok(())
}
