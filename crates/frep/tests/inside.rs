//! `Solid::inside`, which evaluates nothing outside a node's bounds: on CSG models of
//! every kind of node (unions, differences, intersections of quadrics and expressions),
//! it equals F ≥ 0 inside the solid's bounds at random points in and around them.

use crate::common;

use common::{read_file, root, Rng, SeedableRng};
use frep::solid::Solid;
use frep::{Aabb, Surface};
use glam::DVec3;

#[test]
fn inside_is_the_sign_of_f() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    for m in [
        "scenes/models/table.frep",
        "models/examples/machined_part.frep",
        "models/examples/bumpy_ball.frep",
        "models/canonical/s2_csg.hf",
    ] {
        let model = read_file(&root().join(m)).unwrap_or_else(|e| panic!("{m}: {e}"));
        let solid = Solid::build(&model.shape).unwrap();
        let b = solid.bounds();
        let pad = 1e-9 * (1.0 + b.extent().max_element());
        let within = Aabb::new(b.lo - pad, b.hi + pad);
        let mut counts = [0usize; 2];
        for _ in 0..40_000 {
            let u = DVec3::new(rng.gen(), rng.gen(), rng.gen());
            let p = b.lo + (b.hi - b.lo) * (u * 1.2 - 0.1);
            let want = within.contains(p) && solid.value(p) >= 0.0;
            assert_eq!(solid.inside(p), want, "{m} at {p:?}");
            counts[usize::from(want)] += 1;
        }
        println!("{m}: {counts:?} points outside, inside");
        assert!(counts[1] > 1_000 && counts[0] > 1_000, "{m}: {counts:?}");
    }
}
