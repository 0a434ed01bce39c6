//! Next-event estimation: light arriving directly at a shading point from the light sources.
//!
//! With a one-light sampler, one light is drawn with the single 64-bit number `Dim::LightSelect`
//! and one point on it with `Dim::LightPoint`; the contribution is divided by the product
//! pmf × pdf and MIS-weighted (power heuristic) against the BSDF's density for the same
//! direction. Where the strategy takes every light (`all`, and the default over a few lights
//! at diffuse points), every light gets its own point (`Dim::LightPoint`, sub-index = light)
//! and selection pmf 1. Delta lights get weight 1: BSDF sampling cannot find them. A sample
//! on an emissive surface that only smooth glass blocks is reached through the glass instead
//! (`mnee`).

use super::guided::Scattering;
use super::light_paths::Highlight;
use super::mnee;
use super::timing::{Stopwatch, timed};
use super::{RayCounters, Tally};
use crate::geometry::{Ray, offset_ray_origin};
use crate::light::{Light, SampleBits};
use crate::light_sampler::{LightStrategy, ShadingContext};
use crate::math::{Rgb, Vec3A, luminance, power_heuristic};
use crate::sampling::{Dim, SampleStream};
use crate::scene::Scene;

/// The two numbers light `id`'s sample takes (draw `sub` of [`Dim::LightPoint`]), only the
/// bits it reads ([`Light::sample_bits`]): none for a point, spot or directional light
/// (numbers have addresses, so leaving one out changes no other).
#[inline(always)]
fn light_numbers(scene: &Scene, id: u32, stream: &SampleStream, bounce: u32, sub: u32) -> [u64; 2] {
    match scene.lights[id as usize].sample_bits() {
        SampleBits::None => [0; 2],
        SampleBits::Top => stream.get_2d_u64_top(bounce, Dim::LightPoint, sub),
        SampleBits::All => stream.get_2d_u64(bounce, Dim::LightPoint, sub),
    }
}

/// The contribution of one chosen light, divided by its selection probability `pmf`, through
/// the volume of absorption `medium` the point lies in; where smooth glass blocks an emissive
/// surface or a point or directional light, the light that reaches the point through it
/// ([`mnee`], as `glass` allows), with the two numbers `u` ([`light_numbers`]).
/// `observe(c, visible)` hears of each shadow ray: the luminance of the unshadowed,
/// unweighted contribution and whether it got through. Always inlined, as
/// [`estimate_direct`].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn light_contribution(
    scene: &Scene,
    id: u32,
    pmf: f32,
    scattering: &Scattering,
    p: Vec3A,
    medium: Rgb,
    glass: mnee::AtVertex,
    highlight: Option<&Highlight>,
    u: [u64; 2],
    counters: &mut RayCounters,
    observe: impl FnOnce(f32, bool),
) -> Rgb {
    let light = &scene.lights[id as usize];
    if glass.smooth && light.is_delta() {
        return Rgb::ZERO;
    }
    let Some(ls) = light.sample_li(p, u, &scene.images) else { return Rgb::ZERO };
    let sp = &scattering.sp;
    // BSDF sampling cannot find a delta light: its density there is not needed.
    let (f, bsdf_pdf) = if light.is_delta() { (sp.eval_cos(ls.wi), 0.0) } else { sp.eval_cos_pdf(ls.wi) };
    // A light behind glass is connected whatever the straight way's cosine says (BSDF
    // sampling weighs its paths by whether the connection would have found them).
    let behind_glass = glass.refractions > 0 && light.connects_through_glass();
    if (f == Rgb::ZERO || !(ls.pdf > 0.0)) && !behind_glass {
        return Rgb::ZERO;
    }
    // Where smooth glass may stand in the way, the connection's walk along it is the shadow
    // ray (and seeds the chain through the glass), else a shadow ray.
    let occluded = if behind_glass {
        let most = glass.refractions;
        let watch = Stopwatch::start(counters.timing);
        let behind = match light {
            Light::Sphere(lamp) => mnee::lamp_through_glass(scene, lamp, &ls, pmf, scattering, p, most, counters),
            _ if light.is_delta() => {
                mnee::delta_through_glass(scene, light, &ls, u, pmf, scattering, p, most, counters)
            }
            _ => match light.area_point(u, &scene.images) {
                Some(point) => mnee::through_glass(scene, &point, pmf, scattering, p, most, counters),
                None => mnee::Behind::Blocked,
            },
        };
        watch.stop(&mut counters.time.glass);
        match behind {
            mnee::Behind::Through(c) => {
                observe(luminance(c), c != Rgb::ZERO);
                return c;
            }
            mnee::Behind::Blocked => true,
            mnee::Behind::Clear => false,
        }
    } else {
        let origin = sp.ray_origin(p, ls.wi);
        counters.shadow_rays += 1;
        counters.time.shadow_rays += counters.timing as u64;
        timed(counters.timing, &mut counters.time.shadow, || {
            if ls.distance.is_infinite() {
                scene.occluded(&Ray::new(origin, ls.wi), f32::INFINITY)
            } else {
                let target = if ls.n == Vec3A::ZERO { ls.p } else { offset_ray_origin(ls.p, ls.n) };
                scene.occluded(&Ray::new(origin, target - origin), 1.0)
            }
        })
    };
    // Only a light on this side of the surface is reached through the volume the point is in;
    // towards the far side the ray leaves it at once.
    let inside = medium != Rgb::ZERO && ls.wi.dot(sp.n_geom) > 0.0;
    let through = if inside { super::transmittance(medium, ls.distance) } else { Rgb::ONE };
    if f == Rgb::ZERO || !(ls.pdf > 0.0) {
        return Rgb::ZERO;
    }
    let unshadowed = f * ls.radiance * through / (pmf * ls.pdf);
    observe(luminance(unshadowed), !occluded);
    if occluded {
        return Rgb::ZERO;
    }
    let weight = match highlight {
        _ if !light.is_delta() => power_heuristic(pmf * ls.pdf, scattering.mixed_pdf(ls.wi, bsdf_pdf)),
        Some(h) => h.weight(scene, id, &ls),
        None => 1.0,
    };
    unshadowed * weight
}

