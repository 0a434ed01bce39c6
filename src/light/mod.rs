//! Light sources: what each kind emits, how to sample a point or direction on it, and its
//! power.
//!
//! Owns: the closed set [`Light`] (one struct per kind, one file each) and [`LightSample`].
//! Units (docs/conventions.md): area lights carry radiance [W/(m²·sr)], point and spot lights
//! radiant intensity [W/sr], directional lights irradiance [W/m²]. [`Light::flux`] is per
//! channel; powers are its luminance (Rec.709 Y), the watts that reports and the power limit
//! speak. Samplers compare lights by the brightest channel instead (the `power` sampler that
//! of the flux, the tree that of `LightBounds::phi`, as pbrt-v4 does), so that a blue lamp is
//! not starved for its low luminance where blue is all that lights a wall. Depends on `math`
//! and `sampling` (for the numbers that pick points).

mod area;
mod area_light;
mod bounds;
mod distant;
mod environment;
mod point;
mod quad;
mod sphere;
mod spot;
mod sun;
mod triangle;

pub use area::{AreaEmission, AreaPoint};
pub use area_light::{AreaLight, Spread};
pub use bounds::{BoundsPacket, LANES, Lanes, LightBounds, cone_union};
pub use distant::DistantLight;
pub use environment::{EnvironmentLight, EnvironmentMap};
pub use point::PointLight;
pub use quad::QuadLight;
pub use sphere::{LampModel, SphereLight};
pub use spot::{SpotCone, SpotCurve, SpotLight};
pub use sun::SunLight;
pub use triangle::{EmissionTexture, TriangleLight};

use crate::geometry::Ray;
use crate::material::Image;
use crate::math::{Rgb, Vec2, Vec3A, luminance};
use crate::sampling::unit_f32;

/// Index of a light in the scene's light list.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct LightId(pub u32);

/// A point or direction chosen on a light, seen from a receiving point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Radiance arriving at the receiver along `-wi` (before visibility). For delta lights the
    /// incident irradiance-like term (I/d² or E) that the estimator divides by pdf = 1.
    pub radiance: Rgb,
    /// Unit direction from the receiver towards the light.
    pub wi: Vec3A,
    /// Distance to the light point (infinite for directional lights).
    pub distance: f32,
    /// Solid-angle density of `wi` (1 for delta lights).
    pub pdf: f32,
    /// The point on the light (shadow-ray target; unused for directional lights).
    pub p: Vec3A,
    /// Unit surface normal at `p` on the receiver's side (zero for point-like lights).
    pub n: Vec3A,
}

/// Where a ray meets a lamp (a light with a shape of its own that is not scene geometry:
/// [`SphereLight`], [`AreaLight`]), and the radiance it brings back from there.
#[derive(Clone, Copy, Debug)]
pub struct LampHit {
    /// Ray parameter.
    pub t: f32,
    /// The point on the lamp.
    pub p: Vec3A,
    /// The lamp's normal there (for the density of having sampled it).
    pub n: Vec3A,
    /// Radiance arriving back along the ray.
    pub radiance: Rgb,
}

/// Every kind of light myriad renders.
#[derive(Clone, Debug)]
pub enum Light {
    /// Isotropic point light.
    Point(PointLight),
    /// Spot light with glTF cone falloff.
    Spot(SpotLight),
    /// Directional ("sun") light at infinity.
    Distant(DistantLight),
    /// Emissive triangle.
    Triangle(TriangleLight),
    /// Emissive parallelogram (RON quads and grid cells).
    Quad(QuadLight),
    /// Radiance from every direction at infinity (found by rays that leave the scene).
    Environment(EnvironmentLight),
    /// A point or spot lamp with a radius (a facing disk or a sphere).
    Sphere(SphereLight),
    /// A rectangle or ellipse lamp (Blender's area light).
    Area(AreaLight),
    /// A sun with an angular size.
    Sun(SunLight),
}

