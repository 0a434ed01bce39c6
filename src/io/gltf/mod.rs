//! glTF 2.0 (`.gltf`, `.glb`) → [`SceneDescription`], as Blender's exporter writes it.
//!
//! Reads the default scene (or the one asked for) with its whole node hierarchy (matrix or
//! TRS transforms), every triangle primitive (strips and fans converted; points and lines
//! skipped with one warning), the metallic-roughness materials with the extensions in
//! `SUPPORTED` (emissive strength, specular, IOR, clearcoat, transmission, volume, texture
//! transforms), alpha masks and blending, normal maps, perspective cameras and
//! KHR_lights_punctual lights (intensities × `punctual_scale`, 1/683 by default: Blender
//! writes W·683/(4π) cd and W/m²·683 lx). Other extensions are named in one warning.
//!
//! Each primitive becomes one mesh, stored once however many nodes use it (instancing).
//! The document's structure is checked before anything walks it (`check.rs`: indices, sizes,
//! strides, the node forest), and every accessor's type and shape before it is read, so a
//! broken file is an error naming the element, never a panic inside the reader. Images are
//! decoded one by one: a missing or unreadable one is a warning and the materials that use it
//! fall back to their factors.

mod accessor;
mod check;
mod draco;
mod meshopt;
mod tolerate;

use std::collections::BTreeSet;
use std::path::Path;
use std::sync::Arc;

use gltf::accessor::DataType;
use gltf::mesh::{Mode, Semantic};
use gltf::texture::{MagFilter, WrappingMode};

use super::LoadOptions;
use super::image_file;
use crate::camera::Fit;
use crate::error::{Error, Result};
use crate::light::{LampModel, SpotCurve};
use crate::material::texture::{UvTransform, Wrap};
use crate::material::{AlphaMode, Material, TextureRef};
use crate::math::{Mat4, Rgb, Vec2, Vec3A};
use crate::scene::description::{CameraDesc, CameraPlacement, InstanceDesc, LightDesc, MeshDesc, SceneDescription};

/// Extensions myriad reads, with what it does with each (`info` lists them). Others are
/// named in one warning, and refused where the file requires them.
pub const SUPPORTED: [(&str, &str); 16] = [
    ("KHR_materials_clearcoat", "the Principled coat"),
    ("KHR_materials_sheen", "the Principled sheen, as Cycles renders it"),
    ("KHR_materials_anisotropy", "anisotropic metal and specular, as Cycles after Blender's import"),
    ("KHR_materials_transmission", "glass and other transmission"),
    ("KHR_materials_volume", "absorption inside transmissive solids"),
    ("KHR_materials_emissive_strength", "emission above 1"),
    ("KHR_materials_specular", "specular strength and tint"),
    ("KHR_materials_ior", "the index of refraction"),
    ("KHR_texture_transform", "texture offsets, rotations and scales"),
    ("KHR_lights_punctual", "point, spot and directional lights"),
    (draco::NAME, "Draco-compressed meshes, decoded"),
    (meshopt::NAMES[0], "meshopt-compressed buffer views, decoded"),
    (meshopt::NAMES[1], "meshopt-compressed buffer views, decoded"),
    ("KHR_mesh_quantization", "integer positions, normals and texture coordinates"),
    ("EXT_texture_webp", "WebP textures"),
    ("KHR_texture_basisu", "its fallback image (Basis Universal is not decoded)"),
];

/// What myriad does with extension `name`, if it reads it.
pub fn handling(name: &str) -> Option<&'static str> {
    SUPPORTED.iter().find(|(n, _)| *n == name).map(|(_, what)| *what)
}

