//! The glTF 2.0 metallic-roughness BSDF (with KHR_materials_specular), in the local frame.
//!
//! Follows the glTF specification's model (Appendix B): a dielectric layer over a diffuse
//! base, blended with a metal by `metallic`:
//!
//! ```text
//! f = (1−m)·(1 − F_d(cosθo))·(1 − F_d(cosθi))·base/π  +  F(v·h)·D(h)·G2/(4·cosθo·cosθi)
//! F   = Schlick with F0 = lerp(0.04·s, base, m), F90 = lerp(s, 1, m)
//! F_d = Schlick with F0 = 0.04·s, F90 = s          (s = specularFactor)
//! ```
//! Deviation: the specification's `fresnel_mix` weights the diffuse lobe by 1 − F_d(v·h),
//! which reflects up to 14% more than it receives for a white rough plastic at grazing
//! angles (our albedo test caught it). Weighting by the Fresnel transmission at both ends,
//! as Ashikhmin & Shirley do, keeps the model reciprocal and its albedo at most 1.
//! GGX with `alpha = roughness²`, height-correlated Smith G2, visible-normal sampling. With
//! `m = 0, s = 0` both Fresnel terms vanish and the model is exactly Lambertian, which
//! Blender's exported diffuse materials rely on. The one-sample lobe choice uses the albedo
//! estimate at θo: P(spec) ∝ lum(F(cosθo)), P(diffuse) ∝ lum((1−m)(1−F_d(cosθo))·base).

use super::BsdfSample;
use super::microfacet::Ggx;
use crate::math::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::math::{Rgb, Vec2, Vec3A, luminance};
use std::f32::consts::FRAC_1_PI;

/// Parameters of the metallic-roughness model at one surface point.
#[derive(Clone, Copy, Debug)]
pub struct MetalRough {
    base: Rgb,
    metallic: f32,
    specular: f32,
    f0: Rgb,
    f90: Rgb,
    ggx: Ggx,
}

#[inline]
fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

impl MetalRough {
    /// The model for base colour, metallic, roughness and specularFactor (all in [0,1]).
    pub fn new(base: Rgb, metallic: f32, roughness: f32, specular: f32) -> Self {
        let dielectric_f0 = Rgb::splat(0.04 * specular);
        let f0 = dielectric_f0.lerp(base, metallic);
        let f90 = Rgb::splat(specular).lerp(Rgb::ONE, metallic);
        Self { base, metallic, specular, f0, f90, ggx: Ggx::from_roughness(roughness) }
    }

    #[inline]
    fn fresnel(&self, cos: f32) -> Rgb {
        self.f0 + (self.f90 - self.f0) * schlick_weight(cos)
    }

    #[inline]
    fn dielectric_fresnel(&self, cos: f32) -> f32 {
        let f0 = 0.04 * self.specular;
        f0 + (self.specular - f0) * schlick_weight(cos)
    }

    /// Diffuse weight for one direction: the dielectric layer's Fresnel transmission.
    #[inline]
    fn diffuse_albedo(&self, cos: f32) -> Rgb {
        self.base * ((1.0 - self.metallic) * (1.0 - self.dielectric_fresnel(cos)))
    }

    /// Probability of choosing the specular lobe for outgoing `wo`.
    #[inline]
    fn specular_probability(&self, wo: Vec3A) -> f32 {
        let s = luminance(self.fresnel(wo.z));
        let d = luminance(self.diffuse_albedo(wo.z));
        if s + d <= 0.0 { 0.0 } else { s / (s + d) }
    }

    /// BSDF value (without the cosine).
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let h = (wo + wi).normalize();
        let voh = wo.dot(h).max(0.0);
        let spec = self.fresnel(voh) * (self.ggx.d(h) * self.ggx.g2(wo, wi) / (4.0 * wo.z * wi.z));
        spec + self.diffuse_albedo(wo.z) * ((1.0 - self.dielectric_fresnel(wi.z)) * FRAC_1_PI)
    }

    /// Solid-angle density of [`MetalRough::sample`].
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let ps = self.specular_probability(wo);
        let h = (wo + wi).normalize();
        ps * self.ggx.reflection_pdf(wo, h) + (1.0 - ps) * cosine_hemisphere_pdf(wi.z)
    }

    /// Picks a lobe with `u_lobe`, then a direction with `u`.
    #[inline]
    pub fn sample(&self, wo: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u_lobe < self.specular_probability(wo) {
            let h = self.ggx.sample_visible_normal(wo, u);
            2.0 * wo.dot(h) * h - wo
        } else {
            square_to_cosine_hemisphere(u)
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        if !(pdf > 0.0) {
            return None;
        }
        let weight = self.eval(wo, wi) * (wi.z / pdf);
        Some(BsdfSample { wi, weight, pdf })
    }
}
