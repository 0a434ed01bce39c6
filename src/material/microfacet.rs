//! The GGX (Trowbridge-Reitz) microfacet distribution, in the local frame, isotropic or
//! stretched along the frame's x and y axes.
//!
//! Owns: D, Smith Λ/G1/G2 (height-correlated), and visible-normal sampling (Heitz 2018,
//! "Sampling the GGX Distribution of Visible Normals", JCGT 7(4)) with its density.
//! `alpha = roughness²` as glTF defines it (docs/conventions.md); Blender's Anisotropic
//! stretches it as Cycles does: α_x = α/√(1 − 0.9·anisotropic) along the tangent,
//! α_y = α·√(1 − 0.9·anisotropic) across it.

use crate::math::{Vec2, Vec3A};
use std::f32::consts::PI;

/// Smallest alpha we evaluate: below it D overflows f32 at the peak. 1e-3 reads as a mirror.
pub const MIN_ALPHA: f32 = 1e-3;

/// GGX distribution of widths `alpha_x` along the local x axis and `alpha_y` along y.
#[derive(Clone, Copy, Debug)]
pub struct Ggx {
    /// Width along x (roughness² when isotropic), in [[`MIN_ALPHA`], 1].
    pub alpha_x: f32,
    /// Width along y.
    pub alpha_y: f32,
}

impl Ggx {
    /// The isotropic distribution for glTF perceptual `roughness`.
    pub fn from_roughness(roughness: f32) -> Self {
        Self::anisotropic(roughness, 0.0)
    }

    /// The distribution for perceptual `roughness` and Blender's `anisotropic` (in [0, 1]),
    /// stretched along the local x axis (the tangent).
    pub fn anisotropic(roughness: f32, anisotropic: f32) -> Self {
        let alpha = roughness * roughness;
        let aspect = (1.0 - 0.9 * anisotropic.clamp(0.0, 1.0)).sqrt();
        let width = |a: f32| a.clamp(MIN_ALPHA, 1.0);
        Self { alpha_x: width(alpha / aspect), alpha_y: width(alpha * aspect) }
    }

    /// The perceptual roughness of the isotropic lobe its energy tables read: (α_x·α_y)^¼,
    /// as Cycles.
    #[inline]
    pub fn table_roughness(&self) -> f32 {
        (self.alpha_x * self.alpha_y).sqrt().sqrt()
    }

    /// Whether it is the same along x and y.
    #[inline]
    pub fn is_isotropic(&self) -> bool {
        self.alpha_x == self.alpha_y
    }

    /// Normal distribution D(h).
    #[inline]
    pub fn d(&self, h: Vec3A) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        if self.is_isotropic() {
            let a2 = self.alpha_x * self.alpha_x;
            let t = h.z * h.z * (a2 - 1.0) + 1.0;
            return a2 / (PI * t * t);
        }
        // 1/(π·αx·αy·((x/αx)² + (y/αy)² + z²)²) with (αx·αy)² brought into the square.
        let a = self.alpha_x * self.alpha_y;
        let (x, y, z) = (h.x * self.alpha_y, h.y * self.alpha_x, h.z * a);
        let t = x * x + y * y + z * z;
        a * a * a / (PI * t * t)
    }

    /// Smith Λ(w).
    #[inline]
    pub fn lambda(&self, w: Vec3A) -> f32 {
        let c2 = w.z * w.z;
        if c2 == 0.0 {
            return f32::INFINITY;
        }
        let (x, y) = (self.alpha_x * w.x, self.alpha_y * w.y);
        0.5 * ((1.0 + (x * x + y * y) / c2).sqrt() - 1.0)
    }

    /// Masking G1(w).
    #[inline]
    pub fn g1(&self, w: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing G2(wo, wi).
    #[inline]
    pub fn g2(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// A microfacet normal visible from `wo` (wo.z > 0).
    #[inline]
    pub fn sample_visible_normal(&self, wo: Vec3A, u: Vec2) -> Vec3A {
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        let vh = Vec3A::new(ax * wo.x, ay * wo.y, wo.z).normalize();
        let lensq = vh.x * vh.x + vh.y * vh.y;
        let t1 = if lensq > 0.0 { Vec3A::new(-vh.y, vh.x, 0.0) / lensq.sqrt() } else { Vec3A::X };
        let t2 = vh.cross(t1);
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let p1 = r * phi.cos();
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
        let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        Vec3A::new(ax * nh.x, ay * nh.y, nh.z.max(0.0)).normalize()
    }

    /// What a lobe's value and its sampling density towards one direction share: D(h) and
    /// Λ(wo), worked out once for both.
    #[inline]
    pub fn facet(&self, wo: Vec3A, h: Vec3A) -> Facet {
        Facet { d: self.d(h), lambda_o: self.lambda(wo) }
    }

    /// G2(wo, wi) with Λ(wo) from `facet`.
    #[inline]
    pub fn g2_from(&self, facet: Facet, wi: Vec3A) -> f32 {
        1.0 / (1.0 + facet.lambda_o + self.lambda(wi))
    }
}

/// D(h) and Λ(wo) of a [`Ggx`] for one `wo` and half vector `h` ([`Ggx::facet`]).
#[derive(Clone, Copy, Debug)]
pub struct Facet {
    /// D(h).
    pub d: f32,
    /// Λ(wo).
    pub lambda_o: f32,
}

impl Facet {
    /// Masking G1(wo).
    #[inline]
    pub fn g1(&self) -> f32 {
        1.0 / (1.0 + self.lambda_o)
    }

    /// Solid-angle density of the reflected direction `wi` when `h` was drawn by
    /// [`Ggx::sample_visible_normal`] from `wo`: G1(wo)·D(h) / (4·wo.z).
    #[inline]
    pub fn reflection_pdf(&self, wo: Vec3A) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        self.g1() * self.d / (4.0 * wo.z)
    }
}

