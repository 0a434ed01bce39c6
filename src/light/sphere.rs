//! A point or spot lamp with a radius: Blender's point and spot lights as Cycles renders them
//! (Cycles 5.0, `kernel/light/point.h` and `spot.h`; docs/gltf-blender.md).
//!
//! The lamp's radiance is `L = I / (π r²)` for a lamp of intensity `I` (a Blender light of
//! power P: `I = P / (4π)`), uniform over its shape, in one of two models:
//! - [`LampModel::FacingDisk`] (Blender's "Soft Falloff", on by default): a disk of radius r
//!   through the centre whose face turns to each receiver. On its axis a receiver gets
//!   `I / (d² + r²)`, finite even at the centre: the soft falloff.
//! - [`LampModel::Sphere`]: the sphere of radius r. Outside it a facing receiver gets exactly
//!   `I / d²`, inside it `π L` from every direction.
//!
//! A spot's cone attenuates each light ray by its own direction, from the point on the lamp
//! to the receiver (not from the centre), and not at all for receivers inside the sphere.
//! Lamps are seen by BSDF rays (and camera rays where `camera_visible`), let paths through and
//! cast no shadow: the scene keeps them out of its triangles (`Scene::lamps_along`).

use super::{LampHit, LightSample, SpotCone};
use crate::geometry::Ray;
use crate::math::frame::Frame;
use crate::math::warp::{
    UNIFORM_SPHERE_PDF, square_to_disk_concentric, square_to_uniform_cone, square_to_uniform_sphere, uniform_cone_pdf,
};
use crate::math::{Rgb, Vec2, Vec3A};
use std::f32::consts::PI;

/// What shape a point or spot lamp of some radius has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LampModel {
    /// A disk that faces each receiver (Blender's Soft Falloff, its default).
    #[default]
    FacingDisk,
    /// A sphere.
    Sphere,
}

/// A point or spot lamp of radius `radius` > 0.
#[derive(Clone, Debug)]
pub struct SphereLight {
    /// Centre (metres).
    pub center: Vec3A,
    /// Radius (metres, > 0).
    pub radius: f32,
    /// Radiance of its surface, I / (π r²).
    pub radiance: Rgb,
    /// Disk or sphere.
    pub model: LampModel,
    /// The spot cone, for a spot lamp.
    pub spot: Option<SpotCone>,
    /// Camera rays see it (Blender's Ray Visibility › Camera, off for lights by default).
    pub camera_visible: bool,
}

impl SphereLight {
    /// The lamp of intensity `intensity` [W/sr] and radius `radius` (> 0).
    pub fn new(center: Vec3A, radius: f32, intensity: Rgb, model: LampModel, spot: Option<SpotCone>) -> Self {
        let radiance = intensity / (PI * radius * radius);
        Self { center, radius, radiance, model, spot, camera_visible: false }
    }

    /// Its intensity, the π r² L every receiver outside sees of it (a spot's on its axis).
    pub fn intensity(&self) -> Rgb {
        PI * self.radius * self.radius * self.radiance
    }

    /// Flux per channel: 4π·I, or the spot cone's share of it.
    pub fn flux(&self) -> Rgb {
        match &self.spot {
            Some(cone) => cone.flux(self.intensity()),
            None => 4.0 * PI * self.intensity(),
        }
    }

    /// Whether `p` is inside the sphere (a sphere lamp's inside is lit evenly, without a
    /// cone).
    #[inline]
    fn inside(&self, p: Vec3A) -> bool {
        self.model == LampModel::Sphere && (p - self.center).length_squared() <= self.radius * self.radius
    }

    /// A point on the lamp as seen from `p` (two numbers in `[0,1)²`), with its solid-angle
    /// density; `None` where it sends nothing to `p`.
    #[inline]
    pub fn sample_li(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        match self.model {
            LampModel::FacingDisk => self.sample_disk(p, u),
            LampModel::Sphere => self.sample_sphere(p, u),
        }
    }

    /// Uniformly by area on the disk facing `p`: density t² / (π r² cos θ).
    fn sample_disk(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        let n = (p - self.center).try_normalize()?;
        let frame = Frame::from_normal(n);
        let d = square_to_disk_concentric(u) * self.radius;
        let q = self.center + frame.s * d.x + frame.t * d.y;
        let w = q - p;
        let dist2 = w.length_squared();
        let dist = dist2.sqrt();
        let wi = w / dist;
        let cos = -wi.dot(n);
        let radiance = self.radiance_along(-wi);
        if !(cos > 0.0) || radiance == Rgb::ZERO {
            return None;
        }
        let pdf = dist2 / (PI * self.radius * self.radius * cos);
        Some(LightSample { radiance, wi, distance: dist, pdf, p: q, n })
    }

