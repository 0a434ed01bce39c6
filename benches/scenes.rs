#![allow(missing_docs)] // criterion_group! generates undocumented items
//! Scene loading and ray tracing at scale (`cargo bench --bench scenes`):
//! - `gltf_load`: reading and building (lights, BVH) a glTF with 5000 separately exported
//!   emissive quads, each its own mesh, material and node (what Blender writes for 5000 lamp
//!   objects), and one with a 10⁶-triangle emissive mesh;
//! - `bvh_build`: the BVH over 10⁵ and 10⁶ triangles;
//! - `trace`: closest-hit and occlusion queries of incoherent rays (random origins above a
//!   bumpy surface, directions uniform over the sphere), 10⁵ and 10⁶ triangles;
//! - `trace_cornell`: incoherent secondary rays inside `cornell-9x9.ron` (random origins in
//!   the box, directions uniform over the sphere) through myriad's `Scene::intersect` /
//!   `occluded` and, on the same triangles and rays, through obvhs alone (its CWBVH and
//!   triangle test, as its examples use them): the gap is myriad's own overhead;
//! - `rays`: each tracer this build has (built-in, Embree) on the rays a render traces in
//!   `lobby.glb` and `cornell_grid_7.glb` (tests/data/blender): camera rays (closest hit),
//!   bounce rays from the camera's hits in cosine-distributed directions (closest hit) and
//!   shadow rays from them to a point on a light (any hit), 320 × 240 of each.
//!
//! The generated files stay in `target/bench-scenes/` for use with `myriad info` and
//! `myriad render`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use myriad::commands::load_scene;
use myriad::geometry::{Ray, TracerKind, offset_ray_origin};
use myriad::math::{UVec2, Vec3A};
use myriad::sampling::{Dim, SampleStream};
use myriad::scene::{BuildOptions, Scene};
use serde_json::{Value, json};
use std::hint::black_box;
use std::path::{Path, PathBuf};

fn out_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-scenes");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A glTF document around one binary buffer stored next to it as `NAME.bin`.
fn write_gltf(name: &str, mut doc: Value, blob: &[u8]) -> PathBuf {
    let dir = out_dir();
    std::fs::write(dir.join(format!("{name}.bin")), blob).unwrap();
    doc["asset"] = json!({"version": "2.0", "generator": "myriad benches/scenes.rs"});
    doc["extensionsUsed"] = json!(["KHR_materials_emissive_strength"]);
    doc["buffers"] = json!([{"byteLength": blob.len(), "uri": format!("{name}.bin")}]);
    doc["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 0.9, "aspectRatio": 1.333, "znear": 0.1}}]);
    let nodes = doc["nodes"].as_array_mut().unwrap();
    nodes.push(json!({"name": "Camera", "camera": 0, "translation": [0.0, 6.0, 22.0]}));
    doc["scenes"] = json!([{"nodes": (0..nodes.len()).collect::<Vec<_>>()}]);
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, doc.to_string()).unwrap();
    path
}

fn push_f32s(blob: &mut Vec<u8>, values: impl IntoIterator<Item = f32>) {
    for v in values {
        blob.extend_from_slice(&v.to_le_bytes());
    }
}

