//! `min_depth`: a render of depth d alone (`min_depth = max_depth = d`), and the sum of
//! every depth's image is the image of all depths.

use crate::common;

use common::*;
use mis::Method;
use render::integrator::{IntegratorKind, RenderOptions};
use render::Technique;

/// On the ball on the floor (its lights visible to the camera, four vertices, roulette
/// from the second), the images of depths 0…4 rendered one at a time sum to the image of
/// `max_depth = 4`, pixel by pixel to 1e-9 relative, for heuristics and per-depth optimal
/// estimators alike; depths 1 and 2 each carry light (the check has power), and a depth
/// past `max_depth` is refused.
#[test]
fn per_depth_images_sum_to_the_full_image() {
    let scene = ball_on_floor(12);
    let techniques = [
        (Technique::Bsdf, 1),
        (Technique::LightPower, 1),
        (Technique::LightUniform, 1),
    ];
    for m in [
        Method::Balance,
        Method::Power,
        Method::OptimalDirect,
        Method::OptimalProgressive,
    ] {
        let full = RenderOptions {
            max_depth: 4,
            rr_depth: 2,
            ..options(IntegratorKind::Path, m, &techniques, 8, 31)
        };
        let (image, _) = run(&scene, &full);
        let depths: Vec<_> = (0..=4)
            .map(|d| {
                let o = RenderOptions {
                    min_depth: d,
                    max_depth: d,
                    ..full.clone()
                };
                run(&scene, &o).0
            })
            .collect();
        let mut energy = [0.0; 5];
        let mut worst: f64 = 0.0;
        for y in 0..12 {
            for x in 0..12 {
                let sum = depths
                    .iter()
                    .fold(render::Rgb::ZERO, |s, img| s + img.rgb(x, y));
                let want = image.rgb(x, y);
                let err = (sum - want).abs().max_element() / want.max_element().max(1e-3);
                worst = worst.max(err);
                for (e, img) in energy.iter_mut().zip(&depths) {
                    *e += img.rgb(x, y).max_element();
                }
            }
        }
        println!("{m}: per-depth energy {energy:.3?}, worst relative difference {worst:.2e}");
        assert!(worst < 1e-9, "{m}: {worst}");
        assert!(energy[1] > 0.0 && energy[2] > 0.0, "{m}: {energy:?}");
    }
    let too_deep = RenderOptions {
        min_depth: 5,
        max_depth: 4,
        ..options(IntegratorKind::Path, Method::Balance, &techniques, 1, 1)
    };
    let e = too_deep.validate().unwrap_err();
    assert_eq!(
        e,
        render::integrator::OptionsError::MinDepth {
            min_depth: 5,
            deepest: 4,
            integrator: IntegratorKind::Path
        }
    );
    assert!(e.to_string().contains("min_depth 5 exceeds"), "{e}");
    let direct = RenderOptions {
        min_depth: 2,
        ..options(IntegratorKind::Direct, Method::Balance, &techniques, 1, 1)
    };
    let e = direct.validate().unwrap_err();
    assert!(e.to_string().contains("direct shades one vertex"), "{e}");
}
