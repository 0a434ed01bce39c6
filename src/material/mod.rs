//! Surface scattering: materials as the scene stores them and the BSDFs they produce.
//!
//! Owns: [`Material`] (glTF metallic-roughness parameters, emission and sidedness, as every
//! loader produces them), [`Bsdf`] (a `Copy` enum evaluated at one point, in a local frame)
//! and [`ShadingPoint`] (a BSDF with its world frame: the face-forwarding and the
//! geometric-normal test that stop light leaking through surfaces). Depends on `math`.
//!
//! Deviation from the architecture sketch: the closed set is {Lambertian, Principled} (the
//! Principled BSDF as Cycles evaluates it for a glTF material, glass included:
//! `principled.rs`); a conductor is metallic = 1, a glass transmission = 1.

mod diffuse;
pub mod fresnel;
mod lobes;
mod microfacet;
mod principled;
mod sheen;
pub mod tables;
pub mod texture;

pub use diffuse::Diffuse;
pub use lobes::GlossyLobes;
pub use microfacet::Ggx;
pub use principled::{Principled, PrincipledAt};
pub use texture::{Image, TextureRef};

use crate::math::frame::Frame;
use crate::math::{Rgb, Vec2, Vec3A};

/// A sampled scattering direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Incident direction (towards the next vertex).
    pub wi: Vec3A,
    /// f·|cos θi| / pdf.
    pub weight: Rgb,
    /// Solid-angle density of `wi`.
    pub pdf: f32,
}

/// A BSDF at one point, in its local frame (normal = +Z, directions point away).
#[derive(Clone, Copy, Debug)]
// Built on the stack at every path vertex: boxing the large variant would allocate per bounce.
#[allow(clippy::large_enum_variant)]
pub enum Bsdf {
    /// Lambertian.
    Diffuse(Diffuse),
    /// Cycles' Principled BSDF (coat, metal, glass, dielectric specular over diffuse).
    Principled(Principled),
}

impl Bsdf {
    /// The BSDF seen from `wo`: what depends on the outgoing direction alone (the
    /// Principled lobes' weights) computed once for the queries that follow.
    #[inline]
    pub fn at(&self, wo: Vec3A) -> BsdfAt {
        match self {
            Bsdf::Diffuse(b) => BsdfAt::Diffuse(*b, wo),
            Bsdf::Principled(b) => BsdfAt::Principled(b.at(wo)),
        }
    }

    /// BSDF value, without the cosine.
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Rgb {
        self.at(wo).eval(wi)
    }

    /// Solid-angle density of [`Bsdf::sample`] returning `wi`.
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        self.at(wo).pdf(wi)
    }

    /// True when the BSDF can send light through the surface (glass).
    #[inline]
    pub fn transmits(&self) -> bool {
        matches!(self, Bsdf::Principled(p) if p.transmits())
    }

    /// Samples an incident direction; `u_lobe` picks a lobe, `u` the direction in it.
    #[inline]
    pub fn sample(&self, wo: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        self.at(wo).sample(u_lobe, u)
    }
}

/// A [`Bsdf`] seen from one outgoing direction (local frame).
#[derive(Clone, Copy, Debug)]
#[allow(clippy::large_enum_variant)]
pub enum BsdfAt {
    /// Lambertian, and the outgoing direction.
    Diffuse(Diffuse, Vec3A),
    /// The Principled BSDF with its lobe weights for that direction.
    Principled(PrincipledAt),
}

impl BsdfAt {
    /// BSDF value towards `wi`, without the cosine.
    #[inline]
    pub fn eval(&self, wi: Vec3A) -> Rgb {
        match self {
            BsdfAt::Diffuse(b, wo) => b.eval(*wo, wi),
            BsdfAt::Principled(b) => b.eval(wi),
        }
    }

    /// Solid-angle density of [`BsdfAt::sample`] returning `wi`.
    #[inline]
    pub fn pdf(&self, wi: Vec3A) -> f32 {
        match self {
            BsdfAt::Diffuse(b, wo) => b.pdf(*wo, wi),
            BsdfAt::Principled(b) => b.pdf(wi),
        }
    }

