//! Triangle mesh files: Wavefront OBJ (read here, so that errors name the line and
//! column) and PLY, ASCII or binary (through the `ply-rs-bw` crate).
//!
//! OBJ: `v`, `vt` and `vn` statements and `f` faces of any number of corners (fanned
//! into triangles), each corner `v`, `v/vt`, `v//vn` or `v/vt/vn`, 1-based or negative
//! (counted back from the last vertex); other statements (groups, materials, lines)
//! are skipped. PLY: the `vertex` element's `x y z` (and `nx ny nz`, `u v` or `s t`
//! where present) and the `face` element's `vertex_indices` (or `vertex_index`) lists.

use super::ReadError;
use crate::triangles::Triangles;
use glam::{DVec2, DVec3};
use std::collections::HashMap;
use std::path::Path;

/// The largest mesh file read: 1 GiB.
pub const MAX_MESH_BYTES: u64 = 1 << 30;

/// Whether a file extension names a mesh format (`obj`, `ply`; any case).
pub fn is_mesh_extension(ext: &str) -> bool {
    matches!(ext.to_ascii_lowercase().as_str(), "obj" | "ply")
}

/// Reads an OBJ or PLY file, by its extension.
pub fn read_mesh(path: &Path) -> Result<Triangles, ReadError> {
    let file = path.display().to_string();
    let whole = |m: String| ReadError::at(&file, 0, 0, m);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let meta = std::fs::metadata(path).map_err(|e| whole(format!("cannot read the file: {e}")))?;
    if !meta.is_file() {
        return Err(whole(
            "expected a mesh file, found a folder, device or pipe".into(),
        ));
    }
    if meta.len() > MAX_MESH_BYTES {
        return Err(whole(format!(
            "the file is {} bytes, more than the {MAX_MESH_BYTES} a mesh file may have",
            meta.len()
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| whole(format!("cannot read the file: {e}")))?;
    match ext.as_deref() {
        Some("obj") => {
            let text = String::from_utf8_lossy(&bytes);
            read_obj(&text, &file)
        }
        Some("ply") => read_ply(&bytes, &file),
        _ => Err(whole("expected a file ending in .obj or .ply".into())),
    }
}

/// Reads OBJ text; `file` names it in errors.
pub fn read_obj(text: &str, file: &str) -> Result<Triangles, ReadError> {
    let (mut v, mut vt, mut vn) = (Vec::new(), Vec::new(), Vec::new());
    // Corners as (v, vt, vn) indices (0-based; vt, vn may be absent), unified into one
    // vertex per distinct triple.
    let mut corners: HashMap<(usize, Option<usize>, Option<usize>), u32> = HashMap::new();
    let mut order: Vec<(usize, Option<usize>, Option<usize>)> = Vec::new();
    let mut indices: Vec<[u32; 3]> = Vec::new();
    for (l, line) in text.lines().enumerate() {
        let line_no = l + 1;
        let code = line.split('#').next().unwrap_or("");
        let mut words = words(code);
        let Some((_, head)) = words.next() else {
            continue;
        };
        let err = |col: usize, m: String| ReadError::at(file, line_no, col + 1, m);
        let mut numbers = |n: usize, what: &str| -> Result<Vec<f64>, ReadError> {
            let mut out = Vec::with_capacity(n);
            for k in 0..n {
                let (col, w) = words.next().ok_or_else(|| {
                    err(
                        code.trim_end().len(),
                        format!("expected {n} numbers after {what}, found {k}"),
                    )
                })?;
                let x: f64 = w
                    .parse()
                    .map_err(|_| err(col, format!("expected a number, found {w:?}")))?;
                if !x.is_finite() {
                    return Err(err(col, format!("expected a finite number, found {w:?}")));
                }
                out.push(x);
            }
            Ok(out)
        };
        match head {
            "v" => {
                let p = numbers(3, "v")?;
                v.push(DVec3::new(p[0], p[1], p[2]));
            }
            "vn" => {
                let p = numbers(3, "vn")?;
                vn.push(DVec3::new(p[0], p[1], p[2]));
            }
            "vt" => {
                let p = numbers(1, "vt")?;
                let second = words
                    .next()
                    .and_then(|(_, w)| w.parse().ok())
                    .unwrap_or(0.0);
                vt.push(DVec2::new(p[0], second));
            }
            "f" => {
                let mut face = Vec::new();
                for (col, w) in words {
                    let mut parts = w.split('/');
                    let index = |s: Option<&str>,
                                 len: usize,
                                 what: &str|
                     -> Result<Option<usize>, ReadError> {
                        let Some(s) = s.filter(|s| !s.is_empty()) else {
                            return Ok(None);
                        };
                        let i: i64 = s.parse().map_err(|_| {
                            err(col, format!("expected a {what} index, found {s:?}"))
                        })?;
                        let k = match i {
                            1.. => i - 1,
                            ..=-1 => len as i64 + i,
                            0 => -1,
                        };
                        if k < 0 || k >= len as i64 {
                            return Err(err(
                                col,
                                format!("{what} index {i} names none of the {len} {what}s so far"),
                            ));
                        }
                        Ok(Some(k as usize))
                    };
                    let pv = index(parts.next(), v.len(), "vertex")?
                        .ok_or_else(|| err(col, format!("expected a vertex index, found {w:?}")))?;
                    let pt = index(parts.next(), vt.len(), "texture coordinate")?;
                    let pn = index(parts.next(), vn.len(), "normal")?;
                    let key = (pv, pt, pn);
                    let id = *corners.entry(key).or_insert_with(|| {
                        order.push(key);
                        (order.len() - 1) as u32
                    });
                    face.push(id);
                }
                if face.len() < 3 {
                    return Err(err(
                        0,
                        format!("a face needs 3 corners or more, found {}", face.len()),
                    ));
                }
                for k in 1..face.len() - 1 {
                    indices.push([face[0], face[k], face[k + 1]]);
                }
                if indices.len() > crate::triangles::MAX_TRIANGLES {
                    return Err(err(0, "too many triangles".into()));
                }
            }
            _ => {}
        }
    }
    // Normals and texture coordinates only where every corner has them.
    let all_t = order.iter().all(|c| c.1.is_some());
    let all_n = order.iter().all(|c| c.2.is_some());
    let positions = order.iter().map(|c| v[c.0]).collect();
    let uvs = match all_t {
        true => order.iter().map(|c| vt[c.1.unwrap_or(0)]).collect(),
        false => Vec::new(),
    };
    let normals = match all_n {
        true => order.iter().map(|c| vn[c.2.unwrap_or(0)]).collect(),
        false => Vec::new(),
    };
    Triangles::new(positions, normals, uvs, indices).map_err(|m| ReadError::at(file, 0, 0, m))
}

/// The whitespace-separated words of a line, with their 0-based character columns.
fn words(line: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut col = 0;
    line.split(' ')
        .flat_map(|w| w.split('\t'))
        .filter_map(move |w| {
            let at = col;
            col += w.chars().count() + 1;
            let w = w.trim_matches('\r');
            (!w.is_empty()).then_some((at, w))
        })
}

/// Reads PLY bytes (ASCII or binary); `file` names it in errors.
pub fn read_ply(bytes: &[u8], file: &str) -> Result<Triangles, ReadError> {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Property};
    let whole = |m: String| ReadError::at(file, 0, 0, m);
    let parser = Parser::<DefaultElement>::new();
    let ply = std::panic::catch_unwind(|| parser.read_ply(&mut &bytes[..]))
        .map_err(|_| whole("the PLY reader failed on this file".into()))?
        .map_err(|e| match e.line() {
            // An ASCII file's line (the column is not known: its first).
            Some(line) => ReadError::at(file, line, 1, format!("not a readable PLY file ({e})")),
            None => whole(format!("not a readable PLY file ({e})")),
        })?;
    // In an ASCII file, element k of the body is on line `header + k + 1`: where the
    // checks below find a bad face, they can say where.
    let header_lines = match ply.header.encoding {
        ply_rs_bw::ply::Encoding::Ascii => bytes
            .split(|&b| b == b'\n')
            .position(|l| l.starts_with(b"end_header"))
            .map(|i| i + 1),
        _ => None,
    };
    let vertex_count = ply.payload.get("vertex").map_or(0, Vec::len);
    let face_at = |k: usize, m: String| match header_lines {
        Some(h) => ReadError::at(file, h + vertex_count + k + 1, 1, m),
        None => whole(m),
    };
    let scalar = |p: &Property| -> Option<f64> {
        Some(match *p {
            Property::Char(x) => x.into(),
            Property::UChar(x) => x.into(),
            Property::Short(x) => x.into(),
            Property::UShort(x) => x.into(),
            Property::Int(x) => x.into(),
            Property::UInt(x) => x.into(),
            Property::Float(x) => x.into(),
            Property::Double(x) => x,
            _ => return None,
        })
    };
    let vertices = ply
        .payload
        .get("vertex")
        .ok_or_else(|| whole("expected a vertex element".into()))?;
    let get =
        |e: &DefaultElement, names: &[&str]| names.iter().find_map(|n| e.get(*n).and_then(scalar));
    let mut positions = Vec::with_capacity(vertices.len());
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    for (k, e) in vertices.iter().enumerate() {
        let c = |n: &str| {
            get(e, &[n]).ok_or_else(|| whole(format!("vertex {} has no number {n}", k + 1)))
        };
        positions.push(DVec3::new(c("x")?, c("y")?, c("z")?));
        if let (Some(x), Some(y), Some(z)) = (get(e, &["nx"]), get(e, &["ny"]), get(e, &["nz"])) {
            normals.push(DVec3::new(x, y, z));
        }
        if let (Some(u), Some(v)) = (
            get(e, &["u", "s", "texture_u"]),
            get(e, &["v", "t", "texture_v"]),
        ) {
            uvs.push(DVec2::new(u, v));
        }
    }
    let faces = ply
        .payload
        .get("face")
        .ok_or_else(|| whole("expected a face element".into()))?;
    let mut indices = Vec::new();
    for (k, e) in faces.iter().enumerate() {
        let list: Vec<i64> = match e.get("vertex_indices").or_else(|| e.get("vertex_index")) {
            Some(Property::ListChar(v)) => v.iter().map(|&x| x.into()).collect(),
            Some(Property::ListUChar(v)) => v.iter().map(|&x| x.into()).collect(),
            Some(Property::ListShort(v)) => v.iter().map(|&x| x.into()).collect(),
            Some(Property::ListUShort(v)) => v.iter().map(|&x| x.into()).collect(),
            Some(Property::ListInt(v)) => v.iter().map(|&x| x.into()).collect(),
            Some(Property::ListUInt(v)) => v.iter().map(|&x| x.into()).collect(),
            _ => {
                return Err(face_at(
                    k,
                    format!("face {} has no integer list vertex_indices", k + 1),
                ))
            }
        };
        if list.len() < 3 {
            return Err(face_at(
                k,
                format!(
                    "face {} has {} corners; a face needs 3 or more",
                    k + 1,
                    list.len()
                ),
            ));
        }
        if let Some(i) = list.iter().find(|&&i| i < 0 || i >= positions.len() as i64) {
            return Err(face_at(
                k,
                format!("face {} names vertex {i} of {}", k + 1, positions.len()),
            ));
        }
        for j in 1..list.len() - 1 {
            indices.push([list[0], list[j], list[j + 1]].map(|i| i as u32));
        }
    }
    Triangles::new(positions, normals, uvs, indices).map_err(whole)
}
