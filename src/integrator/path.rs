//! The path tracer: camera ray → bounces with NEE and MIS → radiance.
//!
//! pbrt-v4's `PathIntegrator` structure. At every vertex: add emission (MIS-weighted against
//! NEE when the vertex was found by BSDF sampling), stop at `max_depth` scattering events
//! (1 = direct lighting only), estimate direct light, sample the BSDF, and from the fourth
//! scattering event on ([`RR_MIN_DEPTH`]) play Russian roulette. Every random number is
//! addressed by (bounce, `Dim`), so the choices of one decision never shift another's
//! numbers. Each contribution may be clamped as Cycles clamps ([`Clamp`]; off by default).

use super::direct::estimate_direct;
use super::guided::Scattering;
use super::light_paths::{Highlight, LightPaths};
use super::mnee::{AtVertex, GlassChain, MAX_CASTERS};
use super::surface::Surface;
use super::timing::{Stopwatch, timed};
use super::transmittance;
use super::{RayCounters, Tally};
use crate::geometry::{Ray, SurfaceHit};
use crate::guiding::Guide;
use crate::light::{Light, LightId};
use crate::light_sampler::{LightStrategy, ShadingContext};
use crate::math::{Rgb, Vec3A, power_heuristic};
use crate::sampling::{Dim, SampleStream};
use crate::scene::Scene;
use crate::settings::Clamp;

/// First-hit data of one camera sample, for the AOVs.
#[derive(Clone, Copy, Debug, Default)]
pub struct FirstHit {
    /// Base colour of the material hit.
    pub albedo: Rgb,
    /// Shading normal, facing the camera.
    pub normal: Vec3A,
    /// Distance along the camera ray.
    pub depth: f32,
}

impl FirstHit {
    /// What the AOVs record of the camera ray's `hit`, seen from `wo`.
    fn of(scene: &Scene, hit: &SurfaceHit, wo: Vec3A) -> Self {
        let normal = if hit.n_shading.dot(wo) < 0.0 { -hit.n_shading } else { hit.n_shading };
        let albedo = scene.materials[hit.material as usize].base_color_at(hit.uv, &scene.images);
        Self { albedo, normal, depth: hit.t }
    }
}

/// Russian roulette starts once this many scattering events are behind the path. Measured
/// on cornell_grid_7.glb (320×240, 64 spp, 9 events, 2 threads, 3 seeds, against Cycles'
/// 1024-spp render), relMSE / million rays: survival max(β) from 2 events 0.0079 (an older
/// build); √max(β) from 3 events (Cycles' rule) 0.0050 / 21.8; ∜max(β) from 4 events
/// 0.0040 / 25.4, 1.19× the CPU time for 1.25× less error (1.05× the efficiency; materials.glb
/// 0.228 → 0.210 for 1.04× the rays); without roulette 0.0037 / 32.5 (0.88×).
const RR_MIN_DEPTH: u32 = 4;

// Light paths weigh next-event estimation at a path's second vertex with the path's density
// there, which roulette before it would change.
const _: () = assert!(RR_MIN_DEPTH >= 2, "light paths assume no roulette before the second vertex");

/// What one camera path found.
#[derive(Clone, Copy, Debug)]
pub struct PathSample {
    /// Radiance arriving along the camera ray.
    pub radiance: Rgb,
    /// The first surface hit, for AOVs.
    pub first_hit: Option<FirstHit>,
}

/// The vertex a BSDF-sampled ray left from, for the MIS weight where the ray meets a light.
#[derive(Clone, Copy, Debug)]
struct Previous {
    /// Its light-sampling context.
    ctx: ShadingContext,
    /// The density with which its BSDF chose the ray.
    bsdf_pdf: f32,
    /// Whether its BSDF is Lambert's (what next-event estimation there chose by:
    /// [`LightStrategy::selection_pmf`]).
    diffuse: bool,
}

/// Radiance from the environment and the suns with an angle along `dir` for a ray that left
/// the scene, MIS-weighted against next-event estimation when the ray was found by BSDF
/// sampling at `prev` (a camera ray sees a sun only where it is camera-visible). Always
/// inlined into the path loop ([`Tracer::trace`]).
#[inline(always)]
fn escaped(
    scene: &Scene,
    strategy: &LightStrategy,
    dir: Vec3A,
    prev: Option<Previous>,
    counters: &mut RayCounters,
) -> Rgb {
    let mut l = Rgb::ZERO;
    if let Some(id) = scene.environment {
        let Light::Environment(env) = &scene.lights[id as usize] else { unreachable!("the environment index") };
        l += env.radiance_from(dir) * bsdf_hit_weight(strategy, id, prev, |_| env.pdf(dir), counters);
    }
    for &id in &scene.suns {
        let Light::Sun(sun) = &scene.lights[id as usize] else { unreachable!("a sun's index") };
        if prev.is_some() || sun.camera_visible {
            l += sun.radiance_from(dir) * bsdf_hit_weight(strategy, id, prev, |_| sun.pdf(), counters);
        }
    }
    l
}

