//! Isotropic point light.

use super::LightSample;
use crate::math::{Rgb, Vec3A};
use std::f32::consts::PI;

/// A point light of radiant intensity `intensity` [W/sr].
#[derive(Clone, Debug)]
pub struct PointLight {
    /// Position (metres).
    pub position: Vec3A,
    /// Radiant intensity per channel.
    pub intensity: Rgb,
}

/// The (delta) sample of a light at `position` seen from `p`: `radiance(wi, d²)` gives what
/// arrives along the unit direction `wi` towards the light from distance d (`None`: nothing).
#[inline]
pub(super) fn delta_sample(
    position: Vec3A,
    p: Vec3A,
    radiance: impl FnOnce(Vec3A, f32) -> Option<Rgb>,
) -> Option<LightSample> {
    let d = position - p;
    let dist2 = d.length_squared();
    if !(dist2 > 0.0) {
        return None;
    }
    let dist = dist2.sqrt();
    let wi = d / dist;
    Some(LightSample { radiance: radiance(wi, dist2)?, wi, distance: dist, pdf: 1.0, p: position, n: Vec3A::ZERO })
}

impl PointLight {
    /// The (delta) sample seen from `p`.
    #[inline]
    pub fn sample_li(&self, p: Vec3A) -> Option<LightSample> {
        delta_sample(self.position, p, |_, dist2| Some(self.intensity / dist2))
    }

    /// Flux per channel, 4π·I.
    pub fn flux(&self) -> Rgb {
        4.0 * PI * self.intensity
    }
}
