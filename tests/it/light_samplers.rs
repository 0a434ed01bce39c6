//! Light-sampler contract tests, generic over `LightSampler`: pmf normalisation, sample/pmf
//! agreement, chi-square of picks, per-light unbiasedness, and the one-sample estimator
//! against the exact sum over point lights (exact variance known, so a z-test needs no
//! reference noise).

use crate::common::{Stats, check_intervals_at, draw, pick_chi_square, sidak, z_p_value};
use myriad::light::{AreaEmission, DistantLight, Light, LightId, PointLight, QuadLight, SpotLight, TriangleLight};
use myriad::light_sampler::{
    DEFENSIVE, LEVELS, LearnedSampler, LightSampler, LightStrategy, Observations, ShadingContext,
};
use myriad::material::GlossyLobes;
use myriad::math::{Rgb, Vec3A};
use myriad::sampling::{Dim, SampleStream};
use myriad::settings::LightSamplerKind;

/// Uniform number for test case `i`, stream `salt`.
pub fn rnd(i: u64, salt: u64) -> f32 {
    SampleStream::new(salt, i, 0).get_1d(0, Dim::LightSelect, 0)
}

/// A mixed light set with powers over 3 decades: quads and triangles facing various ways,
/// points, spots and a sun.
pub fn mixed_lights(n: usize) -> Vec<Light> {
    (0..n)
        .map(|i| {
            let i64_ = i as u64;
            let p = Vec3A::new(rnd(i64_, 1) * 8.0 - 4.0, rnd(i64_, 2) * 4.0, rnd(i64_, 3) * 8.0 - 4.0);
            let power = 10f32.powf(3.0 * rnd(i64_, 4));
            let dir = Vec3A::new(rnd(i64_, 5) - 0.5, rnd(i64_, 6) - 0.5, rnd(i64_, 7) - 0.5).normalize();
            let emission = AreaEmission { radiance: Rgb::new(1.0, 0.8, 0.6) * power, two_sided: i % 7 == 0 };
            match i % 6 {
                0 | 1 => {
                    let t = dir.any_orthonormal_vector() * 0.2;
                    let b = dir.cross(t);
                    Light::Quad(QuadLight::new(p, t, b, emission).unwrap())
                }
                2 => Light::Triangle(
                    TriangleLight::new([p, p + Vec3A::X * 0.3, p + Vec3A::Z * 0.2 + dir * 0.1], emission).unwrap(),
                ),
                3 => Light::Point(PointLight { position: p, intensity: Rgb::splat(power) }),
                4 => Light::Spot(SpotLight {
                    position: p,
                    direction: dir,
                    intensity: Rgb::splat(power),
                    cos_inner: 0.9,
                    cos_outer: 0.7,
                    curve: Default::default(),
                }),
                _ if i == 5 => Light::Distant(DistantLight {
                    direction: Vec3A::new(0.3, -1.0, 0.2).normalize(),
                    irradiance: Rgb::splat(2.0),
                }),
                _ => Light::Point(PointLight { position: p, intensity: Rgb::new(power, 0.0, 0.0) }),
            }
        })
        .collect()
}

/// Random shading contexts inside the lights' box, some with no normal (volume-like).
pub fn contexts(n: usize) -> Vec<ShadingContext> {
    (0..n as u64)
        .map(|i| {
            let p = Vec3A::new(rnd(i, 11) * 10.0 - 5.0, rnd(i, 12) * 5.0 - 0.5, rnd(i, 13) * 10.0 - 5.0);
            let n = if i % 5 == 0 {
                Vec3A::ZERO
            } else {
                Vec3A::new(rnd(i, 14) - 0.5, rnd(i, 15) - 0.3, rnd(i, 16) - 0.5).normalize()
            };
            // Every third context with a normal is a glossy point, whose lobe the tree weighs.
            let lobes = (i % 3 == 1 && n != Vec3A::ZERO).then(|| {
                let mirror = Vec3A::new(rnd(i, 17) - 0.5, rnd(i, 18), rnd(i, 19) - 0.5).normalize();
                GlossyLobes::new(mirror, rnd(i, 20) * 0.5, [(0.5, 0.02 + rnd(i, 21) * 0.3), (0.2, 0.05)])
            });
            ShadingContext { lobes, ..ShadingContext::new(p, n) }
        })
        .collect()
}

fn one_light_sampler(kind: LightSamplerKind, lights: &[Light]) -> myriad::light_sampler::AnyLightSampler {
    match LightStrategy::build(kind, lights, Vec3A::ZERO, 10.0).sampler() {
        Some(s) => s.clone(),
        None => panic!("{kind} is a one-light sampler"),
    }
}

