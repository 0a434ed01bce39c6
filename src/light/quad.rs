//! Emissive parallelogram `p0 + s·e1 + t·e2`, sampled uniformly in the solid angle it
//! subtends where it is a rectangle seen large enough ([`SphericalRectangle`]), otherwise
//! uniformly by area.
//!
//! Light grids are made of these, and so is every emissive mesh whose consecutive triangles
//! pair up into parallelograms (a Blender plane or grid lamp, exported as two triangles per
//! face): one light per lamp instead of two triangles halves the light count the samplers
//! see, saves a level of the light tree, and keeps a lamp's pmf in one place.

use super::{AreaEmission, LightSample};
use crate::math::spherical_rectangle::SphericalRectangle;
use crate::math::{Vec2, Vec3A};

/// Smallest solid angle (sr, judged from the centre) sampled as one: below, the lamp is
/// small or far enough that area sampling's density hardly varies over it, and costs less.
/// Per sample against area sampling (160×120, 64 spp, 8 seeds; instructions by cachegrind):
/// panels.glb relMSE·spp 0.01986 → 0.01591 at 3·10⁻⁴ sr (pbrt-v4's bound) for 3948 → 4837
/// instructions, → 0.01622 at 0.05 for 4492, product 0.93× (0.96× at 0.03, 0.94× at 0.1);
/// cornell_grid_7.glb, whose lamps never cover 0.05 sr, the same error for 1.2 % more
/// instructions (the test below).
pub const MIN_SPHERICAL: f32 = 0.05;
/// Largest: near 2π (a receiver almost in contact) the parametrisation loses precision.
pub const MAX_SPHERICAL: f32 = 6.22;

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
    /// Its edges are perpendicular (to 10⁻⁴ of their lengths' product), so that it can be
    /// sampled by solid angle.
    pub rectangle: bool,
}

impl QuadLight {
    /// A quad light; `None` when the parallelogram has no area.
    pub fn new(p0: Vec3A, e1: Vec3A, e2: Vec3A, emission: AreaEmission) -> Option<Self> {
        let c = e1.cross(e2);
        let area = c.length();
        let n = c.try_normalize()?;
        let rectangle = e1.dot(e2).abs() <= 1e-4 * e1.length() * e2.length();
        (area > 0.0 && area.is_finite()).then_some(Self { p0, e1, e2, n, area, emission, rectangle })
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

    /// A sample seen from `p`: uniform in solid angle where [`spherical`](Self::spherical)
    /// says so, else uniform by area.
    #[inline]
    pub fn sample_li(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        match self.spherical(p) {
            Some(r) => self.sample_spherical(p, &r, u),
            None => self.emission.sample_at(p, self.p0 + self.e1 * u.x + self.e2 * u.y, self.n, self.area),
        }
    }

    /// Solid-angle density at `p` of [`sample_li`](Self::sample_li) picking `q` (a point of
    /// the quad, normal `n_q`).
    #[inline]
    pub fn pdf_li(&self, p: Vec3A, q: Vec3A, n_q: Vec3A) -> f32 {
        match self.spherical(p) {
            Some(r) => r.solid_angle().recip(),
            None => self.emission.pdf_li(p, q, n_q, self.area),
        }
    }

    /// The quad as a spherical rectangle seen from `p`, where it is sampled as one: a
    /// rectangle whose emitting side faces `p` and which, judged from its centre, covers at
    /// least [`MIN_SPHERICAL`] sr (A·cos θ/d² ≥ it), and exactly at most [`MAX_SPHERICAL`].
    /// The first test is inline, for it is all most samples pay; the rest out of line.
    #[inline]
    fn spherical(&self, p: Vec3A) -> Option<SphericalRectangle> {
        let height = self.n.dot(p - self.p0);
        let faces = self.emission.two_sided || height > 0.0;
        let d2 = (self.p0 + 0.5 * (self.e1 + self.e2) - p).length_squared();
        let seen = self.area * height;
        (self.rectangle && faces && seen * seen >= MIN_SPHERICAL * MIN_SPHERICAL * d2 * d2 * d2)
            .then(|| self.seen_from(p))
            .flatten()
    }

    /// [`spherical`](Self::spherical) past its first test.
    #[inline(never)]
    fn seen_from(&self, p: Vec3A) -> Option<SphericalRectangle> {
        let r = SphericalRectangle::new(p, self.p0, self.e1, self.e2)?;
        (r.solid_angle() > 0.0 && r.solid_angle() <= MAX_SPHERICAL).then_some(r)
    }

    /// A sample of `r`, the quad seen from `p` (out of line, as [`seen_from`](Self::seen_from)).
    #[inline(never)]
    fn sample_spherical(&self, p: Vec3A, r: &SphericalRectangle, u: Vec2) -> Option<LightSample> {
        let sample = self.emission.sample_at(p, r.sample(u), self.n, self.area)?;
        Some(LightSample { pdf: r.solid_angle().recip(), ..sample })
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
