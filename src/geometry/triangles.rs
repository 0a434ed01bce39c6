//! A BLAS's triangles as planes of coordinates, and the ray–triangle test over the primitives
//! a CWBVH node's leaf children hold.
//!
//! Owns: the triangle storage of [`super::accel::Blas`] (BVH order) and Möller–Trumbore, one
//! triangle at a time ([`intersect`]) and eight at a time with AVX2. A node test reports the
//! primitives of every leaf child the ray meets as a group: consecutive slots from a base,
//! chosen by a 24-bit mask. Stored as nine planes (x, y, z of each vertex) the group's
//! triangles load eight to a register, and one pass tests them all. The wide test does the
//! scalar test's arithmetic, operation by operation in the same order (glam's dot: products,
//! then sums left to right; its cross: one product rounded, the other subtracted from it in
//! a fused multiply-add where the build has FMA, as x86-64-v3 has), and the group's hits
//! are then taken in the order obvhs's traversal visits them (highest slot first, a hit kept
//! only when nearer than the nearest so far), so every hit, distance and barycentric is the scalar loop's, bit for bit
//! (`wide_test_is_the_scalar_test`).

use glam::Vec3A;

use super::traverse::Group;

/// Nine coordinate planes (x0, y0, z0, x1, …, z2) in chunks of [`CHUNK`] slots: chunk `c`
/// holds plane `k` of slots `c·CHUNK + j`, `j < STORED`, at `(9c + k)·STORED + j`.
pub struct Triangles {
    planes: Vec<f32>,
    len: usize,
}

/// Slots a chunk owns.
const CHUNK: usize = 256;
/// Slots a chunk stores a plane: its own and copies of the next chunk's first 24 (zeros past
/// the last triangle), so that a group's 24 slots from any slot of the chunk lie in it. A
/// group's planes are then one pointer and constant offsets: a ray sets up no pointer per
/// plane, which the traversal loop kept on the stack.
const STORED: usize = CHUNK + 24;

/// Möller–Trumbore: (t, b1, b2) when the ray `o + t·d` meets triangle `v` with `t ∈ (tmin, tmax)`.
/// The test of builds without AVX2, and the reference the wide test is checked against.
#[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "avx2"))))]
#[inline(always)]
pub fn intersect(v: [Vec3A; 3], o: Vec3A, d: Vec3A, tmin: f32, tmax: f32) -> Option<(f32, f32, f32)> {
    let e1 = v[1] - v[0];
    let e2 = v[2] - v[0];
    let pvec = d.cross(e2);
    let det = e1.dot(pvec);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tvec = o - v[0];
    let b1 = tvec.dot(pvec) * inv;
    if !(0.0..=1.0).contains(&b1) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let b2 = d.dot(qvec) * inv;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return None;
    }
    let t = e2.dot(qvec) * inv;
    (t > tmin && t < tmax).then_some((t, b1, b2))
}

/// What a group test found nearest: (slot, t, b1, b2).
pub type GroupHit = (u32, f32, f32, f32);

impl Triangles {
    /// Stores `tris` in this order.
    pub fn new(tris: &[[Vec3A; 3]]) -> Self {
        let len = tris.len();
        let mut planes = vec![0.0f32; len.div_ceil(CHUNK) * 9 * STORED];
        for (c, chunk) in planes.chunks_exact_mut(9 * STORED).enumerate() {
            for (j, t) in tris.iter().skip(c * CHUNK).take(STORED).enumerate() {
                for (k, v) in t.iter().enumerate() {
                    for (a, x) in v.to_array().into_iter().enumerate() {
                        chunk[(3 * k + a) * STORED + j] = x;
                    }
                }
            }
        }
        Self { planes, len }
    }

    /// Where plane 0 of `slot` is stored (plane k: `k·STORED` further).
    #[inline(always)]
    fn at(slot: usize) -> usize {
        slot / CHUNK * 9 * STORED + slot % CHUNK
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.planes.capacity() * std::mem::size_of::<f32>()
    }

