//! An area lamp: Blender's area light (rectangle, square, disk or ellipse) as Cycles renders
//! it (Cycles 5.0, `kernel/light/area.h`; docs/gltf-blender.md).
//!
//! One-sided, emitting towards its normal `n = u × v / |u × v|` with radiance `L0 = P / (π A)`
//! for a lamp of power P and area A, scaled by the spread falloff `N · max(tan(s/2) − tan θ,
//! 0)` for a spread s < 180° (θ from the normal; `N = 1 / (tan(s/2) − s/2)` keeps the power
//! P whatever the spread). From behind it is invisible and sends nothing. Like every lamp it
//! is seen by BSDF rays (and camera rays where `camera_visible`), lets paths through and
//! casts no shadow.

use super::{LampHit, LightSample};
use crate::geometry::Ray;
use crate::math::warp::square_to_disk_concentric;
use crate::math::{Rgb, Vec2, Vec3A};
use std::f32::consts::{FRAC_PI_4, PI};

/// The spread falloff of an area lamp narrower than 180°.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    /// tan(s/2).
    tan_half: f32,
    /// The normalisation N that keeps the lamp's power.
    norm: f32,
}

impl Spread {
    /// The falloff of spread `s` radians; `None` at 180° or more (plain Lambertian emission).
    pub fn new(s: f32) -> Option<Self> {
        let half = 0.5 * s.max(0.0);
        if half >= 0.5 * PI - 1e-6 {
            return None;
        }
        // Cycles' series below 0.05 rad, where tan(h) − h cancels: (tan h − h) ≈ h³/3.
        let norm = if half > 0.05 { 1.0 / (half.tan() - half) } else { 3.0 / (half * half * half).max(1e-30) };
        Some(Self { tan_half: half.tan(), norm })
    }

    /// The factor along the normal, where it is largest: N·tan(s/2).
    pub fn peak(&self) -> f32 {
        self.norm * self.tan_half
    }

    /// Cosine of s/2: beyond it from the normal the lamp sends nothing.
    pub fn cos_half(&self) -> f32 {
        (1.0 + self.tan_half * self.tan_half).sqrt().recip()
    }

    /// The factor on the radiance at cos θ from the normal.
    #[inline]
    fn factor(&self, cos: f32) -> f32 {
        let tan = (1.0 - cos * cos).max(0.0).sqrt() / cos;
        self.norm * (self.tan_half - tan).max(0.0)
    }
}

/// A rectangle (parallelogram) or ellipse lamp.
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// Centre (metres).
    pub center: Vec3A,
    /// Half of its first side (from the centre to the middle of an edge).
    pub u: Vec3A,
    /// Half of its second side; it emits towards `u × v`.
    pub v: Vec3A,
    /// Unit normal, the side it emits to.
    pub n: Vec3A,
    /// Area, m².
    pub area: f32,
    /// The ellipse inscribed in the rectangle instead of the rectangle.
    pub ellipse: bool,
    /// Radiance along its normal without spread, L0.
    pub radiance: Rgb,
    /// The spread falloff, narrower than 180°.
    pub spread: Option<Spread>,
    /// Camera rays see it (off for Blender lights by default).
    pub camera_visible: bool,
}

impl AreaLight {
    /// The lamp of centre `center`, half sides `u` and `v` (emitting towards `u × v`),
    /// radiance `radiance` and spread `spread` radians (π: none); `None` when it has no area.
    pub fn new(center: Vec3A, u: Vec3A, v: Vec3A, ellipse: bool, radiance: Rgb, spread: f32) -> Option<Self> {
        let c = u.cross(v);
        let n = c.try_normalize()?;
        let area = 4.0 * c.length() * if ellipse { FRAC_PI_4 } else { 1.0 };
        (area > 0.0 && area.is_finite()).then_some(Self {
            center,
            u,
            v,
            n,
            area,
            ellipse,
            radiance,
            spread: Spread::new(spread),
            camera_visible: false,
        })
    }

    /// Flux per channel: π·A·L0 (the spread keeps it).
    pub fn flux(&self) -> Rgb {
        PI * self.area * self.radiance
    }

    /// Radiance leaving along the unit direction `omega` (towards a receiver).
    #[inline]
    fn radiance_along(&self, omega: Vec3A) -> Rgb {
        let cos = omega.dot(self.n);
        if !(cos > 0.0) {
            return Rgb::ZERO;
        }
        match &self.spread {
            Some(s) => self.radiance * s.factor(cos),
            None => self.radiance,
        }
    }

    /// Uniform by area, seen from `p` (two numbers in `[0,1)²`).
    #[inline]
    pub fn sample_li(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        let (x, y) = if self.ellipse {
            let d = square_to_disk_concentric(u);
            (d.x, d.y)
        } else {
            (2.0 * u.x - 1.0, 2.0 * u.y - 1.0)
        };
        let q = self.center + self.u * x + self.v * y;
        let w = q - p;
        let dist2 = w.length_squared();
        if !(dist2 > 0.0) {
            return None;
        }
        let dist = dist2.sqrt();
        let wi = w / dist;
        let radiance = self.radiance_along(-wi);
        if radiance == Rgb::ZERO {
            return None;
        }
        let cos = -wi.dot(self.n);
        Some(LightSample { radiance, wi, distance: dist, pdf: dist2 / (cos * self.area), p: q, n: self.n })
    }

