//! Image textures in scenes: a PNG's sRGB values decode to linear, the image lands on a
//! floor by its planar projection, and a missing or unknown file is a located error.

use glam::DVec3;
use render::material::Material;
use render::scene::{parse_scene, SceneFormat};
use render::texture::TexCoord;
use render::Rgb;

const SCENE: &str = r#"
camera = { eye = [0, -4, 2], target = [0, 0, 0], resolution = [16, 12] }
materials.floor = { type = "diffuse", reflectance = { image = { file = "FILE", scale = 0.5 } } }
objects = [{ solid = "box(center = [0, 0, -0.5], size = [4, 4, 1])", material = "floor" }]
lights = [{ type = "sphere", center = [0, 0, 3], radius = 0.3, power = 50 }]
"#;

/// A PNG of two columns, sRGB 188 and 0: decoded to linear (188 → 0.5029), projected
/// onto the floor at 0.5 repeats per unit: the left half of each 2-unit tile is the
/// first column.
#[test]
fn a_png_texture_decodes_srgb_and_projects_onto_the_floor() {
    let dir = std::env::temp_dir().join(format!("render-image-tex-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut png = Vec::new();
    render::png_io::write_rgb8(&mut png, &[188, 188, 188, 0, 0, 0], 2, 1).unwrap();
    std::fs::write(dir.join("t.png"), png).unwrap();
    let (scene, _) = parse_scene(
        &SCENE.replace("FILE", "t.png"),
        SceneFormat::Toml,
        &dir.join("s.toml"),
    )
    .unwrap();
    let Material::Diffuse { reflectance } = &scene.materials[0] else {
        panic!("a diffuse floor")
    };
    let at = |x: f64, y: f64| {
        reflectance.eval(&TexCoord {
            p: DVec3::new(x, y, 0.0),
            n: DVec3::Z,
            ..TexCoord::default()
        })
    };
    let linear = ((188.0 / 255.0 + 0.055) / 1.055f64).powf(2.4);
    // Column centres: u = 0.25 and 0.75 of a tile, x = 0.5 and 1.5.
    assert!(
        (at(0.5, 0.3) - Rgb::splat(linear)).abs().max_element() < 1e-6,
        "{}",
        at(0.5, 0.3)
    );
    assert!(at(1.5, 0.3).abs().max_element() < 1e-6, "{}", at(1.5, 0.3));
    assert!((at(0.5 + 2.0, 7.0) - at(0.5, 0.3)).abs().max_element() < 1e-6);
    // A missing file and an unknown kind of file are errors at the texture's key.
    for (file, want) in [
        ("gone.png", "cannot read"),
        ("t.txt", "ending in .png or .exr"),
    ] {
        let e = parse_scene(
            &SCENE.replace("FILE", file),
            SceneFormat::Toml,
            &dir.join("s.toml"),
        )
        .err()
        .unwrap();
        assert_eq!(e.key, "materials.floor.reflectance.image.file", "{e}");
        assert!(e.to_string().contains(want), "{e}");
        assert!(e.line == 3, "{e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Pattern textures are read in the object's own space: a ball moved by a rotation and
/// a translation shows, at each moved point, the colour the unmoved ball shows at the
/// point it came from (checkers stay in world space, as before).
#[test]
fn patterns_move_with_their_object() {
    let scene = |transform: &str| {
        let text = format!(
            r#"
camera = {{ eye = [0, -6, 2], target = [0, 0, 0], resolution = [16, 12] }}
materials.marble = {{ type = "diffuse", reflectance = {{ pattern = {{ kind = "marble", a = 0.9, b = 0.1, scale = 2 }} }} }}
objects = [{{ solid = "sphere([0, 0, 0], 1)", material = "marble"{transform} }}]
lights = [{{ type = "sphere", center = [0, 0, 4], radius = 0.3, power = 50 }}]
"#
        );
        parse_scene(&text, SceneFormat::Toml, std::path::Path::new("t.toml"))
            .unwrap()
            .0
    };
    let (still, moved) = (
        scene(""),
        scene(
            r#", transform = [{ rotate = { axis = [0, 0, 1], degrees = 90 } }, { translate = [5, 1, 0] }]"#,
        ),
    );
    let forward = |p: DVec3| DVec3::new(-p.y, p.x, p.z) + DVec3::new(5.0, 1.0, 0.0);
    let colour = |s: &render::scene::Scene, p: DVec3, n: DVec3| {
        let Material::Diffuse { reflectance } = &s.materials[0] else {
            panic!("diffuse")
        };
        let hit = render::scene::SurfaceHit {
            t: 1.0,
            p,
            n,
            object: 0,
            material: 0,
            uv: glam::DVec2::ZERO,
        };
        reflectance.eval(&s.tex_coord(&hit))
    };
    let mut differ = 0;
    for k in 0..200 {
        let (a, b) = (k as f64 * 0.37, k as f64 * 0.11);
        let n = DVec3::new(a.cos() * b.sin(), a.sin() * b.sin(), b.cos());
        let at_origin = colour(&still, n, n);
        let moved_n = DVec3::new(-n.y, n.x, n.z);
        assert!(
            (colour(&moved, forward(n), moved_n) - at_origin)
                .abs()
                .max_element()
                < 1e-9
        );
        // In world space the moved ball would show other colours.
        differ += usize::from(
            (colour(&still, forward(n), moved_n) - at_origin)
                .abs()
                .max_element()
                > 1e-3,
        );
    }
    assert!(differ > 100, "{differ}");
}