    /// The vertices of triangle `slot` (always inlined, as `Accel::closest_hit`).
    #[inline(always)]
    pub fn vertices(&self, slot: u32) -> [Vec3A; 3] {
        let i = Self::at(slot as usize);
        // One bounds check for the nine planes, not one each.
        let planes = &self.planes[i..=i + 8 * STORED];
        let c = |k: usize| planes[k * STORED];
        [Vec3A::new(c(0), c(1), c(2)), Vec3A::new(c(3), c(4), c(5)), Vec3A::new(c(6), c(7), c(8))]
    }

    /// The nearest hit closer than `tmax` among the slots of `group` that `accept(slot, b1,
    /// b2)` keeps, taken as obvhs's traversal takes a group: highest slot first, a hit
    /// replacing the one kept only when strictly nearer.
    #[inline(always)]
    pub fn closest_in_group(
        &self,
        o: Vec3A,
        d: Vec3A,
        tmax: f32,
        group: Group,
        accept: &impl Fn(u32, f32, f32) -> bool,
    ) -> Option<GroupHit> {
        let mut best = None;
        let mut tmax = tmax;
        self.for_each_hit(o, d, group, |slot, t, b1, b2| {
            if t < tmax && accept(slot, b1, b2) {
                best = Some((slot, t, b1, b2));
                tmax = t;
            }
            false
        });
        best
    }

    /// Whether any slot of the group (as in [`closest_in_group`](Self::closest_in_group))
    /// holds a hit closer than `tmax` that `accept` keeps.
    #[inline(always)]
    pub fn any_in_group(
        &self,
        o: Vec3A,
        d: Vec3A,
        tmax: f32,
        group: Group,
        accept: &impl Fn(u32, f32, f32) -> bool,
    ) -> bool {
        self.for_each_hit(o, d, group, |slot, t, b1, b2| t < tmax && accept(slot, b1, b2))
    }

    /// Calls `f(slot, t, b1, b2)` for every triangle of the group the ray meets at `t > 0`,
    /// highest slot first, until it returns true; returns whether one did.
    #[inline(always)]
    fn for_each_hit(&self, o: Vec3A, d: Vec3A, group: Group, mut f: impl FnMut(u32, f32, f32, f32) -> bool) -> bool {
        #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
        {
            debug_assert!((group.base as usize) < self.len);
            let planes = Self::at(group.base as usize);
            // Eight slots a register, the highest eight first, only those holding some.
            let mut chunks = (group.mask & 0xff != 0) as u32
                | ((group.mask & 0xff00 != 0) as u32) << 1
                | ((group.mask & 0xff_0000 != 0) as u32) << 2;
            while chunks != 0 {
                let chunk = 31 - chunks.leading_zeros();
                chunks &= !(1 << chunk);
                let lanes = (group.mask >> (8 * chunk)) & 0xff;
                let first = group.base + 8 * chunk;
                // SAFETY: AVX2 is compiled in (and checked at start-up, `crate::cpu`); the
                // group's base is a real triangle, whose chunk stores 24 slots from it.
                let hits = unsafe { self.test8(o, d, planes + 8 * chunk as usize) };
                for slot in (Group { base: first, mask: hits.mask & lanes }).slots() {
                    let l = (slot - first) as usize;
                    if f(slot, hits.t[l], hits.b1[l], hits.b2[l]) {
                        return true;
                    }
                }
            }
            false
        }
        #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
        {
            group.slots().any(|slot| {
                intersect(self.vertices(slot), o, d, 0.0, f32::INFINITY).is_some_and(|(t, b1, b2)| f(slot, t, b1, b2))
            })
        }
    }

