//! Manifold next-event estimation: light reaching a surface through smooth glass.
//!
//! A light sample on an emissive surface (or on a lamp's disk) that only smooth solid glass
//! ([`Material::smooth_glass`](crate::material::Material::smooth_glass)) blocks is not given
//! up: the walk along its straight way, which is its shadow ray too ([`Behind`]), finds the
//! glass, and the refractions the straight segment makes through the glass seed a chain of vertices
//! that Newton's method walks over the glass until each one obeys Snell's law (Hanika, Droske
//! and Fascione 2015, *Manifold next event estimation*; Cycles' shadow caustics). The light
//! then arrives along the chain with the generalised geometry term G: the density of the
//! direction it leaves the receiver in per unit area of the light, by the implicit function
//! theorem on the chain's constraints. A point or directional light behind smooth glass is
//! connected the same way, the chain ending at its point or direction and carrying instead
//! the density of its directions (or of its beam) at the receiver; BSDF sampling cannot find
//! such light. Paths from a receiver cross such glass as smooth glass (the connection stands
//! for them; [`AtVertex::smooth`]), where no sample of a delta light can meet them.
//!
//! BSDF sampling finds the same paths (a receiver, 1 to [`MAX_CASTERS`] refractions through
//! smooth glass, an emissive surface or a lamp), and each strategy is good where the other is poor:
//! where the glass focuses light (a caustic's bright core) G is large and varies fast over
//! the light, and BSDF sampling hits the light easily; where it spreads light thin, only
//! the solved connection finds it. So the two are weighed by the power heuristic, both
//! densities per unit area of the light: the connection's is the light's selection pmf ×
//! its point density, BSDF sampling's the receiver's density of the first direction × the
//! probability of refracting at each vertex × G ([`GlassChain`] follows a path's chain to
//! weigh the light it meets). What is lost: light along chains the connection does not
//! find — one whose straight seed crosses anything but smooth glass, one Newton's method
//! does not solve, a second solution of the same seed — keeps
//! only its BSDF-sampled share.
//!
//! Against Cycles: it serves emissive triangles and quads as well as lamps (Cycles only
//! lamps; glTF scenes bring their light in meshes) and weighs by MIS where Cycles leaves every such path to
//! the connection and clamps G at 2; casters and receivers follow from the materials rather
//! than object flags; the constraints' derivatives are forward differences in f64 (analytic
//! in Cycles). `chain.rs` solves the chains; this file weighs and adds up what they bring.

mod chain;

use glam::DVec3;

use self::chain::{
    Chain, End, Straight, connect_to, delta_density, geometry_term, ior_at_light, passage, ray_from_surface,
    surface_end, to_f32, to_f64, turned, walk,
};
use super::RayCounters;
use super::guided::Scattering;
use crate::geometry::SurfaceHit;
use crate::light::{AreaPoint, LampHit, Light, LightId, LightSample, SphereLight};
use crate::light_sampler::{LightStrategy, ShadingContext};
use crate::math::{Rgb, Vec3A, power_heuristic};
use crate::scene::Scene;

/// Most refractions a chain may have.
pub const MAX_CASTERS: usize = 4;

/// The power-heuristic weight of the connection along a solved `chain` against BSDF
/// sampling, both as densities per unit area of the light (across `n_y`): `light_pdf`
/// (selection pmf × point density) against `bsdf_pdf` (the receiver's density of the
/// chain's first direction) × refracting at every vertex × G. Also G.
fn connection_weight(
    chain: &Chain,
    n_y: DVec3,
    light_pdf: f32,
    bsdf_pdf: impl FnOnce(Vec3A) -> f32,
) -> Option<(f32, f32)> {
    let g = geometry_term(chain, n_y)? as f32;
    let (_, probability) = passage(chain);
    let wi = to_f32(chain.first_direction());
    Some((power_heuristic(light_pdf, bsdf_pdf(wi) * probability * g), g))
}