    /// [`eval`](Self::eval) and [`pdf`](Self::pdf) towards `wi` at once (for less than both).
    #[inline]
    pub fn eval_pdf(&self, wi: Vec3A) -> (Rgb, f32) {
        match self {
            BsdfAt::Diffuse(b, wo) => (b.eval(*wo, wi), b.pdf(*wo, wi)),
            BsdfAt::Principled(b) => b.eval_pdf(wi),
        }
    }

    /// Whether it is Lambert's BSDF: one lobe, and the cheapest to evaluate.
    #[inline]
    pub fn is_diffuse(&self) -> bool {
        matches!(self, BsdfAt::Diffuse(..))
    }

    /// The mean roughness of what it samples (see [`PrincipledAt::mean_roughness`]).
    #[inline]
    pub fn mean_roughness(&self) -> f32 {
        match self {
            BsdfAt::Diffuse(..) => 1.0,
            BsdfAt::Principled(b) => b.mean_roughness(),
        }
    }

    /// Whether [`sample`](Self::sample) reads its `u_lobe` (Lambert's one lobe does not).
    #[inline]
    pub fn chooses_lobes(&self) -> bool {
        !self.is_diffuse()
    }

    /// Samples an incident direction; `u_lobe` picks a lobe, `u` the direction in it.
    #[inline]
    pub fn sample(&self, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            BsdfAt::Diffuse(b, wo) => b.sample(*wo, u),
            BsdfAt::Principled(b) => b.sample(u_lobe, u),
        }
    }
}

/// Glass up to this roughness counts as smooth for next-event estimation through it: its
/// lobe (GGX α = 0.01, under a degree wide) bends light so nearly along Snell's law that a
/// connection solved for the exact refraction stands for it. Paths from a receiver then
/// cross it as smooth glass too (else next-event estimation at its rough vertices would
/// count light the connection already brought: 8 % too much at roughness 0.1); what is lost
/// is the blur such glass gives a caustic. glass.glb's tinted ball (roughness 0.05) is such
/// glass.
pub const SMOOTH_GLASS_ROUGHNESS: f32 = 0.1;

/// Smooth solid glass ([`Material::smooth_glass`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothGlass {
    /// Index of refraction inside.
    pub ior: f32,
    /// What one crossing lets through besides Fresnel (√base colour: two crossings tint by it).
    pub tint: Rgb,
    /// Absorption coefficient inside [1/m].
    pub absorption: Rgb,
}

impl SmoothGlass {
    /// What one crossing passes on towards a viewer at cosine `cos_o` to the normal, `eta`
    /// being the far side's IOR over the viewer's: (1 − F)·tint, the smooth limit of the
    /// Principled glass lobe (which, as Cycles', does not scale radiance by η²).
    #[inline]
    pub fn transmittance(&self, cos_o: f32, eta: f32) -> Rgb {
        self.tint * (1.0 - fresnel::dielectric(cos_o, eta))
    }

    /// The probability that BSDF sampling refracts there rather than reflects (what the
    /// Principled BSDF's sampling of its glass lobe gives in the smooth limit).
    #[inline]
    pub fn refraction_probability(&self, cos_o: f32, eta: f32) -> f32 {
        1.0 - principled::reflect_probability(fresnel::dielectric(cos_o, eta), self.tint)
    }
}