/// The one-light samplers under test.
pub const SAMPLERS: [LightSamplerKind; 5] = [
    LightSamplerKind::Uniform,
    LightSamplerKind::Power,
    LightSamplerKind::Local,
    LightSamplerKind::Tree,
    LightSamplerKind::Cells,
];

#[test]
fn every_light_owns_the_values_its_pmf_says() {
    let lights = mixed_lights(200);
    for kind in SAMPLERS {
        let s = one_light_sampler(kind, &lights);
        for ctx in &contexts(12) {
            check_intervals_at(&s, ctx, lights.len());
            // Σ pmf = 1, except that the tree may find a dead branch (a cluster whose bounds
            // reach the point while none of its children's do): its values pick nothing. So
            // may `cells`, in the cells it leaves to the tree.
            let total: f64 = (0..lights.len()).map(|i| s.pmf(ctx, LightId(i as u32)) as f64).sum();
            let may_miss = matches!(kind, LightSamplerKind::Tree | LightSamplerKind::Cells);
            assert!((total - 1.0).abs() < 1e-5 || may_miss && total < 1.0, "{kind}: Σ pmf = {total}");
        }
    }
}

#[test]
fn picks_of_independent_numbers_follow_the_pmf() {
    let lights = mixed_lights(200);
    let ctxs = contexts(12);
    let alpha = sidak(SAMPLERS.len() * ctxs.len());
    for kind in SAMPLERS {
        let s = one_light_sampler(kind, &lights);
        for (i, ctx) in ctxs.iter().enumerate() {
            let r = pick_chi_square(&s, ctx, lights.len(), 50_000, i as u64);
            assert!(r.p > alpha, "{kind} at {ctx:?}: {r:?}");
        }
    }
}

/// `n` point lights scattered over a 20 m square 1–4 m up, intensities log-uniform over six
/// decades: at 10⁶ lights the dimmest have pmf ~10⁻¹¹, far below what a 24- or 32-bit number
/// can choose, and together they hold a share of the power that a test can see.
fn dim_and_bright(n: usize) -> Vec<Light> {
    let unit = |x: u64| (x >> 11) as f32 / (1u64 << 53) as f32;
    (0..n as u64)
        .map(|i| {
            let position = Vec3A::new(
                20.0 * unit(draw(i, 1)) - 10.0,
                1.0 + 3.0 * unit(draw(i, 2)),
                20.0 * unit(draw(i, 3)) - 10.0,
            );
            Light::Point(PointLight { position, intensity: Rgb::splat(10f32.powf(6.0 * unit(draw(i, 4)))) })
        })
        .collect()
}

/// Share of the pmf in lights below 2⁻²⁴, and the pick-count chi-square at `ctx`.
fn million_light_check(kind: LightSamplerKind, n: usize, draws: u64) {
    let lights = dim_and_bright(n);
    let s = one_light_sampler(kind, &lights);
    let ctx = ShadingContext::new(Vec3A::new(0.5, 0.0, -0.5), Vec3A::Y);
    let dim: f64 = (0..n as u32).map(|i| s.pmf(&ctx, LightId(i)) as f64).filter(|&p| p < 2f64.powi(-24)).sum();
    // The dim lights hold enough mass that missing them would show.
    assert!(dim * draws as f64 > 1000.0, "{kind}: only {dim} of the pmf is below 2^-24");
    let r = pick_chi_square(&s, &ctx, n, draws, 7);
    eprintln!("{kind}, {n} lights, {draws} draws: pmf below 2^-24: {dim:.4}; {r:?}");
    assert!(r.p > crate::common::ALPHA / 2.0, "{kind} at {n} lights: {r:?}");
}

#[test]
fn at_a_million_lights_picks_follow_the_pmf_down_to_the_dimmest() {
    million_light_check(LightSamplerKind::Power, 1_000_000, 10_000_000);
}

#[test]
fn the_tree_at_a_hundred_thousand_lights_picks_as_its_pmf_says() {
    million_light_check(LightSamplerKind::Tree, 100_000, 4_000_000);
}

/// Above [`myriad::light_sampler::CELLS_MAX_LIGHTS`] lights `cells` tables choose among the
/// tree's clusters and the tree below them: the contract holds as with fewer lights.
#[test]
fn cells_over_clusters_of_many_lights_picks_as_its_pmf_says() {
    let lights = mixed_lights(3000);
    assert!(lights.len() > myriad::light_sampler::CELLS_MAX_LIGHTS);
    let strategy = LightStrategy::build(LightSamplerKind::Cells, &lights, Vec3A::ZERO, 10.0);
    assert_eq!(strategy.label(LightSamplerKind::Cells), "cells");
    let s = strategy.sampler().expect("one light at a time");
    let ctxs = contexts(6);
    let alpha = sidak(ctxs.len());
    for (i, ctx) in ctxs.iter().enumerate() {
        check_intervals_at(s, ctx, lights.len());
        let r = pick_chi_square(s, ctx, lights.len(), 300_000, 40 + i as u64);
        assert!(r.p > alpha, "at {ctx:?}: {r:?}");
    }
    assert!(strategy.cell_stats().is_some_and(|c| c.tables > 0));
}