/// What next-event estimation finds along the straight way of a light sample where smooth
/// glass may stand in it (one walk serves as its shadow ray and seeds the chain).
pub enum Behind {
    /// The light in plain sight.
    Clear,
    /// Something other than smooth glass in the way (or more than a chain may cross).
    Blocked,
    /// Smooth glass alone in the way: the light that comes through it (zero where no chain
    /// was solved or its last segment is blocked).
    Through(Rgb),
}

/// Walks the straight way from the receiver at `p` (geometric normal `n_p`) to the light at
/// `end`; through smooth glass alone, `lit` says what the solved chain brings.
fn behind(
    scene: &Scene,
    p: Vec3A,
    n_p: Vec3A,
    end: End,
    most: usize,
    counters: &mut RayCounters,
    lit: impl FnOnce(&Chain, &mut RayCounters) -> Rgb,
) -> Behind {
    match walk(scene, p, n_p, end, most, counters) {
        Straight::Clear => Behind::Clear,
        Straight::Blocked => Behind::Blocked,
        Straight::Glass(chain) => {
            counters.glass_tried += 1;
            let c = chain.map_or(Rgb::ZERO, |chain| lit(&chain, counters));
            counters.glass_solved += (c != Rgb::ZERO) as u64;
            Behind::Through(c)
        }
    }
}

/// The straight way to an emissive surface's point `point`, sampled from the surface
/// `scattering` at `p`; through smooth glass, the light that reaches `p` along the chain of
/// at most `most` refractions (a path through more would end before it reached the light:
/// its depth counts each one), divided by the point's density and the light's selection
/// probability `pmf` and weighed against BSDF sampling.
pub fn through_glass(
    scene: &Scene,
    point: &AreaPoint,
    pmf: f32,
    scattering: &Scattering,
    p: Vec3A,
    most: usize,
    counters: &mut RayCounters,
) -> Behind {
    let end = surface_end(p, point.p, point.n);
    let radiance = |x: DVec3| point.emission.radiance_towards(point.n, to_f32(-end.seen_from(x)));
    let light_pdf = pmf * point.pdf;
    behind(scene, p, scattering.sp.n_geom, end, most, counters, |chain, counters| {
        weighed(scene, chain, to_f64(point.n), light_pdf, radiance, scattering, counters)
    })
}

/// Where a chain from the receiver at `p` ends on the facing-disk `lamp` for its point `q`
/// on the disk facing whoever saw it (normal `n`): its offset from the centre, turned to the
/// disk facing `p`; also that disk's normal and the point there (what `p`'s light sample
/// would have chosen); `None` for a receiver at the lamp's centre.
fn lamp_end(lamp: &SphereLight, p: Vec3A, q: Vec3A, n: Vec3A) -> Option<(End, DVec3, Vec3A)> {
    let centre = to_f64(lamp.center);
    let towards = (to_f64(p) - centre).try_normalize()?;
    let offset = turned(to_f64(q) - centre, to_f64(n), towards);
    Some((End::Facing { centre, towards, offset }, towards, to_f32(centre + offset)))
}

/// The straight way to a point or spot lamp seen as a facing disk, sampled at `sample`
/// from `p`, as [`through_glass`] for surfaces; the disk turns to the chain's last
/// refraction, as it faces whoever sees it.
#[allow(clippy::too_many_arguments)]
pub fn lamp_through_glass(
    scene: &Scene,
    lamp: &SphereLight,
    sample: &LightSample,
    pmf: f32,
    scattering: &Scattering,
    p: Vec3A,
    most: usize,
    counters: &mut RayCounters,
) -> Behind {
    let Some((end, n_y, seen)) = lamp_end(lamp, p, sample.p, sample.n) else { return Behind::Blocked };
    let radiance = |x: DVec3| lamp.radiance_along(to_f32(x - end.point_from(x).unwrap_or(x)).normalize_or_zero());
    let light_pdf = pmf * lamp.disk_pdf_from(p, seen);
    behind(scene, p, scattering.sp.n_geom, end, most, counters, |chain, counters| {
        weighed(scene, chain, n_y, light_pdf, radiance, scattering, counters)
    })
}

