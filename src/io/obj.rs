//! Wavefront `.obj` (+ `.mtl`) → meshes and materials, through tobj.
//!
//! Each `o`/`g` group becomes a mesh (polygons triangulated by tobj). Material mapping
//! (documented in docs/scene-format.md): `Kd` → base colour (default 0.8 grey), `Ke` →
//! emitted radiance (one-sided: the counter-clockwise side emits), `Ks` → specular factor
//! (max component), `Ns` → roughness = (2/(Ns+2))^¼ (the Blinn-Phong exponent's
//! Beckmann-equivalent alpha, alpha = roughness²), the PBR extension keys `Pr`/`Pm`
//! (roughness, metallic) when present, `map_Kd` and `map_Ke` → base-colour and emission
//! textures (sRGB; `map_Ke` without `Ke` emits the texture as is). A missing `.mtl` is a
//! warning and the mesh is grey; a missing texture is a warning and the factor is used.

use std::path::Path;

use crate::error::{Error, Result};
use crate::material::{Image, Material, TextureRef};
use crate::math::{Mat4, Rgb, Vec2, Vec3A};
use crate::scene::description::{InstanceDesc, MeshDesc, SceneDescription};

/// Meshes, materials and texture images of one `.obj` file; `MeshDesc::material` indexes
/// `materials`, texture references index `images`.
#[derive(Debug, Default)]
pub struct LoadedMeshes {
    /// One mesh per group.
    pub meshes: Vec<MeshDesc>,
    /// The file's materials, plus a default grey one at the end when some group has none.
    pub materials: Vec<Material>,
    /// Images the materials' `map_Kd` / `map_Ke` name.
    pub images: Vec<Image>,
    /// What was skipped or assumed.
    pub warnings: Vec<String>,
    /// Files read: the OBJ, its material libraries, their textures.
    pub inputs: Vec<std::path::PathBuf>,
}

fn parse_f32(m: &tobj::Material, key: &str) -> Option<f32> {
    m.unknown_param.get(key).and_then(|s| s.trim().parse().ok())
}

/// Loads a texture named in the `.mtl`, relative to the `.obj`; a missing or unreadable one is
/// a warning (the material keeps its factor) so that a mesh is never silently grey.
fn texture(name: Option<&str>, dir: &Path, out: &mut LoadedMeshes, material: &str) -> Option<TextureRef> {
    let name = name?.split_whitespace().last()?;
    let path = dir.join(name);
    out.inputs.push(path.clone());
    match super::image_file::load(&path) {
        Ok(img) => {
            out.images.push(img);
            Some(TextureRef::plain((out.images.len() - 1) as u32))
        }
        Err(e) => {
            out.warnings.push(format!("material '{material}': texture not loaded ({e}); using its colour factor"));
            None
        }
    }
}

fn convert_material(m: &tobj::Material, dir: &Path, out: &mut LoadedMeshes) -> Material {
    let kd = m.diffuse.map_or(Rgb::splat(0.8), Rgb::from);
    let specular = m.specular.map_or(0.0, |ks| ks.iter().fold(0.0f32, |a, &b| a.max(b)).clamp(0.0, 1.0));
    let roughness =
        parse_f32(m, "Pr").unwrap_or_else(|| m.shininess.map_or(1.0, |ns| (2.0 / (ns.max(0.0) + 2.0)).powf(0.25)));
    let base_color_texture = texture(m.diffuse_texture.as_deref(), dir, out, &m.name);
    let emission_texture = texture(m.unknown_param.get("map_Ke").map(String::as_str), dir, out, &m.name);
    let mut emission = m.emissive.map_or(Rgb::ZERO, Rgb::from);
    if emission == Rgb::ZERO && emission_texture.is_some() {
        // map_Ke without Ke: the texture alone sets the emission.
        emission = Rgb::ONE;
    }
    Material {
        metallic: parse_f32(m, "Pm").unwrap_or(0.0).clamp(0.0, 1.0),
        roughness: roughness.clamp(0.0, 1.0),
        specular,
        emission,
        double_sided: false,
        base_color_texture,
        emission_texture,
        ..Material::diffuse(&m.name, kd)
    }
}

/// Reads a text file, without a leading byte-order mark; not UTF-8 is an error naming it.
fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let text = String::from_utf8(bytes)
        .map_err(|e| Error::scene(path.display().to_string(), "file", format!("is not UTF-8 text: {e}")))?;
    Ok(super::strip_bom(&text).to_string())
}

/// The colour statements of an MTL file, which tobj reads as exactly three numbers.
const COLOR_KEYS: [&str; 4] = ["Ka", "Kd", "Ks", "Ke"];

