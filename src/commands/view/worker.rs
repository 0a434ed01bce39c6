//! The viewer's render thread: one [`Progressive`] render at a time, restarted whenever the
//! window asks for another view (sampler or camera), each pass's image sent to the window.
//! A view starts with a 1-spp preview at half the width and height (a quarter of the work,
//! so the first image comes at once), then passes of half the time accumulated so far, from
//! [`MIN_PASS`] to [`MAX_PASS`]: frequent images while they change most, few enough that
//! copying and drawing them costs 1–2 % (`tools/view_bench.py`). A new view calls the pass
//! under way off at the next pixel.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, TryRecvError};
use std::time::{Duration, Instant};

use crate::camera::Camera;
use crate::film::AovSet;
use crate::interrupt::{self, Stop};
use crate::light_sampler::LightStrategy;
use crate::math::{Rgb, UVec2};
use crate::render::{Progressive, RenderSettings};
use crate::scene::Scene;
use crate::settings::LightSamplerKind;

/// The shortest pass after the first.
pub const MIN_PASS: Duration = Duration::from_millis(100);
/// The longest pass (unless one sample per pixel takes longer).
pub const MAX_PASS: Duration = Duration::from_millis(500);
/// Images of at least this many pixels get a preview first.
const PREVIEW_PIXELS: u32 = 128 * 96;

/// What the window wants rendered; a later view replaces an earlier one.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// Numbers the views in the order asked, so that frames of an older one are dropped.
    pub generation: u64,
    /// The light sampler.
    pub sampler: LightSamplerKind,
    /// Whether paths are guided.
    pub guiding: bool,
    /// Whether light through smooth glass is solved for.
    pub caustics: bool,
    /// Where the camera is.
    pub camera: Camera,
}

impl View {
    /// What the status bar calls it: what chose the lights, guiding when it is on, and the
    /// connections through glass when they are off.
    fn label(&self, strategy: &LightStrategy) -> String {
        let mut label = strategy.label(self.sampler);
        if self.guiding {
            label += " + guiding";
        }
        if !self.caustics {
            label += ", caustics off";
        }
        label
    }
}

/// What the window asks of the render thread.
pub enum Order {
    /// Restart the accumulation with this view.
    Show(View),
    /// Write the image so far (EXR, with its provenance) into this folder, named after its
    /// sampler and spp.
    Save(PathBuf),
    /// Stop.
    Quit,
}

/// The image after a pass.
pub struct Frame {
    /// The view it shows.
    pub generation: u64,
    /// Its sampler.
    pub sampler: LightSamplerKind,
    /// What chose its lights ([`LightStrategy::label`]): the sampler, or what stood in for it.
    pub label: String,
    /// Mean of each pixel, row-major.
    pub pixels: Vec<Rgb>,
    /// Samples per pixel so far (0: the half-resolution preview).
    pub spp: u32,
    /// Camera samples per second since this view's accumulation began.
    pub samples_per_second: f64,
    /// Whether the accumulation has reached its cap (`--spp` or `--time`) and stopped.
    pub done: bool,
}

/// What the render thread tells the window.
pub enum Report {
    /// A pass finished.
    Frame(Frame),
    /// The image was saved there.
    Saved(PathBuf),
    /// Something failed (building a sampler, writing a file); the view goes on.
    Failed(String),
}

/// What a view accumulates and for how long.
#[derive(Clone, Debug)]
pub struct Accumulate {
    /// Seed, depth, size, and the budget `Budget::Spp(spp)`.
    pub settings: RenderSettings,
    /// Stop refining at this many samples per pixel.
    pub spp: u32,
    /// Stop refining after this long, if set.
    pub time: Option<Duration>,
    /// The scene's name, for the provenance of saved images.
    pub scene_name: String,
    /// The ray tracer the scene was built for, for the same.
    pub tracer: &'static str,
}

impl Accumulate {
    /// Whether a view with `spp` samples per pixel after `elapsed` has reached its cap.
    fn finished(&self, spp: u32, elapsed: Duration) -> bool {
        spp >= self.spp || self.time.is_some_and(|t| elapsed >= t)
    }
}

/// Runs views until told to quit (or the user stops the process): renders `scene` (whose
/// camera it moves), building each sampler the first time it is asked for. The window sets
/// `cancel` before it sends a new view or quits: the pass under way stops at the next pixel
/// (an `all` pass over thousands of lights takes seconds).
pub fn run(
    scene: &mut Scene,
    plan: &Accumulate,
    cancel: &AtomicBool,
    orders: Receiver<Order>,
    reports: Sender<Report>,
) {
    let mut strategies: HashMap<LightSamplerKind, LightStrategy> = HashMap::new();
    let Ok(Order::Show(mut view)) = orders.recv() else { return };
    loop {
        scene.camera = view.camera;
        let strategy = strategies
            .entry(view.sampler)
            .or_insert_with(|| LightStrategy::build(view.sampler, &scene.lights, scene.center, scene.radius));
        cancel.store(false, Ordering::Relaxed);
        match accumulate(scene, strategy, view, plan, cancel, &orders, &reports) {
            Some(next) => view = next,
            None => return,
        }
    }
}

