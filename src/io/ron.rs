//! `.ron` scene files → [`SceneDescription`].
//!
//! Parses the format of [`crate::scene::format`] (implicit `Some` on, unknown fields denied),
//! reports syntax errors as `file: line:col: message` with the offending line and a caret, and
//! compiles the file into the description: named materials to indices, shapes and light grids
//! to meshes and lights, `.obj`/`.gltf`/`.glb` files loaded relative to the scene file and
//! included with their materials and lights.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use ::ron::extensions::Extensions;

use super::LoadOptions;
use crate::camera::{Fit, ThinLens};
use crate::error::{Error, Result};
use crate::light::{EnvironmentLight, LampModel, SpotCurve};
use crate::material::Material;
use crate::math::{Mat4, Rgb, UVec2, Vec2, Vec3A};
use crate::scene::MAX_RESOLUTION;
use crate::scene::description::{
    CameraDesc, CameraPlacement, InstanceDesc, LampShape, LightDesc, MeshDesc, SceneDescription,
};
use crate::scene::format::{
    AreaShape, CameraFit, CameraSpec, EnvironmentSpec, LightSpec, MaterialSpec, ObjectSpec, SceneFile, SpotFalloff,
    TransformSpec,
};
use crate::scene::shapes;

/// Reads and compiles the scene file at `path`.
pub fn load(path: &Path, options: &LoadOptions) -> Result<SceneDescription> {
    let text = std::fs::read_to_string(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::InvalidData => {
            Error::scene(path.display().to_string(), "file", "is not UTF-8 text, so not a RON scene")
        }
        _ => Error::io(path, e),
    })?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut desc = parse(&text, &path.display().to_string(), base, options)?;
    desc.inputs.insert(0, path.to_path_buf());
    Ok(desc)
}

/// Compiles scene text; `source` names it in messages, `base_dir` resolves relative paths.
pub fn parse(text: &str, source: &str, base_dir: &Path, options: &LoadOptions) -> Result<SceneDescription> {
    let text = super::strip_bom(text);
    let file: SceneFile = ::ron::Options::default()
        .with_default_extension(Extensions::IMPLICIT_SOME | Extensions::UNWRAP_VARIANT_NEWTYPES)
        .from_str(text)
        .map_err(|e| {
            let (line, col) = (e.span.start.line, e.span.start.col);
            let (snippet, caret) = excerpt(text.lines().nth(line.saturating_sub(1)).unwrap_or(""), col);
            let code = shorten(&e.code.to_string(), 300);
            Error::scene(source, format!("{line}:{col}"), format!("{code}\n  {line:>4} | {snippet}\n       | {caret}^"))
        })?;
    compile(file, source, base_dir, options)
}

/// Characters of a line shown either side of an error's column.
const EXCERPT: usize = 60;

/// The part of `line` around column `col` (1-based, in characters) and the spaces that put a
/// caret under it: a long line (a whole scene on one line) is cut to the neighbourhood.
fn excerpt(line: &str, col: usize) -> (String, String) {
    let chars: Vec<char> = line.chars().collect();
    let at = col.saturating_sub(1).min(chars.len());
    let (from, to) = (at.saturating_sub(EXCERPT), (at + EXCERPT).min(chars.len()));
    let (pre, post) = (if from > 0 { "…" } else { "" }, if to < chars.len() { "…" } else { "" });
    let snippet: String = chars[from..to].iter().collect();
    (format!("{pre}{snippet}{post}"), " ".repeat(at - from + pre.chars().count()))
}

/// `text` cut to `max` characters, saying so.
fn shorten(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        Some((i, _)) => format!("{}… ({} characters in all)", &text[..i], text.chars().count()),
        None => text.to_string(),
    }
}

fn v3(a: [f32; 3]) -> Vec3A {
    Vec3A::from(a)
}

fn transform(t: &TransformSpec) -> Mat4 {
    let r = t.rotate_deg.map(f32::to_radians);
    let rotation =
        glam::Quat::from_rotation_z(r[2]) * glam::Quat::from_rotation_y(r[1]) * glam::Quat::from_rotation_x(r[0]);
    Mat4::from_scale_rotation_translation(
        t.scale.map_or(glam::Vec3::ONE, glam::Vec3::from),
        rotation,
        glam::Vec3::from(t.translate),
    )
}

fn material(name: &str, spec: &MaterialSpec) -> Material {
    match *spec {
        MaterialSpec::Diffuse { albedo } => Material::diffuse(name, v3(albedo)),
        MaterialSpec::MetalRough { base_color, metallic, roughness, specular, ior, coat, coat_roughness } => Material {
            metallic,
            roughness,
            specular,
            ior,
            coat,
            coat_roughness,
            ..Material::diffuse(name, v3(base_color))
        },
        MaterialSpec::Emissive { radiance, two_sided, albedo } => {
            Material { emission: v3(radiance), double_sided: two_sided, ..Material::diffuse(name, v3(albedo)) }
        }
    }
}

