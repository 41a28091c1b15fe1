//! Triangle meshes (`frep::triangles`) and their files (`frep::read::read_obj`,
//! `read_ply`): the crossings of a meshed box equal the box solid's, normals face out,
//! transforms keep fronts, and malformed files are located errors.

use crate::common::*;
use frep::read::{read_obj, read_ply};
use frep::triangles::Triangles;
use frep::{Affine, Ray, Solid};
use glam::DVec3;

/// The cube [-1, 1]³ as OBJ: 8 vertices, 6 quads wound counter-clockwise from outside
/// (negative indices on the last face).
const CUBE_OBJ: &str = "# a cube
o cube
v -1 -1 -1
v  1 -1 -1
v  1  1 -1
v -1  1 -1
v -1 -1  1
v  1 -1  1
v  1  1  1
v -1  1  1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f -4 -1 -5 -8
";

fn cube_ply_ascii() -> String {
    let mut s = String::from(
        "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n\
         property float z\nelement face 6\nproperty list uchar int vertex_indices\nend_header\n",
    );
    for l in CUBE_OBJ.lines().filter_map(|l| l.strip_prefix("v ")) {
        s.push_str(l.trim());
        s.push('\n');
    }
    for f in [
        "0 3 2 1", "4 5 6 7", "0 1 5 4", "1 2 6 5", "2 3 7 6", "4 7 3 0",
    ] {
        s.push_str(&format!("4 {f}\n"));
    }
    s
}

fn box_solid() -> Solid {
    let b = frep::csg::box_tree(&frep::Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)));
    Solid::build(&Shape::function(b)).unwrap()
}

/// Random rays from outside: the mesh's first crossing is the box solid's (t and
/// outward normal), and shadow queries agree.
#[test]
fn a_meshed_cube_crosses_rays_as_the_box_does() {
    let solid = box_solid();
    for mesh in [
        read_obj(CUBE_OBJ, "cube.obj").unwrap(),
        read_ply(cube_ply_ascii().as_bytes(), "cube.ply").unwrap(),
    ] {
        assert_eq!(mesh.len(), 12);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let mut hits = 0;
        for _ in 0..2000 {
            let o = DVec3::new(rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0), 3.5);
            let target = DVec3::new(
                rng.gen_range(-1.5..1.5),
                rng.gen_range(-1.5..1.5),
                rng.gen_range(-1.5..1.5),
            );
            let ray = Ray::new(o, (target - o).normalize());
            let (m, s) = (
                mesh.intersect(&ray, 0.0, 100.0),
                solid.intersect(&ray, 0.0, 100.0),
            );
            assert_eq!(m.is_some(), s.is_some(), "{ray:?}");
            if let (Some(m), Some(s)) = (m, s) {
                hits += 1;
                assert!((m.t - s.t).abs() < 1e-9, "{} vs {}", m.t, s.t);
                assert!(
                    m.normal.distance(s.normal) < 1e-9,
                    "{} vs {}",
                    m.normal,
                    s.normal
                );
            }
            assert_eq!(mesh.occludes(&ray, 0.0, 100.0), m.is_some());
            assert!(!mesh.occludes(&ray, 0.0, m.map_or(100.0, |h| h.t) * (1.0 - 1e-9)));
        }
        assert!(hits > 500, "{hits}");
    }
}

/// A mirroring transform reverses the winding, so normals still face out; a singular
/// one is refused.
#[test]
fn transforms_keep_fronts_in_front() {
    let mesh = read_obj(CUBE_OBJ, "cube.obj").unwrap();
    let mirror = Affine::scale(DVec3::new(-2.0, 1.0, 1.0))
        .then(&Affine::translate(DVec3::new(0.0, 0.0, 5.0)));
    let moved = mesh.transformed(&mirror).unwrap();
    let ray = Ray::new(DVec3::new(-10.0, 0.2, 5.1), DVec3::X);
    let hit = moved.intersect(&ray, 0.0, 100.0).unwrap();
    assert!(
        (hit.t - 8.0).abs() < 1e-12 && hit.normal.distance(-DVec3::X) < 1e-12,
        "{hit:?}"
    );
    assert!(mesh
        .transformed(&Affine::scale(DVec3::new(1.0, 0.0, 1.0)))
        .is_none());
}

