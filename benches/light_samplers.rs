#![allow(missing_docs)] // criterion_group! generates undocumented items
//! Cost of one light selection (`sample` + the `pmf` MIS needs) per sampler, 10² to 10⁶
//! lights on a grid (`cargo bench --bench light_samplers`).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use myriad::light::{AreaEmission, Light, LightId, QuadLight};
use myriad::light_sampler::{LightSampler, LightSamplerKind, LightStrategy, ShadingContext};
use myriad::math::{Rgb, Vec3A};
use std::hint::black_box;

/// `n` small quads on a ceiling, powers spread over two decades.
fn grid(n: usize) -> Vec<Light> {
    let side = (n as f32).sqrt().ceil() as usize;
    (0..n)
        .map(|i| {
            let (x, z) = ((i % side) as f32 / side as f32, (i / side) as f32 / side as f32);
            let s = 0.5 / side as f32;
            let power = 10f32.powf(2.0 * ((i * 7919) % 1000) as f32 / 1000.0);
            let e = AreaEmission { radiance: Rgb::splat(power), two_sided: false };
            Light::Quad(
                QuadLight::new(Vec3A::new(x * 2.0 - 1.0, 2.0, z * 2.0 - 1.0), Vec3A::Z * s, Vec3A::X * s, e).unwrap(),
            )
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("light_select");
    for n in [100usize, 10_000, 1_000_000] {
        let lights = grid(n);
        for kind in [LightSamplerKind::Uniform, LightSamplerKind::Power] {
            let LightStrategy::One(s) = LightStrategy::build(kind, &lights, 2.0) else { unreachable!() };
            let ctx = ShadingContext { p: Vec3A::new(0.1, 0.5, 0.2), n: Vec3A::Y };
            let mut k = 0u32;
            group.bench_with_input(BenchmarkId::new(kind.name(), n), &n, |b, _| {
                b.iter(|| {
                    k = k.wrapping_add(0x9e37_79b9);
                    let u = (k >> 8) as f32 / (1u32 << 24) as f32;
                    let picked = s.sample(black_box(&ctx), u).unwrap();
                    black_box(s.pmf(&ctx, LightId(picked.light.0)))
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