/// The scene's environment, its map read relative to the scene (and listed in `inputs`).
fn environment(
    spec: &EnvironmentSpec,
    source: &str,
    base_dir: &Path,
    inputs: &mut Vec<std::path::PathBuf>,
) -> Result<(String, EnvironmentLight)> {
    Ok(match spec {
        EnvironmentSpec::Constant { radiance } => {
            ("environment".into(), EnvironmentLight { radiance: v3(*radiance), map: None, rotation: 0.0 })
        }
        EnvironmentSpec::Map { path, scale, rotate_deg } => {
            if !scale.is_finite() || *scale < 0.0 || !rotate_deg.is_finite() {
                return Err(Error::scene(
                    source,
                    "environment",
                    format!("needs a finite scale ≥ 0 (not {scale}) and a finite rotation (not {rotate_deg})"),
                ));
            }
            let full = base_dir.join(path);
            let map = super::environment::load(&full)?;
            inputs.push(full.clone());
            let light = EnvironmentLight {
                radiance: Rgb::splat(*scale),
                map: Some(Arc::new(map)),
                rotation: rotate_deg.to_radians(),
            };
            (format!("environment '{}'", full.display()), light)
        }
    })
}

/// Turns a parsed file into a description: camera → film and render settings → materials →
/// objects → environment → lights.
fn compile(file: SceneFile, source: &str, base_dir: &Path, options: &LoadOptions) -> Result<SceneDescription> {
    let mut c = Compiler {
        desc: SceneDescription { source: source.to_string(), ..Default::default() },
        source,
        base_dir,
        options,
        materials: BTreeMap::new(),
    };
    c.camera(&file.camera);
    c.settings(&file)?;
    c.materials(&file.materials);
    for (i, obj) in file.objects.iter().enumerate() {
        c.object(i, obj)?;
    }
    if let Some(env) = &file.environment {
        c.desc.environment = Some(environment(env, source, base_dir, &mut c.desc.inputs)?);
    }
    for (i, light) in file.lights.iter().enumerate() {
        c.light(i, light)?;
    }
    Ok(c.desc)
}

/// The description being compiled and what its parts need: the file's name and folder, how
/// to read included files, and the materials by name.
struct Compiler<'a> {
    desc: SceneDescription,
    source: &'a str,
    base_dir: &'a Path,
    options: &'a LoadOptions,
    materials: BTreeMap<String, u32>,
}