/// Radiance from the lamps `ray` passes before `t_end` (lamps stop nothing: a path takes up
/// each one's light and goes on), MIS-weighted against next-event estimation when the ray
/// was found by BSDF sampling at `prev`, or against next-event estimation through glass
/// when the path came along a `chain` of refractions from a receiver; through the volume of
/// absorption `medium` the ray travels in. A camera ray sees only camera-visible lamps.
#[inline]
#[allow(clippy::too_many_arguments)]
fn lamps_seen(
    scene: &Scene,
    strategy: &LightStrategy,
    ray: &Ray,
    t_end: f32,
    prev: Option<Previous>,
    chain: GlassChain,
    medium: Rgb,
    counters: &mut RayCounters,
) -> Rgb {
    let mut l = Rgb::ZERO;
    scene.lamps_along(ray, t_end, |id, hit| {
        let light = &scene.lights[id as usize];
        if prev.is_none() && !light.camera_visible() {
            return;
        }
        let through = if medium != Rgb::ZERO { transmittance(medium, hit.t * ray.dir.length()) } else { Rgb::ONE };
        let weight = hit_weight(
            strategy,
            id,
            prev,
            |counters| chain.lamp_weight(scene, strategy, hit, id, counters),
            |ctx| light.pdf_li(ctx.p, hit.p, hit.n),
            counters,
        );
        l += hit.radiance * through * weight;
    });
    l
}

/// The MIS weight of the light of light `id` a path met: against the connection through glass
/// where `through_glass` gives one (the path came along a chain from a receiver; timed as
/// connection work), else [`bsdf_hit_weight`] with the light's density `light_pdf`.
#[inline]
fn hit_weight(
    strategy: &LightStrategy,
    id: u32,
    prev: Option<Previous>,
    through_glass: impl FnOnce(&mut RayCounters) -> Option<f32>,
    light_pdf: impl FnOnce(&ShadingContext) -> f32,
    counters: &mut RayCounters,
) -> f32 {
    let watch = Stopwatch::start(counters.timing);
    let weight = through_glass(counters);
    watch.stop(&mut counters.time.glass);
    match weight {
        Some(w) => w,
        None => bsdf_hit_weight(strategy, id, prev, light_pdf, counters),
    }
}

/// The MIS weight of light `id` reached by a BSDF-sampled ray from `prev` (1 for a camera
/// ray), against next-event estimation there, which would have sampled the same direction
/// with density `light_pdf(prev)` once the light was chosen.
#[inline]
fn bsdf_hit_weight(
    strategy: &LightStrategy,
    id: u32,
    prev: Option<Previous>,
    light_pdf: impl FnOnce(&ShadingContext) -> f32,
    counters: &mut RayCounters,
) -> f32 {
    match prev {
        None => 1.0,
        Some(v) => {
            let pmf = timed(counters.timing, &mut counters.time.choice, || {
                strategy.selection_pmf(&v.ctx, LightId(id), v.diffuse)
            });
            power_heuristic(v.bsdf_pdf, pmf * light_pdf(&v.ctx))
        }
    }
}

/// What the light emitting at `hit` (if it is on one) back along `dir` adds to a path of
/// throughput `beta`, weighted against next-event estimation when the ray was found by BSDF
/// sampling at `prev`, or against next-event estimation through glass when the path came
/// along a `chain` of refractions from a receiver.
#[inline]
#[allow(clippy::too_many_arguments)]
fn emitted(
    scene: &Scene,
    strategy: &LightStrategy,
    hit: &SurfaceHit,
    dir: Vec3A,
    prev: Option<Previous>,
    chain: GlassChain,
    beta: Rgb,
    counters: &mut RayCounters,
) -> Rgb {
    let Some(id) = hit.light else { return Rgb::ZERO };
    let light = &scene.lights[id as usize];
    let le = light.emitted(hit.n_geom, dir, hit.uv, &scene.images);
    if le == Rgb::ZERO {
        return le;
    }
    let weight = hit_weight(
        strategy,
        id,
        prev,
        |counters| chain.weight(scene, strategy, hit, id, counters),
        |ctx| light.pdf_li(ctx.p, hit.p, hit.n_geom),
        counters,
    );
    beta * le * weight
}

