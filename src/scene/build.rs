//! `SceneDescription` → `Scene`: validate, place instances, turn emitters into lights, build
//! the BVH.
//!
//! Every check names the file and the object, so that a bad scene is an error a user can act
//! on, never a panic or a silently black image.

use std::time::Instant;

use std::sync::Arc;

use super::description::{CameraDesc, CameraPlacement, LightDesc, MeshDesc, SceneDescription};
use super::{Scene, SceneStats};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::geometry::{Attributes, GeometryBuilder, NO_LIGHT};
use crate::light::{AreaEmission, DistantLight, Light, PointLight, QuadLight, SpotLight, TriangleLight};
use crate::material::{Image, Material};
use crate::math::{Mat3, Mat4, Rgb, UVec2, Vec3A};

/// Choices made when building, usually from the command line.
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// Output size; default: the scene's, else 640 wide at the camera's aspect ratio.
    pub resolution: Option<UVec2>,
    /// Camera to use, by name; default: the first.
    pub camera: Option<String>,
}

/// Width used when neither the command line nor the scene gives a resolution.
const DEFAULT_WIDTH: u32 = 640;

fn check_color(file: &str, what: &str, name: &str, c: Rgb, max: Option<f32>) -> Result<()> {
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

fn validate_material(file: &str, m: &Material, images: usize) -> Result<()> {
    let what = format!("material '{}'", m.name);
    check_color(file, &what, "base colour", m.base_color, Some(1.0))?;
    check_color(file, &what, "emission", m.emission, None)?;
    check_unit(file, &what, "metallic", m.metallic)?;
    check_unit(file, &what, "roughness", m.roughness)?;
    check_unit(file, &what, "specular", m.specular)?;
    let textures =
        [&m.base_color_texture, &m.metallic_roughness_texture, &m.emission_texture, &m.normal_texture.map(|n| n.0)];
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
    if m.quads && !m.triangles.len().is_multiple_of(2) {
        return Err(Error::scene(file, what, "a quad mesh needs an even number of triangles"));
    }
    Ok(())
}

fn finite3(file: &str, what: &str, name: &str, v: Vec3A) -> Result<()> {
    if v.is_finite() { Ok(()) } else { Err(Error::scene(file, what, format!("{name} {v} is not finite"))) }
}

/// What placing meshes needs to know besides the mesh.
struct Placer<'a> {
    desc: &'a SceneDescription,
    images: &'a Arc<Vec<Image>>,
    geo: GeometryBuilder,
    lights: Vec<Light>,
    stats: SceneStats,
    degenerate_emitters: usize,
}