/// Reads a glTF file.
pub fn load(path: &Path, options: &LoadOptions) -> Result<SceneDescription> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    // A JSON glTF saved with a byte-order mark is still JSON.
    let text = bytes.strip_prefix("\u{feff}".as_bytes()).unwrap_or(&bytes);
    let (json_bytes, blob) = if text.starts_with(b"glTF") {
        // Bytes after the length the header declares are not part of the GLB (the crate
        // would read them as a chunk): ignored.
        let declared = text.get(8..12).map_or(text.len(), |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize);
        let glb = gltf::binary::Glb::from_slice(&text[..declared.clamp(12.min(text.len()), text.len())])
            .map_err(|e| parse_error(&file, text, e))?;
        (glb.json.into_owned(), glb.bin.map(|b| b.into_owned()))
    } else {
        (text.to_vec(), None)
    };
    let deserialize = |e| parse_error(&file, text, gltf::Error::Deserialize(e));
    let mut value: serde_json::Value = serde_json::from_slice(&json_bytes).map_err(deserialize)?;
    let tolerated = tolerate::tolerate(&mut value);
    let mut json: gltf::json::Root = serde_json::from_value(value).map_err(deserialize)?;
    let base = path.parent();
    check::structure(&file, &json)?;
    let external = check::external_files(&file, &json, base)?;
    if let Some(missing) = json.extensions_required.iter().find(|e| handling(e).is_none()) {
        return Err(Error::scene(
            &file,
            "extensionsRequired",
            format!("requires the extension {missing}, which myriad does not read; export the file without it"),
        ));
    }
    // The crate's validation refuses required extensions it does not know itself; myriad
    // reads these (checked just above).
    json.extensions_required.clear();
    validate(&json).map_err(|e| parse_error(&file, text, e))?;
    let gltf = gltf::Gltf { document: gltf::Document::from_json_without_validation(json), blob };
    let buffers = import_buffers(&gltf.document, base, gltf.blob.clone()).map_err(|e| buffer_error(&file, e))?;
    let decoded = meshopt::decode_views(&gltf.document, &buffers).map_err(|(at, m)| Error::scene(&file, at, m))?;
    let views = accessor::Views::new(&buffers, decoded);
    let generator = gltf.document.as_json().asset.generator.as_deref().unwrap_or("");
    let mut loader = Loader {
        file: &file,
        tolerated,
        views: &views,
        blender: generator.starts_with(BLENDER_GENERATOR) || generator.starts_with(ADDON_GENERATOR),
        desc: SceneDescription {
            source: file.clone(),
            inputs: std::iter::once(path.to_path_buf()).chain(external).collect(),
            ..Default::default()
        },
    };
    let doc = &gltf.document;
    loader.desc.extensions =
        doc.extensions_used().map(|e| (e.to_string(), handling(e).unwrap_or("ignored").to_string())).collect();
    loader.static_pose(doc);
    if !loader.tolerated.unknown_lights.is_empty() {
        let which: Vec<usize> = loader.tolerated.unknown_lights.iter().copied().collect();
        loader.warn(format!(
            "skips KHR_lights_punctual lights {which:?}, whose type is none of directional, point, spot"
        ));
    }
    let unsupported: Vec<&str> = doc.extensions_used().filter(|e| handling(e).is_none()).collect();
    if !unsupported.is_empty() {
        loader.warn(format!("ignores the extensions {unsupported:?} (rendered without them)"));
    }
    let images = loader.images(doc, base);
    loader.materials(doc, &images);
    let primitives = loader.meshes(doc)?;
    loader.nodes(doc, &primitives, options)?;
    Ok(loader.desc)
}

/// The crate's validation, less its one rule stricter than the specification: an accessor
/// without a buffer view is zeros (sparse values may replace some; a Draco primitive's
/// accessors have none at all), not missing data.
fn validate(json: &gltf::json::Root) -> gltf::Result<()> {
    use gltf::json::validation::{Error as Invalid, Validate};
    let mut errors = Vec::new();
    json.validate(json, gltf::json::Path::new, &mut |path, error| {
        let path = path();
        let p = path.as_str();
        let zeros = matches!(error, Invalid::Missing) && p.starts_with("accessors[") && p.ends_with("].bufferView");
        // A primitive without positions is valid (the loader skips it).
        let no_position = matches!(error, Invalid::Missing) && p.ends_with(".attributes[\"POSITION\"]");
        if !(zeros || no_position) {
            errors.push((path, error));
        }
    });
    if errors.is_empty() { Ok(()) } else { Err(gltf::Error::Validation(errors)) }
}

/// A parse failure, explained: JSON syntax (line, column), GLB structure, validation (the
/// JSON path), Draco (unsupported, say so), or not glTF at all.
fn parse_error(file: &str, bytes: &[u8], e: gltf::Error) -> Error {
    let first = bytes.iter().copied().find(|b| !b.is_ascii_whitespace());
    match e {
        gltf::Error::Deserialize(j) if !bytes.starts_with(b"glTF") && first != Some(b'{') => Error::scene(
            file,
            "file",
            format!("is not a glTF file (neither binary GLB, which starts with 'glTF', nor JSON glTF): {j}"),
        ),
        // Line 0: a type error found after parsing (the document as a whole).
        gltf::Error::Deserialize(j) if j.line() == 0 => Error::scene(file, "document", format!("invalid glTF: {j}")),
        gltf::Error::Deserialize(j) => {
            Error::scene(file, format!("{}:{}", j.line(), j.column()), format!("invalid glTF JSON: {j}"))
        }
        gltf::Error::Binary(b) => Error::scene(file, "GLB container", format!("truncated or corrupt binary glTF: {b}")),
        gltf::Error::Validation(errors) => {
            let text: Vec<String> = errors.iter().take(5).map(|(path, err)| format!("{path}: {err}")).collect();
            let message = format!("invalid glTF: {}", text.join("; "));
            Error::scene(file, errors.first().map_or("document".into(), |(p, _)| p.to_string()), message)
        }
        other => Error::scene(file, "file", other.to_string()),
    }
}

/// The data of every buffer: the GLB's binary chunk, a file or a data URI, and nothing for a
/// placeholder a meshopt extension fills or one without a URI and no binary chunk to refer to
/// (`gltf::import_buffers` refuses those; a view that reads one is an error where it is read).
fn import_buffers(
    doc: &gltf::Document,
    base: Option<&Path>,
    mut blob: Option<Vec<u8>>,
) -> gltf::Result<Vec<gltf::buffer::Data>> {
    doc.buffers()
        .map(|buffer| {
            let bin = matches!(buffer.source(), gltf::buffer::Source::Bin);
            if bin && (meshopt::fallback_buffer(&buffer) || blob.is_none()) {
                return Ok(gltf::buffer::Data(Vec::new()));
            }
            if let gltf::buffer::Source::Uri(uri) = buffer.source()
                && let Some(bytes) = plain_data_uri(uri)
            {
                return check_length(&buffer, gltf::buffer::Data(bytes));
            }
            let data = match gltf::buffer::Data::from_source_and_blob(buffer.source(), base, &mut blob) {
                // An `http:` (or other) URI myriad does not fetch: no data, an error only
                // where an accessor reads it (the glTF-Validator calls such files valid).
                Err(gltf::Error::UnsupportedScheme) => return Ok(gltf::buffer::Data(Vec::new())),
                other => other?,
            };
            check_length(&buffer, data)
        })
        .collect()
}

