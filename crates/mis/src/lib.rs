//! # mis — multiple importance sampling, independent of rendering
//!
//! Combines samples from several techniques into one Monte Carlo estimate of `F = ∫ f`:
//! the heuristics of Veach (1997, ch. 9: balance, power, maximum, cutoff; multi-sample and
//! one-sample models) and the optimal MIS estimators of Kondapaneni et al. (2019: direct,
//! uncorrelated, progressive, full weights), for any number of channels.
//!
//! Per iteration the caller draws `n_i` samples from each technique i and passes each one
//! as (technique, f per channel, every technique's pdf at the sample). All state is sums
//! and counts in f64, so estimators of the same kind [`Estimator::merge`] across threads,
//! tiles and runs. Estimates may be negative; nothing is clamped. See `docs/mis.md`.
//! A renderer that keeps one estimator per pixel stores their states as flat blocks of
//! `f64` and runs them with a [`Kernel`] (module [`block`]).
//!
//! ```
//! use mis::{Estimator, Layout, Method, Params};
//! // ∫₀¹ f with f(x) = 3 + 2x = 3·p₀ + 1·p₁ for p₀ = 1 (uniform), p₁ = 2x (linear): F = 4.
//! let layout = Layout::new(&[1, 1], 1); // one sample of each technique per iteration
//! let params = Params { ridge: Some(0.0), ..Params::default() };
//! let mut optimal = Method::OptimalDirect.build(&layout, &params).unwrap();
//! let mut balance: mis::AnyEstimator = "balance".parse::<Method>().unwrap().build(&layout, &params).unwrap();
//! for k in 0..8 {
//!     let u = (k as f64 + 0.5) / 8.0;
//!     for (t, x) in [(0, u), (1, u.sqrt())] {
//!         let pdfs = [1.0, 2.0 * x];
//!         for e in [&mut optimal, &mut balance] {
//!             e.add_sample(t, &[3.0 + 2.0 * x], &pdfs);
//!         }
//!     }
//!     optimal.end_iteration();
//!     balance.end_iteration();
//! }
//! // f lies in the span of the pdfs: optimal MIS is exact for any samples.
//! assert!((optimal.estimate_vec()[0] - 4.0).abs() < 1e-12);
//! assert!((balance.estimate_vec()[0] - 4.0).abs() > 1e-6);
//! ```
#![warn(missing_docs)]

pub mod block;
pub mod direct;
pub mod estimator;
pub mod heuristic;
pub mod layout;
pub mod linalg;
pub mod moments;
pub mod one_sample;
pub mod param_error;
pub mod progressive;
pub mod uncorrelated;
pub mod weighted;
pub mod weights;

pub use block::Kernel;
pub use direct::Direct;
pub use estimator::{
    AnyEstimator, Estimator, Method, Params, UnknownMethod, DEFAULT_RIDGE,
    DEFAULT_RIDGE_UNCORRELATED, DEFAULT_TRAIN, DEFAULT_WARMUP,
};
pub use heuristic::Heuristic;
pub use layout::Layout;
pub use linalg::SolveMethod;
pub use moments::Moments;
pub use one_sample::OneSample;
pub use param_error::ParamError;
pub use progressive::{Progressive, Schedule};
pub use uncorrelated::Uncorrelated;
pub use weighted::Weighted;
pub use weights::{optimal_contribution, optimal_weight};
