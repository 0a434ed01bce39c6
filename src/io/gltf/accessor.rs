//! Accessors read as the glTF specification defines them, where the `gltf` crate's reader
//! stops short: an accessor without a buffer view is zeros (sparse values may then replace
//! some), sparse substitution applies on top of any base, and the integer component types
//! `KHR_mesh_quantization` allows for positions, normals and texture coordinates are read
//! as their values or, when `normalized`, as the specification's
//! `max(c / (2ᵇ⁻¹ − 1), −1)` (signed) or `c / (2ᵇ − 1)` (unsigned).
//!
//! Buffer views come from [`Views`], which holds the bytes `EXT_meshopt_compression` (and
//! `KHR_meshopt_compression`) views decode to. Sizes were checked against the views by
//! `check.rs` before anything is read; every read here is bounds-checked again, so a view
//! that decodes shorter than declared is an error, not a panic.

use std::collections::HashMap;

use gltf::accessor::{DataType, Dimensions};

/// Bytes behind each buffer view: the file's, or what a compressed view decodes to.
pub struct Views<'a> {
    buffers: &'a [gltf::buffer::Data],
    decoded: HashMap<usize, Vec<u8>>,
}

impl<'a> Views<'a> {
    /// The views of `buffers`, with `decoded` views (by index) replacing theirs.
    pub fn new(buffers: &'a [gltf::buffer::Data], decoded: HashMap<usize, Vec<u8>>) -> Self {
        Self { buffers, decoded }
    }

    /// The bytes of `view` (empty where they lie outside its buffer), or why there are none:
    /// its buffer holds no data at all.
    pub fn bytes(&self, view: &gltf::buffer::View) -> Result<&[u8], String> {
        if let Some(d) = self.decoded.get(&view.index()) {
            return Ok(d);
        }
        let index = view.buffer().index();
        let buffer = self.buffers.get(index).map_or(&[][..], |b| &b.0[..]);
        if buffer.is_empty() && view.length() > 0 {
            return Err(format!(
                "reads buffer {index}, which holds no data: it has no uri and the file is no GLB with a binary \
                 chunk, or its uri is one myriad does not fetch (http:)"
            ));
        }
        Ok(buffer.get(view.offset()..view.offset().saturating_add(view.length())).unwrap_or(&[]))
    }
}

/// The component at byte `at` of `bytes`, as f32.
fn component(bytes: &[u8], ty: DataType, normalized: bool, at: usize) -> Option<f32> {
    let b = bytes.get(at..at + ty.size())?;
    Some(match ty {
        DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        DataType::I8 => signed(b[0] as i8 as f32, 127.0, normalized),
        DataType::U8 => unsigned(b[0] as f32, 255.0, normalized),
        DataType::I16 => signed(i16::from_le_bytes([b[0], b[1]]) as f32, 32767.0, normalized),
        DataType::U16 => unsigned(u16::from_le_bytes([b[0], b[1]]) as f32, 65535.0, normalized),
        DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
    })
}

fn signed(v: f32, max: f32, normalized: bool) -> f32 {
    if normalized { (v / max).max(-1.0) } else { v }
}

fn unsigned(v: f32, max: f32, normalized: bool) -> f32 {
    if normalized { v / max } else { v }
}

/// An element's layout: `n` components of type `ty`, normalised or not.
#[derive(Clone, Copy)]
struct Element {
    ty: DataType,
    n: usize,
    normalized: bool,
}

/// Fills `out` (whole elements) from view `view`, the first element at `offset`.
fn read_dense(
    views: &Views,
    view: &gltf::buffer::View,
    offset: usize,
    e: Element,
    out: &mut [f32],
) -> Result<(), String> {
    let bytes = views.bytes(view)?;
    let size = e.ty.size();
    let stride = view.stride().unwrap_or(e.n * size);
    for (i, element) in out.chunks_exact_mut(e.n).enumerate() {
        for (c, o) in element.iter_mut().enumerate() {
            let at = offset + i * stride + c * size;
            *o = component(bytes, e.ty, e.normalized, at)
                .ok_or("its data lies outside its buffer view: the file is truncated or corrupt")?;
        }
    }
    Ok(())
}

