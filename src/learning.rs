//! What a render learns from its own paths: the one hook between the render loop and every
//! method that learns (the `learned` light sampler and path guiding).
//!
//! Owns: [`Seen`], what one worker's paths record during a pass (merged across workers by
//! integer addition, so any grouping gives the same bits), and [`Learning`], the state a
//! render learns into and its schedule: a pass starting below [`LEARN_UNTIL`] records, ends
//! at the next power of two of spp, and the state learns there from everything recorded
//! since. What is learned is therefore a function of the samples alone, not of the thread
//! count or how passes split them; a render of a sample range `a..b` needs the state at `a`,
//! which [`Learning`]'s owner makes by rendering samples `0..min(a, until)` first. The light
//! sampler learns up to [`LEARN_UNTIL`] spp, path guiding up to [`GUIDE_UNTIL`]. The last
//! pass of a fixed budget records nothing: what it would teach, nothing would use.
//!
//! The integrator writes into a [`Seen`] through its `record_*` methods; the render loop
//! asks [`Learning`] how long a pass may be, hands it each pass's [`Seen`], and renders
//! with [`Learning::strategy`] and [`Learning::guide`]. Nothing else in the core knows what
//! is learned.

use std::sync::Arc;

use crate::guiding::GUIDE_UNTIL;
use crate::guiding::{Guide, GuideStats, Guiding, Records};
use crate::light::LightId;
use crate::light_sampler::{LearnedStats, LightStrategy, Observations, ShadingContext};
use crate::math::Vec3A;

pub use crate::light_sampler::LEARN_UNTIL;

/// What one worker's paths saw during a pass, for every method that learns; empty (and
/// free) when nothing learns.
#[derive(Debug, Default)]
pub struct Seen {
    /// Light samples at shading points, for a light sampler that learns.
    light: Option<Observations>,
    /// The light paths brought back through their vertices, for path guiding (shared by a
    /// pass's workers, each thread adding to its own sums).
    guide: Option<Arc<Records>>,
}

impl Seen {
    /// An empty record of the same kinds: what each worker of a pass starts from.
    pub fn empty_like(&self) -> Seen {
        Seen { light: self.light.as_ref().map(|_| Observations::default()), guide: self.guide.clone() }
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
        self.guide = self.guide.or(other.guide);
        self
    }

    /// Where path guiding's records go, when it learns.
    #[inline]
    pub fn guide_records(&self) -> Option<&Records> {
        self.guide.as_deref()
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
    /// The light strategy as learned so far (a fresh copy of the one the render was given),
    /// when its light sampler learns.
    strategy: Option<LightStrategy>,
    /// Path guiding, when the render guides.
    guiding: Option<Guiding>,
    /// What passes since the last learning saw.
    pending: Seen,
    /// Where the last learning was (samples per pixel).
    learned_at: u32,
}

impl Learning {
    /// Learning for a render with `strategy`, guided (`guide`: the scene's bounding sphere)
    /// or not: `None` when nothing in it learns (the render then uses `strategy` as it is).
    pub fn new(strategy: &LightStrategy, guide: Option<(Vec3A, f32)>) -> Option<Self> {
        let strategy = strategy.fresh_learner();
        let guiding = guide.map(|(center, radius)| Guiding::new(center, radius));
        (strategy.is_some() || guiding.is_some()).then(|| Self {
            strategy,
            guiding,
            pending: Seen::default(),
            learned_at: 0,
        })
    }

    /// The light strategy to render with now, when it learns.
    pub fn strategy(&self) -> Option<&LightStrategy> {
        self.strategy.as_ref()
    }

    /// The guide to render with now, when the render guides.
    pub fn guide(&self) -> Option<&Guide> {
        self.guiding.as_ref().map(Guiding::guide)
    }

    /// The samples per pixel after which nothing more is learned: a render of samples
    /// `a..b` needs the state at `min(a, until)`.
    pub fn until(&self) -> u32 {
        let light = if self.strategy.is_some() { LEARN_UNTIL } else { 0 };
        let guide = if self.guiding.is_some() { GUIDE_UNTIL } else { 0 };
        light.max(guide)
    }

    /// For a pass starting at sample `first`: the most samples it may take and what its
    /// paths record into, when it must record (it then ends at the next power of two, where
    /// the state learns); `None` once learning is over.
    pub fn recording(&self, first: u32) -> Option<(u32, Seen)> {
        (first < self.until()).then(|| {
            let limit = (first + 1).next_power_of_two() - first;
            let seen = Seen {
                light: self.strategy.as_ref().filter(|_| first < LEARN_UNTIL).map(|_| Observations::default()),
                guide: self.guiding.as_ref().filter(|_| first < GUIDE_UNTIL).map(Guiding::records),
            };
            (limit, seen)
        })
    }

    /// Takes what a pass ending at sample `end` recorded; learns from everything since the
    /// last time when `end` is a power of two within [`until`](Self::until).
    pub fn after_pass(&mut self, seen: Seen, end: u32) {
        self.pending = std::mem::take(&mut self.pending).merge(seen);
        if end.is_power_of_two() && end <= self.until() {
            let Seen { light, guide: _ } = std::mem::take(&mut self.pending);
            if let (Some(strategy), Some(light)) = (self.strategy.as_mut(), light) {
                strategy.learn(light);
            }
            if let Some(g) = self.guiding.as_mut().filter(|_| end <= GUIDE_UNTIL) {
                g.learn(end - self.learned_at);
            }
            self.learned_at = end;
        }
    }

    /// The samples per pixel the state last learned at (0: not yet).
    pub fn learned_at(&self) -> u32 {
        self.learned_at
    }

    /// What the light sampler has learned so far.
    pub fn light_stats(&self) -> Option<LearnedStats> {
        self.strategy.as_ref()?.learner().map(|l| l.stats())
    }

    /// What path guiding has learned so far.
    pub fn guide_stats(&self) -> Option<GuideStats> {
        self.guiding.as_ref().map(Guiding::stats)
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
        assert!(Learning::new(&strategy(LightSamplerKind::Tree), None).is_none());
        assert!(Learning::new(&strategy(LightSamplerKind::Tree), Some((Vec3A::ZERO, 1.0))).is_some());
        let learning = Learning::new(&strategy(LightSamplerKind::Learned), None).expect("learned learns");
        let limits: Vec<u32> = [0, 1, 2, 3, 5, 8, 15].iter().map(|&f| learning.recording(f).unwrap().0).collect();
        assert_eq!(limits, [1, 1, 2, 1, 3, 8, 1]);
        assert!(learning.recording(LEARN_UNTIL).is_none());
    }
}
