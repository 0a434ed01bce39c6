//! Rendering an image: pixels over rayon, samples per pixel, timing and statistics.
//!
//! Owns: [`RenderSettings`], [`render`], [`RenderOutput`] and the [`RenderObserver`] that
//! watches a render (progress displays, convergence plots; no UI crate here). The film is
//! cut into bands of rows; rayon's work stealing balances them. Sample `s` of pixel `p`
//! always uses `SampleStream::new(seed, p, s)` (as `PixelStreams::new(seed, p).sample(s)`),
//! and a pixel's samples are added in index order, so the image is bit-identical whatever
//! the thread count, and a render of samples `a..b` merges exactly with one of `b..c`. An
//! equal-time render runs passes until its budget is spent.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::film::{AovSet, Film};
use crate::guiding::{Guide, GuideStats};
use crate::integrator::light_paths::LightPaths;
use crate::integrator::{RayCounters, Tally, path, timing};
use crate::interrupt::{self, Stop};
use crate::learning::{Learning, Seen};
use crate::light_sampler::{LearnedStats, LightStrategy};
use crate::math::UVec2;
use crate::sampling::{Dim, PixelStreams};
use crate::scene::Scene;
use crate::settings::Clamp;

/// Rows per work item: small enough to balance 2–64 threads on a 240-row image.
const ROWS_PER_BAND: u32 = 2;

/// Light paths' splats a worker keeps before it adds them to the film (bounds its memory).
const SPLAT_BATCH: usize = 4096;

/// Longest a fixed-spp pass should take, so that a Ctrl-C (which lets the pass under way
/// finish) is answered soon.
const MAX_PASS: Duration = Duration::from_secs(1);

/// How long to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Exactly this many samples per pixel: samples `0..n`.
    Spp(u32),
    /// Samples `first..end` of every pixel (`first < end`), the very samples a render of
    /// `end` spp takes there: a part of a render split into sample ranges.
    Samples(u32, u32),
    /// Whole passes over the image until this much time is spent (at least one sample).
    Time(Duration),
}

impl Budget {
    /// The first sample index and the samples per pixel of a fixed budget.
    pub fn fixed(&self) -> Option<(u32, u32)> {
        match *self {
            Budget::Spp(n) => Some((0, n)),
            Budget::Samples(a, b) => Some((a, b.saturating_sub(a))),
            Budget::Time(_) => None,
        }
    }
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
    /// Sample clamping (off: the unbiased picture).
    pub clamp: Clamp,
    /// Whether paths are guided by what earlier passes learned ([`crate::guiding`]).
    pub guiding: bool,
    /// Whether caustics are solved for where the scene has any: light through smooth glass
    /// ([`crate::integrator::mnee`]) and point and spot lights' highlights off glossy
    /// surfaces ([`crate::integrator::light_paths`]).
    pub caustics: bool,
    /// Image size in pixels (the camera keeps its vertical field of view at any size).
    pub resolution: UVec2,
    /// Extra images to keep.
    pub aovs: AovSet,
}

/// Whoever watches a render: a progress display, a convergence plot, a viewer. Work is
/// counted in camera samples for a fixed spp and in milliseconds for a time budget.
pub trait RenderObserver: Sync {
    /// The render begins and will report `total` units of work.
    fn start(&self, _total: u64) {}
    /// `n` more units are done; called from the worker threads as bands finish.
    fn advance(&self, _n: u64) {}
    /// A pass has finished: `film` holds every sample so far, `elapsed` since the start.
    fn pass(&mut self, _film: &Film, _elapsed: Duration) {}
}

/// Nobody watches.
impl RenderObserver for () {}

/// An observer that only wants the film after each pass: `OnPass(|film, elapsed| ...)`.
pub struct OnPass<F>(pub F);

impl<F: FnMut(&Film, Duration) + Sync> RenderObserver for OnPass<F> {
    fn pass(&mut self, film: &Film, elapsed: Duration) {
        (self.0)(film, elapsed)
    }
}

/// Two watchers of one render (a progress display and a viewer, say).
impl<A: RenderObserver, B: RenderObserver> RenderObserver for (A, B) {
    fn start(&self, total: u64) {
        self.0.start(total);
        self.1.start(total);
    }
    fn advance(&self, n: u64) {
        self.0.advance(n);
        self.1.advance(n);
    }
    fn pass(&mut self, film: &Film, elapsed: Duration) {
        self.0.pass(film, elapsed);
        self.1.pass(film, elapsed);
    }
}

