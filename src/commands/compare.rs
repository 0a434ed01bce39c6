//! `myriad compare`: render one scene with several light samplers at equal spp or equal
//! time, measure each against a reference, and write renders, error maps, a contact sheet, a
//! convergence plot and reports.
//!
//! Every sampler renders with the same seeds (1..=K), so at equal spp the camera rays and
//! BSDF directions are identical and differences come from the light choice alone. Runs go
//! seed by seed, every sampler in turn, so that at equal time a machine's changing speed
//! touches every sampler alike. The
//! reference is rendered with a seed no compared run uses (or given), and cached in the
//! output folder under a key of everything that determines it.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::progress::Progress;
use super::settings::{COMPARE_DEFAULT_SPP, RenderRequest, Resolved};
use super::{LoadedScene, SceneOptions, load_scene};
use crate::compare::html::{self, Page, PageImage};
use crate::compare::images::{SheetColumn, contact_sheet, error_picture, preview_picture};
use crate::compare::metrics::{
    BIAS_ALPHA, REL_MSE_EPSILON, TRIMMED_SHARE, bias_check, efficiency, error_metrics, relative_error_map,
    trimmed_rel_mse,
};
use crate::compare::plot::{Curve, convergence_svg};
use crate::compare::report::{CompareReport, ReferenceInfo, RunResult, SamplerResult, Stat, num};
use crate::error::{Error, Result};
use crate::film::{AovSet, Film};
use crate::fingerprint::Fingerprint;
use crate::interrupt::Stop;
use crate::light_sampler::LightStrategy;
use crate::math::{Rgb, UVec2};
use crate::render::{Budget, RenderObserver, RenderSettings, render};
use crate::scene::{BuildOptions, Scene, SceneReport};
use crate::settings::LightSamplerKind;

/// The samplers compared when none are named (the scene's own is added to them).
pub const DEFAULT_SAMPLERS: [LightSamplerKind; 5] = [
    LightSamplerKind::Uniform,
    LightSamplerKind::Power,
    LightSamplerKind::Local,
    LightSamplerKind::Tree,
    LightSamplerKind::Cells,
];

/// The reference's seed: no compared run (seeds S+1..=S+K) uses it.
pub const REFERENCE_SEED: u64 = 0x5eed_0000_0000_0000;

/// What to compare and how.
#[derive(Clone, Debug)]
pub struct CompareOptions {
    /// Scene file.
    pub scene: PathBuf,
    /// Samplers, in report order; `None`: [`DEFAULT_SAMPLERS`] and the scene's own sampler.
    pub samplers: Option<Vec<LightSamplerKind>>,
    /// Equal spp (default [`COMPARE_DEFAULT_SPP`]) or equal time per sampler and seed, the
    /// base seed (runs use the seeds after it) and the depth; the sampler is ignored.
    pub settings: RenderRequest,
    /// A reference EXR to measure against; otherwise one is rendered (and cached).
    pub reference: Option<PathBuf>,
    /// spp of a rendered reference (default: see [`reference_budget`]).
    pub reference_spp: Option<u32>,
    /// Time of a rendered reference, instead of an spp.
    pub reference_time: Option<Duration>,
    /// Sampler of a rendered reference; default [`REFERENCE_SAMPLER`].
    pub reference_sampler: Option<LightSamplerKind>,
    /// Seeds per sampler (mean ± standard deviation over them).
    pub seeds: u32,
    /// Output folder.
    pub out_dir: PathBuf,
    /// Image size.
    pub resolution: Option<UVec2>,
    /// Camera name.
    pub camera: Option<String>,
    /// How to read the scene file.
    pub load: crate::io::LoadOptions,
    /// Exposure of the previews, stops.
    pub exposure: f32,
    /// Show progress bars.
    pub progress: bool,
    /// Measure runs rendered elsewhere instead of rendering them: `DIR/SAMPLER-SEED.part`,
    /// each from `render --samples 0..SPP --sampler SAMPLER --seed SEED` (what `myriad slurm
    /// --compare` has its job array write). Equal spp only.
    pub runs: Option<PathBuf>,
    /// Stream each run to the tev viewer at this address.
    pub display: Option<String>,
}

/// The part file of one (sampler, seed) run in a runs folder.
pub fn run_part(dir: &Path, kind: LightSamplerKind, seed: u64) -> PathBuf {
    dir.join(format!("{}-{seed}.part", kind.name()))
}

/// The reference image and its per-pixel variance (zero when unknown).
struct Reference {
    pixels: Vec<Rgb>,
    variance: Vec<Rgb>,
    info: ReferenceInfo,
}

