//! The environment light: a white furnace (a convex Lambertian object under a constant sky
//! reflects exactly its albedo), a map's samples against its own radiance integrated by
//! hand, a floor lit by a sky map against the irradiance worked out texel by texel, and bad
//! maps as clear errors.

use crate::common::{assert_mentions, chi_square, draw, load};
use crate::render::render_with;
use myriad::image::{Channel, Layers};
use myriad::light::{EnvironmentLight, EnvironmentMap, Light};
use myriad::math::{Rgb, UVec2, Vec3A};
use myriad::settings::LightSamplerKind;
use std::f64::consts::PI;
use std::path::Path;
use std::sync::Arc;

/// Writes an equirectangular map of `w × h` texels (`f(column, row)`, top row first).
fn write_map(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> Rgb) {
    let texels: Vec<Rgb> = (0..h).flat_map(|r| (0..w).map(move |c| (c, r))).map(|(c, r)| f(c, r)).collect();
    let channel = |name: &str, k: usize| Channel { name: name.into(), data: texels.iter().map(|t| t[k]).collect() };
    let layers = Layers { size: UVec2::new(w, h), channels: vec![channel("R", 0), channel("G", 1), channel("B", 2)] };
    myriad::io::exr::write(path, &layers, &[]).unwrap();
}

fn scene_file(dir: &Path, body: &str) -> std::path::PathBuf {
    let path = dir.join("scene.ron");
    std::fs::write(&path, format!("Scene({body})")).unwrap();
    path
}

#[test]
fn a_lambertian_sphere_in_a_white_furnace_reflects_its_albedo() {
    let dir = tempfile::tempdir().unwrap();
    let path = scene_file(
        dir.path(),
        r#"camera: Perspective(eye: (0, 0, 4), look_at: (0, 0, 0), yfov_deg: 30),
           materials: { "grey": Diffuse(albedo: (0.8, 0.6, 0.4)) },
           objects: [ Sphere(center: (0, 0, 0), radius: 1, subdivisions: 5, material: "grey") ],
           environment: Constant(radiance: (1, 1, 1))"#,
    );
    let scene = load(&path, Some(UVec2::new(16, 16)), None).unwrap();
    for kind in [LightSamplerKind::Tree, LightSamplerKind::Uniform, LightSamplerKind::All] {
        let film = render_with(&scene, kind, 64, 4, 1);
        // The centre pixels see the sphere, the corners the sky.
        for (px, expect) in [((8, 8), Rgb::new(0.8, 0.6, 0.4)), ((0, 0), Rgb::ONE)] {
            let i = px.1 * 16 + px.0;
            let (m, v) = (film.mean(i), film.variance_of_mean(i));
            for c in 0..3 {
                let tol = 5.0 * v[c].sqrt() + 1e-4;
                assert!((m[c] - expect[c]).abs() <= tol, "{kind} pixel {px:?} channel {c}: {} vs {}", m[c], expect[c]);
            }
        }
    }
}

#[test]
fn a_white_glass_sphere_in_a_white_furnace_neither_gains_nor_loses() {
    // Rough, lossless glass under a constant sky: whatever path a ray takes through it, it
    // ends on the sky, so every pixel is 1 but for the little the depth limit cuts off.
    let dir = tempfile::tempdir().unwrap();
    let path = scene_file(
        dir.path(),
        r#"camera: Perspective(eye: (0, 0, 4), look_at: (0, 0, 0), yfov_deg: 30),
           objects: [ Mesh(path: "sphere.gltf") ],
           environment: Constant(radiance: (1, 1, 1))"#,
    );
    // A sphere of glass as a glTF (RON has no glass material), from the RON sphere's triangles.
    let sphere = myriad::scene::shapes::sphere_mesh("sphere", Vec3A::ZERO, 1.0, 5, 0);
    let glass = serde_json::json!({"pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0.4},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                       "KHR_materials_volume": {"thicknessFactor": 1}}});
    write_gltf_mesh(&dir.path().join("sphere.gltf"), &sphere.positions, &sphere.triangles, glass, "test");
    let scene = load(&path, Some(UVec2::new(16, 16)), None).unwrap();
    let film = render_with(&scene, LightSamplerKind::Tree, 256, 16, 1);
    for i in [8 * 16 + 8, 6 * 16 + 7, 0] {
        let (m, v) = (film.mean(i), film.variance_of_mean(i));
        assert!(
            m.x > 0.97 - 5.0 * v.x.sqrt() && m.x < 1.0 + 5.0 * v.x.sqrt() + 1e-3,
            "pixel {i}: {} ± {}",
            m.x,
            v.x.sqrt()
        );
    }
}

/// Writes a glTF holding one mesh of `material`, as written by `generator`.
fn write_gltf_mesh(
    path: &Path,
    positions: &[Vec3A],
    triangles: &[[u32; 3]],
    material: serde_json::Value,
    generator: &str,
) {
    let mut bytes: Vec<u8> = positions.iter().flat_map(|p| [p.x, p.y, p.z]).flat_map(f32::to_le_bytes).collect();
    let index_offset = bytes.len();
    bytes.extend(triangles.iter().flatten().flat_map(|i| i.to_le_bytes()));
    let (lo, hi) =
        positions.iter().fold((Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN)), |(a, b), &p| (a.min(p), b.max(p)));
    std::fs::write(path.with_extension("bin"), &bytes).unwrap();
    let uri = path.with_extension("bin").file_name().unwrap().to_string_lossy().into_owned();
    let doc = serde_json::json!({
        "asset": {"version": "2.0", "generator": generator},
        "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [material],
        "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_volume"],
        "buffers": [{"byteLength": bytes.len(), "uri": uri}],
        "bufferViews": [{"buffer": 0, "byteLength": index_offset}, {"buffer": 0, "byteOffset": index_offset, "byteLength": bytes.len() - index_offset}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3", "min": lo.to_array(), "max": hi.to_array()},
            {"bufferView": 1, "componentType": 5125, "count": triangles.len() * 3, "type": "SCALAR"}
        ]
    });
    std::fs::write(path, doc.to_string()).unwrap();
}

