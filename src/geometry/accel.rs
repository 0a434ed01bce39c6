//! The ray-query acceleration structures: obvhs compressed 8-wide BVHs, two levels when
//! meshes are instanced.
//!
//! Owns: one [`Blas`] per geometry block (the flattened world-space triangles, and each mesh
//! that several instances share, in object space), [`Instance`] placements, a top-level
//! CWBVH over the instances when there is more than one, closest-hit and occlusion queries
//! with an acceptance test (alpha cut-outs). Medium build preset: PLOC + reinsertion, the
//! best build/trace trade-off measured here (docs/conventions.md). This file and the traversal
//! it runs (`traverse.rs`) are the only ones that import obvhs.
//!
//! A BLAS stores its triangles in BVH order ("direct layout", `triangles.rs`), so the slots
//! of the group of primitives a node test hands over are triangle indices; callers reorder
//! per-triangle data with the permutation [`Blas::build`] returns. Instanced rays are moved into object space without
//! normalising the direction, so hit distances `t` stay comparable across instances.

use std::time::{Duration, Instant};

use obvhs::{
    Boundable, BvhBuildParams,
    aabb::Aabb,
    cwbvh::CwBvh,
    cwbvh::builder::{build_cwbvh, build_cwbvh_from_tris},
    triangle::Triangle,
};

use super::triangles::Triangles;
use super::{RawHit, Ray, traverse};
use crate::math::{Mat3, Mat4, Vec3A};

/// An obvhs ray. Direction components of −0.0 are turned into +0.0: obvhs takes the ray's
/// octant from `d < 0` (false for −0.0) but its inverse from the sign bit (−∞-like for
/// −0.0), and with the two disagreeing the CWBVH node test misses every box (found by
/// `negative_zero_directions_still_hit`).
#[inline(always)]
fn obvhs_ray(o: Vec3A, d: Vec3A, t_max: f32) -> obvhs::ray::Ray {
    obvhs::ray::Ray::new(o, d + Vec3A::ZERO, 0.0, t_max)
}

/// Which ray tracer answers the scene's ray queries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TracerKind {
    /// Intel Embree 3 where this build has it (`cfg(embree)`), else the built-in one.
    Best,
    /// myriad's own: obvhs's compressed 8-wide BVH with an AVX2 node and leaf test.
    Builtin,
    /// Intel Embree 3 (the system library).
    Embree,
}

/// Stored triangles from which `best` traces with Embree. Measured (benches/scenes.rs `rays`
/// and `trace`, whole renders): on real scenes of 2 k to 21 k triangles the two tracers are
/// within ±12 % of each other either way (the built-in one's closest hits are faster there,
/// Embree's shadow rays), from 10⁵ triangles Embree traces 2× to 4× as many rays per second.
pub const EMBREE_FROM: usize = 50_000;

/// The process's choice (`--tracer`), 0 while unset.
static CHOSEN: std::sync::atomic::AtomicU8 = std::sync::atomic::AtomicU8::new(0);

impl TracerKind {
    const ALL: [Self; 3] = [Self::Best, Self::Builtin, Self::Embree];

    /// The tracers this build can trace with.
    pub const BUILT: &[Self] = if cfg!(embree) { &[Self::Builtin, Self::Embree] } else { &[Self::Builtin] };

    /// The tracer `--tracer` or MYRIAD_TRACER names (`builtin`, `embree`, `best`).
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.name() == name)
    }

    /// Makes `self` the tracer of every scene built afterwards without one named (`--tracer`).
    pub fn choose_for_process(self) {
        let index = Self::ALL.iter().position(|&t| t == self).unwrap_or(0);
        CHOSEN.store(index as u8 + 1, std::sync::atomic::Ordering::Relaxed);
    }

    /// The tracer MYRIAD_TRACER names, if set; an error naming the choices if it names none.
    pub fn from_env() -> Result<Option<Self>, String> {
        let Ok(value) = std::env::var("MYRIAD_TRACER") else { return Ok(None) };
        Self::parse(&value)
            .map(Some)
            .ok_or_else(|| format!("MYRIAD_TRACER={value} names no tracer; use best, builtin or embree"))
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Best => "best",
            Self::Builtin => "builtin",
            Self::Embree => "embree",
        }
    }

    /// What `Best` means for a scene of `stored` triangles in this build: Embree from
    /// [`EMBREE_FROM`] triangles up, the built-in tracer below (docs/performance.md).
    pub fn resolve(self, stored: usize) -> Self {
        match self {
            Self::Best if cfg!(embree) && stored >= EMBREE_FROM => Self::Embree,
            Self::Best => Self::Builtin,
            t => t,
        }
    }
}

