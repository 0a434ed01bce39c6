//! Spot light: full intensity inside an inner cone, none outside an outer one, and between
//! them a curve of `t = clamp((cosθ − cos_outer) / max(1e-3, cos_inner − cos_outer), 0, 1)`:
//! `t²` as the KHR_lights_punctual reference has it, or Blender's smoothstep `t²(3 − 2t)`,
//! where Cycles' blend puts the inner cosine at `cos_outer + (1 − cos_outer)·blend`.

use super::LightSample;
use crate::math::{Rgb, Vec3A};
use std::f32::consts::PI;

/// How a spot light fades between its inner and outer cones.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SpotCurve {
    /// `t²`, KHR_lights_punctual's reference falloff.
    #[default]
    Quadratic,
    /// `t²(3 − 2t)`, Blender's (Cycles') spot blend.
    Smoothstep,
}

/// A spot light of on-axis radiant intensity `intensity` [W/sr].
#[derive(Clone, Debug)]
pub struct SpotLight {
    /// Position (metres).
    pub position: Vec3A,
    /// Unit direction the cone points to.
    pub direction: Vec3A,
    /// On-axis radiant intensity.
    pub intensity: Rgb,
    /// Cosine of the inner cone half-angle (full intensity inside).
    pub cos_inner: f32,
    /// Cosine of the outer cone half-angle (dark outside).
    pub cos_outer: f32,
    /// The fade between the cones.
    pub curve: SpotCurve,
}

/// A spot's cone: full intensity inside `cos_inner`, none outside `cos_outer`, `curve`
/// between (the spot lamps with a radius apply it to each light ray's own direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotCone {
    /// Unit direction the cone points to.
    pub direction: Vec3A,
    /// Cosine of the inner half-angle.
    pub cos_inner: f32,
    /// Cosine of the outer half-angle.
    pub cos_outer: f32,
    /// The fade between the cones.
    pub curve: SpotCurve,
}

impl SpotCone {
    /// Angular attenuation at cosine `cos_theta` from the axis.
    #[inline]
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        let scale = 1.0 / (self.cos_inner - self.cos_outer).max(1e-3);
        let t = ((cos_theta - self.cos_outer) * scale).clamp(0.0, 1.0);
        match self.curve {
            SpotCurve::Quadratic => t * t,
            SpotCurve::Smoothstep => t * t * (3.0 - 2.0 * t),
        }
    }

    /// Flux of a light of on-axis intensity `intensity` in this cone, per channel:
    /// 2π·I·(1 − (cos_inner + cos_outer)/2) (pbrt-v4's approximation).
    pub fn flux(&self, intensity: Rgb) -> Rgb {
        2.0 * PI * (1.0 - 0.5 * (self.cos_inner + self.cos_outer)) * intensity
    }
}

impl SpotLight {
    /// Its cone.
    #[inline]
    pub fn cone(&self) -> SpotCone {
        SpotCone { direction: self.direction, cos_inner: self.cos_inner, cos_outer: self.cos_outer, curve: self.curve }
    }

    /// Angular attenuation at cosine `cos_theta` from the axis.
    #[inline]
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        self.cone().falloff(cos_theta)
    }

    /// The (delta) sample seen from `p`; `None` outside the cone.
    #[inline]
    pub fn sample_li(&self, p: Vec3A) -> Option<LightSample> {
        super::point::delta_sample(self.position, p, |wi, dist2| {
            let f = self.falloff(self.direction.dot(-wi));
            (f > 0.0).then(|| self.intensity * (f / dist2))
        })
    }

    /// Flux estimate per channel ([`SpotCone::flux`]).
    pub fn flux(&self) -> Rgb {
        self.cone().flux(self.intensity)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_curves_fade_from_the_outer_to_the_inner_cone() {
        let spot = |curve| SpotLight {
            position: Vec3A::ZERO,
            direction: Vec3A::NEG_Y,
            intensity: Rgb::ONE,
            cos_inner: 0.9,
            cos_outer: 0.7,
            curve,
        };
        let (q, s) = (spot(SpotCurve::Quadratic), spot(SpotCurve::Smoothstep));
        for c in [1.0, 0.9, 0.7, 0.5] {
            assert_eq!(q.falloff(c), s.falloff(c), "cos {c}");
        }
        assert!((q.falloff(0.8) - 0.25).abs() < 1e-6 && (s.falloff(0.8) - 0.5).abs() < 1e-6);
    }
}