#[test]
fn power_sampler_is_proportional_to_the_brightest_channel_of_the_flux() {
    let lights = mixed_lights(50);
    let s = one_light_sampler(LightSamplerKind::Power, &lights);
    let ctx = ShadingContext::new(Vec3A::ZERO, Vec3A::Y);
    let weight = |l: &Light| l.flux(10.0).max_element() as f64;
    let total: f64 = lights.iter().map(weight).sum();
    for (i, l) in lights.iter().enumerate() {
        let expect = weight(l) / total;
        let got = s.pmf(&ctx, LightId(i as u32)) as f64;
        assert!((got - expect).abs() <= 1e-5 * expect.max(1e-3), "light {i}: {got} vs {expect}");
    }
}

/// Irradiance-like contribution c_i = I·cos/d² of point light `l` at `ctx` (no occlusion).
fn point_contribution(l: &Light, ctx: &ShadingContext) -> f64 {
    l.sample_li(ctx.p, Default::default(), &[]).map_or(0.0, |s| s.radiance.x as f64 * (s.wi.dot(ctx.n).max(0.0)) as f64)
}

/// The one-sample estimator c_I/p_I against Σ c_i, with its exact variance
/// Σ c_i²/p_i − (Σ c_i)²: a z-test with no noise in the reference.
pub fn check_estimator_against_sum(sampler: &impl LightSampler, lights: &[Light], ctx: &ShadingContext, alpha: f64) {
    let c: Vec<f64> = lights.iter().map(|l| point_contribution(l, ctx)).collect();
    let total: f64 = c.iter().sum();
    let var: f64 = c
        .iter()
        .enumerate()
        .map(|(i, ci)| {
            let p = sampler.pmf(ctx, LightId(i as u32)) as f64;
            assert!(*ci == 0.0 || p > 0.0, "light {i} contributes {ci} but has pmf 0");
            if p > 0.0 { ci * ci / p } else { 0.0 }
        })
        .sum::<f64>()
        - total * total;
    let n = 20_000u64;
    let mut stats = Stats::default();
    for k in 0..n {
        let x = sampler.sample(ctx, draw(k, 99)).map_or(0.0, |s| c[s.light.0 as usize] / s.pmf as f64);
        stats.add(x);
    }
    let se = (var.max(0.0) / n as f64).sqrt();
    let z = (stats.mean() - total) / se.max(1e-12 * total.max(1e-30));
    assert!(
        z_p_value(z) > alpha || (stats.mean() - total).abs() <= 1e-6 * total,
        "mean {} vs exact {total} (z = {z})",
        stats.mean()
    );
}

#[test]
fn one_sample_estimator_matches_the_sum_over_point_lights() {
    // 250 lights: `cells` tables over the lights; 1500: over the tree's clusters.
    for n in [250, 1500] {
        estimator_matches_the_sum(n);
    }
}

fn estimator_matches_the_sum(n: u64) {
    let lights: Vec<Light> = (0..n)
        .map(|i| {
            Light::Point(PointLight {
                position: Vec3A::new(rnd(i, 21) * 20.0 - 10.0, 0.5 + rnd(i, 22) * 3.0, rnd(i, 23) * 20.0 - 10.0),
                intensity: Rgb::splat(10f32.powf(4.0 * rnd(i, 24))),
            })
        })
        .collect();
    let ctxs: Vec<ShadingContext> = (0..6u64)
        .map(|i| ShadingContext::new(Vec3A::new(rnd(i, 31) * 16.0 - 8.0, 0.0, rnd(i, 32) * 16.0 - 8.0), Vec3A::Y))
        .collect();
    // Two light counts, each every sampler at every context.
    let alpha = sidak(2 * SAMPLERS.len() * ctxs.len());
    for kind in SAMPLERS {
        let s = one_light_sampler(kind, &lights);
        for ctx in &ctxs {
            check_estimator_against_sum(&s, &lights, ctx, alpha);
        }
    }
}

/// Whether a light lies on the x < `x` side (behind a wall there, for the `learned` tests);
/// directional lights never do.
fn left_of(x: f32) -> impl Fn(&Light) -> bool {
    move |l: &Light| {
        let b = l.bounds();
        !b.infinite && b.centroid().x < x
    }
}

