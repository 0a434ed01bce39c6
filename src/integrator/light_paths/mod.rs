//! Light paths to the camera for the highlights of point and spot lights on glossy surfaces.
//!
//! A path camera → x1 → x2 → point light, where x2 is glossy and mirrors the light towards
//! x1, is the path tracer's worst case: BSDF sampling at x1 must happen to reach the small
//! part of x2 whose lobe holds the light, and next-event estimation there then returns a
//! value thousands of times the pixel's (lobby.glb's floor and metal balls, materials.glb's
//! copper ball: the fireflies that decide their error). Traced from the light the same path
//! is easy (BDPT's light tracing, t = 1): a direction from the light, the glossy lobe at x2
//! sampled towards x1 (so its peak cancels), x1 joined to the camera. One camera sample in
//! eight ([`RATE`]) also traces such a light path (its numbers are the sample's:
//! [`Dim::LightPathLight`], [`Dim::LightPathDirection`], the BSDF's dimensions at sub-index 1),
//! from a light chosen by the power it sends at glossy surfaces, in a direction that favours
//! them ([`emission`]), and adds what it brings to the pixel where x1 is seen, as a splat.
//!
//! Both strategies sample the same paths (x1 seen by the pinhole camera, reflecting;
//! x2 glossy, reflecting; a point or spot light), so each is weighed by the power heuristic
//! against the other, with the densities both compute from one function
//! ([`Densities::ratio`]): the camera's density over the whole image × BSDF sampling at x1,
//! against [`RATE`] (light paths per camera sample) × the light's density of directions ×
//! BSDF sampling at x2, each given the light. The probabilities of choosing the light are left
//! out of the weights on both sides: the weights still sum to 1 for every path, and the
//! light tree's probability at x2, which a light path would otherwise have to replay, cost a
//! quarter of a light path for 1–3 % of its error.
//! Every other path is the path tracer's alone.
//! Off with a lens (depth of field), guiding or clamping, where the path tracer's densities
//! are not the ones written here.

mod emission;

use super::RayCounters;
use super::surface::Surface;
use crate::camera::Projection;
use crate::film::Splat;
use crate::geometry::{Ray, SurfaceHit};
use crate::light::{Light, LightSample};
use crate::material::Bsdf;
use crate::math::{Rgb, UVec2, Vec3A};
use crate::sampling::{Dim, SampleStream};
use crate::scene::Scene;
use emission::Directions;

/// The point and spot lights light paths start from, chosen by the power they send at
/// surfaces that may be glossy, and the directions they leave them in ([`emission`]).
#[derive(Clone, Debug)]
pub struct LightPaths {
    /// Their indices in the scene's lights, ascending.
    ids: Vec<u32>,
    /// Cumulative probabilities (the last is 1).
    cdf: Vec<f32>,
    /// How each leaves its light.
    directions: Vec<Directions>,
    /// The image light paths end on.
    resolution: UVec2,
}

/// Where the camera sees x1, the first vertex of a path, as both strategies need it.
#[derive(Clone, Copy, Debug)]
pub struct CameraVertex {
    /// Its geometric normal.
    pub n_geom: Vec3A,
    /// The camera's density of reaching it, per unit area (over the whole image).
    pub importance: f32,
}

/// A glossy x2 whose next-event estimation of a point or spot light light paths also
/// sample: what its MIS weight needs.
#[derive(Clone, Copy, Debug)]
pub struct Highlight<'a> {
    /// The light paths.
    pub paths: &'a LightPaths,
    /// The path's first vertex.
    pub x1: CameraVertex,
    /// The density with which BSDF sampling at x1 chose the way to x2.
    pub pdf_x1: f32,
    /// The BSDF at x2 and its frame.
    pub surface: Surface,
    /// Unit direction from x2 back to x1.
    pub wo: Vec3A,
}

impl Surface {
    /// Whether light paths sample paths camera → x1 → x2 → light with this surface as x1:
    /// where it does not transmit.
    #[inline]
    pub fn can_be_x1(&self) -> bool {
        !self.bsdf.transmits()
    }

    /// Whether it can be their x2: reflecting and glossy.
    #[inline]
    pub fn can_be_x2(&self) -> bool {
        !self.bsdf.transmits() && !matches!(self.bsdf, Bsdf::Diffuse(_))
    }
}

/// The densities of one path camera → x1 → x2 → light under the two strategies, given the
/// light, as their ratio light paths ÷ path tracer.
#[derive(Clone, Copy, Debug)]
struct Densities {
    /// The light's density of emitting towards x2, per solid angle.
    emit_pdf: f32,
    /// |cos| at x2 of the way from the light, and the squared distance.
    cos_x2_light: f32,
    dist2_light: f32,
    /// BSDF sampling's density at x2 of the way to x1 (seen from the light).
    pdf_x2: f32,
    /// |cos| at x1 of the way to x2.
    cos_x1: f32,
    /// The camera's density at x1 per unit area.
    importance: f32,
    /// BSDF sampling's density at x1 of the way to x2 (seen from the camera).
    pdf_x1: f32,
    /// |cos| at x2 of the way to x1.
    cos_x2_x1: f32,
}

