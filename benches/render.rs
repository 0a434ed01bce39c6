#![allow(missing_docs)] // criterion_group! generates undocumented items
//! Whole-render throughput on the Cornell grids and BVH build time on the 10⁵-lamp grid
//! (`cargo bench --bench render`). Samples/s = 80·60·spp / time.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use myriad::commands::load_scene;
use myriad::light_sampler::LightStrategy;
use myriad::math::UVec2;
use myriad::render::{Budget, RenderSettings, render};
use myriad::scene::BuildOptions;
use myriad::settings::{Clamp, LightSamplerKind};
use std::path::Path;

fn scene(name: &str, res: UVec2) -> myriad::scene::Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    load_scene(Some(&path), &BuildOptions { resolution: Some(res), camera: None, ..Default::default() }.into())
        .unwrap()
        .scene
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("render_80x60_4spp");
    group.sample_size(10);
    for name in ["cornell-5x5.ron", "cornell-9x9.ron", "cornell-32x32.ron"] {
        let s = scene(name, UVec2::new(80, 60));
        for kind in LightSamplerKind::EVERY {
            if kind == LightSamplerKind::All && s.lights.len() > 100 {
                continue;
            }
            let strategy = LightStrategy::build(kind, &s.lights, s.center, s.radius);
            let (budget, resolution) = (Budget::Spp(4), UVec2::new(80, 60));
            let settings = RenderSettings {
                budget,
                seed: 0,
                max_depth: 8,
                clamp: Clamp::OFF,
                guiding: false,
                caustics: true,
                resolution,
                aovs: Default::default(),
            };
            group.bench_with_input(BenchmarkId::new(kind.name(), name), &name, |b, _| {
                b.iter(|| render(&s, &strategy, &settings, &mut ()).stats.samples)
            });
        }
    }
    group.finish();

    let mut group = c.benchmark_group("scene_build");
    group.sample_size(10);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-320x320.ron");
    let desc = myriad::io::load_scene(&path, &Default::default()).unwrap();
    group.bench_function("cornell-320x320 (102400 lamps)", |b| {
        b.iter(|| myriad::scene::build(desc.clone(), &BuildOptions::default()).unwrap().1.stats.triangles)
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