/// `text` (an MTL file) with every colour statement given three numbers: one number means
/// grey, as the format allows; two, or words that are not numbers, are an error naming the
/// line.
fn normalise_mtl(text: &str, file: &str) -> Result<String> {
    let mut out = String::with_capacity(text.len());
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or("");
        if COLOR_KEYS.contains(&key) {
            let numbers: Vec<f32> = words.map(str::parse).collect::<Result<_, _>>().map_err(|_| {
                Error::scene(
                    file,
                    format!("line {}", i + 1),
                    format!("{key} takes numbers (r g b), not '{}'", line.trim()),
                )
            })?;
            match numbers[..] {
                [v] => out.push_str(&format!("{key} {v} {v} {v}")),
                [r, g, b] => out.push_str(&format!("{key} {r} {g} {b}")),
                _ => {
                    return Err(Error::scene(
                        file,
                        format!("line {}", i + 1),
                        format!("{key} needs three numbers r g b (or one for grey), found '{}'", line.trim()),
                    ));
                }
            }
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    Ok(out)
}

/// The first face of an OBJ text that refers to a vertex, texture coordinate or normal not
/// defined before it (tobj says only that one does): its line number and what is wrong.
/// Indices count from 1; negative ones count back from the last defined.
fn face_out_of_range(text: &str) -> Option<(usize, String)> {
    let mut defined = [0i64; 3];
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => defined[0] += 1,
            Some("vt") => defined[1] += 1,
            Some("vn") => defined[2] += 1,
            Some("f") => {
                for corner in words {
                    for (k, index) in corner.split('/').enumerate().take(3) {
                        let Ok(n) = index.parse::<i64>() else { continue };
                        let (kind, kinds) = [
                            ("vertex", "vertices"),
                            ("texture coordinate", "texture coordinates"),
                            ("normal", "normals"),
                        ][k];
                        let count = defined[k];
                        if n == 0 || n > count || n < -count {
                            return Some((
                                i + 1,
                                format!(
                                    "face '{}' uses {kind} {n}, but {count} {kinds} are defined before it \
                                     (indices count from 1, or back from -1)",
                                    line.trim()
                                ),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// Loads the meshes, materials and textures of an `.obj` file.
pub fn load_meshes(path: &Path) -> Result<LoadedMeshes> {
    let file = path.display().to_string();
    let dir = path.parent().unwrap_or(Path::new("."));
    let text = read_text(path)?;
    // tobj hands the material loader a name; our errors about the file it names come back
    // through here.
    let mtl_error = std::cell::RefCell::new(None);
    let libraries = std::cell::RefCell::new(Vec::new());
    let load_mtl = |name: &Path| {
        let mtl = dir.join(name);
        libraries.borrow_mut().push(mtl.clone());
        let text = read_text(&mtl).map_err(|_| tobj::LoadError::OpenFileFailed)?;
        let text = normalise_mtl(&text, &mtl.display().to_string()).map_err(|e| {
            mtl_error.replace(Some(e));
            tobj::LoadError::MaterialParseError
        })?;
        tobj::load_mtl_buf(&mut text.as_bytes())
    };
    let (models, materials) = tobj::load_obj_buf(&mut text.as_bytes(), &tobj::GPU_LOAD_OPTIONS, load_mtl).map_err(
        |e| match face_out_of_range(&text) {
            Some((line, message)) => Error::scene(&file, format!("line {line}"), message),
            None => Error::scene(&file, "file", format!("not a readable OBJ file: {e}")),
        },
    )?;
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let mut out = LoadedMeshes { inputs: vec![path.to_path_buf()], ..Default::default() };
    out.inputs.extend(libraries.into_inner());
    match materials {
        Ok(ms) => {
            let converted: Vec<Material> = ms.iter().map(|m| convert_material(m, dir, &mut out)).collect();
            out.materials = converted;
        }
        Err(e) => out.warnings.push(format!("{file}: material library not loaded ({e}); its meshes are grey")),
    }
    let mut default_material = None;
    for model in models {
        let m = &model.mesh;
        let what = format!("group '{}'", model.name);
        let positions: Vec<Vec3A> = m.positions.chunks_exact(3).map(|p| Vec3A::new(p[0], p[1], p[2])).collect();
        let normals =
            (!m.normals.is_empty()).then(|| m.normals.chunks_exact(3).map(|n| Vec3A::new(n[0], n[1], n[2])).collect());
        let uvs =
            (!m.texcoords.is_empty()).then(|| m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])).collect());
        let triangles: Vec<[u32; 3]> = m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        if triangles.is_empty() {
            out.warnings.push(format!("{file}: {what} has no faces; skipped"));
            continue;
        }
        let material = match m.material_id.filter(|&i| i < out.materials.len()) {
            Some(i) => i as u32,
            None => *default_material.get_or_insert_with(|| {
                out.materials.push(Material::diffuse("obj-default", Rgb::splat(0.8)));
                (out.materials.len() - 1) as u32
            }),
        };
        out.meshes.push(MeshDesc { name: model.name.clone(), positions, normals, uvs, triangles, material });
    }
    Ok(out)
}

/// An `.obj` file as a whole scene (no camera: pass `--camera auto` or place it in a RON file).
pub fn load_scene(path: &Path) -> Result<SceneDescription> {
    let loaded = load_meshes(path)?;
    let mut desc = SceneDescription { source: path.display().to_string(), ..Default::default() };
    desc.materials = loaded.materials;
    desc.images = loaded.images;
    desc.warnings = loaded.warnings;
    desc.inputs = loaded.inputs;
    for (i, mesh) in loaded.meshes.into_iter().enumerate() {
        desc.instances.push(InstanceDesc { mesh: i as u32, transform: Mat4::IDENTITY, name: mesh.name.clone() });
        desc.meshes.push(mesh);
    }
    Ok(desc)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_face_past_the_vertices_defined_is_found_by_its_line() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1 2 3\n\nf 1/1 2/1 3/2\n";
        let (line, message) = face_out_of_range(text).unwrap();
        assert_eq!(line, 7);
        assert!(message.contains("texture coordinate 2") && message.contains("1 texture coordinates"), "{message}");
        assert_eq!(face_out_of_range("v 0 0 0\nf -1 -1 -2\n").unwrap().0, 2);
        assert_eq!(face_out_of_range("v 0 0 0\nf 0 1 1\n").unwrap().0, 2);
        assert!(face_out_of_range("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n").is_none());
    }
}
