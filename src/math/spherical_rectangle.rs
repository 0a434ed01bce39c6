//! Uniform sampling of the solid angle a rectangle subtends (Ureña, Fajardo & King 2013, "An
//! Area-Preserving Parametrization for Spherical Rectangles").
//!
//! Owns: [`SphericalRectangle`], the rectangle as seen from one point: its solid angle and
//! the map from the unit square to points of the rectangle whose directions are uniform
//! over that solid angle. Area sampling's density in solid angle is d²/(cos θ·A), which
//! swings by (d_far/d_near)² over a lamp close to the receiver; this one is 1/Ω everywhere.
//!
//! Worked in f32, with [`safe_acos`]'s polynomial: the solid angle is a sum of four angles
//! less 2π, and the cancellation leaves about 10⁻⁶ sr of round-off whatever the size, so
//! callers use it where the rectangle covers much more than that (quads from 0.05 sr, where
//! it is 2·10⁻⁵ of the density).

use super::{Vec2, Vec3A, safe_acos};
use std::f32::consts::TAU;

/// A rectangle `corner + s·ex + t·ey` (s, t ∈ [0, 1], `ex ⟂ ey`) seen from a point off its
/// plane, in the frame of Ureña et al.: x along `ex`, y along `ey`, z towards the point's
/// side reversed, so that the rectangle lies at z = `z0` < 0 and spans [`x0`, `x1`] ×
/// [`y0`, `y1`] around the point.
#[derive(Clone, Copy, Debug)]
pub struct SphericalRectangle {
    o: Vec3A,
    x: Vec3A,
    y: Vec3A,
    z: Vec3A,
    x0: f32,
    x1: f32,
    y0: f32,
    y1: f32,
    z0: f32,
    /// z of the plane normals through the edges at y0 and at y1.
    b0: f32,
    b1: f32,
    /// 2π less the angles at the corners on the x0 side: where the sampled angle starts.
    k: f32,
    solid_angle: f32,
}

impl SphericalRectangle {
    /// The rectangle seen from `o`; `None` when `o` lies in its plane or the edges are not
    /// finite and non-zero.
    #[inline]
    pub fn new(o: Vec3A, corner: Vec3A, ex: Vec3A, ey: Vec3A) -> Option<Self> {
        let (w, h) = (ex.length(), ey.length());
        if !(w > 0.0 && h > 0.0 && w.is_finite() && h.is_finite()) {
            return None;
        }
        let (x, y) = (ex / w, ey / h);
        let mut z = x.cross(y);
        let d = corner - o;
        let (x0, y0, mut z0) = (d.dot(x), d.dot(y), d.dot(z));
        if z0 > 0.0 {
            z0 = -z0;
            z = -z;
        }
        if !(z0 < 0.0) {
            return None;
        }
        let (x1, y1) = (x0 + w, y0 + h);
        // The planes through o and each edge (at y0, x1, y1, x0) have normals (0, z0, −y0),
        // (−z0, 0, x1), (0, −z0, y1), (z0, 0, −x0) over their lengths; the angle between
        // neighbours is the acos of minus their dot product.
        let z2 = z0 * z0;
        let (r0, r1, r2, r3) = (
            (z2 + y0 * y0).sqrt().recip(),
            (z2 + x1 * x1).sqrt().recip(),
            (z2 + y1 * y1).sqrt().recip(),
            (z2 + x0 * x0).sqrt().recip(),
        );
        let g0 = safe_acos(x1 * y0 * r0 * r1);
        let g1 = safe_acos(-x1 * y1 * r1 * r2);
        let g2 = safe_acos(x0 * y1 * r2 * r3);
        let g3 = safe_acos(-x0 * y0 * r3 * r0);
        let k = TAU - g2 - g3;
        let solid_angle = (g0 + g1 - k).max(0.0);
        Some(Self { o, x, y, z, x0, x1, y0, y1, z0, b0: -y0 * r0, b1: y1 * r2, k, solid_angle })
    }

    /// Steradians the rectangle covers seen from the point.
    #[inline]
    pub fn solid_angle(&self) -> f32 {
        self.solid_angle
    }

