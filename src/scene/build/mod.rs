//! `SceneDescription` → `Scene`, in steps: validate the description (`validate.rs`), choose
//! the camera and the image size, check that the result fits the memory limit, place the
//! meshes and make their emitters lights (`place.rs`), add the other lights (`lights.rs`),
//! build the BVH, place the camera.
//!
//! Every check names the file and the object, so that a bad scene is an error a user can act
//! on, never a panic or a silently black image.

mod lights;
mod place;
mod validate;

use std::time::Instant;

use self::place::{Placement, Placer};
use super::description::{CameraDesc, CameraPlacement, LightDesc, SceneDescription};
use super::{Lamps, Scene, SceneReport, SceneStats};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::geometry::{Geometry, TracerKind};
use crate::light::{Light, PointLight, SpotLight};
use crate::limits::{BYTES_PER_INSTANCE, BYTES_PER_LIGHT, BYTES_PER_PIXEL, BYTES_PER_TRIANGLE, check_memory};
use crate::math::{UVec2, Vec3A};

/// Choices made when building, usually from the command line.
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// Output size; default: the scene's, else 640 wide at the camera's aspect ratio.
    pub resolution: Option<UVec2>,
    /// Camera to use, by name; default: the first.
    pub camera: Option<String>,
    /// The ray tracer; default: `--tracer`, else MYRIAD_TRACER, else the fastest built.
    pub tracer: TracerKind,
    /// Frame the whole scene, with a warning, when it has no camera and none is asked for,
    /// instead of refusing it (`info` describes any scene; `render` needs a view).
    pub frame_without_camera: bool,
}

/// Width used when neither the command line nor the scene gives a resolution.
const DEFAULT_WIDTH: u32 = 640;

/// Largest image side.
pub const MAX_RESOLUTION: u32 = 32768;

/// The camera the options ask for (`None`: `auto`, placed once the bounds are known).
fn choose_camera<'a>(desc: &'a SceneDescription, opts: &BuildOptions) -> Result<Option<&'a CameraDesc>> {
    let file = desc.source.as_str();
    match opts.camera.as_deref() {
        Some(AUTO_CAMERA) => Ok(None),
        Some(name) => desc.cameras.iter().find(|c| c.name == name).map(Some).ok_or_else(|| {
            let names: Vec<&str> = desc.cameras.iter().map(|c| c.name.as_str()).collect();
            Error::scene(
                file,
                "cameras",
                format!("no camera named '{name}'; the scene has {names:?} (or pass --camera auto)"),
            )
        }),
        None if desc.cameras.is_empty() && opts.frame_without_camera => Ok(None),
        None => desc.cameras.first().map(Some).ok_or_else(|| {
            Error::scene(
                file,
                "cameras",
                "the scene has no camera; add one (in Blender: a camera object, exported with 'Cameras' on), \
                 or pass --camera auto to frame the whole scene",
            )
        }),
    }
}

/// The image size: the options', else the scene's, else 640 wide at the camera's aspect ratio.
fn resolution(desc: &SceneDescription, opts: &BuildOptions, camera: Option<&CameraDesc>) -> Result<UVec2> {
    if let Some(r) = opts.resolution.or(desc.resolution) {
        if r.min_element() == 0 || r.max_element() > MAX_RESOLUTION {
            return Err(Error::scene(
                &desc.source,
                "resolution",
                format!("{} × {} is not a usable image size (1 to {MAX_RESOLUTION} per side)", r.x, r.y),
            ));
        }
        return Ok(r);
    }
    let Some((name, aspect)) = camera.and_then(|c| Some((&c.name, c.aspect_ratio?))) else {
        return Ok(UVec2::new(DEFAULT_WIDTH, DEFAULT_WIDTH * 3 / 4));
    };
    let height = (DEFAULT_WIDTH as f64 / aspect as f64).round();
    if !(1.0..=MAX_RESOLUTION as f64).contains(&height) {
        return Err(Error::scene(
            &desc.source,
            format!("camera '{name}'"),
            format!(
                "has aspect ratio {aspect:e}, which at {DEFAULT_WIDTH} pixels wide is {height:.1e} pixels tall \
                 (1 to {MAX_RESOLUTION} work); pass --resolution WIDTHxHEIGHT"
            ),
        ));
    }
    Ok(UVec2::new(DEFAULT_WIDTH, height as u32))
}

