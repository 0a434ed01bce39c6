//! The environment: radiance arriving from infinitely far in every direction, constant or
//! from an equirectangular map, seen by rays that leave the scene and sampled by
//! next-event estimation like any other light (it sits in the light tree beside the suns).
//!
//! Map convention (Blender's, with +Y up as in glTF): the image's centre column looks along
//! +X, columns run towards +Z, the top row is the zenith (+Y). A rotation turns the map about
//! +Y. Maps are importance-sampled by a piecewise-constant density over texels, weighted by
//! luminance × sin θ (the texel's solid angle); each texel's probability is exactly the one
//! its pdf reports ([`Distribution1D`] cells, drawn with 64-bit numbers).

use std::f32::consts::PI;
use std::sync::Arc;

use super::LightSample;
use crate::math::distribution::Distribution1D;
use crate::math::{Rgb, Vec2, Vec3A, luminance, warp};
use crate::sampling::unit_f32;

/// An equirectangular radiance map, ready to be sampled.
#[derive(Debug)]
pub struct EnvironmentMap {
    width: usize,
    height: usize,
    /// Row-major, top row first.
    texels: Vec<Rgb>,
    /// Rows by their total weight.
    rows: Distribution1D,
    /// Within each row, texels by weight (`None` for a row with no light).
    columns: Vec<Option<Distribution1D>>,
    /// Mean radiance over the sphere (solid-angle weighted).
    mean: Rgb,
}

impl EnvironmentMap {
    /// A map of `width × height` texels (row-major, top row first); `None` when it emits
    /// nothing at all. Texels must be finite and non-negative (the loader checks).
    pub fn new(width: usize, height: usize, texels: Vec<Rgb>) -> Option<Self> {
        assert_eq!(texels.len(), width * height, "texel count");
        let sin_theta = |row: usize| (PI * (row as f32 + 0.5) / height as f32).sin();
        let mut row_weights = Vec::with_capacity(height);
        let mut columns = Vec::with_capacity(height);
        let mut mean = Rgb::ZERO;
        let mut solid_angle = 0.0f32;
        for (r, row) in texels.chunks_exact(width).enumerate() {
            let weights: Vec<f32> = row.iter().map(|&t| luminance(t) * sin_theta(r)).collect();
            row_weights.push(weights.iter().map(|&w| w as f64).sum::<f64>() as f32);
            columns.push(Distribution1D::new(&weights));
            mean += row.iter().fold(Rgb::ZERO, |a, &t| a + t) * sin_theta(r);
            solid_angle += sin_theta(r) * width as f32;
        }
        let rows = Distribution1D::new(&row_weights)?;
        Some(Self { width, height, texels, rows, columns, mean: mean / solid_angle })
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.texels.capacity() * std::mem::size_of::<Rgb>()
            + self.rows.memory_bytes()
            + self.columns.iter().flatten().map(Distribution1D::memory_bytes).sum::<usize>()
    }

    /// The texel a map coordinate `(u, v) ∈ [0,1)²` falls in, as (column, row).
    fn texel(&self, uv: Vec2) -> (usize, usize) {
        let c = ((uv.x * self.width as f32) as usize).min(self.width - 1);
        let r = ((uv.y * self.height as f32) as usize).min(self.height - 1);
        (c, r)
    }
}

/// The environment light.
#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    /// Constant radiance, or the factor the map is multiplied by.
    pub radiance: Rgb,
    /// The map, when not constant.
    pub map: Option<Arc<EnvironmentMap>>,
    /// Rotation about +Y, radians (the map turns with it).
    pub rotation: f32,
}

/// Map coordinates of a unit direction in the map's own frame.
fn direction_to_uv(d: Vec3A) -> Vec2 {
    let u = 0.5 + d.z.atan2(d.x) / (2.0 * PI);
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    Vec2::new(u.rem_euclid(1.0), v)
}

/// The unit direction at map coordinates `uv`, and sin θ there.
fn uv_to_direction(uv: Vec2) -> (Vec3A, f32) {
    let (phi, theta) = (2.0 * PI * (uv.x - 0.5), PI * uv.y);
    let (sin_t, cos_t) = theta.sin_cos();
    (Vec3A::new(sin_t * phi.cos(), cos_t, sin_t * phi.sin()), sin_t)
}

