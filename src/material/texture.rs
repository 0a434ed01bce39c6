//! Image textures: decoded pixels shared by every texture that reads them, and the
//! per-material way of reading one (wrap modes, filter, KHR_texture_transform).
//!
//! Pixels are stored as they come (8-bit RGBA, not decoded): colour data (base colour,
//! emission) is decoded from sRGB at lookup through a 256-entry table, data textures (metallic-
//! roughness, normals, alpha) are used linearly. Lookups are bilinear unless the glTF sampler
//! asks for nearest magnification.

use std::sync::OnceLock;

use crate::math::{Rgb, UVec2, Vec2, Vec4, node_position};

/// Decoded image pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Name (file name or glTF image name), for messages.
    pub name: String,
    /// Width and height.
    pub size: UVec2,
    /// RGBA, 8 bits per channel, row-major from the top row (as images are stored).
    pub texels: Vec<[u8; 4]>,
}

/// What happens outside [0, 1] texture coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// Tile (glTF REPEAT, the default).
    #[default]
    Repeat,
    /// Stretch the edge texels (CLAMP_TO_EDGE).
    Clamp,
    /// Tile, mirroring every other copy (MIRRORED_REPEAT).
    Mirror,
}

/// A 2×3 affine map of texture coordinates (KHR_texture_transform: scale, then rotate, then
/// offset).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// Row-major [[a, b, c], [d, e, f]]: u' = a·u + b·v + c, v' = d·u + e·v + f.
    pub m: [f32; 6],
}

impl Default for UvTransform {
    fn default() -> Self {
        Self { m: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0] }
    }
}

impl UvTransform {
    /// The KHR_texture_transform matrix T·R·S.
    pub fn from_khr(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Self {
        let (s, c) = rotation.sin_cos();
        // R = [[c, s], [-s, c]] as the extension's reference matrix writes it.
        Self { m: [c * scale[0], s * scale[1], offset[0], -s * scale[0], c * scale[1], offset[1]] }
    }

    /// Applies the map.
    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let m = &self.m;
        Vec2::new(m[0] * uv.x + m[1] * uv.y + m[2], m[3] * uv.x + m[4] * uv.y + m[5])
    }
}

/// How a material reads an image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index of the image.
    pub image: u32,
    /// Wrap mode in u and v.
    pub wrap: [Wrap; 2],
    /// Nearest-texel lookups (glTF magFilter NEAREST) instead of bilinear.
    pub nearest: bool,
    /// Texture-coordinate transform.
    pub transform: UvTransform,
}

impl TextureRef {
    /// A repeating, bilinear, untransformed reference to `image`.
    pub fn plain(image: u32) -> Self {
        Self { image, wrap: [Wrap::Repeat; 2], nearest: false, transform: UvTransform::default() }
    }

