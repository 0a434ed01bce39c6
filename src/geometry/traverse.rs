//! Closest-hit and occlusion traversal of an obvhs CWBVH, with an eight-wide AVX2 node test.
//!
//! Owns: the ray–node test and the two traversal loops [`closest`] and [`any`] that
//! [`super::accel`] runs over its BLASes and TLAS. The loops are obvhs's own (its exported
//! `traverse!` macro, as `CwBvh::ray_traverse` and `ray_traverse_miss` use it); only the node
//! test and the traversal state (whose stack is not zero-filled for every ray) differ. obvhs
//! tests a node's eight child boxes as two SSE halves, converting each quantised plane byte
//! to a float one at a time; with AVX2 (the x86-64-v3 build, `.cargo/config.toml`)
//! [`node_hits`] widens each axis's eight plane bytes to floats in two instructions, tests
//! all eight boxes at once, and places the hits with one vector shift. It does the same
//! arithmetic in the same order as obvhs's test (multiply, then add; the same min/max
//! operand order), so it visits the same nodes and every image is bit-identical to one
//! traced with obvhs's traversal (`node_test_matches_obvhs`). Builds without AVX2 use
//! obvhs's test.

use std::mem::MaybeUninit;

use glam::UVec2;
use obvhs::cwbvh::{CwBvh, node::CwBvhNode};
use obvhs::faststack::FastStack;
use obvhs::ray::Ray;

/// The nearest box distance obvhs's node test accepts (its `node::EPSILON`, which it does not
/// export); the same value keeps the two tests identical.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
const BOX_T_MIN: f32 = 0.0001;

/// The child hit mask of `node` for `ray` in obvhs's layout: bits 24–31 the internal children
/// hit (by traversal priority), bits 0–23 the primitives of the leaf children hit.
#[inline(always)]
pub fn node_hits(node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    {
        // SAFETY: compiled only where AVX2 is enabled (and checked at start-up, `crate::cpu`).
        unsafe { node_hits_avx2(node, ray, oct_inv4) }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    {
        node.intersect_ray(ray, oct_inv4)
    }
}

/// [`node_hits`] with AVX2: the eight children's slab tests in one pass.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
unsafe fn node_hits_avx2(node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
    use glam::Vec3A;
    use std::arch::x86_64::*;

    let scale = node.compute_extent() * ray.inv_direction;
    let offset = (Vec3A::from(node.p) - ray.origin) * ray.inv_direction;
    // Along a negative direction the max plane is met first.
    fn near_far<'a>(min: &'a [u8; 8], max: &'a [u8; 8], negative: bool) -> (&'a [u8; 8], &'a [u8; 8]) {
        if negative { (max, min) } else { (min, max) }
    }
    let (near_x, far_x) = near_far(&node.child_min_x, &node.child_max_x, ray.direction.x < 0.0);
    let (near_y, far_y) = near_far(&node.child_min_y, &node.child_max_y, ray.direction.y < 0.0);
    let (near_z, far_z) = near_far(&node.child_min_z, &node.child_max_z, ray.direction.z < 0.0);
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    // SAFETY: AVX2 is available (the caller's contract); every load reads exactly the 8 bytes
    // of a `[u8; 8]` or a `u64`.
    unsafe {
        let widen = |q: u64| _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(q as i64));
        let planes = |q: &[u8; 8]| _mm256_cvtepi32_ps(widen(u64::from_le_bytes(*q)));
        let t = |q: &[u8; 8], scale: f32, offset: f32| {
            _mm256_add_ps(_mm256_mul_ps(planes(q), _mm256_set1_ps(scale)), _mm256_set1_ps(offset))
        };
        let t_near = _mm256_max_ps(
            t(near_x, scale.x, offset.x),
            _mm256_max_ps(t(near_y, scale.y, offset.y), t(near_z, scale.z, offset.z)),
        );
        let t_far = _mm256_min_ps(
            t(far_x, scale.x, offset.x),
            _mm256_min_ps(t(far_y, scale.y, offset.y), t(far_z, scale.z, offset.z)),
        );
        let t_near = _mm256_max_ps(t_near, _mm256_set1_ps(BOX_T_MIN));
        let t_far = _mm256_min_ps(t_far, _mm256_set1_ps(ray.tmax));
        let hit = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far));
        // Each hit child contributes its bits shifted to its place; OR the eight lanes together.
        let placed = _mm256_and_si256(_mm256_sllv_epi32(widen(child_bits8), widen(bit_index8)), hit);
        let four = _mm_or_si128(_mm256_castsi256_si128(placed), _mm256_extracti128_si256::<1>(placed));
        let two = _mm_or_si128(four, _mm_unpackhi_epi64(four, four));
        let one = _mm_or_si128(two, _mm_shuffle_epi32::<0b01>(two));
        _mm_cvtsi128_si32(one) as u32
    }
}

