//! Cycles' sheen (Blender's Principled Sheen, "Microfiber"; glTF's KHR_materials_sheen after
//! Blender's import): Zeltner, Burley and Chiang 2022, "Practical Multiple-Scattering Sheen
//! Using Linearly Transformed Cosines".
//!
//! In the frame whose x axis is the viewer's azimuth, the lobe times the cosine is
//! `colour · albedo · D(ω)`, D(ω) = max(z, 0)/π · (a / ((a·x + b·z)² + (a·y)² + z²))²: the
//! cosine distribution transformed by M = [[1, 0, −b], [0, 1, 0], [0, 0, a]], so it is sampled
//! exactly (a cosine direction mapped by M) and D is its density. a, b and the albedo come
//! from the table measured on Cycles (`tables::sheen`). Cycles layers it on top of everything
//! else, which keeps 1 − max(colour·albedo) of its weight (`principled.rs`).

use super::tables;
use crate::math::warp::square_to_cosine_hemisphere;
use crate::math::{Rgb, Vec2, Vec3, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// A sheen layer: its colour (Blender's Sheen Weight × Sheen Tint) and roughness in [0, 1].
/// Unaligned (16 bytes): it rides in every Principled BSDF, which is copied per vertex.
#[derive(Clone, Copy, Debug)]
pub struct Sheen {
    /// Colour, ≥ 0.
    pub color: Vec3,
    /// Roughness in [0, 1].
    pub roughness: f32,
}

/// The sheen seen from one outgoing direction.
#[derive(Clone, Copy, Debug)]
pub struct SheenLobe {
    /// colour · albedo: what the lobe reflects of uniform light.
    pub weight: Rgb,
    a: f32,
    b: f32,
    /// cos and sin of the outgoing direction's azimuth.
    azimuth: Vec2,
}

impl Sheen {
    /// The lobe seen from `wo` (local frame, z up), or `None` where Cycles has none (a faint
    /// or degenerate transform).
    #[inline]
    pub fn at(&self, wo: Vec3A) -> Option<SheenLobe> {
        let [a, b, albedo] = tables::sheen(self.roughness.clamp(1e-3, 1.0), wo.z);
        if !(a >= 1e-5 && albedo >= 1e-5) {
            return None;
        }
        let azimuth = Vec2::new(wo.x, wo.y).try_normalize().unwrap_or(Vec2::X);
        Some(SheenLobe { weight: Rgb::from(self.color) * albedo, a, b, azimuth })
    }
}

impl SheenLobe {
    /// `w` in the lobe's frame (x along the viewer's azimuth).
    #[inline]
    fn in_lobe_frame(self, w: Vec3A) -> Vec3A {
        let (c, s) = (self.azimuth.x, self.azimuth.y);
        Vec3A::new(c * w.x + s * w.y, c * w.y - s * w.x, w.z)
    }

    /// `w` from the lobe's frame back to the local frame.
    #[inline]
    fn in_local_frame(self, w: Vec3A) -> Vec3A {
        let (c, s) = (self.azimuth.x, self.azimuth.y);
        Vec3A::new(c * w.x - s * w.y, s * w.x + c * w.y, w.z)
    }

    /// (a / |M⁻¹ω|²)²/π at lobe-frame `l`: D(ω)/cos θ.
    #[inline]
    fn shape(&self, l: Vec3A) -> f32 {
        let (x, y) = (self.a * l.x + self.b * l.z, self.a * l.y);
        let len2 = x * x + y * y + l.z * l.z;
        let r = self.a / len2;
        r * r * FRAC_1_PI
    }

    /// Solid-angle density of [`SheenLobe::sample`] at `wi`, D(ω).
    #[inline]
    pub fn pdf(&self, wi: Vec3A) -> f32 {
        if wi.z <= 0.0 {
            return 0.0;
        }
        wi.z * self.shape(self.in_lobe_frame(wi))
    }

    /// The lobe's value (without the cosine) towards `wi`.
    #[inline]
    pub fn eval(&self, wi: Vec3A) -> Rgb {
        if wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        self.weight * self.shape(self.in_lobe_frame(wi))
    }

    /// A direction drawn with density [`SheenLobe::pdf`].
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec3A {
        let c = square_to_cosine_hemisphere(u);
        self.in_local_frame(Vec3A::new(c.x - c.z * self.b, c.y, c.z * self.a).normalize())
    }

    /// Its albedo as one number for layering: the largest channel of `weight`.
    #[inline]
    pub fn albedo(&self) -> f32 {
        self.weight.max_element()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lobe_is_a_density_over_the_hemisphere() {
        for (roughness, mu) in [(0.3f32, 0.9f32), (0.5, 0.5), (0.8, 0.2), (1.0, 0.6)] {
            let wo = Vec3A::new((1.0 - mu * mu).sqrt() * 0.6, (1.0 - mu * mu).sqrt() * 0.8, mu);
            let lobe = Sheen { color: Vec3::ONE, roughness }.at(wo).expect("a visible sheen");
            let v = crate::math::warp::hemisphere_integral(400, 400, |w| lobe.pdf(w) as f64);
            assert!((v - 1.0).abs() < 0.01, "roughness {roughness}, μ {mu}: ∫D = {v}");
        }
    }

    #[test]
    fn sheen_is_brightest_at_grazing_angles() {
        let albedo = |mu: f32| tables::sheen(0.5, mu)[2];
        assert!(albedo(0.1) > 2.0 * albedo(0.9), "{} vs {}", albedo(0.1), albedo(0.9));
    }
}
