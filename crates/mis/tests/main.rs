//! The mis crate's integration tests in one binary (one link instead of 3; the
//! tests of every module run in parallel).
//! `no_alloc` stays apart: it counts the allocations of the whole process.

mod common;
mod heuristics;
mod optimal;
mod robustness;
