//! Small numeric vocabulary shared by every other module.
//!
//! Owns: the glam types we speak (the ones obvhs speaks too), the `Rgb` colour alias and a
//! few scalar helpers. Depends on nothing else in the crate.

pub mod distribution;
mod fixed;
pub mod frame;
pub mod warp;

pub use fixed::Fixed;
pub use glam::{Mat3, Mat4, UVec2, Vec2, Vec3, Vec3A, Vec4};

/// Linear Rec.709 RGB radiometric quantity (radiance, albedo, throughput…).
///
/// A plain alias of `Vec3A`: colours need the same component-wise SIMD arithmetic as points,
/// and an alias keeps them free to mix with glam's operators.
pub type Rgb = Vec3A;

/// Rec.709 luminance weights: the watts of lights' powers, and what `learned` observes.
pub const LUMINANCE: Vec3A = Vec3A::new(0.2126, 0.7152, 0.0722);

/// Linear interpolation weights of `x ∈ [0,1]` (clamped; NaN as 0) on `N ≥ 2` evenly
/// spaced nodes: (lower node, fraction towards the next).
#[inline]
pub fn node_position<const N: usize>(x: f32) -> (usize, f32) {
    // max/min, not clamp, which keeps NaN: NaN becomes 0.
    #[allow(clippy::manual_clamp)]
    let f = x.max(0.0).min(1.0) * (N - 1) as f32;
    // Through i32, which x86 converts in one instruction each way (usize takes a dozen).
    // SAFETY: f is finite and in [0, N − 1], so the saturation `as` would add is not needed.
    let i = unsafe { f.to_int_unchecked::<i32>() }.min(N as i32 - 2);
    (i as usize, f - i as f32)
}

/// Luminance of a linear Rec.709 colour.
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    c.dot(LUMINANCE)
}

/// The smallest box holding `points`, as (lowest, highest) corner; for none, an empty box
/// (every component of the lowest at `f32::MAX`, of the highest at `f32::MIN`).
#[inline]
pub fn point_bounds(points: impl IntoIterator<Item = Vec3A>) -> (Vec3A, Vec3A) {
    points.into_iter().fold((Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN)), |(lo, hi), p| (lo.min(p), hi.max(p)))
}

/// The Morton code of three coordinates of up to 21 bits: `a`'s bits at positions 0, 3, 6 …,
/// `b`'s at 1, 4, 7 …, `c`'s at 2, 5, 8 … (so `c`'s highest bit is the code's highest).
#[inline]
pub fn morton3(a: u32, b: u32, c: u32) -> u64 {
    fn spread(v: u32) -> u64 {
        let mut x = v as u64 & 0x1f_ffff;
        x = (x | x << 32) & 0x001f_0000_0000_ffff;
        x = (x | x << 16) & 0x001f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        (x | x << 2) & 0x1249_2492_4924_9249
    }
    spread(a) | spread(b) << 1 | spread(c) << 2
}

/// `acos` clamped to its domain, so that dot products a hair above 1 give 0, not NaN.
///
/// A polynomial (Abramowitz & Stegun 4.4.46, absolute error ≤ 2·10⁻⁸ before f32 rounding)
/// rather than libm's `acosf`: light-tree builds take several per light, and this one
/// inlines and is about as accurate in f32.
#[inline]
#[allow(clippy::excessive_precision)] // the published coefficients, as printed
pub fn safe_acos(x: f32) -> f32 {
    let a = x.abs().min(1.0);
    let p = -0.001_262_491_1_f32;
    let p = p * a + 0.006_670_090_1;
    let p = p * a - 0.017_088_125_6;
    let p = p * a + 0.030_891_881_0;
    let p = p * a - 0.050_174_304_6;
    let p = p * a + 0.088_978_987_4;
    let p = p * a - 0.214_598_801_6;
    let p = p * a + 1.570_796_305_0;
    let r = (1.0 - a).sqrt() * p;
    if x < 0.0 { std::f32::consts::PI - r } else { r }
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

#[cfg(test)]
mod tests {
    #[test]
    fn morton_codes_interleave_the_bits_of_each_coordinate() {
        assert_eq!(super::morton3(1, 0, 0), 1);
        assert_eq!(super::morton3(0, 1, 0), 2);
        assert_eq!(super::morton3(0, 0, 1), 4);
        assert_eq!(super::morton3(0, 0, 1 << 20), 1 << 62);
        assert_eq!(super::morton3(0b11, 0b01, 0b10), 0b101_011);
        assert_eq!(super::morton3(u32::MAX, u32::MAX, u32::MAX), (1 << 63) - 1);
    }

    use super::*;

    #[test]
    fn node_positions_clamp_and_take_nan_to_the_first_node() {
        assert_eq!(node_position::<5>(0.5), (2, 0.0));
        assert_eq!(node_position::<5>(0.3), (1, 0.3 * 4.0 - 1.0));
        // The last node is reached as the end of the last cell.
        assert_eq!(node_position::<5>(1.0), (3, 1.0));
        for x in [-2.0, f32::NEG_INFINITY, f32::NAN] {
            assert_eq!(node_position::<5>(x), (0, 0.0), "{x}");
        }
        assert_eq!(node_position::<256>(f32::INFINITY), (254, 1.0));
    }

    #[test]
    fn safe_acos_matches_libm_and_clamps() {
        for i in 0..=20_000 {
            let x = -1.0 + i as f32 / 10_000.0;
            let exact = (x as f64).acos();
            assert!((safe_acos(x) as f64 - exact).abs() < 1e-6, "acos({x}): {} vs {exact}", safe_acos(x));
        }
        assert_eq!(safe_acos(1.000_001), 0.0);
        assert_eq!(safe_acos(-1.000_001), std::f32::consts::PI);
    }
}