/// A reference as read from disk: RGB, variance (zeros when absent) and header attributes.
pub(crate) struct ReferenceFile {
    /// Its RGB.
    pub pixels: Vec<Rgb>,
    /// Its variance layer (zeros when absent).
    pub variance: Vec<Rgb>,
    /// Its header attributes.
    pub meta: Vec<(String, String)>,
}

/// Reads an EXR's RGB (and variance when present), checking its size.
pub(crate) fn read_reference(path: &Path, size: UVec2) -> Result<ReferenceFile> {
    let (layers, meta) = crate::io::exr::read(path)?;
    if layers.size != size {
        return Err(Error::Input {
            path: path.into(),
            message: format!(
                "the reference is {} × {} but the renders are {} × {}; pass --resolution {}x{}",
                layers.size.x, layers.size.y, size.x, size.y, layers.size.x, layers.size.y
            ),
        });
    }
    let pixels =
        layers.rgb().ok_or_else(|| Error::Input { path: path.into(), message: "no R, G, B channels".into() })?;
    let variance = layers.rgb_layer("variance").unwrap_or_else(|| vec![Rgb::ZERO; pixels.len()]);
    Ok(ReferenceFile { pixels, variance, meta })
}

/// The reference's sampler unless one is named: every sampler is unbiased, so the one that
/// converges fastest makes the best reference for the time. The tree is within 7–9 % of
/// `local`'s error per sample at a fraction of its O(n) cost (docs/scaling), and `all` costs n
/// shadow rays a vertex: both are for small scenes only.
pub const REFERENCE_SAMPLER: LightSamplerKind = LightSamplerKind::Tree;

/// A rendered reference takes this many times what each compared run takes (spp or time)...
pub const REFERENCE_FACTOR: u32 = 16;

/// ... but at most this long (then it renders for this long instead).
pub const MAX_REFERENCE_TIME: Duration = Duration::from_secs(600);

/// A reference whose own noise (its variance of the mean, as relMSE) exceeds this share of the
/// best compared run's relMSE is flagged: it would move the numbers it judges.
pub const NOISY_REFERENCE: f64 = 0.1;

/// The rendered reference's budget: `--reference-spp` or `--reference-time` if given, else
/// [`REFERENCE_FACTOR`] × each run's, capped at [`MAX_REFERENCE_TIME`] by the estimate
/// `per_spp` from a timing pass.
fn reference_budget(opts: &CompareOptions, runs: Budget, per_spp: Duration) -> Budget {
    if let Some(n) = opts.reference_spp {
        return Budget::Spp(n.max(1));
    }
    if let Some(t) = opts.reference_time {
        return Budget::Time(t);
    }
    match runs.fixed() {
        Some((_, n)) => {
            let spp = n.saturating_mul(REFERENCE_FACTOR);
            if per_spp * spp > MAX_REFERENCE_TIME { Budget::Time(MAX_REFERENCE_TIME) } else { Budget::Spp(spp) }
        }
        None => match runs {
            Budget::Time(t) => Budget::Time((t * REFERENCE_FACTOR).min(MAX_REFERENCE_TIME)),
            _ => unreachable!("a budget is fixed or a time"),
        },
    }
}

/// Wall time of one sample per pixel of `kind` over the plan's image (a short timing pass
/// for the estimates; its image is dropped).
fn time_per_spp(scene: &Scene, kind: LightSamplerKind, plan: &Plan) -> Duration {
    let strategy = LightStrategy::build(kind, &scene.lights, scene.center, scene.radius);
    let settings = RenderSettings { budget: Budget::Spp(1), ..plan.settings(REFERENCE_SEED) };
    render(scene, &strategy, &settings, &mut ()).stats.elapsed
}

/// The budget in words.
fn budget_words(b: Budget) -> String {
    match b {
        Budget::Time(t) => format!("{:.0} s", t.as_secs_f64()),
        _ => format!("{} spp", b.fixed().map_or(0, |f| f.1)),
    }
}

/// Everything the rendered reference depends on: the bytes of every file the scene was read
/// from, how it was read and built, every render setting, and this build of myriad.
fn reference_key(
    opts: &CompareOptions,
    loaded: &LoadedScene,
    sampler: LightSamplerKind,
    budget: Budget,
    max_depth: u32,
) -> Result<String> {
    let mut key = Fingerprint::new("myriad compare reference");
    for input in &loaded.report.inputs {
        key.file(input)?;
    }
    let size = loaded.report.resolution;
    key.value("gltf_scene", format!("{:?}", opts.load.gltf_scene))
        .value("punctual_scale", opts.load.punctual_scale.to_bits())
        .value("camera", opts.camera.as_deref().unwrap_or("-"))
        .value("resolution", format!("{}x{}", size.x, size.y))
        .value("sampler", sampler.name())
        .value("budget", format!("{budget:?}"))
        .value("max_depth", max_depth)
        .value("seed", REFERENCE_SEED)
        .value("build", crate::fingerprint::build_id());
    Ok(key.finish())
}