/// A watcher lent for one render.
impl<A: RenderObserver + ?Sized> RenderObserver for &mut A {
    fn start(&self, total: u64) {
        (**self).start(total);
    }
    fn advance(&self, n: u64) {
        (**self).advance(n);
    }
    fn pass(&mut self, film: &Film, elapsed: Duration) {
        (**self).pass(film, elapsed);
    }
}

/// A watcher that may not be there.
impl<A: RenderObserver> RenderObserver for Option<A> {
    fn start(&self, total: u64) {
        if let Some(a) = self {
            a.start(total);
        }
    }
    fn advance(&self, n: u64) {
        if let Some(a) = self {
            a.advance(n);
        }
    }
    fn pass(&mut self, film: &Film, elapsed: Duration) {
        if let Some(a) = self {
            a.pass(film, elapsed);
        }
    }
}

/// Counts and timings of a render.
#[derive(Clone, Copy, Debug)]
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
    /// What a learning light sampler learned (its memory, the time learning took).
    pub learned: Option<LearnedStats>,
    /// What path guiding learned (its memory, the time learning took).
    pub guide: Option<GuideStats>,
    /// The samples per pixel the render last learned at (light sampler or guiding; 0 when
    /// nothing learned).
    pub learned_at: u32,
    /// Whether the user stopped the render ([`Stop::AfterPass`]: the film holds the passes
    /// finished; [`Stop::Now`]: it is incomplete and must not be written).
    pub stopped: Stop,
    /// The point and spot lights light paths started from (0: no light paths traced).
    pub light_path_lights: usize,
}

impl Default for RenderStats {
    fn default() -> Self {
        Self {
            elapsed: Duration::ZERO,
            spp: 0,
            samples: 0,
            rays: RayCounters::default(),
            non_finite_samples: 0,
            learned: None,
            guide: None,
            learned_at: 0,
            stopped: Stop::No,
            light_path_lights: 0,
        }
    }
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

/// One pass: samples `first..first + count` of every pixel, rendered with `strategy`.
struct Pass<'a> {
    scene: &'a Scene,
    strategy: &'a LightStrategy,
    guide: Option<&'a Guide>,
    light_paths: Option<&'a LightPaths>,
    settings: &'a RenderSettings,
    first: u32,
    count: u32,
}

/// Who hears of a pass under way: `progress` as bands finish; setting `cancel` calls the
/// pass off at the next pixel (the film is then incomplete).
#[derive(Clone, Copy, Default)]
struct Watch<'a> {
    progress: Option<&'a dyn RenderObserver>,
    cancel: Option<&'a AtomicBool>,
}

/// What one pass reports besides the samples it adds to the film.
struct PassTally {
    /// Whether the pass was called off half-way (its samples are then incomplete).
    cancelled: bool,
    rays: RayCounters,
    non_finite: u64,
    /// What its paths saw, for whatever learns.
    seen: Seen,
}

