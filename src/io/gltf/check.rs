//! A glTF document's structure, checked before anything walks it.
//!
//! The `gltf` crate's validation follows references but not sizes, and some of its own code
//! (a primitive's `POSITION` bounds, an image's source, accessor reads) indexes before it
//! checks. So the raw JSON is checked first, against everything the loader or the crate will
//! later rely on: every index in range, every buffer view inside its buffer, every accessor
//! (and its sparse parts) inside its view with a stride no smaller than its element, images
//! with a source, accessors without data no larger than the memory limit, and a node graph
//! that is a forest (each node the child of at most one node, scene roots of none), so that
//! walking it visits each node once. Errors name the element (`accessors[3]`, `nodes[7]`).

use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;
use gltf::json::{self, Index, Root};

use crate::error::{Error, Result};

/// Checks `root`; `file` names it in errors.
pub fn structure(file: &str, root: &Root) -> Result<()> {
    let err = |at: String, message: String| Error::scene(file, at, message);
    for (i, view) in root.buffer_views.iter().enumerate() {
        let buffer = get(&root.buffers, view.buffer).ok_or_else(|| {
            err(
                format!("bufferViews[{i}]"),
                format!("refers to buffer {}, but there are {}", view.buffer.value(), root.buffers.len()),
            )
        })?;
        let (offset, length) = (view.byte_offset.map_or(0, |o| o.0), view.byte_length.0);
        if offset.checked_add(length).is_none_or(|end| end > buffer.byte_length.0) {
            return Err(err(
                format!("bufferViews[{i}]"),
                format!(
                    "bytes {offset}..+{length} lie outside buffer {} ({} bytes)",
                    view.buffer.value(),
                    buffer.byte_length.0
                ),
            ));
        }
    }
    for (i, accessor) in root.accessors.iter().enumerate() {
        check_accessor(root, accessor).map_err(|m| err(format!("accessors[{i}]"), m))?;
    }
    for (i, image) in root.images.iter().enumerate() {
        let at = || format!("images[{i}]");
        match (&image.buffer_view, &image.uri) {
            (Some(v), _) => {
                get(&root.buffer_views, *v)
                    .ok_or_else(|| err(at(), format!("refers to buffer view {}, which does not exist", v.value())))?;
                if image.mime_type.is_none() {
                    return Err(err(at(), "is stored in a buffer view but has no mimeType".into()));
                }
            }
            (None, Some(_)) => {}
            (None, None) => return Err(err(at(), "has neither a uri nor a bufferView: there is no picture".into())),
        }
    }
    for (i, texture) in root.textures.iter().enumerate() {
        let at = || format!("textures[{i}]");
        let own = Some(texture.source.value()).filter(|&s| s != u32::MAX as usize);
        let sources = texture_sources(texture.extensions.as_ref().map(|e| &e.others), own);
        if let Some(bad) = sources.into_iter().find(|&s| s >= root.images.len()) {
            return Err(err(at(), format!("uses image {bad}, which does not exist")));
        }
    }
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let at = || format!("meshes[{m}].primitives[{p}]");
            let accessors = prim.attributes.values().chain(&prim.indices);
            if let Some(bad) = accessors.into_iter().find(|a| get(&root.accessors, **a).is_none()) {
                return Err(err(
                    at(),
                    format!("uses accessor {}, but there are {}", bad.value(), root.accessors.len()),
                ));
            }
        }
    }
    check_node_forest(root).map_err(|(at, m)| err(at, m))
}

/// The images a texture may show: an extension's source first (`EXT_texture_webp`,
/// `KHR_texture_basisu`: the form the file prefers), then its own `source` (the fallback, and
/// the only source glTF requires).
/// `extensions` are the texture's extension objects, `source` its own image.
pub fn texture_sources(extensions: Option<&serde_json::Map<String, json::Value>>, source: Option<usize>) -> Vec<usize> {
    let extension = extensions.into_iter().flat_map(|e| e.values());
    extension.filter_map(|v| v.get("source")?.as_u64()).map(|s| s as usize).chain(source).collect()
}

/// `list[index]`, if it exists.
fn get<T>(list: &[T], index: Index<T>) -> Option<&T> {
    list.get(index.value())
}

/// Bytes of one element of an accessor (`None` when its type or component is invalid, which
/// the crate's validation reports).
fn element_size(component: &Checked<json::accessor::GenericComponentType>, ty: &Checked<Type>) -> Option<u64> {
    match (component, ty) {
        (Checked::Valid(c), Checked::Valid(t)) => Some((c.0.size() * t.multiplicity()) as u64),
        _ => None,
    }
}

/// Checks that `count` elements of `element` bytes, `stride` apart, from `offset` fit in view
/// `view`.
fn fits(
    root: &Root,
    view: Index<json::buffer::View>,
    offset: u64,
    count: u64,
    element: u64,
    what: &str,
) -> Result<(), String> {
    let v = get(&root.buffer_views, view)
        .ok_or_else(|| format!("{what} refers to buffer view {}, which does not exist", view.value()))?;
    let stride = match v.byte_stride {
        Some(s) if (s.0 as u64) < element => {
            return Err(format!(
                "{what}'s elements are {element} bytes but buffer view {} sets a byteStride of {} bytes",
                view.value(),
                s.0
            ));
        }
        Some(s) => s.0 as u64,
        None => element,
    };
    let end = count
        .checked_sub(1)
        .and_then(|c| c.checked_mul(stride))
        .and_then(|b| b.checked_add(offset))
        .and_then(|b| b.checked_add(element));
    match end {
        Some(end) if end <= v.byte_length.0 => Ok(()),
        _ => Err(format!(
            "{what}: {count} elements of {element} bytes from byte {offset} do not fit in buffer view {} ({} bytes)",
            view.value(),
            v.byte_length.0
        )),
    }
}