/// Loads the given reference, reuses a cached one, or renders (with `sampler` and `budget`)
/// and caches a new one.
fn reference(
    opts: &CompareOptions,
    loaded: &LoadedScene,
    sampler: LightSamplerKind,
    budget: Budget,
    max_depth: u32,
) -> Result<Reference> {
    let (scene, size) = (&loaded.scene, loaded.report.resolution);
    if let Some(path) = &opts.reference {
        let ReferenceFile { pixels, variance, .. } = read_reference(path, size)?;
        let info = ReferenceInfo { path: path.display().to_string(), origin: "given".into(), ..Default::default() };
        return Ok(Reference { pixels, variance, info });
    }
    let origin = format!("{sampler}, {}, seed {REFERENCE_SEED:#x}", budget_words(budget));
    let key = reference_key(opts, loaded, sampler, budget, max_depth)?;
    let path = opts.out_dir.join("reference.exr");
    if path.exists()
        && let Ok(ReferenceFile { pixels, variance, meta }) = read_reference(&path, size)
        && meta.iter().any(|(k, v)| k == "myriad.reference_key" && *v == key)
    {
        let info = ReferenceInfo { path: path.display().to_string(), origin, reused: true, ..Default::default() };
        return Ok(Reference { pixels, variance, info });
    }
    let strategy = LightStrategy::build(sampler, &scene.lights, scene.center, scene.radius);
    let aovs = AovSet { variance: true, ..Default::default() };
    let settings = RenderSettings { budget, seed: REFERENCE_SEED, max_depth, resolution: size, aovs };
    let out = render(scene, &strategy, &settings, &mut Progress::new(opts.progress, "ref"));
    // A reference stopped short is not the reference its key describes.
    if out.stats.stopped != Stop::No {
        return Err(Error::Interrupted);
    }
    let mut meta = super::render::provenance(&opts.scene.display().to_string(), sampler, &settings, &out.stats);
    meta.push(("myriad.reference_key".into(), key));
    crate::io::exr::write(&path, &out.film.layers(aovs), &meta)?;
    let pixels = out.film.means();
    let variance = (0..pixels.len()).map(|i| out.film.variance_of_mean(i)).collect();
    let info = ReferenceInfo {
        path: path.display().to_string(),
        origin: if budget.fixed().is_some() { origin } else { format!("{origin} ({} spp)", out.stats.spp) },
        seconds: out.stats.elapsed.as_secs_f64(),
        spp: out.stats.spp,
        ..Default::default()
    };
    Ok(Reference { pixels, variance, info })
}

/// Decides the reference's budget and, when progress is shown, says what the comparison will
/// render and how long it should take (from one-spp timing passes where the budget is spp).
fn announce(opts: &CompareOptions, plan: &Plan, scene: &Scene, ref_sampler: LightSamplerKind) -> Budget {
    let fixed = plan.budget.fixed();
    let render_ref = opts.reference.is_none();
    // One timing pass per sampler at most (the reference's sampler is often a compared one).
    let mut timed: Vec<(LightSamplerKind, Duration)> = Vec::new();
    let mut timing = |kind| match timed.iter().find(|t| t.0 == kind) {
        Some(&(_, t)) => t,
        None => {
            let t = time_per_spp(scene, kind, plan);
            timed.push((kind, t));
            t
        }
    };
    let ref_per_spp = if render_ref && opts.reference_spp.is_none() && opts.reference_time.is_none() && fixed.is_some()
    {
        timing(ref_sampler)
    } else {
        Duration::ZERO
    };
    let budget = reference_budget(opts, plan.budget, ref_per_spp);
    if !opts.progress {
        return budget;
    }
    let seeds = plan.seeds.len() as u32;
    let runs: Duration = match (fixed, plan.budget) {
        (_, _) if opts.runs.is_some() => Duration::ZERO,
        (Some((_, n)), _) => plan.samplers.iter().map(|&k| timing(k) * n * seeds).sum(),
        (None, Budget::Time(t)) => t * seeds * plan.samplers.len() as u32,
        (None, _) => Duration::ZERO,
    };
    let ref_time = match budget {
        _ if !render_ref => Duration::ZERO,
        Budget::Time(t) => t,
        b => timing(ref_sampler) * b.fixed().map_or(0, |f| f.1),
    };
    let reference = if render_ref {
        format!("reference {ref_sampler}, {} (≈ {:.0} s, unless cached)", budget_words(budget), ref_time.as_secs_f64())
    } else {
        "the given reference".to_string()
    };
    let names: Vec<&str> = plan.samplers.iter().map(|k| k.name()).collect();
    let _ = writeln!(
        std::io::stderr(),
        "compare    {} × {} px: {reference}; then {} × {seeds} seed(s) at {} each (≈ {:.0} s); total ≈ {:.0} s",
        plan.resolution.x,
        plan.resolution.y,
        names.join(", "),
        budget_words(plan.budget),
        runs.as_secs_f64(),
        (runs + ref_time).as_secs_f64()
    );
    budget
}