/// The primitives a node test found, as a group: slots `base + i` (indices into
/// `bvh.primitive_indices`) for the bits `i` of `mask`. obvhs hands them to its closure one at
/// a time; taking the whole group at once lets a test cover several at a time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Group {
    /// The slot of bit 0.
    pub base: u32,
    /// Which slots from `base` (24 bits).
    pub mask: u32,
}

impl Group {
    /// The group's slots, highest first: the order in which obvhs's traversal visits them.
    #[inline(always)]
    pub fn slots(self) -> impl Iterator<Item = u32> {
        let (base, mut left) = (self.base, self.mask);
        std::iter::from_fn(move || {
            (left != 0).then(|| {
                let bit = 31 - left.leading_zeros();
                left &= !(1 << bit);
                base + bit
            })
        })
    }
}

/// Takes the rest of the traversal state's current primitive group (the one obvhs is about
/// to hand over included) as a [`Group`].
macro_rules! take_group {
    ($state:expr) => {{
        let mask = $state.primitive_group.y | (1 << ($state.primitive_id - $state.primitive_group.x));
        $state.primitive_group.y = 0;
        Group { base: $state.primitive_group.x, mask }
    }};
}

/// Entries of a traversal stack: obvhs's (a CWBVH deeper than this fails its validation).
const STACK: usize = 32;

/// obvhs's traversal state (`Traversal`, the fields its `traverse!` macro reads) with a stack
/// that is not zero-filled: `CwBvh::new_traversal` writes all 256 bytes of its stack for
/// every ray (and every instance a ray enters), which the traversal only reads back after
/// pushing.
struct State {
    stack: Stack,
    current_group: UVec2,
    primitive_group: UVec2,
    oct_inv4: u32,
    primitive_id: u32,
    hitmask: u32,
}

impl State {
    /// The state at the start of a traversal of `bvh` in `direction`'s order.
    #[inline(always)]
    fn new(bvh: &CwBvh, direction: glam::Vec3A) -> Self {
        // Its stack is dead here, and its zero-filling with it.
        let start = bvh.new_traversal(direction);
        Self {
            stack: Stack::new(),
            current_group: start.current_group,
            primitive_group: start.primitive_group,
            oct_inv4: start.oct_inv4,
            primitive_id: 0,
            hitmask: 0,
        }
    }
}

/// A stack of node groups whose entries are written only when pushed. Entry 0 is written at
/// the start, so every entry a pop can read (the one below the top, or entry 0 when empty)
/// holds a value; like obvhs's stack, a push onto a full one overwrites its top.
struct Stack {
    data: [MaybeUninit<UVec2>; STACK],
    len: usize,
}

impl Stack {
    #[inline(always)]
    fn new() -> Self {
        let mut data = [const { MaybeUninit::uninit() }; STACK];
        data[0] = MaybeUninit::new(UVec2::ZERO);
        Self { data, len: 0 }
    }
}

impl FastStack<UVec2> for Stack {
    #[inline(always)]
    fn push(&mut self, v: UVec2) {
        self.data[self.len] = MaybeUninit::new(v);
        self.len = (self.len + 1).min(STACK - 1);
    }

