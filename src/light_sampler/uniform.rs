//! Uniform light selection: pmf = 1/n, the seed's "uniform" sampler.

use super::{LightSampler, SampledLight, ShadingContext};
use crate::light::LightId;

/// Picks each of `n` lights with probability 1/n.
#[derive(Clone, Debug)]
pub struct UniformSampler {
    n: u32,
}

impl UniformSampler {
    /// A sampler over `n > 0` lights.
    pub fn new(n: usize) -> Self {
        assert!(n > 0 && n <= u32::MAX as usize, "uniform sampler needs 1..2^32 lights");
        Self { n: n as u32 }
    }
}

impl LightSampler for UniformSampler {
    #[inline]
    fn sample(&self, _ctx: &ShadingContext, u: f32) -> Option<SampledLight> {
        // f64: with 10⁶ lights an f32 product rounds to the wrong cell near cell edges.
        let i = ((u as f64 * self.n as f64) as u32).min(self.n - 1);
        Some(SampledLight { light: LightId(i), pmf: 1.0 / self.n as f32 })
    }

    #[inline]
    fn pmf(&self, _ctx: &ShadingContext, light: LightId) -> f32 {
        debug_assert!(light.0 < self.n);
        1.0 / self.n as f32
    }
}
