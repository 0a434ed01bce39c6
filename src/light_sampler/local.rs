//! `local`: a CDF over every light's importance at the shading point, the seed's "weighted"
//! sampler (its `lights_pdf` and `lights_cdf`) and pbrt-v4's `ExhaustiveLightSampler`.
//!
//! O(n) per shading point, and again for the pmf MIS needs at an emitter hit: the ideal the
//! light tree approximates in O(log n). Importances are evaluated four lights at a time
//! (`BoundsPacket`, SSE) into a per-thread scratch table (allocated once per thread), and the
//! light is found by inverting the cumulative sum in f64. Inversion keeps the mapping from
//! `u` to lights monotone, so stratified `u` stay stratified over the lights (pbrt's
//! single-pass reservoir does not: its choice jumps around as `u` moves), and the lights are
//! laid out in Morton order of their centres, so that neighbouring `u` pick neighbouring
//! lights in space, not in file order (on `cornell-32x32`, direct light, 16 spp, 320 × 240:
//! relMSE 0.0421 in file order, 0.0414 in Morton order, tree 0.0415).

use std::cell::RefCell;

use super::{LightSampler, SampledLight, ShadingContext};
use crate::light::{BoundsPacket, Light, LightBounds, LightId};

thread_local! {
    /// Importances of the current shading point, reused across calls.
    static SCRATCH: RefCell<Vec<f32>> = const { RefCell::new(Vec::new()) };
}

/// Importance-proportional selection over all lights.
#[derive(Clone, Debug)]
pub struct LocalSampler {
    /// Bounds in Morton order, four per packet.
    packets: Vec<BoundsPacket>,
    /// Slot (Morton position) → light.
    order: Vec<u32>,
    /// Light → slot.
    slot: Vec<u32>,
}

/// Spreads the low 10 bits of `v` to every third bit.
fn spread3(mut v: u32) -> u32 {
    v &= 0x3ff;
    v = (v | (v << 16)) & 0x0300_00ff;
    v = (v | (v << 8)) & 0x0300_f00f;
    v = (v | (v << 4)) & 0x030c_30c3;
    (v | (v << 2)) & 0x0924_9249
}

impl LocalSampler {
    /// A sampler over `lights`.
    pub fn new(lights: &[Light]) -> Self {
        let bounds: Vec<LightBounds> = lights.iter().map(Light::bounds).collect();
        let (mut lo, mut hi) = (glam::Vec3A::splat(f32::MAX), glam::Vec3A::splat(f32::MIN));
        for b in bounds.iter().filter(|b| !b.infinite) {
            lo = lo.min(b.centroid());
            hi = hi.max(b.centroid());
        }
        let scale = 1023.0 / (hi - lo).max(glam::Vec3A::splat(1e-12));
        // Directional lights sort last.
        let morton = |b: &LightBounds| -> u64 {
            if b.infinite {
                return u64::MAX;
            }
            let q = ((b.centroid() - lo) * scale).max(glam::Vec3A::ZERO).min(glam::Vec3A::splat(1023.0));
            (spread3(q.x as u32) | (spread3(q.y as u32) << 1) | (spread3(q.z as u32) << 2)) as u64
        };
        let mut order: Vec<u32> = (0..lights.len() as u32).collect();
        order.sort_by_key(|&i| (morton(&bounds[i as usize]), i));
        let mut slot = vec![0u32; lights.len()];
        for (s, &l) in order.iter().enumerate() {
            slot[l as usize] = s as u32;
        }
        let sorted: Vec<LightBounds> = order.iter().map(|&l| bounds[l as usize]).collect();
        Self { packets: sorted.chunks(4).map(BoundsPacket::new).collect(), order, slot }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.packets.capacity() * std::mem::size_of::<BoundsPacket>()
            + (self.order.capacity() + self.slot.capacity()) * 4
    }

    /// Fills `out` with every light's importance at `ctx` and returns their f64 sum (summed
    /// in light order, the same order `pmf` uses).
    fn importances(&self, ctx: &ShadingContext, out: &mut Vec<f32>) -> f64 {
        out.clear();
        let mut total = 0.0f64;
        for packet in &self.packets {
            for w in packet.importance(ctx.p, ctx.n).to_array() {
                out.push(w);
                total += w as f64;
            }
        }
        out.truncate(self.order.len());
        total
    }
}

impl LightSampler for LocalSampler {
    fn sample(&self, ctx: &ShadingContext, u: f32) -> Option<SampledLight> {
        SCRATCH.with_borrow_mut(|w| {
            let total = self.importances(ctx, w);
            if !(total > 0.0) {
                return None;
            }
            // The light whose cumulative range holds u·total; the last positive light takes
            // any round-off remainder.
            let target = u as f64 * total;
            let last = w.iter().rposition(|&x| x > 0.0)?;
            let mut below = 0.0f64;
            let mut chosen = last;
            for (i, &x) in w[..last].iter().enumerate() {
                below += x as f64;
                if target < below && x > 0.0 {
                    chosen = i;
                    break;
                }
            }
            Some(SampledLight { light: LightId(self.order[chosen]), pmf: (w[chosen] as f64 / total) as f32 })
        })
    }

    fn pmf(&self, ctx: &ShadingContext, light: LightId) -> f32 {
        let s = self.slot[light.0 as usize] as usize;
        let (k, lane) = (s / 4, s % 4);
        let w = self.packets[k].importance(ctx.p, ctx.n).to_array()[lane] as f64;
        if w <= 0.0 {
            return 0.0;
        }
        let total: f64 =
            self.packets.iter().flat_map(|p| p.importance(ctx.p, ctx.n).to_array()).map(|x| x as f64).sum();
        (w / total) as f32
    }
}
