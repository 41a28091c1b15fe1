//! A parameter of a heuristic or an estimator out of its range.

use std::fmt;

/// Which parameter is out of range, and its value ([`crate::Heuristic::validate`],
/// [`crate::Params::validate`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamError {
    /// The power heuristic's β is not finite and > 0.
    Beta(f64),
    /// The cutoff heuristic's c is not in [0, 1].
    Cutoff(f64),
    /// The ridge λ is not finite and ≥ 0.
    Ridge(f64),
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ParamError::Beta(b) => write!(f, "power heuristic needs a finite β > 0, got {b}"),
            ParamError::Cutoff(c) => write!(f, "cutoff heuristic needs c in [0, 1], got {c}"),
            ParamError::Ridge(r) => write!(f, "ridge λ must be finite and ≥ 0, got {r}"),
        }
    }
}

impl std::error::Error for ParamError {}