/// Russian roulette from [`RR_MIN_DEPTH`] on: a path survives with probability
/// min(1, max(beta)^¼) and carries `beta` divided by it; false when it ends. The fourth root
/// ends dim paths less eagerly than Cycles' square root (or max(beta)) would: in closed
/// rooms the variance a terminated path's survivors carry costs more than the extra bounces.
#[inline]
fn survives_roulette(stream: &SampleStream, depth: u32, beta: &mut Rgb) -> bool {
    if depth < RR_MIN_DEPTH {
        return true;
    }
    let survive = beta.max_element().sqrt().sqrt().min(1.0);
    // A path that survives for certain draws no number (its draw could not end it).
    if survive == 1.0 {
        return true;
    }
    if stream.get_1d(depth, Dim::RussianRoulette, 0) >= survive {
        return false;
    }
    *beta /= survive;
    true
}

/// `c` scaled down so that its channels sum to at most `limit` (0: no limit): Cycles' clamp of
/// one contribution. Light reaching the camera after at most one scattering event is direct
/// (next-event estimation at depth 0, emitters hit at depth 0 or 1), the rest indirect.
#[inline]
fn clamped(c: Rgb, limit: f32) -> Rgb {
    if limit > 0.0 {
        let sum = c.x.abs() + c.y.abs() + c.z.abs();
        if sum > limit {
            return c * (limit / sum);
        }
    }
    c
}

/// What traces a path: the scene, how it chooses lights and guides directions, how deep
/// paths go and how contributions are clamped.
#[derive(Clone, Copy)]
pub struct Tracer<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The light strategy of next-event estimation.
    pub strategy: &'a LightStrategy,
    /// Path guiding's learned distributions, when the render guides.
    pub guide: Option<&'a Guide>,
    /// Most scattering events (1 = direct lighting only).
    pub max_depth: u32,
    /// Clamping of contributions.
    pub clamp: Clamp,
    /// Whether light through smooth glass is solved for (the scene has some to solve for
    /// and the render asks for it).
    pub caustics: bool,
    /// The light paths that camera samples also trace (one in eight), when the render traces
    /// them: what next-event estimation of point and spot lights at glossy second vertices is
    /// weighed against.
    pub light_paths: Option<&'a LightPaths>,
    /// Whether paths report their first hit (the film keeps AOVs): its albedo is a texture
    /// lookup a camera ray would otherwise pay for nothing.
    pub first_hits: bool,
}