/// What the light at the end of the solved `chain` (its area measured across `n_y`, chosen
/// with density `light_pdf` per unit area, pmf included), sending `radiance(x)` towards the
/// chain's last refraction x, brings to `scattering` at its receiver, divided by
/// `light_pdf` and weighed against BSDF sampling.
fn weighed(
    scene: &Scene,
    chain: &Chain,
    n_y: DVec3,
    light_pdf: f32,
    radiance: impl FnOnce(DVec3) -> Rgb,
    scattering: &Scattering,
    counters: &mut RayCounters,
) -> Rgb {
    if !(light_pdf > 0.0) {
        return Rgb::ZERO;
    }
    let f = scattering.sp.eval_cos(to_f32(chain.first_direction()));
    let le = radiance(chain.vertex(chain.k - 1).x);
    if f == Rgb::ZERO || le == Rgb::ZERO {
        return Rgb::ZERO;
    }
    let Some((weight, g)) = connection_weight(chain, n_y, light_pdf, |wi| scattering.pdf(wi)) else {
        return Rgb::ZERO;
    };
    if !light_reaches(scene, chain, counters) {
        return Rgb::ZERO;
    }
    f * passage(chain).0 * le * (g * weight / light_pdf)
}

/// Whether nothing blocks the chain's last segment, from its last refraction to the light.
fn light_reaches(scene: &Scene, chain: &Chain, counters: &mut RayCounters) -> bool {
    let last = chain.vertex(chain.k - 1);
    let (ray, t_max) = ray_from_surface(to_f32(last.x), to_f32(last.n_geom), chain.end);
    counters.shadow_rays += 1;
    !scene.occluded(&ray, t_max)
}

/// What next-event estimation at a vertex has to do with smooth glass.
#[derive(Clone, Copy, Debug, Default)]
pub struct AtVertex {
    /// How many refractions through smooth glass a light sample may be connected through
    /// here: 0 where the vertex is no receiver or the path has no depth left for one.
    pub refractions: usize,
    /// Whether the vertex is smooth glass a path from a receiver reached, which it crosses
    /// as smooth (with roughness 0): no light sample of a delta light can meet it there.
    /// (Next-event estimation at its slight roughness instead found a point or directional
    /// light's caustics as rare fireflies, and counted again the chains the connection
    /// solves.)
    pub smooth: bool,
}

/// Where a delta light (point, spot or directional) is, for a chain to end at.
fn delta_end(sample: &LightSample) -> End {
    if sample.distance.is_infinite() { End::Direction(to_f64(sample.wi)) } else { End::Point(to_f64(sample.p)) }
}

/// The straight way to the delta light `light` (its sample from `p`: `sample`); through
/// smooth glass, the light that reaches the surface `scattering` at `p` along the chain of
/// at most `most` refractions, divided by the light's selection probability `pmf`. BSDF
/// sampling cannot find such light, so the chain takes it all; next-event estimation at the
/// glass takes none ([`AtVertex::smooth`]).
#[allow(clippy::too_many_arguments)]
pub fn delta_through_glass(
    scene: &Scene,
    light: &Light,
    sample: &LightSample,
    u: [u64; 2],
    pmf: f32,
    scattering: &Scattering,
    p: Vec3A,
    most: usize,
    counters: &mut RayCounters,
) -> Behind {
    behind(scene, p, scattering.sp.n_geom, delta_end(sample), most, counters, |chain, counters| {
        delta_along(scene, light, chain, u, pmf, scattering, counters)
    })
}

