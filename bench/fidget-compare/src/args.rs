//! Command-line arguments (plain parsing: the bench keeps its dependencies few).

use std::path::{Path, PathBuf};

/// What to run.
pub struct Args {
    /// Model files (.vm).
    pub models: Vec<PathBuf>,
    /// Output folder for PNGs and results.md.
    pub out: PathBuf,
    /// Number of random points for point evaluation.
    pub points: usize,
    /// Fidget float-slice batch length.
    pub batch: usize,
    /// Timed repetitions (best is reported).
    pub reps: usize,
    /// Timed repetitions of frepray's (slow) ray renders.
    pub ray_reps: usize,
    /// The ray profile counts every `stride`-th pixel in x and y.
    pub stride: usize,
    /// Image sizes (square, and as many voxels deep).
    pub sizes: Vec<usize>,
    /// Per-model half-size of the view box, `name=h`.
    pub halves: Vec<(String, f64)>,
}

const USAGE: &str = "\
usage: fidget-compare [MODEL.vm ...] [--out DIR] [--points N] [--batch B] [--reps R]
                      [--ray-reps R] [--stride S]
                      [--sizes 512,1024] [--half NAME=H ...]

MODEL.vm   Fidget tapes (default: colonnade.vm and tanglecube.vm in
           <crate>/../../models/fidget)
--out      output folder for depth PNGs and results.md (default: out)
--points   random points for the point-evaluation rate (default 1000000)
--batch    Fidget float-slice batch length (default 4096)
--reps     timed repetitions, best reported (default 3)
--ray-reps timed repetitions of frepray's ray renders (default 1)
--stride   the ray profile counts every S-th pixel in x and y (default 4)
--sizes    heightmap sizes N (N x N pixels, N voxels deep; default 512)
--half     half-size h of the view box [-h,h]^3 for a model (defaults:
           colonnade=1.4286, i.e. Fidget's recommended scale 0.7; tanglecube=2.5;
           anything else 1)";

impl Args {
    /// Parses `std::env::args`.
    pub fn parse() -> Result<Args, String> {
        let mut a = Args {
            models: vec![],
            out: PathBuf::from("out"),
            points: 1_000_000,
            batch: 4096,
            reps: 3,
            ray_reps: 1,
            stride: 4,
            sizes: vec![512],
            halves: vec![],
        };
        let mut it = std::env::args().skip(1);
        while let Some(s) = it.next() {
            let mut val = |name: &str| it.next().ok_or(format!("{name} needs a value\n{USAGE}"));
            let num = |v: String, name: &str| -> Result<usize, String> {
                v.parse()
                    .map_err(|_| format!("{name}: expected a number, found '{v}'"))
            };
            match s.as_str() {
                "-h" | "--help" => return Err(USAGE.to_string()),
                "--out" => a.out = PathBuf::from(val("--out")?),
                "--points" => a.points = num(val("--points")?, "--points")?,
                "--batch" => a.batch = num(val("--batch")?, "--batch")?.max(1),
                "--reps" => a.reps = num(val("--reps")?, "--reps")?.max(1),
                "--ray-reps" => a.ray_reps = num(val("--ray-reps")?, "--ray-reps")?.max(1),
                "--stride" => a.stride = num(val("--stride")?, "--stride")?.max(1),
                "--sizes" => {
                    a.sizes = val("--sizes")?
                        .split(',')
                        .filter(|v| !v.is_empty())
                        .map(|v| num(v.to_string(), "--sizes"))
                        .collect::<Result<_, _>>()?
                }
                "--half" => {
                    let v = val("--half")?;
                    let (n, h) = v
                        .split_once('=')
                        .ok_or(format!("--half: expected NAME=H, found '{v}'"))?;
                    let h: f64 = h
                        .parse()
                        .map_err(|_| format!("--half: bad number in '{v}'"))?;
                    a.halves.push((n.to_string(), h));
                }
                f if f.starts_with("--") => return Err(format!("unknown option {f}\n{USAGE}")),
                f => a.models.push(PathBuf::from(f)),
            }
        }
        if a.models.is_empty() {
            let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/fidget");
            a.models = vec![dir.join("colonnade.vm"), dir.join("tanglecube.vm")];
        }
        Ok(a)
    }

    /// The view box half-size for a model file.
    pub fn half_for(&self, path: &Path) -> f64 {
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
        if let Some((_, h)) = self.halves.iter().rev().find(|(n, _)| n == stem) {
            return *h;
        }
        match stem {
            "colonnade" => 1.0 / 0.7,
            "tanglecube" => 2.5,
            _ => 1.0,
        }
    }
}
