//! The RON scene format: these types *are* its reference (field docs = manual).
//!
//! A file is one `Scene(...)` with `#![enable(implicit_some)]` implied, so optional fields take
//! their value directly. Every struct denies unknown fields, so a typo is an error with line
//! and column. Units: metres, radians only where a name says `_rad`, degrees where it says
//! `_deg`; colours are linear Rec.709. Paths are relative to the scene file. Example:
//!
//! ```ron
//! Scene(
//!     camera: Perspective(eye: (0, 1, 4.4), look_at: (0, 1, 0), yfov_deg: 37),
//!     film: (resolution: (320, 240)),
//!     render: (spp: 64, max_depth: 8, sampler: power),
//!     materials: { "white": Diffuse(albedo: (0.73, 0.73, 0.73)) },
//!     objects: [ Quad(corner: (-1, 0, 1), edge1: (2, 0, 0), edge2: (0, 0, -2), material: "white") ],
//!     lights: [ Grid(center: (0, 1.99, 0), normal: (0, -1, 0), extent: (1.2, 1.2), rows: 5, cols: 5,
//!                    fill: 0.25, emission: Power(watts: 45, color: (1, 1, 1))) ],
//! )
//! ```

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::settings::RenderDefaults;

/// Three numbers: a point, a direction or a colour.
pub type V3 = [f32; 3];

/// The whole file: `Scene(camera: ..., film: ..., render: ..., materials: ..., objects: ..., lights: ..., environment: ...)`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Scene")]
pub struct SceneFile {
    /// The one camera (the command line's `--camera auto` can replace it).
    pub camera: CameraSpec,
    /// Image size (`film: (resolution: (640, 480))`).
    #[serde(default)]
    pub film: FilmSpec,
    /// Render defaults (the command line overrides each).
    #[serde(default)]
    pub render: RenderDefaults,
    /// Named materials, referred to by objects.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialSpec>,
    /// Surfaces: shapes, and meshes included from OBJ or glTF files.
    #[serde(default)]
    pub objects: Vec<ObjectSpec>,
    /// Lights (besides objects with emissive materials).
    #[serde(default)]
    pub lights: Vec<LightSpec>,
    /// Light from infinitely far in every direction, seen where rays leave the scene.
    pub environment: Option<EnvironmentSpec>,
}

/// The environment.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum EnvironmentSpec {
    /// The same radiance from every direction [W/(m²·sr)].
    Constant {
        /// Radiance per channel.
        radiance: V3,
    },
    /// An equirectangular (latitude-longitude) map, `.exr` or `.hdr`, in linear radiance, as
    /// Blender reads one: the image's centre looks along +X, its top row is straight up (+Y).
    Map {
        /// The image file, relative to the scene file.
        path: String,
        /// Factor on every texel (Blender's background strength).
        #[serde(default = "one")]
        scale: f32,
        /// Turns the map about +Y, degrees (positive: from +X towards −Z).
        #[serde(default)]
        rotate_deg: f32,
    },
}

/// How the scene is seen.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum CameraSpec {
    /// Perspective camera with a 1-pixel box filter: a pinhole, or with `depth_of_field` a
    /// thin lens.
    Perspective {
        /// Position of the pinhole (the lens's centre), metres.
        eye: V3,
        /// Point looked at.
        look_at: V3,
        /// Up direction (default +Y).
        #[serde(default = "default_up")]
        up: V3,
        /// Field of view in degrees along the `fit` dimension (`yfov_deg` is the same).
        #[serde(alias = "yfov_deg")]
        fov_deg: f32,
        /// Which dimension `fov_deg` spans: `Vertical` (the default), `Horizontal`, or `Auto`,
        /// the larger of width and height (Blender's Auto sensor fit).
        #[serde(default)]
        fit: CameraFit,
        /// Shift of the view as fractions of the fitted dimension's extent, x right and y up
        /// (Blender's lens shift; default none).
        #[serde(default)]
        shift: (f32, f32),
        /// A thin lens focusing at a distance (default none: everything sharp).
        depth_of_field: Option<DepthOfField>,
    },
}

