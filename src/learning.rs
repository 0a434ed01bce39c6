//! What a render learns from its own paths: the one hook between the render loop and every
//! method that learns (today the `learned` light sampler; path guiding plugs in here too).
//!
//! Owns: [`Seen`], what one worker's paths record during a pass (merged across workers by
//! integer addition, so any grouping gives the same bits), and [`Learning`], the state a
//! render learns into and its schedule: a pass starting below [`LEARN_UNTIL`] records, ends
//! at the next power of two of spp, and the state learns there from everything recorded
//! since. What is learned is therefore a function of the samples alone, not of the thread
//! count or how passes split them; a render of a sample range `a..b` needs the state at `a`,
//! which [`Learning`]'s owner makes by rendering samples `0..min(a, LEARN_UNTIL)` first.
//!
//! The integrator writes into a [`Seen`] through its `record_*` methods; the render loop
//! asks [`Learning`] how long a pass may be, hands it each pass's [`Seen`], and renders
//! with [`Learning::strategy`]. Nothing else in the core knows what is learned.

use crate::light::LightId;
use crate::light_sampler::{LearnedStats, LightStrategy, Observations, ShadingContext};

pub use crate::light_sampler::LEARN_UNTIL;

/// What one worker's paths saw during a pass, for every method that learns; empty (and
/// free) when nothing learns.
#[derive(Debug, Default)]
pub struct Seen {
    /// Light samples at shading points, for a light sampler that learns.
    light: Option<Observations>,
}

impl Seen {
    /// An empty record of the same kinds: what each worker of a pass starts from.
    pub fn empty_like(&self) -> Seen {
        Seen { light: self.light.as_ref().map(|_| Observations::default()) }
    }

    /// Adds another worker's records.
    pub fn merge(mut self, other: Seen) -> Seen {
        self.light = match (self.light, other.light) {
            (Some(mut a), Some(b)) => {
                a.merge(b);
                Some(a)
            }
            (a, b) => a.or(b),
        };
        self
    }

    /// Records one light sample at `ctx` of `strategy`'s sampler: the luminance `c` of its
    /// unshadowed, unweighted contribution and whether its shadow ray got through. Nothing
    /// when no light sampler learns.
    #[inline]
    pub fn record_light_sample(
        &mut self,
        strategy: &LightStrategy,
        ctx: &ShadingContext,
        light: LightId,
        c: f32,
        visible: bool,
    ) {
        if let (Some(seen), Some(learner)) = (self.light.as_mut(), strategy.learner()) {
            learner.observe(seen, ctx, light, c, visible);
        }
    }
}

/// The state a render learns into, and when it learns.
#[derive(Debug)]
pub struct Learning {
    /// The light strategy as learned so far (a fresh copy of the one the render was given).
    strategy: LightStrategy,
    /// What passes since the last learning saw.
    pending: Seen,
}

impl Learning {
    /// Learning for a render with `strategy`: `None` when nothing in it learns (the render
    /// then uses `strategy` as it is).
    pub fn new(strategy: &LightStrategy) -> Option<Self> {
        let strategy = strategy.fresh_learner()?;
        Some(Self { strategy, pending: Seen::default() })
    }

    /// The light strategy to render with now.
    pub fn strategy(&self) -> &LightStrategy {
        &self.strategy
    }

    /// For a pass starting at sample `first`: the most samples it may take and what its
    /// paths record into, when it must record (it then ends at the next power of two, where
    /// the state learns); `None` once learning is over.
    pub fn recording(&self, first: u32) -> Option<(u32, Seen)> {
        (first < LEARN_UNTIL).then(|| {
            let limit = (first + 1).next_power_of_two() - first;
            (limit, Seen { light: Some(Observations::default()) })
        })
    }

    /// Takes what a pass ending at sample `end` recorded; learns from everything since the
    /// last time when `end` is a power of two within [`LEARN_UNTIL`].
    pub fn after_pass(&mut self, seen: Seen, end: u32) {
        self.pending = std::mem::take(&mut self.pending).merge(seen);
        if end.is_power_of_two() && end <= LEARN_UNTIL {
            let Seen { light } = std::mem::take(&mut self.pending);
            if let Some(light) = light {
                self.strategy.learn(light);
            }
        }
    }

    /// What the light sampler has learned so far.
    pub fn light_stats(&self) -> Option<LearnedStats> {
        self.strategy.learner().map(|l| l.stats())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{Light, PointLight};
    use crate::math::{Rgb, Vec3A};
    use crate::settings::LightSamplerKind;

    fn strategy(kind: LightSamplerKind) -> LightStrategy {
        let lights: Vec<Light> = (0..20)
            .map(|i| Light::Point(PointLight { position: Vec3A::new(i as f32, 2.0, 0.0), intensity: Rgb::ONE }))
            .collect();
        LightStrategy::build(kind, &lights, Vec3A::ZERO, 20.0)
    }

    #[test]
    fn only_a_strategy_that_learns_gets_learning_and_passes_end_at_powers_of_two() {
        assert!(Learning::new(&strategy(LightSamplerKind::Tree)).is_none());
        let learning = Learning::new(&strategy(LightSamplerKind::Learned)).expect("learned learns");
        let limits: Vec<u32> = [0, 1, 2, 3, 5, 8, 15].iter().map(|&f| learning.recording(f).unwrap().0).collect();
        assert_eq!(limits, [1, 1, 2, 1, 3, 8, 1]);
        assert!(learning.recording(LEARN_UNTIL).is_none());
    }
}