impl Default for TracerKind {
    /// `--tracer`'s choice, else MYRIAD_TRACER's, else the best.
    fn default() -> Self {
        match CHOSEN.load(std::sync::atomic::Ordering::Relaxed) {
            0 => Self::from_env().ok().flatten().unwrap_or(Self::Best),
            n => Self::ALL[n as usize - 1],
        }
    }
}

/// A bottom-level BVH and its triangles: in BVH order for the built-in tracer (nine
/// coordinate planes), as they came for Embree (three corners each, which Embree reads).
pub struct Blas {
    bvh: Option<CwBvh>,
    tris: Triangles,
    corners: Vec<Vec3A>,
}

impl Blas {
    /// Builds the BVH over `tris` (in the current rayon pool). Returns it and the
    /// permutation `order[new] = old`.
    pub fn build(tris: Vec<[Vec3A; 3]>) -> (Self, Vec<u32>) {
        if tris.is_empty() {
            return (Self { bvh: None, tris: Triangles::new(&[]), corners: Vec::new() }, Vec::new());
        }
        let prims: Vec<Triangle> = tris.iter().map(|&[v0, v1, v2]| Triangle { v0, v1, v2 }).collect();
        let bvh = build_cwbvh_from_tris(&prims, BvhBuildParams::medium_build(), &mut Duration::default());
        drop(prims);
        let order = bvh.primitive_indices.clone();
        let sorted: Vec<[Vec3A; 3]> = order.iter().map(|&i| tris[i as usize]).collect();
        (Self { bvh: Some(bvh), tris: Triangles::new(&sorted), corners: Vec::new() }, order)
    }

    /// The triangles as they are, for Embree to build its own BVH over (no permutation).
    pub fn corners(tris: &[[Vec3A; 3]]) -> Self {
        Self { bvh: None, tris: Triangles::new(&[]), corners: tris.as_flattened().to_vec() }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len() + self.corners.len() / 3
    }

    /// True when it holds no triangle.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Vertices of triangle `tri` (BVH order), in this BLAS's space. Always inlined, as
    /// [`Accel::closest_hit`].
    #[inline(always)]
    pub fn vertices(&self, tri: u32) -> [Vec3A; 3] {
        if self.corners.is_empty() {
            self.tris.vertices(tri)
        } else {
            let k = 3 * tri as usize;
            [self.corners[k], self.corners[k + 1], self.corners[k + 2]]
        }
    }

    fn memory_bytes(&self) -> usize {
        self.bvh
            .as_ref()
            .map_or(0, |b| b.nodes.len() * std::mem::size_of_val(&b.nodes[0]) + b.primitive_indices.len() * 4)
            + self.tris.memory_bytes()
            + self.corners.capacity() * std::mem::size_of::<Vec3A>()
    }

    fn bounds(&self) -> Aabb {
        let mut b = self.bvh.as_ref().map_or(Aabb::empty(), |b| b.total_aabb);
        self.corners.iter().for_each(|&c| {
            b.extend(c);
        });
        b
    }