/// Adds `pass`'s samples to `film`; its paths record into copies of `recording` (one per
/// worker, merged), empty when nothing learns.
fn render_pass(pass: &Pass, film: &mut Film, recording: &Seen, watch: Watch) -> PassTally {
    let called_off = || watch.cancel.is_some_and(|c| c.load(Ordering::Relaxed));
    let Pass { scene, strategy, guide, light_paths, settings, first, count } = *pass;
    let caustics = scene.caustics && settings.caustics;
    let (max_depth, clamp) = (settings.max_depth, settings.clamp);
    let first_hits = film.has_first_hit();
    let tracer = path::Tracer { scene, strategy, guide, max_depth, clamp, caustics, light_paths, first_hits };
    let size = settings.resolution;
    let (bands, splat_sums) = film.bands_mut(ROWS_PER_BAND);
    let bands: Vec<_> = bands.collect();
    // Each worker sums its bands' counts and records; every sum is of integers, so the
    // totals do not depend on how rayon splits the bands.
    let empty = || (Tally { seen: recording.empty_like(), ..Tally::default() }, 0u64, Vec::new());
    let (tally, bad, mut splats) = bands
        .into_par_iter()
        .fold(empty, |(mut tally, mut bad, mut splats), (row0, pixels, mut aovs)| {
            if interrupt::requested() == Stop::Now {
                return (tally, bad, splats);
            }
            for (k, px) in pixels.iter_mut().enumerate() {
                if called_off() {
                    break;
                }
                let index = row0 as usize * size.x as usize + k;
                let pixel = UVec2::new(index as u32 % size.x, index as u32 / size.x);
                let streams = PixelStreams::new(settings.seed, index as u64);
                for s in first..first + count {
                    let stream = streams.sample(s as u64);
                    let jitter = stream.get_2d(0, Dim::PixelJitter, 0);
                    let ray = if scene.camera.has_lens() {
                        scene.camera.ray_through_lens(pixel, size, jitter, stream.get_2d(0, Dim::Lens, 0))
                    } else {
                        scene.camera.ray(pixel, size, jitter)
                    };
                    let timing = timing::is_timed(index as u64, s as u64);
                    tally.rays.timing = timing;
                    let start = if timing { timing::ticks() } else { 0 };
                    let smp = tracer.radiance(ray, &stream, &mut tally);
                    if timing {
                        tally.rays.time.total += timing::ticks().wrapping_sub(start);
                    }
                    if smp.radiance.is_finite() {
                        px.add(smp.radiance);
                    } else {
                        bad += 1;
                        px.add(crate::math::Rgb::ZERO);
                    }
                    if let Some(a) = aovs.as_deref_mut() {
                        a[k].add(smp.first_hit);
                    }
                    if let (Some(paths), Some(sums)) = (light_paths, &splat_sums) {
                        splats.extend(paths.trace(scene, &stream, &mut tally.rays));
                        if splats.len() >= SPLAT_BATCH {
                            sums.add(&mut splats);
                        }
                    }
                }
            }
            if let Some(observer) = watch.progress {
                observer.advance(pixels.len() as u64 * count as u64);
            }
            (tally, bad, splats)
        })
        .reduce(empty, |(a, bad_a, mut splats_a), (b, bad_b, splats_b)| {
            splats_a.extend(splats_b);
            (a.merge(b), bad_a + bad_b, splats_a)
        });
    if let Some(sums) = splat_sums {
        sums.add(&mut splats);
    }
    film.add_spp(count);
    PassTally { cancelled: called_off(), rays: tally.rays, non_finite: bad, seen: tally.seen }
}

/// The size of the next pass, or `None` when the budget is spent. `done` samples per pixel
/// are rendered, the last pass took `per_spp` per sample (unknown before the first), and
/// `elapsed` has passed since the render began.
///
/// A fixed-spp render reaches every power of two (convergence plots see the image there),
/// in passes of at most [`MAX_PASS`]; an equal-time one runs passes of about 1/20 of its
/// budget and stops when the next would overshoot by more than half a pass.
fn next_pass(budget: Budget, done: u32, per_spp: Option<Duration>, elapsed: Duration) -> Option<u32> {
    let budget = match budget.fixed() {
        Some((_, n)) => Budget::Spp(n),
        None => budget,
    };
    let Some(per_spp) = per_spp.filter(|_| done > 0) else { return (budget != Budget::Spp(0)).then_some(1) };
    let per_spp = per_spp.as_secs_f64().max(1e-9);
    match budget {
        Budget::Spp(n) if done >= n => None,
        Budget::Spp(n) => {
            let boundary = (done as u64 + 1).next_power_of_two().min(n as u64) as u32;
            let cap = (MAX_PASS.as_secs_f64() / per_spp).max(1.0);
            Some((boundary - done).min(cap as u32).max(1))
        }
        Budget::Time(limit) => {
            let fits = limit.saturating_sub(elapsed).as_secs_f64() / per_spp;
            let chunk = (limit.as_secs_f64() / 20.0 / per_spp).max(1.0);
            (fits >= 0.5).then(|| fits.min(chunk).round().clamp(1.0, (u32::MAX - done) as f64) as u32)
        }
        Budget::Samples(..) => unreachable!("made a Spp budget above"),
    }
}

/// Whether a render of `settings` traces light paths where the scene has something for them
/// ([`LightPaths`]): with the caustics switch, and where the path tracer's densities are the
/// ones they weigh themselves against (no guiding, no clamping, two scattering events).
fn traces_light_paths(settings: &RenderSettings) -> bool {
    settings.caustics && !settings.guiding && !settings.clamp.is_on() && settings.max_depth >= 2
}

/// Renders samples `0..end` into a film that is then dropped: the state `learning` a render
/// of a sample range starting at `end` needs (see [`crate::learning`]).
fn train(
    learning: &mut Learning,
    scene: &Scene,
    strategy: &LightStrategy,
    settings: &RenderSettings,
    end: u32,
) -> RayCounters {
    let mut film = Film::new(settings.resolution, false);
    let mut rays = RayCounters::default();
    while film.spp() < end {
        let first = film.spp();
        let (limit, recording) = learning.recording(first).expect("training stays within the learning");
        let count = limit.min(end - first);
        let pass = Pass {
            scene,
            strategy: learning.strategy().unwrap_or(strategy),
            guide: learning.guide(),
            light_paths: None,
            settings,
            first,
            count,
        };
        let tally = render_pass(&pass, &mut film, &recording, Watch::default());
        rays.add(&tally.rays);
        learning.after_pass(tally.seen, first + count);
    }
    rays
}

