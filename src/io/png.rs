//! PNG previews: exposure, clamp, the sRGB transfer curve, 8 bits per channel.

use std::path::Path;

use crate::error::{Error, Result};
use crate::math::{Rgb, UVec2};

/// The sRGB opto-electronic transfer function (IEC 61966-2-1) of a linear value in [0,1].
#[inline]
pub fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 }
}

/// Linear colours → 8-bit sRGB bytes at exposure `2^stops`.
pub fn to_srgb8(pixels: &[Rgb], stops: f32) -> Vec<u8> {
    let scale = 2f32.powf(stops);
    pixels
        .iter()
        .flat_map(|p| {
            let c = (*p * scale).to_array();
            c.map(|v| (srgb_encode(if v.is_finite() { v.clamp(0.0, 1.0) } else { 0.0 }) * 255.0 + 0.5) as u8)
        })
        .collect()
}

/// Writes a preview of linear `pixels` (row-major, top row first) atomically.
pub fn write(path: &Path, size: UVec2, pixels: &[Rgb], stops: f32) -> Result<()> {
    write_srgb8(path, size, to_srgb8(pixels, stops))
}

/// Writes already-encoded 8-bit RGB bytes as a PNG, atomically.
pub fn write_srgb8(path: &Path, size: UVec2, bytes: Vec<u8>) -> Result<()> {
    let img = image::RgbImage::from_raw(size.x, size.y, bytes).ok_or_else(|| Error::Output {
        path: path.into(),
        message: "pixel count does not match the image size".into(),
    })?;
    super::write_atomically(path, |tmp| {
        img.save_with_format(tmp, image::ImageFormat::Png)
            .map_err(|e| Error::Output { path: path.into(), message: format!("PNG write failed: {e}") })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_curve_endpoints_and_midpoint() {
        assert_eq!(to_srgb8(&[Rgb::ZERO, Rgb::ONE, Rgb::splat(4.0)], 0.0), vec![0, 0, 0, 255, 255, 255, 255, 255, 255]);
        // Linear 0.2159 is sRGB 0.502 (128/255 after rounding); one stop up doubles it.
        assert_eq!(to_srgb8(&[Rgb::splat(0.2159)], 0.0)[0], 128);
        assert_eq!(to_srgb8(&[Rgb::splat(0.10795)], 1.0)[0], 128);
    }
}
