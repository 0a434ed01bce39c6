//! `SceneDescription`: the plain-data scene every loader produces and `scene::build` consumes.
//!
//! Owns: the loader-neutral intermediate representation. RON, OBJ and glTF files all become
//! this; nothing here touches files or builds acceleration structures. Meshes are stored once
//! in object space and placed by instances, so a loader never has to flatten. Positions and
//! colours are validated by `scene::build`, not here.

use std::path::PathBuf;
use std::sync::Arc;

use crate::camera::{Fit, ThinLens};
use crate::light::{EnvironmentLight, LampModel, SpotCurve};
use crate::material::{Image, Material};
use crate::math::{Mat4, Rgb, UVec2, Vec2, Vec3A};

/// A whole scene, before validation and acceleration-structure building.
#[derive(Clone, Debug, Default)]
pub struct SceneDescription {
    /// The file it came from, for messages (may be a label such as `<built-in>`).
    pub source: String,
    /// Cameras; the first is used unless another is asked for by name.
    pub cameras: Vec<CameraDesc>,
    /// Output size the scene asks for, if any.
    pub resolution: Option<UVec2>,
    /// Render settings the scene asks for; the command line overrides them.
    pub render: crate::settings::RenderDefaults,
    /// Materials, indexed by [`MeshDesc::material`].
    pub materials: Vec<Material>,
    /// Decoded images, indexed by the materials' textures.
    pub images: Vec<Image>,
    /// Triangle meshes in object space.
    pub meshes: Vec<MeshDesc>,
    /// Placements of meshes in the world.
    pub instances: Vec<InstanceDesc>,
    /// Lights that are not emissive meshes.
    pub lights: Vec<LightDesc>,
    /// Things the loader skipped or approximated, for the user.
    pub warnings: Vec<String>,
    /// The file format's extensions the file uses (glTF's), each with what myriad does with
    /// it ("ignored" where it does nothing), for `info`.
    pub extensions: Vec<(String, String)>,
    /// Every file read to make it (the scene, its buffers, images, included meshes and
    /// material libraries), in the order read: what a cache of its renders depends on.
    pub inputs: Vec<PathBuf>,
    /// The environment, if any (with a label for messages).
    pub environment: Option<(String, EnvironmentLight)>,
}

/// A perspective camera.
#[derive(Clone, Debug)]
pub struct CameraDesc {
    /// Name (glTF node or camera name).
    pub name: String,
    /// Placement.
    pub placement: CameraPlacement,
    /// Field of view along the fitted dimension, radians.
    pub fov: f32,
    /// Which dimension `fov` spans (glTF: the height).
    pub fit: Fit,
    /// The view's shift in fractions of the fitted dimension's extent (Blender's lens shift).
    pub shift: Vec2,
    /// A thin lens, for depth of field.
    pub lens: Option<ThinLens>,
    /// Width/height the camera was authored for, if known (glTF `aspectRatio`).
    pub aspect_ratio: Option<f32>,
}

/// How a camera is placed in the world.
#[derive(Clone, Copy, Debug)]
pub enum CameraPlacement {
    /// Eye, target and up vector.
    LookAt {
        /// Eye position.
        eye: Vec3A,
        /// Point looked at.
        target: Vec3A,
        /// Up direction.
        up: Vec3A,
    },
    /// A node's world matrix; the camera looks down local −Z with +Y up (glTF).
    Matrix(Mat4),
}

/// An indexed triangle mesh in object space with one material.
#[derive(Clone, Debug, Default)]
pub struct MeshDesc {
    /// Name, for messages.
    pub name: String,
    /// Vertex positions.
    pub positions: Vec<Vec3A>,
    /// Vertex normals, when the file has them (flat shading otherwise).
    pub normals: Option<Vec<Vec3A>>,
    /// Vertex texture coordinates.
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles as vertex-index triples, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Material index.
    pub material: u32,
}

/// One placement of a mesh.
#[derive(Clone, Debug)]
pub struct InstanceDesc {
    /// Index into [`SceneDescription::meshes`].
    pub mesh: u32,
    /// Object-to-world transform.
    pub transform: Mat4,
    /// Name, for messages (node name).
    pub name: String,
}

/// The shape of a point or spot light with a radius (a lamp: seen by rays, casting no
/// shadow); without one it is a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LampShape {
    /// Radius, metres (> 0).
    pub radius: f32,
    /// A disk facing each receiver (Blender's Soft Falloff) or a sphere.
    pub model: LampModel,
    /// Camera rays see it.
    pub camera_visible: bool,
}

