//! Spawning rays off surfaces without self-intersection ("acne").
//!
//! Wächter & Binder 2019, "A Fast and Robust Method for Avoiding Self-Intersection" (Ray
//! Tracing Gems, ch. 6): move the origin along the geometric normal by a fixed number of ULPs
//! of each coordinate, so the offset scales with the magnitude of the position (float error
//! grows with it), plus a small absolute offset near the origin where ULPs vanish. Hit points
//! are interpolated from the triangle's vertices, which keeps their error within a few ULPs.

use crate::math::Vec3A;

const ORIGIN: f32 = 1.0 / 32.0;
const FLOAT_SCALE: f32 = 1.0 / 65536.0;
const INT_SCALE: f32 = 256.0;

/// `p` nudged off its surface towards the side `n` (unit geometric normal) points to.
#[inline]
pub fn offset_ray_origin(p: Vec3A, n: Vec3A) -> Vec3A {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse4.1", target_feature = "ssse3"))]
    {
        // SAFETY: compiled only where SSE4.1 and SSSE3 are enabled (the x86-64-v3 build,
        // checked at start-up by `crate::cpu`).
        unsafe { offset_sse(p, n) }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse4.1", target_feature = "ssse3")))]
    offset_scalar(p, n)
}

/// [`offset_ray_origin`] one coordinate at a time: the rule as written, which builds
/// without SSE4.1 run and [`offset_sse`] must match.
#[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "sse4.1", target_feature = "ssse3"))))]
#[inline]
fn offset_scalar(p: Vec3A, n: Vec3A) -> Vec3A {
    let of = n * INT_SCALE;
    let step = |x: f32, o: f32, nn: f32| {
        let oi = o as i32;
        let moved = f32::from_bits((x.to_bits() as i32).wrapping_add(if x < 0.0 { -oi } else { oi }) as u32);
        if x.abs() < ORIGIN { x + FLOAT_SCALE * nn } else { moved }
    };
    Vec3A::new(step(p.x, of.x, n.x), step(p.y, of.y, n.y), step(p.z, of.z, n.z))
}

/// [`offset_ray_origin`] on the three coordinates at once: the same arithmetic as the
/// per-coordinate steps (the ULP offset truncated to an integer, negated where the
/// coordinate is negative, added to its bits; the absolute offset near the origin), so the
/// same origins bit for bit (a ray spawns one to three of them a vertex).
///
/// # Safety
/// The CPU must have SSE4.1 and SSSE3.
#[cfg(all(target_arch = "x86_64", target_feature = "sse4.1", target_feature = "ssse3"))]
#[inline(always)]
unsafe fn offset_sse(p: Vec3A, n: Vec3A) -> Vec3A {
    use std::arch::x86_64::*;
    let (pm, nm) = (__m128::from(p), __m128::from(n));
    // SAFETY: register-only intrinsics, available by the caller's contract.
    unsafe {
        // |n|·256 ≤ 256: truncation needs no saturation.
        let oi = _mm_cvttps_epi32(_mm_mul_ps(nm, _mm_set1_ps(INT_SCALE)));
        // Negated where the coordinate's sign bit is set (and zeroed at +0, where the
        // absolute offset below is taken anyway, as it is at −0).
        let moved = _mm_castsi128_ps(_mm_add_epi32(_mm_castps_si128(pm), _mm_sign_epi32(oi, _mm_castps_si128(pm))));
        let near = _mm_add_ps(pm, _mm_mul_ps(_mm_set1_ps(FLOAT_SCALE), nm));
        let abs = _mm_andnot_ps(_mm_set1_ps(-0.0), pm);
        Vec3A::from(_mm_blendv_ps(moved, near, _mm_cmplt_ps(abs, _mm_set1_ps(ORIGIN))))
    }
}

/// `p` nudged off its surface (unit geometric normal `n`, either orientation) towards the side
/// `dir` points into: where a ray leaving `p` along `dir` starts.
#[inline]
pub fn offset_toward(p: Vec3A, n: Vec3A, dir: Vec3A) -> Vec3A {
    offset_ray_origin(p, if dir.dot(n) >= 0.0 { n } else { -n })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_build_offsets_alike() {
        let mut next = crate::sampling::test_numbers(11);
        let mut coordinate = || {
            let magnitude = 10f32.powf(8.0 * next() - 5.0);
            let signed = if next() < 0.5 { -magnitude } else { magnitude };
            if next() < 0.05 { [0.0, -0.0, ORIGIN, -ORIGIN][(next() * 4.0) as usize] } else { signed }
        };
        for _ in 0..20_000 {
            let p = Vec3A::new(coordinate(), coordinate(), coordinate());
            let n = (Vec3A::new(coordinate(), coordinate(), coordinate())).normalize_or(Vec3A::Y);
            let (a, b) = (offset_ray_origin(p, n), offset_scalar(p, n));
            assert!(
                a.x.to_bits() == b.x.to_bits() && a.y.to_bits() == b.y.to_bits() && a.z.to_bits() == b.z.to_bits(),
                "{p} {n}: {a} against {b}"
            );
        }
    }

    #[test]
    fn offset_moves_to_the_normal_side_at_every_scale() {
        for scale in [1e-3f32, 1.0, 1e3, 1e5] {
            let p = Vec3A::new(0.3, -0.7, 0.5) * scale;
            let n = Vec3A::new(0.2, 0.9, -0.1).normalize();
            let q = offset_ray_origin(p, n);
            assert!((q - p).dot(n) > 0.0, "scale {scale}");
            assert!((q - p).length() < 1e-3 * scale.max(1.0), "scale {scale}");
            let q2 = offset_ray_origin(p, -n);
            assert!((q2 - p).dot(n) < 0.0);
        }
    }
}