    /// Outside the sphere uniformly in the cone it subtends, inside uniformly over every
    /// direction; the point is where that direction meets the sphere.
    fn sample_sphere(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        let to_center = self.center - p;
        let dist2 = to_center.length_squared();
        let r2 = self.radius * self.radius;
        let (wi, pdf) = if dist2 > r2 {
            let axis = to_center / dist2.sqrt();
            let one_minus_cos = one_minus_cos_cap(r2 / dist2);
            (
                Frame::from_normal(axis).to_world(square_to_uniform_cone(u, one_minus_cos)),
                uniform_cone_pdf(one_minus_cos),
            )
        } else {
            (square_to_uniform_sphere(u), UNIFORM_SPHERE_PDF)
        };
        let t = self.sphere_distance(p, wi)?;
        let q = p + wi * t;
        let n = (q - self.center) / self.radius;
        let radiance = if dist2 > r2 { self.radiance_along(-wi) } else { self.radiance };
        (radiance != Rgb::ZERO).then_some(LightSample { radiance, wi, distance: t, pdf, p: q, n })
    }

    /// Where the ray from `p` along the unit `wi` meets the sphere (from outside the nearer
    /// crossing, from inside the exit); a ray that grazes the silhouette after round-off
    /// takes its closest approach.
    #[inline]
    fn sphere_distance(&self, p: Vec3A, wi: Vec3A) -> Option<f32> {
        let oc = p - self.center;
        let b = oc.dot(wi);
        let c = oc.length_squared() - self.radius * self.radius;
        let disc = (b * b - c).max(0.0).sqrt();
        let t = if c > 0.0 { -b - disc } else { -b + disc };
        (t > 0.0).then_some(t)
    }

    /// Solid-angle density with which [`sample_li`](Self::sample_li) from `p` picks `q` on
    /// the lamp.
    #[inline]
    pub fn pdf_li(&self, p: Vec3A, q: Vec3A) -> f32 {
        match self.model {
            LampModel::FacingDisk => {
                let Some(n) = (p - self.center).try_normalize() else { return 0.0 };
                let w = q - p;
                let dist2 = w.length_squared();
                let cos = -w.dot(n) / dist2.sqrt();
                if cos > 0.0 { dist2 / (PI * self.radius * self.radius * cos) } else { 0.0 }
            }
            LampModel::Sphere => {
                let dist2 = (self.center - p).length_squared();
                let r2 = self.radius * self.radius;
                if dist2 > r2 { uniform_cone_pdf(one_minus_cos_cap(r2 / dist2)) } else { UNIFORM_SPHERE_PDF }
            }
        }
    }

    /// For a disk facing each receiver: the density per unit area with which
    /// [`sample_li`](Self::sample_li) from `p` picks the point `q` of the disk facing `p`
    /// (zero outside a spot's cone as `p` sees `q`).
    pub fn disk_pdf_from(&self, p: Vec3A, q: Vec3A) -> f32 {
        debug_assert_eq!(self.model, LampModel::FacingDisk);
        if self.radiance_along((p - q).normalize_or_zero()) == Rgb::ZERO {
            return 0.0;
        }
        1.0 / (PI * self.radius * self.radius)
    }

    /// Radiance along the unit direction `omega` leaving the lamp (towards a receiver
    /// outside): the spot cone's attenuation applied.
    #[inline]
    pub fn radiance_along(&self, omega: Vec3A) -> Rgb {
        match &self.spot {
            Some(cone) => self.radiance * cone.falloff(omega.dot(cone.direction)),
            None => self.radiance,
        }
    }

    /// Where `ray` meets the lamp within `t_max`, and the radiance it brings back: the disk
    /// facing the ray's origin, or the sphere (its far side from inside).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<LampHit> {
        let o = ray.origin;
        let (t, n) = match self.model {
            LampModel::FacingDisk => {
                let n = (o - self.center).try_normalize()?;
                let denom = ray.dir.dot(n);
                if !(denom < 0.0) {
                    return None;
                }
                let t = (self.center - o).dot(n) / denom;
                let q = ray.at(t);
                ((q - self.center).length_squared() <= self.radius * self.radius).then_some((t, n))?
            }
            LampModel::Sphere => {
                let len = ray.dir.length();
                let t = self.sphere_distance(o, ray.dir / len)? / len;
                (t, (ray.at(t) - self.center) / self.radius)
            }
        };
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let omega = -ray.dir.normalize();
        let radiance = if self.inside(o) { self.radiance } else { self.radiance_along(omega) };
        Some(LampHit { t, p: ray.at(t), n, radiance })
    }

    /// The box around the lamp (both models lie within the sphere).
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        (self.center - Vec3A::splat(self.radius), self.center + Vec3A::splat(self.radius))
    }
}