impl Placer<'_> {
    /// Pushes a mesh's vertex attributes (object space, or transformed by `m`).
    fn attributes(&mut self, mesh: &MeshDesc, m: Option<Mat4>) -> Option<Attributes> {
        if mesh.normals.is_none() && mesh.uvs.is_none() {
            return None;
        }
        let normals: Option<Vec<Vec3A>> = mesh.normals.as_ref().map(|ns| match m {
            Some(m) => {
                let nm = Mat3::from_mat4(m).inverse().transpose();
                ns.iter().map(|&n| (nm * n).normalize_or_zero()).collect()
            }
            None => ns.clone(),
        });
        let base = self.geo.push_vertices(normals.as_deref(), mesh.uvs.as_deref(), mesh.positions.len());
        Some(Attributes { base, smooth: mesh.normals.is_some(), has_uv: mesh.uvs.is_some() })
    }

    /// Adds a shared mesh once, in object space, and each of its placements.
    fn place_shared(&mut self, mesh: &MeshDesc, transforms: &[Mat4]) {
        let masked = self.desc.materials[mesh.material as usize].alpha_cutoff.is_some();
        let attr = self.attributes(mesh, None);
        let block = self.geo.add_shared_mesh(&mesh.positions, &mesh.triangles, attr, mesh.material, masked);
        for &m in transforms {
            self.geo.add_instance(block, m);
        }
        self.stats.instances += transforms.len();
    }

    /// Adds every triangle of one placement to the flattened block, creating lights for
    /// emissive ones.
    fn place_flat(&mut self, mesh: &MeshDesc, m: Mat4) {
        let material = &self.desc.materials[mesh.material as usize];
        // A mirroring transform reverses the winding; swap two corners to keep the front
        // side (glTF: the front of a negative-determinant node is its clockwise side).
        let flip = Mat3::from_mat4(m).determinant() < 0.0;
        let positions: Vec<Vec3A> = mesh.positions.iter().map(|&p| m.transform_point3a(p)).collect();
        let attr = self.attributes(mesh, Some(m));
        let emission = AreaEmission { radiance: material.emission, two_sided: material.double_sided };
        let (emissive, masked) = (material.is_emissive(), material.alpha_cutoff.is_some());
        let corners = |t: [u32; 3]| if flip { [t[0], t[2], t[1]] } else { t };
        self.stats.instances += 1;
        if emissive && mesh.quads {
            for pair in mesh.triangles.chunks_exact(2) {
                let [a, b, _] = pair[0].map(|i| positions[i as usize]);
                let d = positions[pair[1][2] as usize];
                let (e1, e2) = if flip { (d - a, b - a) } else { (b - a, d - a) };
                let id = match QuadLight::new(a, e1, e2, emission) {
                    Some(q) => self.add_light(Light::Quad(q), 2),
                    None => {
                        self.degenerate_emitters += 2;
                        NO_LIGHT
                    }
                };
                for &t in pair {
                    let t = corners(t);
                    self.geo.push_triangle(t.map(|i| positions[i as usize]), t, attr, mesh.material, id, masked);
                }
            }
            return;
        }
        for &t in &mesh.triangles {
            let t = corners(t);
            let mut id = NO_LIGHT;
            if emissive {
                let light = TriangleLight::new(t.map(|i| positions[i as usize]), emission).map(|l| {
                    match (&material.emission_texture, &mesh.uvs) {
                        (Some(tex), Some(uvs)) => l.with_texture(*tex, t.map(|i| uvs[i as usize]), self.images.clone()),
                        _ => l,
                    }
                });
                match light {
                    Some(l) => id = self.add_light(Light::Triangle(l), 1),
                    None => self.degenerate_emitters += 1,
                }
            }
            self.geo.push_triangle(t.map(|i| positions[i as usize]), t, attr, mesh.material, id, masked);
        }
    }

    fn add_light(&mut self, light: Light, triangles: usize) -> u32 {
        self.lights.push(light);
        self.stats.emissive_triangles += triangles;
        (self.lights.len() - 1) as u32
    }
}

