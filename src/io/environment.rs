//! Environment maps: an equirectangular `.exr` or `.hdr` image → [`EnvironmentMap`].

use std::path::Path;

use crate::error::{Error, Result};
use crate::light::EnvironmentMap;
use crate::math::Rgb;

/// Bytes per texel of a loaded map: the radiance and its sampling tables.
const BYTES_PER_TEXEL: u64 = 12 + 8 + 8;

/// Reads the map at `path` (linear radiance; `.exr` RGB or Radiance `.hdr`). Every texel must
/// be finite and non-negative; an image with no light at all is an error too.
pub fn load(path: &Path) -> Result<EnvironmentMap> {
    let bad = |message: String| Error::Input { path: path.into(), message };
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
    let (width, height, texels) = match ext.as_str() {
        "exr" => {
            let (layers, _) = super::exr::read(path)?;
            let rgb = layers.rgb().ok_or_else(|| bad("has no R, G, B channels".into()))?;
            (layers.size.x as usize, layers.size.y as usize, rgb)
        }
        "hdr" => {
            let reader = image::ImageReader::open(path).map_err(|e| Error::io(path, e))?;
            let (w, h) =
                reader.into_dimensions().map_err(|e| bad(format!("not a readable Radiance HDR image: {e}")))?;
            crate::limits::check_memory(w as u64 * h as u64 * BYTES_PER_TEXEL, "this environment map").map_err(&bad)?;
            let img = image::ImageReader::open(path)
                .map_err(|e| Error::io(path, e))?
                .decode()
                .map_err(|e| bad(format!("not a readable Radiance HDR image: {e}")))?
                .into_rgb32f();
            let texels = img.pixels().map(|p| Rgb::new(p[0], p[1], p[2])).collect();
            (w as usize, h as usize, texels)
        }
        _ => return Err(bad(format!("an environment map must be .exr or .hdr, not '.{ext}'"))),
    };
    crate::limits::check_memory((width * height) as u64 * BYTES_PER_TEXEL, "this environment map").map_err(&bad)?;
    if let Some(i) = texels.iter().position(|t: &Rgb| !t.is_finite() || t.min_element() < 0.0) {
        return Err(bad(format!(
            "texel ({}, {}) is {}: radiance must be finite and non-negative",
            i % width,
            i / width,
            texels[i]
        )));
    }
    EnvironmentMap::new(width, height, texels).ok_or_else(|| bad("is black everywhere: it emits no light".into()))
}
