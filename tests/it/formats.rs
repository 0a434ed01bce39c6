//! glTF and OBJ import: Blender's own exports load with the counts their README gives and
//! render what Cycles renders; one Cornell box written as RON, OBJ/MTL and glTF renders alike;
//! broken files are clear errors naming the file and the element.

use crate::common::{assert_mentions, blender, cornell, cornell_json, load, load_error, load_report};
use crate::render::{compare_films, render_guided, render_with};
use myriad::commands::LoadedScene;
use myriad::math::{Rgb, UVec2};
use myriad::scene::{AUTO_CAMERA, Scene};
use myriad::settings::LightSamplerKind;
use serde_json::json;
use std::collections::BTreeMap;
use std::path::Path;

fn light_kinds(scene: &Scene) -> BTreeMap<&'static str, usize> {
    let mut kinds = BTreeMap::new();
    for l in &scene.lights {
        *kinds.entry(l.kind_name()).or_default() += 1;
    }
    kinds
}

/// Lights by kind, e.g. `[("point", 1)]`.
type LightCounts = &'static [(&'static str, usize)];

/// (file, meshes, mesh nodes, triangles, emissive triangles, lights by kind), from the
/// README of `tests/data/blender/`: each emissive face Blender exported as two triangles is
/// one quad light.
const BLENDER_FILES: [(&str, usize, usize, usize, usize, LightCounts); 4] = [
    ("cornell_grid_7.glb", 56, 56, 132, 98, &[("quad", 49)]),
    ("panels.glb", 7, 7, 24, 8, &[("quad", 4)]),
    ("punctual.glb", 2, 2, 14, 0, &[("directional", 1), ("point", 1), ("spot", 1)]),
    ("instanced_lamps.glb", 2, 401, 4802, 4800, &[("quad", 2400)]),
];

#[test]
fn blender_exports_load_with_the_counts_of_their_readme() {
    for (file, meshes, instances, triangles, emissive, lights) in BLENDER_FILES {
        let LoadedScene { scene, report, .. } =
            load_report(&blender(file), None, None).unwrap_or_else(|e| panic!("{file}: {e}"));
        let st = &report.stats;
        assert_eq!(
            (st.meshes, st.instances, st.triangles, st.emissive_triangles),
            (meshes, instances, triangles, emissive),
            "{file}"
        );
        assert_eq!(light_kinds(&scene), lights.iter().copied().collect(), "{file}");
        assert_eq!(st.cameras, ["Camera"], "{file}");
        assert_eq!(report.resolution, UVec2::new(640, 480), "{file}: 4:3 from aspectRatio");
        assert!(report.warnings.is_empty(), "{file}: {:?}", report.warnings);
    }
    // One emissive box mesh placed 400 times: each placement is 6 lights of its own, and the
    // two meshes are stored once each.
    let inst = load_report(&blender("instanced_lamps.glb"), None, None).unwrap().report;
    assert_eq!(inst.stats.stored_triangles, 4802);
}

/// How close our image means must come to Cycles's renders of these files
/// (`tests/data/blender/refs/`), whose own noise at 1024 spp is about 0.3 % on the mean (ours
/// at 64 × 48 and 64 spp adds about as much).
/// (name, tolerance, spp): glossy and glass scenes, whose caustics are noisy, take more samples.
const CYCLES_TOLERANCE: [(&str, f32, u32); 6] = [
    ("cornell_grid_7", 0.01, 64),
    ("panels", 0.01, 64),
    ("punctual", 0.01, 64),
    ("instanced_lamps", 0.01, 64),
    ("materials", 0.01, 1024),
    ("glass", 0.01, 256),
];

