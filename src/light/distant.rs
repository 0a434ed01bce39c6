//! Directional light ("sun") at infinity.

use super::LightSample;
use crate::math::{Rgb, Vec3A};
use std::f32::consts::PI;

/// Parallel light of irradiance `irradiance` [W/m²] (measured perpendicular to the beam).
#[derive(Clone, Debug)]
pub struct DistantLight {
    /// Unit direction the light travels in (from the sun into the scene).
    pub direction: Vec3A,
    /// Irradiance per channel.
    pub irradiance: Rgb,
}

impl DistantLight {
    /// The (delta) sample: the same from every point.
    #[inline]
    pub fn sample_li(&self) -> Option<LightSample> {
        Some(LightSample {
            radiance: self.irradiance,
            wi: -self.direction,
            distance: f32::INFINITY,
            pdf: 1.0,
            p: Vec3A::ZERO,
            n: Vec3A::ZERO,
        })
    }

    /// Flux per channel through a disk of the scene's bounding radius: π·r²·E.
    pub fn flux(&self, scene_radius: f32) -> Rgb {
        PI * scene_radius * scene_radius * self.irradiance
    }
}