    /// The raw texel value (each channel in [0, 1], not colour-decoded) at `uv`.
    #[inline]
    pub fn sample(&self, images: &[Image], uv: Vec2) -> Vec4 {
        let img = &images[self.image as usize];
        let uv = self.transform.apply(uv);
        let (w, h) = (img.size.x as i64, img.size.y as i64);
        // Wrapped once per row and column, not per texel (a wrap may divide).
        let fetch = |x: i64, y: i64| {
            let t = img.texels[(y * w + x) as usize];
            Vec4::new(t[0] as f32, t[1] as f32, t[2] as f32, t[3] as f32) * (1.0 / 255.0)
        };
        let (x, y) = (uv.x * w as f32 - 0.5, uv.y * h as f32 - 0.5);
        if self.nearest {
            let (x, y) = ((x + 0.5).floor() as i64, (y + 0.5).floor() as i64);
            return fetch(wrap(x, w, self.wrap[0]), wrap(y, h, self.wrap[1]));
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let (xa, xb) = (wrap(x0, w, self.wrap[0]), wrap(x0 + 1, w, self.wrap[0]));
        let (ya, yb) = (wrap(y0, h, self.wrap[1]), wrap(y0 + 1, h, self.wrap[1]));
        let top = fetch(xa, ya).lerp(fetch(xb, ya), fx);
        let bottom = fetch(xa, yb).lerp(fetch(xb, yb), fx);
        top.lerp(bottom, fy)
    }

    /// Colour at `uv`, decoded from sRGB to linear (alpha untouched), for base colour and
    /// emission. Decoding happens per texel before filtering would be exact; decoding the
    /// filtered value is what real-time renderers do and differs only across edges.
    #[inline]
    pub fn sample_srgb(&self, images: &[Image], uv: Vec2) -> Vec4 {
        let v = self.sample(images, uv);
        Vec4::new(srgb_to_linear(v.x), srgb_to_linear(v.y), srgb_to_linear(v.z), v.w)
    }
}

#[inline]
fn wrap(i: i64, n: i64, mode: Wrap) -> i64 {
    // Inside the image every mode is the identity (and most lookups are inside).
    if (0..n).contains(&i) {
        return i;
    }
    match mode {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Mirror => {
            let p = i.rem_euclid(2 * n);
            if p < n { p } else { 2 * n - 1 - p }
        }
    }
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1).
#[inline]
pub fn srgb_to_linear(x: f32) -> f32 {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    let exact = |x: f32| if x <= 0.04045 { x / 12.92 } else { ((x + 0.055) / 1.055).powf(2.4) };
    let table = TABLE.get_or_init(|| std::array::from_fn(|i| exact(i as f32 / 255.0)));
    // Texels are k/255: exact table hits; filtered values interpolate between entries.
    let (i, t) = node_position::<256>(x);
    let (lo, hi) = (table[i], table[i + 1]);
    lo * (1.0 - t) + hi * t
}

/// The mean colour of `tex` (sRGB-decoded) over the triangle with texture coordinates
/// `uv`, from 64 stratified lookups: the power of a textured emitter.
pub fn mean_over_triangle(tex: &TextureRef, images: &[Image], uv: [Vec2; 3]) -> Rgb {
    let n = 8;
    let mut sum = Vec4::ZERO;
    for i in 0..n * n {
        let u = Vec2::new(((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32);
        let b = crate::math::warp::square_to_triangle(u);
        sum += tex.sample_srgb(images, uv[0] * b[0] + uv[1] * b[1] + uv[2] * b[2]);
    }
    Rgb::from(sum.truncate()) / (n * n) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Vec<Image> {
        // 2 × 2: black, white / white, black.
        let (b, w) = ([0, 0, 0, 255], [255, 255, 255, 255]);
        vec![Image { name: "checker".into(), size: UVec2::new(2, 2), texels: vec![b, w, w, b] }]
    }

    #[test]
    fn bilinear_and_nearest_lookups() {
        let imgs = checker();
        let t = TextureRef::plain(0);
        assert_eq!(t.sample(&imgs, Vec2::new(0.25, 0.25)).x, 0.0);
        assert_eq!(t.sample(&imgs, Vec2::new(0.75, 0.25)).x, 1.0);
        // The centre blends all four texels.
        assert!((t.sample(&imgs, Vec2::splat(0.5)).x - 0.5).abs() < 1e-6);
        let n = TextureRef { nearest: true, ..t };
        assert_eq!(n.sample(&imgs, Vec2::new(0.6, 0.4)).x, 1.0);
        // Repeat wraps; clamp does not.
        assert_eq!(t.sample(&imgs, Vec2::new(1.25, 0.25)).x, 0.0);
        let c = TextureRef { wrap: [Wrap::Clamp; 2], ..t };
        assert_eq!(c.sample(&imgs, Vec2::new(7.0, 0.25)).x, 1.0);
        assert_eq!(wrap(-1, 4, Wrap::Mirror), 0);
        assert_eq!(wrap(4, 4, Wrap::Mirror), 3);
    }

    #[test]
    fn texture_transform_matches_the_extension() {
        // Scale 2 then offset 0.5: u' = 2u + 0.5.
        let t = UvTransform::from_khr([0.5, 0.0], 0.0, [2.0, 1.0]);
        assert_eq!(t.apply(Vec2::new(0.25, 0.5)), Vec2::new(1.0, 0.5));
        // A quarter turn maps (1, 0) to (0, -1) in the extension's convention.
        let r = UvTransform::from_khr([0.0, 0.0], std::f32::consts::FRAC_PI_2, [1.0, 1.0]);
        assert!((r.apply(Vec2::X) - Vec2::new(0.0, -1.0)).length() < 1e-6);
    }

    #[test]
    fn srgb_decoding() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214).abs() < 1e-3);
        let imgs = checker();
        let m = mean_over_triangle(&TextureRef::plain(0), &imgs, [Vec2::ZERO, Vec2::X, Vec2::Y]);
        assert!(m.x > 0.2 && m.x < 0.8, "{m}");
    }
}