/// `data` unless it is shorter than `buffer` says.
fn check_length(buffer: &gltf::Buffer, data: gltf::buffer::Data) -> gltf::Result<gltf::buffer::Data> {
    if data.len() < buffer.length() {
        return Err(gltf::Error::BufferLength {
            buffer: buffer.index(),
            expected: buffer.length(),
            actual: data.len(),
        });
    }
    Ok(data)
}

/// The bytes of a data URI that is not base64 (RFC 2397: the payload percent-encoded), which
/// the crate would decode as base64; `None` for other URIs.
fn plain_data_uri(uri: &str) -> Option<Vec<u8>> {
    let (header, payload) = uri.strip_prefix("data:")?.split_once(',')?;
    (!header.ends_with(";base64")).then(|| urlencoding::decode_binary(payload.as_bytes()).into_owned())
}

fn buffer_error(file: &str, e: gltf::Error) -> Error {
    match e {
        gltf::Error::BufferLength { buffer, expected, actual } => Error::scene(
            file,
            format!("buffers[{buffer}]"),
            format!("holds {actual} bytes but the file declares {expected}: the file (or its .bin) is truncated"),
        ),
        gltf::Error::MissingBlob => {
            Error::scene(file, "buffers[0]", "refers to the GLB's binary chunk, which is missing")
        }
        other => Error::scene(file, "buffers", format!("cannot be read: {other}")),
    }
}

struct Loader<'a> {
    file: &'a str,
    /// What `tolerate` changed in the document.
    tolerated: tolerate::Tolerated,
    views: &'a accessor::Views<'a>,
    desc: SceneDescription,
    /// Written by Blender's exporter: rendered as Cycles renders it after import.
    blender: bool,
}

/// A light's size where its `extras` give one (what glTF's punctual lights cannot say:
/// Blender's exporter writes a light's custom properties there, so a `radius` or an `angle`
/// added in Blender reaches myriad): `radius` (metres) of a point or spot, `soft_falloff`
/// (default true), `angle` (radians, Blender's) of a sun.
#[derive(Clone, Copy, Debug, Default, serde::Deserialize)]
struct LightExtras {
    radius: Option<f32>,
    soft_falloff: Option<bool>,
    angle: Option<f32>,
}

impl LightExtras {
    /// The lamp shape of a point or spot with a radius.
    fn lamp(&self) -> Option<crate::scene::description::LampShape> {
        let radius = self.radius.filter(|r| *r != 0.0)?;
        let model = if self.soft_falloff.unwrap_or(true) { LampModel::FacingDisk } else { LampModel::Sphere };
        Some(crate::scene::description::LampShape { radius, model, camera_visible: false })
    }
}

/// The `asset.generator` Blender's glTF exporter writes (followed by its version).
const BLENDER_GENERATOR: &str = "Khronos glTF Blender I/O";

/// The generator of the files myriad's Blender add-on writes (blender/myriad_blender), which
/// follow the same Blender conventions.
const ADDON_GENERATOR: &str = "myriad Blender add-on";

/// A Blender spot's full-intensity half-angle, from the cones its exporter wrote (outer =
/// spot size / 2, inner = outer·(1 − blend)): Cycles fades by a smoothstep from cos(outer)
/// up to cos(outer) + (1 − cos(outer))·blend.
fn blender_spot_inner(inner: f32, outer: f32) -> f32 {
    let blend = if outer > 0.0 { (1.0 - inner / outer).clamp(0.0, 1.0) } else { 0.0 };
    let cos_outer = outer.cos();
    (cos_outer + (1.0 - cos_outer) * blend).clamp(-1.0, 1.0).acos()
}

/// The glTF-to-myriad index of each image (None: failed to load).
type ImageMap = Vec<Option<u32>>;

