//! Meshes of solids (`frep::mesh`): closed and consistently oriented, of the right
//! topology and volume, their vertices on F = 0, and within a measured Hausdorff
//! distance of the exact surface that shrinks as the grid does.

use crate::common::*;
use frep::mesh::{self, Mesh, MeshError};
use frep::{Aabb, Ray, Solid, Surface};
use glam::DVec3;

fn ball(r: f64) -> Tree {
    r * r - (Tree::x().square() + Tree::y().square() + Tree::z().square())
}

/// The torus of radii `big` and `small` about z: (|p|² + R² − r²)² − 4R²(x² + y²) ≤ 0.
fn torus(big: f64, small: f64) -> Tree {
    let (x2, y2) = (Tree::x().square(), Tree::y().square());
    let s = x2.clone() + y2.clone() + Tree::z().square() + (big * big - small * small);
    4.0 * big * big * (x2 + y2) - s.square()
}

fn cube(r: f64) -> Aabb {
    Aabb::new(DVec3::splat(-r), DVec3::splat(r))
}

/// The closest point to `p` on triangle `abc` (Ericson, Real-Time Collision
/// Detection, §5.1.5).
fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

fn corners(m: &Mesh, t: &[u32; 3]) -> [DVec3; 3] {
    t.map(|i| DVec3::from(m.vertices[i as usize]))
}

/// The distance from `p` to the mesh (every triangle tried).
fn distance_to(m: &Mesh, p: DVec3) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = corners(m, t);
            closest_on_triangle(p, a, b, c).distance(p)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Points spread over every triangle (its corners, edge midpoints and centroid).
fn points_on(m: &Mesh) -> impl Iterator<Item = DVec3> + '_ {
    m.triangles.iter().flat_map(move |t| {
        let [a, b, c] = corners(m, t);
        [
            (a + b) * 0.5,
            (b + c) * 0.5,
            (c + a) * 0.5,
            (a + b + c) / 3.0,
        ]
    })
}