/// A render that grows pass by pass: the film, the learning state and the counts. [`render`]
/// drives one to a budget; a viewer drives one itself, a pass at a time, and starts a new one
/// when the view changes.
///
/// A strategy that learns starts from nothing here and learns between passes, at every
/// power of two of spp up to [`Learning::until`]: [`Progressive::pass`] ends passes there, so
/// what it learns depends on the samples, not on how passes split them.
pub struct Progressive<'a> {
    scene: &'a Scene,
    strategy: &'a LightStrategy,
    settings: RenderSettings,
    film: Film,
    learning: Option<Learning>,
    light_paths: Option<LightPaths>,
    /// Index of the first sample (a sample range's start; 0 otherwise).
    offset: u32,
    rays: RayCounters,
    non_finite: u64,
}

impl<'a> Progressive<'a> {
    /// An empty film for `settings` (its budget only gives the first sample index); a range
    /// starting past 0 first trains a learning strategy on the samples before it.
    pub fn new(scene: &'a Scene, strategy: &'a LightStrategy, settings: &RenderSettings) -> Self {
        let offset = settings.budget.fixed().map_or(0, |f| f.0);
        let guide = settings.guiding.then_some((scene.center, scene.radius));
        let mut learning = Learning::new(strategy, guide);
        let mut rays = RayCounters::default();
        if let Some(l) = learning.as_mut().filter(|_| offset > 0) {
            let end = offset.min(l.until());
            rays.add(&train(l, scene, strategy, settings, end));
        }
        let light_paths = traces_light_paths(settings).then(|| LightPaths::new(scene, settings.resolution)).flatten();
        let film = Film::new(settings.resolution, settings.aovs.wants_first_hit());
        let film = if light_paths.is_some() { film.with_splats() } else { film };
        Self { scene, strategy, settings: *settings, film, learning, light_paths, offset, rays, non_finite: 0 }
    }

    /// Adds the next `count` samples of every pixel (fewer when the strategy must learn
    /// first), telling `progress` as bands finish; returns how many it added.
    pub fn pass(&mut self, count: u32, progress: Option<&dyn RenderObserver>) -> u32 {
        self.pass_unless(count, progress, None).expect("a pass without a cancel flag runs to its end")
    }

    /// [`pass`](Self::pass), called off as soon as `cancel` is set (a viewer whose view
    /// changed): then `None`, and this render's film is incomplete, to be dropped.
    pub fn pass_unless(
        &mut self,
        count: u32,
        progress: Option<&dyn RenderObserver>,
        cancel: Option<&AtomicBool>,
    ) -> Option<u32> {
        let first = self.offset + self.film.spp();
        let recording = self.learning.as_ref().and_then(|l| l.recording(first));
        let (count, seen) = match recording {
            Some((limit, seen)) => (count.min(limit), Some(seen)),
            None => (count, None),
        };
        // What the budget's last pass would teach is never used: it records nothing.
        let last = self.settings.budget.fixed().is_some_and(|(a, n)| first + count >= a + n);
        let seen = seen.filter(|_| !last);
        let learned = self.learning.as_ref();
        let strategy = learned.and_then(Learning::strategy).unwrap_or(self.strategy);
        let guide = learned.and_then(Learning::guide);
        let light_paths = self.light_paths.as_ref();
        let pass = Pass { scene: self.scene, strategy, guide, light_paths, settings: &self.settings, first, count };
        let tally =
            render_pass(&pass, &mut self.film, seen.as_ref().unwrap_or(&Seen::default()), Watch { progress, cancel });
        if tally.cancelled {
            return None;
        }
        self.rays.add(&tally.rays);
        self.non_finite += tally.non_finite;
        if let Some(l) = self.learning.as_mut().filter(|_| seen.is_some()) {
            l.after_pass(tally.seen, first + count);
        }
        Some(count)
    }

    /// Every sample so far.
    pub fn film(&self) -> &Film {
        &self.film
    }

