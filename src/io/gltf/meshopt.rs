//! `EXT_meshopt_compression` and `KHR_meshopt_compression`: buffer views stored compressed
//! by meshoptimizer (gltfpack's and glTF-Transform's `meshopt` output), decoded with the
//! `meshopt` crate's bindings to meshoptimizer itself (its decoders are documented safe on
//! untrusted input: a corrupt stream is an error code, never a read out of bounds).
//!
//! A compressed view names its source bytes (buffer, offset, length), the element count and
//! stride it decodes to, a mode (vertex attributes, triangle indices, index sequences) and a
//! filter applied after decoding (octahedral normals, quaternions, exponent-mantissa floats,
//! colours). Its own buffer may be a placeholder without data (`fallback`), which
//! [`fallback_buffer`] recognises so that importing the buffers does not fail on it.

use std::collections::HashMap;

use gltf::json::Value;

/// The two names of the extension.
pub const NAMES: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// The extension object of `extensions`, under either name.
fn extension(extensions: Option<&serde_json::Map<String, Value>>) -> Option<&Value> {
    let e = extensions?;
    NAMES.iter().find_map(|n| e.get(*n))
}

/// Whether `buffer` is a placeholder the extension fills (it has no data of its own).
pub fn fallback_buffer(buffer: &gltf::Buffer) -> bool {
    extension(buffer.extensions()).and_then(|e| e.get("fallback")).and_then(Value::as_bool) == Some(true)
}

#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Compressed {
    buffer: usize,
    #[serde(default)]
    byte_offset: usize,
    byte_length: usize,
    byte_stride: usize,
    count: usize,
    mode: String,
    #[serde(default)]
    filter: Option<String>,
}

/// Every compressed view's decoded bytes, by view index. Errors name the view.
pub fn decode_views(
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
) -> Result<HashMap<usize, Vec<u8>>, (String, String)> {
    let mut out = HashMap::new();
    for view in doc.views() {
        let Some(ext) = extension(view.extensions()) else { continue };
        let at = format!("bufferViews[{}]", view.index());
        let c: Compressed = serde_json::from_value(ext.clone())
            .map_err(|e| (at.clone(), format!("has a malformed meshopt extension: {e}")))?;
        out.insert(view.index(), decode(&c, buffers).map_err(|m| (at, m))?);
    }
    Ok(out)
}

fn decode(c: &Compressed, buffers: &[gltf::buffer::Data]) -> Result<Vec<u8>, String> {
    let source = buffers
        .get(c.buffer)
        .and_then(|b| b.0.get(c.byte_offset..c.byte_offset.checked_add(c.byte_length)?))
        .ok_or_else(|| {
            format!("its compressed bytes (buffer {}, {} bytes) lie outside the buffers", c.buffer, c.byte_length)
        })?;
    let size = c.count.checked_mul(c.byte_stride).ok_or("declares a size beyond what memory holds")?;
    crate::limits::check_memory(size as u64, format_args!("a meshopt view of {} elements", c.count))?;
    let mut out = vec![0u8; size];
    let (dst, src) = (out.as_mut_ptr().cast(), source.as_ptr());
    let code = match (c.mode.as_str(), c.byte_stride) {
        ("ATTRIBUTES", s) if s.is_multiple_of(4) && (4..=256).contains(&s) => {
            // SAFETY: `out` holds count × stride bytes, `source` is a live slice.
            unsafe { meshopt::ffi::meshopt_decodeVertexBuffer(dst, c.count, s, src, source.len()) }
        }
        ("TRIANGLES", 2 | 4) if c.count.is_multiple_of(3) => {
            // SAFETY: as above.
            unsafe { meshopt::ffi::meshopt_decodeIndexBuffer(dst, c.count, c.byte_stride, src, source.len()) }
        }
        ("INDICES", 2 | 4) => {
            // SAFETY: as above.
            unsafe { meshopt::ffi::meshopt_decodeIndexSequence(dst, c.count, c.byte_stride, src, source.len()) }
        }
        (mode, stride) => {
            return Err(format!(
                "has meshopt mode {mode} with byteStride {stride}, which the extension does not allow"
            ));
        }
    };
    if code != 0 {
        return Err(format!("holds a corrupt meshopt stream (meshoptimizer's decoder says {code})"));
    }
    let filter = c.filter.as_deref().unwrap_or("NONE");
    let (dst, count, stride) = (out.as_mut_ptr().cast(), c.count, c.byte_stride);
    match (filter, stride) {
        ("NONE", _) => {}
        // SAFETY: each filter rewrites count × stride bytes of `out` in place, with the
        // stride the extension requires of it (checked here).
        ("OCTAHEDRAL", 4 | 8) => unsafe { meshopt::ffi::meshopt_decodeFilterOct(dst, count, stride) },
        ("QUATERNION", 8) => unsafe { meshopt::ffi::meshopt_decodeFilterQuat(dst, count, stride) },
        ("EXPONENTIAL", s) if s.is_multiple_of(4) => unsafe {
            meshopt::ffi::meshopt_decodeFilterExp(dst, count, stride)
        },
        ("COLOR", 4 | 8) => unsafe { meshopt::ffi::meshopt_decodeFilterColor(dst, count, stride) },
        (f, s) => {
            return Err(format!("has meshopt filter {f} with byteStride {s}, which the extension does not allow"));
        }
    }
    Ok(out)
}