    /// [`intersect`] (with `tmin` 0, `tmax` ∞) for the eight slots whose plane 0 is stored
    /// from `at`.
    ///
    /// # Safety
    /// The CPU must have AVX2, and `at` must be [`Self::at`] of a slot below `len`, plus at
    /// most 16.
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    #[inline(always)]
    unsafe fn test8(&self, o: Vec3A, d: Vec3A, at: usize) -> Hits8 {
        use std::arch::x86_64::*;
        debug_assert!(at % STORED + 8 <= STORED && at + 8 * STORED + 8 <= self.planes.len());
        // SAFETY: AVX2 by the caller's contract; each load reads planes[at + k·STORED ..+8],
        // inside plane k of the slot's chunk, which stores 24 slots from any of its own.
        unsafe {
            let load = |k: usize| _mm256_loadu_ps(self.planes.as_ptr().add(at + k * STORED));
            let (add, sub, mul) = (_mm256_add_ps, _mm256_sub_ps, _mm256_mul_ps);
            let splat = |v: Vec3A| [_mm256_set1_ps(v.x), _mm256_set1_ps(v.y), _mm256_set1_ps(v.z)];
            let v0 = [load(0), load(1), load(2)];
            let minus = |a: [__m256; 3], b: [__m256; 3]| [sub(a[0], b[0]), sub(a[1], b[1]), sub(a[2], b[2])];
            // glam's cross: `c − a·b` fused where the build has FMA, products rounded first.
            let neg_mul_sub = |a: __m256, b: __m256, c: __m256| {
                #[cfg(target_feature = "fma")]
                {
                    _mm256_fnmadd_ps(a, b, c)
                }
                #[cfg(not(target_feature = "fma"))]
                {
                    sub(c, mul(a, b))
                }
            };
            let cross = |a: [__m256; 3], b: [__m256; 3]| {
                [
                    neg_mul_sub(b[1], a[2], mul(a[1], b[2])),
                    neg_mul_sub(b[2], a[0], mul(a[2], b[0])),
                    neg_mul_sub(b[0], a[1], mul(a[0], b[1])),
                ]
            };
            let dot = |a: [__m256; 3], b: [__m256; 3]| add(add(mul(a[0], b[0]), mul(a[1], b[1])), mul(a[2], b[2]));
            let e1 = minus([load(3), load(4), load(5)], v0);
            let e2 = minus([load(6), load(7), load(8)], v0);
            let d = splat(d);
            let pvec = cross(d, e2);
            let det = dot(e1, pvec);
            let zero = _mm256_setzero_ps();
            let one = _mm256_set1_ps(1.0);
            let abs = _mm256_andnot_ps(_mm256_set1_ps(-0.0), det);
            let mut ok = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_NEQ_OQ>(det, zero),
                _mm256_cmp_ps::<_CMP_LT_OQ>(abs, _mm256_set1_ps(f32::INFINITY)),
            );
            let inv = _mm256_div_ps(one, det);
            let tvec = minus(splat(o), v0);
            let b1 = mul(dot(tvec, pvec), inv);
            ok = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_GE_OQ>(b1, zero));
            ok = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_LE_OQ>(b1, one));
            let qvec = cross(tvec, e1);
            let b2 = mul(dot(d, qvec), inv);
            // `b2 < 0 || b1 + b2 > 1` rejects: its negation keeps unordered lanes, as the scalar test does.
            ok = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_NLT_UQ>(b2, zero));
            ok = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_NGT_UQ>(add(b1, b2), one));
            let t = mul(dot(e2, qvec), inv);
            ok = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_GT_OQ>(t, zero));
            let mut hits = Hits8 { mask: _mm256_movemask_ps(ok) as u32, t: [0.0; 8], b1: [0.0; 8], b2: [0.0; 8] };
            _mm256_storeu_ps(hits.t.as_mut_ptr(), t);
            _mm256_storeu_ps(hits.b1.as_mut_ptr(), b1);
            _mm256_storeu_ps(hits.b2.as_mut_ptr(), b2);
            hits
        }
    }
}

/// Eight triangle tests: which lanes hit, and their distances and barycentrics.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
struct Hits8 {
    mask: u32,
    t: [f32; 8],
    b1: [f32; 8],
    b2: [f32; 8],
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::test_numbers as numbers;

    /// Slot by slot with the scalar test, as obvhs's traversal would: the reference.
    fn scalar_closest(tris: &[[Vec3A; 3]], o: Vec3A, d: Vec3A, tmax: f32, group: Group) -> Option<GroupHit> {
        let (mut best, mut tmax) = (None, tmax);
        for slot in group.slots() {
            if let Some((t, b1, b2)) = intersect(tris[slot as usize], o, d, 0.0, tmax) {
                best = Some((slot, t, b1, b2));
                tmax = t;
            }
        }
        best
    }

