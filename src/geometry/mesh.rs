//! The scene's triangles with the shading attributes a hit needs.
//!
//! Owns: [`GeometryBuilder`] (collects world-space triangles into one flattened block, and
//! shared meshes once each with their instances), [`Geometry`] (the built form: [`Accel`]
//! plus per-triangle [`TriangleInfo`] in BVH order per block, and indexed vertex normals, UVs
//! and, for anisotropic materials, tangents) and the closest-hit query that turns a raw hit
//! into a [`SurfaceHit`] in world space.
//! Block 0 is always the flattened world-space one.

use std::time::Instant;

use super::accel::{Accel, Blas, Instance, TracerKind};
use super::{Ray, SurfaceHit, TriangleRef};
use crate::math::{Mat4, Vec2, Vec3A};

/// `TriangleInfo::light` of a triangle that does not emit.
pub const NO_LIGHT: u32 = u32::MAX;

/// Per-triangle shading record (24 bytes).
#[derive(Clone, Copy, Debug)]
pub struct TriangleInfo {
    /// Indices of the corners' normals and UVs in [`Geometry`]'s vertex arrays.
    pub attr: [u32; 3],
    /// Material index.
    pub material: u32,
    /// Light index, or [`NO_LIGHT`].
    pub light: u32,
    /// Whether `attr` holds interpolated normals (false: flat shading).
    pub smooth: bool,
    /// Whether `attr` holds UVs.
    pub has_uv: bool,
    /// Whether the material cuts out by alpha: hits must be tested.
    pub masked: bool,
}

/// Shading attributes of triangles about to be added.
#[derive(Clone, Copy, Debug)]
pub struct Attributes {
    /// Index of the first vertex's normal/UV, from [`GeometryBuilder::push_vertices`].
    pub base: u32,
    /// Normals are present.
    pub smooth: bool,
    /// UVs are present.
    pub has_uv: bool,
}

#[derive(Default)]
struct Block {
    tris: Vec<[Vec3A; 3]>,
    info: Vec<TriangleInfo>,
}

/// Collects triangles before the BVHs are built.
#[derive(Default)]
pub struct GeometryBuilder {
    /// Block 0 (flattened, world space) then one per shared mesh (object space).
    blocks: Vec<Block>,
    placements: Vec<(u32, Mat4)>,
    normals: Vec<Vec3A>,
    uvs: Vec<Vec2>,
    /// Empty until a mesh brings tangents; then as long as `normals`.
    tangents: Vec<Vec3A>,
}

impl GeometryBuilder {
    /// An empty builder with its world-space block.
    pub fn new() -> Self {
        Self { blocks: vec![Block::default()], placements: vec![(0, Mat4::IDENTITY)], ..Default::default() }
    }

    /// Appends per-vertex normals and UVs (either may be absent; absent UVs read as zero) and
    /// returns the index of the first, for [`Attributes::base`].
    pub fn push_vertices(&mut self, normals: Option<&[Vec3A]>, uvs: Option<&[Vec2]>, count: usize) -> u32 {
        self.push_vertices_with_tangents(normals, uvs, None, count)
    }

    /// [`push_vertices`](Self::push_vertices) with tangents (transformed as normals are).
    pub fn push_vertices_with_tangents(
        &mut self,
        normals: Option<&[Vec3A]>,
        uvs: Option<&[Vec2]>,
        tangents: Option<&[Vec3A]>,
        count: usize,
    ) -> u32 {
        let base = self.normals.len() as u32;
        match tangents {
            Some(t) => {
                self.tangents.resize(base as usize, Vec3A::ZERO);
                self.tangents.extend_from_slice(&t[..count]);
            }
            None if !self.tangents.is_empty() => self.tangents.resize(base as usize + count, Vec3A::ZERO),
            None => {}
        }
        match normals {
            Some(n) => self.normals.extend_from_slice(&n[..count]),
            None => self.normals.resize(self.normals.len() + count, Vec3A::ZERO),
        }
        match uvs {
            Some(t) => self.uvs.extend_from_slice(&t[..count]),
            None => self.uvs.resize(self.uvs.len() + count, Vec2::ZERO),
        }
        base
    }