/// The direction `wo` refracts into through a facet of normal `h` (on `wo`'s side), relative
/// IOR `eta` (the far side over `wo`'s side); `None` past total internal reflection.
#[inline]
pub fn refract(wo: Vec3A, h: Vec3A, eta: f32) -> Option<Vec3A> {
    let cos_i = wo.dot(h);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wo / eta + h * (cos_i / eta - cos_t))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projected_normal_area_is_one() {
        // ∫ D(h) cos θh dω = 2π ∫ D(θ) cos θ sin θ dθ = 1 (midpoint rule in θ).
        for roughness in [0.1f32, 0.3, 0.6, 1.0] {
            let g = Ggx::from_roughness(roughness);
            let n = 200_000;
            let dt = std::f64::consts::FRAC_PI_2 / n as f64;
            let sum: f64 = (0..n)
                .map(|i| {
                    let t = (i as f64 + 0.5) * dt;
                    let h = Vec3A::new(t.sin() as f32, 0.0, t.cos() as f32);
                    g.d(h) as f64 * t.cos() * t.sin() * dt
                })
                .sum();
            let v = 2.0 * std::f64::consts::PI * sum;
            assert!((v - 1.0).abs() < 1e-3, "roughness {roughness}: {v}");
        }
    }

    #[test]
    fn an_anisotropic_distribution_keeps_unit_projected_area() {
        // ∫ D(h) cos θh dω over (cos θ, φ) by the midpoint rule: stretching keeps the area.
        for (roughness, anisotropic) in [(0.4f32, 0.5f32), (0.7, 1.0)] {
            let g = Ggx::anisotropic(roughness, anisotropic);
            assert!(g.alpha_x > g.alpha_y && !g.is_isotropic());
            let v = crate::math::warp::hemisphere_integral(2000, 400, |h| (g.d(h) * h.z) as f64);
            assert!((v - 1.0).abs() < 2e-3, "roughness {roughness}, anisotropic {anisotropic}: {v}");
        }
    }

    #[test]
    fn visible_normals_face_the_viewer() {
        let g = Ggx::from_roughness(0.5);
        let wo = Vec3A::new(0.6, 0.0, 0.8);
        for i in 0..1000 {
            let u = Vec2::new((i as f32 + 0.5) / 1000.0, ((i * 7919) % 1000) as f32 / 1000.0);
            let h = g.sample_visible_normal(wo, u);
            assert!((h.length() - 1.0).abs() < 1e-4 && h.z >= 0.0 && h.dot(wo) >= -1e-4);
        }
    }
}