    #[test]
    fn wide_test_is_the_scalar_test() {
        let mut u = numbers(3);
        let mut p = || Vec3A::new(u(), u(), u()) * 2.0 - 1.0;
        // Small triangles near the origin, some degenerate (a repeated vertex, collinear);
        // three chunks, so that some groups start near a chunk's end.
        let tris: Vec<[Vec3A; 3]> = (0..2 * CHUNK + 61)
            .map(|i| {
                let c = p() * 0.5;
                let (a, b) = (c + p() * 0.6, c + p() * 0.6);
                match i % 13 {
                    0 => [c, c, b],
                    1 => [c, a, c + (a - c) * 2.0],
                    _ => [c, a, b],
                }
            })
            .collect();
        let store = Triangles::new(&tris);
        assert_eq!(store.len(), tris.len());
        for (i, t) in tris.iter().enumerate() {
            assert_eq!(store.vertices(i as u32), *t);
        }
        let mut u = numbers(9);
        let (mut hits, mut groups) = (0, 0);
        for _ in 0..20_000 {
            let o = Vec3A::new(u(), u(), u()) * 4.0 - 2.0;
            // Aimed into the cloud of triangles, so that most groups hold a hit.
            let mut d = (Vec3A::new(u(), u(), u()) - 0.5) * 0.8 - o;
            if u() < 0.1 {
                d.x = 0.0;
            }
            let tmax = if u() < 0.5 { f32::INFINITY } else { u() * 1.5 };
            // One group in four starts within 24 slots of a chunk's end.
            let base = if u() < 0.25 {
                (CHUNK - 24 + (u() * 24.0) as usize + CHUNK * (u() * 2.0) as usize) as u32
            } else {
                (u() * (tris.len() - 1) as f32) as u32
            };
            let width = (tris.len() as u32 - base).min(24);
            let mask = ((u() * (1u64 << 24) as f32) as u32 | 1) & ((1u32 << width) - 1).max(1);
            let group = Group { base, mask };
            let want = scalar_closest(&tris, o, d, tmax, group);
            let got = store.closest_in_group(o, d, tmax, group, &|_, _, _| true);
            assert_eq!(
                got.map(|h| (h.0, h.1.to_bits(), h.2.to_bits(), h.3.to_bits())),
                want.map(|h| (h.0, h.1.to_bits(), h.2.to_bits(), h.3.to_bits())),
                "o {o} d {d} base {base} mask {mask:#x}"
            );
            assert_eq!(store.any_in_group(o, d, tmax, group, &|_, _, _| true), want.is_some());
            hits += want.is_some() as u32;
            groups += 1;
        }
        assert!(hits > 3000 && groups - hits > 3000, "{hits} of {groups} groups hit");
    }

    #[test]
    fn refused_hits_let_farther_ones_through() {
        // Two parallel triangles across the z axis at z = 1 and z = 2; a ray up the axis.
        let (both, second) = (Group { base: 0, mask: 0b11 }, Group { base: 0, mask: 0b10 });
        let at = |z: f32| [Vec3A::new(-1.0, -1.0, z), Vec3A::new(1.0, -1.0, z), Vec3A::new(0.0, 1.0, z)];
        let store = Triangles::new(&[at(1.0), at(2.0)]);
        let (o, d) = (Vec3A::ZERO, Vec3A::Z);
        let near = store.closest_in_group(o, d, f32::INFINITY, both, &|_, _, _| true).unwrap();
        assert_eq!((near.0, near.1), (0, 1.0));
        let far = store.closest_in_group(o, d, f32::INFINITY, both, &|slot, _, _| slot != 0).unwrap();
        assert_eq!((far.0, far.1), (1, 2.0));
        assert!(store.closest_in_group(o, d, 1.5, both, &|slot, _, _| slot != 0).is_none());
        assert!(!store.any_in_group(o, d, 1.5, second, &|_, _, _| true));
        assert!(store.any_in_group(o, d, 2.5, second, &|_, _, _| true));
    }
}