    /// Always inlined, as [`Accel::closest_hit`].
    #[inline(always)]
    fn closest(&self, ray: obvhs::ray::Ray, accept: &impl Fn(u32, f32, f32) -> bool) -> Option<(u32, f32, f32, f32)> {
        let bvh = self.bvh.as_ref()?;
        let mut bary = (0.0f32, 0.0f32);
        let (slot, t) = traverse::closest(bvh, ray, |r, group| {
            let (slot, t, b1, b2) = self.tris.closest_in_group(r.origin, r.direction, r.tmax, group, accept)?;
            bary = (b1, b2);
            Some((slot, t))
        })?;
        Some((slot, t, bary.0, bary.1))
    }

    #[inline]
    fn any(&self, ray: obvhs::ray::Ray, accept: &impl Fn(u32, f32, f32) -> bool) -> bool {
        let Some(bvh) = self.bvh.as_ref() else { return false };
        traverse::any(bvh, ray, |r, group| self.tris.any_in_group(r.origin, r.direction, r.tmax, group, accept))
    }
}

/// A placement of a BLAS in the world.
#[derive(Clone, Copy, Debug)]
pub struct Instance {
    /// Index of the BLAS it places.
    pub blas: u32,
    /// Object → world.
    pub to_world: Mat4,
    /// World → object.
    pub to_object: Mat4,
    /// Transforms normals to world space (inverse transpose).
    pub normal_matrix: Mat3,
    /// The transform mirrors (negative determinant): the front face is the clockwise one.
    pub mirrored: bool,
    /// True for the identity placement of the flattened world-space BLAS.
    pub identity: bool,
    world_bounds: Aabb,
}

impl Boundable for Instance {
    fn aabb(&self) -> Aabb {
        self.world_bounds
    }
}

/// Sizes and timings of the acceleration structures.
#[derive(Clone, Copy, Debug, Default)]
pub struct AccelStats {
    /// Wall time of all builds.
    pub build_time: Duration,
    /// Bytes of nodes, triangles and index tables.
    pub memory_bytes: usize,
}

/// All BLASes, their instances and (with more than one instance) the TLAS, or Embree's
/// scene over the same: the one seam every ray query of the renderer goes through.
pub struct Accel {
    blases: Vec<Blas>,
    instances: Vec<Instance>,
    tlas: Option<CwBvh>,
    #[cfg(embree)]
    embree: Option<super::embree::EmbreeScene>,
    stats: AccelStats,
}

impl Accel {
    /// Places `blases` by `placements` (BLAS index, object-to-world; the identity
    /// placement of a world-space BLAS is detected and kept transform-free) and builds the
    /// TLAS when needed. `build_time` is what the BLAS builds took.
    pub fn new(blases: Vec<Blas>, placements: &[(u32, Mat4)], build_time: Duration) -> Self {
        Self::place(blases, placements, build_time, false)
    }

    /// [`Accel::new`] over BLASes of [`Blas::corners`], traced by Embree; `masked[k]`: some
    /// triangle of block k needs the acceptance test. An error when Embree cannot start or
    /// build.
    #[cfg(embree)]
    pub fn new_embree(
        blases: Vec<Blas>,
        placements: &[(u32, Mat4)],
        masked: &[bool],
        build_time: Duration,
    ) -> Result<Self, String> {
        let start = Instant::now();
        let mut accel = Self::place(blases, placements, build_time, true);
        let blocks: Vec<super::embree::BlockTriangles> = accel
            .blases
            .iter()
            .zip(masked)
            .map(|(b, &masked)| super::embree::BlockTriangles { corners: &b.corners, masked })
            .collect();
        let placed: Vec<(u32, Mat4)> = accel.instances.iter().map(|i| (i.blas, i.to_world)).collect();
        let scene = super::embree::EmbreeScene::build(&blocks, &placed)?;
        accel.stats.build_time += start.elapsed();
        accel.stats.memory_bytes += scene.memory_bytes();
        accel.embree = Some(scene);
        Ok(accel)
    }

    /// The tracer answering this one's queries.
    pub fn tracer(&self) -> TracerKind {
        #[cfg(embree)]
        if self.embree.is_some() {
            return TracerKind::Embree;
        }
        TracerKind::Builtin
    }