/// An image's noise as relMSE would see it: the mean over pixels of its variance of the mean
/// over (`image`² + ε), `image` a low-noise estimate of the truth.
fn relative_noise(variance: &[Rgb], image: &[Rgb]) -> f64 {
    variance
        .iter()
        .zip(image)
        .map(|(v, p)| (0..3).map(|c| v[c] as f64 / ((p[c] as f64).powi(2) + REL_MSE_EPSILON)).sum::<f64>() / 3.0)
        .sum::<f64>()
        / image.len().max(1) as f64
}

/// Measures the reference's own noise against the least noisy run's (both over that run's
/// image, so a noisy reference does not judge itself): flagged beyond [`NOISY_REFERENCE`].
fn judge_reference(info: &mut ReferenceInfo, variance: &[Rgb], image: &[Rgb], run_noise: f64) {
    // Either side without a variance estimate (one sample per pixel) cannot be judged.
    if variance.iter().all(|v| *v == Rgb::ZERO) || !(run_noise > 0.0) {
        return;
    }
    let noise = relative_noise(variance, image);
    info.noise_rel_mse = Some(noise);
    info.too_noisy = noise > NOISY_REFERENCE * run_noise;
    if info.too_noisy && info.spp > 0 {
        info.needed_spp = Some((info.spp as f64 * noise / (NOISY_REFERENCE * run_noise)).ceil() as u64);
    }
}

/// What the comparison renders, every choice made: the samplers in report order, the
/// budget and depth of each run, and the seeds each sampler renders with.
struct Plan {
    samplers: Vec<LightSamplerKind>,
    budget: Budget,
    max_depth: u32,
    resolution: UVec2,
    seeds: Vec<u64>,
}

impl Plan {
    /// The command line's choices over the scene's, over the defaults.
    fn new(opts: &CompareOptions, report: &SceneReport) -> Result<Self> {
        let Resolved { budget, seed, max_depth, .. } = opts.settings.resolve(&report.render, COMPARE_DEFAULT_SPP)?;
        let samplers = opts.samplers.clone().unwrap_or_else(|| {
            let mut samplers = DEFAULT_SAMPLERS.to_vec();
            samplers.extend(report.render.sampler.filter(|s| !samplers.contains(s)));
            samplers
        });
        if samplers.is_empty() || opts.seeds == 0 {
            return Err(Error::Usage("give at least one sampler and one seed".into()));
        }
        let seeds = (1..=opts.seeds as u64).map(|k| seed.wrapping_add(k)).collect();
        Ok(Self { samplers, budget, max_depth, resolution: report.resolution, seeds })
    }

    fn settings(&self, seed: u64) -> RenderSettings {
        let (budget, max_depth, resolution) = (self.budget, self.max_depth, self.resolution);
        RenderSettings { budget, seed, max_depth, resolution, aovs: AovSet::default() }
    }

    /// The bias flag's level for one sampler: [`BIAS_ALPHA`] over all of them (Šidák).
    fn bias_alpha(&self) -> f64 {
        1.0 - (1.0 - BIAS_ALPHA).powf(1.0 / self.samplers.len() as f64)
    }

    fn mode(&self) -> String {
        match self.budget {
            Budget::Spp(n) | Budget::Samples(0, n) => format!("equal spp ({n})"),
            Budget::Samples(a, b) => format!("equal samples ({a}..{b})"),
            Budget::Time(t) => format!("equal time ({} s)", t.as_secs_f64()),
        }
    }
}

/// Where `compare` writes for `scene` unless told (`compare-NAME` in the current folder,
/// NAME the file's stem; `compare-scene` for the built-in one), and where `view` looks for
/// the reference it cached.
pub fn default_out_dir(scene: Option<&Path>) -> PathBuf {
    let stem = scene.and_then(|s| s.file_stem()).map_or("scene".into(), |s| s.to_string_lossy());
    PathBuf::from(format!("compare-{stem}"))
}

