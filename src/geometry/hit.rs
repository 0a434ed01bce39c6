//! What a closest-hit query reports: the tracer's raw hit ([`RawHit`], the same from every
//! tracer) and the surface it found ([`SurfaceHit`]).

use crate::math::{Vec2, Vec3A};

/// The raw result of a closest-hit query.
#[derive(Clone, Copy, Debug)]
pub struct RawHit {
    /// Index of the instance hit.
    pub instance: u32,
    /// Triangle within the instance's BLAS (BVH order).
    pub tri: u32,
    /// Ray parameter.
    pub t: f32,
    /// Barycentric weight of vertex 1.
    pub b1: f32,
    /// Barycentric weight of vertex 2.
    pub b2: f32,
}

/// A triangle of a [`Geometry`](super::Geometry): its instance and its slot in that
/// instance's BLAS.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TriangleRef {
    /// Index of the instance.
    pub instance: u32,
    /// Triangle within the instance's BLAS (BVH order).
    pub tri: u32,
}

/// A ray-surface intersection, in world space.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    /// Hit point, interpolated from the triangle's vertices.
    pub p: Vec3A,
    /// Unit geometric normal of the triangle, on its counter-clockwise (front) side.
    pub n_geom: Vec3A,
    /// Unit interpolated shading normal (equal to `n_geom` for flat triangles), before any
    /// face-forwarding.
    pub n_shading: Vec3A,
    /// Texture coordinates (zero when the mesh has none).
    pub uv: Vec2,
    /// The triangle hit, for what only some materials need of it
    /// ([`Geometry::position_derivatives`](super::Geometry::position_derivatives)).
    pub triangle: TriangleRef,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Material index.
    pub material: u32,
    /// Light index when the triangle emits.
    pub light: Option<u32>,
}
