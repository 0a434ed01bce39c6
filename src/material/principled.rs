//! The Principled BSDF as Cycles (Blender 4.x/5.0) evaluates it for a glTF material: an
//! optional coat over a metal mixed by `metallic` with glass (by `transmission`) and with a
//! dielectric specular layer over a Lambertian base.
//!
//! ```text
//! f = f_sheen + (1 − max_rgb A_sheen(μo))·f_coated                     (sheen.rs)
//! f_coated = k·F_c(v·h)·GGX_c·c_coat + (1 − k·A_coat(μo))·f_below     (coat weight k, IOR 1.5)
//! f_below = m·F82(v·h)·GGX·c_metal + (1−m)·t·f_glass
//!         + (1−m)·(1−t)·[ F_d(v·h)·GGX·c_spec + (1 − max_rgb A_spec(μo))·base/π ]
//! f_glass = F(v·h, η)·GGX_reflect + (1 − F)·√base·GGX_refract (Walter et al. 2007), ·c_glass
//! GGX     = D(h)·G2/(4·μo·μi), α = roughness², stretched along the tangent by Anisotropic
//!           for the metal and the specular layer (not the glass or the coat, as Cycles); their
//!           tables read the roughness (α_x·α_y)^¼
//! F82     = Schlick from F0 = base with Cycles' 82° tint (specular colour, white by default)
//! F_d     = mix(F0_d, 1, s(v·h)), s = (F_exact(v·h, η′) − F0(η′)) / (1 − F0(η′)),
//!           F0_d = F0(η)·specularFactor·specularColor, η′ the IOR of F0(η)·specularFactor
//! c       = (E + F_ms·(1 − E)) / E: multiple scattering, E = E(roughness, μo) from tables,
//!           F_ms = F_avg·Ē / (1 − F_avg·(1 − Ē)) with F_avg the lobe's average Fresnel
//! A_spec  = (E + F_ms·(1 − E)) · mix(F0_d, 1, s̄(roughness, μo, η′)): the layer's albedo
//! ```
//! The base is attenuated by the specular layer's albedo towards the viewer, one number for
//! all channels, as Cycles' `closure_layering_weight` does; so the model is not reciprocal
//! (nor is Cycles'). With `specularFactor` 0 (η′ = 1) there is no specular layer and the base
//! is exactly Lambertian. Glass is Cycles' solid refraction: η is the relative IOR across the
//! surface as the ray meets it (ior entering, 1/ior leaving), each crossing transmits √base
//! (so a closed object tints by `base`), and the refracted value carries no η² of radiance
//! compression (Cycles' sampled weight is T·G2/G1); its compensation uses the glass tables
//! with F_avg = √base. A thin-walled sheet (glTF without a volume) transmits base along the
//! reflection mirrored through the surface. Lobes are chosen in proportion to their albedo
//! estimates.