    fn push(
        block: &mut Block,
        positions: [Vec3A; 3],
        corners: [u32; 3],
        attr: Option<Attributes>,
        material: u32,
        light: u32,
        masked: bool,
    ) {
        let (attr, smooth, has_uv) =
            attr.map_or(([0; 3], false, false), |a| (corners.map(|c| a.base + c), a.smooth, a.has_uv));
        block.tris.push(positions);
        block.info.push(TriangleInfo { attr, material, light, smooth, has_uv, masked });
    }

    /// Appends one world-space triangle to the flattened block. `corners` index the vertex
    /// attributes relative to `attr.base`.
    pub fn push_triangle(
        &mut self,
        positions: [Vec3A; 3],
        corners: [u32; 3],
        attr: Option<Attributes>,
        material: u32,
        light: u32,
        masked: bool,
    ) {
        Self::push(&mut self.blocks[0], positions, corners, attr, material, light, masked);
    }

    /// Adds a mesh that several instances share, in object space; returns its block.
    pub fn add_shared_mesh(
        &mut self,
        positions: &[Vec3A],
        triangles: &[[u32; 3]],
        attr: Option<Attributes>,
        material: u32,
        masked: bool,
    ) -> u32 {
        let mut block = Block::default();
        for &t in triangles {
            Self::push(&mut block, t.map(|i| positions[i as usize]), t, attr, material, NO_LIGHT, masked);
        }
        self.blocks.push(block);
        (self.blocks.len() - 1) as u32
    }

    /// Places shared block `block` in the world.
    pub fn add_instance(&mut self, block: u32, transform: Mat4) {
        self.placements.push((block, transform));
    }

    /// Builds every BVH with `tracer` (`best`: see [`TracerKind::resolve`]; the built-in one
    /// reorders triangles into BVH order, lights keep their ids). Where Embree is asked for
    /// but this build lacks it or it fails, the built-in tracer takes over and the second value
    /// says why.
    pub fn build(self, tracer: TracerKind) -> (Geometry, Option<String>) {
        let start = Instant::now();
        let masked = self.blocks.iter().flat_map(|b| &b.info).any(|i| i.masked);
        if tracer.resolve(self.blocks.iter().map(|b| b.tris.len()).sum()) == TracerKind::Builtin {
            return (self.build_builtin(start, masked), None);
        }
        #[cfg(embree)]
        return self.build_embree(start, masked);
        #[cfg(not(embree))]
        {
            let why = "this myriad was built without Embree (install it: apt install libembree-dev, then build \
                       again): traced with the built-in tracer";
            (self.build_builtin(start, masked), Some(why.to_string()))
        }
    }

    /// [`GeometryBuilder::build`] for Embree: the blocks as they are (Embree builds its own
    /// BVHs), or the built-in tracer's where Embree fails, with why.
    #[cfg(embree)]
    fn build_embree(self, start: Instant, masked: bool) -> (Geometry, Option<String>) {
        let blocks_masked: Vec<bool> = self.blocks.iter().map(|b| b.info.iter().any(|i| i.masked)).collect();
        let blases = self.blocks.iter().map(|b| Blas::corners(&b.tris)).collect();
        match Accel::new_embree(blases, &self.placements, &blocks_masked, start.elapsed()) {
            Ok(accel) => {
                let info = self.blocks.into_iter().map(|b| b.info).collect();
                let (normals, uvs, tangents) = (self.normals, self.uvs, self.tangents);
                (Geometry { accel, info, normals, uvs, tangents, masked }, None)
            }
            Err(why) => {
                let why = format!("{why}: traced with the built-in tracer instead");
                (self.build_builtin(Instant::now(), masked), Some(why))
            }
        }
    }

    fn build_builtin(self, start: Instant, masked: bool) -> Geometry {
        let mut blases = Vec::with_capacity(self.blocks.len());
        let mut infos = Vec::with_capacity(self.blocks.len());
        for block in self.blocks {
            let (blas, order) = Blas::build(block.tris);
            infos.push(order.iter().map(|&old| block.info[old as usize]).collect::<Vec<_>>());
            blases.push(blas);
        }
        let accel = Accel::new(blases, &self.placements, start.elapsed());
        Geometry { accel, info: infos, normals: self.normals, uvs: self.uvs, tangents: self.tangents, masked }
    }
}