/// The mean of each channel of Cycles's reference render of `name`.
fn cycles_mean(name: &str) -> [f32; 3] {
    let path = blender(&format!("refs/{name}.cycles.exr"));
    let (layers, _) = myriad::io::exr::read(&path).unwrap_or_else(|e| panic!("{e}"));
    ["R", "G", "B"].map(|c| {
        let data = &layers.channel(c).unwrap_or_else(|| panic!("{}: no {c} channel", path.display())).data;
        (data.iter().map(|&x| x as f64).sum::<f64>() / data.len() as f64) as f32
    })
}

#[test]
fn the_cycles_references_are_the_renders_their_readme_describes() {
    // The means the README lists, so that a replaced reference cannot go unnoticed.
    let listed = [("cornell_grid_7", [0.6508, 0.6258, 0.5628]), ("instanced_lamps", [1.1359, 0.8519, 0.4543])];
    for (name, mean) in listed {
        let got = cycles_mean(name);
        for c in 0..3 {
            assert!((got[c] - mean[c]).abs() < 1e-4, "{name}: channel {c} mean {} vs {}", got[c], mean[c]);
        }
    }
}

#[test]
fn blender_exports_render_what_cycles_renders() {
    for (name, tolerance, spp) in CYCLES_TOLERANCE {
        let (file, cycles) = (format!("{name}.glb"), cycles_mean(name));
        let scene = load(&blender(&file), Some(UVec2::new(64, 48)), None).unwrap();
        // Cycles' 8 bounces are 9 scattering events.
        let film = render_with(&scene, LightSamplerKind::Tree, spp, 9, 1);
        let means = film.means();
        let mean = means.iter().fold(myriad::math::Rgb::ZERO, |a, &b| a + b) / means.len() as f32;
        for c in 0..3 {
            let ratio = mean[c] / cycles[c];
            eprintln!("{file}: channel {c}: {:+.2} %", 100.0 * (ratio - 1.0));
            assert!((ratio - 1.0).abs() < tolerance, "{file}: channel {c} mean {} vs Cycles {}", mean[c], cycles[c]);
        }
    }
}

#[test]
fn one_cornell_box_as_ron_obj_and_gltf_renders_alike() {
    // The OBJ has no camera, so all three are framed by `--camera auto`: the same bounds give
    // the same camera.
    let size = Some(UVec2::new(40, 30));
    let films: Vec<_> = ["ron", "obj", "gltf"]
        .iter()
        .zip(1u64..)
        .map(|(ext, seed)| {
            let loaded = load_report(&cornell(ext), size, Some(AUTO_CAMERA)).unwrap();
            assert_eq!(loaded.report.stats.triangles, 32, "{ext}");
            let scene = crate::common::TestScene::from(loaded);
            assert!((scene.total_power() - 9.806).abs() < 1e-2, "{ext}: {} W", scene.total_power());
            (ext, render_with(&scene, LightSamplerKind::Tree, 64, 8, seed))
        })
        .collect();
    for (a, b) in [(0, 1), (0, 2), (1, 2)] {
        compare_films(&films[a].1, &films[b].1, 1e-3, &format!("{} vs {}", films[a].0, films[b].0));
    }
    // Without a camera and without `auto`, the error says how to get one.
    let err = load(&cornell("obj"), size, None).err().unwrap().to_string();
    assert!(err.contains("cornell.obj") && err.contains("--camera auto"), "{err}");
}