/// `n` points spread evenly over the unit sphere (a Fibonacci lattice).
fn fibonacci(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            DVec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// The unit ball's mesh is a closed, outward-facing sphere (Euler characteristic 2),
/// its vertices on the sphere to rounding; its one-sided Hausdorff distances both ways
/// (mesh points to the sphere, sphere points to the mesh) shrink about fourfold when
/// the grid's cubes halve, as the chords of a smooth surface do (second order).
#[test]
fn a_ball_meshes_to_a_closed_sphere_converging_at_second_order() {
    let f = Expr::new(&ball(1.0));
    let mut hausdorff = Vec::new();
    for res in [8, 16] {
        let m = mesh::mesh(&f, &cube(1.0), res).unwrap();
        assert!(m.is_watertight(), "resolution {res}");
        assert_eq!(m.euler_characteristic(), 2, "resolution {res}");
        for v in &m.vertices {
            assert!((DVec3::from(*v).length() - 1.0).abs() < 1e-12, "{v:?}");
        }
        let volume = 4.0 / 3.0 * std::f64::consts::PI;
        let h = 2.0 / f64::from(res);
        // Inscribed: a little less than the ball, by less than the chord height's share.
        assert!(
            m.volume() < volume && m.volume() > volume * (1.0 - h * h),
            "{}",
            m.volume()
        );
        let out = points_on(&m)
            .map(|p| (p.length() - 1.0).abs())
            .fold(0.0, f64::max);
        let back = fibonacci(400)
            .into_iter()
            .map(|p| distance_to(&m, p))
            .fold(0.0, f64::max);
        assert!(
            out < h * h && back < h * h,
            "res {res}: {out} {back}, h = {h}"
        );
        hausdorff.push(out.max(back));
    }
    let ratio = hausdorff[0] / hausdorff[1];
    assert!(ratio > 3.0, "Hausdorff {hausdorff:?}: ratio {ratio}");
}

/// A torus meshes to a closed surface of genus 1 (Euler characteristic 0) with the
/// torus's volume 2π²Rr² to within the grid's second-order error.
#[test]
fn a_torus_meshes_to_genus_one_with_its_volume() {
    let (big, small) = (1.0, 0.4);
    let f = Expr::new(&torus(big, small));
    let m = mesh::mesh(
        &f,
        &Aabb::new(DVec3::new(-1.4, -1.4, -0.4), DVec3::new(1.4, 1.4, 0.4)),
        40,
    )
    .unwrap();
    assert!(m.is_watertight());
    assert_eq!(m.euler_characteristic(), 0);
    let exact = 2.0 * std::f64::consts::PI.powi(2) * big * small * small;
    assert!(
        (m.volume() / exact - 1.0).abs() < 0.02,
        "{} vs {exact}",
        m.volume()
    );
}

/// A solid that reaches past the box is cut by it and closed (the box is padded by a
/// cube: a gyroid slab meshes closed), and the mesh does not depend on the threads.
#[test]
fn meshes_are_closed_at_the_box_and_independent_of_threads() {
    // A gyroid sheet clipped to a box by CSG, as `frepray mesh` does for unbounded models.
    let (x, y, z) = (Tree::x() * 3.0, Tree::y() * 3.0, Tree::z() * 3.0);
    let gyroid = x.sin() * y.cos() + y.sin() * z.cos() + z.sin() * x.cos();
    let sheet = 0.6 - gyroid.abs();
    let b = cube(1.5);
    let boxed = frep::csg::intersection(&sheet, &frep::csg::box_tree(&b));
    let f = Expr::new(&boxed);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    let a = one.install(|| mesh::mesh(&f, &b, 24).unwrap());
    let c = three.install(|| mesh::mesh(&f, &b, 24).unwrap());
    assert_eq!(a, c);
    assert!(a.is_watertight());
    assert!(a.triangles.len() > 1000);
    // Cut at the box: nothing past it.
    for v in &a.vertices {
        assert!(v.iter().all(|c| c.abs() <= 1.5 + 1e-9), "{v:?}");
    }
}

/// Real models: closed meshes whose vertices are on F = 0 (|F|/|∇F| tiny against the
/// cube), and every surface point the exact ray intersection finds lies within a cube's
/// diagonal of the mesh (nothing of the surface is missing).
#[test]
fn models_mesh_closed_and_cover_their_surface() {
    for (file, res) in [
        ("examples/bumpy_ball.frep", 40),
        ("fidget/tanglecube.vm", 32),
    ] {
        let model = read_file(&model_file(file)).unwrap();
        let solid = Solid::build(&model.shape).unwrap();
        let bounds = solid.bounds();
        let f = expr(&model);
        let m = mesh::mesh(&f, &bounds, res).unwrap();
        let h = bounds.extent().max_element() / f64::from(res);
        assert!(m.is_watertight(), "{file}");
        for v in &m.vertices {
            let (value, g) = f.gradient(*v);
            let step = value.abs() / DVec3::from(g).length();
            assert!(step < 1e-6 * h, "{file}: {v:?} is {step} from F = 0");
        }
        let centre = bounds.center();
        let far = bounds.extent().length();
        for d in fibonacci(150) {
            let ray = Ray::new(centre + d * far, -d);
            if let Some(hit) = solid.intersect(&ray, 0.0, 2.0 * far) {
                let p = ray.at(hit.t);
                let gap = distance_to(&m, p);
                assert!(
                    gap < 3f64.sqrt() * h,
                    "{file}: {p} is {gap} from the mesh (h = {h})"
                );
            }
        }
    }
}

/// Bad arguments are errors, not panics; a limit on the triangles is an error too.
#[test]
fn bad_arguments_are_errors() {
    let f = Expr::new(&ball(1.0));
    assert_eq!(mesh::mesh(&f, &cube(1.0), 0), Err(MeshError::Resolution(0)));
    assert_eq!(
        mesh::mesh(&f, &cube(1.0), mesh::MAX_RESOLUTION + 1),
        Err(MeshError::Resolution(mesh::MAX_RESOLUTION + 1))
    );
    let unbounded = Aabb::new(DVec3::splat(f64::NEG_INFINITY), DVec3::splat(f64::INFINITY));
    assert_eq!(mesh::mesh(&f, &unbounded, 8), Err(MeshError::Bounds));
    assert_eq!(
        mesh::mesh_limited(&f, &cube(1.0), 32, 100),
        Err(MeshError::TooLarge { limit: 100 })
    );
}

/// OBJ and STL hold what the mesh holds: OBJ's vertices read back exactly, STL's
/// triangle count, size and facet normals (pointing out of the ball).
#[test]
fn obj_and_stl_files() {
    let m = mesh::mesh(&Expr::new(&ball(1.0)), &cube(1.0), 6).unwrap();
    let mut obj = Vec::new();
    m.write_obj(&mut obj).unwrap();
    let text = String::from_utf8(obj).unwrap();
    let vs: Vec<[f64; 3]> = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(vs, m.vertices);
    assert_eq!(
        text.lines().filter(|l| l.starts_with("f ")).count(),
        m.triangles.len()
    );
    let mut stl = Vec::new();
    m.write_stl(&mut stl).unwrap();
    assert_eq!(stl.len(), 84 + 50 * m.triangles.len());
    assert_eq!(
        u32::from_le_bytes(stl[80..84].try_into().unwrap()) as usize,
        m.triangles.len()
    );
    let f32_at = |o: usize| f32::from_le_bytes(stl[o..o + 4].try_into().unwrap()) as f64;
    for k in 0..m.triangles.len() {
        let o = 84 + 50 * k;
        let n = DVec3::new(f32_at(o), f32_at(o + 4), f32_at(o + 8));
        let a = DVec3::new(f32_at(o + 12), f32_at(o + 16), f32_at(o + 20));
        // Zero for degenerate triangles (a vertex at a grid corner on the sphere).
        assert!(n.length() < 1e-6 || n.dot(a) > 0.0, "facet {k}: {n} at {a}");
    }
}