/// Vertex normals and texture coordinates are interpolated; normals say which side is
/// the front.
#[test]
fn normals_and_uvs_interpolate() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 -1\nvn 0 0 -1\nvn 0 0 -1\nf 1/1/1 2/2/2 3/3/3\n";
    let m = read_obj(obj, "tri.obj").unwrap();
    assert!(m.has_normals() && m.has_uvs());
    let h = m
        .intersect(&Ray::new(DVec3::new(0.25, 0.5, 1.0), -DVec3::Z), 0.0, 10.0)
        .unwrap();
    assert_eq!(h.normal, -DVec3::Z);
    assert!((h.uv - glam::DVec2::new(0.25, 0.5)).length() < 1e-12);
    assert!((h.t - 1.0).abs() < 1e-12);
}

/// Malformed OBJ and PLY files name the line and column (OBJ) and what was expected.
#[test]
fn malformed_mesh_files_are_located_errors() {
    let cases = [
        ("v 0 0 0\nv 1 0 x\n", (2, 7), "expected a number"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
            (4, 7),
            "vertex index 4",
        ),
        ("v 0 0 0\nv 1 0 0\nf 1 2\n", (3, 1), "3 corners or more"),
        ("v 0 0\n", (1, 6), "expected 3 numbers"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/2 3/3\n",
            (4, 3),
            "texture coordinate index 1",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 2 3\n",
            (4, 3),
            "vertex index 0",
        ),
    ];
    for (text, (line, column), want) in cases {
        let e = read_obj(text, "bad.obj").unwrap_err();
        assert_eq!((e.line, e.column), (line, column), "{e}");
        assert!(e.message.contains(want), "{e}");
    }
    let e = read_obj("# nothing\n", "empty.obj").unwrap_err();
    assert!(e.to_string().contains("no triangles"), "{e}");
    let e = read_ply(b"ply\nformat ascii 1.0\nelement vertex 1\n", "cut.ply").unwrap_err();
    assert!(
        e.to_string()
            .starts_with("cut.ply:4:1: not a readable PLY file"),
        "{e}"
    );
    let bad = cube_ply_ascii().replace("4 0 3 2 1", "4 0 3 2 9");
    let e = read_ply(bad.as_bytes(), "bad.ply").unwrap_err();
    assert!(e.to_string().contains("face 1 names vertex 9 of 8"), "{e}");
}

/// A binary little-endian PLY reads as its ASCII twin.
#[test]
fn binary_ply_reads_as_ascii() {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\n\
property double y\nproperty double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
        .to_vec();
    for p in [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in p {
            b.extend_from_slice(&x.to_le_bytes());
        }
    }
    b.push(3);
    for i in [0u32, 1, 2] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    let m = read_ply(&b, "tri.ply").unwrap();
    assert_eq!((m.len(), m.positions().len()), (1, 3));
    assert_eq!(m.triangle(0)[1], DVec3::X);
    let _: &Triangles = &m;
}

/// Garbage never panics either reader: 3 000 random texts built from OBJ's and PLY's
/// own words and bytes (a fixed seed) each read to a value or an error.
#[test]
fn garbage_is_an_error_never_a_panic() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(42);
    let words = [
        "v",
        "vt",
        "vn",
        "f",
        "1",
        "-1",
        "0",
        "2/3",
        "1//2",
        "-7/-1/2",
        "1e308",
        "nan",
        "\n",
        " ",
        "ply\n",
        "format ascii 1.0\n",
        "format binary_little_endian 1.0\n",
        "element vertex 3\n",
        "element face 1\n",
        "property float x\n",
        "property list uchar int vertex_indices\n",
        "end_header\n",
        "\u{ff}",
        "#",
    ];
    for _ in 0..3000 {
        let n = rng.gen_range(0..40);
        let text: String = (0..n)
            .map(|_| words[rng.gen_range(0..words.len())])
            .collect();
        let _ = read_obj(&text, "g.obj");
        let mut bytes = text.into_bytes();
        for _ in 0..rng.gen_range(0..8) {
            bytes.push(rng.gen());
        }
        let _ = read_ply(&bytes, "g.ply");
    }
}

/// An ASCII PLY's errors name the line: a malformed body line as the parser reports it,
/// a face naming a vertex that is not there at the face's own line.
#[test]
fn ascii_ply_errors_name_the_line() {
    let text = cube_ply_ascii();
    let header = text.lines().position(|l| l == "end_header").unwrap() + 1;
    let bad = text.replace("4 0 3 2 1", "4 0 3 2 9");
    let e = read_ply(bad.as_bytes(), "bad.ply").unwrap_err();
    // Face 1 follows the header and the 8 vertices.
    assert_eq!((e.line, e.column), (header + 8 + 1, 1), "{e}");
    let broken = text.replacen("-1 -1 -1", "-1 oops -1", 1);
    let e = read_ply(broken.as_bytes(), "broken.ply").unwrap_err();
    assert_eq!(e.line, header + 1, "{e}");
}
