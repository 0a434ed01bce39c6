//! `local`: a CDF over every light's importance at the shading point, the seed's "weighted"
//! sampler and pbrt-v4's `ExhaustiveLightSampler`.
//!
//! O(n) per shading point, and again for the pmf MIS needs at an emitter hit: the ideal the
//! light tree approximates in O(log n). Importances are evaluated four lights at a time
//! (`BoundsPacket`, SSE). Like pbrt, no table is built: one pass draws the light by streaming
//! weighted reservoir sampling with the single number remapped at each step (in f64, so 10⁶
//! steps lose no accuracy that matters), so a call allocates nothing.

use super::{LightSampler, SampledLight, ShadingContext};
use crate::light::{BoundsPacket, Light, LightBounds, LightId};

/// Importance-proportional selection over all lights.
#[derive(Clone, Debug)]
pub struct LocalSampler {
    packets: Vec<BoundsPacket>,
}

impl LocalSampler {
    /// A sampler over `lights`.
    pub fn new(lights: &[Light]) -> Self {
        let bounds: Vec<LightBounds> = lights.iter().map(Light::bounds).collect();
        Self { packets: bounds.chunks(4).map(BoundsPacket::new).collect() }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.packets.capacity() * std::mem::size_of::<BoundsPacket>()
    }
}

impl LightSampler for LocalSampler {
    fn sample(&self, ctx: &ShadingContext, u: f32) -> Option<SampledLight> {
        // Reservoir of one: after light i, the kept light is j ≤ i with probability w_j/W_i,
        // and u stays uniform given the choices so far.
        let (mut u, mut total, mut chosen, mut chosen_w) = (u as f64, 0.0f64, usize::MAX, 0.0f64);
        for (k, packet) in self.packets.iter().enumerate() {
            for (lane, w) in packet.importance(ctx.p, ctx.n).to_array().into_iter().enumerate() {
                if w <= 0.0 {
                    continue;
                }
                let w = w as f64;
                total += w;
                let p = w / total;
                if u < p {
                    chosen = 4 * k + lane;
                    chosen_w = w;
                    u /= p;
                } else {
                    u = (u - p) / (1.0 - p);
                }
            }
        }
        (chosen != usize::MAX).then(|| SampledLight { light: LightId(chosen as u32), pmf: (chosen_w / total) as f32 })
    }

    fn pmf(&self, ctx: &ShadingContext, light: LightId) -> f32 {
        let (k, lane) = (light.0 as usize / 4, light.0 as usize % 4);
        let w = self.packets[k].importance(ctx.p, ctx.n).to_array()[lane] as f64;
        if w <= 0.0 {
            return 0.0;
        }
        // Summed in the same order as `sample`, so the two agree to the last bit.
        let mut total = 0.0f64;
        for packet in &self.packets {
            for x in packet.importance(ctx.p, ctx.n).to_array() {
                if x > 0.0 {
                    total += x as f64;
                }
            }
        }
        (w / total) as f32
    }
}