impl Densities {
    /// Light paths' density over the path tracer's (both per unit area at x1 and x2; the
    /// distance x1–x2 cancels). Infinite where only light paths sample the path.
    #[inline]
    fn ratio(&self) -> f32 {
        let light = RATE * self.emit_pdf * self.cos_x2_light / self.dist2_light * self.pdf_x2 * self.cos_x1;
        let camera = self.importance * self.pdf_x1 * self.cos_x2_x1;
        light / camera
    }
}

/// Light paths per camera sample: each camera sample traces one with this probability (and
/// its splat counts 1/RATE times). A light path costs about as much as a camera path (three
/// rays, two shaded vertices), and a few of them take most of the highlights' noise away.
/// Against the build without light paths, `tools/switch_bench.py` (320 × 240, 64 spp, seeds
/// 1–6, relMSE against Cycles, equal-CPU efficiency): ¼ → materials.glb 7.3×, lobby.glb 0.95×;
/// ⅛ → 6.9× and 1.01×. With one per camera sample (and light chosen by power, uniform
/// directions) lobby.glb lost 2 % (0.98×) for 18 % less error.
pub const RATE: f32 = 0.125;

/// The power heuristic's weight of the path tracer for a ratio `r` of densities.
#[inline]
fn path_tracer_weight(r: f32) -> f32 {
    if r.is_finite() { 1.0 / (1.0 + r * r) } else { 0.0 }
}

impl LightPaths {
    /// Light paths for `scene` rendered at `resolution`, or `None` where there is nothing
    /// for them: no point or spot light, no glossy material, a lens, or no highlight the
    /// camera sees that the probes found ([`emission`]).
    pub fn new(scene: &Scene, resolution: UVec2) -> Option<Self> {
        let ids = Self::lights_of(scene);
        let probed = emission::probe_all(scene, &ids, resolution);
        if !probed.iter().any(|p| p.sees_highlight) {
            return None;
        }
        // A light that sends little at glossy surfaces keeps a small chance (its highlights
        // on a glossy object the probes missed).
        let powers: Vec<f64> = ids
            .iter()
            .zip(&probed)
            .map(|(&i, p)| scene.lights[i as usize].power(scene.radius) as f64 * p.glossy_share.max(0.02) as f64)
            .collect();
        let total: f64 = powers.iter().sum();
        if ids.is_empty() || !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut running = 0.0;
        let mut cdf: Vec<f32> = powers
            .iter()
            .map(|p| {
                running += p;
                (running / total) as f32
            })
            .collect();
        *cdf.last_mut().expect("one light at least") = 1.0;
        let directions = probed.into_iter().map(|p| p.directions).collect();
        Some(Self { ids, cdf, directions, resolution })
    }

    /// The point and spot lights of `scene` light paths may start from: none without a
    /// glossy material, or with a lens.
    fn lights_of(scene: &Scene) -> Vec<u32> {
        let glossy = scene.materials.iter().any(|m| m.may_reflect_glossily());
        if !glossy || scene.camera.has_lens() {
            return Vec::new();
        }
        (0..scene.lights.len() as u32)
            .filter(|&i| {
                let light = &scene.lights[i as usize];
                matches!(light, Light::Point(_) | Light::Spot(_)) && light.power(scene.radius) > 0.0
            })
            .collect()
    }

    /// How many lights they start from.
    pub fn lights(&self) -> usize {
        self.ids.len()
    }

    /// The place of light `id` among theirs (`None` for lights they do not start from).
    #[inline]
    fn find(&self, id: u32) -> Option<usize> {
        self.ids.binary_search(&id).ok()
    }

    /// The probability of the light at place `k`.
    #[inline]
    fn pmf(&self, k: usize) -> f32 {
        self.cdf[k] - if k > 0 { self.cdf[k - 1] } else { 0.0 }
    }

    /// The place of the light for `u ∈ [0,1)`.
    #[inline]
    fn choose(&self, u: f32) -> usize {
        self.cdf.partition_point(|&c| c <= u).min(self.ids.len() - 1)
    }

    /// Where the camera sees `p` on a surface of normal `n_geom`, and its density there.
    #[inline]
    fn projection(&self, scene: &Scene, p: Vec3A, n_geom: Vec3A) -> Option<(Projection, CameraVertex)> {
        let proj = scene.camera.project(p, self.resolution)?;
        let importance = proj.importance * n_geom.dot(proj.to_camera).abs() / (proj.distance * proj.distance);
        Some((proj, CameraVertex { n_geom, importance }))
    }

    /// The first vertex of a camera path, at `p` with geometric normal `n_geom` on a surface
    /// that can be x1 ([`Surface::can_be_x1`]), as light paths see it (`None` outside the
    /// image).
    #[inline]
    pub fn camera_vertex(&self, scene: &Scene, p: Vec3A, n_geom: Vec3A) -> Option<CameraVertex> {
        self.projection(scene, p, n_geom).map(|(_, v)| v)
    }

