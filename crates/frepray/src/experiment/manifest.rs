//! `results.json`: the numbers of an experiment and the manifest that lets a rerun
//! skip finished renders. Rewritten whole (temp + rename) after every render.

use super::ExperimentError;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The manifest's format version.
pub const FORMAT: u32 = 1;

/// Where the reference image came from: a rerun must use the same one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "source", rename_all = "lowercase")]
pub enum ReferenceSource {
    /// Loaded from an EXR file.
    File {
        /// The file, as given (made absolute where possible).
        path: String,
    },
    /// Rendered into `reference.exr` in the output folder.
    Rendered {
        /// The estimator used.
        estimator: String,
        /// Samples per pixel.
        spp: u32,
        /// The seed of the first part; part k uses `seed + k`.
        seed: u64,
        /// Independent parts (seeds) the reference averages, 2 since the reference's
        /// noise is estimated from their difference; 1 in older folders.
        #[serde(default = "one")]
        parts: u32,
    },
}

fn one() -> u32 {
    1
}

/// The reference an experiment measures against.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceInfo {
    /// Its origin.
    #[serde(flatten)]
    pub source: ReferenceSource,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// [`super::Image::fingerprint`] of its pixels.
    pub fingerprint: String,
    /// Render time in seconds (rendered references only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_s: Option<f64>,
    /// The reference's own noise, its estimated variance per value averaged over pixels
    /// and channels (rendered in two parts: `mean (A − B)²` scaled to the whole); it adds
    /// to every measured MSE and is subtracted in the net MSE.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise_mse: Option<f64>,
}

/// One finished render.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderRecord {
    /// The estimator.
    pub estimator: String,
    /// Samples per pixel.
    pub spp: u32,
    /// The seed.
    pub seed: u64,
    /// The image with its error, relative to the output folder.
    pub file: String,
    /// Render time in seconds.
    #[serde(with = "finite")]
    pub time_s: f64,
    /// Mean squared error.
    #[serde(with = "finite")]
    pub mse: f64,
    /// √MSE.
    #[serde(with = "finite")]
    pub rmse: f64,
    /// Relative MSE (ε in [`super::REL_EPSILON`]).
    #[serde(with = "finite")]
    pub relmse: f64,
    /// MSE without the worst pixels ([`super::TRIM_FRACTION`]).
    #[serde(with = "finite", default = "nan")]
    pub trimmed_mse: f64,
    /// Processor time of the render in seconds (all threads; where the platform tells).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu_s: Option<f64>,
    /// Non-finite channel values in the image.
    pub nonfinite: u64,
}

fn nan() -> f64 {
    f64::NAN
}

/// One point of the sweep: the renders of an estimator at a sample count, averaged
/// over the repeats (MSE, relMSE and time are means; RMSE = √mean MSE), with 95 %
/// intervals over the seeds ([`super::stats`]; `None` with one seed).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// The estimator.
    pub estimator: String,
    /// Samples per pixel.
    pub spp: u32,
    /// The seeds of the repeats.
    pub seeds: Vec<u64>,
    /// Mean render time in seconds.
    #[serde(with = "finite")]
    pub time_s: f64,
    /// Mean MSE.
    #[serde(with = "finite")]
    pub mse: f64,
    /// √(mean MSE).
    #[serde(with = "finite")]
    pub rmse: f64,
    /// Mean relMSE.
    #[serde(with = "finite")]
    pub relmse: f64,
    /// 95 % interval of the mean MSE.
    pub mse_ci: Option<[f64; 2]>,
    /// 95 % interval of the RMSE (√ of the MSE interval, clamped at 0).
    pub rmse_ci: Option<[f64; 2]>,
    /// 95 % interval of the mean relMSE.
    pub relmse_ci: Option<[f64; 2]>,
    /// Mean trimmed MSE ([`super::TRIM_FRACTION`] of the pixels left out).
    #[serde(with = "finite", default = "nan")]
    pub trimmed_mse: f64,
    /// Mean MSE less the reference's own noise, where it is known (may be ≤ 0 when the
    /// reference is as noisy as the render: then no ratio uses it).
    pub net_mse: Option<f64>,
    /// The least processor time over the seeds (renders of a point's seeds interleave
    /// with the other estimators', so load hits all alike), in seconds.
    pub cpu_s: Option<f64>,
    /// The variance decomposition, where asked for ([`super::decompose`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variance: Option<super::decompose::Variance>,
}