/// A triangle's corners in world space with their shading normals (not normalised) and its
/// front normal.
#[derive(Clone, Copy, Debug)]
pub struct Corners {
    /// The corners.
    pub p: [Vec3A; 3],
    /// The shading normal at each corner.
    pub n: [Vec3A; 3],
    /// The unit normal of the triangle's front.
    pub n_geom: Vec3A,
}

/// All triangles of a scene, ready for ray queries.
pub struct Geometry {
    /// The BVHs and the triangles' positions.
    pub accel: Accel,
    /// Shading record per triangle, per block, in BVH order.
    info: Vec<Vec<TriangleInfo>>,
    normals: Vec<Vec3A>,
    uvs: Vec<Vec2>,
    /// Per-vertex tangents (empty when no mesh has them).
    tangents: Vec<Vec3A>,
    /// Whether any triangle is alpha-masked; without one, traversal asks nothing per
    /// candidate hit (its shading record would be a memory access per triangle tested).
    masked: bool,
}

impl Geometry {
    /// Triangles as rendered (every instance counted).
    pub fn triangle_count(&self) -> usize {
        self.accel.instances().iter().map(|i| self.info[i.blas as usize].len()).sum()
    }

    /// Triangles stored (shared meshes counted once).
    pub fn stored_triangle_count(&self) -> usize {
        self.info.iter().map(Vec::len).sum()
    }

    /// Bytes held by the triangles, their attributes and the BVHs.
    pub fn memory_bytes(&self) -> usize {
        self.accel.stats().memory_bytes
            + self.info.iter().map(|i| i.capacity() * std::mem::size_of::<TriangleInfo>()).sum::<usize>()
            + self.normals.capacity() * std::mem::size_of::<Vec3A>()
            + self.uvs.capacity() * std::mem::size_of::<Vec2>()
            + self.tangents.capacity() * std::mem::size_of::<Vec3A>()
    }

    /// The shading record of triangle `tri` of block `blas`.
    #[inline]
    pub fn info(&self, blas: u32, tri: u32) -> &TriangleInfo {
        &self.info[blas as usize][tri as usize]
    }

    /// Texture coordinates at barycentrics (b1, b2) of a triangle.
    #[inline]
    pub fn uv_at(&self, info: &TriangleInfo, b1: f32, b2: f32) -> Vec2 {
        if !info.has_uv {
            return Vec2::ZERO;
        }
        let [a, b, c] = info.attr.map(|i| self.uvs[i as usize]);
        a * (1.0 - b1 - b2) + b * b1 + c * b2
    }