#[test]
fn broken_gltf_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let glb = std::fs::read(blender("panels.glb")).unwrap();
    let e = load_error(dir.path(), "truncated.glb", &glb[..glb.len() / 2]);
    assert_mentions(&e, &["truncated.glb"]);

    let text = serde_json::to_string(&cornell_json()).unwrap();
    let e = load_error(dir.path(), "syntax.gltf", text.replacen(',', "", 3).as_bytes());
    assert_mentions(&e, &["syntax.gltf", "line"]);

    let e = load_error(dir.path(), "not.glb", b"solid cube\nfacet normal 0 0 1\n");
    assert_mentions(&e, &["not.glb", "not a glTF"]);

    let mut doc = cornell_json();
    doc["buffers"][0]["byteLength"] = json!(100_000);
    let e = load_error(dir.path(), "short.gltf", doc.to_string().as_bytes());
    assert_mentions(&e, &["short.gltf", "buffer"]);

    let mut doc = cornell_json();
    doc["bufferViews"][1]["byteLength"] = json!(12);
    let e = load_error(dir.path(), "view.gltf", doc.to_string().as_bytes());
    assert_mentions(&e, &["view.gltf", "accessors[1]", "do not fit in buffer view 1"]);

    let mut doc = cornell_json();
    doc["meshes"][2]["primitives"][0]["material"] = json!(99);
    let e = load_error(dir.path(), "index.gltf", doc.to_string().as_bytes());
    assert_mentions(&e, &["index.gltf", "material"]);

    let mut doc = cornell_json();
    doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    doc["meshes"][0]["primitives"][0]["extensions"] =
        json!({"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}});
    let e = load_error(dir.path(), "draco.gltf", doc.to_string().as_bytes());
    assert_mentions(&e, &["draco.gltf", "Draco"]);
}

#[test]
fn a_missing_texture_is_a_warning_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = cornell_json();
    doc["images"] = json!([{"uri": "walls.png"}]);
    doc["textures"] = json!([{"source": 0}]);
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    let path = dir.path().join("textured.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let report = load_report(&path, Some(UVec2::new(8, 6)), None).unwrap().report;
    assert!(report.warnings.iter().any(|w| w.contains("walls.png")), "{:?}", report.warnings);
}

#[test]
fn points_and_lines_are_skipped_with_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = cornell_json();
    doc["meshes"][0]["primitives"][0]["mode"] = json!(0);
    doc["meshes"][1]["primitives"][0]["mode"] = json!(1);
    let path = dir.path().join("points.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let report = load_report(&path, Some(UVec2::new(8, 6)), None).unwrap().report;
    let skipped: Vec<_> = report.warnings.iter().filter(|w| w.contains("point and line")).collect();
    assert_eq!(skipped.len(), 1, "{:?}", report.warnings);
}

#[test]
fn an_obj_with_a_missing_texture_warns_and_names_it() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("t.obj"),
        "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("t.mtl"), "newmtl m\nKd 1 1 1\nmap_Kd bricks.jpg\n").unwrap();
    let report = load_report(&dir.path().join("t.obj"), Some(UVec2::new(8, 6)), Some(AUTO_CAMERA)).unwrap().report;
    assert!(report.warnings.iter().any(|w| w.contains("bricks.jpg")), "{:?}", report.warnings);
}

#[test]
fn a_ron_scene_places_a_gltf_file_and_adds_a_light_grid() {
    let dir = tempfile::tempdir().unwrap();
    let ron = format!(
        r#"Scene(
    camera: Perspective(eye: (0, 1, 4.4), look_at: (0, 1, 0), yfov_deg: 37),
    objects: [
        Mesh(path: "{}", transform: (translate: (5, 0, 0))),
        Mesh(path: "{}"),
    ],
    lights: [ Grid(center: (0, 1.98, 0), normal: (0, -1, 0), extent: (1, 1), rows: 4, cols: 4, fill: 0.5,
                   emission: Power(watts: 10, color: (1, 1, 1))) ],
)"#,
        cornell("gltf").display(),
        blender("instanced_lamps.glb").display()
    );
    let path = dir.path().join("mix.ron");
    std::fs::write(&path, ron).unwrap();
    let LoadedScene { scene, report, .. } = load_report(&path, Some(UVec2::new(8, 6)), None).unwrap();
    assert_eq!(report.stats.triangles, 32 + 4802 + 2 * 16);
    assert_eq!(light_kinds(&scene), [("quad", 1 + 16 + 2400)].into_iter().collect());
    // The included file's camera is not used: the RON scene's is.
    assert_eq!(report.stats.cameras.len(), 1);
}