/// Surface appearance, as loaded (glTF metallic-roughness with emission and textures).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name, for messages and `info`.
    pub name: String,
    /// Base colour (linear).
    pub base_color: Rgb,
    /// Base alpha (coverage), multiplied by the base-colour texture's alpha.
    pub base_alpha: f32,
    /// Metalness in [0,1].
    pub metallic: f32,
    /// Perceptual roughness in [0,1].
    pub roughness: f32,
    /// KHR_materials_specular `specularFactor` in [0,1] (1 when absent in glTF): scales the
    /// dielectric's F0 (Blender's Specular IOR Level × 2).
    pub specular: f32,
    /// KHR_materials_specular `specularColorFactor` (≥ 0; Blender's Specular Tint), which
    /// colours the dielectric's F0 and the metal's 82° reflectance.
    pub specular_color: Rgb,
    /// Index of refraction of the dielectric (KHR_materials_ior, 1.5 by default), > 1.
    pub ior: f32,
    /// Share of the dielectric that is glass (KHR_materials_transmission), in [0, 1].
    pub transmission: f32,
    /// The glass is a sheet of no thickness (glTF transmission without a volume) rather than
    /// the surface of a solid.
    pub thin: bool,
    /// Absorption coefficient inside a solid glass object [1/m] (KHR_materials_volume):
    /// light travelling a distance d inside keeps exp(−σ·d).
    pub absorption: Rgb,
    /// Weight of a clear coat on top (KHR_materials_clearcoat; Blender's Coat), in [0, 1].
    pub coat: f32,
    /// Perceptual roughness of the coat, in [0, 1].
    pub coat_roughness: f32,
    /// Emitted radiance (emissiveFactor × emissiveStrength), W/(m²·sr).
    pub emission: Rgb,
    /// Emits on both sides (glTF `doubleSided`); otherwise only on the counter-clockwise side.
    pub double_sided: bool,
    /// Multiplies the base colour (sRGB) and alpha.
    pub base_color_texture: Option<TextureRef>,
    /// G multiplies roughness, B metallic (linear).
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Multiplies the emission (sRGB).
    pub emission_texture: Option<TextureRef>,
    /// Tangent-space normal map, with its `scale`.
    pub normal_texture: Option<(TextureRef, f32)>,
    /// Sheen colour (KHR_materials_sheen `sheenColorFactor`; Blender's Sheen Weight × Sheen
    /// Tint), ≥ 0; black is no sheen.
    pub sheen_color: Rgb,
    /// Sheen roughness in [0, 1].
    pub sheen_roughness: f32,
    /// Multiplies the sheen colour (sRGB).
    pub sheen_color_texture: Option<TextureRef>,
    /// Its alpha multiplies the sheen roughness.
    pub sheen_roughness_texture: Option<TextureRef>,
    /// Anisotropy of the metal and specular layer in [0, 1] (KHR_materials_anisotropy
    /// `anisotropyStrength`, Blender's Anisotropic).
    pub anisotropy: f32,
    /// Angle from the tangent to the direction of the anisotropy, counter-clockwise about the
    /// normal, radians.
    pub anisotropy_rotation: f32,
    /// Red and green (to [−1, 1]) turn the anisotropy by their direction in tangent space,
    /// blue multiplies its strength (linear). With it the tangent follows the UVs; without,
    /// it runs around the mesh's vertical (Blender's default, [`Material::tangent`]).
    pub anisotropy_texture: Option<TextureRef>,
    /// How alpha makes the surface see-through.
    pub alpha: AlphaMode,
    /// What the loader read but myriad does not render (properties, extensions), for `info`.
    pub ignored: Vec<String>,
}

/// How a material's alpha (base alpha × the base-colour texture's) lets rays through.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum AlphaMode {
    /// Alpha is ignored.
    #[default]
    Opaque,
    /// glTF MASK: cut out where alpha is below the cutoff.
    Mask(f32),
    /// glTF BLEND, as stochastic transparency: a ray passes with probability 1 − alpha (a
    /// hash of the ray and the hit decides, so every ray and surface draws its own number).
    Blend,
}

impl Material {
    /// A Lambertian material.
    pub fn diffuse(name: &str, albedo: Rgb) -> Self {
        Self {
            name: name.to_string(),
            base_color: albedo,
            base_alpha: 1.0,
            metallic: 0.0,
            roughness: 1.0,
            specular: 0.0,
            specular_color: Rgb::ONE,
            ior: 1.5,
            transmission: 0.0,
            thin: false,
            absorption: Rgb::ZERO,
            coat: 0.0,
            coat_roughness: 0.0,
            emission: Rgb::ZERO,
            double_sided: true,
            base_color_texture: None,
            metallic_roughness_texture: None,
            emission_texture: None,
            normal_texture: None,
            sheen_color: Rgb::ZERO,
            sheen_roughness: 0.0,
            sheen_color_texture: None,
            sheen_roughness_texture: None,
            anisotropy: 0.0,
            anisotropy_rotation: 0.0,
            anisotropy_texture: None,
            alpha: AlphaMode::Opaque,
            ignored: Vec::new(),
        }
    }