/// What the delta light `light` sends along the solved `chain` to the surface `scattering`
/// at its receiver, divided by the light's selection probability `pmf`; zero where the
/// chain's last segment is blocked.
fn delta_along(
    scene: &Scene,
    light: &Light,
    chain: &Chain,
    u: [u64; 2],
    pmf: f32,
    scattering: &Scattering,
    counters: &mut RayCounters,
) -> Rgb {
    let last = chain.vertex(chain.k - 1);
    let f = scattering.sp.eval_cos(to_f32(chain.first_direction()));
    // What the light sends along the chain's last segment: irradiance across the beam of a
    // directional light, the intensity (radiance there × distance²) of a point or spot.
    let Some(seen) = light.sample_li(to_f32(last.x), u, &scene.images) else { return Rgb::ZERO };
    let emitted = match chain.end.point_from(last.x) {
        Some(y) => seen.radiance * (last.x - y).length_squared() as f32,
        None => seen.radiance,
    };
    if f == Rgb::ZERO || emitted == Rgb::ZERO {
        return Rgb::ZERO;
    }
    // Radiance is not compressed by η² where it refracts (as in Cycles, and as BSDF sampling
    // carries it here), so light leaving a point inside glass is η² brighter outside than the
    // spreading of its directions alone gives: as bright as a small lamp there.
    let Some(density) = delta_density(chain).map(|d| d * ior_at_light(chain).powi(2)) else { return Rgb::ZERO };
    if !light_reaches(scene, chain, counters) {
        return Rgb::ZERO;
    }
    f * passage(chain).0 * emitted * (density as f32 / pmf)
}

/// A surface a path left where next-event estimation looks through glass.
#[derive(Clone, Copy, Debug)]
struct Receiver {
    /// Its light-selection context, and whether its BSDF is Lambert's (what next-event
    /// estimation there chose by: [`LightStrategy::selection_pmf`]).
    ctx: ShadingContext,
    diffuse: bool,
    /// Its geometric normal.
    n_geom: Vec3A,
    /// The density with which its scattering chose the direction the path left in.
    pdf: f32,
}

/// A path's chain of refractions through smooth glass since it last left a receiver, for
/// the weight of the light it may meet at the chain's end against [`through_glass`].
#[derive(Clone, Copy, Debug, Default)]
pub struct GlassChain {
    /// The receiver; `None` when the path has since met anything but smooth glass it
    /// refracted through, or more of it than a chain may have.
    from: Option<Receiver>,
    /// Where it refracted.
    vertices: [Vec3A; MAX_CASTERS],
    k: usize,
}

impl GlassChain {
    /// Whether the path came along it from a receiver.
    #[inline]
    pub fn from_receiver(&self) -> bool {
        self.from.is_some()
    }

    /// Whether the solved `chain` is this one: as many refractions, each where the path's
    /// was (the solve stops within 10⁻³ of Snell's law, the glass's narrowest lobe bends
    /// within about as much).
    fn is(&self, chain: &Chain) -> bool {
        let Some(from) = self.from else { return false };
        chain.k == self.k
            && (0..self.k).all(|i| {
                let (solved, taken) = (to_f32(chain.vertex(i).x), self.vertices[i]);
                (solved - taken).length() <= 1e-2 * (taken - from.ctx.p).length()
            })
    }

    /// A path leaving a receiver at `ctx` (geometric normal `n_geom`; a Lambert BSDF there:
    /// `diffuse`) in a direction its scattering chose with density `pdf`.
    #[inline]
    pub fn leaving(ctx: ShadingContext, diffuse: bool, n_geom: Vec3A, pdf: f32) -> Self {
        Self { from: Some(Receiver { ctx, diffuse, n_geom, pdf }), ..Self::default() }
    }

    /// The chain, one refraction through smooth glass at `p` longer.
    #[inline]
    pub fn through(mut self, p: Vec3A) -> Self {
        if self.from.is_none() || self.k == MAX_CASTERS {
            return Self::default();
        }
        self.vertices[self.k] = p;
        self.k += 1;
        self
    }

    /// The MIS weight of the light emitted at `hit` by light `id` against [`through_glass`]
    /// from the receiver, or `None` when the path did not reach it along a chain from one.
    /// Where the connection would not have found this very chain, BSDF sampling's weight is 1.
    pub fn weight(
        &self,
        scene: &Scene,
        strategy: &LightStrategy,
        hit: &SurfaceHit,
        id: u32,
        counters: &mut RayCounters,
    ) -> Option<f32> {
        let from = self.from.filter(|_| self.k > 0)?;
        let area_pdf = scene.lights[id as usize].area_pdf()?;
        let end = surface_end(from.ctx.p, hit.p, hit.n_geom);
        Some(self.weight_against(scene, strategy, id, end, to_f64(hit.n_geom), area_pdf, counters))
    }