impl EnvironmentLight {
    /// World direction → the map's frame (undoing the rotation), and back.
    fn to_map(&self, d: Vec3A) -> Vec3A {
        let (s, c) = self.rotation.sin_cos();
        Vec3A::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    fn to_world(&self, d: Vec3A) -> Vec3A {
        let (s, c) = self.rotation.sin_cos();
        Vec3A::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
    }

    /// Radiance arriving from direction `dir` (unit, pointing away from the scene).
    #[inline]
    pub fn radiance_from(&self, dir: Vec3A) -> Rgb {
        match &self.map {
            None => self.radiance,
            Some(m) => {
                let (c, r) = m.texel(direction_to_uv(self.to_map(dir)));
                self.radiance * m.texels[r * m.width + c]
            }
        }
    }

    /// A direction towards the environment from two 64-bit numbers: uniform over the sphere
    /// for a constant one, by the map's density otherwise.
    #[inline]
    pub fn sample_li(&self, u: [u64; 2]) -> Option<LightSample> {
        let (wi, pdf) = match &self.map {
            None => {
                let wi = warp::square_to_uniform_sphere(Vec2::new(unit_f32(u[0]), unit_f32(u[1])));
                (wi, warp::UNIFORM_SPHERE_PDF)
            }
            Some(m) => {
                let row = m.rows.sample(u[1]);
                let col = m.columns[row.index].as_ref()?.sample(u[0]);
                let uv = Vec2::new(
                    (col.index as f32 + col.offset) / m.width as f32,
                    (row.index as f32 + row.offset) / m.height as f32,
                );
                let (d, sin_t) = uv_to_direction(uv);
                if !(sin_t > 0.0) {
                    return None;
                }
                let pdf_uv = row.pmf * col.pmf * (m.width * m.height) as f32;
                (self.to_world(d), pdf_uv / (2.0 * PI * PI * sin_t))
            }
        };
        let radiance = self.radiance_from(wi);
        Some(LightSample { radiance, wi, distance: f32::INFINITY, pdf, p: Vec3A::ZERO, n: Vec3A::ZERO })
    }

    /// Solid-angle density with which [`sample_li`](Self::sample_li) picks direction `dir`.
    #[inline]
    pub fn pdf(&self, dir: Vec3A) -> f32 {
        match &self.map {
            None => warp::UNIFORM_SPHERE_PDF,
            Some(m) => {
                let d = self.to_map(dir);
                let (c, r) = m.texel(direction_to_uv(d));
                let Some(cols) = &m.columns[r] else { return 0.0 };
                // Accurate near the poles, where 1 − y² is not.
                let sin_t = (d.x * d.x + d.z * d.z).sqrt();
                if !(sin_t > 0.0) {
                    return 0.0;
                }
                let pdf_uv = m.rows.pmf(r) * cols.pmf(c) * (m.width * m.height) as f32;
                pdf_uv / (2.0 * PI * PI * sin_t)
            }
        }
    }

    /// Mean radiance over all directions.
    pub fn mean_radiance(&self) -> Rgb {
        self.radiance * self.map.as_ref().map_or(Rgb::ONE, |m| m.mean)
    }

    /// Flux per channel through a disk of the scene's bounding radius: π·r² times the
    /// irradiance a uniform environment of the mean radiance gives, π·L̄.
    pub fn flux(&self, scene_radius: f32) -> Rgb {
        PI * scene_radius * scene_radius * PI * self.mean_radiance()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_and_map_coordinates_round_trip() {
        for k in 0..200 {
            let uv = Vec2::new((k as f32 * 0.618).fract(), (k as f32 + 0.5) / 200.0);
            let (d, _) = uv_to_direction(uv);
            let back = direction_to_uv(d);
            assert!((back - uv).abs().max_element() < 1e-4 || (back.x - uv.x).abs() > 0.999, "{uv} → {d} → {back}");
        }
        // The centre looks along +X, the top row is +Y.
        assert!((uv_to_direction(Vec2::new(0.5, 0.5)).0 - Vec3A::X).length() < 1e-6);
        assert!(direction_to_uv(Vec3A::Y).y < 1e-6);
        let light = EnvironmentLight { radiance: Rgb::ONE, map: None, rotation: 0.7 };
        let d = Vec3A::new(0.3, 0.5, -0.8).normalize();
        assert!((light.to_world(light.to_map(d)) - d).length() < 1e-6);
    }
}
