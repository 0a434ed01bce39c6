//! Scene loading: RON features, OBJ meshes, validation messages, and scale.

use myriad::commands::load_scene;
use myriad::io::ron::parse;
use myriad::light::Light;
use myriad::math::{UVec2, Vec3A};
use myriad::scene::{BuildOptions, build};
use std::path::Path;
use std::time::Instant;

const HEAD: &str = r#"Scene(
    camera: Perspective(eye: (0, 1, 3), look_at: (0, 1, 0), yfov_deg: 40),
    materials: { "white": Diffuse(albedo: (0.7, 0.7, 0.7)), "lamp": Emissive(radiance: (3, 3, 3)) },
"#;

fn scene(body: &str) -> String {
    format!("{HEAD}{body}\n)")
}

fn built(text: &str, dir: &Path) -> myriad::Result<(myriad::scene::Scene, myriad::scene::SceneReport)> {
    build(
        parse(text, "test.ron", dir, &Default::default())?,
        &BuildOptions { resolution: Some(UVec2::new(8, 6)), camera: None, ..Default::default() },
    )
}

#[test]
fn a_million_lamp_grid_loads() {
    let text = scene(
        "lights: [ Grid(center: (0, 2, 0), normal: (0, -1, 0), extent: (2, 2), rows: 1000, cols: 1000, \
         emission: Power(watts: 50), color_jitter: 0.1, decades: 2, seed: 4) ],",
    );
    let t = Instant::now();
    let (s, report) = built(&text, Path::new(".")).unwrap();
    eprintln!("1000 × 1000 grid: load + build {:.2} s", t.elapsed().as_secs_f64());
    assert_eq!(s.lights.len(), 1_000_000);
    assert_eq!(report.stats.triangles, 2_000_000);
    assert!((s.total_power() - 50.0).abs() < 50.0 * 1e-3, "{}", s.total_power());
}

#[test]
fn emissive_objects_become_quad_lights_and_boxes_six() {
    let text = scene(
        r#"objects: [
            Quad(corner: (0, 2, 0), edge1: (1, 0, 0), edge2: (0, 0, 1), material: "lamp"),
            Box(size: (1, 1, 1), transform: (translate: (0, 0.5, 0), rotate_deg: (0, 30, 0)), material: "lamp"),
            Sphere(center: (2, 1, 0), radius: 0.5, subdivisions: 1, material: "white"),
        ],"#,
    );
    let (s, report) = built(&text, Path::new(".")).unwrap();
    assert_eq!(s.lights.len(), 7);
    assert!(s.lights.iter().all(|l| matches!(l, Light::Quad(_))));
    assert_eq!(report.stats.triangles, 2 + 12 + 80);
    // The box's faces point outwards after the rotation.
    for l in &s.lights[1..] {
        let Light::Quad(q) = l else { unreachable!() };
        let c = q.p0 + 0.5 * (q.e1 + q.e2);
        assert!(q.n.dot(c - Vec3A::new(0.0, 0.5, 0.0)) > 0.0);
    }
}

#[test]
fn obj_meshes_load_with_transform_and_materials() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("tri.obj"),
        "mtllib tri.mtl\no lamp\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl glow\nf 1 2 4 3\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("tri.mtl"), "newmtl glow\nKd 0 0 0\nKe 2 1 0.5\n").unwrap();
    let text = scene(r#"objects: [ Mesh(path: "tri.obj", transform: (translate: (0, 0, -1), scale: (2, 2, 2))) ],"#);
    let (s, report) = built(&text, dir.path()).unwrap();
    assert_eq!(report.stats.triangles, 2);
    assert_eq!(s.lights.len(), 1, "a parallelogram with Ke becomes one quad light");
    let Light::Quad(q) = &s.lights[0] else { panic!() };
    assert!((q.area - 4.0).abs() < 1e-5, "scaled by 2: {}", q.area);
    assert!([q.p0, q.p0 + q.e1, q.p0 + q.e2].iter().all(|v| v.z == -1.0));
    assert_eq!(q.emission.radiance, myriad::math::Rgb::new(2.0, 1.0, 0.5));

    // Without its .mtl the mesh loads grey, with a warning that says so.
    std::fs::remove_file(dir.path().join("tri.mtl")).unwrap();
    let (s, report) = built(&text, dir.path()).unwrap();
    assert!(s.lights.is_empty());
    assert!(report.warnings.iter().any(|w| w.contains("material library")), "{:?}", report.warnings);
}

