//! The interface every multi-sample combination implements, and the by-name choice of one.
//!
//! One *iteration* draws `n_i` samples from each technique i (Veach 1997, §9.2.2: the
//! multi-sample model). For each sample the caller passes the index of the technique that
//! drew it, the integrand value(s) `f` (one per channel, any sign) and the pdfs of **all**
//! T techniques at that sample; a technique that produced nothing is reported with
//! [`Estimator::add_failed`]; [`Estimator::end_iteration`] closes the iteration. The state
//! is sums and counts, so [`Estimator::merge`] combines threads, tiles or separate runs.

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use crate::{Direct, Heuristic, Layout, ParamError, Progressive, Schedule, Uncorrelated, Weighted};

/// A multi-sample Monte Carlo estimator of `F = ∫ f` (per channel) from several techniques.
pub trait Estimator {
    /// The problem layout (techniques, samples per iteration, channels).
    fn layout(&self) -> &Layout;

    /// One sample drawn by `technique`: `f` has one value per channel, `pdfs` one density
    /// per technique, all evaluated at the sample. A sample whose own pdf is 0 counts as
    /// failed. O(T²) for the optimal estimators, O(T) for the heuristics; no allocation.
    fn add_sample(&mut self, technique: usize, f: &[f64], pdfs: &[f64]);

    /// `technique` produced no sample this time (it still counts towards its `n_i`).
    fn add_failed(&mut self, technique: usize);

    /// Closes an iteration: exactly `n_i` samples (or failures) of each technique i must
    /// have been added since the previous call.
    fn end_iteration(&mut self);

    /// Completed iterations N.
    fn iterations(&self) -> u64;

    /// The estimate of F for every channel into `out` (0 before the first iteration).
    fn estimate(&self, out: &mut [f64]);

    /// The estimate as a new vector.
    fn estimate_vec(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.layout().channels()];
        self.estimate(&mut out);
        out
    }

    /// Adds another state of the same kind and layout (panics otherwise). For sums-only
    /// estimators two halves of a run merge into the whole run, to rounding.
    fn merge(&mut self, other: &Self)
    where
        Self: Sized;
}

/// The estimators by name; parse one from its name with [`str::parse`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Balance heuristic (Veach 1997).
    Balance,
    /// Power heuristic with exponent [`Params::beta`].
    Power,
    /// Maximum heuristic.
    Maximum,
    /// Cutoff heuristic with threshold [`Params::cutoff`].
    Cutoff,
    /// Optimal MIS, α and the estimate from the same samples ([`Direct`]).
    OptimalDirect,
    /// Optimal MIS, `Â` and `b̂` from alternate iterations ([`Uncorrelated`]).
    OptimalUncorrelated,
    /// Optimal MIS, α from earlier iterations, re-solved on a doubling schedule ([`Progressive`]).
    OptimalProgressive,
    /// Optimal MIS, α trained on the first iterations, then fixed per-sample optimal
    /// weights ([`Progressive`] with [`Schedule::Once`]).
    OptimalFull,
}

impl Method {
    /// Every method, in the order of their names.
    pub const ALL: [Method; 8] = [
        Method::Balance,
        Method::Power,
        Method::Maximum,
        Method::Cutoff,
        Method::OptimalDirect,
        Method::OptimalUncorrelated,
        Method::OptimalProgressive,
        Method::OptimalFull,
    ];

