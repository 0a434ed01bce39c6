#![allow(missing_docs)] // criterion_group! generates undocumented items
//! Light selection: the cost of one `sample` + the `pmf` MIS needs, per sampler, at 10² to 10⁶
//! lights (`cells` at 10² only: above its 256 lights it is the tree); and the light tree's
//! build time (`cargo bench --bench light_samplers`).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use myriad::light::{AreaEmission, Light, LightId, TriangleLight};
use myriad::light_sampler::{LightSampler, LightStrategy, LightTree, ShadingContext};
use myriad::math::{Rgb, Vec3A};
use myriad::sampling::{Dim, SampleStream};
use myriad::settings::LightSamplerKind;
use std::hint::black_box;

/// `n` small emissive triangles scattered over a 20 m × 20 m ceiling at heights 2–4 m, facing
/// down with some tilt, powers spread over three decades: the shape of a large lighting rig.
pub fn triangles(n: usize) -> Vec<Light> {
    (0..n)
        .map(|i| {
            let s = SampleStream::new(7, i as u64, 0);
            let p = s.get_2d(0, Dim::LightPoint, 0);
            let q = s.get_2d(0, Dim::BsdfDirection, 0);
            let c = Vec3A::new(p.x * 20.0 - 10.0, 2.0 + 2.0 * q.x, p.y * 20.0 - 10.0);
            let size = 0.2 / (n as f32).sqrt().max(1.0) * 10.0;
            let tilt = (q.y - 0.5) * size;
            let v = [c, c + Vec3A::new(size, tilt, 0.0), c + Vec3A::new(0.0, -tilt, size)];
            let power = 10f32.powf(3.0 * s.get_1d(0, Dim::LightSelect, 0));
            TriangleLight::new(v, AreaEmission { radiance: Rgb::splat(power), two_sided: false })
                .map(Light::Triangle)
                .unwrap()
        })
        .collect()
}

fn selection(c: &mut Criterion) {
    let mut group = c.benchmark_group("light_select");
    for n in [100usize, 10_000, 1_000_000] {
        let lights = triangles(n);
        for kind in [
            LightSamplerKind::Uniform,
            LightSamplerKind::Power,
            LightSamplerKind::Local,
            LightSamplerKind::Tree,
            LightSamplerKind::Cells,
        ] {
            if kind == LightSamplerKind::Local && n > 10_000 {
                group.sample_size(10);
            }
            let strategy = LightStrategy::build(kind, &lights, Vec3A::ZERO, 20.0);
            let s = strategy.sampler().expect("a one-light sampler");
            let mut k = 0u64;
            group.bench_with_input(BenchmarkId::new(kind.name(), n), &n, |b, _| {
                b.iter(|| {
                    // A fresh shading point on the floor each call, as in a render.
                    k += 1;
                    let st = SampleStream::new(3, k, 0);
                    let p = st.get_2d(0, Dim::PixelJitter, 0);
                    let ctx = ShadingContext::new(Vec3A::new(p.x * 20.0 - 10.0, 0.0, p.y * 20.0 - 10.0), Vec3A::Y);
                    let picked = s.sample(black_box(&ctx), st.get_1d_u64(0, Dim::LightSelect, 0));
                    black_box(picked.map(|x| s.pmf(&ctx, LightId(x.light.0))))
                })
            });
            group.sample_size(100);
        }
    }
    group.finish();
}

fn tree_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("tree_build");
    group.sample_size(10);
    for n in [1_000usize, 100_000, 1_000_000] {
        let lights = triangles(n);
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| LightTree::new(black_box(&lights)).stats().nodes)
        });
    }
    group.finish();
}

criterion_group!(benches, selection, tree_build);
criterion_main!(benches);
