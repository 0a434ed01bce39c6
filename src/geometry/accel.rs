//! The ray-query acceleration structure: an obvhs compressed 8-wide BVH over all triangles.
//!
//! Owns: building the CWBVH (medium preset: PLOC + reinsertion; crates.md measured it as the
//! best build/trace trade-off here), the direct-layout triangle array it indexes, closest-hit
//! and occlusion queries. This is the only file that imports obvhs.
//!
//! The triangles are stored in BVH order ("direct layout"), so the slot obvhs hands to the
//! intersection closure is our triangle index; the caller reorders its per-triangle data with
//! the permutation [`Accel::build`] returns.

use std::time::{Duration, Instant};

use obvhs::{BvhBuildParams, cwbvh::CwBvh, cwbvh::builder::build_cwbvh_from_tris, ray::RayHit, triangle::Triangle};

use super::Ray;
use crate::math::Vec3A;

/// Sizes and timings of a built [`Accel`].
#[derive(Clone, Copy, Debug, Default)]
pub struct AccelStats {
    /// Wall time of the build.
    pub build_time: Duration,
    /// Number of BVH nodes.
    pub nodes: usize,
    /// Bytes of nodes, triangles and index tables.
    pub memory_bytes: usize,
}

/// The raw result of a closest-hit query.
#[derive(Clone, Copy, Debug)]
pub struct RawHit {
    /// Triangle index (BVH order).
    pub tri: u32,
    /// Ray parameter.
    pub t: f32,
    /// Barycentric weight of vertex 1.
    pub b1: f32,
    /// Barycentric weight of vertex 2.
    pub b2: f32,
}

/// CWBVH plus its triangles in BVH order.
pub struct Accel {
    bvh: Option<CwBvh>,
    tris: Vec<Triangle>,
    stats: AccelStats,
}

/// Möller-Trumbore: (t, b1, b2) when the ray meets the triangle within `[tmin, tmax]`.
#[inline(always)]
fn intersect(tri: &Triangle, o: Vec3A, d: Vec3A, tmin: f32, tmax: f32) -> Option<(f32, f32, f32)> {
    let e1 = tri.v1 - tri.v0;
    let e2 = tri.v2 - tri.v0;
    let pvec = d.cross(e2);
    let det = e1.dot(pvec);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tvec = o - tri.v0;
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

impl Accel {
    /// Builds the BVH over `tris` (the thread count is that of the current rayon pool).
    /// Returns the structure and the permutation `order[new] = old`.
    pub fn build(tris: Vec<[Vec3A; 3]>) -> (Self, Vec<u32>) {
        let start = Instant::now();
        let tris: Vec<Triangle> = tris.into_iter().map(|[v0, v1, v2]| Triangle { v0, v1, v2 }).collect();
        if tris.is_empty() {
            let stats = AccelStats { build_time: start.elapsed(), ..Default::default() };
            return (Self { bvh: None, tris, stats }, Vec::new());
        }
        let bvh = build_cwbvh_from_tris(&tris, BvhBuildParams::medium_build(), &mut Duration::default());
        let order = bvh.primitive_indices.clone();
        let sorted: Vec<Triangle> = order.iter().map(|&i| tris[i as usize]).collect();
        let memory_bytes = bvh.nodes.len() * std::mem::size_of_val(&bvh.nodes[0])
            + bvh.primitive_indices.len() * 4
            + sorted.len() * std::mem::size_of::<Triangle>();
        let stats = AccelStats { build_time: start.elapsed(), nodes: bvh.nodes.len(), memory_bytes };
        (Self { bvh: Some(bvh), tris: sorted, stats }, order)
    }

    /// Build statistics.
    pub fn stats(&self) -> AccelStats {
        self.stats
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// True when there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Vertices of triangle `tri` (BVH order).
    #[inline]
    pub fn vertices(&self, tri: u32) -> [Vec3A; 3] {
        let t = &self.tris[tri as usize];
        [t.v0, t.v1, t.v2]
    }

    /// Closest intersection with `t ∈ (0, t_max)`.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<RawHit> {
        let bvh = self.bvh.as_ref()?;
        let oray = obvhs::ray::Ray::new(ray.origin, ray.dir, 0.0, t_max);
        let mut rh = RayHit::none();
        let mut bary = (0.0f32, 0.0f32);
        let hit = bvh.ray_traverse(oray, &mut rh, |r, slot| {
            match intersect(&self.tris[slot], r.origin, r.direction, 0.0, r.tmax) {
                Some((t, b1, b2)) => {
                    bary = (b1, b2);
                    t
                }
                None => f32::INFINITY,
            }
        });
        hit.then_some(RawHit { tri: rh.primitive_id, t: rh.t, b1: bary.0, b2: bary.1 })
    }

    /// True when something lies on the segment `origin + t·dir`, `t ∈ (0, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let Some(bvh) = self.bvh.as_ref() else { return false };
        let oray = obvhs::ray::Ray::new(ray.origin, ray.dir, 0.0, t_max);
        !bvh.ray_traverse_miss(oray, |r, slot| {
            intersect(&self.tris[slot], r.origin, r.direction, 0.0, r.tmax).map_or(f32::INFINITY, |h| h.0)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(z: f32) -> Vec<[Vec3A; 3]> {
        let a = Vec3A::new(-1.0, -1.0, z);
        let b = Vec3A::new(1.0, -1.0, z);
        let c = Vec3A::new(1.0, 1.0, z);
        let d = Vec3A::new(-1.0, 1.0, z);
        vec![[a, b, c], [a, c, d]]
    }

    #[test]
    fn closest_hit_and_occlusion() {
        let mut tris = quad(-1.0);
        tris.extend(quad(-3.0));
        let (accel, order) = Accel::build(tris.clone());
        assert_eq!(order.len(), 4);
        let ray = Ray::new(Vec3A::new(0.2, 0.3, 0.0), Vec3A::new(0.0, 0.0, -1.0));
        let h = accel.closest_hit(&ray, f32::INFINITY).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
        let [v0, v1, v2] = accel.vertices(h.tri);
        let p = v0 * (1.0 - h.b1 - h.b2) + v1 * h.b1 + v2 * h.b2;
        assert!((p - Vec3A::new(0.2, 0.3, -1.0)).length() < 1e-5);
        assert!(tris[order[h.tri as usize] as usize][0].z == -1.0);
        assert!(accel.occluded(&ray, 2.0));
        assert!(!accel.occluded(&ray, 0.5));
        assert!(accel.closest_hit(&Ray::new(Vec3A::ZERO, Vec3A::Z), f32::INFINITY).is_none());
        // Closest hit honours t_max.
        assert!(accel.closest_hit(&ray, 0.9).is_none());
    }

    #[test]
    fn empty_scene_never_hits() {
        let (accel, _) = Accel::build(Vec::new());
        let ray = Ray::new(Vec3A::ZERO, Vec3A::X);
        assert!(accel.closest_hit(&ray, f32::INFINITY).is_none());
        assert!(!accel.occluded(&ray, f32::INFINITY));
    }
}