#[test]
fn mirrored_emitters_keep_their_front_side() {
    // glTF's rule: a negative-determinant transform reverses the winding, so the front face
    // of a mirrored one-sided emitter is the mirror image of the original front face.
    let text = scene(r#"objects: [ Box(size: (1, 1, 1), transform: (scale: (-1, 1, 1)), material: "lamp") ],"#);
    let (s, _) = built(&text, Path::new(".")).unwrap();
    for l in &s.lights {
        let Light::Quad(q) = l else { unreachable!() };
        let c = q.p0 + 0.5 * (q.e1 + q.e2);
        assert!(q.n.dot(c) > 0.0, "mirrored box face points inwards");
    }
}

#[test]
fn missing_fields_and_bad_values_are_located() {
    let e = parse(
        &scene("objects: [ Quad(corner: (0, 0, 0), edge1: (1, 0, 0), material: \"white\") ],"),
        "x.ron",
        Path::new("."),
        &Default::default(),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("x.ron") && e.contains("edge2"), "{e}");
    let bad_camera = HEAD.replace("look_at: (0, 1, 0)", "look_at: (0, 1, 3)") + ")";
    let e = built(&bad_camera, Path::new(".")).err().unwrap().to_string();
    assert!(e.contains("is at the target [0, 1, 3]"), "{e}");
    let e = built(&scene("film: (resolution: (0, 10)),"), Path::new(".")).err().unwrap().to_string();
    assert!(e.contains("resolution"), "{e}");
}

#[test]
fn shipped_scenes_load() {
    for name in ["cornell-5x5.ron", "cornell-9x9.ron", "cornell-32x32.ron", "cornell-320x320.ron"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
        let s = load_scene(Some(&path), &Default::default()).unwrap().scene;
        let n: usize = name.trim_start_matches("cornell-").split('x').next().unwrap().parse().unwrap();
        assert_eq!(s.lights.len(), n * n, "{name}");
        assert!((s.total_power() - 45.24).abs() < 0.01, "{name}: {}", s.total_power());
    }
}

#[test]
fn blender_lamps_and_a_thin_lens_load_from_ron_and_bad_ones_are_located() {
    let text = r#"Scene(
    camera: Perspective(eye: (0, 1, 3), look_at: (0, 1, 0), fov_deg: 50, fit: Auto, shift: (0.1, -0.05),
                        depth_of_field: (aperture_radius: 0.01, focus_distance: 3)),
    lights: [
        Point(position: (0, 2, 0), intensity: (1, 1, 1), radius: 0.1),
        Point(position: (1, 2, 0), intensity: (1, 1, 1), radius: 0.1, soft_falloff: false, visible: true),
        Spot(position: (0, 2, 1), direction: (0, -1, 0), intensity: (5, 5, 5), inner_deg: 20, outer_deg: 30,
             falloff: Smoothstep, radius: 0.05),
        Directional(direction: (0, -1, 0), irradiance: (1, 1, 1), angle_deg: 10),
        Directional(direction: (0, -1, 0), irradiance: (1, 1, 1)),
        Area(center: (0, 2, 0), u: (0.5, 0, 0), v: (0, 0, 0.3), shape: Ellipse, radiance: (4, 4, 4), spread_deg: 60),
    ],
)"#;
    let (s, _) = built(text, Path::new(".")).unwrap();
    let kinds: Vec<&str> = s.lights.iter().map(|l| l.kind_name()).collect();
    assert_eq!(kinds, ["sphere lamp", "sphere lamp", "sphere lamp", "sun", "directional", "area lamp"]);
    assert!(s.camera.has_lens());
    assert!(
        matches!(&s.lights[1], Light::Sphere(l) if l.camera_visible && l.model == myriad::light::LampModel::Sphere)
    );
    assert!(!s.lamps.is_empty() && s.lamps.camera_visible() && s.suns == [3]);
    let fails = |body: &str, needles: &[&str]| {
        let text =
            format!("Scene(camera: Perspective(eye: (0, 1, 3), look_at: (0, 1, 0), fov_deg: 50), lights: [{body}])");
        let Err(e) = built(&text, Path::new(".")) else { panic!("{body} loaded") };
        let e = e.to_string();
        assert!(needles.iter().all(|n| e.contains(n)), "{body}: {e}");
    };
    fails("Point(position: (0, 2, 0), intensity: (1, 1, 1), radius: -0.1)", &["lights[0] Point", "radius"]);
    fails("Directional(direction: (0, -1, 0), irradiance: (1, 1, 1), angle_deg: 400)", &["lights[0]", "angle"]);
    fails("Area(center: (0, 2, 0), u: (1, 0, 0), v: (2, 0, 0), radiance: (1, 1, 1))", &["lights[0] Area", "zero area"]);
    fails("Area(center: (0, 2, 0), u: (1, 0, 0), v: (0, 0, 1), radiance: (1, 1, 1), shape: Circle)", &["Circle"]);
    let Err(e) = built(
        "Scene(camera: Perspective(eye: (0, 1, 3), look_at: (0, 1, 0), fov_deg: 50, depth_of_field: (aperture_radius: 0.1, focus_distance: 0)))",
        Path::new("."),
    ) else {
        panic!("a focus distance of 0 loaded")
    };
    let e = e.to_string();
    assert!(e.contains("focus distance"), "{e}");
}