    /// Traces the light path of one camera sample and returns what it adds to the image,
    /// weighted against the path tracer (per sample of the whole image: a pixel's mean adds
    /// its splats' sum over its samples per pixel).
    #[inline(always)]
    pub fn trace(&self, scene: &Scene, stream: &SampleStream, counters: &mut RayCounters) -> Option<Splat> {
        // Seven camera samples in eight trace none: they skip the call.
        if stream.get_1d(0, Dim::LightPathLight, 1) >= RATE {
            return None;
        }
        self.trace_one(scene, stream, counters)
    }

    /// [`trace`](Self::trace) for a camera sample that traces a light path.
    fn trace_one(&self, scene: &Scene, stream: &SampleStream, counters: &mut RayCounters) -> Option<Splat> {
        counters.light_paths += 1;
        let k = self.choose(stream.get_1d(0, Dim::LightPathLight, 0));
        let (id, light_pmf) = (self.ids[k], self.pmf(k));
        let light = &scene.lights[id as usize];
        let (dir, emit_pdf) = self.directions[k].sample(light, stream.get_2d(0, Dim::LightPathDirection, 0));
        // x2: a glossy surface the light reaches.
        counters.rays += 1;
        let hit2 = scene.intersect(&Ray::new(emission::position(light), dir), f32::INFINITY)?;
        let x2 = surface_at(scene, &hit2, dir)?;
        if !x2.can_be_x2() {
            return None;
        }
        let from_light = x2.seen_from(-dir);
        let u_lobe = if from_light.chooses_lobes() { stream.get_1d(0, Dim::BsdfLobe, 1) } else { 0.0 };
        let bs = from_light.sample(u_lobe, stream.get_2d(0, Dim::BsdfDirection, 1))?;
        // x1: where the lobe sends the light, seen by the camera.
        counters.rays += 1;
        let hit1 = scene.intersect(&Ray::new(from_light.ray_origin(hit2.p, bs.wi), bs.wi), f32::INFINITY)?;
        let (proj, cam) = self.projection(scene, hit1.p, hit1.n_geom)?;
        let x1 = surface_at(scene, &hit1, -proj.to_camera)?;
        if !x1.can_be_x1() {
            return None;
        }
        let at_x1 = x1.seen_from(proj.to_camera);
        let (f1, pdf_x1) = at_x1.eval_cos_pdf(-bs.wi);
        let at_x2 = x2.seen_from(bs.wi);
        let ls = light.sample_li(hit2.p, [0, 0], &scene.images)?;
        let f2 = at_x2.eval_cos(ls.wi);
        if f1 == Rgb::ZERO || f2 == Rgb::ZERO {
            return None;
        }
        counters.shadow_rays += 1;
        let start = at_x1.ray_origin(hit1.p, proj.to_camera);
        if scene.occluded(&Ray::new(start, scene.camera.position() - start), 1.0) {
            return None;
        }
        let densities = Densities {
            emit_pdf,
            cos_x2_light: hit2.n_geom.dot(dir).abs(),
            dist2_light: ls.distance * ls.distance,
            pdf_x2: bs.pdf,
            cos_x1: hit1.n_geom.dot(bs.wi).abs(),
            importance: cam.importance,
            pdf_x1,
            cos_x2_x1: hit2.n_geom.dot(bs.wi).abs(),
        };
        let intensity = ls.radiance * densities.dist2_light;
        let value = f1 * f2 * intensity * (cam.importance * densities.cos_x2_x1)
            / (light_pmf * densities.emit_pdf * densities.cos_x2_light * bs.pdf * densities.cos_x1);
        let weight = (1.0 - path_tracer_weight(densities.ratio())) / RATE;
        let value = value * weight;
        if !(value.is_finite() && value.max_element() > 0.0) {
            return None;
        }
        counters.splats += 1;
        Some(Splat { pixel: proj.pixel.y * self.resolution.x + proj.pixel.x, value })
    }
}

impl Highlight<'_> {
    /// The path tracer's MIS weight for next-event estimation at this x2 of light `id` (its
    /// sample `ls`): 1 unless light paths start from it.
    #[inline]
    pub fn weight(&self, scene: &Scene, id: u32, ls: &LightSample) -> f32 {
        let Some(k) = self.paths.find(id) else { return 1.0 };
        let light = &scene.lights[id as usize];
        let from_light = self.surface.seen_from(ls.wi);
        let densities = Densities {
            emit_pdf: self.paths.directions[k].pdf(light, -ls.wi),
            cos_x2_light: self.surface.n_geom.dot(ls.wi).abs(),
            dist2_light: ls.distance * ls.distance,
            pdf_x2: from_light.pdf(self.wo),
            cos_x1: self.x1.n_geom.dot(self.wo).abs(),
            importance: self.x1.importance,
            pdf_x1: self.pdf_x1,
            cos_x2_x1: self.surface.n_geom.dot(self.wo).abs(),
        };
        path_tracer_weight(densities.ratio())
    }
}

/// The BSDF at `hit`, reached along `dir`, as the path tracer would shade it there.
#[inline]
fn surface_at(scene: &Scene, hit: &SurfaceHit, dir: Vec3A) -> Option<Surface> {
    Surface::at(scene, &scene.materials[hit.material as usize], hit, dir.dot(hit.n_geom) < 0.0, false)
}
