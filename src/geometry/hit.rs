//! What a closest-hit query reports about the surface it found.

use crate::math::{Vec2, Vec3A};

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
    /// ∂p/∂u of the triangle (zero without UVs): the tangent normal maps use.
    pub dpdu: Vec3A,
    /// ∂p/∂v of the triangle (zero without UVs).
    pub dpdv: Vec3A,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Material index.
    pub material: u32,
    /// Light index when the triangle emits.
    pub light: Option<u32>,
}
