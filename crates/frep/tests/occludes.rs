//! `Solid::occludes` (a shadow ray's question) answers as `Solid::intersect(..).is_some()`
//! on every ray: expression solids searched by intervals (with and without an occupancy
//! grid) and in Bernstein form, a perturbed quadric and CSG, from three eyes and over
//! sub-ranges of each ray, so that rays starting and ending inside solids count too.

use crate::common;

use common::{model_file, read_file, root};
use frep::solid::Solid;
use frep::Surface;

#[test]
fn occludes_is_whether_intersect_hits() {
    let models = [
        root().join("models/canonical/s3_blend.hf"),
        root().join("models/canonical/s4_gyroid.hf"),
        root().join("models/examples/bumpy_ball.frep"),
        root().join("scenes/models/table.frep"),
        root().join("models/examples/machined_part.frep"),
        model_file("fidget/tanglecube.vm"),
        model_file("fidget/quarter.vm"),
    ];
    for m in &models {
        let model = read_file(m).unwrap_or_else(|e| panic!("{}: {e}", m.display()));
        let solid = Solid::build(&model.shape).unwrap();
        let b = solid.bounds();
        let size = b.extent().length();
        let (mut hits, mut rays) = (0, 0);
        for ray in common::eye_rays(&b) {
            let far = 4.0 * size / ray.d.length();
            // The whole ray, and stretches of it that start and end anywhere.
            for (k, (t0, t1)) in [(0.0, far), (0.3, 0.55), (0.45, 0.7), (0.5, 0.52)]
                .into_iter()
                .enumerate()
            {
                let (t0, t1) = if k == 0 {
                    (t0, t1)
                } else {
                    (t0 * far, t1 * far)
                };
                let want = solid.intersect(&ray, t0, t1).is_some();
                assert_eq!(
                    solid.occludes(&ray, t0, t1),
                    want,
                    "{}: {ray:?} in ({t0}, {t1})",
                    m.display()
                );
                hits += usize::from(want);
                rays += 1;
            }
        }
        println!("{}: {hits} of {rays} ray ranges hit", m.display());
        assert!(
            hits > 200 && hits + 200 < rays,
            "{}: {hits} of {rays}",
            m.display()
        );
    }
}

/// CSG where a shadow ray starts inside a part: overlapping unions and differences
/// (of quadrics, of an expression and a quadric, nested), rays from random points in the
/// bounds over random lengths, so that many cross one part's boundary inside another
/// (the union is not crossed there) or start inside the part a difference removes.
/// `occludes` equals `intersect(..).is_some()` on every one.
#[test]
fn occludes_agrees_where_rays_start_inside_csg_parts() {
    use common::{read_str, Format, Rng, SeedableRng};
    use glam::DVec3;
    let texts = [
        "output union(sphere([0, 0, 0], 1), sphere([0.8, 0, 0], 0.7), sphere([0, 0.9, 0], 0.5))",
        "output difference(sphere([0, 0, 0], 1), sphere([0.6, 0.3, 0], 0.6))",
        "output union(difference(sphere([0, 0, 0], 1), sphere([0, 0, 0.8], 0.5)), \
         r_union(sphere([0.9, 0, 0], 0.4), sphere([1.2, 0, 0], 0.4)))",
        "output difference(union(sphere([0, 0, 0], 1), sphere([0, 0, 1], 0.6)), \
         sphere([0, 0, 0.5], 0.5), sphere([0.9, 0, 0], 0.3))",
    ];
    let mut rng = rand_pcg::Pcg64::seed_from_u64(77);
    for text in texts {
        let model = read_str(text, Format::Frep, "t.frep").unwrap();
        let solid = Solid::build(&model.shape).unwrap();
        let b = solid.bounds();
        let (mut hits, mut inside) = (0, 0);
        for k in 0..4000 {
            let o = DVec3::new(
                rng.gen_range(b.lo.x..b.hi.x),
                rng.gen_range(b.lo.y..b.hi.y),
                rng.gen_range(b.lo.z..b.hi.z),
            );
            let d = DVec3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            );
            let ray = frep::Ray::new(o, d);
            let t1 = rng.gen_range(0.0..2.0);
            let want = solid.intersect(&ray, 0.0, t1).is_some();
            assert_eq!(
                solid.occludes(&ray, 0.0, t1),
                want,
                "{text}: ray {k} {ray:?} to {t1}"
            );
            hits += usize::from(want);
            inside += usize::from(solid.inside(o));
        }
        assert!(
            hits > 500 && inside > 500,
            "{text}: {hits} hits, {inside} from inside"
        );
    }
}
