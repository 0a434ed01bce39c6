//! Isotropic point light.

use super::LightSample;
use crate::math::{Rgb, Vec3A, luminance};
use std::f32::consts::PI;

/// A point light of radiant intensity `intensity` [W/sr].
#[derive(Clone, Debug)]
pub struct PointLight {
    /// Position.
    pub position: Vec3A,
    /// Radiant intensity per channel.
    pub intensity: Rgb,
}

impl PointLight {
    /// The (delta) sample seen from `p`.
    #[inline]
    pub fn sample_li(&self, p: Vec3A) -> Option<LightSample> {
        let d = self.position - p;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0) {
            return None;
        }
        let dist = dist2.sqrt();
        Some(LightSample {
            radiance: self.intensity / dist2,
            wi: d / dist,
            distance: dist,
            pdf: 1.0,
            p: self.position,
            n: Vec3A::ZERO,
        })
    }

    /// 4π·Y(I).
    pub fn power(&self) -> f32 {
        4.0 * PI * luminance(self.intensity)
    }
}