/// What of its two 64-bit numbers a light's sample reads ([`Light::sample_bits`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleBits {
    /// None: a delta light.
    None,
    /// The top 32 bits of each (area lights take the top 24 as floats).
    Top,
    /// All 64 bits.
    All,
}

impl Light {
    /// Samples the light as seen from `p` with two 64-bit numbers (area lights take their
    /// top 24 bits as floats in `[0,1)²`); `None` when it cannot reach `p`. Emission
    /// textures read `images`, the scene's.
    #[inline(always)]
    pub fn sample_li(&self, p: Vec3A, u: [u64; 2], images: &[Image]) -> Option<LightSample> {
        let unit = || Vec2::new(unit_f32(u[0]), unit_f32(u[1]));
        match self {
            Light::Point(l) => l.sample_li(p),
            Light::Spot(l) => l.sample_li(p),
            Light::Distant(l) => l.sample_li(),
            Light::Triangle(l) => l.sample_li(p, unit(), images),
            Light::Quad(l) => l.sample_li(p, unit()),
            Light::Environment(l) => l.sample_li(u),
            Light::Sphere(l) => l.sample_li(p, unit()),
            Light::Area(l) => l.sample_li(p, unit()),
            Light::Sun(l) => l.sample_li(unit()),
        }
    }

    /// The point of an emissive triangle or quad that [`Light::sample_li`] would take for
    /// `u`, with its density per area; `None` for every other light.
    #[inline]
    pub fn area_point(&self, u: [u64; 2], images: &[Image]) -> Option<AreaPoint> {
        let unit = Vec2::new(unit_f32(u[0]), unit_f32(u[1]));
        match self {
            Light::Triangle(l) => Some(l.area_point(unit, images)),
            Light::Quad(l) => Some(l.area_point(unit)),
            _ => None,
        }
    }

    /// Whether it is an emissive triangle or quad of the scene's geometry (what
    /// [`Light::area_point`] samples).
    #[inline]
    pub fn is_surface(&self) -> bool {
        matches!(self, Light::Triangle(_) | Light::Quad(_))
    }

    /// Whether next-event estimation connects it through smooth glass: emissive surfaces and
    /// point and spot lamps with a radius seen as a facing disk (Blender's default) by their
    /// points, point, spot and directional lights as they are (a spot only where the straight
    /// way from the receiver is inside its cone: its sample starts there). A sphere lamp's
    /// points are sampled on the cap the receiver sees, which the glass turns away from the
    /// chain: measured, its connections did not pay.
    #[inline]
    pub fn connects_through_glass(&self) -> bool {
        match self {
            Light::Triangle(_) | Light::Quad(_) | Light::Point(_) | Light::Spot(_) | Light::Distant(_) => true,
            Light::Sphere(l) => l.model == LampModel::FacingDisk,
            _ => false,
        }
    }

    /// The density per unit area with which [`Light::area_point`] chooses its points.
    #[inline]
    pub fn area_pdf(&self) -> Option<f32> {
        match self {
            Light::Triangle(l) => Some(1.0 / l.area),
            Light::Quad(l) => Some(1.0 / l.area),
            _ => None,
        }
    }

    /// Solid-angle density with which [`Light::sample_li`] from `p` picks the light point `q`
    /// with normal `n_q`. Zero for delta lights (they cannot be hit); for lights at infinity
    /// (which rays reach by leaving the scene) see [`EnvironmentLight::pdf`] and
    /// [`SunLight::pdf`].
    #[inline]
    pub fn pdf_li(&self, p: Vec3A, q: Vec3A, n_q: Vec3A) -> f32 {
        match self {
            Light::Point(_) | Light::Spot(_) | Light::Distant(_) | Light::Environment(_) | Light::Sun(_) => 0.0,
            Light::Triangle(l) => l.emission.pdf_li(p, q, n_q, l.area),
            Light::Quad(l) => l.emission.pdf_li(p, q, n_q, l.area),
            Light::Sphere(l) => l.pdf_li(p, q),
            Light::Area(l) => l.pdf_li(p, q),
        }
    }