/// The accessor's elements as `D` floats each, in order. `expect` lists the component
/// types the caller accepts (beyond which the element would be meaningless).
pub fn floats<const D: usize>(
    views: &Views,
    acc: &gltf::Accessor,
    expect: &[DataType],
) -> Result<Vec<[f32; D]>, String> {
    let (ty, n) = (acc.data_type(), acc.dimensions().multiplicity());
    if n != D || !expect.contains(&ty) {
        return Err(format!("is {:?} of {ty:?}; expected {D} components of {expect:?}", acc.dimensions()));
    }
    let (count, e) = (acc.count(), Element { ty, n, normalized: acc.normalized() });
    let mut flat = vec![0.0f32; count * D];
    if let Some(view) = acc.view() {
        read_dense(views, &view, acc.offset(), e, &mut flat)?;
    }
    if let Some(sparse) = acc.sparse() {
        let at = sparse_indices(views, &sparse, count)?;
        let mut values = vec![0.0f32; at.len() * D];
        let v = sparse.values();
        read_dense(views, &v.view(), v.offset(), e, &mut values).map_err(|e| format!("sparse values: {e}"))?;
        for (k, &i) in at.iter().enumerate() {
            flat[i * D..(i + 1) * D].copy_from_slice(&values[k * D..(k + 1) * D]);
        }
    }
    Ok(flat.chunks_exact(D).map(|c| std::array::from_fn(|k| c[k])).collect())
}

/// The accessor's elements as vertex indices (unsigned bytes, shorts or ints).
pub fn indices(views: &Views, acc: &gltf::Accessor) -> Result<Vec<u32>, String> {
    let ty = acc.data_type();
    if acc.dimensions() != Dimensions::Scalar || !matches!(ty, DataType::U8 | DataType::U16 | DataType::U32) {
        return Err(format!("is {:?} of {ty:?}; indices are scalars of U8, U16 or U32", acc.dimensions()));
    }
    // u32 values do not survive f32: read them as integers.
    let count = acc.count();
    let mut out = vec![0u32; count];
    let read = |bytes: &[u8], stride: usize, offset: usize, out: &mut [u32]| -> Result<(), String> {
        for (i, o) in out.iter_mut().enumerate() {
            *o = unsigned_int(bytes, ty, offset + i * stride)
                .ok_or("its data lies outside its buffer view: the file is truncated or corrupt")?;
        }
        Ok(())
    };
    if let Some(view) = acc.view() {
        read(views.bytes(&view)?, view.stride().unwrap_or(ty.size()), acc.offset(), &mut out)?;
    }
    if let Some(sparse) = acc.sparse() {
        let at = sparse_indices(views, &sparse, count)?;
        let v = sparse.values();
        let mut values = vec![0u32; at.len()];
        read(views.bytes(&v.view())?, ty.size(), v.offset(), &mut values).map_err(|e| format!("sparse values: {e}"))?;
        for (&i, &x) in at.iter().zip(&values) {
            out[i] = x;
        }
    }
    Ok(out)
}

fn unsigned_int(bytes: &[u8], ty: DataType, at: usize) -> Option<u32> {
    let b = bytes.get(at..at + ty.size())?;
    Some(match ty {
        DataType::U8 => b[0] as u32,
        DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    })
}

/// The element indices a sparse accessor replaces, each checked against `count`.
fn sparse_indices(views: &Views, sparse: &gltf::accessor::sparse::Sparse, count: usize) -> Result<Vec<usize>, String> {
    use gltf::accessor::sparse::IndexType;
    let idx = sparse.indices();
    let ty = match idx.index_type() {
        IndexType::U8 => DataType::U8,
        IndexType::U16 => DataType::U16,
        IndexType::U32 => DataType::U32,
    };
    let bytes = views.bytes(&idx.view())?;
    (0..sparse.count())
        .map(|k| {
            let i = unsigned_int(bytes, ty, idx.offset() + k * ty.size())
                .ok_or("its sparse indices lie outside their buffer view")? as usize;
            if i >= count {
                return Err(format!("sparse index {i} is out of range: the accessor has {count} elements"));
            }
            Ok(i)
        })
        .collect()
}
