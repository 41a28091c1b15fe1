//! Textured roughness: every pixel of a floor whose GGX α is a checker of two values
//! equals, bit for bit, the render with one of the two constant α (pixels inside a
//! cell), for a conductor, a dielectric and a plastic (whose α on a 1/32 grid keeps its
//! tabulated coat exact); malformed roughness is a located error.

use crate::common::{options, run, MIX};
use mis::Method;
use render::integrator::IntegratorKind;
use render::scene::{parse_scene, Scene, SceneFormat};
use std::path::Path;

fn floor(material: &str, roughness: &str) -> Scene {
    let text = format!(
        r#"
camera = {{ eye = [0.3, 0.2, 2], target = [0.3, 0.2, 0], up = [0, 1, 0], fov = 70, resolution = [16, 16] }}
materials.floor = {{ {material}, roughness = {roughness} }}
objects = [{{ solid = "box(center = [0, 0, -0.5], size = [8, 8, 1])", material = "floor" }}]
lights = [{{ type = "sphere", center = [0.5, -0.8, 1.5], radius = 0.3, power = 60 }}]
"#
    );
    parse_scene(&text, SceneFormat::Toml, Path::new("r.toml"))
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

#[test]
fn a_checker_of_roughness_is_each_roughness_in_its_cells() {
    for (material, a, b) in [
        (r#"type = "conductor", metal = "gold""#, 0.1, 0.5),
        (r#"type = "dielectric", eta = 1.5"#, 0.05, 0.4),
        (r#"type = "plastic", diffuse = [0.6, 0.3, 0.2]"#, 0.125, 0.5),
    ] {
        let o = options(IntegratorKind::Direct, Method::Balance, &MIX, 8, 5);
        let render = |roughness: &str| run(&floor(material, roughness), &o).0;
        let (ia, ib) = (render(&a.to_string()), render(&b.to_string()));
        let mixed = render(&format!(
            "{{ checker = {{ a = {a}, b = {b}, scale = 1 }} }}"
        ));
        let (mut na, mut nb) = (0, 0);
        for y in 0..16 {
            for x in 0..16 {
                let p = mixed.rgb(x, y);
                na += usize::from(p == ia.rgb(x, y));
                nb += usize::from(p == ib.rgb(x, y));
            }
        }
        println!("{material}: {na} pixels as α = {a}, {nb} as α = {b}, of 256");
        // The view spans about 2.8 × 2.8 units: four cells or more, edges crossing some
        // pixels.
        assert!(na >= 32 && nb >= 32, "{material}: {na} {nb}");
        assert!(na + nb >= 192, "{material}: {na} {nb}");
    }
}

#[test]
fn malformed_roughness_is_located() {
    let err = |r: &str| {
        let text = format!(
            "camera = {{ eye = [0, 0, 2], target = [0, 0, 0], up = [0, 1, 0] }}\n\
             materials.m = {{ type = \"conductor\", metal = \"gold\", roughness = {r} }}\n"
        );
        parse_scene(&text, SceneFormat::Toml, Path::new("r.toml"))
            .err()
            .expect("an error")
    };
    let e = err("[0.1, 0.2, 0.3]");
    assert_eq!(
        (e.line, e.key.as_str()),
        (2, "materials.m.roughness"),
        "{e}"
    );
    assert!(e.message.contains("one number"), "{e}");
    let e = err("{ image = { file = \"r.png\" } }");
    assert!(e.message.contains("not an image"), "{e}");
    let e = err("{ pattern = { kind = \"noise\", a = 0, b = 2 } }");
    assert!(e.key.starts_with("materials.m.roughness"), "{e}");
}
