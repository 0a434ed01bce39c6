//! Reading texture images (PNG, JPEG) from files into [`Image`]s.

use std::path::Path;

use crate::error::{Error, Result};
use crate::material::Image;
use crate::math::UVec2;

/// Decodes the image at `path` to 8-bit RGBA.
pub fn load(path: &Path) -> Result<Image> {
    let img = image::ImageReader::open(path)
        .map_err(|e| Error::io(path, e))?
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?
        .decode()
        .map_err(|e| Error::Input { path: path.into(), message: format!("not a readable PNG or JPEG image: {e}") })?
        .into_rgba8();
    Ok(from_rgba8(path.display().to_string(), img.width(), img.height(), img.into_raw()))
}

/// An [`Image`] from raw RGBA8 bytes.
pub fn from_rgba8(name: String, width: u32, height: u32, bytes: Vec<u8>) -> Image {
    let texels = bytes.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    Image { name, size: UVec2::new(width, height), texels }
}