/// Runs the comparison and writes every output into `opts.out_dir`: reference → each sampler
/// with each seed → ranking → contact sheet, plot and reports.
pub fn compare(opts: &CompareOptions) -> Result<CompareReport> {
    let scene_options = SceneOptions {
        load: opts.load,
        build: BuildOptions { resolution: opts.resolution, camera: opts.camera.clone() },
    };
    // The scene must load before the output folder is made: a broken scene leaves nothing.
    let loaded = load_scene(Some(&opts.scene), &scene_options)?;
    let plan = Plan::new(opts, &loaded.report)?;
    // Ctrl-C stops the comparison (after the pass under way) and writes no report.
    let _busy = crate::interrupt::busy();
    crate::io::ensure_dir(&opts.out_dir)?;
    let ref_sampler = opts.reference_sampler.unwrap_or(REFERENCE_SAMPLER);
    let ref_budget = announce(opts, &plan, &loaded.scene, ref_sampler);
    let mut reference = reference(opts, &loaded, ref_sampler, ref_budget, plan.max_depth)?;
    let size = plan.resolution;
    let mut columns = vec![SheetColumn {
        title: "reference".into(),
        caption: reference.info.origin.replacen(", seed", "\nseed", 1),
        render: preview_picture(size, &reference.pixels, opts.exposure),
        error: None,
    }];
    let scene_hash = match &opts.runs {
        Some(_) if plan.budget.fixed().is_none() => {
            return Err(Error::Usage("--runs measures runs of a fixed spp; give --spp, not --time".into()));
        }
        Some(_) => super::merge::scene_fingerprint(&loaded, &scene_options)?,
        None => String::new(),
    };
    let runs_from = opts.runs.as_deref().map(|d| (d, scene_hash.as_str()));
    let mut samplers: Vec<SamplerRuns> =
        plan.samplers.iter().map(|&kind| SamplerRuns::build(kind, &loaded.scene, size)).collect();
    // Seed by seed, every sampler in turn: a machine that slows down or speeds up during the
    // comparison (a busy neighbour, a warming CPU) touches every sampler alike, where
    // sampler after sampler it would favour whichever ran in the quiet minutes.
    for &seed in &plan.seeds {
        for s in &mut samplers {
            s.run(opts, &plan, &loaded, runs_from, seed, &reference)?;
        }
    }
    let mut results = Vec::new();
    // The least noisy run's own noise and image, to judge the reference's noise by.
    let mut quietest: Option<(f64, &[Rgb])> = None;
    for s in &samplers {
        let first = s.first.as_ref().expect("a plan has at least one seed");
        if quietest.is_none_or(|q| first.noise < q.0) {
            quietest = Some((first.noise, &first.pixels));
        }
    }
    if let Some((run_noise, image)) = quietest {
        judge_reference(&mut reference.info, &reference.variance, image, run_noise);
    }
    let finished: Vec<_> = samplers.into_iter().map(|s| s.finish(&plan, &reference)).collect();
    let mut pictures = vec![reference.pixels];
    for (result, column, pixels) in finished {
        results.push(result);
        columns.push(column);
        pictures.push(pixels);
    }
    rank(&mut results);
    let report = CompareReport {
        scene: opts.scene.display().to_string(),
        mode: plan.mode(),
        resolution: [size.x, size.y],
        max_depth: plan.max_depth,
        threads: rayon::current_num_threads(),
        reference: reference.info,
        samplers: results,
        files: Vec::new(),
    };
    write_report(opts, report, &columns, &pictures)
}

/// One sampler's renders, seed after seed: its strategy built once, each run's numbers, the
/// statistics over seeds, and what the first seed's run left for the report.
struct SamplerRuns {
    kind: LightSamplerKind,
    strategy: LightStrategy,
    build_seconds: f64,
    /// The most the strategy held in any run (a learning one holds more once it has learned).
    memory_bytes: usize,
    runs: Vec<RunResult>,
    seeds: SeedStatistics,
    first: Option<FirstRun>,
}

/// The first seed's run, once its render and error map are written: what the report and the
/// contact sheet show of it.
struct FirstRun {
    pixels: Vec<Rgb>,
    /// Its own noise (relMSE of its variance of the mean), to judge the reference by.
    noise: f64,
    column: SheetColumn,
    files: Vec<String>,
}

/// Watches one run: its progress bar, and the relMSE after every pass.
struct Convergence<'a> {
    progress: Progress,
    reference: &'a [Rgb],
    points: Vec<(f64, f64)>,
}