/// A light that is not an emissive mesh.
#[derive(Clone, Debug)]
pub enum LightDesc {
    /// Isotropic point light (a lamp of some radius with `lamp`).
    Point {
        /// Label for messages.
        name: Arc<str>,
        /// Position.
        position: Vec3A,
        /// Radiant intensity [W/sr].
        intensity: Rgb,
        /// Its radius and how it looks, when it is not a point.
        lamp: Option<LampShape>,
    },
    /// Spot light (KHR_lights_punctual falloff).
    Spot {
        /// Label for messages.
        name: Arc<str>,
        /// Position.
        position: Vec3A,
        /// Direction the cone points to.
        direction: Vec3A,
        /// On-axis radiant intensity [W/sr].
        intensity: Rgb,
        /// Inner cone half-angle, radians.
        inner_angle: f32,
        /// Outer cone half-angle, radians.
        outer_angle: f32,
        /// The fade between the cones.
        curve: SpotCurve,
        /// Its radius and how it looks, when it is not a point.
        lamp: Option<LampShape>,
    },
    /// Directional light (a sun of some angular size with `angle` > 0).
    Directional {
        /// Label for messages.
        name: Arc<str>,
        /// Direction the light travels in.
        direction: Vec3A,
        /// Irradiance perpendicular to the beam [W/m²].
        irradiance: Rgb,
        /// Angular diameter, radians (0: parallel light).
        angle: f32,
        /// Camera rays see the sun (with an angle).
        camera_visible: bool,
    },
    /// A rectangle or ellipse lamp (Blender's area light): one-sided, seen by rays, casting
    /// no shadow.
    Area {
        /// Label for messages.
        name: Arc<str>,
        /// Centre.
        center: Vec3A,
        /// Half of its first side; it emits towards `u × v`.
        u: Vec3A,
        /// Half of its second side.
        v: Vec3A,
        /// The ellipse inscribed in the rectangle.
        ellipse: bool,
        /// Radiance along its normal [W/(m²·sr)].
        radiance: Rgb,
        /// Spread, radians (π: Lambertian).
        spread: f32,
        /// Camera rays see it.
        camera_visible: bool,
    },
    /// Emissive parallelogram `corner + s·edge1 + t·edge2`, front side along `edge1 × edge2`.
    Quad {
        /// Label for messages (shared by all cells of a grid).
        name: Arc<str>,
        /// Corner.
        corner: Vec3A,
        /// First edge.
        edge1: Vec3A,
        /// Second edge.
        edge2: Vec3A,
        /// Radiance [W/(m²·sr)].
        radiance: Rgb,
        /// Emits from both faces.
        two_sided: bool,
    },
}

impl LightDesc {
    /// The label messages use (`lights[3] Spot`, a glTF node's name).
    pub fn name(&self) -> &str {
        match self {
            LightDesc::Point { name, .. }
            | LightDesc::Spot { name, .. }
            | LightDesc::Directional { name, .. }
            | LightDesc::Area { name, .. }
            | LightDesc::Quad { name, .. } => name,
        }
    }

    /// The light moved by `m` (intensities and a lamp's radius unchanged, as Cycles keeps a
    /// lamp's radius whatever its object's scale).
    pub fn transformed(&self, m: &Mat4) -> LightDesc {
        let dir = |d: &Vec3A| m.transform_vector3a(*d).normalize_or_zero();
        let mut moved = self.clone();
        match &mut moved {
            LightDesc::Point { position, .. } => *position = m.transform_point3a(*position),
            LightDesc::Spot { position, direction, .. } => {
                *position = m.transform_point3a(*position);
                *direction = dir(direction);
            }
            LightDesc::Directional { direction, .. } => *direction = dir(direction),
            LightDesc::Area { center, u, v, .. } => {
                *center = m.transform_point3a(*center);
                *u = m.transform_vector3a(*u);
                *v = m.transform_vector3a(*v);
            }
            LightDesc::Quad { corner, edge1, edge2, .. } => {
                *corner = m.transform_point3a(*corner);
                *edge1 = m.transform_vector3a(*edge1);
                *edge2 = m.transform_vector3a(*edge2);
            }
        }
        moved
    }
}

impl SceneDescription {
    /// Adds everything of `other` except its cameras and render settings, placed by
    /// `transform`; with `material`, every mesh of `other` uses that material of `self`.
    pub fn include(&mut self, other: SceneDescription, transform: Mat4, material: Option<u32>) {
        let (mesh_base, material_base, image_base) =
            (self.meshes.len() as u32, self.materials.len() as u32, self.images.len() as u32);
        self.images.extend(other.images);
        self.materials.extend(other.materials.into_iter().map(|mut m| {
            for t in [&mut m.base_color_texture, &mut m.metallic_roughness_texture, &mut m.emission_texture]
                .into_iter()
                .flatten()
            {
                t.image += image_base;
            }
            if let Some((t, _)) = &mut m.normal_texture {
                t.image += image_base;
            }
            m
        }));
        self.meshes.extend(other.meshes.into_iter().map(|mut m| {
            m.material = material.unwrap_or(material_base + m.material);
            m
        }));
        self.instances.extend(other.instances.into_iter().map(|i| InstanceDesc {
            mesh: mesh_base + i.mesh,
            transform: transform * i.transform,
            name: i.name,
        }));
        self.lights.extend(other.lights.iter().map(|l| l.transformed(&transform)));
        self.warnings.extend(other.warnings);
        self.inputs.extend(other.inputs);
    }
}