    /// Every triangle in world space (vertices counter-clockwise from the front), with its
    /// record: for bounds and tests.
    pub fn world_triangles(&self) -> impl Iterator<Item = ([Vec3A; 3], &TriangleInfo)> + '_ {
        self.accel.instances().iter().flat_map(move |inst| {
            let blas = &self.accel.blases()[inst.blas as usize];
            (0..blas.len() as u32).map(move |t| (world_vertices(inst, blas.vertices(t)), self.info(inst.blas, t)))
        })
    }

    /// Closest surface along `ray` with `t ∈ (0, t_max)`. `cut_out(material, uv)` is asked
    /// about hits on alpha-masked triangles; true lets the ray pass. Always inlined, as
    /// `Accel::closest_hit`.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32, cut_out: impl Fn(u32, Vec2) -> bool) -> Option<SurfaceHit> {
        let raw = if self.masked {
            self.accel.closest_hit(ray, t_max, |blas, tri, b1, b2| {
                let info = self.info(blas, tri);
                !info.masked || !cut_out(info.material, self.uv_at(info, b1, b2))
            })
        } else {
            self.accel.closest_hit(ray, t_max, |_, _, _, _| true)
        }?;
        let inst = &self.accel.instances()[raw.instance as usize];
        let [v0, v1, v2] = world_vertices(inst, self.accel.blases()[inst.blas as usize].vertices(raw.tri));
        let (b1, b2) = (raw.b1, raw.b2);
        let b0 = 1.0 - b1 - b2;
        let p = v0 * b0 + v1 * b1 + v2 * b2;
        let n_geom = (v1 - v0).cross(v2 - v0).normalize_or_zero();
        let info = self.info(inst.blas, raw.tri);
        let n_shading = if info.smooth {
            let [a, b, c] = info.attr.map(|i| self.normals[i as usize]);
            let n = a * b0 + b * b1 + c * b2;
            let n = if inst.identity { n } else { inst.normal_matrix * n };
            n.try_normalize().unwrap_or(n_geom)
        } else {
            n_geom
        };
        let uv = self.uv_at(info, b1, b2);
        Some(SurfaceHit {
            p,
            // World vertices of a mirrored instance wind the other way: flip back to its front.
            n_geom: if inst.mirrored { -n_geom } else { n_geom },
            n_shading,
            uv,
            triangle: TriangleRef { instance: raw.instance, tri: raw.tri },
            t: raw.t,
            material: info.material,
            light: (info.light != NO_LIGHT).then_some(info.light),
        })
    }

    /// `triangle`'s corners and their shading normals in world space (every corner the
    /// triangle's front normal where the mesh is flat-shaded), and its front normal: what a
    /// walk over the surface (manifold next-event estimation) interpolates between.
    pub fn corners(&self, triangle: TriangleRef) -> Corners {
        let inst = &self.accel.instances()[triangle.instance as usize];
        let info = self.info(inst.blas, triangle.tri);
        let p = world_vertices(inst, self.accel.blases()[inst.blas as usize].vertices(triangle.tri));
        let n_geom = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let n_geom = if inst.mirrored { -n_geom } else { n_geom };
        let n = if info.smooth {
            info.attr.map(|i| {
                if inst.identity { self.normals[i as usize] } else { inst.normal_matrix * self.normals[i as usize] }
            })
        } else {
            [n_geom; 3]
        };
        Corners { p, n, n_geom }
    }

    /// ∂p/∂u and ∂p/∂v of `triangle` in world space (zero without UVs or where its UV
    /// mapping is degenerate): the tangent frame normal maps use, asked for only by them.
    pub fn position_derivatives(&self, triangle: TriangleRef) -> (Vec3A, Vec3A) {
        let inst = &self.accel.instances()[triangle.instance as usize];
        let info = self.info(inst.blas, triangle.tri);
        if !info.has_uv {
            return (Vec3A::ZERO, Vec3A::ZERO);
        }
        let p = world_vertices(inst, self.accel.blases()[inst.blas as usize].vertices(triangle.tri));
        position_derivatives(p, info.attr.map(|i| self.uvs[i as usize]))
    }

    /// The tangent its mesh carries at `p` on `triangle` (world space, not normalised; zero
    /// where the mesh has none): asked for only by anisotropic materials.
    pub fn tangent_at(&self, triangle: TriangleRef, p: Vec3A) -> Vec3A {
        let inst = &self.accel.instances()[triangle.instance as usize];
        let info = self.info(inst.blas, triangle.tri);
        if info.attr.iter().any(|&i| i as usize >= self.tangents.len()) {
            return Vec3A::ZERO;
        }
        let t = info.attr.map(|i| self.tangents[i as usize]);
        let [v0, v1, v2] = world_vertices(inst, self.accel.blases()[inst.blas as usize].vertices(triangle.tri));
        // Barycentrics of p by areas (p lies on the triangle).
        let n = (v1 - v0).cross(v2 - v0);
        let area = n.length_squared();
        if !(area > 0.0) {
            return Vec3A::ZERO;
        }
        let b1 = (p - v0).cross(v2 - v0).dot(n) / area;
        let b2 = (v1 - v0).cross(p - v0).dot(n) / area;
        let local = t[0] * (1.0 - b1 - b2) + t[1] * b1 + t[2] * b2;
        if inst.identity { local } else { inst.normal_matrix * local }
    }

    /// True when something not cut out blocks the segment from `origin` to
    /// `origin + dir·t_max`.
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray, t_max: f32, cut_out: impl Fn(u32, Vec2) -> bool) -> bool {
        if !self.masked {
            return self.accel.occluded(ray, t_max, |_, _, _, _| true);
        }
        self.accel.occluded(ray, t_max, |blas, tri, b1, b2| {
            let info = self.info(blas, tri);
            !info.masked || !cut_out(info.material, self.uv_at(info, b1, b2))
        })
    }
}