    /// Solid-angle density with which [`sample_li`](Self::sample_li) from `p` picks `q`.
    #[inline]
    pub fn pdf_li(&self, p: Vec3A, q: Vec3A) -> f32 {
        let w = q - p;
        let dist2 = w.length_squared();
        let cos = w.dot(self.n).abs() / dist2.sqrt();
        if cos > 0.0 && dist2 > 0.0 { dist2 / (cos * self.area) } else { 0.0 }
    }

    /// Where `ray` meets the lamp's front within `t_max`, and the radiance it brings back.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<LampHit> {
        let denom = ray.dir.dot(self.n);
        if !(denom < 0.0) {
            return None;
        }
        let t = (self.center - ray.origin).dot(self.n) / denom;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let q = ray.at(t);
        let d = q - self.center;
        let (x, y) = (d.dot(self.u) / self.u.length_squared(), d.dot(self.v) / self.v.length_squared());
        let inside = if self.ellipse { x * x + y * y <= 1.0 } else { x.abs() <= 1.0 && y.abs() <= 1.0 };
        let radiance = self.radiance_along(-ray.dir.normalize());
        (inside && radiance != Rgb::ZERO).then_some(LampHit { t, p: q, n: self.n, radiance })
    }

    /// The box around it.
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        let extent = self.u.abs() + self.v.abs();
        (self.center - extent, self.center + extent)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Irradiance on the lamp's axis at distance `d`, facing it, over its own samples.
    fn on_axis(l: &AreaLight, d: f32) -> f64 {
        let p = l.center + l.n * d;
        let k = 400;
        let mut sum = 0.0;
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                if let Some(s) = l.sample_li(p, u) {
                    assert!((l.pdf_li(p, s.p) / s.pdf - 1.0).abs() < 1e-3);
                    sum += (s.radiance.x * s.wi.dot(-l.n) / s.pdf) as f64;
                }
            }
        }
        sum / (k * k) as f64
    }

    #[test]
    fn every_shape_and_spread_gives_what_cycles_measured() {
        // P = 100 W at 0.3 m on the axis (Cycles 5.0.1 renders): a 0.2 m square 308.32, a
        // 0.4 × 0.1 rectangle 273.84, a 0.3 m disk 282.94, a 0.4 × 0.2 ellipse 279.18, and the
        // 0.2 m square with a spread of 60° 1894.3.
        let lamp = |w: f32, h: f32, ellipse, spread: f32| {
            let area = w * h * if ellipse { FRAC_PI_4 } else { 1.0 };
            let l0 = Rgb::splat(100.0 / (PI * area));
            AreaLight::new(Vec3A::ZERO, Vec3A::X * (0.5 * w), Vec3A::Z * (0.5 * h), ellipse, l0, spread).unwrap()
        };
        // u × v = X × Z = −Y: the lamp faces down.
        assert_eq!(lamp(0.2, 0.2, false, PI).n, -Vec3A::Y);
        for (l, want) in [
            (lamp(0.2, 0.2, false, PI), 308.32),
            (lamp(0.4, 0.1, false, PI), 273.84),
            (lamp(0.3, 0.3, true, PI), 282.94),
            (lamp(0.4, 0.2, true, PI), 279.18),
            (lamp(0.2, 0.2, false, 60f32.to_radians()), 1894.3),
        ] {
            let e = on_axis(&l, 0.3);
            assert!((e - want).abs() < 2e-3 * want, "{e} against {want}");
        }
    }

    #[test]
    fn the_back_sends_nothing_and_rays_meet_it_only_from_the_front() {
        let l = AreaLight::new(Vec3A::ZERO, Vec3A::X * 0.5, Vec3A::Z * 0.5, false, Rgb::ONE, PI).unwrap();
        assert!(l.sample_li(Vec3A::Y, Vec2::splat(0.5)).is_none(), "above, behind its face");
        let below = Vec3A::new(0.1, -1.0, 0.2);
        let s = l.sample_li(below, Vec2::new(0.3, 0.8)).unwrap();
        let hit = l.intersect(&Ray::new(below, s.wi), f32::INFINITY).unwrap();
        assert!((hit.p - s.p).length() < 1e-5 && hit.radiance == Rgb::ONE);
        assert!(l.intersect(&Ray::new(Vec3A::Y, -Vec3A::Y), f32::INFINITY).is_none(), "from behind");
        assert!(l.intersect(&Ray::new(below, Vec3A::new(2.0, 1.0, 0.0)), f32::INFINITY).is_none(), "beside it");
    }
}
