//! Wavefront `.obj` (+ `.mtl`) → meshes and materials, through tobj.
//!
//! Each `o`/`g` group becomes a mesh (polygons triangulated by tobj). Material mapping
//! (documented in README "Scene formats"): `Kd` → base colour (default 0.8 grey), `Ke` →
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
}

fn parse_f32(m: &tobj::Material, key: &str) -> Option<f32> {
    m.unknown_param.get(key).and_then(|s| s.trim().parse().ok())
}

/// Loads a texture named in the `.mtl`, relative to the `.obj`; a missing or unreadable one is
/// a warning (the material keeps its factor) so that a mesh is never silently grey.
fn texture(name: Option<&str>, dir: &Path, out: &mut LoadedMeshes, material: &str) -> Option<TextureRef> {
    let name = name?.split_whitespace().last()?;
    let path = dir.join(name);
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

/// Loads the meshes, materials and textures of an `.obj` file.
pub fn load_meshes(path: &Path) -> Result<LoadedMeshes> {
    std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    let file = path.display().to_string();
    let dir = path.parent().unwrap_or(Path::new("."));
    let (models, materials) = tobj::load_obj(path, &tobj::GPU_LOAD_OPTIONS)
        .map_err(|e| Error::scene(&file, "file", format!("not a readable OBJ file: {e}")))?;
    let mut out = LoadedMeshes::default();
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
        out.meshes.push(MeshDesc {
            name: model.name.clone(),
            positions,
            normals,
            uvs,
            triangles,
            material,
            quads: false,
        });
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
    for (i, mesh) in loaded.meshes.into_iter().enumerate() {
        desc.instances.push(InstanceDesc { mesh: i as u32, transform: Mat4::IDENTITY, name: mesh.name.clone() });
        desc.meshes.push(mesh);
    }
    Ok(desc)
}
