//! Light transport: unidirectional path tracing with next-event estimation and MIS.
//!
//! Owns: the per-path estimator ([`path::radiance`]), next-event estimation for one shading
//! point ([`direct::estimate_direct`]), and the counters both keep (with [`timing`], where a
//! sample of the paths spends its time). Depends on scene, material,
//! light, light_sampler, learning (what the paths record for whatever learns from them) and
//! sampling; knows nothing of threads, and of pixels only the one the camera projects a light
//! path's last vertex to ([`light_paths`]).

pub mod direct;
pub mod guided;
pub mod light_paths;
pub mod mnee;
pub mod path;
pub mod surface;
pub mod timing;

pub use path::{FirstHit, Tracer};

use crate::learning::Seen;
use crate::math::Rgb;

/// What a path keeps of its light over `distance` in a volume of absorption `sigma`
/// (Beer–Lambert): the glass a path travels through, for its segments and its light samples.
#[inline]
pub fn transmittance(sigma: Rgb, distance: f32) -> Rgb {
    let d = -sigma * distance;
    Rgb::new(d.x.exp(), d.y.exp(), d.z.exp())
}

/// What one worker's paths report besides their radiance.
#[derive(Debug, Default)]
pub struct Tally {
    /// Rays traced.
    pub rays: RayCounters,
    /// What the paths saw, for whatever learns from it (empty when nothing does).
    pub seen: Seen,
    /// The path under way's vertices, while path guiding learns (scratch, not merged).
    pub trail: guided::Trail,
}

/// Rays traced by one worker and where the timed paths spent their time, summed at the end
/// of a render (no atomics on the hot path).
#[derive(Clone, Copy, Debug, Default)]
pub struct RayCounters {
    /// Closest-hit rays (camera and bounce rays).
    pub rays: u64,
    /// Occlusion (shadow) rays.
    pub shadow_rays: u64,
    /// Light samples behind smooth glass for which a connection through it was tried
    /// ([`mnee`]).
    pub glass_tried: u64,
    /// Those of them it brought light along.
    pub glass_solved: u64,
    /// Light paths traced ([`light_paths`]).
    pub light_paths: u64,
    /// Those of them that brought light to the image.
    pub splats: u64,
    /// Ticks per phase of the timed paths.
    pub time: timing::PhaseTimes,
    /// Whether the path being traced is timed ([`timing::is_timed`]).
    pub timing: bool,
}

impl Tally {
    /// Adds another worker's tally (what its paths saw merged into this one's).
    pub fn merge(mut self, other: Tally) -> Tally {
        self.rays.add(&other.rays);
        self.seen = self.seen.merge(other.seen);
        self
    }
}

impl RayCounters {
    /// Adds another worker's counts.
    pub fn add(&mut self, other: &RayCounters) {
        self.rays += other.rays;
        self.shadow_rays += other.shadow_rays;
        self.glass_tried += other.glass_tried;
        self.glass_solved += other.glass_solved;
        self.light_paths += other.light_paths;
        self.splats += other.splats;
        self.time.add(&other.time);
    }

    /// All rays.
    pub fn total(&self) -> u64 {
        self.rays + self.shadow_rays
    }
}
