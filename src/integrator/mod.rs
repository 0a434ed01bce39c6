//! Light transport: unidirectional path tracing with next-event estimation and MIS.
//!
//! Owns: the per-path estimator ([`path::radiance`]), next-event estimation for one shading
//! point ([`direct::estimate_direct`]), and the counters both keep. Depends on scene, material,
//! light, light_sampler and sampling; knows nothing of pixels or threads.

pub mod direct;
pub mod path;

pub use path::FirstHit;

/// What one worker's paths report besides their radiance.
#[derive(Debug, Default)]
pub struct Tally {
    /// Rays traced.
    pub rays: RayCounters,
    /// What the light samples saw, kept when the light sampler learns from it.
    pub seen: Option<crate::light_sampler::Observations>,
}

/// Rays traced by one worker, summed at the end of a render (no atomics on the hot path).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounters {
    /// Closest-hit rays (camera and bounce rays).
    pub rays: u64,
    /// Occlusion (shadow) rays.
    pub shadow_rays: u64,
}

impl Tally {
    /// Adds another worker's tally (what its light samples saw merged into this one's).
    pub fn merge(mut self, other: Tally) -> Tally {
        self.rays.add(&other.rays);
        self.seen = match (self.seen, other.seen) {
            (Some(mut a), Some(b)) => {
                a.merge(b);
                Some(a)
            }
            (a, b) => a.or(b),
        };
        self
    }
}

impl RayCounters {
    /// Adds another worker's counts.
    pub fn add(&mut self, other: &RayCounters) {
        self.rays += other.rays;
        self.shadow_rays += other.shadow_rays;
    }

    /// All rays.
    pub fn total(&self) -> u64 {
        self.rays + self.shadow_rays
    }
}
