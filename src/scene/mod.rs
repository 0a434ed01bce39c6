//! The renderable scene: immutable, `Sync`, built once from a [`SceneDescription`].
//!
//! Owns: [`Scene`] (camera, geometry with its BVH, materials, lights, bounds) and the
//! [`SceneReport`] its build makes (source, camera name, the file's render settings,
//! statistics, warnings, files read),
//! the description types and the RON format (plain data), procedural shapes, the built-in
//! default scene, and `build` (validate, flatten instances, emissive surfaces → lights).
//! Depends on geometry, material, light and camera; never touches files (the `io` loaders
//! produce descriptions).

mod build;
pub mod description;
pub mod format;
pub mod shapes;

pub use build::{AUTO_CAMERA, BuildOptions, MAX_RESOLUTION, build};
pub use description::SceneDescription;

use std::time::Duration;

use crate::camera::Camera;
use crate::geometry::{BoxBvh, Geometry, Ray, SurfaceHit};
use crate::light::{LampHit, Light};
use crate::material::{Image, Material};
use crate::math::Vec3A;
use crate::sampling::fmix64;

/// Counts, sizes and timings of a built scene.
#[derive(Clone, Debug, Default)]
pub struct SceneStats {
    /// Triangles rendered (every instance counted).
    pub triangles: usize,
    /// Triangles stored (a mesh shared by several instances counted once).
    pub stored_triangles: usize,
    /// Triangles that emit (one light each, or two per quad light).
    pub emissive_triangles: usize,
    /// Mesh instances placed.
    pub instances: usize,
    /// Distinct meshes in the description (a glTF primitive, an OBJ group, a RON shape).
    pub meshes: usize,
    /// Names of the cameras the scene defines.
    pub cameras: Vec<String>,
    /// Time to build the BVH.
    pub bvh_build_time: Duration,
    /// The ray tracer the BVH is for (`builtin`, `embree`).
    pub tracer: &'static str,
    /// Time for the whole build (validation, flattening, lights, BVH).
    pub build_time: Duration,
    /// Bytes of geometry and BVH.
    pub geometry_bytes: usize,
    /// Bytes of the light list.
    pub light_bytes: usize,
}

/// What building a scene found, for people and for caches: where it came from, the camera
/// chosen, the render settings the file asked for, counts and timings, warnings, and every
/// file read. Nothing here is needed to render.
#[derive(Clone, Debug, Default)]
pub struct SceneReport {
    /// Where it came from.
    pub source: String,
    /// Name of the camera in use.
    pub camera_name: String,
    /// The image size the command line, else the scene, asked for (else 640 wide at the
    /// camera's aspect ratio); what renders of this scene use unless told otherwise.
    pub resolution: crate::math::UVec2,
    /// Render settings the scene asked for.
    pub render: crate::settings::RenderDefaults,
    /// Counts and timings.
    pub stats: SceneStats,
    /// What the loader and the build skipped or approximated.
    pub warnings: Vec<String>,
    /// The file's format extensions and what myriad does with each
    /// ([`SceneDescription::extensions`]).
    pub extensions: Vec<(String, String)>,
    /// Every file the scene was read from ([`SceneDescription::inputs`]).
    pub inputs: Vec<std::path::PathBuf>,
}

/// A scene ready to render: geometry, materials, lights and the camera, and nothing else.
pub struct Scene {
    /// The camera in use; the image size is a render setting.
    pub camera: Camera,
    /// Triangles and the BVH.
    pub geometry: Geometry,
    /// Materials, indexed by the triangles.
    pub materials: Vec<Material>,
    /// Images the textures of materials and emitters read; passed to whatever samples them.
    pub images: Vec<Image>,
    /// Every light; emissive triangles point into this list.
    pub lights: Vec<Light>,
    /// The environment light's index in `lights`, if there is one: what rays that leave the
    /// scene see.
    pub environment: Option<u32>,
    /// The lamps: lights with a shape of their own outside the geometry, which rays see along
    /// their way but which stop nothing.
    pub lamps: Lamps,
    /// Suns with an angle, by index in `lights`: rays that leave the scene see them too.
    pub suns: Vec<u32>,
    /// Centre of the bounding sphere of everything.
    pub center: Vec3A,
    /// Radius of that sphere (sizes directional lights' power).
    pub radius: f32,
    /// Whether next-event estimation looks for light through smooth glass
    /// ([`crate::integrator::mnee`]): some material is smooth glass and some light one it
    /// connects ([`Light::connects_through_glass`]).
    pub caustics: bool,
}

