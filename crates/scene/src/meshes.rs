//! The resolved scene's triangle meshes (objects read from OBJ or PLY files), shared:
//! both back ends and every copy of the scene hold the same meshes.

use crate::check::transform;
use crate::data::MeshId;
use crate::desc::TransformDesc;
use crate::error::{SceneError, Seg};
use crate::locate::Source;
use frep::triangles::Triangles;
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};
use std::path::Path;
use std::sync::Arc;

/// The pool of meshes, one per mesh object (transforms folded in).
#[derive(Clone, Debug, Default)]
pub struct MeshPool {
    meshes: Vec<Arc<Triangles>>,
}

impl MeshPool {
    /// Adds a mesh; returns its id.
    pub fn push(&mut self, mesh: Triangles) -> MeshId {
        self.meshes.push(Arc::new(mesh));
        MeshId(self.meshes.len() as u32 - 1)
    }
    /// The mesh of `id`.
    pub fn mesh(&self, id: MeshId) -> &Arc<Triangles> {
        &self.meshes[id.index()]
    }
    /// Number of meshes.
    pub fn len(&self) -> usize {
        self.meshes.len()
    }
    /// Whether the pool is empty.
    pub fn is_empty(&self) -> bool {
        self.meshes.is_empty()
    }
}

/// Equal when the meshes hold the same vertices, attributes and triangles.
impl PartialEq for MeshPool {
    fn eq(&self, o: &Self) -> bool {
        self.meshes.len() == o.meshes.len()
            && self.meshes.iter().zip(&o.meshes).all(|(a, b)| {
                Arc::ptr_eq(a, b) || (a.positions() == b.positions() && a.indices() == b.indices())
            })
    }
}

/// The content hash of a mesh (FNV-1a 64 over its positions and triangles), which
/// stands for it in a resolved scene's JSON: a dump stays small, and the scene's hash
/// still changes with every vertex.
fn content_hash(m: &Triangles) -> u64 {
    let mut h = Fnv::default();
    for p in m.positions() {
        for x in p.to_array() {
            h.eat(&x.to_le_bytes());
        }
    }
    for t in m.indices() {
        for i in t {
            h.eat(&i.to_le_bytes());
        }
    }
    h.0
}

impl Serialize for MeshPool {
    /// Per mesh: its counts, whether it has normals and uvs, and its content hash.
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        struct One<'a>(&'a Triangles);
        impl Serialize for One<'_> {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                let m = self.0;
                let mut map = s.serialize_map(Some(5))?;
                map.serialize_entry("vertices", &m.positions().len())?;
                map.serialize_entry("triangles", &m.len())?;
                map.serialize_entry("normals", &m.has_normals())?;
                map.serialize_entry("uvs", &m.has_uvs())?;
                map.serialize_entry("content", &format!("{:016x}", content_hash(m)))?;
                map.end()
            }
        }
        s.collect_seq(self.meshes.iter().map(|m| One(m)))
    }
}

/// Reads the mesh file `file` (named at key `at`, relative to `base`) and moves it by
/// `t` (at key `tp`). A malformed file's error names its line and column and the
/// scene's key; a file that cannot be read at all is reported at the key.
pub(crate) fn read(
    src: &Source,
    base: &Path,
    at: &[Seg],
    file: &str,
    tp: &[Seg],
    t: Option<&TransformDesc>,
) -> Result<Triangles, SceneError> {
    let full = base.join(file);
    let m = frep::read::read_mesh(&full).map_err(|e| {
        let here = src.at_value(at, "");
        match e.line {
            0 => src.at_value(at, e.to_string()),
            _ => SceneError {
                file: e.file,
                line: e.line,
                column: e.column,
                key: here.key,
                message: format!(
                    "{} (mesh of {}:{}:{})",
                    e.message, here.file, here.line, here.column
                ),
            },
        }
    })?;
    match t {
        Some(t) => {
            let a = transform(src, tp, t)?;
            m.transformed(&a)
                .ok_or_else(|| src.at_value(tp, "the transform is singular (a zero scale)"))
        }
        None => Ok(m),
    }
}

/// FNV-1a 64, fed a piece at a time: the content hashes that stand for meshes and
/// images in a resolved scene's JSON.
pub(crate) struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Adds `bytes`.
    pub fn eat(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}
