//! Emissive parallelogram `p0 + s·e1 + t·e2`, sampled uniformly by area.
//!
//! Light grids are made of these, and so is every emissive mesh whose consecutive triangles
//! pair up into parallelograms (a Blender plane or grid lamp, exported as two triangles per
//! face): one light per lamp instead of two triangles halves the light count the samplers
//! see, saves a level of the light tree, and keeps a lamp's pmf in one place.

use super::{AreaEmission, AreaPoint, LightSample};
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

    /// The parallelogram triangles `t0` and `t1` (corners counter-clockwise seen from their
    /// front) make together, when they make one: they share an edge, face the same way, and
    /// the two corners off the edge mirror each other through its middle to within 10⁻⁵ of
    /// the edge lengths plus 10⁻⁶ of the coordinates (f32 round-off of a transformed quad is
    /// below that). Sampling it
    /// uniformly by area is sampling the pair in proportion to area, then uniformly.
    pub fn from_triangles(t0: [Vec3A; 3], t1: [Vec3A; 3], emission: AreaEmission) -> Option<Self> {
        // t0 as (o, s1, s2) with o the corner t1 lacks; t1 must then hold s1 and s2.
        let k = (0..3).find(|&k| !t1.contains(&t0[k]))?;
        let (o, s1, s2) = (t0[k], t0[(k + 1) % 3], t0[(k + 2) % 3]);
        let q = *t1.iter().find(|&&v| v != s1 && v != s2)?;
        if !(t1.contains(&s1) && t1.contains(&s2)) {
            return None;
        }
        let (e1, e2) = (s1 - o, s2 - o);
        // Relative to the edges, and to the coordinates' own round-off far from the origin.
        let far = o.abs().max(q.abs()).max(s1.abs()).max(s2.abs()).max_element();
        let tolerance = 1e-5 * e1.length().max(e2.length()) + 1e-6 * far;
        let facing = e1.cross(e2).dot((t1[1] - t1[0]).cross(t1[2] - t1[0])) > 0.0;
        if !facing || (o + q - s1 - s2).length() > tolerance {
            return None;
        }
        Self::new(o, e1, e2, emission)
    }

    /// The two triangles that cover it, counter-clockwise like the quad.
    pub fn triangles(&self) -> [[Vec3A; 3]; 2] {
        let (a, b, c, d) = (self.p0, self.p0 + self.e1, self.p0 + self.e1 + self.e2, self.p0 + self.e2);
        [[a, b, c], [a, c, d]]
    }

    /// Uniform-area sample seen from `p`.
    #[inline]
    pub fn sample_li(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        let a = self.area_point(u);
        self.emission.sample_at(p, a.p, self.n, self.area)
    }

    /// The point `u` chooses uniformly by area.
    #[inline]
    pub fn area_point(&self, u: Vec2) -> AreaPoint {
        AreaPoint {
            p: self.p0 + self.e1 * u.x + self.e2 * u.y,
            n: self.n,
            pdf: 1.0 / self.area,
            emission: self.emission,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rgb;

    const E: AreaEmission = AreaEmission { radiance: Rgb::ONE, two_sided: false };

    #[test]
    fn triangle_pairs_make_the_parallelogram_they_cover() {
        let (a, b, c, d) =
            (Vec3A::new(1.0, 2.0, 3.0), Vec3A::new(3.0, 2.0, 3.5), Vec3A::new(3.5, 2.0, 5.0), Vec3A::ZERO);
        let d = d + a + c - b;
        // Blender's split (a,b,c)+(a,c,d), the other diagonal, and rotated corner orders.
        for (t0, t1) in [([a, b, c], [a, c, d]), ([a, b, d], [b, c, d]), ([c, a, b], [d, a, c]), ([b, d, a], [c, d, b])]
        {
            let q = QuadLight::from_triangles(t0, t1, E).unwrap_or_else(|| panic!("{t0:?} {t1:?}"));
            let corners = [q.p0, q.p0 + q.e1, q.p0 + q.e1 + q.e2, q.p0 + q.e2];
            assert!([a, b, c, d].iter().all(|v| corners.iter().any(|w| (*v - *w).length() < 1e-5)), "{corners:?}");
            let n = (b - a).cross(c - a).normalize();
            assert!(q.n.dot(n) > 0.999 && (q.area - (b - a).cross(d - a).length()).abs() < 1e-4);
        }
        // A trapezoid, opposite faces, and triangles without a common edge are no quad.
        let trapezoid = d + 0.01 * (c - d);
        assert!(QuadLight::from_triangles([a, b, c], [a, c, trapezoid], E).is_none());
        assert!(QuadLight::from_triangles([a, b, c], [a, d, c], E).is_none(), "faces away");
        assert!(QuadLight::from_triangles([a, b, c], [a, d, d + Vec3A::X], E).is_none());
        // Far from the origin, round-off in the coordinates is not a reason to refuse.
        let far = Vec3A::splat(1.0e3);
        let q = QuadLight::from_triangles([a + far, b + far, c + far], [a + far, c + far, d + far], E);
        assert!(q.is_some());
    }
}