/// The lamps of a scene and the BVH over their shapes.
pub struct Lamps {
    bvh: BoxBvh,
    /// The light index of each box.
    ids: Vec<u32>,
    /// Whether any lamp is seen by camera rays.
    camera_visible: bool,
}

impl Lamps {
    /// The lamps among `lights` (those with [`Light::lamp_bounds`]).
    pub fn new(lights: &[Light]) -> Self {
        let (mut boxes, mut ids) = (Vec::new(), Vec::new());
        for (i, light) in lights.iter().enumerate() {
            if let Some(b) = light.lamp_bounds() {
                boxes.push(b);
                ids.push(i as u32);
            }
        }
        let camera_visible = ids.iter().any(|&i| lights[i as usize].camera_visible());
        Self { bvh: BoxBvh::build(&boxes), ids, camera_visible }
    }

    /// True when the scene has none.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Whether camera rays may see some lamp.
    #[inline]
    pub fn camera_visible(&self) -> bool {
        self.camera_visible
    }

    /// Bytes of the BVH and the index.
    pub fn memory_bytes(&self) -> usize {
        self.bvh.memory_bytes() + self.ids.len() * 4
    }
}

/// A hash of a ray (its origin and direction bits): rays of different samples, bounces and
/// pixels differ, so it stands in for a random number where traversal has no sample stream.
#[inline]
fn ray_key(ray: &Ray) -> u64 {
    let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
    let bits =
        |a: [f32; 3]| (a[0].to_bits() as u64) ^ ((a[1].to_bits() as u64) << 21) ^ ((a[2].to_bits() as u64) << 42);
    fmix64(bits(o) ^ fmix64(bits(d)))
}

/// The number in `[0,1)` a ray (by its key) draws at the surface point `uv`: different for
/// every surface it meets, so that stacked transparent layers are independent.
#[inline]
fn hit_number(key: u64, uv: crate::math::Vec2) -> f32 {
    let h = fmix64(key ^ ((uv.x.to_bits() as u64) << 32 | uv.y.to_bits() as u64));
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

impl Scene {
    /// Closest surface along `ray` within `t_max` (alpha cut-outs let rays through).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        self.geometry.intersect(ray, t_max, |m, uv| self.cut_out(ray, m, uv))
    }

    /// True when something blocks `ray` before `t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.geometry.occluded(ray, t_max, |m, uv| self.cut_out(ray, m, uv))
    }

    /// Whether material `m` lets `ray` through at `uv` (asked only about alpha-masked
    /// triangles, so the ray's number is drawn only there).
    #[inline]
    fn cut_out(&self, ray: &Ray, m: u32, uv: crate::math::Vec2) -> bool {
        self.materials[m as usize].is_cut_out(uv, &self.images, hit_number(ray_key(ray), uv))
    }

    /// Calls `seen(light, hit)` for every lamp `ray` meets before `t_max`, in no particular
    /// order: a path passes through lamps, taking up the light of each.
    #[inline]
    pub fn lamps_along(&self, ray: &Ray, t_max: f32, mut seen: impl FnMut(u32, &LampHit)) {
        self.lamps.bvh.for_each_candidate(ray, t_max, |i| {
            let id = self.lamps.ids[i as usize];
            if let Some(hit) = self.lights[id as usize].intersect_lamp(ray, t_max) {
                seen(id, &hit);
            }
        });
    }

    /// Total emitted power (luminance watts) of every light.
    pub fn total_power(&self) -> f64 {
        self.lights.iter().map(|l| l.power(self.radius) as f64).sum()
    }
}