impl RenderObserver for Convergence<'_> {
    fn start(&self, total: u64) {
        self.progress.start(total);
    }

    fn advance(&self, n: u64) {
        self.progress.advance(n);
    }

    fn pass(&mut self, film: &Film, elapsed: std::time::Duration) {
        if let Ok(m) = error_metrics(&film.means(), self.reference) {
            self.points.push((elapsed.as_secs_f64(), m.rel_mse));
        }
    }
}

/// One run's film, seconds and relMSE-over-time points.
struct Run {
    film: Film,
    seconds: f64,
    convergence: Vec<(f64, f64)>,
}

/// Renders one run of `strategy` with `seed`.
fn render_run(
    opts: &CompareOptions,
    plan: &Plan,
    scene: &Scene,
    strategy: &LightStrategy,
    kind: LightSamplerKind,
    seed: u64,
    reference: &Reference,
) -> Result<(Run, usize)> {
    let mut watch = Convergence {
        progress: Progress::new(opts.progress, kind.name()),
        reference: &reference.pixels,
        points: vec![],
    };
    let name = format!("{kind} seed {seed}");
    let mut display = opts.display.as_deref().map(|a| super::display::TevStream::connect(a, &name, AovSet::default()));
    let r = render(scene, strategy, &plan.settings(seed), &mut (&mut watch, &mut display));
    if r.stats.stopped != Stop::No {
        return Err(Error::Interrupted);
    }
    let memory = r.stats.learned.map_or(0, |l| l.memory_bytes);
    Ok((Run { film: r.film, seconds: r.stats.elapsed.as_secs_f64(), convergence: watch.points }, memory))
}

/// Reads one run rendered elsewhere (see [`CompareOptions::runs`]), checking that it is the
/// run this plan would render.
fn load_run(dir: &Path, plan: &Plan, scene_hash: &str, kind: LightSamplerKind, seed: u64) -> Result<Run> {
    let path = run_part(dir, kind, seed);
    let (h, film) = crate::io::part::read(&path)?;
    let spp = plan.budget.fixed().map_or(0, |f| f.1);
    let wanted = [
        ("sampler", h.sampler.clone(), kind.name().to_string()),
        ("seed", h.seed.to_string(), seed.to_string()),
        ("samples", format!("{}..{}", h.samples[0], h.samples[1]), format!("0..{spp}")),
        ("max depth", h.max_depth.to_string(), plan.max_depth.to_string()),
        ("resolution", format!("{:?}", h.resolution), format!("{:?}", plan.resolution.to_array())),
        ("scene contents", h.scene_hash.clone(), scene_hash.to_string()),
    ];
    if let Some((what, have, want)) = wanted.into_iter().find(|(_, have, want)| have != want) {
        return Err(Error::Input {
            path,
            message: format!("is not this comparison's run: its {what} is {have}, the comparison's {want}"),
        });
    }
    Ok(Run { film, seconds: h.render_seconds, convergence: Vec::new() })
}

impl SamplerRuns {
    /// Builds `kind`'s strategy for `scene` and times the build.
    fn build(kind: LightSamplerKind, scene: &Scene, size: UVec2) -> Self {
        let t = Instant::now();
        let strategy = LightStrategy::build(kind, &scene.lights, scene.center, scene.radius);
        let build_seconds = t.elapsed().as_secs_f64();
        let memory_bytes = strategy.memory_bytes();
        let seeds = SeedStatistics::new((size.x * size.y) as usize);
        Self { kind, strategy, build_seconds, memory_bytes, runs: Vec::new(), seeds, first: None }
    }

    /// Renders (or, with `runs`, reads) the run with `seed` and measures it against the
    /// reference; the first one's render and error map are written.
    fn run(
        &mut self,
        opts: &CompareOptions,
        plan: &Plan,
        loaded: &LoadedScene,
        runs_from: Option<(&Path, &str)>,
        seed: u64,
        reference: &Reference,
    ) -> Result<()> {
        let kind = self.kind;
        let run = match runs_from {
            Some((dir, hash)) => load_run(dir, plan, hash, kind, seed)?,
            None => {
                // A fresh copy per seed: `cells` builds its tables during a run, and a later
                // seed must pay for them again to be timed fairly.
                let fresh = self.strategy.clone();
                let (run, memory) = render_run(opts, plan, &loaded.scene, &fresh, kind, seed, reference)?;
                self.memory_bytes = self.memory_bytes.max(memory).max(fresh.memory_bytes());
                run
            }
        };
        let means = run.film.means();
        let m = error_metrics(&means, &reference.pixels)?;
        let rel_mse_trimmed = trimmed_rel_mse(&means, &reference.pixels, TRIMMED_SHARE)?;
        self.seeds.add(&run.film);
        let result = RunResult {
            seed,
            seconds: run.seconds,
            spp: run.film.spp(),
            mse: m.mse,
            rel_mse: m.rel_mse,
            rel_mse_trimmed,
            efficiency: efficiency(m.rel_mse, run.seconds),
            // A run rendered elsewhere shows only where it ended.
            convergence: if run.convergence.is_empty() { vec![(run.seconds, m.rel_mse)] } else { run.convergence },
        };
        if self.first.is_none() {
            self.first = Some(write_first(opts, plan, kind, &run.film, &result, reference)?);
        }
        self.runs.push(result);
        Ok(())
    }

