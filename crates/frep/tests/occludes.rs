//! `Solid::occludes` (a shadow ray's question) answers as `Solid::intersect(..).is_some()`
//! on every ray: expression solids searched by intervals (with and without an occupancy
//! grid) and in Bernstein form, a perturbed quadric and CSG, from three eyes and over
//! sub-ranges of each ray, so that rays starting and ending inside solids count too.

mod common;

use common::{read_file, root, shared};
use frep::solid::Solid;
use frep::Surface;

#[test]
fn occludes_is_whether_intersect_hits() {
    let models = [
        root().join("models/canonical/s3_blend.hf"),
        root().join("models/canonical/s4_gyroid.hf"),
        root().join("models/examples/bumpy_ball.frep"),
        root().join("scenes/models/table.frep"),
        shared("fidget/tanglecube.vm"),
        shared("fidget/quarter.vm"),
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
