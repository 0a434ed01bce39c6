//! Lambertian reflection, in the local shading frame (normal = +Z).

use super::BsdfSample;
use crate::math::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::math::{Rgb, Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// Ideal diffuse reflector with albedo `albedo`.
#[derive(Clone, Copy, Debug)]
pub struct Diffuse {
    /// Hemispherical reflectance in [0,1] per channel.
    pub albedo: Rgb,
}

impl Diffuse {
    /// BSDF value (without the cosine) for local directions pointing away from the surface.
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        self.albedo * FRAC_1_PI
    }

    /// Solid-angle density of [`Diffuse::sample`].
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 { 0.0 } else { cosine_hemisphere_pdf(wi.z) }
    }

    /// Cosine-weighted sampling; the weight is the albedo.
    #[inline]
    pub fn sample(&self, wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = square_to_cosine_hemisphere(u);
        let pdf = cosine_hemisphere_pdf(wi.z);
        (pdf > 0.0).then_some(BsdfSample { wi, weight: self.albedo, pdf })
    }
}
