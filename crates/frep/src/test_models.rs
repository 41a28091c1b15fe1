//! The repository's expression models, for the unit tests that compare two ways of
//! evaluating or searching them.

use crate::{Shape, Tree};

/// The expression models (each one tree): Fidget's five, the canonical HyperFun models
/// but the sphere, and the table scene's blob, named by path. Named, not listed from
/// the folders: a file added there must not change the tests.
pub(crate) fn expression_models() -> Vec<(&'static str, Tree)> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    [
        "models/fidget/colonnade.vm",
        "models/fidget/hi.vm",
        "models/fidget/prospero.vm",
        "models/fidget/quarter.vm",
        "models/fidget/tanglecube.vm",
        "models/canonical/s2_csg.hf",
        "models/canonical/s3_blend.hf",
        "models/canonical/s4_gyroid.hf",
        "models/canonical/s5_twist.hf",
        "scenes/models/blob.frep",
    ]
    .into_iter()
    .map(|m| {
        let model = crate::read::read_file(&root.join(m)).unwrap_or_else(|e| panic!("{m}: {e}"));
        match model.shape {
            Shape::Function { tree, .. } => (m, tree),
            _ => panic!("{m}: not one expression"),
        }
    })
    .collect()
}
