//! Fresnel reflectance: the exact dielectric term, the F0 ↔ IOR relations, and the F82-tint
//! conductor model Cycles' Principled BSDF uses for metals.

use crate::math::Rgb;

/// Normal-incidence reflectance of a dielectric of relative IOR `eta`.
#[inline]
pub fn f0_from_ior(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// The IOR whose normal-incidence reflectance is `f0` (clamped to [0, 0.99]).
#[inline]
pub fn ior_from_f0(f0: f32) -> f32 {
    let s = f0.clamp(0.0, 0.99).sqrt();
    (1.0 + s) / (1.0 - s)
}

/// Unpolarised Fresnel reflectance of a dielectric interface of relative IOR `eta` (outside
/// over inside) for an incident cosine `cos_i` (1 past total internal reflection).
#[inline]
pub fn dielectric(cos_i: f32, eta: f32) -> f32 {
    let c = cos_i.abs().min(1.0);
    let g2 = eta * eta - 1.0 + c * c;
    if g2 <= 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    let (a, b) = (g - c, g + c);
    let t = (c * b - 1.0) / (c * a + 1.0);
    0.5 * (a * a) / (b * b) * (1.0 + t * t)
}

/// The cosine-weighted average of [`dielectric`] over the hemisphere, ∫ 2μ·F(μ) dμ, by Kulla
/// and Conty's fit (as Cycles uses it for energy compensation).
#[inline]
pub fn dielectric_average(eta: f32) -> f32 {
    if eta >= 1.0 {
        (eta - 1.0) / (4.08567 + 1.00071 * eta)
    } else {
        0.997118 + eta * (0.1014 - eta * (0.965241 + 0.130607 * eta))
    }
}

/// (1 − μ)⁵.
#[inline]
pub fn schlick_weight(mu: f32) -> f32 {
    let m = (1.0 - mu).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// The F82-tint conductor: Schlick from `f0`, corrected so that at μ = 1/7 (82°) it equals
/// `tint` × Schlick (Hoffman 2023, as Cycles' Principled metal): white tint is plain Schlick.
#[derive(Clone, Copy, Debug)]
pub struct F82Tint {
    f0: Rgb,
    b: Rgb,
}

impl F82Tint {
    /// The model for normal-incidence colour `f0` and 82° tint `tint` (both in [0, 1]).
    pub fn new(f0: Rgb, tint: Rgb) -> Self {
        const MU: f32 = 1.0 / 7.0;
        let schlick = f0 + (Rgb::ONE - f0) * schlick_weight(MU);
        let denominator = MU * (1.0 - MU).powi(6);
        Self { f0, b: schlick * (Rgb::ONE - tint) / denominator }
    }

    /// Reflectance at microfacet cosine `mu`.
    #[inline]
    pub fn eval(&self, mu: f32) -> Rgb {
        let m = (1.0 - mu).clamp(0.0, 1.0);
        let w5 = schlick_weight(mu);
        (self.f0 + (Rgb::ONE - self.f0) * w5 - self.b * (mu * m * w5)).clamp(Rgb::ZERO, Rgb::ONE)
    }

    /// Its cosine-weighted hemispherical average ∫ 2μ·F(μ) dμ, exactly.
    #[inline]
    pub fn average(&self) -> Rgb {
        self.f0.lerp(Rgb::ONE, 1.0 / 21.0) - self.b / 126.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_fresnel_has_its_known_values() {
        assert!((dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((f0_from_ior(1.5) - 0.04).abs() < 1e-7);
        assert!((ior_from_f0(0.04) - 1.5).abs() < 1e-5);
        // Total internal reflection from inside glass past the critical angle.
        assert_eq!(dielectric(0.5, 1.0 / 1.5), 1.0);
        assert!((dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
        // The fit against a fine midpoint sum: within 7e-3 (2.5 % at η = 1.5; Cycles uses it
        // as it is).
        for eta in [1.2f32, 1.5, 2.0, 3.0, 1.0 / 1.5] {
            let n = 20_000;
            let sum: f64 = (0..n)
                .map(|i| (i as f64 + 0.5) / n as f64)
                .map(|m| 2.0 * m * dielectric(m as f32, eta) as f64 / n as f64)
                .sum();
            assert!(
                (sum - dielectric_average(eta) as f64).abs() < 7e-3,
                "eta {eta}: {sum} vs fit {}",
                dielectric_average(eta)
            );
        }
    }

    #[test]
    fn f82_tint_is_schlick_for_white_and_hits_its_tint_at_82_degrees() {
        let f0 = Rgb::new(0.9, 0.6, 0.3);
        let white = F82Tint::new(f0, Rgb::ONE);
        for mu in [0.0f32, 0.1, 0.5, 1.0] {
            let schlick = f0 + (Rgb::ONE - f0) * schlick_weight(mu);
            assert!((white.eval(mu) - schlick).abs().max_element() < 1e-6);
        }
        let tint = Rgb::new(0.5, 0.8, 1.0);
        let f = F82Tint::new(f0, tint);
        let schlick82 = f0 + (Rgb::ONE - f0) * schlick_weight(1.0 / 7.0);
        assert!((f.eval(1.0 / 7.0) - tint * schlick82).abs().max_element() < 1e-5);
        // The closed-form average against a midpoint sum.
        let n = 20_000;
        let mut sum = Rgb::ZERO;
        for i in 0..n {
            let mu = (i as f32 + 0.5) / n as f32;
            sum += f.eval(mu) * (2.0 * mu / n as f32);
        }
        assert!((sum - f.average()).abs().max_element() < 1e-3, "{sum} vs {}", f.average());
    }
}
