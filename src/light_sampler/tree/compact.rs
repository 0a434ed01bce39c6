//! The 256-byte tree node: eight children's bounds, quantised, in structure-of-arrays form so
//! that one decode feeds one 8-lane (AVX) importance evaluation of all eight.
//!
//! Every quantisation rounds outwards, so a decoded bound always contains the exact one:
//! - boxes on a 16-bit grid over the tree's box, floored/ceiled plus one extra step each way
//!   (absorbs f32 round-off when decoding); only the sphere around the box is used;
//! - cos θo and cos θe floored and sin θo ceiled on a 15-bit grid (decoded angles are never
//!   smaller), cos θe one step lower still, so that the 3e-5 error of a 16-bit cosine cannot
//!   turn a grazing-but-positive direction into a zero;
//! - the axis as three 16-bit components, with θo widened by [`AXIS_SLACK`] to cover its
//!   error (below 5e-5 rad).
//!
//! Flags ride in spare encodings: a negative φ marks a two-sided cluster, and cos θe =
//! `i16::MIN` (below −1, never a real cosine) a directional one.

use super::{NONE, WIDTH};
use crate::light::{BoundsPacket, Lanes, LightBounds};
use crate::math::{Vec3A, safe_acos};
use wide::CmpLt;

/// Angle added to θo to absorb the axis quantisation error.
const AXIS_SLACK: f32 = 2e-4;
/// 16-bit signed-normalised scale.
const SNORM: f32 = 32767.0;
/// cos θe of a directional lane.
const INFINITE_MARK: i16 = i16::MIN;

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

/// One 8-wide node (256 bytes, four cache lines).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node {
    qlo: [[u16; WIDTH]; 3],
    qhi: [[u16; WIDTH]; 3],
    phi: [f32; WIDTH],
    w: [[i16; WIDTH]; 3],
    cos_o: [i16; WIDTH],
    sin_o: [i16; WIDTH],
    cos_e: [i16; WIDTH],
    /// Child references: a node index, `LEAF | light`, or `NONE`.
    pub children: [u32; WIDTH],
}

fn floor_snorm(x: f32) -> i16 {
    (x.clamp(-1.0, 1.0) * SNORM).floor() as i16
}

fn ceil_snorm(x: f32) -> i16 {
    (x.clamp(-1.0, 1.0) * SNORM).ceil() as i16
}

fn round_snorm(x: f32) -> i16 {
    (x.clamp(-1.0, 1.0) * SNORM).round() as i16
}

/// Eight u16 lanes as floats (one load, a zero-extending widen and a convert with AVX2).
#[inline(always)]
fn lanes_u16(q: &[u16; WIDTH]) -> Lanes {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    // SAFETY: the build enables AVX2 (checked by `cfg`); the load reads exactly the 16 bytes of `q`.
    unsafe {
        use std::arch::x86_64::{__m128i, _mm_loadu_si128, _mm256_cvtepi32_ps, _mm256_cvtepu16_epi32};
        let v = _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(_mm_loadu_si128(q.as_ptr().cast::<__m128i>())));
        std::mem::transmute::<std::arch::x86_64::__m256, Lanes>(v)
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    Lanes::new(q.map(|x| x as f32))
}

/// Eight signed-normalised i16 lanes as floats in [−1, 1] (a sign-extending widen with AVX2).
#[inline(always)]
fn lanes_i16(q: &[i16; WIDTH]) -> Lanes {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    // SAFETY: as in `lanes_u16`.
    let v = unsafe {
        use std::arch::x86_64::{__m128i, _mm_loadu_si128, _mm256_cvtepi16_epi32, _mm256_cvtepi32_ps};
        let v = _mm256_cvtepi32_ps(_mm256_cvtepi16_epi32(_mm_loadu_si128(q.as_ptr().cast::<__m128i>())));
        std::mem::transmute::<std::arch::x86_64::__m256, Lanes>(v)
    };
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    let v = Lanes::new(q.map(|x| x as f32));
    v * (1.0 / SNORM)
}

impl Node {
    /// A node with no children.
    pub fn empty() -> Self {
        Self {
            qlo: [[0; WIDTH]; 3],
            qhi: [[0; WIDTH]; 3],
            phi: [0.0; WIDTH],
            w: [[0; WIDTH]; 3],
            cos_o: [SNORM as i16; WIDTH],
            sin_o: [0; WIDTH],
            cos_e: [SNORM as i16; WIDTH],
            children: [NONE; WIDTH],
        }
    }

    /// Stores child `k`: its reference and its bounds, quantised outwards on `grid`.
    pub fn set(&mut self, k: usize, reference: u32, b: &LightBounds, grid: &Quantizer) {
        self.children[k] = reference;
        self.phi[k] = if b.two_sided { -b.phi } else { b.phi };
        for a in 0..3 {
            self.w[a][k] = round_snorm(b.w[a]);
            if !b.infinite {
                let lo = ((b.min[a] - grid.origin[a]) / grid.step[a]).floor() - 1.0;
                let hi = ((b.max[a] - grid.origin[a]) / grid.step[a]).ceil() + 1.0;
                self.qlo[a][k] = lo.clamp(0.0, 65535.0) as u16;
                self.qhi[a][k] = hi.clamp(0.0, 65535.0) as u16;
            }
        }
        let theta_o = if b.cos_theta_o <= -1.0 { std::f32::consts::PI } else { safe_acos(b.cos_theta_o) + AXIS_SLACK };
        let (sin_o, cos_o) = theta_o.min(std::f32::consts::PI).sin_cos();
        self.cos_o[k] = floor_snorm(cos_o);
        self.sin_o[k] = ceil_snorm(sin_o.max(0.0));
        self.cos_e[k] =
            if b.infinite { INFINITE_MARK } else { floor_snorm(b.cos_theta_e).saturating_sub(1).max(-(SNORM as i16)) };
    }

