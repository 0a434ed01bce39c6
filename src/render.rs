//! Rendering an image: pixels over rayon, samples per pixel, timing and statistics.
//!
//! Owns: [`RenderSettings`], [`render`] and [`RenderOutput`]. The film is cut into bands of
//! rows; rayon's work stealing balances them. Sample `s` of pixel `p` always uses
//! `SampleStream::new(seed, p, s)`, and a pixel's samples are added in index order, so the
//! image is bit-identical whatever the thread count, and a render of samples `a..b` merges
//! exactly with one of `b..c`. An equal-time render runs passes until its budget is spent.

use std::time::{Duration, Instant};

use indicatif::ProgressBar;
use rayon::prelude::*;

use crate::film::{AovSet, Film};
use crate::integrator::{RayCounters, path};
use crate::light_sampler::LightStrategy;
use crate::math::UVec2;
use crate::sampling::{Dim, SampleStream};
use crate::scene::Scene;

/// Rows per work item: small enough to balance 2–64 threads on a 240-row image.
const ROWS_PER_BAND: u32 = 2;

/// How long to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Exactly this many samples per pixel.
    Spp(u32),
    /// Whole passes over the image until this much time is spent (at least one sample).
    Time(Duration),
}

/// What to render and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Samples per pixel or time.
    pub budget: Budget,
    /// Seed of every random number.
    pub seed: u64,
    /// Maximum scattering events (1 = direct lighting only).
    pub max_depth: u32,
    /// Extra images to keep.
    pub aovs: AovSet,
}

/// Counts and timings of a render.
#[derive(Clone, Copy, Debug, Default)]
pub struct RenderStats {
    /// Wall time of the sampling loop (scene loading and builds excluded).
    pub elapsed: Duration,
    /// Samples per pixel rendered.
    pub spp: u32,
    /// Camera samples (pixels × spp).
    pub samples: u64,
    /// Rays traced.
    pub rays: RayCounters,
    /// Samples whose value was not finite and were counted as black (a bug if ever > 0).
    pub non_finite_samples: u64,
}

impl RenderStats {
    /// Camera samples per second.
    pub fn samples_per_second(&self) -> f64 {
        self.samples as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }

    /// Rays (closest-hit and shadow) per second.
    pub fn rays_per_second(&self) -> f64 {
        self.rays.total() as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// The result of a render.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The accumulated samples.
    pub film: Film,
    /// Counts and timings.
    pub stats: RenderStats,
}

/// Adds samples `first..first+count` of every pixel to `film`.
fn render_pass(
    scene: &Scene,
    strategy: &LightStrategy,
    settings: &RenderSettings,
    film: &mut Film,
    first: u32,
    count: u32,
    progress: Option<&ProgressBar>,
) -> (RayCounters, u64) {
    let size = scene.camera.resolution();
    let bands: Vec<_> = film.bands_mut(ROWS_PER_BAND).collect();
    let results: Vec<(RayCounters, u64)> = bands
        .into_par_iter()
        .map(|(row0, pixels, mut aovs)| {
            let mut counters = RayCounters::default();
            let mut bad = 0u64;
            for (k, px) in pixels.iter_mut().enumerate() {
                let index = row0 as usize * size.x as usize + k;
                let pixel = UVec2::new(index as u32 % size.x, index as u32 / size.x);
                for s in first..first + count {
                    let stream = SampleStream::new(settings.seed, index as u64, s as u64);
                    let ray = scene.camera.ray(pixel, stream.get_2d(0, Dim::PixelJitter, 0));
                    let smp = path::radiance(scene, strategy, ray, &stream, settings.max_depth, &mut counters);
                    if smp.radiance.is_finite() {
                        px.add(smp.radiance);
                    } else {
                        bad += 1;
                        px.add(crate::math::Rgb::ZERO);
                    }
                    if let Some(a) = aovs.as_deref_mut() {
                        a[k].add(smp.first_hit);
                    }
                }
            }
            if let Some(pb) = progress {
                pb.inc(pixels.len() as u64 * count as u64);
            }
            (counters, bad)
        })
        .collect();
    film.add_spp(count);
    results.iter().fold((RayCounters::default(), 0), |(mut c, b), (rc, rb)| {
        c.add(rc);
        (c, b + rb)
    })
}

/// Renders `scene` with `strategy` in the current rayon pool. `progress` (if any) advances by
/// one per camera sample; its length is set for `Budget::Spp`. `on_pass` sees the film after
/// every pass: at 1, 2, 4, … spp for a fixed-spp render, every ~1/20 of the budget for an
/// equal-time one.
pub fn render(
    scene: &Scene,
    strategy: &LightStrategy,
    settings: &RenderSettings,
    progress: Option<&ProgressBar>,
    on_pass: &mut dyn FnMut(&Film, Duration),
) -> RenderOutput {
    let size = scene.camera.resolution();
    let pixels = size.x as u64 * size.y as u64;
    let mut film = Film::new(size, settings.aovs.wants_first_hit());
    let mut stats = RenderStats::default();
    let start = Instant::now();
    let run = |film: &mut Film, first: u32, count: u32, stats: &mut RenderStats, pb: Option<&ProgressBar>| {
        let (c, bad) = render_pass(scene, strategy, settings, film, first, count, pb);
        stats.rays.add(&c);
        stats.non_finite_samples += bad;
    };
    match settings.budget {
        Budget::Spp(n) => {
            if let Some(pb) = progress {
                pb.set_length(pixels * n as u64);
            }
            // Passes of 1, 1, 2, 4, … samples: `on_pass` sees the image at every power of two
            // (convergence plots), and the sums equal one pass over 0..n bit for bit.
            while film.spp() < n {
                let first = film.spp();
                let count = first.max(1).min(n - first);
                run(&mut film, first, count, &mut stats, progress);
                on_pass(&film, start.elapsed());
            }
        }
        Budget::Time(limit) => {
            if let Some(pb) = progress {
                pb.set_length(limit.as_millis() as u64);
            }
            let mut per_spp = Duration::ZERO;
            loop {
                let elapsed = start.elapsed();
                let left = limit.saturating_sub(elapsed);
                // Passes of ~1/20 of the budget; stop when the next would overshoot by more
                // than half a pass.
                let count = if film.spp() == 0 {
                    1
                } else {
                    let fits = left.as_secs_f64() / per_spp.as_secs_f64().max(1e-9);
                    let chunk = (limit.as_secs_f64() / 20.0 / per_spp.as_secs_f64().max(1e-9)).max(1.0);
                    if fits < 0.5 {
                        break;
                    }
                    fits.min(chunk).round().max(1.0) as u32
                };
                let t0 = Instant::now();
                let first = film.spp();
                run(&mut film, first, count, &mut stats, None);
                per_spp = t0.elapsed() / count;
                on_pass(&film, start.elapsed());
                if let Some(pb) = progress {
                    pb.set_position(start.elapsed().as_millis().min(limit.as_millis()) as u64);
                }
            }
        }
    }
    stats.elapsed = start.elapsed();
    stats.spp = film.spp();
    stats.samples = pixels * film.spp() as u64;
    RenderOutput { film, stats }
}