impl Loader<'_> {
    fn warn(&mut self, message: String) {
        self.desc.warnings.push(format!("{}: {message}", self.file));
    }

    /// A light's size from its `extras` ([`LightExtras`]); extras of another shape are
    /// someone else's and are left alone, with a warning when they name a size wrongly.
    fn light_size(&mut self, label: &str, extras: &gltf::json::extras::Extras) -> LightExtras {
        let Some(raw) = extras.as_ref() else { return LightExtras::default() };
        match serde_json::from_str::<LightExtras>(raw.get()) {
            Ok(size) => size,
            Err(e) if raw.get().contains("\"radius\"") || raw.get().contains("\"angle\"") => {
                self.warn(format!("light '{label}': its extras' radius or angle is not a number ({e}); ignored"));
                LightExtras::default()
            }
            Err(_) => LightExtras::default(),
        }
    }

    /// One warning for what moves a scene (animations, skins, morph targets): the file's
    /// static pose is what renders.
    fn static_pose(&mut self, doc: &gltf::Document) {
        let morphs = doc.meshes().flat_map(|m| m.primitives()).filter(|p| p.morph_targets().next().is_some()).count();
        let parts: Vec<String> = [
            (self.tolerated.animations, "animations"),
            (doc.skins().count(), "skins"),
            (morphs, "primitives with morph targets"),
        ]
        .into_iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, what)| format!("{n} {what}"))
        .collect();
        if !parts.is_empty() {
            self.warn(format!(
                "has {}; myriad renders the static pose (nodes as placed, meshes unmorphed)",
                parts.join(", ")
            ));
        }
    }

    fn err(&self, location: impl Into<String>, message: impl Into<String>) -> Error {
        Error::scene(self.file, location, message)
    }

    /// Decodes every image (PNG, JPEG, WebP, 8 or 16 bits); failures become warnings.
    fn images(&mut self, doc: &gltf::Document, base: Option<&Path>) -> ImageMap {
        let mut map = Vec::new();
        for img in doc.images() {
            let name = match (img.name(), img.source()) {
                (Some(name), _) => name.to_string(),
                (None, gltf::image::Source::Uri { uri, .. }) if !uri.starts_with("data:") => uri.to_string(),
                (None, _) => format!("image {}", img.index()),
            };
            let mime = match img.source() {
                gltf::image::Source::View { mime_type, .. } => Some(mime_type),
                gltf::image::Source::Uri { mime_type, .. } => mime_type,
            };
            match self.image_bytes(&img, base).and_then(|bytes| image_file::decode(name.clone(), &bytes)) {
                Ok(image) => {
                    self.desc.images.push(image);
                    map.push(Some((self.desc.images.len() - 1) as u32));
                }
                Err(_) if mime == Some("image/ktx2") => {
                    self.warn(format!(
                        "images[{}] '{name}' is Basis Universal (KTX2), which myriad does not decode; textures use \
                         the file's fallback image where it has one",
                        img.index()
                    ));
                    map.push(None);
                }
                Err(e) => {
                    self.warn(format!(
                        "images[{}] '{name}' cannot be read ({e}); materials using it fall back to their factors",
                        img.index()
                    ));
                    map.push(None);
                }
            }
        }
        map
    }

    /// The encoded bytes of `img`: its buffer view's, or its URI's (a data URI or a file).
    fn image_bytes(&self, img: &gltf::Image, base: Option<&Path>) -> std::result::Result<Vec<u8>, String> {
        match img.source() {
            gltf::image::Source::View { view, .. } => self.views.bytes(&view).map(<[u8]>::to_vec),
            gltf::image::Source::Uri { uri, .. } => {
                gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), base)
                    .map(|d| d.0)
                    .map_err(|e| e.to_string())
            }
        }
    }

    fn texture(
        &mut self,
        tex: gltf::Texture,
        tex_coord: u32,
        transform: Option<UvTransform>,
        images: &ImageMap,
    ) -> Option<TextureRef> {
        if tex_coord != 0 {
            self.warn(format!("textures[{}] uses TEXCOORD_{tex_coord}; myriad reads TEXCOORD_0", tex.index()));
        }
        // The first source that decoded: an extension's (WebP), else the texture's own.
        let sources = check::texture_sources(tex.extensions(), tex.source().map(|i| i.index()));
        if sources.is_empty() {
            // glTF allows it (an application may supply the image): the factors stand.
            let message = format!("textures[{}] has no image; materials using it keep their factors", tex.index());
            if !self.desc.warnings.iter().any(|w| w.ends_with(&message)) {
                self.warn(message);
            }
        }
        let image = sources.into_iter().find_map(|s| images.get(s).copied().flatten())?;
        let wrap = |w: WrappingMode| match w {
            WrappingMode::ClampToEdge => Wrap::Clamp,
            WrappingMode::MirroredRepeat => Wrap::Mirror,
            WrappingMode::Repeat => Wrap::Repeat,
        };
        let sampler = tex.sampler();
        Some(TextureRef {
            image,
            wrap: [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())],
            nearest: sampler.mag_filter() == Some(MagFilter::Nearest),
            transform: transform.unwrap_or_default(),
        })
    }

    /// A texture an extension's JSON refers to (`{"index": …, "texCoord": …}`); an index
    /// out of range is warned about and read as no texture.
    fn json_texture(
        &mut self,
        doc: &gltf::Document,
        info: Option<&gltf::json::Value>,
        images: &ImageMap,
        what: &str,
    ) -> Option<TextureRef> {
        let info = info?;
        let index = info.get("index").and_then(|i| i.as_u64());
        let Some(tex) = index.and_then(|i| doc.textures().nth(i as usize)) else {
            self.warn(format!("{what} names texture {index:?}, which does not exist: read without it"));
            return None;
        };
        let tex_coord = info.get("texCoord").and_then(|c| c.as_u64()).unwrap_or(0) as u32;
        let transform = info.get("extensions").and_then(|e| e.get("KHR_texture_transform")).map(khr_transform_json);
        self.texture(tex, tex_coord, transform, images)
    }

    /// KHR_materials_sheen's colour, roughness and their textures, on `material`.
    fn sheen(&mut self, doc: &gltf::Document, m: &gltf::Material, material: Material, images: &ImageMap) -> Material {
        let Some(ext) = m.extension_value("KHR_materials_sheen") else { return material };
        let what = format!("material '{}': KHR_materials_sheen", material.name);
        let color = number_array::<3>(ext.get("sheenColorFactor")).map_or(Rgb::ZERO, Rgb::from);
        Material {
            sheen_color: color,
            sheen_roughness: number(ext.get("sheenRoughnessFactor")).unwrap_or(0.0),
            sheen_color_texture: self.json_texture(doc, ext.get("sheenColorTexture"), images, &what),
            sheen_roughness_texture: self.json_texture(doc, ext.get("sheenRoughnessTexture"), images, &what),
            ..material
        }
    }

    /// KHR_materials_anisotropy's strength, rotation and texture, on `material`.
    fn anisotropy(
        &mut self,
        doc: &gltf::Document,
        m: &gltf::Material,
        material: Material,
        images: &ImageMap,
    ) -> Material {
        let Some(ext) = m.extension_value("KHR_materials_anisotropy") else { return material };
        let what = format!("material '{}': KHR_materials_anisotropy", material.name);
        Material {
            anisotropy: number(ext.get("anisotropyStrength")).unwrap_or(0.0),
            anisotropy_rotation: number(ext.get("anisotropyRotation")).unwrap_or(0.0),
            anisotropy_texture: self.json_texture(doc, ext.get("anisotropyTexture"), images, &what),
            ..material
        }
    }

    fn info(&mut self, info: Option<gltf::texture::Info>, images: &ImageMap) -> Option<TextureRef> {
        let info = info?;
        let tt = info.texture_transform();
        let transform = tt.as_ref().map(|t| UvTransform::from_khr(t.offset(), t.rotation(), t.scale()));
        let tex_coord = tt.and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord());
        self.texture(info.texture(), tex_coord, transform, images)
    }

    /// The absorption coefficient of a material's volume, when it has one (a thickness > 0):
    /// −ln(colour)/distance as the specification has it, or, for files Blender wrote, what
    /// Cycles' Volume Absorption node (colour, density 1/distance) gives: (1 − colour)/distance.
    /// A solid without absorption is `Some(0)`; so is one whose distance is not positive,
    /// with a warning naming `material`.
    fn volume(&mut self, m: &gltf::Material, material: &str) -> Option<Rgb> {
        let v = m.volume().filter(|v| v.thickness_factor() > 0.0)?;
        let (color, distance) = (Rgb::from(v.attenuation_color()), v.attenuation_distance());
        if distance.is_infinite() && distance > 0.0 {
            return Some(Rgb::ZERO);
        }
        if !(distance > 0.0) {
            self.warn(format!(
                "material '{material}': KHR_materials_volume attenuationDistance {distance} is not positive; \
                 the volume absorbs nothing"
            ));
            return Some(Rgb::ZERO);
        }
        let per_channel = |c: f32| if self.blender { (1.0 - c).max(0.0) } else { -(c.clamp(1e-6, 1.0)).ln() };
        Some(Rgb::new(per_channel(color.x), per_channel(color.y), per_channel(color.z)) / distance)
    }

    /// The index of refraction: `KHR_materials_ior`'s (1.5 without it). Its special value 0
    /// (Fresnel reflectance 1 at every angle, for specular-glossiness conversions) becomes
    /// the largest IOR myriad takes to be a mirror-like dielectric: 10⁴ (F0 = 0.9996).
    fn ior(&mut self, m: &gltf::Material, material: &str) -> f32 {
        match m.ior() {
            Some(0.0) => {
                self.warn(format!("material '{material}': KHR_materials_ior 0 (full reflection) renders as IOR 10000"));
                1e4
            }
            ior => ior.unwrap_or(1.5),
        }
    }

    fn materials(&mut self, doc: &gltf::Document, images: &ImageMap) {
        for m in doc.materials() {
            let name = m.name().map_or_else(|| format!("material {}", m.index().unwrap_or(0)), str::to_string);
            let pbr = m.pbr_metallic_roughness();
            let bc = pbr.base_color_factor();
            let normal_texture = m.normal_texture().and_then(|n| {
                // The crate exposes no texture transform on normal textures: read the JSON.
                let transform = n.extension_value("KHR_texture_transform").map(khr_transform_json);
                let scale = n.scale();
                self.texture(n.texture(), n.tex_coord(), transform, images).map(|t| (t, scale))
            });
            let clearcoat = m.extension_value("KHR_materials_clearcoat").map_or((0.0, 0.0), |c| {
                // Blender's importer gives a coat without a roughness 0.03, not glTF's 0.
                let default_roughness = if self.blender { 0.03 } else { 0.0 };
                let textured = c.get("clearcoatRoughnessTexture").is_some();
                let roughness =
                    number(c.get("clearcoatRoughnessFactor")).unwrap_or(if textured { 0.0 } else { default_roughness });
                (number(c.get("clearcoatFactor")).unwrap_or(0.0), roughness)
            });
            let volume = self.volume(&m, &name);
            let alpha = match m.alpha_mode() {
                gltf::material::AlphaMode::Mask => AlphaMode::Mask(m.alpha_cutoff().unwrap_or(0.5)),
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            };
            let material = Material {
                base_alpha: bc[3],
                metallic: pbr.metallic_factor(),
                roughness: pbr.roughness_factor(),
                specular: m.specular().map_or(1.0, |s| s.specular_factor()),
                specular_color: m.specular().map_or(Rgb::ONE, |s| Rgb::from(s.specular_color_factor())),
                ior: self.ior(&m, &name),
                transmission: m.transmission().map_or(0.0, |t| t.transmission_factor()),
                thin: volume.is_none() && !self.blender,
                absorption: volume.unwrap_or(Rgb::ZERO),
                coat: clearcoat.0,
                coat_roughness: clearcoat.1,
                emission: Rgb::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0),
                double_sided: m.double_sided(),
                base_color_texture: self.info(pbr.base_color_texture(), images),
                metallic_roughness_texture: self.info(pbr.metallic_roughness_texture(), images),
                emission_texture: self.info(m.emissive_texture(), images),
                normal_texture,
                alpha,
                ignored: ignored_properties(&m),
                ..Material::diffuse(&name, Rgb::new(bc[0], bc[1], bc[2]))
            };
            let material = self.sheen(doc, &m, material, images);
            let material = self.anisotropy(doc, &m, material, images);
            self.desc.materials.push(material);
        }
        // glTF's default material, for primitives without one: white, metallic 1, roughness 1.
        self.desc.materials.push(Material {
            metallic: 1.0,
            specular: 1.0,
            ..Material::diffuse("glTF default", Rgb::ONE)
        });
    }

    /// Reads accessor `acc` of a primitive as `D` floats an element, of the component types
    /// `types` (f32, and the integers `KHR_mesh_quantization` allows there).
    fn floats<const D: usize>(&self, where_: &str, acc: &gltf::Accessor, types: &[DataType]) -> Result<Vec<[f32; D]>> {
        self.defined(where_, acc)?;
        accessor::floats(self.views, acc, types).map_err(|m| self.err(format!("{where_}, accessor {}", acc.index()), m))
    }

    /// An error unless `acc` has a type glTF defines (see `tolerate.rs`).
    fn defined(&self, where_: &str, acc: &gltf::Accessor) -> Result<()> {
        match self.tolerated.unknown_accessors.get(&acc.index()) {
            Some(ty) => Err(self.err(
                format!("{where_}, accessor {}", acc.index()),
                format!("has type '{ty}', which glTF does not define (SCALAR, VEC2 to VEC4 or MAT2 to MAT4)"),
            )),
            None => Ok(()),
        }
    }

    /// One mesh per triangle primitive; returns (glTF mesh, primitive) → mesh index.
    fn meshes(&mut self, doc: &gltf::Document) -> Result<Vec<Vec<Option<u32>>>> {
        let default_material = (self.desc.materials.len() - 1) as u32;
        let mut skipped = BTreeSet::new();
        let mut map = Vec::new();
        for mesh in doc.meshes() {
            let mut prims = Vec::new();
            for prim in mesh.primitives() {
                let where_ =
                    format!("meshes[{}] '{}' primitive {}", mesh.index(), mesh.name().unwrap_or(""), prim.index());
                if prim.get(&Semantic::Positions).is_none() {
                    skipped.insert(format!("{} (no POSITION)", mesh.name().unwrap_or("unnamed")));
                    prims.push(None);
                    continue;
                }
                if !matches!(prim.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                    skipped.insert(format!("{} ({:?})", mesh.name().unwrap_or("unnamed"), prim.mode()));
                    prims.push(None);
                    continue;
                }
                let m = self.primitive(doc, &where_, &prim, default_material)?;
                self.desc.meshes.push(m);
                prims.push(Some((self.desc.meshes.len() - 1) as u32));
            }
            map.push(prims);
        }
        if !skipped.is_empty() {
            self.warn(format!("skips point and line primitives, and those without positions: {skipped:?}"));
        }
        Ok(map)
    }

    fn primitive(
        &self,
        doc: &gltf::Document,
        where_: &str,
        prim: &gltf::Primitive,
        default_material: u32,
    ) -> Result<MeshDesc> {
        let (positions, normals, uvs, indices) = match prim.extension_value(draco::NAME) {
            Some(ext) => {
                let d = draco::decode(doc, self.views, ext).map_err(|m| self.err(where_, m))?;
                (d.positions, d.normals, d.uvs, Some(d.indices))
            }
            None => self.attributes(where_, prim)?,
        };
        let positions: Vec<Vec3A> = positions.into_iter().map(Vec3A::from).collect();
        let n = positions.len();
        if n == 0 {
            return Err(self.err(where_, "has no vertices"));
        }
        if let Some(count) = normals.as_ref().map(Vec::len).filter(|&c| c != n) {
            return Err(self.err(where_, format!("has {count} normals for {n} positions")));
        }
        if let Some(count) = uvs.as_ref().map(Vec::len).filter(|&c| c != n) {
            return Err(self.err(where_, format!("has {count} texture coordinates for {n} positions")));
        }
        // Quantised normals (KHR_mesh_quantization, Draco) are only nearly unit length.
        let unit = |n: Vec3A| if (n.length_squared() - 1.0).abs() > 1e-4 { n.normalize_or_zero() } else { n };
        let normals = normals.map(|v| v.into_iter().map(|n| unit(Vec3A::from(n))).collect());
        let uvs = uvs.map(|v| v.into_iter().map(Vec2::from).collect());
        let indices = indices.unwrap_or_else(|| (0..n as u32).collect());
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(self.err(where_, format!("index {bad} is out of range: the primitive has {n} vertices")));
        }
        let triangles: Vec<[u32; 3]> = match prim.mode() {
            Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
                .map(|i| {
                    let (a, b, c) = (indices[i], indices[i + 1], indices[i + 2]);
                    if i % 2 == 0 { [a, b, c] } else { [b, a, c] }
                })
                .collect(),
            Mode::TriangleFan => {
                (1..indices.len().saturating_sub(1)).map(|i| [indices[0], indices[i], indices[i + 1]]).collect()
            }
            _ => indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        };
        // Strips restart with repeated indices: drop those empty triangles.
        let triangles = triangles.into_iter().filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]).collect();
        let material = prim.material().index().map_or(default_material, |i| i as u32);
        Ok(MeshDesc { name: where_.to_string(), positions, normals, uvs, triangles, material })
    }

    /// A primitive's positions, normals, texture coordinates and indices from its accessors.
    #[allow(clippy::type_complexity)]
    fn attributes(
        &self,
        where_: &str,
        prim: &gltf::Primitive,
    ) -> Result<(Vec<[f32; 3]>, Option<Vec<[f32; 3]>>, Option<Vec<[f32; 2]>>, Option<Vec<u32>>)> {
        use DataType::{F32, I8, I16, U8, U16};
        let pos = prim.get(&Semantic::Positions).ok_or_else(|| self.err(where_, "has no POSITION attribute"))?;
        let positions = self.floats(where_, &pos, &[F32, I8, U8, I16, U16])?;
        let normals = prim.get(&Semantic::Normals).map(|a| self.floats(where_, &a, &[F32, I8, I16])).transpose()?;
        let uvs =
            prim.get(&Semantic::TexCoords(0)).map(|a| self.floats(where_, &a, &[F32, I8, U8, I16, U16])).transpose()?;
        let indices = prim
            .indices()
            .map(|a| {
                self.defined(where_, &a)?;
                accessor::indices(self.views, &a).map_err(|m| self.err(format!("{where_}, accessor {}", a.index()), m))
            })
            .transpose()?;
        Ok((positions, normals, uvs, indices))
    }

    /// A file without scenes (glTF allows it: a library of nodes): every node no other node
    /// holds, as Blender's importer takes them, with a warning; none, if it has no nodes.
    fn root_nodes<'d>(&mut self, doc: &'d gltf::Document) -> Vec<gltf::Node<'d>> {
        let children: BTreeSet<usize> = doc.nodes().flat_map(|n| n.children()).map(|c| c.index()).collect();
        let roots: Vec<gltf::Node> = doc.nodes().filter(|n| !children.contains(&n.index())).collect();
        self.warn(if roots.is_empty() {
            "holds no scene and no nodes: there is nothing to render".to_string()
        } else {
            format!("holds no scene; myriad renders its {} root nodes", roots.len())
        });
        roots
    }

    fn nodes(&mut self, doc: &gltf::Document, primitives: &[Vec<Option<u32>>], options: &LoadOptions) -> Result<()> {
        let roots: Vec<gltf::Node> = match options.gltf_scene {
            Some(k) => doc
                .scenes()
                .nth(k)
                .ok_or_else(|| {
                    self.err(
                        "scenes",
                        format!("has no scene {k}: the file holds {} (numbered from 0)", doc.scenes().len()),
                    )
                })?
                .nodes()
                .collect(),
            None => match doc.default_scene().or_else(|| doc.scenes().next()) {
                Some(scene) => scene.nodes().collect(),
                None => self.root_nodes(doc),
            },
        };
        // The hierarchy is a forest (`check.rs`): the walk visits each node once.
        let mut stack: Vec<(gltf::Node, Mat4)> = roots.into_iter().map(|n| (n, Mat4::IDENTITY)).collect();
        let (mut range_warned, mut ortho) = (false, Vec::new());
        while let Some((node, parent)) = stack.pop() {
            let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
            let name = node.name().map_or_else(|| format!("node {}", node.index()), str::to_string);
            if let Some(mesh) = node.mesh() {
                for m in primitives[mesh.index()].iter().flatten() {
                    self.desc.instances.push(InstanceDesc { mesh: *m, transform: world, name: name.clone() });
                }
            }
            if let Some(cam) = node.camera() {
                match cam.projection() {
                    gltf::camera::Projection::Perspective(p) => self.desc.cameras.push(CameraDesc {
                        name: name.clone(),
                        placement: CameraPlacement::Matrix(world),
                        fov: p.yfov(),
                        fit: Fit::Vertical,
                        shift: Vec2::ZERO,
                        lens: None,
                        aspect_ratio: p.aspect_ratio(),
                    }),
                    gltf::camera::Projection::Orthographic(_) => ortho.push(name.clone()),
                }
            }
            if let Some(light) = node.light().filter(|l| !self.tolerated.unknown_lights.contains(&l.index())) {
                range_warned |= light.range().is_some();
                let label: Arc<str> = Arc::from(light.name().unwrap_or(&name));
                let position = Vec3A::from(world.w_axis.truncate());
                let direction = (-Vec3A::from(world.z_axis.truncate())).normalize_or_zero();
                let power = Rgb::from(light.color()) * (light.intensity() * options.punctual_scale);
                let size = self.light_size(&label, light.extras());
                self.desc.lights.push(match light.kind() {
                    gltf::khr_lights_punctual::Kind::Point => {
                        LightDesc::Point { name: label, position, intensity: power, lamp: size.lamp() }
                    }
                    gltf::khr_lights_punctual::Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                        let (inner_angle, curve) = if self.blender {
                            (blender_spot_inner(inner_cone_angle, outer_cone_angle), SpotCurve::Smoothstep)
                        } else {
                            (inner_cone_angle, SpotCurve::Quadratic)
                        };
                        LightDesc::Spot {
                            name: label,
                            position,
                            direction,
                            intensity: power,
                            inner_angle,
                            outer_angle: outer_cone_angle,
                            curve,
                            lamp: size.lamp(),
                        }
                    }
                    gltf::khr_lights_punctual::Kind::Directional => LightDesc::Directional {
                        name: label,
                        direction,
                        irradiance: power,
                        angle: size.angle.unwrap_or(0.0),
                        camera_visible: false,
                    },
                });
            }
            stack.extend(node.children().map(|c| (c, world)));
        }
        if range_warned {
            self.warn("punctual light `range` is ignored: light falls off with the inverse square of distance".into());
        }
        if !ortho.is_empty() {
            self.warn(format!("orthographic cameras {ortho:?} are not supported and were skipped"));
        }
        Ok(())
    }
}