/// An emissive material with glTF's factor × strength.
fn emitter(name: String, rgb: [f32; 3], strength: f32) -> Value {
    json!({"name": name, "emissiveFactor": rgb,
           "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]},
           "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}})
}

/// `n` ceiling lamps (0.1 m quads facing down at 4 m), each its own mesh, material and node.
fn lamps(n: usize) -> PathBuf {
    let mut blob = Vec::new();
    // One shared quad (positions + indices) in the node's local frame.
    push_f32s(&mut blob, [-0.05, 0.0, -0.05, 0.05, 0.0, -0.05, 0.05, 0.0, 0.05, -0.05, 0.0, 0.05]);
    for i in [0u16, 1, 2, 0, 2, 3] {
        blob.extend_from_slice(&i.to_le_bytes());
    }
    let side = (n as f32).sqrt().ceil() as usize;
    let (mut meshes, mut materials, mut nodes) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..n {
        let s = SampleStream::new(5, i as u64, 0).get_2d(0, Dim::LightSelect, 0);
        materials.push(emitter(format!("lamp.{i:04}"), [1.0, 0.6 + 0.4 * s.x, 0.3 + 0.7 * s.y], 20.0));
        // Blender writes one mesh per object, each with its own accessors; these share them.
        meshes.push(json!({"name": format!("Lamp.{i:04}"),
                           "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": i}]}));
        let (x, z) = ((i % side) as f32, (i / side) as f32);
        let t = [(x / side as f32 - 0.5) * 20.0, 4.0, (z / side as f32 - 0.5) * 20.0];
        nodes.push(json!({"name": format!("Lamp.{i:04}"), "mesh": i, "translation": t}));
    }
    let doc = json!({
        "scene": 0, "nodes": nodes, "meshes": meshes, "materials": materials,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-0.05, 0.0, -0.05], "max": [0.05, 0.0, 0.05]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
    });
    write_gltf(&format!("lamps_{n}"), doc, &blob)
}

/// One indexed mesh of `n` triangles: a bumpy 20 m × 20 m surface, emissive when asked.
fn surface(n: usize, emissive: bool) -> PathBuf {
    let cols = ((n / 2) as f32).sqrt().ceil() as usize;
    let rows = (n / 2).div_ceil(cols);
    let (w, h) = (cols + 1, rows + 1);
    let mut blob = Vec::new();
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for r in 0..h {
        for c in 0..w {
            let s = SampleStream::new(9, (r * w + c) as u64, 0).get_1d(0, Dim::LightSelect, 0);
            let p = [(c as f32 / cols as f32 - 0.5) * 20.0, 0.3 * s, (r as f32 / rows as f32 - 0.5) * 20.0];
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            push_f32s(&mut blob, p);
        }
    }
    let positions = blob.len();
    let mut count = 0;
    'quads: for r in 0..rows {
        for c in 0..cols {
            let v = (r * w + c) as u32;
            for tri in [[v, v + w as u32, v + 1], [v + 1, v + w as u32, v + w as u32 + 1]] {
                if count == n {
                    break 'quads;
                }
                tri.iter().for_each(|i| blob.extend_from_slice(&i.to_le_bytes()));
                count += 1;
            }
        }
    }
    let material = if emissive {
        emitter("glow".into(), [1.0, 0.8, 0.6], 2.0)
    } else {
        json!({"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0]}})
    };
    let doc = json!({
        "scene": 0, "materials": [material],
        "nodes": [{"name": "Surface", "mesh": 0}],
        "meshes": [{"name": "Surface", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": w * h, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": 3 * n, "type": "SCALAR"}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": positions},
                        {"buffer": 0, "byteOffset": positions, "byteLength": blob.len() - positions}],
    });
    let name = if emissive { format!("emissive_surface_{n}") } else { format!("surface_{n}") };
    write_gltf(&name, doc, &blob)
}

fn load(path: &Path) -> Scene {
    load_report(path).scene
}

fn load_report(path: &Path) -> myriad::commands::LoadedScene {
    let options = BuildOptions { resolution: Some(UVec2::new(64, 48)), camera: None, ..Default::default() };
    load_scene(Some(path), &options.into()).unwrap()
}

fn gltf_load(c: &mut Criterion) {
    let mut group = c.benchmark_group("gltf_load");
    group.sample_size(10);
    for (label, path) in [("5000 lamp objects", lamps(5000)), ("1M emissive triangles", surface(1_000_000, true))] {
        group.bench_function(label, |b| b.iter(|| load_report(black_box(&path)).report.stats.triangles));
    }
    group.finish();
}

fn bvh_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("bvh_build");
    group.sample_size(10);
    for n in [100_000usize, 1_000_000] {
        let desc = myriad::io::load_scene(&surface(n, false), &Default::default()).unwrap();
        let options = BuildOptions { resolution: Some(UVec2::new(64, 48)), camera: None, ..Default::default() };
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| myriad::scene::build(desc.clone(), &options).unwrap().1.stats.bvh_build_time)
        });
    }
    group.finish();
}