/// Which image dimension a camera's field of view spans.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
pub enum CameraFit {
    /// The height.
    #[default]
    Vertical,
    /// The width.
    Horizontal,
    /// The larger of the two.
    Auto,
}

/// A thin lens (Cycles' depth of field).
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthOfField {
    /// Radius of the aperture disk, metres (Blender: focal length / (2 · f-stop), e.g. 50 mm
    /// at f/2.8: 0.0089).
    pub aperture_radius: f32,
    /// Distance along the view axis of the plane in focus, metres.
    pub focus_distance: f32,
}

fn default_ior() -> f32 {
    1.5
}

fn default_up() -> V3 {
    [0.0, 1.0, 0.0]
}

/// Image settings of the `film` block.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilmSpec {
    /// Width and height in pixels (default 640 × 480).
    pub resolution: Option<(u32, u32)>,
}

/// A material, named in `materials: { "name": ... }`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum MaterialSpec {
    /// Lambertian reflector.
    Diffuse {
        /// Reflectance per channel, in [0,1].
        albedo: V3,
    },
    /// glTF metallic-roughness, rendered as Cycles' Principled BSDF renders it (GGX with
    /// multiple-scattering compensation; exact dielectric Fresnel; F82-tint metals).
    MetalRough {
        /// Base colour (linear RGB in [0, 1]): the diffuse albedo of dielectrics, F0 of metals.
        base_color: V3,
        /// Metalness in [0,1].
        #[serde(default)]
        metallic: f32,
        /// Perceptual roughness in [0,1] (alpha = roughness²).
        #[serde(default = "one")]
        roughness: f32,
        /// KHR_materials_specular `specularFactor` (default 1; 0 makes a dielectric Lambertian).
        #[serde(default = "one")]
        specular: f32,
        /// Index of refraction of the dielectric (default 1.5).
        #[serde(default = "default_ior")]
        ior: f32,
        /// Weight of a clear coat (IOR 1.5) on top, in [0,1] (default 0).
        #[serde(default)]
        coat: f32,
        /// Perceptual roughness of the coat (default 0).
        #[serde(default)]
        coat_roughness: f32,
    },
    /// A light-emitting surface (diffuse emission).
    Emissive {
        /// Radiance in W/(m²·sr) per channel.
        radiance: V3,
        /// Emit from both faces (default: only the front, counter-clockwise face).
        #[serde(default)]
        two_sided: bool,
        /// Diffuse reflectance of the emitter (default black).
        #[serde(default)]
        albedo: V3,
    },
}

fn one() -> f32 {
    1.0
}

/// Translation, rotation (degrees about X, then Y, then Z) and scale, applied scale first.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransformSpec {
    /// Translation (default none).
    #[serde(default)]
    pub translate: V3,
    /// Euler angles in degrees, applied X then Y then Z (default none).
    #[serde(default)]
    pub rotate_deg: V3,
    /// Scale per axis (default 1).
    pub scale: Option<V3>,
}

