//! `KHR_draco_mesh_compression`: a primitive whose attributes and indices are one Draco
//! bitstream in a buffer view (Blender's exporter with Compression on), decoded with the
//! pure-Rust `draco-core` decoder (no C++ to build; it reads Google's format, EdgeBreaker
//! and sequential, and refuses absurd declared sizes through its decode limits, which are
//! set here from myriad's memory limit).
//!
//! The extension maps each glTF attribute to a Draco attribute by its unique id; the
//! primitive's accessors still give counts and types, and the decoded values are what the
//! uncompressed accessors would hold.

use draco_core::{DecodeLimits, DecoderBuffer, Mesh, MeshDecoder};
use gltf::json::Value;

use super::accessor::Views;

/// The extension's name.
pub const NAME: &str = "KHR_draco_mesh_compression";

/// A decoded primitive: per-point positions, normals and texture coordinates, and the
/// triangles' corners as point indices.
pub struct Decoded {
    pub positions: Vec<[f32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    pub uvs: Option<Vec<[f32; 2]>>,
    pub indices: Vec<u32>,
}

/// Decodes the primitive whose extension object is `ext`.
pub fn decode(doc: &gltf::Document, views: &Views, ext: &Value) -> Result<Decoded, String> {
    let view = ext
        .get("bufferView")
        .and_then(Value::as_u64)
        .and_then(|v| doc.views().nth(v as usize))
        .ok_or("its Draco extension names no buffer view that exists")?;
    let attribute = |name: &str| ext.get("attributes").and_then(|a| a.get(name)).and_then(Value::as_u64);
    let limits = DecodeLimits::default().with_max_decoded_bytes(crate::limits::memory_limit().bytes);
    let mut buffer = DecoderBuffer::new(views.bytes(&view)?).with_limits(limits);
    let mut mesh = Mesh::new();
    MeshDecoder::new()
        .decode(&mut buffer, &mut mesh)
        .map_err(|e| format!("holds a Draco stream that does not decode: {e}"))?;
    let points = mesh.num_points();
    let read = |id: u64, n: usize| -> Result<Vec<f32>, String> {
        let a = mesh.attribute_by_unique_id(id as u32).ok_or(format!("its Draco stream has no attribute {id}"))?;
        Ok(a.read_f32s(points, n))
    };
    let id = attribute("POSITION").ok_or("its Draco extension maps no POSITION")?;
    let positions = read(id, 3)?.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let normals = attribute("NORMAL").map(|id| read(id, 3)).transpose()?;
    let uvs = attribute("TEXCOORD_0").map(|id| read(id, 2)).transpose()?;
    let indices = mesh.faces().iter().flat_map(|f| f.map(|p| p.0)).collect();
    Ok(Decoded {
        positions,
        normals: normals.map(|v| v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()),
        uvs: uvs.map(|v| v.chunks_exact(2).map(|c| [c[0], c[1]]).collect()),
        indices,
    })
}