/// Refines one view until it is done (or called off), then waits; returns the next view, or
/// `None` to quit.
fn accumulate(
    scene: &Scene,
    strategy: &LightStrategy,
    view: View,
    plan: &Accumulate,
    cancel: &AtomicBool,
    orders: &Receiver<Order>,
    reports: &Sender<Report>,
) -> Option<View> {
    let settings = RenderSettings { guiding: view.guiding, caustics: view.caustics, ..plan.settings };
    let size = settings.resolution;
    // Called off: a new view or the end is on its way; wait for it.
    let mut called_off = false;
    if size.x * size.y >= PREVIEW_PIXELS {
        match preview(scene, strategy, view, &settings, cancel) {
            Some(frame) => {
                if reports.send(Report::Frame(frame)).is_err() {
                    return None;
                }
            }
            None => called_off = true,
        }
    }
    let mut progressive = Progressive::new(scene, strategy, &settings);
    let start = Instant::now();
    let mut count = 1;
    loop {
        let done = called_off || plan.finished(progressive.film().spp(), start.elapsed());
        // Every order waiting, the last view winning; when done, wait for one.
        let mut next = None;
        loop {
            let order = if done && next.is_none() {
                orders.recv().map_err(|_| TryRecvError::Disconnected)
            } else {
                orders.try_recv()
            };
            match order {
                Ok(Order::Show(v)) => next = Some(v),
                Ok(Order::Save(dir)) => {
                    let _ = reports.send(save(&progressive, &dir, view.sampler, &settings, plan, start.elapsed()));
                }
                Ok(Order::Quit) | Err(TryRecvError::Disconnected) => return None,
                Err(TryRecvError::Empty) => break,
            }
        }
        if next.is_some() {
            return next;
        }
        if interrupt::requested() != Stop::No {
            return None;
        }
        let t0 = Instant::now();
        let Some(rendered) =
            progressive.pass_unless(count.min(plan.spp - progressive.film().spp()), None, Some(cancel))
        else {
            called_off = true;
            continue;
        };
        let per_spp = t0.elapsed().as_secs_f64() / rendered as f64;
        let elapsed = start.elapsed();
        let target = (elapsed / 2).clamp(MIN_PASS, MAX_PASS);
        count = (target.as_secs_f64() / per_spp.max(1e-9)).clamp(1.0, 1024.0) as u32;
        let film = progressive.film();
        let frame = Frame {
            generation: view.generation,
            sampler: view.sampler,
            label: view.label(strategy),
            pixels: film.means(),
            spp: film.spp(),
            samples_per_second: size.x as f64 * size.y as f64 * film.spp() as f64 / elapsed.as_secs_f64().max(1e-9),
            done: plan.finished(film.spp(), elapsed),
        };
        if reports.send(Report::Frame(frame)).is_err() {
            return None;
        }
    }
}

/// One sample per pixel at half the width and height, each pixel shown as 2 × 2; `None` when
/// called off.
fn preview(
    scene: &Scene,
    strategy: &LightStrategy,
    view: View,
    settings: &RenderSettings,
    cancel: &AtomicBool,
) -> Option<Frame> {
    let full = settings.resolution;
    let half = UVec2::new(full.x.div_ceil(2), full.y.div_ceil(2));
    let mut small = Progressive::new(scene, strategy, &RenderSettings { resolution: half, ..*settings });
    small.pass_unless(1, None, Some(cancel))?;
    let means = small.film().means();
    let pixels = (0..full.y)
        .flat_map(|y| (0..full.x).map(move |x| (y / 2 * half.x + x / 2) as usize))
        .map(|i| means[i])
        .collect();
    Some(Frame {
        generation: view.generation,
        sampler: view.sampler,
        label: view.label(strategy),
        pixels,
        spp: 0,
        samples_per_second: 0.0,
        done: false,
    })
}

/// Writes the view's image so far into `dir` as `view-SAMPLER-Nspp.exr`, with its provenance.
fn save(
    progressive: &Progressive,
    dir: &std::path::Path,
    sampler: LightSamplerKind,
    settings: &RenderSettings,
    plan: &Accumulate,
    elapsed: Duration,
) -> Report {
    let film = progressive.film();
    let path = dir.join(format!("view-{sampler}-{}spp.exr", film.spp()));
    let stats = crate::render::RenderStats { spp: film.spp(), elapsed, ..Default::default() };
    let meta = crate::commands::provenance::provenance(&plan.scene_name, sampler, plan.tracer, settings, &stats);
    match crate::io::exr::write(&path, &film.layers(AovSet::default()), &meta) {
        Ok(()) => Report::Saved(path),
        Err(e) => Report::Failed(e.to_string()),
    }
}