#[inline]
fn world_vertices(inst: &Instance, v: [Vec3A; 3]) -> [Vec3A; 3] {
    if inst.identity { v } else { v.map(|p| inst.to_world.transform_point3a(p)) }
}

/// Blender's default tangent at each of a mesh's vertices (object space, not normalised):
/// around the vertical axis through the centre of the mesh's bounding box, each axis scaled
/// by the box's size along it, as Cycles' radial tangent about the object's Z over its
/// generated coordinates, with glTF's +Y up where Blender has +Z. Anisotropic materials
/// without a direction texture stretch along it ([`Material::tangent`](crate::material::Material::tangent)).
pub fn radial_tangents(positions: &[Vec3A]) -> Vec<Vec3A> {
    let (lo, hi) = crate::math::point_bounds(positions.iter().copied());
    let center = (lo + hi) * 0.5;
    // Blender's texture space: a flat side counts as size 1, a tiny one as 1e-5.
    let size = ((hi - lo) * 0.5).to_array().map(|s| if s == 0.0 { 1.0 } else { s.max(1e-5) });
    positions.iter().map(|&p| Vec3A::new((p.z - center.z) / size[2], 0.0, -(p.x - center.x) / size[0])).collect()
}

/// dp/du and dp/dv of a triangle from its positions and texture coordinates (zero when the
/// UV mapping is degenerate).
fn position_derivatives(p: [Vec3A; 3], uv: [Vec2; 3]) -> (Vec3A, Vec3A) {
    let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let det = d1.x * d2.y - d1.y * d2.x;
    if det.abs() < 1e-12 {
        return (Vec3A::ZERO, Vec3A::ZERO);
    }
    let inv = 1.0 / det;
    ((e1 * d2.y - e2 * d1.y) * inv, (e2 * d1.x - e1 * d2.x) * inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_of_an_axis_aligned_mapping() {
        let p = [Vec3A::ZERO, Vec3A::new(2.0, 0.0, 0.0), Vec3A::new(0.0, 3.0, 0.0)];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let (du, dv) = position_derivatives(p, uv);
        assert!((du - Vec3A::new(2.0, 0.0, 0.0)).length() < 1e-6 && (dv - Vec3A::new(0.0, 3.0, 0.0)).length() < 1e-6);
    }

    #[test]
    fn shared_meshes_are_stored_once_and_hit_in_world_space_by_every_tracer() {
        for &tracer in TracerKind::BUILT {
            let mut g = GeometryBuilder::new();
            let quad = [
                Vec3A::new(-1.0, -1.0, 0.0),
                Vec3A::new(1.0, -1.0, 0.0),
                Vec3A::new(1.0, 1.0, 0.0),
                Vec3A::new(-1.0, 1.0, 0.0),
            ];
            let normals = [Vec3A::Z; 4];
            let base = g.push_vertices(Some(&normals), None, 4);
            let attr = Attributes { base, smooth: true, has_uv: false };
            let block = g.add_shared_mesh(&quad, &[[0, 1, 2], [0, 2, 3]], Some(attr), 7, false);
            for k in 0..100 {
                let m =
                    Mat4::from_translation(glam::Vec3::new(0.0, 0.0, -(k as f32) - 1.0)) * Mat4::from_rotation_y(0.3);
                g.add_instance(block, m);
            }
            let (geo, warning) = g.build(tracer);
            assert_eq!((geo.accel.tracer(), warning), (tracer, None));
            assert_eq!(geo.stored_triangle_count(), 2);
            assert_eq!(geo.triangle_count(), 200);
            let ray = Ray::new(Vec3A::new(0.1, 0.2, 0.0), -Vec3A::Z);
            let hit = geo.intersect(&ray, f32::INFINITY, |_, _| false).unwrap();
            assert!((hit.p.z + 1.0).abs() < 0.1, "{tracer:?}: {}", hit.p);
            assert_eq!(hit.material, 7);
            // The shading normal is rotated with the instance.
            let n = Vec3A::new(0.3f32.sin(), 0.0, 0.3f32.cos());
            assert!((hit.n_shading - n).length() < 1e-4, "{tracer:?}: {}", hit.n_shading);
        }
    }
}
