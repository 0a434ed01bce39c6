//! The BSDF at a surface point before it is seen from any direction: how the path tracer and
//! light paths shade a hit, one way for both (so the densities they weigh each other by are
//! of the same BSDF).

use crate::geometry::SurfaceHit;
use crate::material::{Bsdf, Material, ShadingPoint};
use crate::math::Vec3A;
use crate::scene::Scene;

/// A BSDF on a surface point, with its frame, not yet seen from a direction.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    /// The BSDF.
    pub bsdf: Bsdf,
    /// Geometric normal (as hit).
    pub n_geom: Vec3A,
    /// Shading normal (normal-mapped).
    pub n_shading: Vec3A,
    /// Tangent of anisotropic BSDFs.
    pub tangent: Option<Vec3A>,
}

impl Surface {
    /// `material`'s BSDF at `hit` (textures looked up, normal mapped), reached from outside
    /// its volume when `entering`, its glass taken as smooth when `as_smooth`; `None` where
    /// it scatters nothing.
    #[inline(always)]
    pub fn at(scene: &Scene, material: &Material, hit: &SurfaceHit, entering: bool, as_smooth: bool) -> Option<Self> {
        let bsdf = material.bsdf(hit.uv, &scene.images, entering, as_smooth)?;
        let n_shading = material.mapped_normal(
            hit.n_shading,
            || scene.geometry.position_derivatives(hit.triangle),
            hit.uv,
            &scene.images,
        );
        let tangent = material.tangent(
            n_shading,
            || scene.geometry.tangent_at(hit.triangle, hit.p),
            || scene.geometry.position_derivatives(hit.triangle),
            hit.uv,
            &scene.images,
        );
        Some(Self { bsdf, n_geom: hit.n_geom, n_shading, tangent })
    }

    /// The BSDF seen from `wo`.
    #[inline(always)]
    pub fn seen_from(&self, wo: Vec3A) -> ShadingPoint {
        ShadingPoint::new(self.bsdf, self.n_geom, self.n_shading, self.tangent, wo)
    }
}
