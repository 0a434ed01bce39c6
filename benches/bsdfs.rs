#![allow(missing_docs)] // criterion_group! generates undocumented items
//! BSDF cost per model: one `sample` and one `eval` + `pdf` of a model seen from `wo` (what a
//! path vertex does for the BSDF-sampled direction and the light sample: `eval_pdf`, which
//! shares the half vector and the lobes' terms) (`cargo bench --bench bsdfs`).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use myriad::material::{Bsdf, Diffuse, Principled};
use myriad::math::Rgb;
use myriad::sampling::{Dim, SampleStream};
use std::hint::black_box;

fn models() -> Vec<(&'static str, Bsdf)> {
    let plastic = Principled::new(Rgb::new(0.6, 0.1, 0.1), 0.0, 0.3, 1.5, 1.0, Rgb::ONE);
    vec![
        ("lambert", Bsdf::Diffuse(Diffuse { albedo: Rgb::splat(0.7) })),
        ("principled dielectric", Bsdf::Principled(plastic)),
        (
            "principled metal",
            Bsdf::Principled(Principled::new(Rgb::new(0.95, 0.64, 0.54), 1.0, 0.3, 1.5, 1.0, Rgb::ONE)),
        ),
        ("principled coated", Bsdf::Principled(plastic.with_coat(1.0, 0.05))),
    ]
}

fn bsdfs(c: &mut Criterion) {
    let mut group = c.benchmark_group("bsdf");
    for (name, b) in models() {
        let mut k = 0u64;
        group.bench_function(BenchmarkId::new("sample", name), |bench| {
            bench.iter(|| {
                k += 1;
                let s = SampleStream::new(1, k, 0);
                let wo = myriad::math::warp::square_to_cosine_hemisphere(s.get_2d(0, Dim::PixelJitter, 0));
                black_box(b.sample(black_box(wo), s.get_1d(0, Dim::BsdfLobe, 0), s.get_2d(0, Dim::BsdfDirection, 0)))
            })
        });
        group.bench_function(BenchmarkId::new("eval+pdf", name), |bench| {
            bench.iter(|| {
                k += 1;
                let s = SampleStream::new(2, k, 0);
                let wo = myriad::math::warp::square_to_cosine_hemisphere(s.get_2d(0, Dim::PixelJitter, 0));
                let wi = myriad::math::warp::square_to_cosine_hemisphere(s.get_2d(0, Dim::LightPoint, 0));
                black_box(b.at(black_box(wo)).eval_pdf(wi))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bsdfs);
criterion_main!(benches);