/// A row against the baseline at equal spp (DESIGN.md §4); `None` where undefined
/// (zero or non-finite error or time).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// The estimator.
    pub estimator: String,
    /// Samples per pixel.
    pub spp: u32,
    /// RMSE_baseline / RMSE_method (net of the reference's noise where it is known).
    pub improvement: Option<f64>,
    /// 95 % interval of the improvement (paired seeds, [`super::stats::ratio_ci`]).
    pub improvement_ci: Option<[f64; 2]>,
    /// The improvement in trimmed RMSE (worst pixels left out).
    pub improvement_trimmed: Option<f64>,
    /// The median over pixels of the per-pixel ratio of squared errors baseline /
    /// method (each averaged over seeds and channels): above 1 where most pixels gain.
    pub median_pixel_ratio: Option<f64>,
    /// time_method / time_baseline − 1 (processor time where known, else wall time).
    pub overhead: Option<f64>,
    /// efficiency_method / efficiency_baseline, efficiency = 1 / (MSE × time), time as
    /// in the overhead.
    pub speed_up: Option<f64>,
    /// 95 % interval of the speed-up from the seeds' MSE × time (paired), so that it
    /// widens with the timing noise as with the MSEs'.
    pub speed_up_ci: Option<[f64; 2]>,
}

/// The whole file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// [`FORMAT`].
    pub format: u32,
    /// The command line of the latest run.
    pub command: String,
    /// The scene file (made absolute where possible): a rerun must name the same one.
    pub scene: String,
    /// The renderer's settings that change the images: a rerun must give the same.
    pub renderer: String,
    /// The baseline of the comparisons.
    pub baseline: String,
    /// The reference.
    pub reference: ReferenceInfo,
    /// Whether the latest run was stopped before it finished.
    pub interrupted: bool,
    /// Every finished render, including those of sample counts or estimators that the
    /// latest run did not ask for.
    pub renders: Vec<RenderRecord>,
    /// The points of the latest run that are complete.
    pub results: Vec<Row>,
    /// The comparisons against the baseline.
    pub comparisons: Vec<Comparison>,
    /// Renders with camera rays through pixel centres, for the variance decomposition
    /// (`time_s` and the errors against the reference mean little for them).
    #[serde(default)]
    pub centered: Vec<RenderRecord>,
    /// At equal time: the budget and what it bought each estimator.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub budget: Option<super::budget::Budget>,
}

impl Manifest {
    /// The finished render of (estimator, spp, seed), if any.
    pub fn find(&self, estimator: &str, spp: u32, seed: u64) -> Option<&RenderRecord> {
        self.renders
            .iter()
            .find(|r| r.estimator == estimator && r.spp == spp && r.seed == seed)
    }

    /// Adds `rec`, replacing an earlier render of the same point.
    pub fn upsert(&mut self, rec: RenderRecord) {
        self.renders
            .retain(|r| !(r.estimator == rec.estimator && r.spp == rec.spp && r.seed == rec.seed));
        self.renders.push(rec);
    }

    /// Reads `path`: `Ok(None)` if there is no such file, an error if it is not a
    /// manifest of this format.
    pub fn load(path: &Path) -> Result<Option<Manifest>, ExperimentError> {
        let bytes = match std::fs::read(path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(ExperimentError::io("read", path)(e)),
        };
        let m: Manifest = serde_json::from_slice(&bytes).map_err(|e| ExperimentError::File {
            path: path.to_path_buf(),
            message: format!(
                "not a frepray experiment manifest ({e}); remove it or choose another --out"
            ),
        })?;
        if m.format != FORMAT {
            return Err(ExperimentError::File {
                path: path.to_path_buf(),
                message: format!(
                    "format {} (this frepray writes {FORMAT}); choose another --out",
                    m.format
                ),
            });
        }
        Ok(Some(m))
    }

    /// Writes the manifest as pretty JSON, whole or not at all.
    pub fn save(&self, path: &Path) -> Result<(), ExperimentError> {
        let json = serde_json::to_vec_pretty(self).expect("a manifest serialises");
        render::output::write_atomically(path, |w| {
            std::io::Write::write_all(w, &json)?;
            std::io::Write::write_all(w, b"\n")
        })
        .map_err(ExperimentError::io("write", path))
    }
}

/// f64 fields that may be NaN or infinite (a broken estimator): written as `null`,
/// read back as NaN, since JSON has no such numbers.
mod finite {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_f64(*v)
        } else {
            s.serialize_none()
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}