    /// The sampler's numbers over its seeds, its contact-sheet column and its first image.
    fn finish(self, plan: &Plan, reference: &Reference) -> (SamplerResult, SheetColumn, Vec<Rgb>) {
        let first = self.first.expect("a plan has at least one seed");
        let (mean, mean_variance) = self.seeds.finish();
        let stat = |f: &dyn Fn(&RunResult) -> f64| Stat::of(&self.runs.iter().map(f).collect::<Vec<_>>());
        let (seconds, rel_mse) = (stat(&|r| r.seconds), stat(&|r| r.rel_mse));
        let rel_mse_trimmed = stat(&|r| r.rel_mse_trimmed);
        let efficiency_trimmed = efficiency(rel_mse_trimmed.mean, seconds.mean);
        // The efficiency of the mean error, not the mean of the runs' efficiencies: the mean of
        // 1/relMSE rewards a sampler whose error is mostly low and now and then huge (`power`'s
        // fireflies on glass.glb, 64 spp: 14 of 16 seeds at relMSE·spp 12–15, two at 71 and
        // 1475), where the time to reach an error is set by its expectation.
        let efficiency = Stat { mean: efficiency(rel_mse.mean, seconds.mean), std: stat(&|r| r.efficiency).std };
        let result = SamplerResult {
            sampler: self.kind.name().into(),
            build_seconds: self.build_seconds,
            memory_bytes: self.memory_bytes,
            seconds,
            spp: stat(&|r| r.spp as f64),
            mse: stat(&|r| r.mse),
            rel_mse,
            efficiency,
            efficiency_vs_best: 0.0,
            efficiency_trimmed,
            rel_mse_trimmed,
            bias: bias_check(&mean, &mean_variance, &reference.pixels, &reference.variance, plan.bias_alpha()),
            files: first.files,
            runs: self.runs,
        };
        (result, first.column, first.pixels)
    }
}

/// The mean image over seeds and the variance of that mean.
struct SeedStatistics {
    count: u32,
    sum: Vec<Rgb>,
    sum_sq: Vec<Rgb>,
    /// Σ of the films' own variance-of-the-mean estimates.
    film_variance: Vec<Rgb>,
}

impl SeedStatistics {
    fn new(pixels: usize) -> Self {
        Self {
            count: 0,
            sum: vec![Rgb::ZERO; pixels],
            sum_sq: vec![Rgb::ZERO; pixels],
            film_variance: vec![Rgb::ZERO; pixels],
        }
    }

    fn add(&mut self, film: &Film) {
        self.count += 1;
        for (i, p) in film.means().into_iter().enumerate() {
            self.sum[i] += p;
            self.sum_sq[i] += p * p;
            self.film_variance[i] += film.variance_of_mean(i);
        }
    }

    /// The mean, and its variance: the films' own estimate, or with several seeds the
    /// spread across them where larger (unlike the films' estimate it exists at 1 spp).
    fn finish(self) -> (Vec<Rgb>, Vec<Rgb>) {
        let k = self.count as f32;
        let mean: Vec<Rgb> = self.sum.iter().map(|&s| s / k).collect();
        let variance = (0..mean.len())
            .map(|i| {
                let own = self.film_variance[i] / (k * k);
                if self.count < 2 {
                    return own;
                }
                let across = (self.sum_sq[i] - k * mean[i] * mean[i]).max(Rgb::ZERO) / (k * (k - 1.0));
                own.max(across)
            })
            .collect();
        (mean, variance)
    }
}