/// Incoherent rays: origins 0.5–3 m above the surface, directions uniform over the sphere.
fn rays(count: usize) -> Vec<Ray> {
    (0..count)
        .map(|i| {
            let s = SampleStream::new(11, i as u64, 0);
            let (p, d) = (s.get_2d(0, Dim::PixelJitter, 0), s.get_2d(0, Dim::BsdfDirection, 0));
            let q = s.get_1d(0, Dim::LightSelect, 0);
            let origin = Vec3A::new(p.x * 18.0 - 9.0, 0.5 + 2.5 * q, p.y * 18.0 - 9.0);
            let (z, phi) = (1.0 - 2.0 * d.x, std::f32::consts::TAU * d.y);
            let r = (1.0 - z * z).max(0.0).sqrt();
            Ray::new(origin, Vec3A::new(r * phi.cos(), z, r * phi.sin()))
        })
        .collect()
}

fn trace(c: &mut Criterion) {
    const RAYS: usize = 100_000;
    let rays = rays(RAYS);
    let mut group = c.benchmark_group("trace");
    group.sample_size(10);
    group.throughput(Throughput::Elements(RAYS as u64));
    for n in [100_000usize, 1_000_000] {
        let scene = load(&surface(n, false));
        group.bench_with_input(BenchmarkId::new("closest", n), &n, |b, _| {
            b.iter(|| rays.iter().filter(|r| scene.intersect(r, f32::INFINITY).is_some()).count())
        });
        group.bench_with_input(BenchmarkId::new("occluded", n), &n, |b, _| {
            b.iter(|| rays.iter().filter(|r| scene.occluded(r, 5.0)).count())
        });
    }
    group.finish();
}

fn trace_cornell(c: &mut Criterion) {
    const RAYS: usize = 100_000;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-9x9.ron");
    let scene = load(&path);
    let rays: Vec<Ray> = (0..RAYS)
        .map(|i| {
            let s = SampleStream::new(13, i as u64, 0);
            let (p, d) = (s.get_2d(0, Dim::PixelJitter, 0), s.get_2d(0, Dim::BsdfDirection, 0));
            let origin = Vec3A::new(p.x * 1.8 - 0.9, 0.05 + 1.9 * s.get_1d(0, Dim::LightSelect, 0), p.y * 1.8 - 0.9);
            let (z, phi) = (1.0 - 2.0 * d.x, std::f32::consts::TAU * d.y);
            let r = (1.0 - z * z).max(0.0).sqrt();
            Ray::new(origin, Vec3A::new(r * phi.cos(), z, r * phi.sin()))
        })
        .collect();
    let tris: Vec<obvhs::triangle::Triangle> = scene
        .geometry
        .world_triangles()
        .map(|(v, _)| obvhs::triangle::Triangle { v0: v[0], v1: v[1], v2: v[2] })
        .collect();
    let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
        &tris,
        obvhs::BvhBuildParams::medium_build(),
        &mut std::time::Duration::default(),
    );
    let ordered: Vec<_> = bvh.primitive_indices.iter().map(|&i| tris[i as usize]).collect();
    let mut group = c.benchmark_group("trace_cornell");
    group.throughput(Throughput::Elements(RAYS as u64));
    group.bench_function("myriad closest", |b| {
        b.iter(|| rays.iter().filter(|r| scene.intersect(r, f32::INFINITY).is_some()).count())
    });
    group.bench_function("obvhs closest", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| {
                    let ray = obvhs::ray::Ray::new(r.origin, r.dir, 0.0, f32::INFINITY);
                    let mut hit = obvhs::ray::RayHit::none();
                    bvh.ray_traverse(ray, &mut hit, |ray, id| ordered[id].intersect(ray))
                })
                .count()
        })
    });
    group.bench_function("myriad occluded", |b| b.iter(|| rays.iter().filter(|r| scene.occluded(r, 1.0)).count()));
    group.bench_function("obvhs occluded", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| {
                    let ray = obvhs::ray::Ray::new(r.origin, r.dir, 0.0, 1.0);
                    !bvh.ray_traverse_miss(ray, |ray, id| ordered[id].intersect(ray))
                })
                .count()
        })
    });
    group.finish();
}