#[test]
fn a_mirrored_gltf_node_keeps_its_emitters_front_side() {
    // The lamp is centred on x = 0, so mirroring it in x leaves it in place; it must still
    // emit downwards (a wrong winding flip would light the ceiling's back instead).
    let dir = tempfile::tempdir().unwrap();
    let mut doc = cornell_json();
    let lamp = doc["nodes"].as_array().unwrap().iter().position(|n| n["name"] == "light").unwrap();
    doc["nodes"][lamp]["scale"] = json!([-1.0, 1.0, 1.0]);
    let path = dir.path().join("mirrored.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let size = Some(UVec2::new(24, 18));
    let mirrored = render_with(&load(&path, size, None).unwrap(), LightSamplerKind::Tree, 32, 3, 1);
    let original = render_with(&load(&cornell("gltf"), size, None).unwrap(), LightSamplerKind::Tree, 32, 3, 2);
    compare_films(&mirrored, &original, 1e-3, "mirrored lamp");
}

/// Image mean (all channels) and its standard error, from the film's per-pixel variances.
fn image_mean(film: &myriad::film::Film) -> (f64, f64) {
    let n = (film.size().x * film.size().y) as usize;
    let (mut sum, mut var) = (0.0f64, 0.0f64);
    for i in 0..n {
        let (m, v) = (film.mean(i), film.variance_of_mean(i));
        sum += (m.x + m.y + m.z) as f64 / 3.0;
        // Channels of one path are correlated: the worst case adds their deviations.
        var += ((v.x.sqrt() + v.y.sqrt() + v.z.sqrt()) as f64 / 3.0).powi(2);
    }
    (sum / n as f64, var.sqrt() / n as f64)
}

#[test]
fn a_striped_emission_texture_emits_its_mean_and_renders_unbiased() {
    // The lamp's texture is half black, half white (nearest filtering): its power is half the
    // untextured lamp's, and the image has the mean of a lamp of half the radiance. NEE picks
    // points on the lamp by its mean while BSDF rays see the stripes: MIS must agree.
    let size = Some(UVec2::new(32, 24));
    let striped = load(&cornell("gltf").with_file_name("cornell-striped.gltf"), size, None).unwrap();
    assert!((striped.total_power() - 0.5 * 9.806).abs() < 0.01, "{} W", striped.total_power());
    let dir = tempfile::tempdir().unwrap();
    let mut doc = cornell_json();
    let lamp = doc["materials"].as_array().unwrap().iter().position(|m| m["name"] == "light").unwrap();
    doc["materials"][lamp]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] = json!(8.5);
    let path = dir.path().join("half.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let half = load(&path, size, None).unwrap();
    let (a, sa) = image_mean(&render_with(&striped, LightSamplerKind::Tree, 256, 4, 1));
    let (b, sb) = image_mean(&render_with(&half, LightSamplerKind::Tree, 256, 4, 2));
    let z = (a - b) / (sa * sa + sb * sb).sqrt();
    assert!(z.abs() < 4.0, "striped lamp {a} vs half-radiance lamp {b} (z = {z})");
}

#[test]
fn an_alpha_mask_cuts_the_surface_out() {
    // A fully transparent base-colour texture in MASK mode: rays pass through the back wall.
    let ray = myriad::geometry::Ray::new(myriad::math::Vec3A::new(0.0, 1.5, 0.0), -myriad::math::Vec3A::Z);
    let size = Some(UVec2::new(8, 6));
    let plain = load(&cornell("gltf"), size, None).unwrap();
    let hit = plain.intersect(&ray, f32::INFINITY).expect("the back wall");
    assert!((hit.t - 1.0).abs() < 1e-4, "{}", hit.t);
    let cut = load(&cornell("gltf").with_file_name("cornell-cutout.gltf"), size, None).unwrap();
    assert!(cut.intersect(&ray, f32::INFINITY).is_none());
    assert!(!cut.occluded(&ray, 10.0));
}

#[test]
fn alpha_blend_lets_rays_through_as_often_as_it_is_transparent() {
    // The cut-out wall again, in BLEND mode at alpha 0.25 without its texture: three rays in
    // four pass, for intersection and shadow rays alike, each ray drawing its own number.
    let dir = tempfile::tempdir().unwrap();
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(cornell("gltf").with_file_name("cornell-cutout.gltf")).unwrap())
            .unwrap();
    let wall = &mut doc["materials"][4];
    wall["alphaMode"] = json!("BLEND");
    wall["pbrMetallicRoughness"] = json!({"baseColorFactor": [0.8, 0.8, 0.8, 0.25]});
    let path = dir.path().join("blend.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let scene = load(&path, Some(UVec2::new(8, 6)), None).unwrap();
    let n = 20_000;
    let (mut passed, mut unshadowed) = (0, 0);
    for k in 0..n {
        // Above the boxes, so that only the wall is in the way.
        let origin = myriad::math::Vec3A::new(-0.8 + (k % 100) as f32 * 0.016, 1.45 + (k / 100) as f32 * 0.002, 0.0);
        let ray = myriad::geometry::Ray::new(origin, -myriad::math::Vec3A::Z);
        passed += scene.intersect(&ray, f32::INFINITY).is_none() as usize;
        unshadowed += !scene.occluded(&ray, 10.0) as usize;
    }
    for (what, count) in [("intersection", passed), ("shadow", unshadowed)] {
        let rate = count as f64 / n as f64;
        let se = (0.75 * 0.25 / n as f64).sqrt();
        assert!((rate - 0.75).abs() < 5.0 * se, "{what} rays pass {rate}, expected 0.75");
    }
}

/// The Cycles reference of `name` averaged over `k × k` blocks (exactly what a box-filtered
/// render at 1/k of its resolution sees), with the variance of each block's mean estimated
/// from the spread of its pixels (which overstates it where the picture itself varies).
fn cycles_downsampled(reference: &Path, k: u32) -> (UVec2, Vec<(Rgb, Rgb)>) {
    let (layers, _) = myriad::io::exr::read(reference).unwrap();
    let rgb = layers.rgb().unwrap();
    let size = layers.size / k;
    let (mut sum, mut sum_sq) =
        (vec![Rgb::ZERO; (size.x * size.y) as usize], vec![Rgb::ZERO; (size.x * size.y) as usize]);
    for y in 0..size.y * k {
        for x in 0..size.x * k {
            let (v, b) = (rgb[(y * layers.size.x + x) as usize], ((y / k) * size.x + x / k) as usize);
            sum[b] += v;
            sum_sq[b] += v * v;
        }
    }
    let n = (k * k) as f32;
    let blocks =
        sum.iter().zip(&sum_sq).map(|(&s, &q)| (s / n, (q - s * s / n).max(Rgb::ZERO) / (n * (n - 1.0)))).collect();
    (size, blocks)
}

/// Renders the scene `glb` (a Blender export, or any scene file) at a quarter of the resolution of its Cycles render
/// `reference` with `spp` and checks them pixel by pixel and over 4 × 4-pixel regions: z = (ours − Cycles) over the
/// two standard errors combined, per channel. Stratified samples converge faster than the
/// i.i.d. error the film's variance estimates, and the reference's is overstated where the
/// picture varies, so without bias the mean z² is at most about 1; bias adds to it, the more
/// over a region, where it accumulates while the noise averages out (fireflies, which make
/// single pixels stray, average out too).
pub fn agrees_with_cycles_pixel_by_pixel(glb: &Path, reference: &Path, spp: u32) {
    let name = reference.file_name().unwrap().to_string_lossy();
    let (size, cycles) = cycles_downsampled(reference, 4);
    let scene = load(glb, Some(size), None).unwrap();
    let film = render_with(&scene, LightSamplerKind::Tree, spp, 9, 5);
    // Where neither image is noisy (an emitter seen directly), the renderers' own float
    // arithmetic still differs: Cycles' emission of 4.8 reads 4.7999005.
    let precision = |v: f32| (1e-4 * v as f64).powi(2);
    let z = |pixels: &[usize], c: usize| {
        let (d, v) = pixels.iter().fold((0.0f64, 0.0f64), |(d, v), &i| {
            let dv = (film.variance_of_mean(i)[c] + cycles[i].1[c]) as f64 + precision(cycles[i].0[c]);
            (d + (film.mean(i)[c] - cycles[i].0[c]) as f64, v + dv)
        });
        d / v.max(1e-12).sqrt()
    };
    let mean_z2 = |groups: &[Vec<usize>]| {
        let zs: Vec<f64> = groups.iter().flat_map(|g| (0..3).map(|c| z(g, c))).collect();
        let worst = zs.iter().fold(0.0f64, |w, z| w.max(z.abs()));
        (zs.iter().map(|z| z * z).sum::<f64>() / zs.len() as f64, worst, zs.len())
    };
    let pixels: Vec<Vec<usize>> = (0..cycles.len()).map(|i| vec![i]).collect();
    let (rw, rh) = (size.x / 4, size.y / 4);
    let regions: Vec<Vec<usize>> = (0..rw * rh)
        .map(|r| {
            let (rx, ry) = (r % rw, r / rw);
            (0..16).map(|k| ((ry * 4 + k / 4) * size.x + rx * 4 + k % 4) as usize).collect()
        })
        .collect();
    // z² has variance ≈ 2 for Gaussian noise; five standard errors of the mean, and a little.
    let bound = |n: usize| 1.0 + 5.0 * (2.0 / n as f64).sqrt() + 0.05;
    let (pixel_z2, _, n) = mean_z2(&pixels);
    assert!(pixel_z2 < bound(n), "{name}: mean z² = {pixel_z2} over {n} pixel channels");
    let (region_z2, worst, n) = mean_z2(&regions);
    eprintln!("{name}: mean z² {pixel_z2:.2} over pixels, {region_z2:.2} over regions, worst region {worst:.1}");
    assert!(region_z2 < bound(n), "{name}: mean z² = {region_z2} over {n} region channels");
    assert!(worst < 6.0, "{name}: a region is {worst} standard errors from Cycles");
}

#[test]
fn punctual_lights_agree_with_cycles_pixel_by_pixel() {
    // A point, a spot with Blender's blend and a sun.
    agrees_with_cycles_pixel_by_pixel(&blender("punctual.glb"), &blender("refs/punctual.cycles.exr"), 256);
}

#[test]
fn principled_materials_agree_with_cycles_pixel_by_pixel() {
    // Metals, plastics, a glossy floor and a coated paint under a point, a spot and a panel.
    agrees_with_cycles_pixel_by_pixel(&blender("materials.glb"), &blender("refs/materials.cycles.exr"), 512);
}

#[test]
fn lamps_inside_glass_render_as_cycles_without_its_light_sampling_bias() {
    // A bulb (an emissive sphere) inside a solid glass sphere, clear or frosted at roughness
    // 0.2, 0.45 and 0.8, and inside a hollow frosted shell: every path to the bulb passes the
    // glass, so the picture is caustics. The references are Cycles' with the bulb found by BSDF
    // rays alone: Cycles' own light sampling overestimates a lamp inside rough glass (2.3 % at
    // 0.45, 9.7 % at 0.8; docs/materials.md), which would fail this test. Caustics are too
    // heavy-tailed for a variance estimated from one render's samples, so the noise of each
    // 4 × 4-pixel region is measured as the spread of its mean over four seeds. Guided paths
    // must give the same picture: two of them again with path guiding on.
    const SEEDS: u64 = 4;
    let unguided =
        ["bulb_clear", "bulb_frosted_02", "bulb_frosted_045", "bulb_frosted_08", "bulb_shell"].map(|n| (n, false));
    for (name, guiding) in unguided.into_iter().chain([("bulb_clear", true), ("bulb_frosted_045", true)]) {
        let reference = blender(&format!("factors/{name}.cycles.exr"));
        let (size, cycles) = cycles_downsampled(&reference, 4);
        let scene = load(&blender(&format!("factors/{name}.glb")), Some(size), None).unwrap();
        let (rw, rh) = (size.x as usize / 4, size.y as usize / 4);
        let region = |i: usize| (i % size.x as usize) / 4 + (i / size.x as usize) / 4 * rw;
        // Per seed, per region: the mean of its pixels (RGB).
        let runs: Vec<Vec<Rgb>> = (0..SEEDS)
            .map(|seed| {
                let film = render_guided(&scene, LightSamplerKind::Tree, 1024, 9, 5 + seed, guiding);
                let mut sums = vec![Rgb::ZERO; rw * rh];
                (0..cycles.len()).for_each(|i| sums[region(i)] += film.mean(i) / 16.0);
                sums
            })
            .collect();
        let (mut theirs, mut their_var) = (vec![Rgb::ZERO; rw * rh], vec![Rgb::ZERO; rw * rh]);
        for (i, (m, v)) in cycles.iter().enumerate() {
            theirs[region(i)] += *m / 16.0;
            their_var[region(i)] += *v / 256.0;
        }
        let (mut z2, mut worst) = (0.0f64, 0.0f64);
        for r in 0..rw * rh {
            let mean = runs.iter().fold(Rgb::ZERO, |a, run| a + run[r]) / SEEDS as f32;
            let spread = runs.iter().fold(Rgb::ZERO, |a, run| a + (run[r] - mean) * (run[r] - mean));
            let var = spread / ((SEEDS - 1) * SEEDS) as f32 + their_var[r];
            for c in 0..3 {
                let z = (mean[c] - theirs[r][c]) as f64 / (var[c] as f64).max(1e-12).sqrt();
                (z2, worst) = (z2 + z * z, worst.max(z.abs()));
            }
        }
        let n = (3 * rw * rh) as f64;
        let ours = runs.iter().flatten().fold(Rgb::ZERO, |a, &v| a + v);
        let ratio = ours / (theirs.iter().fold(Rgb::ZERO, |a, &v| a + v) * SEEDS as f32);
        let name = if guiding { format!("{name} (guided)") } else { name.to_string() };
        eprintln!("{name}: image mean {ratio} of Cycles'; regions: mean z² {:.2}, worst {worst:.1}", z2 / n);
        assert!((ratio - Rgb::ONE).abs().max_element() < 0.01, "{name}: image mean {ratio} of Cycles'");
        // A t statistic over 3 degrees of freedom has variance 3: its square averages 3.
        assert!(z2 / n < 3.0 + 5.0 * (2.0 * 3.0 / n).sqrt() + 0.5, "{name}: regions' mean z² {}", z2 / n);
    }
}

#[test]
fn one_factor_blender_scenes_agree_with_cycles_pixel_by_pixel() {
    // tests/data/blender/factors: one material (or the spot) on a sphere, each against its
    // Cycles render (tools/make_blender_factors.py makes both).
    let names = [
        "metal",
        "plastic",
        "specular",
        "coat",
        "sheen",
        "anisotropic",
        "glass_smooth",
        "glass_rough",
        "alpha_blend",
        "spot",
    ];
    for name in names {
        let (glb, reference) =
            (blender(&format!("factors/{name}.glb")), blender(&format!("factors/{name}.cycles.exr")));
        agrees_with_cycles_pixel_by_pixel(&glb, &reference, 256);
    }
}