impl Compiler<'_> {
    fn camera(&mut self, spec: &CameraSpec) {
        let CameraSpec::Perspective { eye, look_at, up, fov_deg, fit, shift, depth_of_field } = *spec;
        self.desc.cameras.push(CameraDesc {
            name: "camera".into(),
            placement: CameraPlacement::LookAt { eye: v3(eye), target: v3(look_at), up: v3(up) },
            fov: fov_deg.to_radians(),
            fit: match fit {
                CameraFit::Vertical => Fit::Vertical,
                CameraFit::Horizontal => Fit::Horizontal,
                CameraFit::Auto => Fit::Auto,
            },
            shift: Vec2::new(shift.0, shift.1),
            lens: depth_of_field
                .map(|d| ThinLens { aperture_radius: d.aperture_radius, focus_distance: d.focus_distance }),
            aspect_ratio: None,
        });
    }

    /// The film's size and the render defaults, refused when empty or zero.
    fn settings(&mut self, file: &SceneFile) -> Result<()> {
        self.desc.resolution = file.film.resolution.map(|(w, h)| UVec2::new(w, h));
        if let Some(UVec2 { x, y }) = self.desc.resolution
            && (x == 0 || y == 0 || x > MAX_RESOLUTION || y > MAX_RESOLUTION)
        {
            return Err(Error::scene(
                self.source,
                "film.resolution",
                format!("{x} × {y} is not a usable image size (1 to {MAX_RESOLUTION} per side)"),
            ));
        }
        for (name, value) in [("spp", file.render.spp), ("max_depth", file.render.max_depth)] {
            if value == Some(0) {
                return Err(Error::scene(self.source, format!("render.{name}"), "must be at least 1, not 0"));
            }
        }
        if let Some(c) = file.render.clamp {
            c.check().map_err(|m| Error::scene(self.source, "render.clamp", m))?;
        }
        self.desc.render = file.render;
        Ok(())
    }

    fn materials(&mut self, specs: &BTreeMap<String, MaterialSpec>) {
        for (name, spec) in specs {
            self.materials.insert(name.clone(), self.desc.materials.len() as u32);
            self.desc.materials.push(material(name, spec));
        }
    }

    /// The index of the material `name`, or an error for `what` listing the names there are.
    fn material(&self, what: &str, name: &str) -> Result<u32> {
        self.materials.get(name).copied().ok_or_else(|| {
            let known: Vec<&String> = self.materials.keys().collect();
            Error::scene(self.source, what, format!("unknown material '{name}'; the scene defines {known:?}"))
        })
    }

    /// Adds a mesh and its one placement.
    fn place(&mut self, mesh: MeshDesc, transform: Mat4, name: String) {
        self.desc.meshes.push(mesh);
        self.desc.instances.push(InstanceDesc { mesh: (self.desc.meshes.len() - 1) as u32, transform, name });
    }

    fn object(&mut self, i: usize, obj: &ObjectSpec) -> Result<()> {
        match obj {
            ObjectSpec::Quad { corner, edge1, edge2, material } => {
                let what = format!("objects[{i}] Quad");
                let m = self.material(&what, material)?;
                self.place(shapes::quad_mesh(&what, v3(*corner), v3(*edge1), v3(*edge2), m), Mat4::IDENTITY, what);
            }
            ObjectSpec::Box { size, transform: t, material } => {
                let what = format!("objects[{i}] Box");
                let m = self.material(&what, material)?;
                self.place(shapes::box_mesh(&what, v3(*size), m), transform(t), what);
            }
            ObjectSpec::Sphere { center, radius, subdivisions, material } => {
                let what = format!("objects[{i}] Sphere");
                let m = self.material(&what, material)?;
                if !(*radius > 0.0) || *subdivisions > 8 {
                    return Err(Error::scene(self.source, what, "needs radius > 0 and at most 8 subdivisions"));
                }
                let mesh = shapes::sphere_mesh(&what, v3(*center), *radius, *subdivisions, m);
                self.place(mesh, Mat4::IDENTITY, what);
            }
            ObjectSpec::Mesh { path, transform: t, material } => {
                self.include(i, Path::new(path), t, material.as_deref())?
            }
        }
        Ok(())
    }

    /// Reads the OBJ or glTF file `path` and places its meshes and lights with `t`.
    fn include(&mut self, i: usize, path: &Path, t: &TransformSpec, material: Option<&str>) -> Result<()> {
        let what = format!("objects[{i}] Mesh");
        let override_material = material.map(|m| self.material(&what, m)).transpose()?;
        let full = self.base_dir.join(path);
        let ext = full.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
        if ext == "ron" {
            return Err(Error::scene(
                self.source,
                what,
                "can include .obj, .gltf and .glb files, not other .ron scenes",
            ));
        }
        let loaded = super::load_scene(&full, self.options).map_err(|e| match e {
            Error::Io { source: io, .. } => {
                Error::scene(self.source, &what, format!("cannot read '{}': {io}", full.display()))
            }
            other => other,
        })?;
        self.desc.include(loaded, transform(t), override_material);
        Ok(())
    }

    fn light(&mut self, i: usize, light: &LightSpec) -> Result<()> {
        let name = |kind: &str| -> Arc<str> { Arc::from(format!("lights[{i}] {kind}")) };
        let desc = match light {
            LightSpec::Point { position, intensity, radius, soft_falloff, visible } => LightDesc::Point {
                name: name("Point"),
                position: v3(*position),
                intensity: v3(*intensity),
                lamp: lamp_shape(*radius, *soft_falloff, *visible),
            },
            LightSpec::Spot {
                position,
                direction,
                intensity,
                inner_deg,
                outer_deg,
                falloff,
                radius,
                soft_falloff,
                visible,
            } => LightDesc::Spot {
                name: name("Spot"),
                position: v3(*position),
                direction: v3(*direction),
                intensity: v3(*intensity),
                inner_angle: inner_deg.to_radians(),
                outer_angle: outer_deg.to_radians(),
                curve: match falloff {
                    SpotFalloff::Quadratic => SpotCurve::Quadratic,
                    SpotFalloff::Smoothstep => SpotCurve::Smoothstep,
                },
                lamp: lamp_shape(*radius, *soft_falloff, *visible),
            },
            LightSpec::Directional { direction, irradiance, angle_deg, visible } => LightDesc::Directional {
                name: name("Directional"),
                direction: v3(*direction),
                irradiance: v3(*irradiance),
                angle: angle_deg.to_radians(),
                camera_visible: *visible,
            },
            LightSpec::Area { center, u, v, shape, radiance, spread_deg, visible } => LightDesc::Area {
                name: name("Area"),
                center: v3(*center),
                u: 0.5 * v3(*u),
                v: 0.5 * v3(*v),
                ellipse: *shape == AreaShape::Ellipse,
                radiance: v3(*radiance),
                spread: spread_deg.to_radians(),
                camera_visible: *visible,
            },
            LightSpec::Quad { corner, edge1, edge2, radiance, two_sided } => LightDesc::Quad {
                name: name("Quad"),
                corner: v3(*corner),
                edge1: v3(*edge1),
                edge2: v3(*edge2),
                radiance: Rgb::from(*radiance),
                two_sided: *two_sided,
            },
            LightSpec::Grid(g) => {
                let label = format!("lights[{i}] Grid");
                let lamps = shapes::light_grid(&label, g).map_err(|m| Error::scene(self.source, &label, m))?;
                self.desc.lights.extend(lamps);
                return Ok(());
            }
        };
        self.desc.lights.push(desc);
        Ok(())
    }
}

/// A point or spot light's lamp shape from the file's fields: none at radius 0 (a point).
fn lamp_shape(radius: f32, soft_falloff: bool, visible: bool) -> Option<LampShape> {
    let model = if soft_falloff { LampModel::FacingDisk } else { LampModel::Sphere };
    (radius != 0.0).then_some(LampShape { radius, model, camera_visible: visible })
}