    /// True when rays may pass through parts of the surface (the BVH then asks
    /// [`Material::is_cut_out`] at each hit).
    pub fn has_alpha(&self) -> bool {
        self.alpha != AlphaMode::Opaque
    }

    /// The name of the model it renders with, for `info`.
    pub fn model_name(&self) -> &'static str {
        match () {
            _ if self.base_color == Rgb::ZERO && self.is_emissive() && self.metallic == 0.0 => "emitter",
            _ if self.transmission > 0.0 && self.metallic < 1.0 && self.thin => "thin glass",
            _ if self.transmission > 0.0 && self.metallic < 1.0 && self.absorption != Rgb::ZERO => "glass + volume",
            _ if self.transmission > 0.0 && self.metallic < 1.0 => "glass",
            _ if self.is_lambertian() => "lambert",
            _ if self.coat > 0.0 => "principled + coat",
            _ if self.sheen_color != Rgb::ZERO => "principled + sheen",
            _ if self.anisotropy > 0.0 => "principled, anisotropic",
            _ => "principled",
        }
    }

    /// The surface as smooth solid glass, when that is all it is: no other lobe, nothing
    /// textured, and roughness at most [`SMOOTH_GLASS_ROUGHNESS`]. Next-event estimation
    /// solves for light that crosses such glass along Snell's law (`integrator::mnee`).
    pub fn smooth_glass(&self) -> Option<SmoothGlass> {
        let plain = self.metallic == 0.0
            && self.transmission == 1.0
            && !self.thin
            && self.coat == 0.0
            && self.sheen_color == Rgb::ZERO
            && self.emission == Rgb::ZERO
            && self.alpha == AlphaMode::Opaque
            && self.base_color_texture.is_none()
            && self.metallic_roughness_texture.is_none()
            && self.normal_texture.is_none();
        let b = self.base_color;
        (plain && self.roughness <= SMOOTH_GLASS_ROUGHNESS).then(|| SmoothGlass {
            ior: self.ior,
            tint: Rgb::new(b.x.sqrt(), b.y.sqrt(), b.z.sqrt()),
            absorption: self.absorption,
        })
    }

    /// Whether its BSDF may reflect other than as Lambert's somewhere, and transmits nowhere
    /// (where light paths may start a highlight: `integrator::light_paths`).
    pub fn may_reflect_glossily(&self) -> bool {
        !(self.metallic == 0.0 && self.is_lambertian()) && self.transmission == 0.0
    }

    /// True when it reflects as Lambert's BSDF alone (whatever its textures say).
    fn is_lambertian(&self) -> bool {
        self.metallic == 0.0
            && self.specular == 0.0
            && self.coat == 0.0
            && self.transmission == 0.0
            && self.sheen_color == Rgb::ZERO
    }

    /// Whether its tangent runs around the mesh's vertical (anisotropic without a direction
    /// texture): the meshes it covers then carry [`radial tangents`](crate::geometry::radial_tangents).
    pub fn needs_radial_tangents(&self) -> bool {
        self.anisotropy > 0.0 && self.anisotropy_texture.is_none()
    }

    /// The direction the anisotropy stretches along at `uv`, on the surface of (mapped) normal
    /// `n`, or `None` where it is isotropic. As Cycles' Principled BSDF after Blender's glTF
    /// import: the tangent is dp/du of the triangle (`derivatives`) with a direction texture,
    /// else the mesh's radial tangent (`radial`), projected onto the surface and turned by
    /// the rotation (and the texture's direction) about `n`.
    #[inline]
    pub fn tangent(
        &self,
        n: Vec3A,
        radial: impl FnOnce() -> Vec3A,
        derivatives: impl FnOnce() -> (Vec3A, Vec3A),
        uv: Vec2,
        images: &[Image],
    ) -> Option<Vec3A> {
        if !(self.anisotropy > 0.0) {
            return None;
        }
        let (t, angle) = match &self.anisotropy_texture {
            Some(tex) => {
                let v = tex.sample(images, uv);
                (derivatives().0, self.anisotropy_rotation + (2.0 * v.y - 1.0).atan2(2.0 * v.x - 1.0))
            }
            None => (radial(), self.anisotropy_rotation),
        };
        let t = (t - n * n.dot(t)).try_normalize()?;
        let (sin, cos) = angle.sin_cos();
        Some(t * cos + n.cross(t) * sin)
    }

    /// True when the surface emits light.
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// Base colour at `uv`.
    #[inline]
    pub fn base_color_at(&self, uv: Vec2, images: &[Image]) -> Rgb {
        match &self.base_color_texture {
            Some(t) => self.base_color * Rgb::from(t.sample_srgb(images, uv).truncate()),
            None => self.base_color,
        }
    }

    /// True where the surface lets the ray through at `uv`; `u ∈ [0,1)` is the ray's own
    /// number for this hit (alpha BLEND passes the ray when alpha ≤ u).
    #[inline]
    pub fn is_cut_out(&self, uv: Vec2, images: &[Image], u: f32) -> bool {
        let alpha = || self.base_alpha * self.base_color_texture.as_ref().map_or(1.0, |t| t.sample(images, uv).w);
        match self.alpha {
            AlphaMode::Opaque => false,
            AlphaMode::Mask(cutoff) => alpha() < cutoff,
            AlphaMode::Blend => alpha() <= u,
        }
    }

    /// The shading normal with the normal map applied. `n`: interpolated normal,
    /// `derivatives`: the triangle's position derivatives in texture space, (dp/du, dp/dv)
    /// (zero without UVs), asked for only when there is a normal map.
    #[inline]
    pub fn mapped_normal(
        &self,
        n: Vec3A,
        derivatives: impl FnOnce() -> (Vec3A, Vec3A),
        uv: Vec2,
        images: &[Image],
    ) -> Vec3A {
        let Some((tex, scale)) = &self.normal_texture else { return n };
        let (dpdu, dpdv) = derivatives();
        let Some(t) = (dpdu - n * n.dot(dpdu)).try_normalize() else { return n };
        // Bitangent handedness follows the UV layout (mirrored UVs flip it).
        let b = if n.cross(t).dot(dpdv) < 0.0 { -n.cross(t) } else { n.cross(t) };
        let v = tex.sample(images, uv);
        let (x, y, z) = ((2.0 * v.x - 1.0) * scale, (2.0 * v.y - 1.0) * scale, 2.0 * v.z - 1.0);
        (t * x + b * y + n * z).try_normalize().unwrap_or(n)
    }

    /// The BSDF at `uv` for a ray that meets the surface from its front (`entering`: into the
    /// object, for glass) or its back, or `None` when the surface reflects nothing (a black
    /// emitter). With `as_smooth`, smooth glass ([`Material::smooth_glass`]) scatters as if
    /// its roughness were 0: what a path that next-event estimation through glass also
    /// follows must meet (`integrator::mnee`). Always inlined into the path loop's two copies
    /// (`integrator::path`), where it is set up at every vertex.
    #[inline(always)]
    pub fn bsdf(&self, uv: Vec2, images: &[Image], entering: bool, as_smooth: bool) -> Option<Bsdf> {
        let base = self.base_color_at(uv, images);
        let (mut metallic, mut roughness) = (self.metallic, if as_smooth { 0.0 } else { self.roughness });
        if let Some(t) = &self.metallic_roughness_texture {
            let v = t.sample(images, uv);
            roughness *= v.y;
            metallic *= v.z;
        }
        if metallic == 0.0 && self.is_lambertian() {
            if base.max_element() <= 0.0 {
                return None;
            }
            return Some(Bsdf::Diffuse(Diffuse { albedo: base }));
        }
        let mut p = Principled::new(base, metallic, roughness, self.ior, self.specular, self.specular_color)
            .with_coat(self.coat, self.coat_roughness);
        // Most materials have neither: they skip the lookups and the copies.
        if self.anisotropy > 0.0 {
            p = p.with_anisotropy(self.anisotropy_at(uv, images));
        }
        if self.sheen_color != Rgb::ZERO {
            p = p.with_sheen(self.sheen_at(uv, images), self.sheen_roughness_at(uv, images));
        }
        let p = if self.thin {
            p.with_thin_transmission(self.transmission, self.ior)
        } else {
            p.with_transmission(self.transmission, if entering { self.ior } else { 1.0 / self.ior })
        };
        Some(Bsdf::Principled(p))
    }

    /// Anisotropy at `uv`.
    #[inline]
    fn anisotropy_at(&self, uv: Vec2, images: &[Image]) -> f32 {
        self.anisotropy * self.anisotropy_texture.as_ref().map_or(1.0, |t| t.sample(images, uv).z)
    }

    /// Sheen colour at `uv`.
    #[inline]
    fn sheen_at(&self, uv: Vec2, images: &[Image]) -> Rgb {
        match &self.sheen_color_texture {
            Some(t) => self.sheen_color * Rgb::from(t.sample_srgb(images, uv).truncate()),
            None => self.sheen_color,
        }
    }

    /// Sheen roughness at `uv`.
    #[inline]
    fn sheen_roughness_at(&self, uv: Vec2, images: &[Image]) -> f32 {
        self.sheen_roughness * self.sheen_roughness_texture.as_ref().map_or(1.0, |t| t.sample(images, uv).w)
    }
}