/// The centre pixel of `object` (a glTF of one mesh) seen from 4 m along +Z under a white sky.
fn centre_under_white_sky(object: (&[Vec3A], &[[u32; 3]]), material: serde_json::Value, generator: &str) -> (Rgb, Rgb) {
    let dir = tempfile::tempdir().unwrap();
    write_gltf_mesh(&dir.path().join("object.gltf"), object.0, object.1, material, generator);
    let path = scene_file(
        dir.path(),
        r#"camera: Perspective(eye: (0, 0, 4), look_at: (0, 0, 0), yfov_deg: 2),
           objects: [ Mesh(path: "object.gltf") ], environment: Constant(radiance: (1, 1, 1))"#,
    );
    let scene = load(&path, Some(UVec2::new(1, 1)), None).unwrap();
    let film = render_with(&scene, LightSamplerKind::Tree, 4096, 24, 7);
    (film.mean(0), film.variance_of_mean(0))
}

/// A unit cube centred at the origin, faces counter-clockwise seen from outside.
fn unit_cube() -> (Vec<Vec3A>, Vec<[u32; 3]>) {
    let mesh = myriad::scene::shapes::box_mesh("cube", Vec3A::ONE, 0);
    (mesh.positions, mesh.triangles)
}

#[test]
fn absorbing_glass_keeps_what_beer_lambert_says() {
    // Looking straight through a smooth unit cube of IOR 1.5 at a white sky: Fresnel R = 0.04
    // at each face, a = the transmittance of 1 m, and every internal bounce leaves for the
    // sky: R + (1 − R)²·a / (1 − R·a). The specification's volume makes a = colour^(d/dist);
    // for a file Blender wrote, Cycles' absorption node makes a = exp(−(1 − colour)·d/dist).
    let (positions, triangles) = unit_cube();
    let volume = serde_json::json!({"pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                       "KHR_materials_volume": {"thicknessFactor": 1, "attenuationDistance": 1,
                                                "attenuationColor": [0.5, 0.25, 1.0]}}});
    let r = 0.04f32;
    let expect = |a: f32| r + (1.0 - r) * (1.0 - r) * a / (1.0 - r * a);
    for (generator, a) in [
        ("test", Rgb::new(0.5, 0.25, 1.0)),
        ("Khronos glTF Blender I/O v5.0.21", Rgb::new((-0.5f32).exp(), (-0.75f32).exp(), 1.0)),
    ] {
        let (m, v) = centre_under_white_sky((&positions, &triangles), volume.clone(), generator);
        for c in 0..3 {
            let e = expect(a[c]);
            assert!(
                (m[c] - e).abs() < 5.0 * v[c].sqrt() + 2e-3,
                "{generator}: channel {c}: {} ± {} vs {e}",
                m[c],
                v[c].sqrt()
            );
        }
    }
}