    /// Where `ray` meets this light within `t_max` when it is a lamp (a light with a shape of
    /// its own outside the scene's geometry: seen, let through, casting no shadow); `None`
    /// for every other light.
    #[inline]
    pub fn intersect_lamp(&self, ray: &Ray, t_max: f32) -> Option<LampHit> {
        match self {
            Light::Sphere(l) => l.intersect(ray, t_max),
            Light::Area(l) => l.intersect(ray, t_max),
            _ => None,
        }
    }

    /// The box a lamp's shape lies in, for the lamps' BVH; `None` for other lights.
    pub fn lamp_bounds(&self) -> Option<(Vec3A, Vec3A)> {
        match self {
            Light::Sphere(l) => Some(l.bounds()),
            Light::Area(l) => Some(l.bounds()),
            _ => None,
        }
    }

    /// Whether camera rays see this light (lamps and suns where they ask for it; emissive
    /// surfaces always, as the scene's geometry they are).
    pub fn camera_visible(&self) -> bool {
        match self {
            Light::Sphere(l) => l.camera_visible,
            Light::Area(l) => l.camera_visible,
            Light::Sun(l) => l.camera_visible,
            _ => true,
        }
    }

    /// Radiance leaving the surface at a ray hit, along `-dir` (`dir`: the ray's direction;
    /// `n_geom`: the hit triangle's front normal; `uv`: texture coordinates at the hit, in
    /// the scene's `images`). Zero for lights that are not triangles: lamps bring their
    /// radiance in their [`LampHit`].
    #[inline]
    pub fn emitted(&self, n_geom: Vec3A, dir: Vec3A, uv: Vec2, images: &[Image]) -> Rgb {
        match self {
            Light::Point(_)
            | Light::Spot(_)
            | Light::Distant(_)
            | Light::Environment(_)
            | Light::Sphere(_)
            | Light::Area(_)
            | Light::Sun(_) => Rgb::ZERO,
            Light::Triangle(l) => l.emitted(uv, -dir, images),
            Light::Quad(l) => l.emission.radiance_towards(n_geom, -dir),
        }
    }

    /// Emitted flux per channel, in watts; `scene_radius` sizes directional lights.
    pub fn flux(&self, scene_radius: f32) -> Rgb {
        match self {
            Light::Point(l) => l.flux(),
            Light::Spot(l) => l.flux(),
            Light::Distant(l) => l.flux(scene_radius),
            Light::Triangle(l) => AreaEmission { radiance: l.mean_radiance(), ..l.emission }.flux(l.area),
            Light::Quad(l) => l.emission.flux(l.area),
            Light::Environment(l) => l.flux(scene_radius),
            Light::Sphere(l) => l.flux(),
            Light::Area(l) => l.flux(),
            Light::Sun(l) => l.flux(scene_radius),
        }
    }

    /// Emitted power in watts (luminance of [`Light::flux`]), what reports and limits speak.
    pub fn power(&self, scene_radius: f32) -> f32 {
        luminance(self.flux(scene_radius))
    }

    /// True for lights no ray can hit (point, spot, directional).
    #[inline]
    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Spot(_) | Light::Distant(_))
    }

    /// What of [`Light::sample_li`]'s two 64-bit numbers it reads: none for a delta light,
    /// all 64 bits for the environment (its map is drawn exactly), the top 32 for the rest.
    #[inline]
    pub fn sample_bits(&self) -> SampleBits {
        match self {
            _ if self.is_delta() => SampleBits::None,
            Light::Environment(_) => SampleBits::All,
            _ => SampleBits::Top,
        }
    }

    /// Short name of the kind, for reports.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Light::Point(_) => "point",
            Light::Spot(_) => "spot",
            Light::Distant(_) => "directional",
            Light::Triangle(_) => "triangle",
            Light::Quad(_) => "quad",
            Light::Environment(_) => "environment",
            Light::Sphere(_) => "sphere lamp",
            Light::Area(_) => "area lamp",
            Light::Sun(_) => "sun",
        }
    }
}
