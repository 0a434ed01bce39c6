//! Uniform light selection: pmf = 1/n, the predecessor project's "uniform" sampler.
//!
//! Light `i` owns the values `u` with ⌊u·n / 2⁶⁴⌋ = i, which is ⌈2⁶⁴/n⌉ or ⌊2⁶⁴/n⌋ of them:
//! its pmf is that count / 2⁶⁴, within 2⁻³³ of 1/n for any n the samplers take.

use super::{LightSampler, SampledLight, ShadingContext};
use crate::light::LightId;
use crate::math::distribution::{RANGE, even_cell, even_pick, probability};

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
    fn sample(&self, _ctx: &ShadingContext, u: u64) -> Option<SampledLight> {
        let i = even_pick(u as u128, self.n, RANGE);
        let (start, end) = even_cell(i, self.n, RANGE);
        Some(SampledLight { light: LightId(i), pmf: probability(end - start) })
    }

    #[inline]
    fn cell(&self, _ctx: &ShadingContext, light: LightId) -> (u128, u128) {
        debug_assert!(light.0 < self.n);
        even_cell(light.0, self.n, RANGE)
    }
}