/// A surface of the scene (every shape is one-sided for emission: its front is where
/// `edge1 × edge2` or its outward normal points).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ObjectSpec {
    /// Parallelogram `corner + s·edge1 + t·edge2`; the front faces along `edge1 × edge2`.
    Quad {
        /// The corner both edges start from (metres).
        corner: V3,
        /// The first edge, a vector from `corner` (metres).
        edge1: V3,
        /// The second edge, a vector from `corner` (metres).
        edge2: V3,
        /// Name of a material in `materials`.
        material: String,
    },
    /// Axis-aligned box of size `size` centred at the origin, then transformed.
    Box {
        /// Edge lengths along x, y and z before the transform (metres).
        size: V3,
        /// Scale, then rotation, then translation into the world.
        #[serde(default)]
        transform: TransformSpec,
        /// Name of a material in `materials`.
        material: String,
    },
    /// Sphere tessellated as an icosphere with smooth normals.
    Sphere {
        /// Centre (metres).
        center: V3,
        /// Radius (metres, > 0).
        radius: f32,
        /// Subdivisions of the icosahedron (default 3: 1280 triangles).
        #[serde(default = "default_subdivisions")]
        subdivisions: u32,
        /// Name of a material in `materials`.
        material: String,
    },
    /// The meshes of a Wavefront `.obj` (with its `.mtl`) or glTF `.gltf`/`.glb` file, with
    /// their materials, emitters and (glTF) punctual lights; not another `.ron` scene.
    Mesh {
        /// Path, relative to the scene file.
        path: String,
        /// Scale, then rotation, then translation into the world.
        #[serde(default)]
        transform: TransformSpec,
        /// Material for every triangle; default: the file's own materials (`.mtl`).
        material: Option<String>,
    },
}

fn default_subdivisions() -> u32 {
    3
}

/// A light that is not a surface of `objects`. Lamps (a point or spot with a `radius`, an
/// `Area`, a `Directional` with an `angle_deg`) render as Blender's lights do in Cycles: rays
/// see them (the camera only where `visible`) but pass through them, and they cast no shadow.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum LightSpec {
    /// Point light: a point, or with a `radius` a lamp of that size.
    Point {
        /// Position (metres).
        position: V3,
        /// Radiant intensity in W/sr per channel (a Blender light of power P: P/(4π)).
        intensity: V3,
        /// Radius of the lamp, metres (default 0: a point).
        #[serde(default)]
        radius: f32,
        /// With a radius: a disk facing each receiver, whose light stays finite close by
        /// (Blender's Soft Falloff; the default), or else a sphere.
        #[serde(default = "yes")]
        soft_falloff: bool,
        /// With a radius: camera rays see the lamp (default false, as Blender's lights).
        #[serde(default)]
        visible: bool,
    },
    /// Spot light: full intensity inside the inner cone, dark outside the outer one.
    Spot {
        /// Position (metres).
        position: V3,
        /// Direction the cone points to.
        direction: V3,
        /// On-axis radiant intensity in W/sr per channel.
        intensity: V3,
        /// Inner cone half-angle in degrees (full intensity inside; default 0).
        #[serde(default)]
        inner_deg: f32,
        /// Outer cone half-angle in degrees (dark outside).
        outer_deg: f32,
        /// The fade between the cones: `Quadratic` (KHR_lights_punctual's, the default) or
        /// `Smoothstep` (Blender's spot blend).
        #[serde(default)]
        falloff: SpotFalloff,
        /// Radius of the lamp, metres (default 0: a point).
        #[serde(default)]
        radius: f32,
        /// With a radius: a facing disk (default) or a sphere, as for `Point`.
        #[serde(default = "yes")]
        soft_falloff: bool,
        /// With a radius: camera rays see the lamp (default false).
        #[serde(default)]
        visible: bool,
    },
    /// Directional light (sun).
    Directional {
        /// Direction the light travels in.
        direction: V3,
        /// Irradiance perpendicular to the beam, W/m² per channel.
        irradiance: V3,
        /// Angular diameter of the sun in degrees (default 0: parallel light, hard shadows).
        #[serde(default)]
        angle_deg: f32,
        /// With an angle: rays from the camera that leave the scene see the sun's disk
        /// (default false).
        #[serde(default)]
        visible: bool,
    },
    /// A one-sided rectangle or ellipse lamp centred at `center`, its sides `u` and `v`
    /// (full lengths), emitting towards `u × v`: Blender's area light.
    Area {
        /// Centre (metres).
        center: V3,
        /// First side: its direction and full length.
        u: V3,
        /// Second side: its direction and full length.
        v: V3,
        /// `Rectangle` (the default) or the `Ellipse` inscribed in it.
        #[serde(default)]
        shape: AreaShape,
        /// Radiance along the normal, W/(m²·sr) per channel (a Blender area light of power P
        /// and area A: P/(π·A)).
        radiance: V3,
        /// Spread in degrees: 180 (the default) is Lambertian; less narrows the beam and
        /// keeps the power.
        #[serde(default = "half_turn")]
        spread_deg: f32,
        /// Camera rays see the lamp (default false).
        #[serde(default)]
        visible: bool,
    },
    /// One emissive parallelogram `corner + s·edge1 + t·edge2`, front along `edge1 × edge2`.
    Quad {
        /// The corner both edges start from (metres).
        corner: V3,
        /// The first edge, a vector from `corner` (metres).
        edge1: V3,
        /// The second edge, a vector from `corner` (metres).
        edge2: V3,
        /// Radiance in W/(m²·sr) per channel.
        radiance: V3,
        /// Emit from both faces (default false).
        #[serde(default)]
        two_sided: bool,
    },
    /// `rows × cols` emissive quads on a plane: the many-light workhorse.
    Grid(GridSpec),
}