/// Direct light reflected towards the viewer of `scattering` at the surface point of `ctx`
/// (its light-selection context; inside a volume of absorption `medium`, zero outside),
/// estimated with `strategy` and weighed
/// against the density `scattering` samples directions with, and for point and spot lights
/// against light paths where they sample the same path (`highlight`); also through smooth
/// glass, as `glass` allows. Always inlined into the path loop's two copies
/// (`path::Tracer::trace`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn estimate_direct(
    scene: &Scene,
    strategy: &LightStrategy,
    scattering: &Scattering,
    ctx: &ShadingContext,
    medium: Rgb,
    glass: mnee::AtVertex,
    highlight: Option<&Highlight>,
    stream: &SampleStream,
    bounce: u32,
    tally: &mut Tally,
) -> Rgb {
    let (sp, p) = (&scattering.sp, ctx.p);
    let diffuse = sp.is_diffuse();
    match strategy.sampler().filter(|_| !strategy.takes_every_light(diffuse)) {
        None => {
            let mut sum = Rgb::ZERO;
            for i in 0..scene.lights.len() as u32 {
                let u = light_numbers(scene, i, stream, bounce, i);
                let rays = &mut tally.rays;
                sum += light_contribution(scene, i, 1.0, scattering, p, medium, glass, highlight, u, rays, |_, _| {});
            }
            sum
        }
        Some(sampler) => {
            let u_select = stream.get_1d_u64(bounce, Dim::LightSelect, 0);
            let rays = &mut tally.rays;
            let choice = timed(rays.timing, &mut rays.time.choice, || {
                sampler.sample_prefetching(ctx, diffuse, u_select, &scene.lights)
            });
            match choice {
                Some(s) => {
                    debug_assert!(s.pmf > 0.0);
                    let Tally { rays, seen, .. } = tally;
                    let observe = |c, visible| seen.record_light_sample(strategy, ctx, s.light, c, visible);
                    let (id, pmf) = (s.light.0, s.pmf);
                    let u = light_numbers(scene, id, stream, bounce, 0);
                    light_contribution(scene, id, pmf, scattering, p, medium, glass, highlight, u, rays, observe)
                }
                None => Rgb::ZERO,
            }
        }
    }
}