    /// The placements (empty BLASes left out) and, unless `embree` traces them, the TLAS.
    fn place(blases: Vec<Blas>, placements: &[(u32, Mat4)], build_time: Duration, embree: bool) -> Self {
        let start = Instant::now();
        let instances: Vec<Instance> = placements
            .iter()
            .filter(|(b, _)| !blases[*b as usize].is_empty())
            .map(|&(blas, m)| {
                let b = blases[blas as usize].bounds();
                let mut world_bounds = Aabb::empty();
                for k in 0..8 {
                    let c = Vec3A::new(
                        if k & 1 == 0 { b.min.x } else { b.max.x },
                        if k & 2 == 0 { b.min.y } else { b.max.y },
                        if k & 4 == 0 { b.min.z } else { b.max.z },
                    );
                    world_bounds.extend(m.transform_point3a(c));
                }
                let linear = Mat3::from_mat4(m);
                Instance {
                    blas,
                    to_world: m,
                    to_object: m.inverse(),
                    normal_matrix: linear.inverse().transpose(),
                    mirrored: linear.determinant() < 0.0,
                    identity: m == Mat4::IDENTITY,
                    world_bounds,
                }
            })
            .collect();
        let tlas = (instances.len() > 1 && !embree)
            .then(|| build_cwbvh(&instances, BvhBuildParams::medium_build(), &mut Duration::default()));
        // Direct layout, as for triangles: the TLAS slot is the instance index.
        let instances = match &tlas {
            Some(t) => t.primitive_indices.iter().map(|&i| instances[i as usize]).collect(),
            None => instances,
        };
        let memory_bytes = blases.iter().map(Blas::memory_bytes).sum::<usize>()
            + instances.len() * std::mem::size_of::<Instance>()
            + tlas.as_ref().map_or(0, |t| t.nodes.len() * std::mem::size_of_val(&t.nodes[0]));
        let stats = AccelStats { build_time: build_time + start.elapsed(), memory_bytes };
        Self {
            blases,
            instances,
            tlas,
            #[cfg(embree)]
            embree: None,
            stats,
        }
    }

    /// Build statistics.
    pub fn stats(&self) -> AccelStats {
        self.stats
    }

