//! Nothing to build: the crate's build-dependencies only unify features with the
//! workspace's build (Cargo.toml).
fn main() {}