    /// The name that [`str::parse`] accepts.
    pub const fn name(self) -> &'static str {
        match self {
            Method::Balance => "balance",
            Method::Power => "power",
            Method::Maximum => "maximum",
            Method::Cutoff => "cutoff",
            Method::OptimalDirect => "optimal-direct",
            Method::OptimalUncorrelated => "optimal-uncorrelated",
            Method::OptimalProgressive => "optimal-progressive",
            Method::OptimalFull => "optimal-full",
        }
    }

    /// Whether this is one of the optimal-MIS estimators (they cost O(T²) a sample).
    pub const fn is_optimal(self) -> bool {
        matches!(
            self,
            Method::OptimalDirect
                | Method::OptimalUncorrelated
                | Method::OptimalProgressive
                | Method::OptimalFull
        )
    }

    /// The ridge λ this method uses when none is given: [`DEFAULT_RIDGE_UNCORRELATED`] for
    /// the uncorrelated estimator, whose `Â` from half the iterations is near singular at
    /// small N, [`DEFAULT_RIDGE`] for the others (docs/mis.md measures both).
    pub const fn default_ridge(self) -> f64 {
        match self {
            Method::OptimalUncorrelated => DEFAULT_RIDGE_UNCORRELATED,
            _ => DEFAULT_RIDGE,
        }
    }

    /// The heuristic of a heuristic method (None for the optimal ones).
    pub fn heuristic(self, params: &Params) -> Option<Heuristic> {
        match self {
            Method::Balance => Some(Heuristic::Balance),
            Method::Power => Some(Heuristic::Power { beta: params.beta }),
            Method::Maximum => Some(Heuristic::Maximum),
            Method::Cutoff => Some(Heuristic::Cutoff { c: params.cutoff }),
            _ => None,
        }
    }

    /// The re-solve schedule of a progressive method (None for the others).
    pub fn schedule(self, params: &Params) -> Option<Schedule> {
        match self {
            Method::OptimalProgressive => Some(Schedule::Doubling {
                warmup: params.warmup,
            }),
            Method::OptimalFull => Some(Schedule::Once {
                after: params.train,
            }),
            _ => None,
        }
    }

    /// A fresh (empty) estimator of this method for one pixel (or one integral).
    pub fn build(self, layout: &Arc<Layout>, params: &Params) -> Result<AnyEstimator, ParamError> {
        params.validate()?;
        let layout = Arc::clone(layout);
        let ridge = params.ridge_for(self);
        Ok(match self {
            Method::OptimalDirect => AnyEstimator::Direct(Direct::new(layout, ridge)),
            Method::OptimalUncorrelated => {
                AnyEstimator::Uncorrelated(Uncorrelated::new(layout, ridge))
            }
            Method::OptimalProgressive | Method::OptimalFull => AnyEstimator::Progressive(
                Progressive::new(layout, ridge, self.schedule(params).expect("progressive")),
            ),
            m => AnyEstimator::Weighted(Weighted::new(
                layout,
                m.heuristic(params).expect("heuristic methods"),
            )),
        })
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The error of parsing an unknown method name; its message lists the valid names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownMethod(pub String);

impl fmt::Display for UnknownMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        write!(
            f,
            "unknown MIS method {:?}; valid names: {}",
            self.0,
            names.join(", ")
        )
    }
}

impl std::error::Error for UnknownMethod {}

impl FromStr for Method {
    type Err = UnknownMethod;

    /// Case-insensitive; `_` and `-` are interchangeable ("optimal_direct").
    fn from_str(s: &str) -> Result<Method, UnknownMethod> {
        let key = s.trim().to_ascii_lowercase().replace('_', "-");
        Method::ALL
            .into_iter()
            .find(|m| m.name() == key)
            .ok_or_else(|| UnknownMethod(s.to_string()))
    }
}

/// Parameters of the methods; each method reads only its own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Power-heuristic exponent β (default 2).
    pub beta: f64,
    /// Cutoff-heuristic threshold c ∈ [0, 1] (default 0.5).
    pub cutoff: f64,
    /// Ridge λ of the optimal solve, `μ = (λ/N)·tr(Â)/T` after N iterations
    /// ([`crate::linalg::relative_ridge`]); `None`: the method's own,
    /// [`Method::default_ridge`].
    pub ridge: Option<f64>,
    /// Balance-only iterations before the progressive estimator's first solve; it then
    /// re-solves at N = W, 2W, 4W, … (default [`DEFAULT_WARMUP`]).
    pub warmup: u64,
    /// Training iterations of the full-weights estimator before α is solved once and fixed
    /// (default [`DEFAULT_TRAIN`]).
    pub train: u64,
}

/// Default ridge λ, `μ = (λ/N)·tr(Â)/T`, of the direct and progressive estimators; chosen
/// by the measurements in `docs/mis.md`.
pub const DEFAULT_RIDGE: f64 = 0.1;

/// Default ridge λ of the uncorrelated estimator. At λ = 0.1 it was 2.5–6× worse than
/// balance at N = 2–4 on the small-sample problems of `docs/mis.md`; at λ = 1 within
/// 1.16× at every N and 0.50–0.85× at N = 64.
pub const DEFAULT_RIDGE_UNCORRELATED: f64 = 1.0;

/// Default warm-up W of the progressive estimator (docs/mis.md: with the decaying ridge, a
/// solve after the very first iteration is already better than balance).
pub const DEFAULT_WARMUP: u64 = 1;

/// Default training iterations of the full-weights estimator (docs/mis.md).
pub const DEFAULT_TRAIN: u64 = 8;

impl Default for Params {
    fn default() -> Params {
        Params {
            beta: 2.0,
            cutoff: 0.5,
            ridge: None,
            warmup: DEFAULT_WARMUP,
            train: DEFAULT_TRAIN,
        }
    }
}

