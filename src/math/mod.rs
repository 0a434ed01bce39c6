//! Small numeric vocabulary shared by every other module.
//!
//! Owns: the glam types we speak (the ones obvhs speaks too), the `Rgb` colour alias and a
//! few scalar helpers. Depends on nothing else in the crate.

pub mod distribution;
pub mod frame;
pub mod warp;

pub use glam::{Mat3, Mat4, UVec2, Vec2, Vec3, Vec3A, Vec4};

/// Linear Rec.709 RGB radiometric quantity (radiance, albedo, throughput…).
///
/// A plain alias of `Vec3A`: colours need the same component-wise SIMD arithmetic as points,
/// and an alias keeps them free to mix with glam's operators.
pub type Rgb = Vec3A;

/// Rec.709 luminance weights: the scalar by which lights are compared (power, importance).
pub const LUMINANCE: Vec3A = Vec3A::new(0.2126, 0.7152, 0.0722);

/// Luminance of a linear Rec.709 colour.
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    c.dot(LUMINANCE)
}

/// `acos` clamped to its domain, so that dot products a hair above 1 give 0, not NaN.
#[inline]
pub fn safe_acos(x: f32) -> f32 {
    x.clamp(-1.0, 1.0).acos()
}

/// `sqrt` of a value that is non-negative up to round-off.
#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// Multiple-importance weight of technique `a` against `b` (power heuristic, β = 2; Veach 1997).
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let a2 = pdf_a * pdf_a;
    let b2 = pdf_b * pdf_b;
    if a2.is_infinite() {
        return 1.0;
    }
    if a2 + b2 == 0.0 { 0.0 } else { a2 / (a2 + b2) }
}
