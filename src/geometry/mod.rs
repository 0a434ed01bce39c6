//! Surfaces as triangles: storage, ray queries and robust ray spawning.
//!
//! Owns: [`Ray`], the flattened world-space triangle soup with its shading attributes
//! ([`Geometry`]), the obvhs acceleration structure (`accel.rs`, and `traverse.rs` its
//! traversal: the only files that import obvhs), the triangles' storage and test
//! (`triangles.rs`) and [`SurfaceHit`]. Depends on `math` only; knows nothing of materials or
//! lights beyond the ids it stores per triangle.

mod accel;
#[cfg(embree)]
mod embree;
mod hit;
mod mesh;
mod offset;
mod traverse;
mod triangles;

pub use accel::{Accel, AccelStats, Blas, BoxBvh, Instance, TracerKind};
pub use hit::{RawHit, SurfaceHit, TriangleRef};
pub use mesh::{Attributes, Corners, Geometry, GeometryBuilder, NO_LIGHT, TriangleInfo, radial_tangents};
pub use offset::{offset_ray_origin, offset_toward};

use crate::math::Vec3A;

/// A ray: origin and direction (not necessarily normalised).
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3A,
    /// Direction.
    pub dir: Vec3A,
}

impl Ray {
    /// A ray from `origin` along `dir`.
    #[inline]
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        Self { origin, dir }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3A {
        self.origin + self.dir * t
    }
}
