//! Uniform light selection: pmf = 1/n, the predecessor project's "uniform" sampler.
//!
//! The light in slot `i` of the lights' [`SpatialOrder`] owns the values `u` with
//! ⌊u·n / 2⁶⁴⌋ = i, which is ⌈2⁶⁴/n⌉ or ⌊2⁶⁴/n⌋ of them: its pmf is that count / 2⁶⁴, within
//! 2⁻³³ of 1/n for any n the samplers take. Slots in Morton order make a pixel's stratified
//! numbers pick lights spread over space rather than over the scene file's order.

use super::order::SpatialOrder;
use super::{LightSampler, SampledLight, ShadingContext};
use crate::light::{Light, LightId};
use crate::math::distribution::{RANGE, even_interval, even_pick, probability};

/// Picks each of `n` lights with probability 1/n.
#[derive(Clone, Debug)]
pub struct UniformSampler {
    order: SpatialOrder,
}

impl UniformSampler {
    /// A sampler over `lights` (1 to 2³² − 1 of them).
    pub fn new(lights: &[Light]) -> Self {
        assert!(!lights.is_empty() && lights.len() <= u32::MAX as usize, "uniform sampler needs 1..2^32 lights");
        Self { order: SpatialOrder::new(lights) }
    }

    /// Number of lights.
    #[inline]
    fn n(&self) -> u32 {
        self.order.len() as u32
    }

    /// Bytes of its light order.
    pub fn memory_bytes(&self) -> usize {
        self.order.memory_bytes()
    }
}

impl LightSampler for UniformSampler {
    #[inline]
    fn sample(&self, _ctx: &ShadingContext, u: u64) -> Option<SampledLight> {
        let i = even_pick(u as u128, self.n(), RANGE);
        let (start, end) = even_interval(i, self.n(), RANGE);
        Some(SampledLight { light: self.order.light_at(i as usize), pmf: probability(end - start) })
    }

    #[inline]
    fn interval(&self, _ctx: &ShadingContext, light: LightId) -> (u128, u128) {
        debug_assert!(light.0 < self.n());
        even_interval(self.order.slot_of(light) as u32, self.n(), RANGE)
    }
}