/// 1 − cos α of the cone a sphere subtends where sin²α = `sin2` < 1, without the
/// cancellation of `1 − √(1 − sin²)` for small spheres far away.
#[inline]
fn one_minus_cos_cap(sin2: f32) -> f32 {
    sin2 / (1.0 + (1.0 - sin2).max(0.0).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::SpotCurve;

    /// The irradiance at `p` on a surface of normal `n`, by Monte Carlo over the lamp's own
    /// samples (a stratified grid of `k²` numbers).
    fn irradiance(l: &SphereLight, p: Vec3A, n: Vec3A, k: u32) -> f64 {
        let mut sum = 0.0;
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                if let Some(s) = l.sample_li(p, u) {
                    assert!((l.pdf_li(p, s.p) / s.pdf - 1.0).abs() < 1e-3, "pdf_li agrees with the sample's pdf");
                    sum += (s.radiance.x * s.wi.dot(n).max(0.0) / s.pdf) as f64;
                }
            }
        }
        sum / (k * k) as f64
    }

    #[test]
    fn a_facing_disk_gives_the_soft_falloff_and_a_sphere_the_inverse_square() {
        // Cycles' measured values (P = 100 W, so I = 100/(4π)): a disk of radius 0.2 at 0.3 m
        // gives E = P/(4π(d² + r²)) = 61.213; radius 0.4, the receiver inside it, 31.831; a
        // sphere outside gives P/(4πd²) and inside P/(4πr²).
        let i = Rgb::splat(100.0 / (4.0 * PI));
        let p = Vec3A::new(0.0, -0.3, 0.0);
        let disk = |r| SphereLight::new(Vec3A::ZERO, r, i, LampModel::FacingDisk, None);
        let e = irradiance(&disk(0.2), p, Vec3A::Y, 256);
        assert!((e - 61.213).abs() < 0.05, "{e}");
        let e = irradiance(&disk(0.4), p, Vec3A::Y, 256);
        assert!((e - 31.831).abs() < 0.05, "{e}");
        let sphere = |r| SphereLight::new(Vec3A::ZERO, r, i, LampModel::Sphere, None);
        let e = irradiance(&sphere(0.2), p, Vec3A::Y, 256);
        assert!((e - 100.0 / (4.0 * PI as f64 * 0.09)).abs() < 0.05, "{e}");
        let e = irradiance(&sphere(0.4), p, Vec3A::Y, 512);
        assert!((e - 100.0 / (4.0 * PI as f64 * 0.16)).abs() < 0.3, "{e}");
    }

    #[test]
    fn a_spot_lamp_attenuates_each_ray_by_its_own_direction() {
        // Cycles (spot 60°, blend 0.5, r = 0.1; a floor 0.3 m below the lamp, 20° off the
        // axis): 44.28 for the disk and 47.70 for the sphere, where a point lamp gives 73.37.
        let half = 30f32.to_radians();
        let cone = SpotCone {
            direction: -Vec3A::Y,
            cos_outer: half.cos(),
            cos_inner: half.cos() + (1.0 - half.cos()) * 0.5,
            curve: SpotCurve::Smoothstep,
        };
        let i = Rgb::splat(100.0 / (4.0 * PI));
        let theta = 20f32.to_radians();
        let (p, n) = (Vec3A::new(0.3 * theta.tan(), -0.3, 0.0), Vec3A::Y);
        let disk = SphereLight::new(Vec3A::ZERO, 0.1, i, LampModel::FacingDisk, Some(cone));
        let sphere = SphereLight::new(Vec3A::ZERO, 0.1, i, LampModel::Sphere, Some(cone));
        let (ed, es) = (irradiance(&disk, p, n, 512), irradiance(&sphere, p, n, 512));
        assert!((ed - 44.28).abs() < 0.2 && (es - 47.70).abs() < 0.2, "disk {ed}, sphere {es}");
    }

    #[test]
    fn rays_meet_the_lamp_where_sampling_puts_its_points() {
        let i = Rgb::ONE;
        for model in [LampModel::FacingDisk, LampModel::Sphere] {
            let l = SphereLight::new(Vec3A::new(0.0, 2.0, 0.0), 0.5, i, model, None);
            let p = Vec3A::new(0.3, 0.0, 0.1);
            for k in 0..50 {
                let u = Vec2::new((k as f32 * 0.618).fract(), (k as f32 * 0.377 + 0.1).fract());
                let s = l.sample_li(p, u).unwrap();
                let hit = l.intersect(&Ray::new(p, s.wi * 2.0), f32::INFINITY).expect("the sampled direction hits");
                assert!((hit.p - s.p).length() < 1e-4, "{model:?}: {} vs {}", hit.p, s.p);
                assert!((l.pdf_li(p, hit.p) - s.pdf).abs() < 1e-3 * s.pdf);
                assert_eq!(hit.radiance, s.radiance);
            }
            // Not beyond t_max, not behind the ray.
            assert!(l.intersect(&Ray::new(p, Vec3A::Y), 1.0).is_none());
            assert!(l.intersect(&Ray::new(p, -Vec3A::Y), f32::INFINITY).is_none());
        }
    }
}