/// A BSDF placed on a surface and seen from the outgoing direction `wo`: world ↔ local
/// frame, face-forwarded towards the viewer.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint {
    /// Shading frame; `frame.n` is on the viewer's side.
    pub frame: Frame,
    /// Geometric normal on the viewer's side (the hit's `n_geom`, face-forwarded).
    pub n_geom: Vec3A,
    /// The material's BSDF at this point (textures already looked up), seen from `wo`.
    bsdf: BsdfAt,
    /// Whether light can pass through (then `wi` may lie on either side).
    transmits: bool,
}

impl ShadingPoint {
    /// Orients the normals towards `wo` (unit, pointing away from the surface); the local x
    /// axis is `tangent` where the BSDF is anisotropic (a unit vector across `n_shading`).
    #[inline(always)]
    pub fn new(bsdf: Bsdf, n_geom: Vec3A, n_shading: Vec3A, tangent: Option<Vec3A>, wo: Vec3A) -> Self {
        let n_geom = if n_geom.dot(wo) < 0.0 { -n_geom } else { n_geom };
        let ns = if n_shading.dot(n_geom) < 0.0 { -n_shading } else { n_shading };
        let frame = match tangent {
            Some(t) => Frame::from_normal_tangent(ns, t),
            None => Frame::from_normal(ns),
        };
        Self { frame, n_geom, bsdf: bsdf.at(frame.to_local(wo)), transmits: bsdf.transmits() }
    }

