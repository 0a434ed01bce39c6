//! What emissive triangles and quads share: radiance, sidedness and the area-to-solid-angle
//! density conversion.

use crate::math::{Rgb, Vec3A};
use std::f32::consts::PI;

/// Emission of a diffuse area light.
#[derive(Clone, Copy, Debug)]
pub struct AreaEmission {
    /// Radiance [W/(m²·sr)], the same in every direction it emits to.
    pub radiance: Rgb,
    /// Emits from both faces; otherwise only from the counter-clockwise (front) face.
    pub two_sided: bool,
}

/// A point chosen by area on an emitting surface: what a connection that does not reach it
/// along a straight line (manifold next-event estimation through glass) starts from.
#[derive(Clone, Copy, Debug)]
pub struct AreaPoint {
    /// The point.
    pub p: Vec3A,
    /// The surface's unit front normal there.
    pub n: Vec3A,
    /// Density per unit area with which it was chosen.
    pub pdf: f32,
    /// What it emits.
    pub emission: AreaEmission,
}

impl AreaEmission {
    /// Radiance leaving a surface of front normal `n` in direction `w` (unit).
    #[inline]
    pub fn radiance_towards(&self, n: Vec3A, w: Vec3A) -> Rgb {
        if self.two_sided || n.dot(w) > 0.0 { self.radiance } else { Rgb::ZERO }
    }

    /// Solid-angle density at `p` of uniformly sampling a point `q` (normal `n_q`) on an
    /// emitter of area `area`: d² / (|cos θq|·A).
    #[inline]
    pub fn pdf_li(&self, p: Vec3A, q: Vec3A, n_q: Vec3A, area: f32) -> f32 {
        let d = q - p;
        let dist2 = d.length_squared();
        let cos = n_q.dot(d).abs() / dist2.sqrt();
        if cos <= 0.0 || dist2 == 0.0 { 0.0 } else { dist2 / (cos * area) }
    }

    /// Emitted flux per channel: π·A·L, doubled when two-sided.
    pub fn flux(&self, area: f32) -> Rgb {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        PI * area * sides * self.radiance
    }

    /// Builds the sample for point `q` (front normal `n`) seen from `p`; `None` when the
    /// emitting side faces away or the geometry is degenerate.
    #[inline]
    pub(super) fn sample_at(&self, p: Vec3A, q: Vec3A, n: Vec3A, area: f32) -> Option<super::LightSample> {
        let d = q - p;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0) {
            return None;
        }
        let dist = dist2.sqrt();
        let wi = d / dist;
        let radiance = self.radiance_towards(n, -wi);
        let cos = n.dot(wi).abs();
        if radiance == Rgb::ZERO || cos <= 0.0 {
            return None;
        }
        let pdf = dist2 / (cos * area);
        let n_facing = if n.dot(wi) > 0.0 { -n } else { n };
        Some(super::LightSample { radiance, wi, distance: dist, pdf, p: q, n: n_facing })
    }
}
