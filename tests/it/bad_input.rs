//! Inputs that once made myriad panic, abort out of memory or mislead, each reproduced: every
//! one must now be a clear error naming the file and the element (or, where the format allows
//! it, a warning), with nothing allocated beyond the memory limit.

use crate::common::{assert_mentions, cornell, cornell_json, load, load_error};
use myriad::math::UVec2;
use serde_json::json;
use std::path::Path;

/// Caps the memory limit of this test process (every test in it is small), so that a check
/// that fails to refuse a huge size cannot take the machine down with it.
pub fn low_memory_limit() {
    myriad::limits::set_memory_limit(2_000_000_000);
}

/// The Cornell glTF with `edit` applied, loaded from a fresh folder: the error message.
fn gltf_error(edit: impl FnOnce(&mut serde_json::Value)) -> String {
    low_memory_limit();
    let dir = tempfile::tempdir().unwrap();
    let mut doc = cornell_json();
    edit(&mut doc);
    let e = load_error(dir.path(), "broken.gltf", doc.to_string().as_bytes());
    assert!(!e.contains(myriad::guard::BUG_REPORT), "caught only by the last line of defence: {e}");
    e
}

#[test]
fn an_image_with_no_source_is_an_error() {
    let e = gltf_error(|d| {
        d["images"] = json!([{}]);
        d["textures"] = json!([{"source": 0}]);
        d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    });
    assert_mentions(&e, &["broken.gltf", "images[0]", "neither a uri nor a bufferView"]);
}