    /// The film and its statistics, the render having taken `elapsed`.
    pub fn finish(self, elapsed: Duration, stopped: Stop) -> RenderOutput {
        let size = self.settings.resolution;
        let spp = self.film.spp();
        let stats = RenderStats {
            elapsed,
            spp,
            samples: size.x as u64 * size.y as u64 * spp as u64,
            rays: self.rays,
            non_finite_samples: self.non_finite,
            learned: self.learning.as_ref().and_then(Learning::light_stats),
            guide: self.learning.as_ref().and_then(Learning::guide_stats),
            learned_at: self.learning.as_ref().map_or(0, Learning::learned_at),
            stopped,
            light_path_lights: self.light_paths.as_ref().map_or(0, LightPaths::lights),
        };
        RenderOutput { film: self.film, stats }
    }
}

/// Renders `scene` with `strategy` in the current rayon pool, telling `observer` how far it
/// is and showing it the film after every pass ([`next_pass`] sizes them). A stop the user
/// asks for ([`crate::interrupt`]) ends the render after the pass under way, or at once.
pub fn render(
    scene: &Scene,
    strategy: &LightStrategy,
    settings: &RenderSettings,
    observer: &mut dyn RenderObserver,
) -> RenderOutput {
    let pixels = settings.resolution.x as u64 * settings.resolution.y as u64;
    let start = Instant::now();
    let fixed = settings.budget.fixed();
    observer.start(match (fixed, settings.budget) {
        (Some((_, n)), _) => pixels * n as u64,
        (None, Budget::Time(limit)) => limit.as_millis() as u64,
        (None, _) => unreachable!("a budget without spp is a time"),
    });
    let (mut per_spp, mut reported_ms, mut stopped) = (None, 0, Stop::No);
    let mut progressive = Progressive::new(scene, strategy, settings);
    while let Some(count) = next_pass(settings.budget, progressive.film().spp(), per_spp, start.elapsed()) {
        let t0 = Instant::now();
        let progress = Some(&*observer).filter(|_| fixed.is_some());
        let count = progressive.pass(count, progress);
        per_spp = Some(t0.elapsed() / count);
        stopped = interrupt::requested();
        if stopped == Stop::Now {
            break;
        }
        observer.pass(progressive.film(), start.elapsed());
        if let Budget::Time(limit) = settings.budget {
            let ms = start.elapsed().min(limit).as_millis() as u64;
            observer.advance(ms - reported_ms);
            reported_ms = ms;
        }
        if stopped == Stop::AfterPass {
            break;
        }
    }
    progressive.finish(start.elapsed(), stopped)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The passes `budget` runs when every sample takes `per_spp`.
    fn schedule(budget: Budget, per_spp: Duration) -> Vec<u32> {
        let (mut done, mut passes, mut known) = (0u32, Vec::new(), None);
        while let Some(n) = next_pass(budget, done, known, per_spp * done) {
            passes.push(n);
            done += n;
            known = Some(per_spp);
        }
        passes
    }

    #[test]
    fn fixed_spp_passes_reach_every_power_of_two_within_a_second_each() {
        assert_eq!(schedule(Budget::Spp(8), Duration::from_millis(1)), [1, 1, 2, 4]);
        assert_eq!(schedule(Budget::Spp(6), Duration::from_millis(1)), [1, 1, 2, 2]);
        // 0.3 s per sample: at most 3 samples a pass, still ending at 4, 8, 16.
        let slow = schedule(Budget::Spp(16), Duration::from_millis(300));
        assert_eq!(slow, [1, 1, 2, 3, 1, 3, 3, 2]);
        let mut ends: Vec<u32> = slow.iter().scan(0, |d, &n| Some(*d + n).inspect(|&e| *d = e)).collect();
        ends.retain(|e| e.is_power_of_two());
        assert_eq!(ends, [1, 2, 4, 8, 16]);
        // A sample slower than the cap still makes progress.
        assert_eq!(schedule(Budget::Spp(3), Duration::from_secs(2)), [1, 1, 1]);
    }

    #[test]
    fn equal_time_passes_fill_the_budget_without_overshooting_by_half_a_pass() {
        let budget = Duration::from_secs(1);
        let passes = schedule(Budget::Time(budget), Duration::from_millis(7));
        let total: u32 = passes.iter().sum();
        // 1 s at 7 ms a sample: 142.9 samples fit; the last pass may not overshoot by half.
        assert!((142..=143).contains(&total), "{passes:?}");
        assert!(passes[1..].iter().all(|&n| n <= 8), "passes of ~1/20 of the budget: {passes:?}");
        // A single sample longer than the budget: one pass.
        assert_eq!(schedule(Budget::Time(budget), Duration::from_secs(3)), [1]);
    }
}