/// A grid of lamps. Cells tile `extent`; each lamp is a square-ish quad centred in its cell
/// covering `fill` of the cell's area. Columns run along `tangent`, rows along
/// `normal × tangent`; lamps face `normal`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Centre of the grid.
    pub center: V3,
    /// Direction the lamps face (emit towards).
    pub normal: V3,
    /// In-plane direction of the columns (default: X, or Z when the normal is along X);
    /// projected onto the plane.
    pub tangent: Option<V3>,
    /// Size of the whole grid along tangent and bitangent, metres.
    pub extent: (f32, f32),
    /// Number of rows (along the bitangent).
    pub rows: u32,
    /// Number of columns (along the tangent).
    pub cols: u32,
    /// Fraction of each cell's area a lamp covers, in (0, 1] (default 0.25).
    #[serde(default = "default_fill")]
    pub fill: f32,
    /// How bright: per-lamp radiance, or the total power of the grid.
    pub emission: GridEmission,
    /// Relative colour variation: each channel × (1 + jitter·(2u − 1)), u uniform (default 0).
    #[serde(default)]
    pub color_jitter: f32,
    /// Intensity spread: each lamp × 10^(decades·u), u uniform (log-uniform; default 0).
    #[serde(default)]
    pub decades: f32,
    /// Seed of the variations (default 0).
    #[serde(default)]
    pub seed: u64,
    /// Lamps emit from both faces (default false).
    #[serde(default)]
    pub two_sided: bool,
}

fn yes() -> bool {
    true
}

fn half_turn() -> f32 {
    180.0
}

/// How a spot fades between its cones.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
pub enum SpotFalloff {
    /// t², KHR_lights_punctual's.
    #[default]
    Quadratic,
    /// t²(3 − 2t), Blender's spot blend.
    Smoothstep,
}

/// The shape of an `Area` lamp.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
pub enum AreaShape {
    /// The rectangle (parallelogram) of its sides.
    #[default]
    Rectangle,
    /// The ellipse inscribed in it.
    Ellipse,
}

fn default_fill() -> f32 {
    0.25
}

/// Brightness of a grid. After the random variations the lamps are rescaled so that the mean
/// luminance (radiance) or the total power is exactly what is asked.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum GridEmission {
    /// Mean radiance of a lamp.
    Radiance {
        /// W/(m²·sr) per channel.
        rgb: V3,
    },
    /// Total emitted power of the grid in watts (luminance), with the lamps' mean colour.
    /// Held constant, the grid looks the same at 5 × 5 and 1000 × 1000.
    Power {
        /// Total emitted power of the grid, luminance watts (> 0).
        watts: f32,
        /// Mean colour (its luminance is normalised away).
        #[serde(default = "white")]
        color: V3,
    },
}

fn white() -> V3 {
    [1.0, 1.0, 1.0]
}
