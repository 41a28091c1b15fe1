//! The tables of an experiment whose renders ran elsewhere (a Ray cluster, other
//! machines): the same points, intervals and comparisons as [`super::run`] makes from
//! its own renders, from each render's metrics and time.

use super::manifest::{Manifest, ReferenceInfo, ReferenceSource, RenderRecord, FORMAT};
use super::{report, Metrics, Summary};

/// One render measured against the reference ([`super::measure`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    /// Its estimator (canonical name, [`super::canonical`]).
    pub estimator: String,
    /// Samples per pixel.
    pub spp: u32,
    /// Its seed: renders of the same seed pair up across estimators in the intervals.
    pub seed: u64,
    /// Its render time in seconds.
    pub time_s: f64,
    /// Its errors.
    pub metrics: Metrics,
}

/// The points (averaged over seeds, with 95 % intervals from two seeds on) and their
/// comparisons against `baseline` at the same spp, exactly as [`super::run`] reports
/// them; a point is complete when every seed of the renders has a render of it.
/// `reference_noise` is the reference's own variance per value when known (the net MSE).
pub fn summarize(renders: &[Measured], baseline: &str, reference_noise: Option<f64>) -> Summary {
    let mut estimators = vec![baseline.to_string()];
    let (mut spp, mut seeds) = (Vec::new(), Vec::new());
    for r in renders {
        if !estimators.contains(&r.estimator) {
            estimators.push(r.estimator.clone());
        }
        spp.push(r.spp);
        seeds.push(r.seed);
    }
    spp.sort_unstable();
    spp.dedup();
    seeds.sort_unstable();
    seeds.dedup();
    let m = Manifest {
        format: FORMAT,
        command: String::new(),
        scene: String::new(),
        renderer: String::new(),
        baseline: baseline.to_string(),
        reference: ReferenceInfo {
            source: ReferenceSource::File {
                path: String::new(),
            },
            width: 0,
            height: 0,
            fingerprint: String::new(),
            time_s: None,
            noise_mse: reference_noise,
        },
        interrupted: false,
        renders: renders
            .iter()
            .map(|r| RenderRecord {
                estimator: r.estimator.clone(),
                spp: r.spp,
                seed: r.seed,
                file: String::new(),
                time_s: r.time_s,
                mse: r.metrics.mse,
                rmse: r.metrics.mse.sqrt(),
                relmse: r.metrics.relmse,
                trimmed_mse: r.metrics.trimmed_mse,
                cpu_s: None,
                nonfinite: r.metrics.nonfinite,
            })
            .collect(),
        results: Vec::new(),
        comparisons: Vec::new(),
        centered: Vec::new(),
        budget: None,
    };
    let rows = report::rows(&m, &estimators, &spp, &seeds, reference_noise);
    let comparisons = report::compare(&m, &rows, baseline, reference_noise);
    Summary {
        rows,
        comparisons,
        rendered: renders.len(),
        reused: 0,
        interrupted: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(estimator: &str, spp: u32, seed: u64, mse: f64, time_s: f64) -> Measured {
        Measured {
            estimator: estimator.into(),
            spp,
            seed,
            time_s,
            metrics: Metrics {
                mse,
                relmse: mse,
                trimmed_mse: mse,
                nonfinite: 0,
            },
        }
    }

    #[test]
    fn ratios_and_intervals_are_those_of_the_tables() {
        let renders = [
            m("balance", 4, 0, 4.0, 1.0),
            m("balance", 4, 1, 6.0, 1.0),
            m("optimal-direct", 4, 0, 1.0, 2.0),
            m("optimal-direct", 4, 1, 1.5, 2.0),
            // A point missing a seed is not complete.
            m("power", 4, 0, 2.0, 1.0),
        ];
        let s = summarize(&renders, "balance", None);
        assert_eq!(s.rows.len(), 2);
        let c = s
            .comparisons
            .iter()
            .find(|c| c.estimator == "optimal-direct")
            .unwrap();
        // Improvement √(5 / 1.25) = 2, Overhead 2 − 1, Speed Up 5·1 / (1.25·2) = 2.
        assert!((c.improvement.unwrap() - 2.0).abs() < 1e-12);
        assert!((c.overhead.unwrap() - 1.0).abs() < 1e-12);
        assert!((c.speed_up.unwrap() - 2.0).abs() < 1e-12);
        let [lo, hi] = c.improvement_ci.unwrap();
        assert!(lo <= 2.0 && 2.0 <= hi, "[{lo}, {hi}]");
        let row = s.rows.iter().find(|r| r.estimator == "balance").unwrap();
        assert_eq!(row.seeds, [0, 1]);
        assert!(row.mse_ci.is_some());
    }
}