    /// True when world direction `wi` is on a side the surface can send light to, with the
    /// shading and geometric normals agreeing on which side that is (so that interpolated
    /// normals never leak light through a surface).
    #[inline]
    fn allows(&self, wi: Vec3A, local: Vec3A) -> bool {
        let above = wi.dot(self.n_geom) > 0.0;
        (above || self.transmits) && above == (local.z > 0.0)
    }

    /// f(wo, wi)·|cos θi| for world direction `wi`.
    #[inline]
    pub fn eval_cos(&self, wi: Vec3A) -> Rgb {
        let li = self.frame.to_local(wi);
        if !self.allows(wi, li) {
            return Rgb::ZERO;
        }
        self.bsdf.eval(li) * li.z.abs()
    }

    /// Density of sampling world direction `wi`.
    #[inline]
    pub fn pdf(&self, wi: Vec3A) -> f32 {
        let li = self.frame.to_local(wi);
        if !self.allows(wi, li) {
            return 0.0;
        }
        self.bsdf.pdf(li)
    }

    /// [`eval_cos`](Self::eval_cos) and [`pdf`](Self::pdf) for world direction `wi` at once.
    #[inline]
    pub fn eval_cos_pdf(&self, wi: Vec3A) -> (Rgb, f32) {
        let li = self.frame.to_local(wi);
        if !self.allows(wi, li) {
            return (Rgb::ZERO, 0.0);
        }
        let (f, pdf) = self.bsdf.eval_pdf(li);
        (f * li.z.abs(), pdf)
    }