/// How each mesh is placed: shared (stored once, instanced) when it is used more than once
/// and does not emit (each emitting triangle is a light of its own, in world space).
fn placements(desc: &SceneDescription) -> Vec<(Vec<Placement<'_>>, bool)> {
    let mut per_mesh: Vec<Vec<Placement>> = vec![Vec::new(); desc.meshes.len()];
    for inst in &desc.instances {
        per_mesh[inst.mesh as usize].push((inst.transform, &inst.name));
    }
    per_mesh
        .into_iter()
        .zip(&desc.meshes)
        .map(|(p, mesh)| {
            let shared = p.len() > 1 && !desc.materials[mesh.material as usize].is_emissive();
            (p, shared)
        })
        .collect()
}

/// An error when the built scene and its image would not fit the memory limit.
fn check_size(desc: &SceneDescription, placements: &[(Vec<Placement>, bool)], resolution: UVec2) -> Result<()> {
    // `stored`: triangles kept in memory (a shared mesh once); `world`: in the scene, every
    // placement counted, as the render summary and `info` count them.
    let (mut stored, mut world, mut instances, mut lights) = (0u64, 0u64, 0u64, desc.lights.len() as u64);
    for ((p, shared), mesh) in placements.iter().zip(&desc.meshes) {
        let n = mesh.triangles.len() as u64;
        let placed = n.saturating_mul(p.len() as u64);
        world = world.saturating_add(placed);
        if *shared {
            (stored, instances) = (stored + n, instances + p.len() as u64);
        } else {
            stored = stored.saturating_add(placed);
            if desc.materials[mesh.material as usize].is_emissive() {
                lights = lights.saturating_add(placed);
            }
        }
    }
    let pixels = resolution.x as u64 * resolution.y as u64;
    let bytes = [
        (stored, BYTES_PER_TRIANGLE),
        (instances, BYTES_PER_INSTANCE),
        (lights, BYTES_PER_LIGHT),
        (pixels, BYTES_PER_PIXEL),
    ]
    .iter()
    .fold(0u64, |sum, &(n, b)| sum.saturating_add(n.saturating_mul(b)));
    check_memory(
        bytes,
        format_args!(
            "this scene ({world} triangles{}, up to {lights} lights, a {} × {} image)",
            if stored < world { format!(" ({stored} stored: instances share theirs)") } else { String::new() },
            resolution.x,
            resolution.y
        ),
    )
    .map_err(|m| Error::scene(&desc.source, "scene", m))
}

/// Validates `desc` and builds the scene (BVH built in the current rayon pool): validate →
/// camera and size → memory check → place meshes → listed lights → BVH → bounds →
/// directional powers and the environment → camera.
pub fn build(mut desc: SceneDescription, opts: &BuildOptions) -> Result<(Scene, SceneReport)> {
    let start = Instant::now();
    validate::description(&desc)?;
    // The images move into the scene (textures can be large: no copy).
    let images = std::mem::take(&mut desc.images);
    let file = desc.source.as_str();
    let cam_desc = choose_camera(&desc, opts)?;
    let resolution = resolution(&desc, opts, cam_desc)?;
    let placements = placements(&desc);
    check_size(&desc, &placements, resolution)?;

    let mut placer = Placer::new(&desc, &images);
    placer.place_meshes(&placements)?;
    let listed = placer.lights.len();
    placer.place_lights()?;
    let Placer { geo, mut lights, mut stats, materials, degenerate_emitters, .. } = placer;
    let (geometry, tracer_warning) = geo.build(opts.tracer);
    let (center, radius) = bounds(&geometry, &lights);
    // A directional light's power is its irradiance over the scene's disc.
    for (i, l) in desc.lights.iter().enumerate() {
        if let LightDesc::Directional { name, .. } = l {
            lights::check_power(file, &format!("light {i} '{name}'"), &lights[listed + i], radius)?;
        }
    }
    let environment = match &desc.environment {
        Some((name, env)) => {
            lights.push(lights::environment(file, name, env, radius)?);
            Some((lights.len() - 1) as u32)
        }
        None => None,
    };
    let (camera, camera_name) = match cam_desc {
        Some(c) => (scene_camera(file, c)?, c.name.clone()),
        None => (auto_camera(file, center, radius, resolution)?, AUTO_CAMERA.to_string()),
    };
    let mut warnings = desc.warnings.clone();
    warnings.extend(tracer_warning);
    if desc.cameras.is_empty() && opts.camera.is_none() {
        warnings.push("the scene has no camera; rendering it needs one, or --camera auto to frame it all".into());
    }
    if degenerate_emitters > 0 {
        warnings.push(format!("{degenerate_emitters} emissive triangles have zero area and do not emit"));
    }
    if lights.is_empty() {
        warnings.push(
            "the scene has no lights (no emissive surface, light or environment): it renders black; give a \
             material emission, or add a light or an environment"
                .into(),
        );
    }
    lights.shrink_to_fit();
    stats.record(&desc, &geometry, &lights, start);
    let lamps = Lamps::new(&lights);
    let suns = (0..lights.len() as u32).filter(|&i| matches!(lights[i as usize], Light::Sun(_))).collect();
    let caustics =
        materials.iter().any(|m| m.smooth_glass().is_some()) && lights.iter().any(Light::connects_through_glass);
    let scene =
        Scene { camera, geometry, materials, images, lights, environment, lamps, suns, center, radius, caustics };
    let report = SceneReport {
        source: desc.source.clone(),
        camera_name,
        resolution,
        render: desc.render,
        stats,
        warnings,
        extensions: desc.extensions.clone(),
        inputs: desc.inputs.clone(),
    };
    Ok((scene, report))
}

