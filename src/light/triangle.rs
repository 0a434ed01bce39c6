//! Emissive triangle, sampled uniformly by area; optionally with an emission texture.

use super::{AreaEmission, AreaPoint, LightSample};
use crate::material::{Image, TextureRef, texture::mean_over_triangle};
use crate::math::warp::square_to_triangle;
use crate::math::{Rgb, Vec2, Vec3A};

/// An emission texture on a triangle light: radiance = factor × texture(uv).
#[derive(Clone, Debug)]
pub struct EmissionTexture {
    /// How the texture is read.
    pub texture: TextureRef,
    /// Texture coordinates of the three vertices.
    pub uv: [Vec2; 3],
    /// Mean texture colour over the triangle (sRGB-decoded): sets power and bounds.
    pub mean: Rgb,
}

/// One emissive triangle (world space).
#[derive(Clone, Debug)]
pub struct TriangleLight {
    /// Vertices, counter-clockwise seen from the front.
    pub v: [Vec3A; 3],
    /// Unit front normal.
    pub n: Vec3A,
    /// Area.
    pub area: f32,
    /// Emission (its radiance is the factor a texture multiplies).
    pub emission: AreaEmission,
    /// Emission texture, if any (boxed: most lights have none).
    pub texture: Option<Box<EmissionTexture>>,
}

/// Smallest mean texture value a textured emitter is given, relative to its factor: an
/// emitter whose texture is black where we looked must not vanish from sampling (its pmf
/// would be 0 where it may still contribute).
const MIN_TEXTURE_MEAN: f32 = 1e-4;

impl TriangleLight {
    /// A triangle light; `None` when the triangle has no area.
    pub fn new(v: [Vec3A; 3], emission: AreaEmission) -> Option<Self> {
        let c = (v[1] - v[0]).cross(v[2] - v[0]);
        let area = 0.5 * c.length();
        let n = c.try_normalize()?;
        (area > 0.0 && area.is_finite()).then_some(Self { v, n, area, emission, texture: None })
    }

    /// Adds an emission texture of `images` read at vertex coordinates `uv`.
    pub fn with_texture(mut self, texture: TextureRef, uv: [Vec2; 3], images: &[Image]) -> Self {
        let mean = mean_over_triangle(&texture, images, uv).max(Rgb::splat(MIN_TEXTURE_MEAN));
        self.texture = Some(Box::new(EmissionTexture { texture, uv, mean }));
        self
    }

    /// Radiance factor at barycentrics (b1, b2) or, for a hit, at texture coordinates `uv`.
    #[inline]
    fn radiance_at(&self, images: &[Image], uv: impl FnOnce(&EmissionTexture) -> Vec2) -> Rgb {
        match &self.texture {
            None => self.emission.radiance,
            Some(t) => self.emission.radiance * Rgb::from(t.texture.sample_srgb(images, uv(t)).truncate()),
        }
    }

    /// Mean radiance over the triangle (power and bounds).
    pub fn mean_radiance(&self) -> Rgb {
        self.texture.as_ref().map_or(self.emission.radiance, |t| self.emission.radiance * t.mean)
    }

    /// Radiance leaving the triangle at texture coordinates `uv` towards `w` (a texture
    /// reads `images`, the scene's).
    #[inline]
    pub fn emitted(&self, uv: Vec2, w: Vec3A, images: &[Image]) -> Rgb {
        let e = AreaEmission { radiance: self.radiance_at(images, |_| uv), ..self.emission };
        e.radiance_towards(self.n, w)
    }

    /// The point `u` chooses uniformly by area (a texture reads `images`).
    #[inline]
    pub fn area_point(&self, u: Vec2, images: &[Image]) -> AreaPoint {
        let [b0, b1, b2] = square_to_triangle(u);
        let q = self.v[0] * b0 + self.v[1] * b1 + self.v[2] * b2;
        let e = AreaEmission {
            radiance: self.radiance_at(images, |t| t.uv[0] * b0 + t.uv[1] * b1 + t.uv[2] * b2),
            ..self.emission
        };
        AreaPoint { p: q, n: self.n, pdf: 1.0 / self.area, emission: e }
    }

    /// Uniform-area sample seen from `p` (a texture reads `images`).
    #[inline]
    pub fn sample_li(&self, p: Vec3A, u: Vec2, images: &[Image]) -> Option<LightSample> {
        let a = self.area_point(u, images);
        a.emission.sample_at(p, a.p, self.n, self.area)
    }
}
