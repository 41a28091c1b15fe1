//! Equal-time experiments (`experiment --budget SECONDS`): each estimator renders as
//! many samples per pixel as fit in the same processor time, and is compared with the
//! baseline at that equal time rather than at equal samples.
//!
//! The cost of a render is modelled as `t₀ + n·c` (a fixed part: threads, tiles, the
//! image; and c per sample per pixel), measured per estimator by calibration renders,
//! interleaved across estimators and repeated [`CALIBRATION_ROUNDS`] times (the least
//! time of each kept: load only adds): first at 1 and [`CALIBRATION_SPP`] samples, then
//! at the samples of about an eighth of the budget (small renders cost more per sample:
//! their passes are small), then once at the samples that line says fill the budget;
//! the line through the 1-sample and that render's times is the model. The estimator
//! then renders `n = ⌊(budget − t₀) / c⌋` samples (at least 1). The measured times of the renders are reported beside, so that a reader
//! sees how equal they came out.

use super::{ExperimentError, Renderer};
use serde::{Deserialize, Serialize};

/// Samples per pixel of the longer calibration render.
pub const CALIBRATION_SPP: u32 = 4;

/// Calibration rounds (interleaved over the estimators).
pub const CALIBRATION_ROUNDS: u32 = 3;

/// The most samples per pixel a budget may buy.
pub const MAX_BUDGET_SPP: u32 = 1 << 20;

/// XORed into the seed of calibration renders (their images are not measured).
pub const CALIBRATION_SEED_MASK: u64 = 0x5851_F42D_4C95_7F2D;

/// What a budget bought each estimator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Budget {
    /// Processor seconds per render.
    pub seconds: f64,
    /// Per estimator: (name, fixed seconds t₀, seconds per sample c, samples n).
    pub estimators: Vec<BudgetShare>,
}

/// One estimator's calibration and samples.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BudgetShare {
    /// The estimator.
    pub estimator: String,
    /// Fixed seconds of a render.
    pub fixed_s: f64,
    /// Seconds per sample per pixel.
    pub per_sample_s: f64,
    /// Samples per pixel the budget buys.
    pub spp: u32,
}

impl Budget {
    /// The samples per pixel of `estimator`.
    pub fn spp(&self, estimator: &str) -> Option<u32> {
        self.estimators
            .iter()
            .find(|e| e.estimator == estimator)
            .map(|e| e.spp)
    }
}

/// Calibrates every estimator (module docs) and sizes its renders for `seconds`; None
/// if stopped.
pub fn calibrate(
    renderer: &mut dyn Renderer,
    estimators: &[String],
    seconds: f64,
    seed: u64,
    progress: &dyn Fn(&str),
) -> Result<Option<Budget>, ExperimentError> {
    if !(seconds > 0.0 && seconds.is_finite()) {
        return Err(ExperimentError::Budget(seconds));
    }
    // Stage 1: 1 and CALIBRATION_SPP samples, for a first cost per sample.
    let short = vec![vec![1, CALIBRATION_SPP]; estimators.len()];
    let Some(first) = measure(renderer, estimators, &short, seed)? else {
        return Ok(None);
    };
    // Stage 2: about an eighth of the budget, where a render's passes are as large as
    // the budget's will be (small renders cost more per sample).
    let long: Vec<u32> = first
        .iter()
        .map(|t| {
            let (per_sample, _) = fit(1, t[0], CALIBRATION_SPP, t[1]);
            let n = (seconds / 8.0 / per_sample).floor();
            n.clamp(f64::from(CALIBRATION_SPP), f64::from(MAX_BUDGET_SPP)) as u32
        })
        .collect();
    let spps: Vec<Vec<u32>> = long.iter().map(|&n| vec![n]).collect();
    let Some(second) = measure(renderer, estimators, &spps, seed)? else {
        return Ok(None);
    };
    // The samples a budget buys on the line through (1, t₁) and (n, tₙ).
    let buy = |t1: f64, n: u32, tn: f64| {
        let (per_sample, fixed) = fit(1, t1, n, tn);
        // A hair of slack, so that a budget of exactly n samples buys n.
        let k = ((seconds - fixed) / per_sample + 1e-9).floor();
        (
            k.clamp(1.0, f64::from(MAX_BUDGET_SPP)) as u32,
            per_sample,
            fixed,
        )
    };
    let guess: Vec<u32> = (0..estimators.len())
        .map(|i| buy(first[i][0], long[i], second[i][0]).0)
        .collect();
    // Stage 3: one render at the guessed samples (a whole budget), interleaved, and the
    // line refitted through it: the cost measured at the budget's own size.
    let spps: Vec<Vec<u32>> = guess.iter().map(|&n| vec![n]).collect();
    let Some(third) = measure_rounds(renderer, estimators, &spps, seed, 1)? else {
        return Ok(None);
    };
    let shares = estimators
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let (spp, per_sample, fixed) = buy(first[i][0], guess[i], third[i][0]);
            progress(&format!(
                "budget: {e}: {fixed:.4} s + {per_sample:.3e} s per sample (measured at 1 \
                 and {} spp): {spp} spp in {seconds} s",
                guess[i]
            ));
            BudgetShare {
                estimator: e.clone(),
                fixed_s: fixed,
                per_sample_s: per_sample,
                spp,
            }
        })
        .collect();
    Ok(Some(Budget {
        seconds,
        estimators: shares,
    }))
}

/// The least processor time of each estimator's renders at each of its sample counts
/// (`spps[i]`, one or two), over [`CALIBRATION_ROUNDS`] rounds interleaved across the
/// estimators (rotated each round, so that none always runs first); None if stopped.
fn measure(
    renderer: &mut dyn Renderer,
    estimators: &[String],
    spps: &[Vec<u32>],
    seed: u64,
) -> Result<Option<Vec<[f64; 2]>>, ExperimentError> {
    measure_rounds(renderer, estimators, spps, seed, CALIBRATION_ROUNDS)
}

/// [`measure`] over `rounds` rounds.
fn measure_rounds(
    renderer: &mut dyn Renderer,
    estimators: &[String],
    spps: &[Vec<u32>],
    seed: u64,
    rounds: u32,
) -> Result<Option<Vec<[f64; 2]>>, ExperimentError> {
    let mut least = vec![[f64::INFINITY; 2]; estimators.len()];
    for round in 0..rounds as usize {
        for k in 0..estimators.len() {
            let i = (k + round) % estimators.len();
            for (j, &spp) in spps[i].iter().enumerate() {
                let before = renderer.cpu_clock();
                let Some((_, wall)) =
                    renderer.render(&estimators[i], spp, seed ^ CALIBRATION_SEED_MASK)?
                else {
                    return Ok(None);
                };
                let t = before
                    .zip(renderer.cpu_clock())
                    .map_or(wall, |(a, b)| b - a);
                least[i][j] = least[i][j].min(t);
            }
        }
    }
    Ok(Some(least))
}

/// The line t = t₀ + n·c through (n₁, t₁) and (n₂, t₂): (c, t₀ ≥ 0); where noise makes
/// the slope vanish, the longer render's time spread over its samples.
fn fit(n1: u32, t1: f64, n2: u32, t2: f64) -> (f64, f64) {
    let slope = (t2 - t1) / f64::from(n2 - n1);
    if slope > 0.0 {
        (slope, (t1 - slope * f64::from(n1)).max(0.0))
    } else {
        ((t2 / f64::from(n2)).max(1e-12), 0.0)
    }
}
