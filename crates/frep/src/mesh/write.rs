//! Mesh files: Wavefront OBJ (text, shared vertices) and binary STL (what 3-D printing
//! software reads: one facet normal and three f32 vertices per triangle).

use super::Mesh;
use glam::DVec3;
use std::io::{self, Write};

/// Writes `mesh` as OBJ: a comment, `v x y z` per vertex (shortest round-trip form),
/// `f a b c` per triangle (1-based, counter-clockwise from outside).
pub fn obj(mesh: &Mesh, w: &mut dyn Write) -> io::Result<()> {
    let mut w = io::BufWriter::new(w);
    writeln!(
        w,
        "# frepray mesh: {} vertices, {} triangles",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    for v in &mesh.vertices {
        writeln!(w, "v {} {} {}", v[0], v[1], v[2])?;
    }
    for t in &mesh.triangles {
        writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    w.flush()
}

/// Writes `mesh` as binary STL: an 80-byte header, the triangle count, then per
/// triangle its unit normal, three vertices (f32, little-endian) and 2 zero bytes.
pub fn stl(mesh: &Mesh, w: &mut dyn Write) -> io::Result<()> {
    let count = u32::try_from(mesh.triangles.len())
        .map_err(|_| io::Error::other("more triangles than binary STL can count"))?;
    let mut w = io::BufWriter::new(w);
    let mut header = [b' '; 80];
    let title = b"frepray mesh (binary STL)";
    header[..title.len()].copy_from_slice(title);
    w.write_all(&header)?;
    w.write_all(&count.to_le_bytes())?;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| DVec3::from(mesh.vertices[i as usize]));
        let n = (b - a).cross(c - a).normalize_or_zero();
        for v in [n, a, b, c] {
            for x in v.to_array() {
                w.write_all(&(x as f32).to_le_bytes())?;
            }
        }
        w.write_all(&[0, 0])?;
    }
    w.flush()
}