/// A `learned` sampler over `lights` after one pass of observations at `ctxs`, in which
/// every light with `hidden(light)` was occluded and every other one got through.
fn trained(lights: &[Light], ctxs: &[ShadingContext], hidden: &dyn Fn(&Light) -> bool) -> LearnedSampler {
    let mut learned = LearnedSampler::new(lights, Vec3A::ZERO, 10.0);
    let mut seen = Observations::default();
    for (i, ctx) in ctxs.iter().enumerate() {
        for k in 0..4000u64 {
            let u = SampleStream::new(99, i as u64, k).get_1d_u64(0, Dim::LightSelect, 0);
            if let Some(s) = learned.sample(ctx, u) {
                learned.observe(&mut seen, ctx, s.light, 1.0, !hidden(&lights[s.light.0 as usize]));
            }
        }
    }
    learned.learn(seen);
    learned
}

#[test]
fn learned_sampler_moves_samples_off_hidden_lights_and_keeps_its_defensive_floor() {
    let lights = mixed_lights(200);
    let ctxs = contexts(12);
    // Lights on the x < 0 side are behind a wall from everywhere.
    let hidden = left_of(0.0);
    let learned = trained(&lights, &ctxs, &hidden);
    assert!(learned.stats().cells > 0 && learned.stats().samples > 0, "{:?}", learned.stats());
    let tree = LearnedSampler::new(&lights, Vec3A::ZERO, 10.0);
    let floor = DEFENSIVE.powi(LEVELS as i32);
    let alpha = sidak(ctxs.len());
    let (mut moved, mut eligible) = (0, 0);
    for (i, ctx) in ctxs.iter().enumerate() {
        // The contract every sampler keeps: intervals tile, picks follow the pmf.
        check_intervals_at(&learned, ctx, lights.len());
        let r = pick_chi_square(&learned, ctx, lights.len(), 50_000, i as u64);
        assert!(r.p > alpha, "learned at {ctx:?}: {r:?}");
        let (mut hidden_tree, mut hidden_learned) = (0.0f64, 0.0f64);
        for (l, light) in lights.iter().enumerate() {
            let (pt, pl) = (tree.pmf(ctx, LightId(l as u32)), learned.pmf(ctx, LightId(l as u32)));
            // Never below β^levels of the tree's pmf, never 0 where the tree's is not.
            assert!(pl >= floor * pt * (1.0 - 1e-4), "light {l} at {ctx:?}: {pl} < {floor} · {pt}");
            if hidden(light) {
                (hidden_tree, hidden_learned) = (hidden_tree + pt as f64, hidden_learned + pl as f64);
            }
        }
        if hidden_tree > 0.2 {
            eligible += 1;
            moved += (hidden_learned < 0.8 * hidden_tree) as usize;
        }
    }
    assert!(
        eligible >= 4 && moved * 4 >= eligible * 3,
        "the hidden lights kept their share at {} of {eligible} points",
        eligible - moved
    );
}

#[test]
fn learned_sampler_outside_its_grid_samples_as_the_tree() {
    // Trained to shun the x < 0 lights, it has nothing learned for points beyond the
    // scene's bounding sphere (radius 10 here): there its pmf is the tree's, bit for bit.
    let lights = mixed_lights(200);
    let hidden = left_of(0.0);
    let learned = trained(&lights, &contexts(12), &hidden);
    let tree = LearnedSampler::new(&lights, Vec3A::ZERO, 10.0);
    for p in [Vec3A::new(12.5, 0.0, 0.0), Vec3A::new(0.0, -30.0, 2.0), Vec3A::splat(1e9)] {
        let ctx = ShadingContext::new(p, Vec3A::Y);
        for l in 0..lights.len() as u32 {
            assert_eq!(learned.interval(&ctx, LightId(l)), tree.interval(&ctx, LightId(l)), "light {l} at {p:?}");
        }
    }
}

#[test]
fn learned_sampler_keeps_the_tree_where_little_is_hidden() {
    // The x < −3.4 lights (a twelfth of them) are hidden from everywhere. Where the tree
    // gives them under 3 % of its picks, at least 90 % of what the samples offered arrived:
    // those cells have nothing worth learning and sample exactly as the tree does.
    let lights = mixed_lights(200);
    let ctxs = contexts(60);
    let hidden = left_of(-3.4);
    let learned = trained(&lights, &ctxs, &hidden);
    let tree = LearnedSampler::new(&lights, Vec3A::ZERO, 10.0);
    let mut kept = 0;
    for ctx in &ctxs {
        let ids = || (0..lights.len() as u32).map(LightId);
        let share: f32 = ids().filter(|l| hidden(&lights[l.0 as usize])).map(|l| tree.pmf(ctx, l)).sum();
        if share < 0.03 {
            kept += 1;
            for l in ids() {
                assert_eq!(
                    learned.interval(ctx, l),
                    tree.interval(ctx, l),
                    "light {l:?} at {ctx:?} (hidden share {share})"
                );
            }
        }
    }
    assert!(kept >= 10, "only {kept} points with little hidden");
}
