//! `local`: a CDF over every light's importance at the shading point, the seed's "weighted"
//! sampler and pbrt-v4's `ExhaustiveLightSampler`.
//!
//! O(n) per shading point, and again for the pmf MIS needs at an emitter hit: the ideal the
//! light tree approximates in O(log n). Like pbrt, no table is built: one pass draws the light
//! by streaming weighted reservoir sampling with the single number remapped at each step (in
//! f64, so 10⁶ steps lose no accuracy that matters), so a call allocates nothing.

use super::{LightSampler, SampledLight, ShadingContext};
use crate::light::{BoundsView, Light, LightId};

/// Importance-proportional selection over all lights.
#[derive(Clone, Debug)]
pub struct LocalSampler {
    bounds: Vec<BoundsView>,
}

impl LocalSampler {
    /// A sampler over `lights`.
    pub fn new(lights: &[Light]) -> Self {
        Self { bounds: lights.iter().map(|l| l.bounds().view()).collect() }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.bounds.capacity() * std::mem::size_of::<BoundsView>()
    }
}

impl LightSampler for LocalSampler {
    fn sample(&self, ctx: &ShadingContext, u: f32) -> Option<SampledLight> {
        // Reservoir of one: after light i, the kept light is j ≤ i with probability w_j/W_i,
        // and u stays uniform given the choices so far.
        let (mut u, mut total, mut chosen, mut chosen_w) = (u as f64, 0.0f64, usize::MAX, 0.0f64);
        for (i, b) in self.bounds.iter().enumerate() {
            let w = b.importance(ctx.p, ctx.n) as f64;
            if w <= 0.0 {
                continue;
            }
            total += w;
            let p = w / total;
            if u < p {
                chosen = i;
                chosen_w = w;
                u /= p;
            } else {
                u = (u - p) / (1.0 - p);
            }
        }
        (chosen != usize::MAX).then(|| SampledLight { light: LightId(chosen as u32), pmf: (chosen_w / total) as f32 })
    }

    fn pmf(&self, ctx: &ShadingContext, light: LightId) -> f32 {
        let w = self.bounds[light.0 as usize].importance(ctx.p, ctx.n) as f64;
        if w <= 0.0 {
            return 0.0;
        }
        let total: f64 = self.bounds.iter().map(|b| b.importance(ctx.p, ctx.n) as f64).sum();
        (w / total) as f32
    }
}
