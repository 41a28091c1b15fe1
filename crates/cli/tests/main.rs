//! The cli crate's integration tests in one binary (one link instead of 3; the
//! tests of every module run in parallel).

mod cli;
mod optimal_wins;
mod reliability;