#[test]
fn transmission_without_a_volume_is_a_thin_sheet_unless_blender_wrote_it() {
    // One quad of glass tinted (0.5, 1, 1) facing the camera under a white sky. A thin sheet
    // (the specification's default) transmits the base colour once: R + (1 − R)·base; a solid
    // surface (Blender's import: Cycles' solid glass) transmits √base at its one crossing.
    let quad =
        myriad::scene::shapes::quad_mesh("sheet", Vec3A::new(-1.0, -1.0, 0.0), Vec3A::X * 2.0, Vec3A::Y * 2.0, 0);
    let sheet = serde_json::json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}}});
    let r = 0.04f32;
    for (generator, tint) in [("test", 0.5f32), ("Khronos glTF Blender I/O v5.0.21", 0.5f32.sqrt())] {
        let (m, v) = centre_under_white_sky((&quad.positions, &quad.triangles), sheet.clone(), generator);
        let e = r + (1.0 - r) * tint;
        assert!((m.x - e).abs() < 5.0 * v.x.sqrt() + 2e-3, "{generator}: {} ± {} vs {e}", m.x, v.x.sqrt());
    }
}

/// A small map with a bright spot, a dim sky gradient and a black lower half.
fn test_map() -> (u32, u32, impl Fn(u32, u32) -> Rgb) {
    let (w, h) = (32u32, 16u32);
    (w, h, move |c: u32, r: u32| {
        if r >= h / 2 {
            Rgb::ZERO
        } else if (c, r) == (5, 3) {
            Rgb::new(400.0, 300.0, 200.0)
        } else {
            Rgb::new(0.2, 0.4, 1.0) * (1.0 + r as f32)
        }
    })
}

/// Exact solid angle of map row `r` of `h` (a band of θ), per texel of `w`.
fn texel_solid_angle(r: u32, w: u32, h: u32) -> f64 {
    let (t0, t1) = (PI * r as f64 / h as f64, PI * (r + 1) as f64 / h as f64);
    2.0 * PI / w as f64 * (t0.cos() - t1.cos())
}

#[test]
fn map_samples_integrate_the_map_and_follow_their_pdf() {
    let (w, h, f) = test_map();
    let texels: Vec<Rgb> = (0..h).flat_map(|r| (0..w).map(move |c| (c, r))).map(|(c, r)| f(c, r)).collect();
    let map = Arc::new(EnvironmentMap::new(w as usize, h as usize, texels.clone()).unwrap());
    let env = EnvironmentLight { radiance: Rgb::splat(2.0), map: Some(map), rotation: 0.4 };
    // ∫ L dω by hand, texel by texel.
    let exact: f64 = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .map(|(c, r)| 2.0 * texels[(r * w + c) as usize].y as f64 * texel_solid_angle(r, w, h))
        .sum();
    let n = 400_000u64;
    let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
    for k in 0..n {
        let s = env.sample_li([draw(k, 1), draw(k, 2)]).expect("the map emits");
        let pdf = env.pdf(s.wi);
        assert!((pdf - s.pdf).abs() <= 1e-3 * s.pdf, "sample pdf {} vs pdf() {pdf} at {}", s.pdf, s.wi);
        let x = s.radiance.y as f64 / s.pdf as f64;
        (sum, sum_sq) = (sum + x, sum_sq + x * x);
    }
    let mean = sum / n as f64;
    let se = ((sum_sq / n as f64 - mean * mean) / n as f64).sqrt();
    assert!((mean - exact).abs() < 5.0 * se, "E[L/pdf] = {mean} ± {se}, ∫L dω = {exact}");

    // Unrotated, the sampled directions in (θ, φ) cells, one per texel (the centre column
    // looks along +X, columns run towards +Z, the top row is +Y), against pdf() integrated
    // over each cell: pdf·sin θ is constant within a texel, so a few points per cell suffice.
    let env = EnvironmentLight { rotation: 0.0, ..env };
    let cell = |d: Vec3A| {
        let u = (0.5 + (d.z as f64).atan2(d.x as f64) / (2.0 * PI)).rem_euclid(1.0);
        let v = (d.y as f64).clamp(-1.0, 1.0).acos() / PI;
        ((v * h as f64) as usize).min(h as usize - 1) * w as usize + ((u * w as f64) as usize).min(w as usize - 1)
    };
    let mut counts = vec![0.0f64; (w * h) as usize];
    for k in 0..n {
        counts[cell(env.sample_li([draw(k, 3), draw(k, 4)]).unwrap().wi)] += 1.0;
    }
    let sub = 4;
    let expected: Vec<f64> = (0..w * h)
        .map(|t| {
            let (c, r) = (t % w, t / w);
            let (dphi, dtheta) = (2.0 * PI / w as f64, PI / h as f64);
            let mut acc = 0.0;
            for a in 0..sub {
                for b in 0..sub {
                    let theta = (r as f64 + (a as f64 + 0.5) / sub as f64) * dtheta;
                    let phi = 2.0 * PI * ((c as f64 + (b as f64 + 0.5) / sub as f64) / w as f64 - 0.5);
                    let d = Vec3A::new(
                        (theta.sin() * phi.cos()) as f32,
                        theta.cos() as f32,
                        (theta.sin() * phi.sin()) as f32,
                    );
                    acc += env.pdf(d) as f64 * theta.sin();
                }
            }
            acc / (sub * sub) as f64 * dphi * dtheta * n as f64
        })
        .collect();
    let r = chi_square(&counts, &expected);
    assert!(r.p > 1e-3, "{r:?}");
}