/// The centre and radius of a sphere around every triangle, positioned light and lamp (a unit
/// sphere at the origin for an empty scene).
fn bounds(geometry: &Geometry, lights: &[Light]) -> (Vec3A, f32) {
    let (mut lo, mut hi) = (Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN));
    for (v, _) in geometry.world_triangles() {
        for p in v {
            (lo, hi) = (lo.min(p), hi.max(p));
        }
    }
    for l in lights {
        if let Light::Point(PointLight { position, .. }) | Light::Spot(SpotLight { position, .. }) = l {
            (lo, hi) = (lo.min(*position), hi.max(*position));
        }
        if let Some((min, max)) = l.lamp_bounds() {
            (lo, hi) = (lo.min(min), hi.max(max));
        }
    }
    if lo.x <= hi.x { (0.5 * (lo + hi), (0.5 * (hi - lo).length()).max(1e-3)) } else { (Vec3A::ZERO, 1.0) }
}

impl SceneStats {
    /// Counts, sizes and the build time of a scene built from `desc` since `start`.
    fn record(&mut self, desc: &SceneDescription, geometry: &Geometry, lights: &[Light], start: Instant) {
        self.meshes = desc.meshes.len();
        self.cameras = desc.cameras.iter().map(|c| c.name.clone()).collect();
        self.triangles = geometry.triangle_count();
        self.stored_triangles = geometry.stored_triangle_count();
        self.bvh_build_time = geometry.accel.stats().build_time;
        self.tracer = geometry.accel.tracer().name();
        self.geometry_bytes = geometry.memory_bytes();
        self.light_bytes = std::mem::size_of_val(lights);
        self.build_time = start.elapsed();
    }
}

/// The `--camera` value that frames the whole scene instead of using one of its cameras.
pub const AUTO_CAMERA: &str = "auto";

/// The field of view of the `auto` camera, in degrees.
const AUTO_YFOV_DEG: f32 = 40.0;

/// A scene camera, or an error naming it and saying what is wrong.
fn scene_camera(file: &str, c: &CameraDesc) -> Result<Camera> {
    match c.placement {
        CameraPlacement::LookAt { eye, target, up } => Camera::look_at(eye, target, up, c.fov),
        CameraPlacement::Matrix(m) => Camera::from_matrix(&m, c.fov),
    }
    .and_then(|cam| cam.with_projection(c.fit, c.shift))
    .and_then(|cam| match c.lens {
        Some(lens) => cam.with_lens(lens),
        None => Ok(cam),
    })
    .map_err(|m| Error::scene(file, format!("camera '{}'", c.name), format!("cannot be used: {m}")))
}

/// A camera on +Z looking down −Z at the centre of the scene's bounding sphere, slightly from
/// above, far enough back that the whole sphere fits the narrower field of view of an image
/// of `resolution`.
fn auto_camera(file: &str, center: Vec3A, radius: f32, resolution: UVec2) -> Result<Camera> {
    let yfov = AUTO_YFOV_DEG.to_radians();
    let aspect = resolution.x as f32 / resolution.y as f32;
    let half = (0.5 * yfov).tan().min((0.5 * yfov).tan() * aspect).atan();
    let distance = radius / half.sin();
    let dir = Vec3A::new(0.0, 0.25, 1.0).normalize();
    Camera::look_at(center + distance * dir, center, Vec3A::Y, yfov)
        .map_err(|m| Error::scene(file, "--camera auto", format!("cannot frame the scene: {m}")))
}
