//! glTF data in every form the specification allows, read value by value: quantised integer
//! attributes (`KHR_mesh_quantization`), accessors without a buffer view (zeros) and sparse
//! substitution, textures whose image an extension gives (`EXT_texture_webp`, and
//! `KHR_texture_basisu`'s fallback), and extensions required or merely used. Broken
//! compressed streams and lying sizes are errors that name the element.

use std::path::{Path, PathBuf};

use base64::Engine;
use myriad::io::{LoadOptions, load_scene as load_description};
use myriad::math::{Vec2, Vec3A};
use myriad::scene::description::SceneDescription;
use serde_json::{Value, json};

use crate::common::{assert_mentions, gltf_variant, join_glb, load_error, split_glb};

/// A one-triangle glTF with `buffer` as a data URI, the given views and accessors, and a
/// primitive using `attributes` (and `indices`, if any).
fn document(buffer: &[u8], views: Value, accessors: Value, attributes: Value) -> Value {
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(buffer));
    json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": buffer.len(), "uri": uri}],
        "bufferViews": views,
        "accessors": accessors,
        "meshes": [{"primitives": [{"attributes": attributes}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0
    })
}

fn write(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, doc.to_string()).unwrap();
    path
}

fn load(path: &Path) -> SceneDescription {
    load_description(path, &LoadOptions::default()).unwrap()
}