/// Material extensions myriad does not render (when a material has them, `info` lists them).
const UNRENDERED_EXTENSIONS: [&str; 6] = [
    "KHR_materials_iridescence",
    "KHR_materials_dispersion",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_materials_unlit",
    "KHR_materials_variants",
];

/// What a material has that myriad reads past: extensions it does not render and textures of
/// the extensions it does (their factors are used).
fn ignored_properties(m: &gltf::Material) -> Vec<String> {
    let mut ignored: Vec<String> =
        UNRENDERED_EXTENSIONS.iter().filter(|e| m.extension_value(e).is_some()).map(|e| e.to_string()).collect();
    if m.transmission().is_some_and(|t| t.transmission_texture().is_some()) {
        ignored.push("KHR_materials_transmission.transmissionTexture".into());
    }
    if m.volume().is_some_and(|v| v.thickness_texture().is_some()) {
        ignored.push("KHR_materials_volume.thicknessTexture".into());
    }
    if let Some(s) = m.specular() {
        for (present, name) in [
            (s.specular_texture().is_some(), "specularTexture"),
            (s.specular_color_texture().is_some(), "specularColorTexture"),
        ] {
            if present {
                ignored.push(format!("KHR_materials_specular.{name}"));
            }
        }
    }
    if let Some(c) = m.extension_value("KHR_materials_clearcoat") {
        for name in ["clearcoatTexture", "clearcoatRoughnessTexture", "clearcoatNormalTexture"] {
            if c.get(name).is_some() {
                ignored.push(format!("KHR_materials_clearcoat.{name}"));
            }
        }
    }
    if m.occlusion_texture().is_some() {
        ignored.push("occlusionTexture (no effect in a path tracer)".into());
    }
    ignored
}