/// The rays of one pass of a render of `scene`: camera rays; for each camera hit a bounce ray
/// (cosine-distributed about the normal, on the side the camera sees) and a shadow ray
/// (to a point on a light picked uniformly), with the distance it must stay clear.
fn render_rays(scene: &Scene, resolution: UVec2) -> (Vec<Ray>, Vec<Ray>, Vec<(Ray, f32)>) {
    let (mut camera, mut bounce, mut shadow) = (Vec::new(), Vec::new(), Vec::new());
    for y in 0..resolution.y {
        for x in 0..resolution.x {
            let s = SampleStream::new(17, (y * resolution.x + x) as u64, 0);
            let ray = scene.camera.ray(UVec2::new(x, y), resolution, s.get_2d(0, Dim::PixelJitter, 0));
            camera.push(ray);
            let Some(hit) = scene.intersect(&ray, f32::INFINITY) else { continue };
            let n = if hit.n_geom.dot(ray.dir) < 0.0 { hit.n_geom } else { -hit.n_geom };
            let origin = offset_ray_origin(hit.p, n);
            let u = s.get_2d(1, Dim::BsdfDirection, 0);
            let (r, phi) = (u.x.sqrt(), std::f32::consts::TAU * u.y);
            let (t, b) = n.any_orthonormal_pair();
            let d = t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u.x).max(0.0).sqrt();
            bounce.push(Ray::new(origin, d));
            let light = (s.get_1d(1, Dim::LightSelect, 0) * scene.lights.len() as f32) as usize;
            let u = s.get_2d_u64(1, Dim::LightPoint, 0);
            if let Some(ls) = scene.lights.get(light).and_then(|l| l.sample_li(hit.p, u, &scene.images)) {
                if ls.distance.is_finite() {
                    shadow.push((Ray::new(origin, ls.p - origin), 0.999));
                } else {
                    shadow.push((Ray::new(origin, ls.wi), f32::INFINITY));
                }
            }
        }
    }
    (camera, bounce, shadow)
}

fn rays_per_tracer(c: &mut Criterion) {
    let resolution = UVec2::new(320, 240);
    let mut group = c.benchmark_group("rays");
    group.sample_size(10);
    for name in ["lobby", "cornell_grid_7"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/blender/{name}.glb"));
        for &tracer in TracerKind::BUILT {
            let options = BuildOptions { resolution: Some(resolution), tracer, ..Default::default() };
            let scene = load_scene(Some(&path), &options.into()).unwrap().scene;
            let (camera, bounce, shadow) = render_rays(&scene, resolution);
            let label = |kind: &str| format!("{name} {kind} {}", tracer.name());
            for (kind, rays) in [("camera", &camera), ("bounce", &bounce)] {
                group.throughput(Throughput::Elements(rays.len() as u64));
                group.bench_function(label(kind), |b| {
                    b.iter(|| rays.iter().filter(|r| scene.intersect(r, f32::INFINITY).is_some()).count())
                });
            }
            group.throughput(Throughput::Elements(shadow.len() as u64));
            group.bench_function(label("shadow"), |b| {
                b.iter(|| shadow.iter().filter(|(r, t)| scene.occluded(r, *t)).count())
            });
        }
    }
    group.finish();
}

criterion_group!(benches, gltf_load, bvh_build, trace, trace_cornell, rays_per_tracer);
criterion_main!(benches);
