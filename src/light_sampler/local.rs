//! `local`: a CDF over every light's importance at the shading point, the predecessor project's "weighted"
//! sampler (its `lights_pdf` and `lights_cdf`) and pbrt-v4's `ExhaustiveLightSampler`.
//!
//! O(n) per shading point, and again for the pmf MIS needs at an emitter hit: the ideal the
//! light tree approximates in O(log n). Importances are evaluated eight lights at a time
//! (`BoundsPacket`, AVX) into a per-thread scratch table (allocated once per thread), and the
//! light is the one whose interval ([`Split`]) holds `u`. Intervals in slot order keep the mapping
//! from `u` to lights monotone, so stratified `u` stay stratified over the lights (pbrt's
//! single-pass reservoir does not: its choice jumps around as `u` moves), and the slots are the
//! lights' [`SpatialOrder`], so that neighbouring `u` pick neighbouring lights in space, not
//! in file order (on `cornell-32x32`, direct light, 16 spp, 320 × 240: relMSE 0.0421 in file
//! order, 0.0414 in Morton order, tree 0.0415).

use std::cell::RefCell;

use super::order::SpatialOrder;
use super::{LightSampler, SampledLight, ShadingContext};
use crate::light::{BoundsPacket, LANES, Light, LightBounds, LightId};
use crate::math::distribution::{RANGE, Split, probability};

thread_local! {
    /// Importances of the current shading point, reused across calls.
    static SCRATCH: RefCell<Vec<f32>> = const { RefCell::new(Vec::new()) };
}

/// Importance-proportional selection over all lights.
#[derive(Clone, Debug)]
pub struct LocalSampler {
    /// Bounds in Morton order, four per packet.
    packets: Vec<BoundsPacket>,
    /// Slot (Morton position) ↔ light.
    order: SpatialOrder,
}

impl LocalSampler {
    /// A sampler over `lights`.
    pub fn new(lights: &[Light]) -> Self {
        let bounds: Vec<LightBounds> = lights.iter().map(Light::bounds).collect();
        let order = SpatialOrder::of(&bounds);
        Self { packets: order.arrange(&bounds).chunks(LANES).map(BoundsPacket::new).collect(), order }
    }

    /// Bytes of the light table and the per-thread scratch it keeps.
    pub fn memory_bytes(&self) -> usize {
        self.packets.capacity() * std::mem::size_of::<BoundsPacket>() + self.order.memory_bytes()
    }

    /// Number of lights.
    pub fn lights(&self) -> usize {
        self.order.len()
    }

    /// The light in slot (Morton position) `slot`.
    #[inline]
    pub fn light_at(&self, slot: usize) -> LightId {
        self.order.light_at(slot)
    }

    /// The slot (Morton position) of `light`.
    #[inline]
    pub fn slot_of(&self, light: LightId) -> usize {
        self.order.slot_of(light)
    }

    /// Fills `out` with every light's importance at `ctx`, in slot (Morton) order.
    pub fn importances(&self, ctx: &ShadingContext, out: &mut Vec<f32>) {
        out.clear();
        out.extend(self.packets.iter().flat_map(|p| p.importance(ctx.p, ctx.n).to_array()));
        out.truncate(self.order.len());
    }
}

impl LightSampler for LocalSampler {
    fn sample(&self, ctx: &ShadingContext, u: u64) -> Option<SampledLight> {
        SCRATCH.with_borrow_mut(|w| {
            self.importances(ctx, w);
            let mut split = Split::new(RANGE, w.iter().copied())?;
            let u = u as u128;
            w.iter().enumerate().find_map(|(slot, &x)| {
                let (start, end) = split.next(x);
                (u < end).then(|| SampledLight { light: self.order.light_at(slot), pmf: probability(end - start) })
            })
        })
    }

    fn interval(&self, ctx: &ShadingContext, light: LightId) -> (u128, u128) {
        let slot = self.order.slot_of(light);
        SCRATCH.with_borrow_mut(|w| {
            self.importances(ctx, w);
            let Some(mut split) = Split::new(RANGE, w.iter().copied()) else { return (0, 0) };
            for &x in &w[..slot] {
                split.next(x);
            }
            split.next(w[slot])
        })
    }
}