    /// Whether [`sample`](Self::sample) reads its `u_lobe`: a caller may pass anything
    /// (and skip drawing the number) when it does not.
    #[inline]
    pub fn chooses_lobes(&self) -> bool {
        self.bsdf.chooses_lobes()
    }

    /// The mean roughness of what its BSDF samples (see [`BsdfAt::mean_roughness`]).
    #[inline]
    pub fn mean_roughness(&self) -> f32 {
        self.bsdf.mean_roughness()
    }

    /// Whether its BSDF is Lambert's (see [`BsdfAt::is_diffuse`]).
    #[inline]
    pub fn is_diffuse(&self) -> bool {
        self.bsdf.is_diffuse()
    }

    /// The BSDF as light selection weighs it ([`GlossyLobes`]): none for Lambert's, which
    /// weighs every direction alike, nor for surfaces that let light through (selection
    /// weighs their lights without a horizon, [`selection_normal`](Self::selection_normal)).
    #[inline]
    pub fn glossy_lobes(&self) -> Option<GlossyLobes> {
        let BsdfAt::Principled(b) = &self.bsdf else { return None };
        if self.transmits {
            return None;
        }
        let (diffuse, glossy) = b.reflection_shares();
        if glossy[0].0 + glossy[1].0 <= 0.0 {
            return None;
        }
        let wo = b.wo();
        let mirror = self.frame.to_world(Vec3A::new(-wo.x, -wo.y, wo.z));
        Some(GlossyLobes::new(mirror, diffuse, glossy))
    }

    /// Samples a world direction (always inlined into the path loop).
    #[inline(always)]
    pub fn sample(&self, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let s = self.bsdf.sample(u_lobe, u)?;
        let wi = self.frame.to_world(s.wi);
        self.allows(wi, s.wi).then_some(BsdfSample { wi, ..s })
    }

    /// Where a ray leaving `p` along `wi` starts: off the surface on `wi`'s side.
    #[inline]
    pub fn ray_origin(&self, p: Vec3A, wi: Vec3A) -> Vec3A {
        crate::geometry::offset_toward(p, self.n_geom, wi)
    }