use super::BsdfSample;
use super::fresnel::{self, F82Tint};
use super::microfacet::{Facet, Ggx};
use super::sheen::{Sheen, SheenLobe};
use super::tables;
use crate::math::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::math::{Rgb, Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// The dielectric specular layer.
#[derive(Clone, Copy, Debug)]
struct Specular {
    /// The IOR its Fresnel curve follows (η′).
    eta: f32,
    /// F0(η′).
    f0_eta: f32,
    /// Its normal-incidence colour, F0(η)·specularFactor·specularColor, clamped to [0, 1].
    f0: Rgb,
    /// F0(η′)^¼, the tables' third axis.
    z: f32,
    /// Its average Fresnel over the hemisphere.
    average: Rgb,
}

impl Specular {
    /// The layer of `ior`, `specular` (factor) and `color`; `None` when it reflects nothing.
    fn new(ior: f32, specular: f32, color: Rgb) -> Option<Self> {
        let f0 = fresnel::f0_from_ior(ior) * specular;
        if !(f0 > 0.0) {
            return None;
        }
        let eta = if specular == 1.0 { ior } else { fresnel::ior_from_f0(f0) };
        let f0_eta = fresnel::f0_from_ior(eta);
        let lobe_f0 = (color * f0).clamp(Rgb::ZERO, Rgb::ONE);
        let s_avg = ((fresnel::dielectric_average(eta) - f0_eta) / (1.0 - f0_eta)).clamp(0.0, 1.0);
        // F0^¼ as two square roots: a powf call per shading point was 1 % of a render.
        let z = f0_eta.sqrt().sqrt();
        Some(Self { eta, f0_eta, f0: lobe_f0, z, average: lobe_f0.lerp(Rgb::ONE, s_avg) })
    }

    /// Reflectance at microfacet cosine `mu`.
    #[inline]
    fn fresnel(&self, mu: f32) -> Rgb {
        let s = ((fresnel::dielectric(mu, self.eta) - self.f0_eta) / (1.0 - self.f0_eta)).clamp(0.0, 1.0);
        self.f0.lerp(Rgb::ONE, s)
    }
}

/// The energy a GGX lobe of average Fresnel `average` gets back from multiple scattering:
/// the factor (E + F_ms·(1 − E)) / E on its single-scattering value, and E + F_ms·(1 − E).
#[inline]
fn compensation(e: f32, e_avg: f32, average: Rgb) -> (Rgb, Rgb) {
    let f_ms = average * e_avg / (Rgb::ONE - average * (1.0 - e_avg));
    let kept = Rgb::splat(e) + f_ms * (1.0 - e);
    (kept / e.max(1e-4), kept)
}

/// Blender's Coat layer: a clear dielectric of IOR 1.5 over everything else.
#[derive(Clone, Copy, Debug)]
struct Coat {
    weight: f32,
    roughness: f32,
    ggx: Ggx,
    /// The coat's Fresnel layer (its average and table axis).
    layer: Specular,
}

/// The coat's IOR (Blender's default; glTF's clearcoat has none of its own).
const COAT_IOR: f32 = 1.5;

/// Glass: refraction into (or out of) the object behind the surface (Cycles' solid glass),
/// or, thin-walled, straight through a sheet of no thickness (glTF's default without
/// KHR_materials_volume).
#[derive(Clone, Copy, Debug)]
struct Glass {
    /// Share of the dielectric that is glass (glTF transmission), in (0, 1].
    weight: f32,
    /// Relative IOR: the far side's over the viewer's (a thin sheet's IOR on both sides).
    eta: f32,
    /// What one crossing transmits: √base for a solid (two crossings tint by base), base
    /// for a thin sheet.
    tint: Rgb,
    /// A sheet: light passes without bending, its lobe the reflection mirrored.
    thin: bool,
}

/// The probability that sampling glass of crossing tint `tint` reflects at a facet of Fresnel
/// `f` rather than refracting: in proportion to what each way carries.
#[inline]
pub fn reflect_probability(f: f32, tint: Rgb) -> f32 {
    let t = (1.0 - f) * mean(tint);
    if f + t > 0.0 { f / (f + t) } else { 1.0 }
}

/// `w` mirrored through the surface (z negated): a thin sheet's transmission of the
/// reflection towards `w`.
#[inline]
fn mirrored(w: Vec3A) -> Vec3A {
    Vec3A::new(w.x, w.y, -w.z)
}

impl Glass {
    /// The probability of reflecting at a facet of Fresnel `f`.
    #[inline]
    fn reflect_probability(&self, f: f32) -> f32 {
        reflect_probability(f, self.tint)
    }

    /// The half vector of `wo` refracted to `wi` (on the upper side), with the Jacobian of
    /// the half vector against `wi` and the two cosines; `None` when no facet refracts one
    /// into the other.
    #[inline]
    fn refraction(&self, wo: Vec3A, wi: Vec3A) -> Option<(Vec3A, f32, f32, f32)> {
        let h = -(wo + wi * self.eta);
        let h = h.try_normalize()?;
        let h = if h.z < 0.0 { -h } else { h };
        let (cos_o, cos_i) = (wo.dot(h), wi.dot(h));
        if !(cos_o > 0.0 && cos_i < 0.0) {
            return None;
        }
        let denominator = cos_o + self.eta * cos_i;
        let jacobian = self.eta * self.eta * cos_i.abs() / (denominator * denominator);
        Some((h, jacobian, cos_o, cos_i))
    }
}

/// The model at one surface point.
#[derive(Clone, Copy, Debug)]
pub struct Principled {
    base: Rgb,
    metallic: f32,
    roughness: f32,
    /// The metal's and the specular layer's distribution (anisotropic along local x; the
    /// glass's is isotropic of `roughness` whatever the anisotropy, [`Principled::glass_ggx`]).
    ggx: Ggx,
    metal: F82Tint,
    specular: Option<Specular>,
    coat: Option<Coat>,
    glass: Option<Glass>,
    sheen: Option<Sheen>,
}

/// What depends on the outgoing direction: the lobes' weights and the choice between them.
#[derive(Clone, Copy, Debug)]
struct View {
    coat: f32,
    metal: Rgb,
    specular: Rgb,
    glass: Rgb,
    diffuse: Rgb,
    /// Probabilities of sampling the sheen, the coat's GGX lobe, the base's (metal and
    /// specular share one distribution) and the glass's; the rest goes to the diffuse lobe.
    p_sheen: f32,
    p_coat: f32,
    p_glossy: f32,
    p_glass: f32,
}

fn mean(c: Rgb) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

impl Principled {
    /// The model for base colour, metallic and roughness (in [0, 1]), IOR (> 1), specular
    /// factor (in [0, 1]) and specular colour (≥ 0).
    #[inline]
    pub fn new(base: Rgb, metallic: f32, roughness: f32, ior: f32, specular: f32, specular_color: Rgb) -> Self {
        Self {
            base,
            metallic,
            roughness,
            ggx: Ggx::from_roughness(roughness),
            metal: F82Tint::new(base.min(Rgb::ONE), specular_color.min(Rgb::ONE)),
            specular: Specular::new(ior, specular, specular_color),
            coat: None,
            glass: None,
            sheen: None,
        }
    }

    /// The same with its metal and specular layer stretched by Blender's `anisotropic` (in
    /// [0, 1]) along the local x axis, the tangent.
    #[inline]
    pub fn with_anisotropy(self, anisotropic: f32) -> Self {
        if !(anisotropic > 0.0) {
            return self;
        }
        Self { ggx: Ggx::anisotropic(self.roughness, anisotropic), ..self }
    }

    /// The roughness the metal's and specular layer's energy tables read: (α_x·α_y)^¼ after
    /// clamping when anisotropic, as Cycles.
    #[inline]
    fn table_roughness(&self) -> f32 {
        if self.ggx.is_isotropic() { self.roughness } else { self.ggx.table_roughness() }
    }

    /// The glass's distribution.
    #[inline]
    fn glass_ggx(&self) -> Ggx {
        if self.ggx.is_isotropic() { self.ggx } else { Ggx::from_roughness(self.roughness) }
    }

    /// The sheen lobe seen from `wo`, when there is one.
    #[inline]
    fn sheen_lobe(&self, wo: Vec3A) -> Option<SheenLobe> {
        self.sheen.and_then(|s| s.at(wo))
    }

    /// The same under a sheen of `color` (Sheen Weight × Sheen Tint, ≥ 0) and `roughness`.
    #[inline]
    pub fn with_sheen(self, color: Rgb, roughness: f32) -> Self {
        let sheen = (color.max_element() > 0.0).then_some(Sheen { color: color.into(), roughness });
        Self { sheen, ..self }
    }

    /// The same with `transmission` (in [0, 1]) of its dielectric as glass, met at relative
    /// IOR `eta` (ior when the ray enters the object, 1/ior when it leaves).
    #[inline]
    pub fn with_transmission(self, transmission: f32, eta: f32) -> Self {
        let tint = Rgb::new(self.base.x.sqrt(), self.base.y.sqrt(), self.base.z.sqrt());
        let glass =
            (transmission > 0.0 && eta != 1.0).then_some(Glass { weight: transmission, eta, tint, thin: false });
        Self { glass, ..self }
    }

    /// The same with `transmission` (in [0, 1]) of its dielectric as a thin-walled sheet of
    /// `ior`, which light crosses without bending.
    #[inline]
    pub fn with_thin_transmission(self, transmission: f32, ior: f32) -> Self {
        let glass =
            (transmission > 0.0).then_some(Glass { weight: transmission, eta: ior, tint: self.base, thin: true });
        Self { glass, ..self }
    }

    /// True when light can pass through (the BSDF has a refraction lobe).
    pub fn transmits(&self) -> bool {
        self.glass.is_some()
    }

    /// The same with a coat of `weight` and `roughness` (both in [0, 1]) on top.
    #[inline]
    pub fn with_coat(self, weight: f32, roughness: f32) -> Self {
        let coat = (weight > 0.0).then(|| {
            let layer = Specular::new(COAT_IOR, 1.0, Rgb::ONE).expect("IOR 1.5 reflects");
            Coat { weight, roughness, ggx: Ggx::from_roughness(roughness), layer }
        });
        Self { coat, ..self }
    }

    #[inline]
    fn view(&self, wo: Vec3A) -> View {
        let mu = wo.z;
        let rough = self.table_roughness();
        let (e, e_avg) = (tables::albedo(rough, mu), tables::albedo_average(rough));
        let (metal_gain, _) = compensation(e, e_avg, self.metal.average());
        let metal = metal_gain * self.metallic;
        let transmission = self.glass.map_or(0.0, |g| g.weight);
        let dielectric = (1.0 - self.metallic) * (1.0 - transmission);
        let (glass, glass_albedo) = match &self.glass {
            Some(g) => {
                // A sheet's two lobes make one reflection-shaped lobe of Fresnel F + (1 − F)·tint.
                let (e, e_avg, average) = if g.thin {
                    let f = fresnel::dielectric_average(g.eta);
                    (e, e_avg, Rgb::splat(f) + g.tint * (1.0 - f))
                } else {
                    (
                        tables::glass_albedo(self.roughness, mu, g.eta),
                        tables::glass_albedo_average(self.roughness, g.eta),
                        g.tint,
                    )
                };
                let (gain, kept) = compensation(e, e_avg, average);
                let weight = (1.0 - self.metallic) * g.weight;
                (gain * weight, weight * mean(kept))
            }
            None => (Rgb::ZERO, 0.0),
        };
        let (specular, layer_albedo) = match &self.specular {
            Some(s) => {
                let (gain, kept) = compensation(e, e_avg, s.average);
                let albedo = kept * s.f0.lerp(Rgb::ONE, tables::fresnel_weight(rough, mu, s.z));
                (gain * dielectric, albedo.max_element().clamp(0.0, 1.0))
            }
            None => (Rgb::ZERO, 0.0),
        };
        let diffuse = self.base * (dielectric * (1.0 - layer_albedo) * FRAC_1_PI);
        let glossy = self.metallic * mean(self.metal.average()) + dielectric * layer_albedo;
        // The coat takes its albedo from everything under it (one number, as Cycles does).
        let (coat, coat_albedo, below) = match &self.coat {
            Some(c) => {
                let e = tables::albedo(c.roughness, mu);
                let (gain, kept) = compensation(e, tables::albedo_average(c.roughness), c.layer.average);
                let albedo =
                    kept.x * (c.layer.f0.x + (1.0 - c.layer.f0.x) * tables::fresnel_weight(c.roughness, mu, c.layer.z));
                (c.weight * gain.x, c.weight * albedo, (1.0 - c.weight * albedo).clamp(0.0, 1.0))
            }
            None => (0.0, 0.0, 1.0),
        };
        // The sheen, on top of all, takes its albedo from everything under it likewise.
        let (sheen_albedo, coat, coat_albedo, below) = match self.sheen_lobe(wo) {
            Some(l) => {
                let top = (1.0 - l.albedo()).clamp(0.0, 1.0);
                (mean(l.weight), top * coat, top * coat_albedo, top * below)
            }
            None => (0.0, coat, coat_albedo, below),
        };
        let (glossy, glass_albedo) = (below * glossy, below * glass_albedo);
        let diffuse_albedo = below * mean(diffuse) * std::f32::consts::PI;
        let total = sheen_albedo + coat_albedo + glossy + glass_albedo + diffuse_albedo;
        let p = |x: f32| if total > 0.0 { x / total } else { 0.0 };
        View {
            coat,
            metal: metal * below,
            specular: specular * below,
            glass: glass * below,
            diffuse: diffuse * below,
            p_sheen: p(sheen_albedo),
            p_coat: p(coat_albedo),
            p_glossy: p(glossy),
            p_glass: p(glass_albedo),
        }
    }

    /// The value f(wo, wi) (without the cosine) where `F`, and the density of sampling `wi`
    /// where `P` (0 for what is not asked for): asked together, they share the half vector,
    /// each lobe's D(h) and Λ(wo) ([`Facet`]) and the sheen seen from `wo`.
    #[inline(always)]
    fn eval_pdf_view<const F: bool, const P: bool>(&self, v: &View, wo: Vec3A, wi: Vec3A) -> (Rgb, f32) {
        if wi.z < 0.0 {
            return self.transmitted::<F, P>(v, wo, wi);
        }
        let h = (wo + wi).normalize();
        let base = self.ggx.facet(wo, h);
        // The glass reflects with the base's distribution where that is isotropic.
        let glass_facet = self.glass.map(|_| match self.ggx.is_isotropic() {
            true => (self.ggx, base),
            false => {
                let gg = self.glass_ggx();
                (gg, gg.facet(wo, h))
            }
        });
        let coat = self.coat.map(|c| (c, c.ggx.facet(wo, h)));
        let sheen = if v.p_sheen > 0.0 { self.sheen_lobe(wo) } else { None };
        let value = if F {
            let mu = wo.dot(h).max(0.0);
            let lobe = |g: &Ggx, facet: Facet| facet.d * g.g2_from(facet, wi) / (4.0 * wo.z * wi.z);
            let specular = self.specular.map_or(Rgb::ZERO, |s| s.fresnel(mu) * v.specular);
            let base_lobe = lobe(&self.ggx, base);
            let glass = self.glass.zip(glass_facet).map_or(Rgb::ZERO, |(g, (gg, facet))| {
                let glass_lobe = if self.ggx.is_isotropic() { base_lobe } else { lobe(&gg, facet) };
                v.glass * (fresnel::dielectric(mu, g.eta) * glass_lobe)
            });
            let coat = coat.map_or(Rgb::ZERO, |(c, facet)| c.layer.fresnel(mu) * (v.coat * lobe(&c.ggx, facet)));
            let sheen = sheen.map_or(Rgb::ZERO, |l| l.eval(wi));
            sheen + coat + (self.metal.eval(mu) * v.metal + specular) * base_lobe + glass + v.diffuse
        } else {
            Rgb::ZERO
        };
        let pdf = if P {
            let coat = coat.map_or(0.0, |(_, facet)| v.p_coat * facet.reflection_pdf(wo));
            let glass = self.glass.zip(glass_facet).map_or(0.0, |(g, (_, facet))| {
                let f = fresnel::dielectric(wo.dot(h), g.eta);
                v.p_glass * g.reflect_probability(f) * facet.reflection_pdf(wo)
            });
            let sheen = sheen.map_or(0.0, |l| v.p_sheen * l.pdf(wi));
            let diffuse = (1.0 - v.p_sheen - v.p_coat - v.p_glossy - v.p_glass).max(0.0);
            sheen + coat + glass + v.p_glossy * base.reflection_pdf(wo) + diffuse * cosine_hemisphere_pdf(wi.z)
        } else {
            0.0
        };
        (value, pdf)
    }

    /// [`eval_pdf_view`](Self::eval_pdf_view) below the surface (`wi.z` < 0): the glass's
    /// transmission, through a thin sheet or refracted.
    #[inline(always)]
    fn transmitted<const F: bool, const P: bool>(&self, v: &View, wo: Vec3A, wi: Vec3A) -> (Rgb, f32) {
        self.glass.map_or((Rgb::ZERO, 0.0), |g| {
            let gg = self.glass_ggx();
            if g.thin {
                let m = mirrored(wi);
                let h = (wo + m).normalize();
                let f = fresnel::dielectric(wo.dot(h), g.eta);
                let facet = gg.facet(wo, h);
                let value = if F {
                    let lobe = facet.d * gg.g2_from(facet, m) / (4.0 * wo.z * m.z);
                    g.tint * v.glass * ((1.0 - f) * lobe)
                } else {
                    Rgb::ZERO
                };
                let pdf = if P { v.p_glass * (1.0 - g.reflect_probability(f)) * facet.reflection_pdf(wo) } else { 0.0 };
                return (value, pdf);
            }
            let Some((h, jacobian, cos_o, cos_i)) = g.refraction(wo, wi) else { return (Rgb::ZERO, 0.0) };
            let f = fresnel::dielectric(cos_o, g.eta);
            let facet = gg.facet(wo, h);
            let value = if F {
                let denominator = cos_o + g.eta * cos_i;
                let geometry = facet.d * gg.g2_from(facet, wi) * g.eta * g.eta * cos_o * cos_i.abs()
                    / (wo.z * wi.z.abs() * denominator * denominator);
                g.tint * v.glass * ((1.0 - f) * geometry)
            } else {
                Rgb::ZERO
            };
            let pdf = if P {
                let visible = facet.g1() * cos_o * facet.d / wo.z;
                v.p_glass * (1.0 - g.reflect_probability(f)) * visible * jacobian
            } else {
                0.0
            };
            (value, pdf)
        })
    }

    /// True when `wi` is on a side of the surface the model can send light to.
    #[inline]
    fn reaches(&self, wo: Vec3A, wi: Vec3A) -> bool {
        wo.z > 0.0 && (wi.z > 0.0 || (wi.z < 0.0 && self.glass.is_some()))
    }

    /// The model seen from `wo`: its lobe weights, which depend on μo alone, computed once
    /// for every query that follows (a shading point asks for a sample, a value and a
    /// density from the same `wo`; each used to recompute them, with five table lookups).
    #[inline]
    pub fn at(&self, wo: Vec3A) -> PrincipledAt {
        PrincipledAt { model: *self, wo, view: self.view(wo) }
    }
}

/// A [`Principled`] model seen from one outgoing direction `wo` (local frame, z up).
#[derive(Clone, Copy, Debug)]
pub struct PrincipledAt {
    model: Principled,
    wo: Vec3A,
    view: View,
}

impl PrincipledAt {
    /// The outgoing direction it is seen from (local frame).
    #[inline]
    pub fn wo(&self) -> Vec3A {
        self.wo
    }

    /// BSDF value (without the cosine) towards `wi`.
    #[inline]
    pub fn eval(&self, wi: Vec3A) -> Rgb {
        let (m, wo) = (&self.model, self.wo);
        if !m.reaches(wo, wi) {
            return Rgb::ZERO;
        }
        m.eval_pdf_view::<true, false>(&self.view, wo, wi).0
    }

    /// [`eval`](Self::eval) and [`pdf`](Self::pdf) towards `wi` at once, for less than both.
    #[inline]
    pub fn eval_pdf(&self, wi: Vec3A) -> (Rgb, f32) {
        let (m, wo) = (&self.model, self.wo);
        if !m.reaches(wo, wi) {
            return (Rgb::ZERO, 0.0);
        }
        m.eval_pdf_view::<true, true>(&self.view, wo, wi)
    }

    /// The perceptual roughness of the lobes it samples, averaged with the probability it
    /// samples each (Lambert's and the sheen's count as 1): how much a learned directional
    /// distribution can stand in for its sampling (Cycles' guiding probability is
    /// proportional to it).
    #[inline]
    pub fn mean_roughness(&self) -> f32 {
        let (m, v) = (&self.model, &self.view);
        let diffuse = (1.0 - v.p_sheen - v.p_coat - v.p_glossy - v.p_glass).max(0.0);
        let coat = m.coat.map_or(0.0, |c| c.roughness);
        diffuse + v.p_sheen + v.p_coat * coat + (v.p_glossy + v.p_glass) * m.roughness
    }

    /// How the energy it reflects divides between its diffuse part and its GGX lobes about the
    /// mirror direction (the base's, the coat's): their shares and widths α (the wider axis
    /// where anisotropic), what light selection weighs it by.
    #[inline]
    pub fn reflection_shares(&self) -> (f32, [(f32, f32); 2]) {
        let (m, v) = (&self.model, &self.view);
        let diffuse = (1.0 - v.p_coat - v.p_glossy - v.p_glass).max(0.0);
        let coat = m.coat.map_or((0.0, 1.0), |c| (v.p_coat, c.ggx.alpha_x));
        (diffuse, [(v.p_glossy, m.ggx.alpha_x.max(m.ggx.alpha_y)), coat])
    }

    /// Solid-angle density of [`PrincipledAt::sample`] at `wi`.
    #[inline]
    pub fn pdf(&self, wi: Vec3A) -> f32 {
        let (m, wo) = (&self.model, self.wo);
        if !m.reaches(wo, wi) {
            return 0.0;
        }
        m.eval_pdf_view::<false, true>(&self.view, wo, wi).1
    }

    /// Picks the glossy or the diffuse lobe with `u_lobe`, then a direction with `u` (always
    /// inlined into the path loop).
    #[inline(always)]
    pub fn sample(&self, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let (m, wo, v) = (&self.model, self.wo, &self.view);
        if wo.z <= 0.0 {
            return None;
        }
        let reflect = |g: &Ggx| {
            let h = g.sample_visible_normal(wo, u);
            2.0 * wo.dot(h) * h - wo
        };
        let coat_from = v.p_sheen;
        let glossy_from = coat_from + v.p_coat;
        let glass_from = glossy_from + v.p_glossy;
        let wi = match (u_lobe < coat_from, u_lobe < glossy_from, u_lobe < glass_from, u_lobe < glass_from + v.p_glass)
        {
            (true, ..) => m.sheen_lobe(wo)?.sample(u),
            (_, true, ..) => reflect(&m.coat?.ggx),
            (_, _, true, _) => reflect(&m.ggx),
            (.., true) => {
                // The rest of the lobe number decides between reflection and refraction.
                // A direction on the wrong side for its lobe is dropped, as Cycles does.
                let g = m.glass?;
                let h = m.glass_ggx().sample_visible_normal(wo, u);
                let f = fresnel::dielectric(wo.dot(h), g.eta);
                let reflected = 2.0 * wo.dot(h) * h - wo;
                if (u_lobe - glass_from) / v.p_glass < g.reflect_probability(f) {
                    Some(reflected).filter(|wi| wi.z > 0.0)?
                } else if g.thin {
                    Some(mirrored(reflected)).filter(|wi| wi.z < 0.0)?
                } else {
                    super::microfacet::refract(wo, h, g.eta).filter(|wi| wi.z < 0.0)?
                }
            }
            _ => square_to_cosine_hemisphere(u),
        };
        if !m.reaches(wo, wi) {
            return None;
        }
        let (f, pdf) = m.eval_pdf_view::<true, true>(v, wo, wi);
        if !(pdf > 0.0) {
            return None;
        }
        Some(BsdfSample { wi, weight: f * (wi.z.abs() / pdf), pdf })
    }
}