impl Tracer<'_> {
    /// Radiance arriving along `ray` (a camera ray). A render that neither guides paths (nor
    /// learns to), nor solves light through smooth glass, nor clamps (most renders) runs the
    /// path loop compiled without those features ([`trace`](Self::trace)).
    #[inline]
    pub fn radiance(&self, ray: Ray, stream: &SampleStream, tally: &mut Tally) -> PathSample {
        let learning = tally.seen.guide_records().is_some();
        if self.guide.is_none() && !learning && !self.caustics && !self.clamp.is_on() {
            self.trace::<true>(ray, stream, tally, false)
        } else {
            self.trace::<false>(ray, stream, tally, learning)
        }
    }

    /// The path loop. `PLAIN`: the render uses none of guiding, light through glass and
    /// clamping, so the loop takes them as constants and their checks at every vertex, and
    /// the state they carry, compile away (2.0–4.5 % of a sample's instructions with what
    /// they call inlined; the performance page). Both copies are the same code: a plain
    /// render's image is the same from either. What the loop calls at every vertex is
    /// `#[inline(always)]`, as LLVM would leave it out of line once two copies call it.
    /// `recording`: path guiding learns from this path's vertices (`tally.trail`).
    fn trace<const PLAIN: bool>(
        &self,
        mut ray: Ray,
        stream: &SampleStream,
        tally: &mut Tally,
        recording: bool,
    ) -> PathSample {
        let Tracer { scene, strategy, guide, max_depth, clamp, caustics, light_paths, first_hits } = *self;
        let (guide, caustics, clamp) = if PLAIN { (None, false, Clamp::OFF) } else { (guide, caustics, clamp) };
        let mut l = Rgb::ZERO;
        let mut first_hit = None;
        let mut beta = Rgb::ONE;
        // The previous vertex, for MIS at emitter hits.
        let mut prev: Option<Previous> = None;
        // The absorption of the glass the ray travels through (zero outside any).
        let mut medium = Rgb::ZERO;
        // The refractions through smooth glass since the path last left a receiver.
        let mut chain = GlassChain::default();
        // The camera hit where light paths may reach it (point, geometric normal), projected
        // into the image only where the path meets a glossy surface next.
        let mut first: Option<(Vec3A, Vec3A)> = None;
        let mut depth = 0u32;
        loop {
            let counters = &mut tally.rays;
            counters.rays += 1;
            counters.time.closest_rays += counters.timing as u64;
            let hit = timed(counters.timing, &mut counters.time.closest, || scene.intersect(&ray, f32::INFINITY));
            // Light this ray brings is direct for the first two rays, then indirect (Cycles').
            let arriving = clamp.limit(depth >= 2);
            if !scene.lamps.is_empty() && (prev.is_some() || scene.lamps.camera_visible()) {
                let t_end = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
                let seen = beta * lamps_seen(scene, strategy, &ray, t_end, prev, chain, medium, counters);
                l += clamped(seen, arriving);
            }
            let Some(hit) = hit else {
                l += clamped(beta * escaped(scene, strategy, ray.dir.normalize(), prev, counters), arriving);
                break;
            };
            if medium != Rgb::ZERO {
                beta *= transmittance(medium, hit.t * ray.dir.length());
            }
            let wo = -ray.dir.normalize();
            if depth == 0 && first_hits {
                first_hit = Some(FirstHit::of(scene, &hit, wo));
            }
            // Most hits are on no light; only those on one copy the previous vertex and the chain.
            if hit.light.is_some() {
                l += clamped(emitted(scene, strategy, &hit, ray.dir, prev, chain, beta, counters), arriving);
            }
            if depth == max_depth {
                break;
            }
            let material = &scene.materials[hit.material as usize];
            let glass = if caustics { material.smooth_glass() } else { None };
            // Glass on a chain from a receiver is crossed as the connection solves it: smooth.
            let as_smooth = glass.is_some() && chain.from_receiver();
            let entering = ray.dir.dot(hit.n_geom) < 0.0;
            let Some(surface) = Surface::at(scene, material, &hit, entering, as_smooth) else { break };
            let sp = surface.seen_from(wo);
            let scattering = Scattering::new(&sp, hit.p, guide);
            // How lights are chosen here, by next-event estimation and by the MIS weight where
            // the next ray meets one.
            let ctx = ShadingContext::of(hit.p, &sp);
            // Light paths sample camera → x1 → glossy x2 → point or spot light too.
            let highlight = light_paths.and_then(|paths| match (depth, first, prev) {
                (0, ..) => {
                    first = surface.can_be_x1().then_some((hit.p, hit.n_geom));
                    None
                }
                (1, Some((p, n)), Some(prev)) if surface.can_be_x2() => paths
                    .camera_vertex(scene, p, n)
                    .map(|x1| Highlight { paths, x1, pdf_x1: prev.bsdf_pdf, surface, wo }),
                _ => None,
            });
            // Where next-event estimation also looks through smooth glass: off it, outside it.
            let receiver = caustics && glass.is_none() && medium == Rgb::ZERO;

            if !scene.lights.is_empty() {
                // A light reached through k refractions ends a path k vertices deeper.
                let at = AtVertex {
                    refractions: if receiver { MAX_CASTERS.min((max_depth - depth - 1) as usize) } else { 0 },
                    smooth: as_smooth,
                };
                let highlight = highlight.as_ref();
                let direct = beta
                    * estimate_direct(scene, strategy, &scattering, &ctx, medium, at, highlight, stream, depth, tally);
                l += clamped(direct, clamp.limit(depth >= 1));
            }

            // Unguided, the direction is the BSDF's own sample: called as such, it is inlined.
            let bs = if PLAIN { scattering.bsdf_sample(stream, depth) } else { scattering.sample(stream, depth) };
            let Some(bs) = bs else { break };
            beta *= bs.weight;
            if recording && scattering.guidable() {
                tally.trail.push(hit.p, &scattering, &bs, beta, l);
            }
            // Refracting into a solid glass object puts the ray in its volume; out of one, back
            // outside (objects are not nested).
            if bs.wi.dot(sp.n_geom) < 0.0 && !material.thin {
                medium = if entering { material.absorption } else { Rgb::ZERO };
            }
            let left = Previous { ctx, bsdf_pdf: bs.pdf, diffuse: sp.is_diffuse() };
            // Without light through glass the chain stays empty.
            if caustics {
                chain = match glass {
                    _ if receiver => GlassChain::leaving(left.ctx, left.diffuse, sp.n_geom, left.bsdf_pdf),
                    Some(_) if bs.wi.dot(sp.n_geom) < 0.0 => chain.through(hit.p),
                    _ => GlassChain::default(),
                };
            }
            prev = Some(left);
            ray = Ray::new(sp.ray_origin(hit.p, bs.wi), bs.wi);
            depth += 1;
            if !survives_roulette(stream, depth, &mut beta) {
                break;
            }
        }
        debug_assert!(l.is_finite(), "non-finite radiance {l}");
        if let Some(records) = tally.seen.guide_records().filter(|_| !PLAIN) {
            tally.trail.close(l, records);
        }
        PathSample { radiance: l, first_hit }
    }
}
