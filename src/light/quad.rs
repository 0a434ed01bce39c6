//! Emissive parallelogram `p0 + s·e1 + t·e2`, sampled uniformly by area.
//!
//! Light grids are made of these: one light per lamp instead of two triangles, which halves
//! the light count the samplers see and keeps a lamp's pmf in one place.

use super::{AreaEmission, LightSample};
use crate::math::{Vec2, Vec3A};

/// One emissive parallelogram (world space).
#[derive(Clone, Debug)]
pub struct QuadLight {
    /// Corner.
    pub p0: Vec3A,
    /// First edge.
    pub e1: Vec3A,
    /// Second edge; the front normal is `e1 × e2`.
    pub e2: Vec3A,
    /// Unit front normal.
    pub n: Vec3A,
    /// Area.
    pub area: f32,
    /// Emission.
    pub emission: AreaEmission,
}

impl QuadLight {
    /// A quad light; `None` when the parallelogram has no area.
    pub fn new(p0: Vec3A, e1: Vec3A, e2: Vec3A, emission: AreaEmission) -> Option<Self> {
        let c = e1.cross(e2);
        let area = c.length();
        let n = c.try_normalize()?;
        (area > 0.0 && area.is_finite()).then_some(Self { p0, e1, e2, n, area, emission })
    }

    /// The two triangles that cover it, counter-clockwise like the quad.
    pub fn triangles(&self) -> [[Vec3A; 3]; 2] {
        let (a, b, c, d) = (self.p0, self.p0 + self.e1, self.p0 + self.e1 + self.e2, self.p0 + self.e2);
        [[a, b, c], [a, c, d]]
    }

    /// Uniform-area sample seen from `p`.
    #[inline]
    pub fn sample_li(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        let q = self.p0 + self.e1 * u.x + self.e2 * u.y;
        self.emission.sample_at(p, q, self.n, self.area)
    }
}