    #[inline(always)]
    fn pop_fast(&mut self) -> UVec2 {
        self.len = self.len.saturating_sub(1);
        // SAFETY: entries below every length the stack has had, and entry 0, were written.
        unsafe { self.data[self.len].assume_init() }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<UVec2> {
        (self.len > 0).then(|| self.pop_fast())
    }

    #[inline(always)]
    fn len(&self) -> usize {
        self.len
    }

    #[inline(always)]
    fn is_empty(&self) -> bool {
        self.len == 0
    }

    #[inline(always)]
    fn clear(&mut self) {
        self.len = 0;
    }
}

/// The closest primitive along `ray`: `test(ray, group)` tests a [`Group`] of primitives
/// against `ray`, whose `tmax` has shrunk to the closest hit so far, and returns the slot and
/// distance of its nearest hit closer than that, the highest slot winning a tie (as one
/// primitive at a time in [`Group::slots`] order would find). Returns the slot
/// and distance of the closest hit.
#[inline(always)]
pub fn closest(bvh: &CwBvh, ray: Ray, mut test: impl FnMut(&Ray, Group) -> Option<(u32, f32)>) -> Option<(u32, f32)> {
    let mut ray = ray;
    let mut best = None;
    let mut state = State::new(bvh, ray.direction);
    let mut node;
    obvhs::traverse!(bvh, node, state, node_hits(node, &ray, state.oct_inv4), {
        if let Some((slot, t)) = test(&ray, take_group!(state)) {
            best = Some((slot, t));
            ray.tmax = t;
        }
    });
    best
}

/// True when `test(ray, group)` (as in [`closest`], `ray` unchanged) finds a primitive of some
/// group closer than `ray.tmax`; stops at the first.
#[inline(always)]
pub fn any(bvh: &CwBvh, ray: Ray, mut test: impl FnMut(&Ray, Group) -> bool) -> bool {
    let mut state = State::new(bvh, ray.direction);
    let mut node;
    let mut found = false;
    'search: {
        obvhs::traverse!(bvh, node, state, node_hits(node, &ray, state.oct_inv4), {
            if test(&ray, take_group!(state)) {
                found = true;
                break 'search;
            }
        });
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::test_numbers as numbers;
    use glam::Vec3A;
    use obvhs::{BvhBuildParams, cwbvh::builder::build_cwbvh_from_tris, triangle::Triangle};
    use std::time::Duration;

    #[test]
    fn the_stack_pops_what_was_pushed_and_overflows_as_obvhs_does() {
        let mut s = Stack::new();
        assert!(s.is_empty() && s.pop().is_none());
        // Popped empty, as obvhs's stack: its first entry (written at the start).
        assert_eq!(s.pop_fast(), UVec2::ZERO);
        for i in 0..40 {
            s.push(UVec2::new(i, 0));
        }
        // Full at 31: the pushes past it overwrote the top.
        assert_eq!(s.len(), STACK - 1);
        assert_eq!(s.pop_fast(), UVec2::new(30, 0));
        assert_eq!(s.pop(), Some(UVec2::new(29, 0)));
        s.clear();
        assert!(s.is_empty());
    }

    fn soup(n: usize) -> Vec<Triangle> {
        let mut u = numbers(7);
        let mut p = || Vec3A::new(u(), u(), u()) * 2.0 - 1.0;
        (0..n)
            .map(|_| {
                let c = p();
                Triangle { v0: c, v1: c + p() * 0.1, v2: c + p() * 0.1 }
            })
            .collect()
    }

    #[test]
    fn node_test_matches_obvhs() {
        let tris = soup(3000);
        let bvh = build_cwbvh_from_tris(&tris, BvhBuildParams::medium_build(), &mut Duration::default());
        let mut u = numbers(11);
        let mut tested = 0;
        for _ in 0..2000 {
            // Axis-parallel and zero components too: their inverse directions are ±1/ε.
            let mut d = Vec3A::new(u(), u(), u()) * 2.0 - 1.0;
            if u() < 0.2 {
                d.y = 0.0;
            }
            let o = Vec3A::new(u(), u(), u()) * 3.0 - 1.5;
            let ray = Ray::new(o, d + Vec3A::ZERO, 0.0, if u() < 0.5 { f32::INFINITY } else { u() * 2.0 });
            let oct_inv4 = bvh.new_traversal(ray.direction).oct_inv4;
            for node in &bvh.nodes {
                assert_eq!(node_hits(node, &ray, oct_inv4), node.intersect_ray(&ray, oct_inv4));
                tested += 1;
            }
        }
        assert!(tested > 100_000);
    }

    #[test]
    fn traversals_find_what_obvhs_finds() {
        let tris = soup(3000);
        let bvh = build_cwbvh_from_tris(&tris, BvhBuildParams::medium_build(), &mut Duration::default());
        let test = |r: &Ray, slot: usize| tris[bvh.primitive_indices[slot] as usize].intersect(r);
        // One primitive at a time, as obvhs's closures see them.
        let nearest = |r: &Ray, group: Group| {
            let mut best: Option<(u32, f32)> = None;
            for slot in group.slots() {
                let t = test(r, slot as usize);
                if t < best.map_or(r.tmax, |b| b.1) {
                    best = Some((slot, t));
                }
            }
            best
        };
        let blocked_by = |r: &Ray, group: Group| group.slots().any(|slot| test(r, slot as usize) < r.tmax);
        let mut u = numbers(5);
        let (mut hits, mut blocked) = (0, 0);
        for _ in 0..5000 {
            let d = Vec3A::new(u(), u(), u()) * 2.0 - 1.0;
            let o = Vec3A::new(u(), u(), u()) * 3.0 - 1.5;
            let ray = Ray::new(o, d, 0.0, u() * 3.0);
            let mut rh = obvhs::ray::RayHit::none();
            let theirs = bvh.ray_traverse(ray, &mut rh, test).then_some((rh.primitive_id, rh.t));
            assert_eq!(closest(&bvh, ray, nearest), theirs);
            assert_eq!(any(&bvh, ray, blocked_by), !bvh.ray_traverse_miss(ray, test));
            hits += theirs.is_some() as u32;
            blocked += any(&bvh, ray, blocked_by) as u32;
        }
        assert!(hits > 500 && blocked > 500, "{hits} hits, {blocked} blocked");
    }
}
