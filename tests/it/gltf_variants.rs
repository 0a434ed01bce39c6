//! One scene as real tools write it (`tools/make_gltf_variants.py`): Blender's exporter plain,
//! with Draco mesh compression and with WebP images, and gltfpack's quantised
//! (`KHR_mesh_quantization`) and meshopt-compressed (`EXT_meshopt_compression`) repacks of
//! the plain file. Every form holds the plain file's geometry and renders its picture.

use myriad::commands::{SceneOptions, load_scene};
use myriad::film::Film;
use myriad::io::{LoadOptions, load_scene as load_description};
use myriad::math::{Rgb, UVec2, Vec3A};
use myriad::scene::BuildOptions;
use myriad::settings::LightSamplerKind;

use crate::common::{TestScene, gltf_variant};
use crate::render::render_with;

const FORMS: [&str; 4] = ["draco", "webp", "quantized", "meshopt"];

fn render(name: &str) -> Film {
    let build = BuildOptions { resolution: Some(UVec2::new(64, 48)), ..Default::default() };
    let loaded = load_scene(Some(&gltf_variant(name)), &SceneOptions { build, load: Default::default() }).unwrap();
    assert!(loaded.report.warnings.is_empty(), "{name}: {:?}", loaded.report.warnings);
    render_with(&TestScene::from(loaded), LightSamplerKind::Tree, 32, 8, 5)
}

/// The image's mean over a block of `4 × 4` blocks (`None`: the whole image).
fn mean(film: &Film, block: Option<(u32, u32)>) -> Rgb {
    let size = film.size();
    let (mut sum, mut n) = (Rgb::ZERO, 0.0f32);
    for y in 0..size.y {
        for x in 0..size.x {
            if block.is_none_or(|(bx, by)| x * 4 / size.x == bx && y * 4 / size.y == by) {
                sum += film.mean((y * size.x + x) as usize);
                n += 1.0;
            }
        }
    }
    sum / n
}

/// Measured (64 × 48, 32 spp, seed 5): Draco, WebP (Blender's quality 100, lossless) 0.00 %
/// from the plain file's mean, the quantised forms +0.01 %. Leaving out meshopt's octahedral
/// normal filter moves the mean by 28 %.
#[test]
fn every_form_renders_the_plain_files_picture() {
    let plain = render("plain");
    for form in FORMS {
        let film = render(form);
        for block in std::iter::once(None).chain((0..16).map(|b| Some((b % 4, b / 4)))) {
            let (a, b) = (mean(&film, block), mean(&plain, block));
            let worst = ((a - b).abs() / b.max(Rgb::splat(1e-3))).max_element();
            let limit = if block.is_none() { 0.005 } else { 0.02 };
            assert!(worst < limit, "{form}, block {block:?}: {a:?} against {b:?} ({:.3} %)", 100.0 * worst);
        }
    }
}

/// Triangle count, total area and bounds of the scene in world space: what the geometry is,
/// whatever order an encoder put the vertices in, however gltfpack merged meshes or scaled
/// quantised positions by their nodes.
fn shape(name: &str) -> (usize, f32, [f32; 6]) {
    let build = BuildOptions { resolution: Some(UVec2::new(8, 6)), ..Default::default() };
    let loaded = load_scene(Some(&gltf_variant(name)), &SceneOptions { build, load: Default::default() }).unwrap();
    let (mut n, mut area) = (0, 0.0f32);
    let (mut lo, mut hi) = (Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN));
    for (t, _) in loaded.scene.geometry.world_triangles() {
        n += 1;
        area += 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
        for p in t {
            (lo, hi) = (lo.min(p), hi.max(p));
        }
    }
    (n, area, [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z])
}

#[test]
fn the_compressed_forms_hold_the_plain_geometry() {
    let (n0, area0, bounds0) = shape("plain");
    for form in FORMS {
        let (n, area, bounds) = shape(form);
        assert_eq!(n, n0, "{form}: triangles");
        assert!((area - area0).abs() < 1e-3 * area0, "{form}: area {area} against {area0}");
        // Draco's and gltfpack's 14-bit positions: within 1/8192 of the 6 m stage.
        assert!(
            bounds.iter().zip(bounds0).all(|(a, b)| (a - b).abs() < 1e-3),
            "{form}: {bounds:?} against {bounds0:?}"
        );
    }
    for form in ["plain", "draco", "webp", "quantized", "meshopt"] {
        let d = load_description(&gltf_variant(form), &LoadOptions::default()).unwrap();
        // gltfpack drops texture coordinates where no texture reads them: the sphere keeps its.
        assert!(d.meshes.iter().all(|m| m.normals.is_some()), "{form}: normals");
        assert!(d.meshes.iter().any(|m| m.uvs.is_some()), "{form}: texture coordinates");
    }
}
