//! OpenEXR output and input, through the `exr` crate.
//!
//! Writes one single-part, scan-line, ZIP16-compressed file whose channels are f32 (the
//! layout every compositor reads, checked against the reference OpenEXR library;
//! docs/conventions.md), with provenance as text attributes (`myriad.sampler`, `myriad.spp`, …). Reads
//! any flat EXR back as named f32 channels, for references and `diff`.

use std::path::Path;

use exr::prelude::*;

use crate::error::{Error, Result};
use crate::image::{Channel, Layers};
use crate::math::UVec2;

/// Writes `layers` to `path` atomically, with `metadata` as text header attributes.
pub fn write(path: &Path, layers: &Layers, metadata: &[(String, String)]) -> Result<()> {
    let size = (layers.size.x as usize, layers.size.y as usize);
    let channels: Vec<AnyChannel<FlatSamples>> =
        layers.channels.iter().map(|c| AnyChannel::new(c.name.as_str(), FlatSamples::F32(c.data.clone()))).collect();
    let mut attributes = LayerAttributes {
        software_name: Some(Text::from(concat!("myriad ", env!("CARGO_PKG_VERSION")))),
        ..Default::default()
    };
    for (k, v) in metadata {
        attributes.other.insert(Text::from(k.as_str()), AttributeValue::Text(Text::from(v.as_str())));
    }
    let layer = Layer::new(size, attributes, Encoding::SMALL_LOSSLESS, AnyChannels::sort(SmallVec::from_vec(channels)));
    let image = Image::from_layer(layer);
    super::write_atomically(path, |tmp| {
        image
            .write()
            .to_file(tmp)
            .map_err(|e| Error::Output { path: path.into(), message: format!("EXR write failed: {e}") })
    })
}

/// An EXR output's path does not name another picture format (an EXR under a `.png` name
/// would open nowhere).
pub fn check_name(path: &Path) -> Result<()> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if let Some(ext @ ("png" | "jpg" | "jpeg" | "hdr" | "tif" | "tiff" | "webp")) = ext.as_deref() {
        return Err(Error::Usage(format!(
            "-o {} would write an EXR image under a .{ext} name; give -o a .exr path (a PNG preview goes \
             beside it)",
            path.display()
        )));
    }
    Ok(())
}

/// What went wrong reading `path`: a file that cannot be opened says why; one that opens but
/// does not parse, or ends early (the exr crate reports a truncated or corrupt file as an I/O
/// error too), is named as damaged.
fn read_error(path: &Path, e: exr::error::Error) -> Error {
    use std::io::ErrorKind::{NotFound, PermissionDenied};
    match e {
        exr::error::Error::Io(io) if matches!(io.kind(), NotFound | PermissionDenied) || path.is_dir() => {
            Error::io(path, io)
        }
        exr::error::Error::Io(io) => Error::Input {
            path: path.into(),
            message: format!("is damaged: not a complete EXR image ({io}); render or copy it again"),
        },
        other => Error::Input { path: path.into(), message: format!("not a readable EXR image: {other}") },
    }
}

/// Bytes reading every layer of the file described by `meta` takes: the samples as stored
/// and as f32, and the chunk offset tables.
fn bytes_to_read(meta: &exr::meta::MetaData) -> u64 {
    meta.headers.iter().fold(0u64, |sum, h| {
        let samples =
            (h.layer_size.0 as u64).saturating_mul(h.layer_size.1 as u64).saturating_mul(h.channels.list.len() as u64);
        sum.saturating_add(samples.saturating_mul(8)).saturating_add((h.chunk_count as u64).saturating_mul(8))
    })
}

/// Reads the first layer of an EXR file: its channels (as f32) and text attributes. The
/// header is read first, and an image larger than the memory limit is refused before its
/// pixels are.
pub fn read(path: &Path) -> Result<(Layers, Vec<(String, String)>)> {
    crate::guard::contain(&path.display().to_string(), || read_checked(path))
}

fn read_checked(path: &Path) -> Result<(Layers, Vec<(String, String)>)> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| read_error(path, e))?;
    crate::limits::check_memory(bytes_to_read(&meta), "this EXR image")
        .map_err(|message| Error::Input { path: path.into(), message })?;
    let image = read_all_flat_layers_from_file(path).map_err(|e| read_error(path, e))?;
    let layer = image
        .layer_data
        .first()
        .ok_or_else(|| Error::Input { path: path.into(), message: "the EXR file has no layers".into() })?;
    let channels = layer
        .channel_data
        .list
        .iter()
        .map(|c| Channel { name: c.name.to_string(), data: c.sample_data.values_as_f32().collect() })
        .collect();
    let mut metadata: Vec<(String, String)> = layer
        .attributes
        .other
        .iter()
        .chain(image.attributes.other.iter())
        .filter_map(|(k, v)| match v {
            AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    metadata.sort();
    Ok((Layers { size: UVec2::new(layer.size.0 as u32, layer.size.1 as u32), channels }, metadata))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_keeps_channels_and_metadata() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.exr");
        let layers = Layers {
            size: UVec2::new(3, 2),
            channels: ["R", "G", "B", "Z"]
                .iter()
                .enumerate()
                .map(|(k, n)| Channel {
                    name: n.to_string(),
                    data: (0..6).map(|i| (i * 10 + k) as f32 * 0.5).collect(),
                })
                .collect(),
        };
        let meta =
            vec![("myriad.sampler".to_string(), "power".to_string()), ("myriad.spp".to_string(), "16".to_string())];
        write(&path, &layers, &meta).unwrap();
        let (back, back_meta) = read(&path).unwrap();
        assert_eq!(back.size, layers.size);
        for c in &layers.channels {
            assert_eq!(back.channel(&c.name).unwrap().data, c.data);
        }
        for kv in &meta {
            assert!(back_meta.contains(kv), "{back_meta:?}");
        }
    }

    #[test]
    fn garbage_is_an_error_not_a_panic() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.exr");
        std::fs::write(&path, b"this is not an exr").unwrap();
        assert!(read(&path).is_err());
        assert!(matches!(read(&dir.path().join("missing.exr")), Err(Error::Io { .. })));
    }
}
