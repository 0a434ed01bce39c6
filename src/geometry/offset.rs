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
    let of = n * INT_SCALE;
    let step = |x: f32, o: f32, nn: f32| {
        let oi = o as i32;
        let moved = f32::from_bits((x.to_bits() as i32).wrapping_add(if x < 0.0 { -oi } else { oi }) as u32);
        if x.abs() < ORIGIN { x + FLOAT_SCALE * nn } else { moved }
    };
    Vec3A::new(step(p.x, of.x, n.x), step(p.y, of.y, n.y), step(p.z, of.z, n.z))
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
