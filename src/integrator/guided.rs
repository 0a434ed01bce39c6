//! Scattering with path guiding: the BSDF's sampling mixed with a learned directional
//! distribution, and what a path records for guiding to learn from.
//!
//! At a vertex whose region has learned a distribution, the direction is drawn from it with
//! probability α = [`GUIDED_SHARE`] × the BSDF's mean roughness (Cycles' rule: a narrow
//! lobe is better sampled by itself), from the BSDF otherwise (`Dim::GuideChoice`), and its
//! density is the mixture's, α·p_guide + (1 − α)·p_bsdf, whichever drew it: one-sample MIS
//! with the balance heuristic, so a direction the guide never proposes keeps the BSDF's
//! density and the image stays unbiased. Next-event estimation weighs its light samples
//! against the same mixture density. Below [`MIN_ROUGHNESS`] nothing is guided.

use crate::guiding::{Directions, Guide, Records};
use crate::material::{BsdfSample, ShadingPoint};
use crate::math::{Rgb, Vec3A, luminance};
use crate::sampling::{Dim, SampleStream};

/// Largest share of directions the guide draws (at Lambertian vertices; Müller et al.'s and
/// Cycles' 0.5).
pub const GUIDED_SHARE: f32 = 0.5;
/// Mean roughness below which a vertex is not guided (Cycles' default threshold).
pub const MIN_ROUGHNESS: f32 = 0.05;

/// A shading point and, where guiding has learned, the distribution mixed into its sampling.
#[derive(Clone, Copy, Debug)]
pub struct Scattering<'a> {
    /// The BSDF at the point.
    pub sp: &'a ShadingPoint,
    /// The learned distribution and the share α of directions it draws.
    guide: Option<(&'a Directions, f32)>,
    /// Whether the render guides and the BSDF is rough enough to be guided here (where a
    /// path learning for guiding records what comes through).
    guidable: bool,
}

impl<'a> Scattering<'a> {
    /// Scattering at point `p` of `sp`, guided by `guide` where it has learned something.
    #[inline]
    pub fn new(sp: &'a ShadingPoint, p: Vec3A, guide: Option<&'a Guide>) -> Self {
        let Some(g) = guide else { return Self { sp, guide: None, guidable: false } };
        let roughness = sp.mean_roughness();
        let guidable = roughness >= MIN_ROUGHNESS;
        let guide = guidable.then(|| g.at(p, sp.n_geom)).flatten().map(|d| (d, GUIDED_SHARE * roughness.min(1.0)));
        Self { sp, guide, guidable }
    }

    /// Whether guiding may take part here (and a path learning for it should record what
    /// comes through).
    #[inline]
    pub fn guidable(&self) -> bool {
        self.guidable
    }

    /// Density of sampling world direction `wi` (unit).
    #[inline]
    pub fn pdf(&self, wi: Vec3A) -> f32 {
        self.mixed_pdf(wi, self.sp.pdf(wi))
    }

    /// Density of sampling world direction `wi` (unit) where the BSDF samples it with
    /// density `bsdf` (from [`ShadingPoint::eval_cos_pdf`]).
    #[inline]
    pub fn mixed_pdf(&self, wi: Vec3A, bsdf: f32) -> f32 {
        match self.guide {
            None => bsdf,
            Some((d, alpha)) => alpha * d.pdf(wi) + (1.0 - alpha) * bsdf,
        }
    }

    /// The BSDF's own sample with the numbers of `bounce` (what [`sample`](Self::sample) draws
    /// where nothing guides). Always inlined, with what it calls, into the path loop.
    #[inline(always)]
    pub fn bsdf_sample(&self, stream: &SampleStream, bounce: u32) -> Option<BsdfSample> {
        let u_lobe = if self.sp.chooses_lobes() { stream.get_1d(bounce, Dim::BsdfLobe, 0) } else { 0.0 };
        self.sp.sample(u_lobe, stream.get_2d(bounce, Dim::BsdfDirection, 0))
    }

    /// Samples a world direction with the numbers of `bounce`.
    #[inline]
    pub fn sample(&self, stream: &SampleStream, bounce: u32) -> Option<BsdfSample> {
        let from_bsdf = || self.bsdf_sample(stream, bounce);
        let Some((d, alpha)) = self.guide else { return from_bsdf() };
        if stream.get_1d(bounce, Dim::GuideChoice, 0) < alpha {
            let (wi, p_guide) = d.sample(stream.get_2d(bounce, Dim::GuideDirection, 0));
            let (f, bsdf) = self.sp.eval_cos_pdf(wi);
            if f == Rgb::ZERO {
                return None;
            }
            let pdf = alpha * p_guide + (1.0 - alpha) * bsdf;
            Some(BsdfSample { wi, weight: f / pdf, pdf })
        } else {
            let s = from_bsdf()?;
            let pdf = alpha * d.pdf(s.wi) + (1.0 - alpha) * s.pdf;
            Some(BsdfSample { weight: s.weight * (s.pdf / pdf), pdf, ..s })
        }
    }
}

/// A vertex a path left by a sampled direction, for guiding to learn from.
#[derive(Clone, Copy, Debug)]
struct TrailVertex {
    p: Vec3A,
    /// The side of the surface it was on (the face-forwarded geometric normal).
    n: Vec3A,
    wi: Vec3A,
    /// The density `wi` was drawn with.
    pdf: f32,
    /// The path's throughput once through the vertex (what light arriving along `wi` is
    /// multiplied by on its way to the camera).
    beta: Rgb,
    /// Radiance the path had gathered when it left the vertex.
    gathered: Rgb,
}

/// The vertices of the path being traced that guiding learns from: at its end, each learns
/// the light that came back through it, `(L_end − L_then) / β_then`. One per worker, reused
/// path after path (no allocation once it has grown to a path's length).
#[derive(Debug, Default)]
pub struct Trail {
    vertices: Vec<TrailVertex>,
}

impl Trail {
    /// Notes that the path left point `p`, where `s` scattered it as `sample` says, with
    /// throughput `beta` after it, having gathered `gathered` so far.
    #[inline]
    pub fn push(&mut self, p: Vec3A, s: &Scattering, sample: &BsdfSample, beta: Rgb, gathered: Rgb) {
        let (n, wi, pdf) = (s.sp.n_geom, sample.wi, sample.pdf);
        self.vertices.push(TrailVertex { p, n, wi, pdf, beta, gathered });
    }

    /// Records into `records` what came back through each vertex, the path having gathered
    /// `total`, and empties the trail for the next path.
    pub fn close(&mut self, total: Rgb, records: &Records) {
        if self.vertices.is_empty() {
            return;
        }
        let mut recorder = records.recorder();
        for v in self.vertices.drain(..) {
            let d = total - v.gathered;
            let per = |d: f32, b: f32| if b > 0.0 { d / b } else { 0.0 };
            let arriving = Rgb::new(per(d.x, v.beta.x), per(d.y, v.beta.y), per(d.z, v.beta.z));
            recorder.record(v.p, v.n, v.wi, luminance(arriving).max(0.0) / v.pdf);
        }
    }
}