#[test]
fn an_image_in_a_buffer_view_past_its_buffer_is_an_error() {
    let e = gltf_error(|d| {
        d["bufferViews"].as_array_mut().unwrap().push(json!({"buffer": 0, "byteOffset": 8, "byteLength": 10_000_000}));
        let view = d["bufferViews"].as_array().unwrap().len() - 1;
        d["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
    });
    assert_mentions(&e, &["broken.gltf", "bufferViews[", "outside buffer 0"]);
}

#[test]
fn a_primitive_with_a_dangling_position_accessor_is_an_error() {
    // Without positions at all it is valid glTF, skipped with a warning (gltf_accessors.rs).
    let e = gltf_error(|d| d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(999));
    assert_mentions(&e, &["meshes[0].primitives[0]", "accessor 999"]);
}

#[test]
fn a_stride_smaller_than_the_element_is_an_error() {
    let e = gltf_error(|d| {
        let view = d["accessors"][0]["bufferView"].as_u64().unwrap() as usize;
        d["bufferViews"][view]["byteStride"] = json!(4);
    });
    assert_mentions(&e, &["accessors[0]", "byteStride of 4"]);
}

#[test]
fn a_huge_accessor_without_data_is_refused_before_allocating() {
    let e = gltf_error(|d| {
        let a = &mut d["accessors"][0];
        a.as_object_mut().unwrap().remove("bufferView");
        a["count"] = json!(2_147_483_647u64);
    });
    assert_mentions(&e, &["accessors[0]", "2147483647", "memory", "--max-memory"]);
}

#[test]
fn a_node_graph_that_is_not_a_forest_is_an_error() {
    // Each node lists the next twice: 2^depth placements if walked.
    let e = gltf_error(|d| {
        let n = d["nodes"].as_array().unwrap().len();
        for i in 0..n - 1 {
            d["nodes"][i]["children"] = json!([i + 1, i + 1]);
        }
    });
    assert_mentions(&e, &["nodes[", "trees"]);
    let e = gltf_error(|d| {
        d["nodes"][0]["children"] = json!([1]);
        d["nodes"][1]["children"] = json!([0]);
    });
    assert_mentions(&e, &["nodes[", "cycle"]);
}

#[test]
fn an_absurd_camera_aspect_ratio_is_an_error_naming_it() {
    low_memory_limit();
    let dir = tempfile::tempdir().unwrap();
    let mut doc = cornell_json();
    doc["cameras"][0]["perspective"]["aspectRatio"] = json!(1e-30);
    let path = dir.path().join("thin.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let e = load(&path, None, None).err().expect("refused").to_string();
    assert_mentions(&e, &["thin.gltf", "aspect ratio 1e-30", "6.4e32 pixels tall", "--resolution"]);
}

#[test]
fn coordinates_near_the_largest_float_are_errors_not_bvh_panics() {
    let e = gltf_error(|d| d["nodes"][0]["translation"] = json!([1e38, 0.0, 0.0]));
    assert_mentions(&e, &["broken.gltf", "instance", "beyond"]);
    // The auto camera frames scenes up to the coordinate limit.
    low_memory_limit();
    let dir = tempfile::tempdir().unwrap();
    let mut doc = cornell_json();
    doc["nodes"][0]["translation"] = json!([1e11, 0.0, 0.0]);
    let path = dir.path().join("far.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    load(&path, Some(UVec2::new(8, 6)), Some(myriad::scene::AUTO_CAMERA)).unwrap();
}

/// A RON scene around `objects` and `lights`, loaded: the error message.
fn ron_error(body: &str) -> String {
    low_memory_limit();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.ron");
    std::fs::write(
        &path,
        format!("Scene(camera: Perspective(eye: (0, 1, 3), look_at: (0, 1, 0), yfov_deg: 40), {body})"),
    )
    .unwrap();
    let e = load(&path, Some(UVec2::new(8, 6)), None).err().expect("refused").to_string();
    assert!(!e.contains(myriad::guard::BUG_REPORT), "caught only by the last line of defence: {e}");
    e
}

#[test]
fn a_light_or_quad_near_the_largest_float_is_an_error() {
    let e = ron_error("lights: [Point(position: (0, 1, 0), intensity: (1e38, 1e38, 1e38))]");
    assert_mentions(&e, &["scene.ron", "light 0", "beyond myriad's limit"]);
    let e = ron_error("lights: [Quad(corner: (1e38, 0, 0), edge1: (1, 0, 0), edge2: (0, 0, 1), radiance: (1, 1, 1))]");
    assert_mentions(&e, &["light 0", "corner", "beyond"]);
    let e = ron_error("lights: [Directional(direction: (0, -1, 0), irradiance: (1e36, 1, 1))]");
    assert_mentions(&e, &["light 0", "beyond myriad's limit"]);
}

#[test]
fn a_grid_too_large_for_memory_is_refused_before_it_is_made() {
    let e = ron_error(
        "lights: [Grid(center: (0, 2, 0), normal: (0, -1, 0), extent: (1, 1), rows: 7071, cols: 7071, \
         emission: Radiance(rgb: (1, 1, 1)))]",
    );
    assert_mentions(&e, &["lights[0] Grid", "7071 × 7071", "memory", "--max-memory"]);
}

#[test]
fn a_scene_image_too_large_for_memory_is_refused() {
    low_memory_limit();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-5x5.ron");
    let e = load(&path, Some(UVec2::new(16384, 16384)), None).err().expect("refused").to_string();
    assert_mentions(&e, &["cornell-5x5.ron", "16384 × 16384", "memory", "--max-memory"]);
}

#[test]
fn render_settings_of_zero_name_the_file_and_the_setting() {
    let e = ron_error("render: (spp: 0)");
    assert_mentions(&e, &["scene.ron", "render.spp", "at least 1"]);
    let e = ron_error("render: (max_depth: 0)");
    assert_mentions(&e, &["render.max_depth"]);
}

#[test]
fn a_syntax_error_on_a_huge_line_is_shown_in_part() {
    let long = format!(
        "objects: [{}Quad(corner: (0, 0, 0), edge1: (1, 0, 0), edge2: (0, 0, 1), material: 7)]",
        " ".repeat(200_000)
    );
    let e = ron_error(&long);
    assert!(e.len() < 2000, "{} bytes of error", e.len());
    assert_mentions(&e, &["scene.ron", "1:", "…"]);
}

#[test]
fn a_byte_order_mark_is_not_a_syntax_error() {
    low_memory_limit();
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(cornell("ron")).unwrap();
    let path = dir.path().join("bom.ron");
    std::fs::write(&path, format!("\u{feff}{text}")).unwrap();
    load(&path, Some(UVec2::new(8, 6)), Some(myriad::scene::AUTO_CAMERA)).unwrap();
    // The same for OBJ and MTL files.
    std::fs::write(dir.path().join("t.obj"), "\u{feff}mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n")
        .unwrap();
    std::fs::write(dir.path().join("t.mtl"), "\u{feff}newmtl m\nKd 0.5 0.25 0.125\n").unwrap();
    let scene = load(&dir.path().join("t.obj"), Some(UVec2::new(8, 6)), Some(myriad::scene::AUTO_CAMERA)).unwrap();
    assert_eq!(scene.materials[0].base_color, myriad::math::Rgb::new(0.5, 0.25, 0.125));
}

#[test]
fn camera_errors_say_which_value_is_wrong() {
    let e = ron_error_with_camera("eye: (0, 1, 0), look_at: (0, 1, 0), yfov_deg: 40");
    assert_mentions(&e, &["camera 'camera'", "is at the target", "[0, 1, 0]"]);
    let e = ron_error_with_camera("eye: (0, 1, 3), look_at: (0, 1, 0), yfov_deg: 190");
    assert_mentions(&e, &["190", "between 0° and 180°"]);
}

fn ron_error_with_camera(camera: &str) -> String {
    low_memory_limit();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.ron");
    std::fs::write(&path, format!("Scene(camera: Perspective({camera}))")).unwrap();
    load(&path, Some(UVec2::new(8, 6)), None).err().expect("refused").to_string()
}

#[test]
fn an_mtl_colour_with_two_numbers_names_the_line_and_one_number_is_grey() {
    low_memory_limit();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("t.obj"), "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n").unwrap();
    std::fs::write(dir.path().join("t.mtl"), "newmtl m\nKd 0.5 0.5\n").unwrap();
    let e = load(&dir.path().join("t.obj"), Some(UVec2::new(8, 6)), Some(myriad::scene::AUTO_CAMERA))
        .err()
        .expect("refused")
        .to_string();
    assert_mentions(&e, &["t.mtl", "line 2", "three numbers"]);
    std::fs::write(dir.path().join("t.mtl"), "newmtl m\nKd 0.5\n").unwrap();
    let scene = load(&dir.path().join("t.obj"), Some(UVec2::new(8, 6)), Some(myriad::scene::AUTO_CAMERA)).unwrap();
    assert_eq!(scene.materials[0].base_color, myriad::math::Rgb::splat(0.5));
}

#[test]
fn an_exr_with_a_broken_header_is_an_error_not_an_allocation() {
    low_memory_limit();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.exr");
    let layers = myriad::image::Layers {
        size: UVec2::new(4, 3),
        channels: ["R", "G", "B"]
            .iter()
            .map(|n| myriad::image::Channel { name: n.to_string(), data: vec![0.5; 12] })
            .collect(),
    };
    myriad::io::exr::write(&path, &layers, &[]).unwrap();
    let good = std::fs::read(&path).unwrap();
    // Zero each header byte in turn (the header ends where the pixel offsets begin).
    for i in 8..good.len().min(400) {
        let mut bad = good.clone();
        bad[i] = 0;
        let broken = dir.path().join("broken.exr");
        std::fs::write(&broken, &bad).unwrap();
        if let Err(e) = myriad::io::exr::read(&broken) {
            let e = e.to_string();
            assert!(!e.contains(myriad::guard::BUG_REPORT), "byte {i}: {e}");
        }
    }
}

#[test]
fn impossible_material_values_are_errors_or_warnings_naming_the_material() {
    let material = |extensions: serde_json::Value| {
        move |d: &mut serde_json::Value| {
            d["materials"][0]["extensions"] = extensions;
            d["extensionsUsed"] = json!(["KHR_materials_ior", "KHR_materials_transmission", "KHR_materials_volume"]);
        }
    };
    let e = gltf_error(material(json!({"KHR_materials_ior": {"ior": 0.5}})));
    assert_mentions(&e, &["broken.gltf", "material", "IOR must be a finite number above 1, not 0.5"]);
    let e = gltf_error(material(json!({"KHR_materials_transmission": {"transmissionFactor": 2.0}})));
    assert_mentions(&e, &["broken.gltf", "material", "transmission"]);
    // A negative attenuation distance: the glass renders, without absorption, and says so.
    low_memory_limit();
    let dir = tempfile::tempdir().unwrap();
    let mut doc = cornell_json();
    material(json!({"KHR_materials_transmission": {"transmissionFactor": 1.0},
                    "KHR_materials_volume": {"thicknessFactor": 1, "attenuationDistance": -1}}))(&mut doc);
    let path = dir.path().join("glass.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let loaded = crate::common::load_report(&path, Some(UVec2::new(8, 6)), None).unwrap();
    let report = loaded.report.clone();
    let scene = crate::common::TestScene::from(loaded);
    let name = &scene.materials[0].name;
    assert!(
        report
            .warnings
            .iter()
            .any(|w| w.contains(&format!("material '{name}'")) && w.contains("attenuationDistance -1")),
        "{:?}",
        report.warnings
    );
    let film = crate::render::render_with(&scene, myriad::settings::LightSamplerKind::Tree, 4, 4, 1);
    assert!(film.means().iter().all(|p| p.is_finite()));
}