    /// The same for the light of lamp `id` met at `hit` ([`lamp_through_glass`]).
    pub fn lamp_weight(
        &self,
        scene: &Scene,
        strategy: &LightStrategy,
        hit: &LampHit,
        id: u32,
        counters: &mut RayCounters,
    ) -> Option<f32> {
        let from = self.from.filter(|_| self.k > 0)?;
        let light = &scene.lights[id as usize];
        let Light::Sphere(lamp) = light else { return None };
        if !light.connects_through_glass() {
            return None;
        }
        let Some((end, n_y, seen)) = lamp_end(lamp, from.ctx.p, hit.p, hit.n) else { return Some(1.0) };
        let density = lamp.disk_pdf_from(from.ctx.p, seen);
        if !(density > 0.0) {
            return Some(1.0);
        }
        Some(self.weight_against(scene, strategy, id, end, n_y, density, counters))
    }

    /// 1 − the connection's weight for the light `id` at `end` (its area across `n_y`, its
    /// points chosen with `density` per unit area), when solving from the receiver finds
    /// this very chain; else 1.
    #[allow(clippy::too_many_arguments)]
    fn weight_against(
        &self,
        scene: &Scene,
        strategy: &LightStrategy,
        id: u32,
        end: End,
        n_y: DVec3,
        density: f32,
        counters: &mut RayCounters,
    ) -> f32 {
        let Some(from) = self.from else { return 1.0 };
        // The path reached the light within its depth, so the connection had room for its chain.
        let Some(chain) = connect_to(scene, from.ctx.p, from.n_geom, end, MAX_CASTERS, counters) else {
            return 1.0;
        };
        if !self.is(&chain) {
            return 1.0;
        }
        let pmf = strategy.selection_pmf(&from.ctx, LightId(id), from.diffuse);
        1.0 - connection_weight(&chain, n_y, pmf * density, |_| from.pdf).map_or(0.0, |(w, _)| w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::LampModel;

    #[test]
    fn a_point_met_on_a_facing_disk_maps_back_to_the_one_the_receiver_would_have_sampled() {
        // The connection samples an offset on the disk facing the receiver; a path that met
        // the disk facing its last refraction must find that same offset for the weights
        // of the two to add up.
        let lamp = SphereLight::new(Vec3A::new(0.1, 0.9, -0.2), 0.15, Rgb::ONE, LampModel::FacingDisk, None);
        let receiver = Vec3A::new(1.3, 0.0, 0.4);
        let last = Vec3A::new(0.35, 0.55, 0.1);
        for offset in [Vec3A::new(0.05, 0.0, 0.0), Vec3A::new(-0.02, 0.03, 0.09), Vec3A::ZERO] {
            // The offset on the receiver's disk (across the direction to the receiver)...
            let towards = (receiver - lamp.center).normalize();
            let offset = offset - towards * offset.dot(towards);
            let sampled = lamp.center + offset;
            let (end, n, seen) = lamp_end(&lamp, receiver, sampled, towards).unwrap();
            assert!((seen - sampled).length() < 1e-6 && (n - to_f64(towards)).length() < 1e-6);
            // ...is where the disk facing the last refraction shows it, and back again.
            let met = to_f32(end.point_from(to_f64(last)).unwrap());
            let facing = (last - lamp.center).normalize();
            assert!((met - lamp.center).dot(facing).abs() < 1e-6, "on the disk facing the last refraction");
            assert!(((met - lamp.center).length() - offset.length()).abs() < 1e-6);
            let (_, _, back) = lamp_end(&lamp, receiver, met, facing).unwrap();
            assert!((back - sampled).length() < 1e-5, "{back} against {sampled}");
        }
        assert!(lamp_end(&lamp, lamp.center, lamp.center, Vec3A::Y).is_none());
    }
}