/// Writes the render and error map of a sampler's first run and keeps what the report shows
/// of it.
fn write_first(
    opts: &CompareOptions,
    plan: &Plan,
    kind: LightSamplerKind,
    film: &Film,
    run: &RunResult,
    reference: &Reference,
) -> Result<FirstRun> {
    let size = plan.resolution;
    let pixels = film.means();
    let (exr, err_png) = (opts.out_dir.join(format!("{kind}.exr")), opts.out_dir.join(format!("{kind}-error.png")));
    let stats = crate::render::RenderStats {
        spp: run.spp,
        elapsed: std::time::Duration::from_secs_f64(run.seconds),
        ..Default::default()
    };
    let meta = super::render::provenance(&opts.scene.display().to_string(), kind, &plan.settings(run.seed), &stats);
    crate::io::exr::write(&exr, &film.layers(AovSet::default()), &meta)?;
    let errors = error_picture(size, &relative_error_map(&pixels, &reference.pixels));
    crate::io::png::write_srgb8(&err_png, size, errors.bytes.clone())?;
    let column = SheetColumn {
        title: kind.name().into(),
        caption: format!("{} spp, {:.2} s\nrelMSE {}", run.spp, run.seconds, num(run.rel_mse)),
        render: preview_picture(size, &pixels, opts.exposure),
        error: Some(errors),
    };
    let variance: Vec<Rgb> = (0..pixels.len()).map(|i| film.variance_of_mean(i)).collect();
    let noise = relative_noise(&variance, &pixels);
    Ok(FirstRun { pixels, noise, column, files: vec![file_name(&exr), file_name(&err_png)] })
}

/// Each sampler's efficiency against the best one's.
fn rank(results: &mut [SamplerResult]) {
    let best = results.iter().map(|r| r.efficiency.mean).fold(0.0f64, f64::max);
    for r in results {
        r.efficiency_vs_best = if best > 0.0 { r.efficiency.mean / best } else { 0.0 };
    }
}

/// The last component of `p`, for titles and captions.
pub(crate) fn file_name(p: &Path) -> String {
    p.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned())
}

/// The comparison as an HTML page: every image with its caption, the metrics, the plot, the
/// settings and where the numbers come from.
fn html_page(
    opts: &CompareOptions,
    report: &CompareReport,
    columns: &[SheetColumn],
    images: &[Vec<Rgb>],
    svg: &str,
) -> String {
    let size = UVec2::new(report.resolution[0], report.resolution[1]);
    let images = columns
        .iter()
        .zip(images)
        .map(|(c, pixels)| PageImage { name: c.title.clone(), caption: c.caption.replace('\n', ", "), pixels })
        .collect();
    let seeds: Vec<String> =
        report.samplers.first().map_or(Vec::new(), |s| s.runs.iter().map(|r| r.seed.to_string()).collect());
    let facts = [
        ("scene", report.scene.clone()),
        ("mode", report.mode.clone()),
        ("size", format!("{} × {} px", size.x, size.y)),
        ("max depth", report.max_depth.to_string()),
        ("threads", report.threads.to_string()),
        ("seeds", seeds.join(", ")),
        ("reference", format!("{} ({})", report.reference.path, report.reference.origin)),
    ];
    html::page(&Page {
        title: format!("myriad compare: {} ({})", file_name(&opts.scene), report.mode),
        size,
        images,
        table: report.metrics(),
        plot_svg: Some(svg.to_string()),
        facts: facts.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
        exposure: opts.exposure,
    })
}

/// Writes the contact sheet, the convergence plot, report.md, report.json and report.html
/// (`images`: the reference's, then each column's pixels).
fn write_report(
    opts: &CompareOptions,
    mut report: CompareReport,
    columns: &[SheetColumn],
    images: &[Vec<Rgb>],
) -> Result<CompareReport> {
    let out = |name: &str| opts.out_dir.join(name);
    let (sheet_path, plot_path, md_path, json_path, html_path) =
        (out("contact-sheet.png"), out("convergence.svg"), out("report.md"), out("report.json"), out("report.html"));
    let sheet = contact_sheet(columns);
    crate::io::png::write_srgb8(&sheet_path, sheet.size, sheet.bytes)?;
    let curves: Vec<Curve> = report
        .samplers
        .iter()
        .map(|s| Curve { name: s.sampler.clone(), points: s.runs[0].convergence.clone() })
        .collect();
    let svg = convergence_svg(&format!("{} ({})", file_name(&opts.scene), report.mode), &curves)
        .map_err(|m| Error::Output { path: plot_path.clone(), message: m })?;
    crate::io::write_text(&plot_path, &svg)?;
    report.files = [&sheet_path, &plot_path, &md_path, &json_path, &html_path].iter().map(|p| file_name(p)).collect();
    crate::io::write_text(&html_path, &html_page(opts, &report, columns, images, &svg))?;
    crate::io::write_text(&md_path, &report.markdown(&file_name(&sheet_path), &file_name(&plot_path)))?;
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| Error::Output { path: json_path.clone(), message: e.to_string() })?;
    crate::io::write_text(&json_path, &json)?;
    Ok(report)
}
