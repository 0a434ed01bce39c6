//! 24-byte quantised light bounds for tree nodes (pbrt-v4's `CompactLightBounds`, adapted).
//!
//! Every quantisation rounds outwards, so a decoded bound always contains the exact one:
//! the box is floored/ceiled on a 16-bit grid over the tree's box (one extra step each way
//! absorbs f32 round-off when decoding), the cone cosines are floored on a 15-bit grid
//! (decoded angles are never smaller), and the cone is widened by 2e-4 rad to cover the
//! octahedral axis' error (below 1.2e-4 rad with 16 bits per coordinate).

use crate::light::{BoundsView, LightBounds};
use crate::math::{Vec2, Vec3A, safe_acos};

/// Angle added to θo to absorb the axis quantisation error (chord error measured < 1.2e-4).
const AXIS_SLACK: f32 = 2e-4;

/// The grid boxes are quantised on.
#[derive(Clone, Copy, Debug)]
pub struct Quantizer {
    origin: Vec3A,
    step: Vec3A,
}

impl Quantizer {
    /// A grid covering `min..max`.
    pub fn new(min: Vec3A, max: Vec3A) -> Self {
        let ext = (max - min).max(Vec3A::splat(1e-6));
        Self { origin: min, step: ext / 65535.0 }
    }
}

/// Quantised bounds: 24 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct CompactBounds {
    phi: f32,
    axis: u32,
    /// cos θo (15 bits) | cos θe (15 bits) << 15 | two-sided << 30 | infinite << 31.
    cones: u32,
    qmin: [u16; 3],
    qmax: [u16; 3],
}

fn quantize_cos(c: f32) -> u32 {
    ((c.clamp(-1.0, 1.0) + 1.0) * 0.5 * 32767.0).floor() as u32
}

fn dequantize_cos(q: u32) -> f32 {
    (q as f32 / 32767.0) * 2.0 - 1.0
}

fn oct_encode(v: Vec3A) -> u32 {
    let l1 = v.x.abs() + v.y.abs() + v.z.abs();
    let mut p = Vec2::new(v.x, v.y) / l1;
    if v.z < 0.0 {
        p = Vec2::new((1.0 - p.y.abs()) * p.x.signum(), (1.0 - p.x.abs()) * p.y.signum());
    }
    let q = |x: f32| (((x.clamp(-1.0, 1.0) + 1.0) * 0.5 * 65535.0).round() as u32) & 0xffff;
    q(p.x) | (q(p.y) << 16)
}

fn oct_decode(e: u32) -> Vec3A {
    let d = |q: u32| (q as f32 / 65535.0) * 2.0 - 1.0;
    let mut p = Vec2::new(d(e & 0xffff), d(e >> 16));
    let z = 1.0 - p.x.abs() - p.y.abs();
    if z < 0.0 {
        p = Vec2::new((1.0 - p.y.abs()) * p.x.signum(), (1.0 - p.x.abs()) * p.y.signum());
    }
    Vec3A::new(p.x, p.y, z).normalize()
}

impl CompactBounds {
    /// Quantises `b` on `grid`, outwards.
    pub fn new(b: &LightBounds, grid: &Quantizer) -> Self {
        // Widen the normal cone for the axis error; near θo = 0 the 15-bit grid is coarser
        // than the slack, so the cone is at least one grid step wide (≈ 0.6°).
        let q_o = if b.cos_theta_o <= -1.0 {
            0
        } else {
            quantize_cos((safe_acos(b.cos_theta_o) + AXIS_SLACK).min(std::f32::consts::PI).cos()).min(32766)
        };
        let cones =
            q_o | (quantize_cos(b.cos_theta_e) << 15) | ((b.two_sided as u32) << 30) | ((b.infinite as u32) << 31);
        let (mut qmin, mut qmax) = ([0u16; 3], [0u16; 3]);
        if !b.infinite {
            for a in 0..3 {
                let lo = ((b.min[a] - grid.origin[a]) / grid.step[a]).floor() - 1.0;
                let hi = ((b.max[a] - grid.origin[a]) / grid.step[a]).ceil() + 1.0;
                qmin[a] = lo.clamp(0.0, 65535.0) as u16;
                qmax[a] = hi.clamp(0.0, 65535.0) as u16;
            }
        }
        Self { phi: b.phi, axis: oct_encode(b.w), cones, qmin, qmax }
    }

    /// The bounds importance is evaluated on.
    #[inline]
    pub fn decode(&self, grid: &Quantizer) -> BoundsView {
        let lo = Vec3A::new(self.qmin[0] as f32, self.qmin[1] as f32, self.qmin[2] as f32);
        let hi = Vec3A::new(self.qmax[0] as f32, self.qmax[1] as f32, self.qmax[2] as f32);
        let half = 0.5 * (hi - lo) * grid.step;
        BoundsView {
            center: grid.origin + 0.5 * (lo + hi) * grid.step,
            radius: half.length(),
            phi: self.phi,
            w: oct_decode(self.axis),
            cos_theta_o: dequantize_cos(self.cones & 0x7fff),
            cos_theta_e: dequantize_cos((self.cones >> 15) & 0x7fff),
            two_sided: self.cones & (1 << 30) != 0,
            infinite: self.cones & (1 << 31) != 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn octahedral_round_trip_is_accurate() {
        for i in 0..2000 {
            let t = i as f32 * 0.618;
            let v = Vec3A::new(t.sin() * (t * 0.37).cos(), (t * 1.3).cos(), t.cos() * (t * 0.71).sin()).normalize();
            let back = oct_decode(oct_encode(v));
            // Small angles from the chord: acos near 1 is too coarse in f32.
            assert!((v - back).length() < 1.2e-4, "{v} → {back}");
        }
    }

    #[test]
    fn decoded_bounds_contain_the_exact_ones() {
        let grid = Quantizer::new(Vec3A::new(-10.0, 0.0, -3.0), Vec3A::new(10.0, 5.0, 3.0));
        let b = LightBounds {
            min: Vec3A::new(-1.234_567, 2.0, 0.1),
            max: Vec3A::new(-1.2, 2.000_001, 0.3),
            phi: 3.5,
            w: Vec3A::new(0.3, -0.9, 0.1).normalize(),
            cos_theta_o: 0.97,
            cos_theta_e: 0.0,
            two_sided: true,
            infinite: false,
        };
        let c = CompactBounds::new(&b, &grid).decode(&grid);
        let exact = b.view();
        assert!(c.radius >= exact.radius);
        // Every corner of the exact box is inside the decoded sphere.
        for k in 0..8 {
            let corner = Vec3A::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            );
            assert!((corner - c.center).length() <= c.radius);
        }
        assert!(c.cos_theta_o <= b.cos_theta_o && c.cos_theta_e <= b.cos_theta_e);
        // The decoded cone contains the exact one despite the axis error.
        assert!(safe_acos(c.w.dot(b.w)) + safe_acos(b.cos_theta_o) <= safe_acos(c.cos_theta_o));
        assert!(c.two_sided && !c.infinite && c.phi == b.phi);
        assert_eq!(std::mem::size_of::<CompactBounds>(), 24);
    }
}