#[test]
fn a_floor_under_a_sky_map_gets_the_irradiance_of_the_upper_texels() {
    // Direct light only, no occlusion: the floor's radiance is ρ/π · Σ L·cos θ·ΔΩ over the
    // texels above the horizon (the map's lower half is black, so nothing comes from below).
    let (w, h, f) = test_map();
    let dir = tempfile::tempdir().unwrap();
    write_map(&dir.path().join("sky.exr"), w, h, &f);
    let path = scene_file(
        dir.path(),
        r#"camera: Perspective(eye: (0, 1, 0), look_at: (0, 0, 0), up: (0, 0, -1), yfov_deg: 20),
           materials: { "floor": Diffuse(albedo: (0.5, 0.5, 0.5)) },
           objects: [ Quad(corner: (-50, 0, 50), edge1: (100, 0, 0), edge2: (0, 0, -100), material: "floor") ],
           environment: Map(path: "sky.exr", scale: 0.5, rotate_deg: 30)"#,
    );
    let irradiance: f64 = (0..h / 2)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .map(|(c, r)| {
            // cos θ averaged over the row's band: ∫cos·sin dθ / ∫sin dθ.
            let (t0, t1) = (PI * r as f64 / h as f64, PI * (r + 1) as f64 / h as f64);
            let mean_cos = 0.5 * (t1.sin().powi(2) - t0.sin().powi(2)) / (t0.cos() - t1.cos());
            0.5 * f(c, r).x as f64 * mean_cos * texel_solid_angle(r, w, h)
        })
        .sum();
    let expect = 0.5 / PI * irradiance;
    let scene = load(&path, Some(UVec2::new(8, 8)), None).unwrap();
    assert!(matches!(scene.lights[scene.environment.unwrap() as usize], Light::Environment(_)));
    for kind in [LightSamplerKind::Tree, LightSamplerKind::Power] {
        let film = render_with(&scene, kind, 256, 1, 3);
        let n = 64;
        let mean: f64 = (0..n).map(|i| film.mean(i).x as f64).sum::<f64>() / n as f64;
        let se = (0..n).map(|i| film.variance_of_mean(i).x as f64).sum::<f64>().sqrt() / n as f64;
        assert!((mean - expect).abs() < 5.0 * se + 1e-4 * expect, "{kind}: floor {mean} ± {se}, expected {expect}");
    }
}

#[test]
fn broken_environment_maps_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let cam = "camera: Perspective(eye: (0, 0, 4), look_at: (0, 0, 0), yfov_deg: 30),";
    let error = |env: &str| {
        let path = scene_file(dir.path(), &format!("{cam} environment: {env}"));
        load(&path, Some(UVec2::new(4, 4)), None).err().expect("refused").to_string()
    };
    assert_mentions(&error(r#"Map(path: "nope.exr")"#), &["nope.exr"]);
    write_map(&dir.path().join("nan.exr"), 4, 2, |c, r| if (c, r) == (2, 1) { Rgb::splat(f32::NAN) } else { Rgb::ONE });
    assert_mentions(&error(r#"Map(path: "nan.exr")"#), &["nan.exr", "texel (2, 1)", "finite"]);
    write_map(&dir.path().join("black.exr"), 4, 2, |_, _| Rgb::ZERO);
    assert_mentions(&error(r#"Map(path: "black.exr")"#), &["black.exr", "no light"]);
    std::fs::write(dir.path().join("sky.png"), b"not an image").unwrap();
    assert_mentions(&error(r#"Map(path: "sky.png")"#), &["sky.png", ".exr or .hdr"]);
    assert_mentions(&error(r#"Map(path: "black.exr", scale: -1)"#), &["environment", "scale"]);
    assert_mentions(&error("Constant(radiance: (1, -1, 1))"), &["environment", "negative"]);
}
