//! The scene's triangles in world space, with the shading attributes a hit needs.
//!
//! Owns: [`GeometryBuilder`] (collects triangles from every shape and mesh), [`Geometry`]
//! (the built, immutable form: [`Accel`] plus per-triangle [`TriangleInfo`] in BVH order, and
//! indexed vertex normals and UVs) and the closest-hit query that turns a raw hit into a
//! [`SurfaceHit`].

use super::{Accel, Ray, SurfaceHit};
use crate::math::{Vec2, Vec3A};

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
}

/// Collects triangles before the BVH is built.
#[derive(Default)]
pub struct GeometryBuilder {
    tris: Vec<[Vec3A; 3]>,
    info: Vec<TriangleInfo>,
    normals: Vec<Vec3A>,
    uvs: Vec<Vec2>,
}

impl GeometryBuilder {
    /// Number of triangles so far; the index the next triangle will get before reordering.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// True when no triangle was added.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Appends per-vertex normals and UVs (either may be absent; absent UVs read as zero)
    /// and returns the index of the first one, for [`GeometryBuilder::push_triangle`].
    pub fn push_vertices(&mut self, normals: Option<&[Vec3A]>, uvs: Option<&[Vec2]>, count: usize) -> u32 {
        let base = self.normals.len() as u32;
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

    /// Appends one triangle and returns its (pre-BVH) index. `attr`: vertex indices returned
    /// by [`GeometryBuilder::push_vertices`], with whether normals and UVs are meaningful.
    pub fn push_triangle(
        &mut self,
        positions: [Vec3A; 3],
        attr: Option<([u32; 3], bool, bool)>,
        material: u32,
        light: u32,
    ) -> u32 {
        let (attr, smooth, has_uv) = attr.unwrap_or(([0; 3], false, false));
        self.tris.push(positions);
        self.info.push(TriangleInfo { attr, material, light, smooth, has_uv });
        (self.tris.len() - 1) as u32
    }

    /// Sets the light of a triangle added earlier.
    pub fn set_light(&mut self, tri: u32, light: u32) {
        self.info[tri as usize].light = light;
    }

    /// Builds the BVH and reorders the triangles. Returns the geometry and `new_index[old]`.
    pub fn build(self) -> (Geometry, Vec<u32>) {
        let (accel, order) = Accel::build(self.tris);
        let mut new_index = vec![0u32; order.len()];
        for (new, &old) in order.iter().enumerate() {
            new_index[old as usize] = new as u32;
        }
        let info = order.iter().map(|&old| self.info[old as usize]).collect();
        let geometry = Geometry { accel, info, normals: self.normals, uvs: self.uvs };
        (geometry, new_index)
    }
}

/// All triangles of a scene, ready for ray queries.
pub struct Geometry {
    /// The BVH and the triangles' positions.
    pub accel: Accel,
    /// Shading record per triangle, in BVH order.
    pub info: Vec<TriangleInfo>,
    normals: Vec<Vec3A>,
    uvs: Vec<Vec2>,
}

impl Geometry {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.info.len()
    }

    /// Bytes held by the triangles, their attributes and the BVH.
    pub fn memory_bytes(&self) -> usize {
        self.accel.stats().memory_bytes
            + self.info.capacity() * std::mem::size_of::<TriangleInfo>()
            + self.normals.capacity() * std::mem::size_of::<Vec3A>()
            + self.uvs.capacity() * std::mem::size_of::<Vec2>()
    }

    /// Texture coordinates at barycentrics (b1, b2) of triangle `tri`.
    #[inline]
    pub fn uv_at(&self, tri: u32, b1: f32, b2: f32) -> Vec2 {
        let info = &self.info[tri as usize];
        if !info.has_uv {
            return Vec2::ZERO;
        }
        let [a, b, c] = info.attr.map(|i| self.uvs[i as usize]);
        a * (1.0 - b1 - b2) + b * b1 + c * b2
    }

    /// Closest surface along `ray` with `t ∈ (0, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        let raw = self.accel.closest_hit(ray, t_max)?;
        let [v0, v1, v2] = self.accel.vertices(raw.tri);
        let (b1, b2) = (raw.b1, raw.b2);
        let b0 = 1.0 - b1 - b2;
        let p = v0 * b0 + v1 * b1 + v2 * b2;
        let n_geom = (v1 - v0).cross(v2 - v0).normalize_or_zero();
        let info = &self.info[raw.tri as usize];
        let n_shading = if info.smooth {
            let [a, b, c] = info.attr.map(|i| self.normals[i as usize]);
            let n = (a * b0 + b * b1 + c * b2).normalize_or_zero();
            if n == Vec3A::ZERO { n_geom } else { n }
        } else {
            n_geom
        };
        Some(SurfaceHit {
            p,
            n_geom,
            n_shading,
            uv: self.uv_at(raw.tri, b1, b2),
            t: raw.t,
            tri: raw.tri,
            material: info.material,
            light: (info.light != NO_LIGHT).then_some(info.light),
        })
    }

    /// True when something blocks the segment from `origin` to `origin + dir·t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.accel.occluded(ray, t_max)
    }
}