/// A number of extension JSON, if it is one.
fn number(v: Option<&gltf::json::Value>) -> Option<f32> {
    v.and_then(|v| v.as_f64()).map(|v| v as f32)
}

/// `N` numbers of extension JSON, if it is an array of them.
fn number_array<const N: usize>(v: Option<&gltf::json::Value>) -> Option<[f32; N]> {
    let a = v?.as_array()?;
    (a.len() == N).then_some(())?;
    let mut out = [0.0; N];
    for (o, x) in out.iter_mut().zip(a) {
        *o = x.as_f64()? as f32;
    }
    Some(out)
}

/// KHR_texture_transform from raw extension JSON (for normal textures).
fn khr_transform_json(v: &gltf::json::Value) -> UvTransform {
    let pair = |k: &str, d: f32| {
        v.get(k).and_then(|a| a.as_array()).map_or([d, d], |a| {
            [
                a.first().and_then(|x| x.as_f64()).unwrap_or(d as f64) as f32,
                a.get(1).and_then(|x| x.as_f64()).unwrap_or(d as f64) as f32,
            ]
        })
    };
    let rotation = v.get("rotation").and_then(|r| r.as_f64()).unwrap_or(0.0) as f32;
    UvTransform::from_khr(pair("offset", 0.0), rotation, pair("scale", 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_blender_spot_fades_over_its_blend_fraction_of_the_cosine() {
        // Blend 0 (inner = outer): a hard edge. Blend 1 (inner = 0): the fade spans from the
        // outer cone to the axis. Blend 0.3 of a 40° cone: as Cycles, in cosines.
        assert!((blender_spot_inner(0.5, 0.5) - 0.5).abs() < 1e-5);
        assert!(blender_spot_inner(0.0, 0.5) < 1e-3);
        let (outer, blend) = (20f32.to_radians(), 0.3);
        let inner = blender_spot_inner(outer * (1.0 - blend), outer);
        assert!((inner.cos() - (outer.cos() + (1.0 - outer.cos()) * blend)).abs() < 1e-6);
    }
}