/// Validates `desc` and builds the scene (BVH built in the current rayon pool).
pub fn build(desc: SceneDescription, opts: &BuildOptions) -> Result<Scene> {
    let start = Instant::now();
    let file = desc.source.as_str();
    for m in &desc.materials {
        validate_material(file, m, desc.images.len())?;
    }
    for (i, m) in desc.meshes.iter().enumerate() {
        validate_mesh(file, i, m, desc.materials.len())?;
    }
    for inst in &desc.instances {
        if inst.mesh as usize >= desc.meshes.len() || !inst.transform.is_finite() {
            return Err(Error::scene(
                file,
                format!("instance '{}'", inst.name),
                "refers to a missing mesh or has a non-finite transform",
            ));
        }
    }

    // Camera and resolution (`auto` is placed once the scene's bounds are known).
    let cam_desc = match opts.camera.as_deref() {
        Some(AUTO_CAMERA) => None,
        Some(name) => Some(desc.cameras.iter().find(|c| c.name == name).ok_or_else(|| {
            let names: Vec<&str> = desc.cameras.iter().map(|c| c.name.as_str()).collect();
            Error::scene(
                file,
                "cameras",
                format!("no camera named '{name}'; the scene has {names:?} (or pass --camera auto)"),
            )
        })?),
        None => Some(desc.cameras.first().ok_or_else(|| {
            Error::scene(
                file,
                "cameras",
                "the scene has no camera; add one (in Blender: a camera object, exported with 'Cameras' on), \
                 or pass --camera auto to frame the whole scene",
            )
        })?),
    };
    let resolution = opts.resolution.or(desc.resolution).unwrap_or_else(|| {
        let aspect = cam_desc.and_then(|c| c.aspect_ratio).filter(|a| *a > 0.0 && a.is_finite()).unwrap_or(4.0 / 3.0);
        UVec2::new(DEFAULT_WIDTH, ((DEFAULT_WIDTH as f32 / aspect).round() as u32).max(1))
    });

    let mut materials = desc.materials.clone();
    let images = Arc::new(desc.images.clone());
    let mut placer = Placer {
        desc: &desc,
        images: &images,
        geo: GeometryBuilder::new(),
        lights: Vec::new(),
        stats: SceneStats::default(),
        degenerate_emitters: 0,
    };
    // A mesh placed more than once is stored once and instanced, unless it emits (each
    // emitting triangle is a light of its own, in world space).
    let mut placements: Vec<Vec<Mat4>> = vec![Vec::new(); desc.meshes.len()];
    for inst in &desc.instances {
        placements[inst.mesh as usize].push(inst.transform);
    }
    for (mesh, transforms) in desc.meshes.iter().zip(&placements) {
        if transforms.len() > 1 && !desc.materials[mesh.material as usize].is_emissive() {
            placer.place_shared(mesh, transforms);
        } else {
            for &m in transforms {
                placer.place_flat(mesh, m);
            }
        }
    }
    let Placer { mut geo, mut lights, mut stats, degenerate_emitters, .. } = placer;

    // Lights that are not meshes.
    let mut emitter_material = None;
    for (i, l) in desc.lights.iter().enumerate() {
        let light = match l {
            LightDesc::Point { name, position, intensity } => {
                let what = format!("light {i} '{name}'");
                finite3(file, &what, "position", *position)?;
                check_color(file, &what, "intensity", *intensity, None)?;
                Light::Point(PointLight { position: *position, intensity: *intensity })
            }
            LightDesc::Spot { name, position, direction, intensity, inner_angle, outer_angle } => {
                let what = format!("light {i} '{name}'");
                finite3(file, &what, "position", *position)?;
                check_color(file, &what, "intensity", *intensity, None)?;
                let direction = direction
                    .try_normalize()
                    .ok_or_else(|| Error::scene(file, &what, "direction must be a non-zero vector"))?;
                if !(*outer_angle > 0.0
                    && *outer_angle <= std::f32::consts::PI
                    && *inner_angle >= 0.0
                    && inner_angle <= outer_angle)
                {
                    return Err(Error::scene(
                        file,
                        what,
                        format!("cone angles need 0 ≤ inner ({inner_angle}) ≤ outer ({outer_angle}) ≤ π, outer > 0"),
                    ));
                }
                Light::Spot(SpotLight {
                    position: *position,
                    direction,
                    intensity: *intensity,
                    cos_inner: inner_angle.cos(),
                    cos_outer: outer_angle.cos(),
                })
            }
            LightDesc::Directional { name, direction, irradiance } => {
                let what = format!("light {i} '{name}'");
                check_color(file, &what, "irradiance", *irradiance, None)?;
                let direction = direction
                    .try_normalize()
                    .ok_or_else(|| Error::scene(file, &what, "direction must be a non-zero vector"))?;
                Light::Distant(DistantLight { direction, irradiance: *irradiance })
            }
            LightDesc::Quad { name, corner, edge1, edge2, radiance, two_sided } => {
                let what = format!("light {i} '{name}'");
                finite3(file, &what, "corner", *corner)?;
                finite3(file, &what, "edge1", *edge1)?;
                finite3(file, &what, "edge2", *edge2)?;
                check_color(file, &what, "radiance", *radiance, None)?;
                let q = QuadLight::new(
                    *corner,
                    *edge1,
                    *edge2,
                    AreaEmission { radiance: *radiance, two_sided: *two_sided },
                )
                .ok_or_else(|| Error::scene(file, &what, "zero area: its two edges are parallel or zero"))?;
                let mat = *emitter_material.get_or_insert_with(|| {
                    materials.push(Material { name: "<light>".into(), ..Material::diffuse("", Rgb::ZERO) });
                    (materials.len() - 1) as u32
                });
                let id = lights.len() as u32;
                for t in q.triangles() {
                    geo.push_triangle(t, [0, 1, 2], None, mat, id, false);
                }
                stats.emissive_triangles += 2;
                Light::Quad(q)
            }
        };
        lights.push(light);
    }

    let mut warnings = desc.warnings.clone();
    if degenerate_emitters > 0 {
        warnings.push(format!("{degenerate_emitters} emissive triangles have zero area and do not emit"));
    }

    // Bounds of everything, for directional lights and reports.
    let (mut lo, mut hi) = (Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN));
    let (geometry, _) = geo.build();
    for (v, _) in geometry.world_triangles() {
        for p in v {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    for l in &lights {
        if let Light::Point(PointLight { position, .. }) | Light::Spot(SpotLight { position, .. }) = l {
            lo = lo.min(*position);
            hi = hi.max(*position);
        }
    }
    let (center, radius) =
        if lo.x <= hi.x { (0.5 * (lo + hi), (0.5 * (hi - lo).length()).max(1e-3)) } else { (Vec3A::ZERO, 1.0) };

    let (camera, camera_name) = match cam_desc {
        Some(c) => (scene_camera(file, c, resolution)?, c.name.clone()),
        None => (auto_camera(center, radius, resolution), AUTO_CAMERA.to_string()),
    };

    let accel = geometry.accel.stats();
    stats.meshes = desc.meshes.len();
    stats.cameras = desc.cameras.iter().map(|c| c.name.clone()).collect();
    stats.triangles = geometry.triangle_count();
    stats.stored_triangles = geometry.stored_triangle_count();
    stats.bvh_build_time = accel.build_time;
    stats.geometry_bytes = geometry.memory_bytes();
    lights.shrink_to_fit();
    stats.light_bytes = lights.capacity() * std::mem::size_of::<Light>();
    stats.build_time = start.elapsed();
    Ok(Scene {
        source: desc.source.clone(),
        camera,
        camera_name,
        geometry,
        materials,
        images,
        lights,
        center,
        radius,
        render: desc.render,
        stats,
        warnings,
    })
}

/// The `--camera` value that frames the whole scene instead of using one of its cameras.
pub const AUTO_CAMERA: &str = "auto";

/// The field of view of the `auto` camera, in degrees.
const AUTO_YFOV_DEG: f32 = 40.0;

/// A scene camera at the given resolution, or an error naming it when it is degenerate.
fn scene_camera(file: &str, c: &CameraDesc, resolution: UVec2) -> Result<Camera> {
    match c.placement {
        CameraPlacement::LookAt { eye, target, up } => Camera::look_at(eye, target, up, c.yfov, resolution),
        CameraPlacement::Matrix(m) => Camera::from_matrix(&m, c.yfov, resolution),
    }
    .ok_or_else(|| {
        Error::scene(
            file,
            format!("camera '{}'", c.name),
            "degenerate: eye equals target, up is parallel to the view, or the field of view is not in (0°, 180°)",
        )
    })
}

/// A camera on +Z looking down −Z at the centre of the scene's bounding sphere, slightly from
/// above, far enough back that the whole sphere fits the narrower field of view.
fn auto_camera(center: Vec3A, radius: f32, resolution: UVec2) -> Camera {
    let yfov = AUTO_YFOV_DEG.to_radians();
    let aspect = resolution.x as f32 / resolution.y as f32;
    let half = (0.5 * yfov).tan().min((0.5 * yfov).tan() * aspect).atan();
    let distance = radius / half.sin();
    let dir = Vec3A::new(0.0, 0.25, 1.0).normalize();
    Camera::look_at(center + distance * dir, center, Vec3A::Y, yfov, resolution)
        .expect("the auto camera has a finite, non-degenerate placement")
}