#[test]
fn quantised_attributes_read_as_the_specification_says() {
    // POSITION: unsigned shorts, not normalised (their values); NORMAL: normalised bytes
    // (c / 127, at least −1); TEXCOORD_0: normalised unsigned bytes (c / 255).
    let mut b = Vec::new();
    for v in [[0u16, 0, 0], [100, 0, 0], [0, 200, 7]] {
        v.iter().for_each(|c| b.extend(c.to_le_bytes()));
        b.extend([0, 0]); // each element aligned to 4 bytes
    }
    for n in [[0i8, 0, 127], [0, 0, 127], [-128, 0, 0]] {
        b.extend(n.map(|c| c as u8));
        b.push(0);
    }
    b.extend([0u8, 0, 255, 51, 51, 255, 0, 0]);
    let views = json!([
        {"buffer": 0, "byteOffset": 0, "byteLength": 24, "byteStride": 8},
        {"buffer": 0, "byteOffset": 24, "byteLength": 12, "byteStride": 4},
        {"buffer": 0, "byteOffset": 36, "byteLength": 6}
    ]);
    let accessors = json!([
        {"bufferView": 0, "componentType": 5123, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [100, 200, 7]},
        {"bufferView": 1, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC2"}
    ]);
    let mut doc = document(&b, views, accessors, json!({"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}));
    doc["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    doc["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    let dir = tempfile::tempdir().unwrap();
    let d = load(&write(dir.path(), "quantized.gltf", &doc));
    let m = &d.meshes[0];
    assert_eq!(m.positions, [Vec3A::new(0.0, 0.0, 0.0), Vec3A::new(100.0, 0.0, 0.0), Vec3A::new(0.0, 200.0, 7.0)]);
    assert_eq!(m.normals.as_deref().unwrap(), [Vec3A::Z, Vec3A::Z, -Vec3A::X]);
    assert_eq!(m.uvs.as_deref().unwrap(), [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.2), Vec2::new(0.2, 1.0)]);
}

#[test]
fn an_accessor_without_a_buffer_view_is_zeros_that_sparse_values_replace() {
    // Sparse indices [0, 2] (unsigned bytes, padded) and their values, three floats each.
    let mut b = vec![0u8, 2, 0, 0];
    for v in [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0] {
        b.extend(v.to_le_bytes());
    }
    let views =
        json!([{"buffer": 0, "byteOffset": 0, "byteLength": 2}, {"buffer": 0, "byteOffset": 4, "byteLength": 24}]);
    let sparse = json!({"count": 2, "indices": {"bufferView": 0, "componentType": 5121}, "values": {"bufferView": 1}});
    let accessors = json!([
        {"componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [4, 5, 6], "sparse": sparse},
        {"componentType": 5126, "count": 3, "type": "VEC3"}
    ]);
    let doc = document(&b, views, accessors, json!({"POSITION": 0, "NORMAL": 1}));
    let dir = tempfile::tempdir().unwrap();
    let d = load(&write(dir.path(), "sparse.gltf", &doc));
    let m = &d.meshes[0];
    assert_eq!(m.positions, [Vec3A::new(1.0, 2.0, 3.0), Vec3A::ZERO, Vec3A::new(4.0, 5.0, 6.0)]);
    // All-zero normals (no data at all) stay zero: the shading falls back to the face's.
    assert_eq!(m.normals.as_deref().unwrap(), [Vec3A::ZERO; 3]);
}

/// A 2 × 1 image (red, blue) encoded by the `image` crate in `format`.
fn two_texels(format: image::ImageFormat) -> Vec<u8> {
    let img = image::RgbaImage::from_raw(2, 1, vec![255, 0, 0, 255, 0, 0, 255, 255]).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, format).unwrap();
    out.into_inner()
}

fn data_uri(mime: &str, bytes: &[u8]) -> String {
    format!("data:{mime};base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// The Cornell glTF with one texture on material 0, built by `texture`, over `images`.
fn textured(images: Value, texture: Value) -> Value {
    let mut doc = crate::common::cornell_json();
    doc["images"] = images;
    doc["textures"] = json!([texture]);
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    doc
}

#[test]
fn a_texture_takes_its_image_from_an_extension_or_its_fallback() {
    let dir = tempfile::tempdir().unwrap();
    let webp = data_uri("image/webp", &two_texels(image::ImageFormat::WebP));
    let mut doc = textured(json!([{"uri": webp}]), json!({"extensions": {"EXT_texture_webp": {"source": 0}}}));
    doc["extensionsUsed"] = json!(["EXT_texture_webp"]);
    doc["extensionsRequired"] = json!(["EXT_texture_webp"]);
    let d = load(&write(dir.path(), "webp.gltf", &doc));
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
    let tex = d.materials[0].base_color_texture.expect("the WebP texture");
    let img = &d.images[tex.image as usize];
    assert_eq!((img.size.x, img.size.y, img.texels[0], img.texels[1]), (2, 1, [255, 0, 0, 255], [0, 0, 255, 255]));

    // A 16-bit PNG: its top 8 bits.
    let img =
        image::ImageBuffer::<image::Rgba<u16>, _>::from_raw(2, 1, vec![65535u16, 0, 0, 65535, 0, 0, 32896, 65535])
            .unwrap();
    let mut png16 = std::io::Cursor::new(Vec::new());
    img.write_to(&mut png16, image::ImageFormat::Png).unwrap();
    let doc = textured(json!([{"uri": data_uri("image/png", png16.get_ref())}]), json!({"source": 0}));
    let d = load(&write(dir.path(), "png16.gltf", &doc));
    let tex = d.materials[0].base_color_texture.expect("the 16-bit texture");
    assert_eq!(d.images[tex.image as usize].texels[..2], [[255, 0, 0, 255], [0, 0, 128, 255]]);

    // A KTX2 image myriad cannot decode, and the PNG the file gives as its fallback.
    let png = data_uri("image/png", &two_texels(image::ImageFormat::Png));
    let images =
        json!([{"uri": data_uri("image/ktx2", b"\xabKTX 20\xbb not really"), "mimeType": "image/ktx2"}, {"uri": png}]);
    let mut doc = textured(images, json!({"source": 1, "extensions": {"KHR_texture_basisu": {"source": 0}}}));
    doc["extensionsUsed"] = json!(["KHR_texture_basisu"]);
    let d = load(&write(dir.path(), "basisu.gltf", &doc));
    let tex = d.materials[0].base_color_texture.expect("the fallback texture");
    assert_eq!(d.images[tex.image as usize].texels[1], [0, 0, 255, 255]);
    assert!(d.warnings.iter().any(|w| w.contains("Basis Universal")), "{:?}", d.warnings);
}

#[test]
fn sheen_and_anisotropy_read_with_their_textures_and_a_missing_texture_is_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let png = data_uri("image/png", &two_texels(image::ImageFormat::Png));
    let mut doc = textured(json!([{"uri": png}]), json!({"source": 0}));
    doc["extensionsUsed"] = json!(["KHR_materials_sheen", "KHR_materials_anisotropy"]);
    doc["materials"][0]["extensions"] = json!({
        "KHR_materials_sheen": {
            "sheenColorFactor": [0.9, 0.5, 0.25], "sheenRoughnessFactor": 0.4,
            "sheenColorTexture": {"index": 0}, "sheenRoughnessTexture": {"index": 0}
        },
        "KHR_materials_anisotropy": {"anisotropyStrength": 0.7, "anisotropyRotation": 1.25, "anisotropyTexture": {"index": 0}}
    });
    doc["materials"][1]["extensions"] = json!({
        "KHR_materials_sheen": {"sheenColorFactor": [1.0, 1.0, 1.0], "sheenColorTexture": {"index": 7}},
        "KHR_materials_anisotropy": {"anisotropyStrength": 0.3}
    });
    let d = load(&write(dir.path(), "sheen.gltf", &doc));
    let m = &d.materials[0];
    assert_eq!((m.sheen_color.to_array(), m.sheen_roughness), ([0.9, 0.5, 0.25], 0.4));
    assert_eq!((m.anisotropy, m.anisotropy_rotation), (0.7, 1.25));
    assert!(m.sheen_color_texture.is_some() && m.sheen_roughness_texture.is_some() && m.anisotropy_texture.is_some());
    assert!(!m.needs_radial_tangents() && m.ignored.is_empty(), "{:?}", m.ignored);
    // Defaults: roughness 0, rotation 0; without a direction texture, Blender's radial tangent.
    let m = &d.materials[1];
    assert_eq!((m.sheen_roughness, m.anisotropy, m.anisotropy_rotation), (0.0, 0.3, 0.0));
    assert!(m.sheen_color_texture.is_none() && m.needs_radial_tangents());
    assert!(
        d.warnings.iter().any(|w| w.contains("KHR_materials_sheen") && w.contains("texture Some(7)")),
        "{:?}",
        d.warnings
    );
    // And the scene renders (its meshes carry the radial tangents the second material asks for).
    let out =
        crate::split::ok(&["render", "sheen.gltf", "--spp", "2", "--resolution", "16x12", "-o", "s.exr"], dir.path());
    assert!(out.contains("s.exr"), "{out}");
}

#[test]
fn a_plain_data_uri_is_read_and_an_accessor_of_no_defined_type_is_an_error_only_where_read() {
    let dir = tempfile::tempdir().unwrap();
    // The quantised triangle's positions as a percent-encoded (not base64) data URI.
    let mut b = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        v.iter().for_each(|c| b.extend(c.to_le_bytes()));
    }
    let views = json!([{"buffer": 0, "byteLength": 36}]);
    let accessors = json!([
        {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
        {"componentType": 5126, "count": 3, "type": "NotaVEC3"}
    ]);
    let mut doc = document(&b, views, accessors, json!({"POSITION": 0}));
    let encoded: String = b.iter().map(|byte| format!("%{byte:02X}")).collect();
    doc["buffers"][0]["uri"] = json!(format!("data:application/gltf-buffer,{encoded}"));
    let d = load(&write(dir.path(), "plain.gltf", &doc));
    assert_eq!(d.meshes[0].positions[1], Vec3A::new(1.0, 0.0, 0.0));
    // The undefined type is read by nothing above; read as normals, it is an error naming it.
    doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(1);
    let e = load_error(dir.path(), "typed.gltf", doc.to_string().as_bytes());
    assert_mentions(&e, &["accessor 1", "'NotaVEC3'", "does not define"]);
    // A buffer without data (no uri, not a GLB) is named where a mesh reads it.
    doc["buffers"][0].as_object_mut().unwrap().remove("uri");
    let e = load_error(dir.path(), "dataless.gltf", doc.to_string().as_bytes());
    assert_mentions(&e, &["reads buffer 0, which holds no data"]);
}

#[test]
fn required_extensions_myriad_cannot_read_are_refused_and_used_ones_named() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = crate::common::cornell_json();
    doc["extensionsUsed"] = json!(["EXT_lights_ies"]);
    let d = load(&write(dir.path(), "used.gltf", &doc));
    assert!(d.warnings.iter().any(|w| w.contains("EXT_lights_ies")), "{:?}", d.warnings);
    doc["extensionsRequired"] = json!(["EXT_lights_ies"]);
    let e = load_error(dir.path(), "required.gltf", doc.to_string().as_bytes());
    assert_mentions(&e, &["required.gltf", "extensionsRequired", "EXT_lights_ies"]);
}

/// A GLB's JSON chunk, changed by `edit`, and its binary chunk's data changed by `bin`.
fn edited_glb(glb: &[u8], edit: impl FnOnce(&mut Value), bin: impl FnOnce(&mut [u8], &Value)) -> Vec<u8> {
    let (mut doc, mut rest) = split_glb(glb).unwrap();
    bin(&mut rest[8..], &doc); // past the BIN chunk's header
    edit(&mut doc);
    join_glb(&doc, &rest)
}

fn variant(name: &str) -> Vec<u8> {
    std::fs::read(gltf_variant(name)).unwrap()
}

#[test]
fn broken_compressed_streams_and_lying_sizes_are_errors_naming_the_element() {
    let dir = tempfile::tempdir().unwrap();
    // meshopt: the first compressed view's bytes overwritten.
    let meshopt = variant("meshopt");
    let scramble = |bin: &mut [u8], doc: &Value| {
        let view = doc["bufferViews"]
            .as_array()
            .unwrap()
            .iter()
            .find_map(|v| v["extensions"]["EXT_meshopt_compression"].as_object())
            .unwrap();
        let (at, n) =
            (view["byteOffset"].as_u64().unwrap_or(0) as usize, view["byteLength"].as_u64().unwrap() as usize);
        bin[at..at + n].iter_mut().enumerate().for_each(|(i, b)| *b = (i * 37 % 251) as u8);
    };
    // Only the fallback buffer's placeholder carries no bytes: the data lives in buffer 0.
    let e = load_error(dir.path(), "meshopt-corrupt.glb", &edited_glb(&meshopt, |_| {}, scramble));
    assert_mentions(&e, &["meshopt-corrupt.glb", "bufferViews[", "meshopt"]);
    // A view that claims 10¹² elements: refused before allocating.
    let lie = |doc: &mut Value| {
        for v in doc["bufferViews"].as_array_mut().unwrap() {
            let ext = v.get_mut("extensions").and_then(|e| e.get_mut("EXT_meshopt_compression"));
            if let Some(e) = ext.and_then(Value::as_object_mut) {
                e.insert("count".into(), json!(1_000_000_000_000u64));
            }
        }
    };
    let e = load_error(dir.path(), "meshopt-huge.glb", &edited_glb(&meshopt, lie, |_, _| {}));
    assert_mentions(&e, &["meshopt-huge.glb", "bufferViews[", "memory"]);

    // Draco: the stream's bytes after its header overwritten.
    let draco = variant("draco");
    let scramble = |bin: &mut [u8], doc: &Value| {
        let view = &doc["bufferViews"]
            [doc["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["bufferView"]
                .as_u64()
                .unwrap() as usize];
        let (at, n) =
            (view["byteOffset"].as_u64().unwrap_or(0) as usize, view["byteLength"].as_u64().unwrap() as usize);
        bin[at + 12..at + n].iter_mut().enumerate().for_each(|(i, b)| *b = (i * 91 % 253) as u8);
    };
    let e = load_error(dir.path(), "draco-corrupt.glb", &edited_glb(&draco, |_| {}, scramble));
    assert_mentions(&e, &["draco-corrupt.glb", "meshes[0]", "Draco"]);
}

#[test]
fn info_lists_each_extension_with_what_myriad_does_with_it() {
    let dir = tempfile::tempdir().unwrap();
    let glb = gltf_variant("meshopt");
    let out = crate::split::ok(&["info", glb.to_str().unwrap()], dir.path());
    for line in [
        "extension    EXT_meshopt_compression: meshopt-compressed buffer views, decoded",
        "extension    KHR_mesh_quantization: integer positions, normals and texture coordinates",
        "extension    KHR_lights_punctual: point, spot and directional lights",
    ] {
        assert!(out.contains(line), "{out}");
    }
    let mut doc = crate::common::cornell_json();
    doc["extensionsUsed"] = json!(["EXT_lights_ies"]);
    let path = write(dir.path(), "ies.gltf", &doc);
    let out = crate::split::ok(&["info", path.to_str().unwrap()], dir.path());
    assert!(out.contains("extension    EXT_lights_ies: ignored"), "{out}");
}

#[test]
fn a_moving_scene_renders_its_static_pose_with_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = crate::common::cornell_json();
    doc["skins"] = json!([{"joints": [0]}]);
    doc["animations"] = json!([{"channels": [], "samplers": []}]);
    let d = load(&write(dir.path(), "animated.gltf", &doc));
    let pose: Vec<_> = d.warnings.iter().filter(|w| w.contains("static pose")).collect();
    assert_eq!(pose.len(), 1, "{:?}", d.warnings);
    assert!(pose[0].contains("1 animations") && pose[0].contains("1 skins"), "{pose:?}");
}

#[test]
fn a_file_with_nothing_to_render_is_described_by_info_and_refused_by_render() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty.gltf");
    std::fs::write(&path, r#"{"asset": {"version": "2.0"}}"#).unwrap();
    let p = path.to_str().unwrap();
    let out = crate::split::ok(&["info", p], dir.path());
    assert!(out.contains("no scene and no nodes") && out.contains("no camera"), "{out}");
    let out = crate::split::myriad(&["render", p, "--camera", "auto", "-o", "e.exr"], dir.path());
    assert!(
        !out.status.success() && crate::split::text(&out).contains("nothing to render"),
        "{}",
        crate::split::text(&out)
    );
    assert!(!dir.path().join("e.exr").exists());
}

/// Valid files the glTF-Validator's samples hold that the `gltf` crate alone refuses (125 of
/// its 129 valid samples load; before these, 91).
#[test]
fn valid_files_the_strict_parser_refused_load_with_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = crate::common::cornell_json();
    // A texture without an image, a scene without a node list beside the default one, an
    // integer written as a float, a light of a type a later extension may define, a
    // primitive without positions, an animation channel of KHR_animation_pointer (no node).
    doc["textures"] = json!([{}]);
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    doc["scenes"].as_array_mut().unwrap().push(json!({"name": "empty"}));
    doc["meshes"][0]["primitives"][0]["material"] = json!(0.0);
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] = json!({"KHR_lights_punctual": {"lights": [{"type": "spherical", "intensity": 5}]}});
    doc["nodes"].as_array_mut().unwrap().push(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}}));
    let last = doc["nodes"].as_array().unwrap().len() - 1;
    doc["scenes"][0]["nodes"].as_array_mut().unwrap().push(json!(last));
    doc["meshes"][1]["primitives"].as_array_mut().unwrap().push(json!({"attributes": {}}));
    doc["animations"] =
        json!([{"channels": [{"sampler": 0, "target": {"path": "pointer"}}], "samplers": [{"input": 0, "output": 0}]}]);
    let d = load(&write(dir.path(), "lenient.gltf", &doc));
    for part in
        ["textures[0] has no image", "skips KHR_lights_punctual lights [0]", "without positions", "1 animations"]
    {
        assert!(d.warnings.iter().any(|w| w.contains(part)), "{part}: {:?}", d.warnings);
    }
    assert!(d.lights.is_empty() && d.materials[0].base_color_texture.is_none());
}

#[test]
fn bytes_after_a_glb_and_a_buffer_on_the_web_that_nothing_reads_are_no_obstacle() {
    let dir = tempfile::tempdir().unwrap();
    let mut glb = variant("plain");
    glb.push(0);
    let path = dir.path().join("trailing.glb");
    std::fs::write(&path, &glb).unwrap();
    assert!(!load(&path).meshes.is_empty());
    let mut doc = crate::common::cornell_json();
    doc["buffers"].as_array_mut().unwrap().push(json!({"uri": "http://example.com/more.bin", "byteLength": 4}));
    assert!(!load(&write(dir.path(), "web.gltf", &doc)).meshes.is_empty());
}