    /// The point of the rectangle seen along the direction `u` picks, uniformly over the
    /// solid angle: the first number chooses the angle about the y axis (a strip of the
    /// rectangle parallel to `ey`) in proportion to the strip's solid angle, the second the
    /// height on that strip uniformly in the sine of its elevation.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec3A {
        let Self { x0, x1, y0, y1, z0, b0, b1, .. } = *self;
        let au = u.x * self.solid_angle + self.k;
        let (sin_au, cos_au) = au.sin_cos();
        let fu = (cos_au * b0 - b1) / sin_au;
        let cu = ((fu * fu + b0 * b0).sqrt().recip().copysign(fu)).clamp(-1.0, 1.0);
        let xu = (-(cu * z0) / (1.0 - cu * cu).max(1e-12).sqrt()).clamp(x0, x1);
        let d2 = xu * xu + z0 * z0;
        let h0 = y0 / (d2 + y0 * y0).sqrt();
        let h1 = y1 / (d2 + y1 * y1).sqrt();
        let hv = h0 + u.y * (h1 - h0);
        let hv2 = hv * hv;
        let yv = if hv2 < 1.0 - 1e-6 { (hv * d2.sqrt() / (1.0 - hv2).sqrt()).clamp(y0, y1) } else { y1 };
        self.o + xu * self.x + yv * self.y + z0 * self.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ cos θ/d² dA over the rectangle by the midpoint rule, in f64.
    fn solid_angle_by_quadrature(o: Vec3A, corner: Vec3A, ex: Vec3A, ey: Vec3A, n: usize) -> f64 {
        let normal = ex.cross(ey).normalize().as_dvec3();
        let area = ex.cross(ey).length() as f64 / (n * n) as f64;
        let mut sum = 0.0;
        for i in 0..n * n {
            let (s, t) = (((i % n) as f64 + 0.5) / n as f64, ((i / n) as f64 + 0.5) / n as f64);
            let q = corner.as_dvec3() + s * ex.as_dvec3() + t * ey.as_dvec3();
            let d = q - o.as_dvec3();
            sum += normal.dot(d).abs() / d.length().powi(3) * area;
        }
        sum
    }

    #[test]
    fn solid_angle_matches_quadrature_from_near_far_and_grazing_points() {
        let (corner, ex, ey) = (Vec3A::new(-0.5, 2.0, -0.25), Vec3A::new(1.0, 0.0, 0.0), Vec3A::new(0.0, 0.0, 0.5));
        for o in [
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(0.1, 1.9, 0.0),
            Vec3A::new(3.0, 1.99, 2.0),
            Vec3A::new(0.0, 2.3, 0.0),
            Vec3A::new(40.0, -30.0, 10.0),
        ] {
            let r = SphericalRectangle::new(o, corner, ex, ey).unwrap();
            let q = solid_angle_by_quadrature(o, corner, ex, ey, 2000);
            // f32 round-off in the four angles: about 10⁻⁶ sr whatever the size.
            let error = (r.solid_angle() as f64 - q).abs();
            assert!(error < 1e-6 && (q < 0.01 || error < 1e-5 * q), "{o}: {} against {q}", r.solid_angle());
        }
        assert!(SphericalRectangle::new(Vec3A::new(3.0, 2.0, 0.0), corner, ex, ey).is_none(), "in its plane");
    }

    #[test]
    fn samples_lie_on_the_rectangle_and_corners_map_to_corners() {
        let (corner, ex, ey) = (Vec3A::new(-0.5, 2.0, -0.25), Vec3A::new(0.6, 0.0, 0.8), Vec3A::new(0.0, 0.5, 0.0));
        let r = SphericalRectangle::new(Vec3A::new(0.2, 1.0, 1.5), corner, ex, ey).unwrap();
        let n = ex.cross(ey).normalize();
        for i in 0..=10 {
            for j in 0..=10 {
                let q = r.sample(Vec2::new(i as f32 / 10.0, j as f32 / 10.0));
                let (s, t) = ((q - corner).dot(ex) / ex.length_squared(), (q - corner).dot(ey) / ey.length_squared());
                assert!(
                    (q - corner).dot(n).abs() < 1e-5
                        && (-1e-5..=1.0 + 1e-5).contains(&s)
                        && (-1e-5..=1.0 + 1e-5).contains(&t)
                );
            }
        }
        let at = |u: f32, v: f32| r.sample(Vec2::new(u, v));
        let corners = [corner, corner + ex, corner + ey, corner + ex + ey];
        for q in [at(0.0, 0.0), at(1.0, 0.0), at(0.0, 1.0), at(1.0, 1.0)] {
            assert!(corners.iter().any(|c| (q - *c).length() < 1e-4), "{q}");
        }
    }
}