impl Params {
    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<(), ParamError> {
        Heuristic::Power { beta: self.beta }.validate()?;
        Heuristic::Cutoff { c: self.cutoff }.validate()?;
        match self.ridge {
            Some(r) if !(r >= 0.0 && r.is_finite()) => Err(ParamError::Ridge(r)),
            _ => Ok(()),
        }
    }

    /// The ridge `method` runs with: the given one, else the method's default.
    pub fn ridge_for(&self, method: Method) -> f64 {
        self.ridge.unwrap_or(method.default_ridge())
    }

    /// These parameters with the ridge made explicit for `method`, so that two equal
    /// configurations compare (and serialise) equal however they were written.
    pub fn resolved(&self, method: Method) -> Params {
        Params {
            ridge: Some(self.ridge_for(method)),
            ..*self
        }
    }
}

/// Any of the estimators, chosen at run time ([`Method::build`]); dispatches [`Estimator`].
#[derive(Clone, Debug)]
pub enum AnyEstimator {
    /// A heuristic (balance, power, maximum, cutoff).
    Weighted(Weighted),
    /// Optimal, direct.
    Direct(Direct),
    /// Optimal, uncorrelated.
    Uncorrelated(Uncorrelated),
    /// Optimal, progressive or full weights.
    Progressive(Progressive),
}

macro_rules! dispatch {
    ($self:expr, $e:ident => $body:expr) => {
        match $self {
            AnyEstimator::Weighted($e) => $body,
            AnyEstimator::Direct($e) => $body,
            AnyEstimator::Uncorrelated($e) => $body,
            AnyEstimator::Progressive($e) => $body,
        }
    };
}

impl Estimator for AnyEstimator {
    fn layout(&self) -> &Layout {
        dispatch!(self, e => e.layout())
    }
    #[inline]
    fn add_sample(&mut self, technique: usize, f: &[f64], pdfs: &[f64]) {
        dispatch!(self, e => e.add_sample(technique, f, pdfs))
    }
    fn add_failed(&mut self, technique: usize) {
        dispatch!(self, e => e.add_failed(technique))
    }
    fn end_iteration(&mut self) {
        dispatch!(self, e => e.end_iteration())
    }
    fn iterations(&self) -> u64 {
        dispatch!(self, e => e.iterations())
    }
    fn estimate(&self, out: &mut [f64]) {
        dispatch!(self, e => e.estimate(out))
    }
    fn merge(&mut self, other: &AnyEstimator) {
        match (self, other) {
            (AnyEstimator::Weighted(a), AnyEstimator::Weighted(b)) => a.merge(b),
            (AnyEstimator::Direct(a), AnyEstimator::Direct(b)) => a.merge(b),
            (AnyEstimator::Uncorrelated(a), AnyEstimator::Uncorrelated(b)) => a.merge(b),
            (AnyEstimator::Progressive(a), AnyEstimator::Progressive(b)) => a.merge(b),
            _ => panic!("cannot merge estimators of different methods"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_errors_list_every_name() {
        for m in Method::ALL {
            assert_eq!(m.name().parse::<Method>(), Ok(m));
            assert_eq!(m.to_string().to_uppercase().parse::<Method>(), Ok(m));
        }
        assert_eq!(
            "optimal_direct".parse::<Method>(),
            Ok(Method::OptimalDirect)
        );
        let err = "optimal".parse::<Method>().unwrap_err().to_string();
        for m in Method::ALL {
            assert!(err.contains(m.name()), "{err}");
        }
    }

    #[test]
    fn build_checks_parameters() {
        let layout = Layout::new(&[1, 1], 1);
        let bad = Params {
            ridge: Some(-1.0),
            ..Params::default()
        };
        assert!(Method::OptimalDirect.build(&layout, &bad).is_err());
        let bad = Params {
            beta: 0.0,
            ..Params::default()
        };
        assert!(Method::Balance.build(&layout, &bad).is_err());
        for m in Method::ALL {
            let e = m.build(&layout, &Params::default()).unwrap();
            assert_eq!(e.iterations(), 0);
            assert_eq!(e.estimate_vec(), vec![0.0]);
        }
    }

    #[test]
    #[should_panic(expected = "different methods")]
    fn merging_different_methods_panics() {
        let layout = Layout::new(&[1], 1);
        let mut a = Method::Balance.build(&layout, &Params::default()).unwrap();
        let b = Method::OptimalDirect
            .build(&layout, &Params::default())
            .unwrap();
        a.merge(&b);
    }
}
