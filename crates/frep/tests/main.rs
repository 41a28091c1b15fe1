//! The frep crate's integration tests in one binary (one link instead of 11; the
//! tests of every module run in parallel).
//! `no_alloc` stays apart: it counts the allocations of the whole process.

mod bytecode;
mod common;
mod csg_differential;
mod csg_unbounded;
mod inside;
mod mesh;
mod occludes;
mod occupancy;
mod perturbed_march;
mod poly_trace;
mod ray_tape;
mod read_frep;
mod read_hf;
mod read_vm;
mod triangles;
