//! Spot light with the KHR_lights_punctual cone falloff.
//!
//! Between the inner and outer cone the intensity follows the specification's reference:
//! `a = clamp((cosθ − cos_outer) / max(1e-3, cos_inner − cos_outer), 0, 1)`, attenuation `a²`.

use super::LightSample;
use crate::math::{Rgb, Vec3A, luminance};
use std::f32::consts::PI;

/// A spot light of on-axis radiant intensity `intensity` [W/sr].
#[derive(Clone, Debug)]
pub struct SpotLight {
    /// Position.
    pub position: Vec3A,
    /// Unit direction the cone points to.
    pub direction: Vec3A,
    /// On-axis radiant intensity.
    pub intensity: Rgb,
    /// Cosine of the inner cone half-angle (full intensity inside).
    pub cos_inner: f32,
    /// Cosine of the outer cone half-angle (dark outside).
    pub cos_outer: f32,
}

impl SpotLight {
    /// Angular attenuation at cosine `cos_theta` from the axis.
    #[inline]
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        let scale = 1.0 / (self.cos_inner - self.cos_outer).max(1e-3);
        let a = ((cos_theta - self.cos_outer) * scale).clamp(0.0, 1.0);
        a * a
    }

    /// The (delta) sample seen from `p`; `None` outside the cone.
    #[inline]
    pub fn sample_li(&self, p: Vec3A) -> Option<LightSample> {
        let d = self.position - p;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0) {
            return None;
        }
        let dist = dist2.sqrt();
        let wi = d / dist;
        let f = self.falloff(self.direction.dot(-wi));
        if f <= 0.0 {
            return None;
        }
        Some(LightSample {
            radiance: self.intensity * (f / dist2),
            wi,
            distance: dist,
            pdf: 1.0,
            p: self.position,
            n: Vec3A::ZERO,
        })
    }

    /// Power estimate 2π·Y(I)·(1 − (cos_inner + cos_outer)/2) (pbrt-v4's approximation).
    pub fn power(&self) -> f32 {
        2.0 * PI * luminance(self.intensity) * (1.0 - 0.5 * (self.cos_inner + self.cos_outer))
    }
}
