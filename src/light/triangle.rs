//! Emissive triangle, sampled uniformly by area.

use super::{AreaEmission, LightSample};
use crate::math::warp::square_to_triangle;
use crate::math::{Vec2, Vec3A};

/// One emissive triangle (world space).
#[derive(Clone, Debug)]
pub struct TriangleLight {
    /// Vertices, counter-clockwise seen from the front.
    pub v: [Vec3A; 3],
    /// Unit front normal.
    pub n: Vec3A,
    /// Area.
    pub area: f32,
    /// Emission.
    pub emission: AreaEmission,
}

impl TriangleLight {
    /// A triangle light; `None` when the triangle has no area.
    pub fn new(v: [Vec3A; 3], emission: AreaEmission) -> Option<Self> {
        let c = (v[1] - v[0]).cross(v[2] - v[0]);
        let area = 0.5 * c.length();
        let n = c.try_normalize()?;
        (area > 0.0 && area.is_finite()).then_some(Self { v, n, area, emission })
    }

    /// Uniform-area sample seen from `p`.
    #[inline]
    pub fn sample_li(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        let [b0, b1, b2] = square_to_triangle(u);
        let q = self.v[0] * b0 + self.v[1] * b1 + self.v[2] * b2;
        self.emission.sample_at(p, q, self.n, self.area)
    }
}
