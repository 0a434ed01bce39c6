//! Reading texture images (PNG, JPEG, WebP) from files and bytes into [`Image`]s.

use std::path::Path;

use crate::error::{Error, Result};
use crate::material::Image;
use crate::math::UVec2;

/// Decodes the image at `path` to 8-bit RGBA.
pub fn load(path: &Path) -> Result<Image> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    decode(path.display().to_string(), &bytes).map_err(|e| Error::Input {
        path: path.into(),
        message: format!("not a readable PNG, JPEG or WebP image: {e}"),
    })
}

/// Decodes an encoded image (PNG, JPEG or WebP, told by its bytes) to 8-bit RGBA; 16-bit
/// channels keep their top bits.
pub fn decode(name: String, bytes: &[u8]) -> std::result::Result<Image, String> {
    let reader =
        image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format().map_err(|e| e.to_string())?;
    let rgba = reader.decode().map_err(|e| e.to_string())?.into_rgba8();
    Ok(from_rgba8(name, rgba.width(), rgba.height(), rgba.into_raw()))
}

/// An [`Image`] from raw RGBA8 bytes.
pub fn from_rgba8(name: String, width: u32, height: u32, bytes: Vec<u8>) -> Image {
    let texels = bytes.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    Image { name, size: UVec2::new(width, height), texels }
}