    /// The children's bounds, decoded for evaluation.
    #[inline]
    pub fn decode(&self, grid: &Quantizer) -> BoundsPacket {
        let axis = |a: usize| {
            let (lo, hi) = (lanes_u16(&self.qlo[a]), lanes_u16(&self.qhi[a]));
            let s = 0.5 * grid.step[a];
            (Lanes::splat(grid.origin[a]) + (lo + hi) * s, (hi - lo) * s)
        };
        let ((cx, hx), (cy, hy), (cz, hz)) = (axis(0), axis(1), axis(2));
        let phi = Lanes::new(self.phi);
        let cos_e = lanes_i16(&self.cos_e);

        BoundsPacket {
            cx,
            cy,
            cz,
            hx,
            hy,
            hz,
            r2: hx * hx + hy * hy + hz * hz,
            phi: phi.abs(),
            wx: lanes_i16(&self.w[0]),
            wy: lanes_i16(&self.w[1]),
            wz: lanes_i16(&self.w[2]),
            cos_o: lanes_i16(&self.cos_o),
            sin_o: lanes_i16(&self.sin_o),
            cos_e,
            two_sided: phi.cmp_lt(Lanes::ZERO),
            // The mark decodes below −1, where no real cosine lies.
            infinite: cos_e.cmp_lt(Lanes::splat(-1.0)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::BoundsPacket;

    #[test]
    fn node_is_four_cache_lines() {
        assert_eq!(std::mem::size_of::<Node>(), 256);
    }

    #[test]
    fn decoded_importance_is_zero_only_where_the_exact_one_is() {
        let grid = Quantizer::new(Vec3A::new(-10.0, 0.0, -3.0), Vec3A::new(10.0, 5.0, 3.0));
        let mut worst = f32::MAX;
        for i in 0..500 {
            let t = i as f32 * 0.618;
            let w = Vec3A::new(t.sin(), (1.3 * t).cos(), (0.7 * t).sin()).normalize();
            let min = Vec3A::new(-1.234 + t.sin(), 2.0, 0.1 * t.cos());
            let b = LightBounds {
                min,
                max: min + Vec3A::new(0.01 + 0.1 * (t * 3.0).sin().abs(), 0.0, 0.2),
                phi: 3.5,
                w,
                cos_theta_o: [1.0, 0.97, 0.3, -1.0][i % 4],
                cos_theta_e: [0.0, 0.5][i % 2],
                two_sided: i % 3 == 0,
                infinite: false,
            };
            let mut node = Node::empty();
            node.set(0, 0, &b, &grid);
            let q = node.decode(&grid);
            let exact = BoundsPacket::new(&[b]);
            let lane0 = |v: Lanes| v.to_array()[0];
            assert!(lane0(q.r2) >= lane0(exact.r2));
            assert!((lane0(q.two_sided) != 0.0) == b.two_sided && lane0(q.infinite) == 0.0);
            let mut pairs = Vec::new();
            for j in 0..50 {
                let s = j as f32 * 1.7;
                let p = Vec3A::new(3.0 * s.sin(), 2.0 + 2.0 * (0.3 * s).cos(), 2.0 * (0.9 * s).sin());
                let n = Vec3A::new((0.4 * s).cos(), s.sin(), 0.2).normalize();
                let (a, e) = (lane0(q.importance(p, n)), lane0(exact.importance(p, n)));
                // The zero test is what must be conservative; the value moves a little with
                // the quantised centre (importance uses the centre distance, not the nearest
                // point, so a larger enclosing sphere is not always more important).
                assert!(e == 0.0 || a > 0.0, "decoded 0, exact {e}");
                pairs.push((a, e));
            }
            // Away from grazing directions (where the 0.45° minimum cone matters), the values
            // agree closely.
            let top = pairs.iter().fold(0.0f32, |m, p| m.max(p.1));
            for (a, e) in pairs.into_iter().filter(|p| p.1 > 0.05 * top) {
                worst = worst.min(a.min(e) / a.max(e));
            }
        }
        // Not loose either: the decoded importance stays within a few percent.
        assert!(worst > 0.95, "{worst}");
    }

    #[test]
    fn directional_lanes_round_trip() {
        let grid = Quantizer::new(Vec3A::ZERO, Vec3A::ONE);
        let b = LightBounds {
            min: Vec3A::ZERO,
            max: Vec3A::ZERO,
            phi: 2.0,
            w: Vec3A::new(0.0, 1.0, 0.0),
            cos_theta_o: 1.0,
            cos_theta_e: 0.0,
            two_sided: false,
            infinite: true,
        };
        let mut node = Node::empty();
        node.set(2, 7, &b, &grid);
        let q = node.decode(&grid);
        let infinite = q.infinite.to_array();
        assert!(infinite[2] != 0.0 && infinite[0] == 0.0);
        let imp = q.importance(Vec3A::ZERO, Vec3A::Y).to_array();
        assert!((imp[2] - 2.0).abs() < 1e-3 && imp[0] == 0.0);
        assert_eq!(q.importance(Vec3A::ZERO, -Vec3A::Y).to_array()[2], 0.0, "sun below the horizon");
    }
}
