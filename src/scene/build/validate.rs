//! The description's own consistency, before anything is built from it: colours and
//! factors in range, indices that point somewhere, finite transforms, sizes myriad can hold.

use crate::error::{Error, Result};
use crate::limits::MAX_COORDINATE;
use crate::material::Material;
use crate::math::{Mat4, Rgb, Vec3A};
use crate::scene::description::{MeshDesc, SceneDescription};

pub(super) fn check_color(file: &str, what: &str, name: &str, c: Rgb, max: Option<f32>) -> Result<()> {
    if !c.is_finite() {
        return Err(Error::scene(file, what, format!("{name} has a non-finite component {c}")));
    }
    if c.min_element() < 0.0 {
        return Err(Error::scene(
            file,
            what,
            format!("{name} has a negative component {c}; light and colour must be ≥ 0"),
        ));
    }
    if let Some(m) = max
        && c.max_element() > m
    {
        return Err(Error::scene(
            file,
            what,
            format!("{name} {c} exceeds {m}: a surface cannot reflect more than it receives"),
        ));
    }
    Ok(())
}

fn check_unit(file: &str, what: &str, name: &str, x: f32) -> Result<()> {
    if !(0.0..=1.0).contains(&x) {
        return Err(Error::scene(file, what, format!("{name} must be in [0, 1], not {x}")));
    }
    Ok(())
}

/// True for a point myriad can place: finite and within [`MAX_COORDINATE`].
pub(super) fn placeable(p: Vec3A) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_COORDINATE
}

/// An error unless `v` is [`placeable`].
pub(super) fn check_point(file: &str, what: &str, name: &str, v: Vec3A) -> Result<()> {
    if placeable(v) {
        Ok(())
    } else {
        Err(Error::scene(file, what, format!("{name} {v} is not finite or lies beyond ±{MAX_COORDINATE} m")))
    }
}

fn validate_material(file: &str, m: &Material, images: usize) -> Result<()> {
    let what = format!("material '{}'", m.name);
    check_color(file, &what, "base colour", m.base_color, Some(1.0))?;
    check_color(file, &what, "emission", m.emission, None)?;
    check_unit(file, &what, "metallic", m.metallic)?;
    check_unit(file, &what, "roughness", m.roughness)?;
    check_unit(file, &what, "specular", m.specular)?;
    check_unit(file, &what, "coat", m.coat)?;
    check_unit(file, &what, "transmission", m.transmission)?;
    check_color(file, &what, "absorption", m.absorption, None)?;
    check_unit(file, &what, "coat roughness", m.coat_roughness)?;
    check_color(file, &what, "specular colour", m.specular_color, None)?;
    check_color(file, &what, "sheen colour", m.sheen_color, None)?;
    check_unit(file, &what, "sheen roughness", m.sheen_roughness)?;
    check_unit(file, &what, "anisotropy", m.anisotropy)?;
    if !m.anisotropy_rotation.is_finite() {
        return Err(Error::scene(file, what, format!("anisotropy rotation {} is not finite", m.anisotropy_rotation)));
    }
    if !(m.ior > 1.0 && m.ior.is_finite()) {
        return Err(Error::scene(file, what, format!("IOR must be a finite number above 1, not {}", m.ior)));
    }
    let textures = [
        &m.base_color_texture,
        &m.metallic_roughness_texture,
        &m.emission_texture,
        &m.normal_texture.map(|n| n.0),
        &m.sheen_color_texture,
        &m.sheen_roughness_texture,
        &m.anisotropy_texture,
    ];
    if let Some(t) = textures.into_iter().flatten().find(|t| t.image as usize >= images) {
        return Err(Error::scene(file, what, format!("texture uses image {}, but there are {images} images", t.image)));
    }
    Ok(())
}

fn validate_mesh(file: &str, index: usize, m: &MeshDesc, materials: usize) -> Result<()> {
    let what = format!("mesh {index} '{}'", m.name);
    if let Some(i) = m.positions.iter().position(|p| !p.is_finite()) {
        return Err(Error::scene(file, what, format!("vertex {i} has a non-finite coordinate {}", m.positions[i])));
    }
    let n = m.positions.len() as u32;
    if let Some(t) = m.triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
        return Err(Error::scene(
            file,
            what,
            format!("triangle {t} uses vertex {:?}, but there are {n} vertices", m.triangles[t]),
        ));
    }
    let count_ok = |len: Option<usize>| len.is_none_or(|l| l >= m.positions.len());
    if !count_ok(m.normals.as_ref().map(Vec::len)) || !count_ok(m.uvs.as_ref().map(Vec::len)) {
        return Err(Error::scene(file, what, "fewer normals or UVs than positions"));
    }
    if m.material as usize >= materials {
        return Err(Error::scene(
            file,
            what,
            format!("material index {} out of range ({materials} materials)", m.material),
        ));
    }
    Ok(())
}

/// A transform's rows, for messages.
fn rows(m: &Mat4) -> String {
    let r: Vec<String> = (0..4).map(|i| format!("{}", m.row(i))).collect();
    r.join(", ")
}

/// Checks every material, mesh and instance of `desc`.
pub(super) fn description(desc: &SceneDescription) -> Result<()> {
    let file = desc.source.as_str();
    for m in &desc.materials {
        validate_material(file, m, desc.images.len())?;
    }
    for (i, m) in desc.meshes.iter().enumerate() {
        validate_mesh(file, i, m, desc.materials.len())?;
    }
    for inst in &desc.instances {
        let what = format!("instance '{}'", inst.name);
        if inst.mesh as usize >= desc.meshes.len() {
            let n = desc.meshes.len();
            return Err(Error::scene(file, what, format!("refers to mesh {}, but there are {n} meshes", inst.mesh)));
        }
        if !inst.transform.is_finite() {
            return Err(Error::scene(
                file,
                what,
                format!("has a transform with a non-finite entry (rows {})", rows(&inst.transform)),
            ));
        }
    }
    Ok(())
}