fn check_accessor(root: &Root, a: &json::Accessor) -> Result<(), String> {
    let count = a.count.0;
    if count == 0 {
        return Err("has count 0 (glTF requires at least one element)".into());
    }
    let Some(element) = element_size(&a.component_type, &a.type_) else { return Ok(()) };
    match a.buffer_view {
        Some(view) => fits(root, view, a.byte_offset.map_or(0, |o| o.0), count, element, "its data")?,
        None => {
            // No data: the reader makes `count` zero elements.
            let bytes = count.saturating_mul(element);
            crate::limits::check_memory(bytes, format_args!("an accessor of {count} elements without data"))?;
        }
    }
    if let Some(sparse) = &a.sparse {
        let n = sparse.count.0;
        if n == 0 || n > count {
            return Err(format!("has {n} sparse elements for {count} elements"));
        }
        let index_size = match &sparse.indices.component_type {
            Checked::Valid(c) if matches!(c.0, ComponentType::U8 | ComponentType::U16 | ComponentType::U32) => {
                c.0.size() as u64
            }
            _ => return Err("sparse indices must be unsigned bytes, shorts or ints".into()),
        };
        fits(root, sparse.indices.buffer_view, sparse.indices.byte_offset.0, n, index_size, "its sparse indices")?;
        fits(root, sparse.values.buffer_view, sparse.values.byte_offset.0, n, element, "its sparse values")?;
    }
    Ok(())
}

/// Each node the child of at most one node, never its own descendant, and scene roots
/// children of none; indices in range.
fn check_node_forest(root: &Root) -> Result<(), (String, String)> {
    let n = root.nodes.len();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for (i, node) in root.nodes.iter().enumerate() {
        for c in node.children.iter().flatten() {
            let c = c.value();
            let at = format!("nodes[{i}]");
            if c >= n {
                return Err((at, format!("lists child {c}, but there are {n} nodes")));
            }
            if let Some(p) = parent[c] {
                return Err((
                    at,
                    format!(
                        "lists node {c} as a child, which nodes[{p}] already does; glTF node hierarchies must be trees"
                    ),
                ));
            }
            parent[c] = Some(i);
        }
    }
    // With one parent each, a cycle is a loop of parents. Walk up from each node, marking
    // the chain, until a node already known to lead to a root: O(n) in all.
    const DONE: usize = usize::MAX;
    let mut mark = vec![0usize; n];
    for start in 0..n {
        let mut at = start;
        while mark[at] != DONE {
            if mark[at] == start + 1 {
                return Err((format!("nodes[{at}]"), "is its own ancestor: the node hierarchy has a cycle".into()));
            }
            mark[at] = start + 1;
            match parent[at] {
                Some(p) => at = p,
                None => break,
            }
        }
        let mut at = Some(start);
        while let Some(a) = at.filter(|&a| mark[a] != DONE) {
            mark[a] = DONE;
            at = parent[a];
        }
    }
    for (s, scene) in root.scenes.iter().enumerate() {
        let mut seen = std::collections::BTreeSet::new();
        for r in &scene.nodes {
            let r = r.value();
            let at = format!("scenes[{s}]");
            if r >= n {
                return Err((at, format!("lists node {r}, but there are {n} nodes")));
            }
            if let Some(p) = parent[r] {
                return Err((
                    at,
                    format!("lists node {r}, which is a child of nodes[{p}]; a scene lists root nodes only"),
                ));
            }
            if !seen.insert(r) {
                return Err((at, format!("lists node {r} twice")));
            }
        }
    }
    Ok(())
}

/// The files buffers and images refer to: each URI decodes (percent-encoding to UTF-8) and
/// names a regular file, not a device or a folder that reading would never finish. Returns
/// their paths.
pub fn external_files(file: &str, root: &Root, base: Option<&std::path::Path>) -> Result<Vec<std::path::PathBuf>> {
    let mut paths = Vec::new();
    let uris = root.buffers.iter().enumerate().filter_map(|(i, b)| Some((format!("buffers[{i}]"), b.uri.as_deref()?)));
    let images = root.images.iter().enumerate().filter_map(|(i, m)| Some((format!("images[{i}]"), m.uri.as_deref()?)));
    for (at, uri) in uris.chain(images) {
        let path = if let Some(rest) = uri.strip_prefix("file://").or_else(|| uri.strip_prefix("file:")) {
            std::path::PathBuf::from(rest)
        } else if uri.contains(':') {
            continue; // data: URIs, and schemes the crate refuses itself
        } else {
            let decoded = urlencoding::decode(uri)
                .map_err(|_| Error::scene(file, &at, "has a uri whose %-escapes are not UTF-8 text"))?;
            base.map_or_else(|| decoded.as_ref().into(), |b| b.join(decoded.as_ref()))
        };
        if let Ok(meta) = std::fs::metadata(&path)
            && !meta.is_file()
        {
            return Err(Error::scene(file, at, format!("refers to '{}', which is not a regular file", path.display())));
        }
        paths.push(path);
    }
    Ok(paths)
}