#[test]
fn a_gltf_lights_extras_give_it_a_radius_or_an_angle() {
    // Blender's exporter writes a light's custom properties as its extras.
    let gltf = r#"{"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual"],
      "extensions": {"KHR_lights_punctual": {"lights": [
        {"type": "point", "intensity": 683, "extras": {"radius": 0.2}},
        {"type": "point", "intensity": 683, "extras": {"radius": 0.2, "soft_falloff": false}},
        {"type": "directional", "intensity": 683, "extras": {"angle": 0.1}},
        {"type": "point", "intensity": 683, "extras": {"radius": "big"}},
        {"type": "point", "intensity": 683, "extras": {"note": "someone else's"}}]}},
      "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
      "nodes": [{"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 2, 0]},
                {"extensions": {"KHR_lights_punctual": {"light": 1}}, "translation": [1, 2, 0]},
                {"extensions": {"KHR_lights_punctual": {"light": 2}}},
                {"extensions": {"KHR_lights_punctual": {"light": 3}}},
                {"extensions": {"KHR_lights_punctual": {"light": 4}}},
                {"camera": 0, "translation": [0, 1, 5]}],
      "scenes": [{"nodes": [0, 1, 2, 3, 4, 5]}]}"#;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lamps.gltf");
    std::fs::write(&path, gltf).unwrap();
    let loaded = load_scene(Some(&path), &Default::default()).unwrap();
    let mut kinds: Vec<&str> = loaded.scene.lights.iter().map(|l| l.kind_name()).collect();
    kinds.sort();
    assert_eq!(kinds, ["point", "point", "sphere lamp", "sphere lamp", "sun"]);
    let sphere =
        |l: &Light| matches!(l, Light::Sphere(s) if s.model == myriad::light::LampModel::Sphere && s.radius == 0.2);
    assert_eq!(loaded.scene.lights.iter().filter(|l| sphere(l)).count(), 1);
    assert!(
        loaded.report.warnings.iter().any(|w| w.contains("radius or angle is not a number")),
        "{:?}",
        loaded.report.warnings
    );
    assert_eq!(loaded.report.warnings.iter().filter(|w| w.contains("extras")).count(), 1);
}
