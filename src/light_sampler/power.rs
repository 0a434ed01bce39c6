//! Power-proportional light selection: one CDF over emitted power, the same at every point.
//! A light's power here is its flux's brightest channel, the scalar the tree's bounds weigh
//! lights by: with luminance, the blue of three pure-colour panels (panels.glb) got 7 % of
//! the choices and relMSE per sample was 0.00264 against uniform's 0.00218; by the brightest
//! channel 0.00212 (64 spp, 48 seeds, 160×120, against a 4096-spp render).
//!
//! Lights whose power estimate is 0 would never be chosen, which biases the image whenever
//! the estimate is wrong (pbrt drops them). Every light here gets at least a floor of 1e-6
//! of the mean power, so nothing that can contribute has pmf 0 (and `Distribution1D` gives
//! every positive weight at least one of the 2⁶⁴ values, however many lights there are).
//! The CDF runs over the lights in their [`SpatialOrder`], as `uniform` chooses.

use super::order::SpatialOrder;
use super::{LightSampler, SampledLight, ShadingContext};
use crate::light::{Light, LightId};
use crate::math::distribution::Distribution1D;

/// Picks lights with probability proportional to their power.
#[derive(Clone, Debug)]
pub struct PowerSampler {
    /// Over the lights' slots.
    distribution: Distribution1D,
    order: SpatialOrder,
}

impl PowerSampler {
    /// A sampler over `lights` (non-empty); `scene_radius` sizes directional lights.
    pub fn new(lights: &[Light], scene_radius: f32) -> Self {
        let powers: Vec<f32> = lights.iter().map(|l| l.flux(scene_radius).max_element().max(0.0)).collect();
        let mean = powers.iter().map(|&p| p as f64).sum::<f64>() / powers.len().max(1) as f64;
        let floor = if mean > 0.0 { (mean * 1e-6) as f32 } else { 1.0 };
        let weights: Vec<f32> = powers.into_iter().map(|p| p.max(floor)).collect();
        let order = SpatialOrder::new(lights);
        let distribution = Distribution1D::new(&order.arrange(&weights))
            .expect("every weight is at least the floor, which is positive");
        Self { distribution, order }
    }

    /// Bytes of the CDF and the light order.
    pub fn memory_bytes(&self) -> usize {
        self.distribution.memory_bytes() + self.order.memory_bytes()
    }
}

impl LightSampler for PowerSampler {
    #[inline]
    fn sample(&self, _ctx: &ShadingContext, u: u64) -> Option<SampledLight> {
        let s = self.distribution.sample(u);
        Some(SampledLight { light: self.order.light_at(s.index), pmf: s.pmf })
    }

    #[inline]
    fn interval(&self, _ctx: &ShadingContext, light: LightId) -> (u128, u128) {
        self.distribution.interval(self.order.slot_of(light))
    }
}