    /// Every placement, in TLAS order (the slot a hit reports).
    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }

    /// One BLAS per geometry block; block 0 holds the flattened world-space triangles.
    pub fn blases(&self) -> &[Blas] {
        &self.blases
    }

    #[inline]
    fn local_ray(inst: &Instance, ray: &Ray, t_max: f32) -> obvhs::ray::Ray {
        if inst.identity {
            obvhs_ray(ray.origin, ray.dir, t_max)
        } else {
            obvhs_ray(inst.to_object.transform_point3a(ray.origin), inst.to_object.transform_vector3a(ray.dir), t_max)
        }
    }

    /// Closest intersection with `t ∈ (0, t_max)` that `accept(blas, tri, b1, b2)` keeps
    /// (alpha cut-outs return false and the ray passes through). Always inlined: the path
    /// loop's two copies (`integrator::path`) each take the whole query in.
    #[inline(always)]
    pub fn closest_hit(&self, ray: &Ray, t_max: f32, accept: impl Fn(u32, u32, f32, f32) -> bool) -> Option<RawHit> {
        #[cfg(embree)]
        if let Some(e) = &self.embree {
            return e.closest_hit(ray, t_max, &accept);
        }
        let Some(tlas) = &self.tlas else {
            let inst = self.instances.first()?;
            let acc = |tri, b1, b2| accept(inst.blas, tri, b1, b2);
            let (tri, t, b1, b2) = self.blases[inst.blas as usize].closest(Self::local_ray(inst, ray, t_max), &acc)?;
            return Some(RawHit { instance: 0, tri, t, b1, b2 });
        };
        let mut best: Option<RawHit> = None;
        traverse::closest(tlas, obvhs_ray(ray.origin, ray.dir, t_max), |r, group| {
            let mut nearest = None;
            for slot in group.slots() {
                let inst = &self.instances[slot as usize];
                let acc = |tri, b1, b2| accept(inst.blas, tri, b1, b2);
                let tmax = nearest.map_or(r.tmax, |(_, t)| t);
                if let Some((tri, t, b1, b2)) =
                    self.blases[inst.blas as usize].closest(Self::local_ray(inst, ray, tmax), &acc)
                {
                    best = Some(RawHit { instance: slot, tri, t, b1, b2 });
                    nearest = Some((slot, t));
                }
            }
            nearest
        });
        best
    }

    /// True when something `accept` keeps lies on `origin + t·dir`, `t ∈ (0, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32, accept: impl Fn(u32, u32, f32, f32) -> bool) -> bool {
        #[cfg(embree)]
        if let Some(e) = &self.embree {
            return e.occluded(ray, t_max, &accept);
        }
        let Some(tlas) = &self.tlas else {
            let Some(inst) = self.instances.first() else { return false };
            let acc = |tri, b1, b2| accept(inst.blas, tri, b1, b2);
            return self.blases[inst.blas as usize].any(Self::local_ray(inst, ray, t_max), &acc);
        };
        traverse::any(tlas, obvhs_ray(ray.origin, ray.dir, t_max), |r, group| {
            group.slots().any(|slot| {
                let inst = &self.instances[slot as usize];
                let acc = |tri, b1, b2| accept(inst.blas, tri, b1, b2);
                self.blases[inst.blas as usize].any(Self::local_ray(inst, ray, r.tmax), &acc)
            })
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

    const ALL: fn(u32, u32, f32, f32) -> bool = |_, _, _, _| true;

    #[test]
    fn closest_hit_and_occlusion() {
        let mut tris = quad(-1.0);
        tris.extend(quad(-3.0));
        let (blas, order) = Blas::build(tris.clone());
        assert_eq!(order.len(), 4);
        let accel = Accel::new(vec![blas], &[(0, Mat4::IDENTITY)], Duration::ZERO);
        let ray = Ray::new(Vec3A::new(0.2, 0.3, 0.0), Vec3A::new(0.0, 0.0, -1.0));
        let h = accel.closest_hit(&ray, f32::INFINITY, ALL).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
        let [v0, v1, v2] = accel.blases()[0].vertices(h.tri);
        let p = v0 * (1.0 - h.b1 - h.b2) + v1 * h.b1 + v2 * h.b2;
        assert!((p - Vec3A::new(0.2, 0.3, -1.0)).length() < 1e-5);
        assert!(tris[order[h.tri as usize] as usize][0].z == -1.0);
        assert!(accel.occluded(&ray, 2.0, ALL));
        assert!(!accel.occluded(&ray, 0.5, ALL));
        assert!(accel.closest_hit(&Ray::new(Vec3A::ZERO, Vec3A::Z), f32::INFINITY, ALL).is_none());
        assert!(accel.closest_hit(&ray, 0.9, ALL).is_none());
        // A rejected triangle lets the ray through to the next.
        let h2 = accel
            .closest_hit(&ray, f32::INFINITY, |_, tri, _, _| tris[order[tri as usize] as usize][0].z != -1.0)
            .unwrap();
        assert!((h2.t - 3.0).abs() < 1e-6);
    }

    #[test]
    fn instances_place_one_blas_many_times() {
        let (blas, _) = Blas::build(quad(0.0));
        let place = |z: f32, s: f32| {
            Mat4::from_translation(glam::Vec3::new(0.0, 0.0, z)) * Mat4::from_scale(glam::Vec3::splat(s))
        };
        let accel = Accel::new(
            vec![blas],
            &[(0, place(-2.0, 1.0)), (0, place(-5.0, 3.0)), (0, place(-9.0, 0.1))],
            Duration::ZERO,
        );
        assert_eq!(accel.instances().len(), 3);
        let ray = Ray::new(Vec3A::new(2.0, 0.0, 0.0), -Vec3A::Z);
        // x = 2 misses the first (unit) quad and hits the scaled one at z = -5.
        let h = accel.closest_hit(&ray, f32::INFINITY, ALL).unwrap();
        assert_eq!(accel.instances()[h.instance as usize].to_world.w_axis.z, -5.0);
        assert!((h.t - 5.0).abs() < 1e-5, "{}", h.t);
        let centre = Ray::new(Vec3A::ZERO, -Vec3A::Z);
        assert!((accel.closest_hit(&centre, f32::INFINITY, ALL).unwrap().t - 2.0).abs() < 1e-5);
        assert!(accel.occluded(&centre, 2.5, ALL) && !accel.occluded(&centre, 1.5, ALL));
    }

    #[test]
    fn empty_scene_never_hits() {
        let (blas, _) = Blas::build(Vec::new());
        let accel = Accel::new(vec![blas], &[(0, Mat4::IDENTITY)], Duration::ZERO);
        let ray = Ray::new(Vec3A::ZERO, Vec3A::X);
        assert!(accel.closest_hit(&ray, f32::INFINITY, ALL).is_none());
        assert!(!accel.occluded(&ray, f32::INFINITY, ALL));
    }
}

#[cfg(test)]
mod regression {
    use super::*;

    #[test]
    fn negative_zero_directions_still_hit() {
        let (blas, _) =
            Blas::build(vec![[Vec3A::new(-1.0, -1.0, -1.0), Vec3A::new(1.0, -1.0, -1.0), Vec3A::new(1.0, 1.0, -1.0)]]);
        let accel = Accel::new(vec![blas], &[(0, Mat4::IDENTITY)], Duration::ZERO);
        // -Vec3A::Z is (-0, -0, -1).
        let ray = Ray::new(Vec3A::new(0.5, -0.4, 0.0), -Vec3A::Z);
        assert!(accel.closest_hit(&ray, f32::INFINITY, |_, _, _, _| true).is_some());
        assert!(accel.occluded(&ray, 2.0, |_, _, _, _| true));
    }
}

/// A box of the [`BoxBvh`], by its corners.
struct BoxPrim(Aabb);

impl Boundable for BoxPrim {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// A BVH over boxes in which a ray visits every box it passes through, nearest or not: what
/// finds the lamps along a ray (lights with a shape of their own, which camera and BSDF rays
/// see along their whole way and which cast no shadow).
pub struct BoxBvh {
    bvh: Option<CwBvh>,
}

impl BoxBvh {
    /// The BVH over `boxes` (each its min and max corner); empty for none.
    pub fn build(boxes: &[(Vec3A, Vec3A)]) -> Self {
        if boxes.is_empty() {
            return Self { bvh: None };
        }
        let prims: Vec<BoxPrim> = boxes.iter().map(|&(min, max)| BoxPrim(Aabb { min, max })).collect();
        Self { bvh: Some(build_cwbvh(&prims, BvhBuildParams::medium_build(), &mut Duration::default())) }
    }

    /// True when it holds no box.
    pub fn is_empty(&self) -> bool {
        self.bvh.is_none()
    }

    /// Calls `visit(i)` for box `i` of every box `ray` passes through within `t_max` (and
    /// perhaps a few it passes near: the caller tests the shape inside).
    #[inline]
    pub fn for_each_candidate(&self, ray: &Ray, t_max: f32, mut visit: impl FnMut(u32)) {
        let Some(bvh) = self.bvh.as_ref() else { return };
        traverse::closest(bvh, obvhs_ray(ray.origin, ray.dir, t_max), |_, group| {
            group.slots().for_each(|slot| visit(bvh.primitive_indices[slot as usize]));
            None
        });
    }

    /// Bytes of its nodes and index table.
    pub fn memory_bytes(&self) -> usize {
        self.bvh
            .as_ref()
            .map_or(0, |b| b.nodes.len() * std::mem::size_of_val(&b.nodes[0]) + b.primitive_indices.len() * 4)
    }
}