    /// The normal light selection weighs lights by (their horizon): none for surfaces that
    /// let light through, whose lights may lie on either side.
    #[inline]
    pub fn selection_normal(&self) -> Vec3A {
        if self.transmits { Vec3A::ZERO } else { self.frame.n }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The directions a shading point samples for `u_lobe` over a grid of `u`.
    fn directions(sp: &ShadingPoint, u_lobe: f32) -> Vec<Option<Vec3A>> {
        (0..64)
            .map(|k| {
                sp.sample(u_lobe, Vec2::new((k % 8) as f32 / 8.0 + 0.05, (k / 8) as f32 / 8.0 + 0.05)).map(|s| s.wi)
            })
            .collect()
    }

    #[test]
    fn normal_maps_tilt_along_the_uv_tangent_of_the_triangle_hit() {
        use crate::geometry::{Attributes, GeometryBuilder, NO_LIGHT, Ray};
        use crate::math::UVec2;
        // One texel: tangent-space normal (0.6, 0, 0.8), tilted towards +u.
        let images = [Image { name: "n".into(), size: UVec2::ONE, texels: vec![[204, 128, 230, 255]] }];
        let material =
            Material { normal_texture: Some((TextureRef::plain(0), 1.0)), ..Material::diffuse("mapped", Rgb::ONE) };
        let quad = [
            Vec3A::new(-1.0, -1.0, 0.0),
            Vec3A::new(1.0, -1.0, 0.0),
            Vec3A::new(1.0, 1.0, 0.0),
            Vec3A::new(-1.0, 1.0, 0.0),
        ];
        // u along +x, then mirrored (u along −x).
        for (uvs, sign) in
            [([Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y], 1.0), ([Vec2::X, Vec2::ZERO, Vec2::Y, Vec2::ONE], -1.0)]
        {
            let mut g = GeometryBuilder::new();
            let base = g.push_vertices(Some(&[Vec3A::Z; 4]), Some(&uvs), 4);
            let attr = Some(Attributes { base, smooth: true, has_uv: true });
            g.push_triangle([quad[0], quad[1], quad[2]], [0, 1, 2], attr, 0, NO_LIGHT, false);
            g.push_triangle([quad[0], quad[2], quad[3]], [0, 2, 3], attr, 0, NO_LIGHT, false);
            let geo = g.build(crate::geometry::TracerKind::default()).0;
            let hit =
                geo.intersect(&Ray::new(Vec3A::new(0.2, 0.3, 1.0), -Vec3A::Z), f32::INFINITY, |_, _| false).unwrap();
            let n = material.mapped_normal(hit.n_shading, || geo.position_derivatives(hit.triangle), hit.uv, &images);
            assert!((n.x - 0.6 * sign).abs() < 0.01 && n.y.abs() < 0.01 && (n.z - 0.8).abs() < 0.01, "{n}");
        }
        // Without a normal map the derivatives are never asked for.
        let plain = Material::diffuse("plain", Rgb::ONE);
        assert_eq!(plain.mapped_normal(Vec3A::Z, || unreachable!(), Vec2::ZERO, &images), Vec3A::Z);
    }

    #[test]
    fn only_bsdfs_that_choose_lobes_read_the_lobe_number() {
        let (n, wo) = (Vec3A::Z, Vec3A::new(0.3, 0.1, 0.9).normalize());
        let lambert = ShadingPoint::new(Bsdf::Diffuse(Diffuse { albedo: Rgb::splat(0.5) }), n, n, None, wo);
        assert!(!lambert.chooses_lobes());
        assert_eq!(directions(&lambert, 0.01), directions(&lambert, 0.99));
        let principled = Principled::new(Rgb::splat(0.5), 0.0, 0.3, 1.5, 1.0, Rgb::ONE);
        let layered = ShadingPoint::new(Bsdf::Principled(principled), n, n, None, wo);
        assert!(layered.chooses_lobes());
        assert_ne!(directions(&layered, 0.01), directions(&layered, 0.99));
    }

    #[test]
    fn glossy_lobes_mirror_the_viewer_and_skip_lambert_and_glass() {
        let n = Vec3A::Z;
        let wo = Vec3A::new(0.3, 0.1, 1.0).normalize();
        let at = |bsdf: Bsdf| ShadingPoint::new(bsdf, n, n, None, wo).glossy_lobes();
        let metal = Principled::new(Rgb::splat(0.9), 1.0, 0.3, 1.5, 0.5, Rgb::ONE);
        let lobes = at(Bsdf::Principled(metal)).expect("metal is glossy");
        assert!((lobes.mirror - Vec3A::new(-wo.x, -wo.y, wo.z)).length() < 1e-5, "{}", lobes.mirror);
        assert!(lobes.diffuse < 1e-6 && (lobes.glossy[0].0 - 1.0).abs() < 1e-5, "{lobes:?}");
        assert!((lobes.glossy[0].1 - 0.09f32.powi(2)).abs() < 1e-7, "α² of roughness 0.3: {lobes:?}");
        // A dielectric splits its energy between the diffuse base and the specular layer, and
        // a coat adds its own lobe.
        let plastic = Principled::new(Rgb::splat(0.8), 0.0, 0.2, 1.5, 0.5, Rgb::ONE).with_coat(1.0, 0.05);
        let lobes = at(Bsdf::Principled(plastic)).expect("a coated dielectric is glossy");
        assert!(lobes.diffuse > 0.3 && lobes.glossy[0].0 > 0.0 && lobes.glossy[1].0 > 0.0, "{lobes:?}");
        assert!((lobes.diffuse + lobes.glossy[0].0 + lobes.glossy[1].0 - 1.0).abs() < 1e-4, "{lobes:?}");
        assert_eq!(at(Bsdf::Diffuse(Diffuse { albedo: Rgb::splat(0.5) })), None);
        let glass = Principled::new(Rgb::ONE, 0.0, 0.1, 1.5, 0.5, Rgb::ONE).with_transmission(1.0, 1.5);
        assert_eq!(at(Bsdf::Principled(glass)), None);
    }
}
