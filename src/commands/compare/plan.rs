//! What a comparison renders, every choice made before the first render: the options as
//! asked, the samplers in report order, each run's budget, depth and seeds, and where runs
//! rendered elsewhere (`myriad slurm --compare`) and `compare`'s outputs live.

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::commands::settings::{COMPARE_DEFAULT_SPP, RenderRequest, Resolved};
use crate::compare::metrics::BIAS_ALPHA;
use crate::error::{Error, Result};
use crate::film::AovSet;
use crate::light_sampler::LightStrategy;
use crate::math::UVec2;
use crate::render::{Budget, RenderSettings, render};
use crate::scene::{Scene, SceneReport};
use crate::settings::{Clamp, LightSamplerKind};

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

/// The part file of one (sampler, seed) run in a runs folder.
pub fn run_part(dir: &Path, kind: LightSamplerKind, seed: u64) -> PathBuf {
    dir.join(format!("{}-{seed}.part", kind.name()))
}

/// Where `compare` writes for `scene` unless told (`compare-NAME` in the current folder,
/// NAME the file's stem; `compare-scene` for the built-in one), and where `view` looks for
/// the reference it cached.
pub fn default_out_dir(scene: Option<&Path>) -> PathBuf {
    let stem = scene.and_then(|s| s.file_stem()).map_or("scene".into(), |s| s.to_string_lossy());
    PathBuf::from(format!("compare-{stem}"))
}

/// What the comparison renders, every choice made: the samplers in report order, the
/// budget and depth of each run, and the seeds each sampler renders with.
pub(crate) struct Plan {
    pub(crate) samplers: Vec<LightSamplerKind>,
    pub(crate) budget: Budget,
    pub(crate) max_depth: u32,
    /// The runs' sample clamping (the reference is never clamped: the bias check then shows
    /// what clamping costs).
    pub(crate) clamp: Clamp,
    /// Whether the runs are guided.
    pub(crate) guiding: bool,
    /// Whether the runs solve for light through smooth glass (the reference always does).
    pub(crate) caustics: bool,
    pub(crate) resolution: UVec2,
    pub(crate) seeds: Vec<u64>,
    /// The ray tracer the scene was built for, for the provenance.
    pub(crate) tracer: &'static str,
}

impl Plan {
    /// The command line's choices over the scene's, over the defaults.
    pub(crate) fn new(opts: &CompareOptions, report: &SceneReport) -> Result<Self> {
        let Resolved { budget, seed, max_depth, clamp, guiding, caustics, .. } =
            opts.settings.resolve(&report.render, COMPARE_DEFAULT_SPP)?;
        let samplers = opts.samplers.clone().unwrap_or_else(|| {
            let mut samplers = DEFAULT_SAMPLERS.to_vec();
            samplers.extend(report.render.sampler.filter(|s| !samplers.contains(s)));
            samplers
        });
        if samplers.is_empty() || opts.seeds == 0 {
            return Err(Error::Usage("give at least one sampler and one seed".into()));
        }
        let what = format!("{} sampler(s) × --seeds {}", samplers.len(), opts.seeds);
        crate::limits::check_runs(samplers.len() as u64 * opts.seeds as u64, what).map_err(Error::Usage)?;
        let seeds = (1..=opts.seeds as u64).map(|k| seed.wrapping_add(k)).collect();
        let tracer = report.stats.tracer;
        let resolution = report.resolution;
        Ok(Self { samplers, budget, max_depth, clamp, guiding, caustics, resolution, seeds, tracer })
    }

    pub(crate) fn settings(&self, seed: u64) -> RenderSettings {
        let Plan { budget, max_depth, clamp, guiding, caustics, resolution, .. } = *self;
        RenderSettings { budget, seed, max_depth, clamp, guiding, caustics, resolution, aovs: AovSet::default() }
    }

    /// The bias flag's level for one sampler: [`BIAS_ALPHA`] over all of them (Šidák).
    pub(crate) fn bias_alpha(&self) -> f64 {
        1.0 - (1.0 - BIAS_ALPHA).powf(1.0 / self.samplers.len() as f64)
    }

    pub(crate) fn mode(&self) -> String {
        match self.budget {
            Budget::Spp(n) | Budget::Samples(0, n) => format!("equal spp ({n})"),
            Budget::Samples(a, b) => format!("equal samples ({a}..{b})"),
            Budget::Time(t) => format!("equal time ({} s)", t.as_secs_f64()),
        }
    }
}

/// The budget in words.
pub(crate) fn budget_words(b: Budget) -> String {
    match b {
        Budget::Time(t) => format!("{:.0} s", t.as_secs_f64()),
        _ => format!("{} spp", b.fixed().map_or(0, |f| f.1)),
    }
}

/// Wall time of one sample per pixel of `kind` over the plan's image (a short timing pass
/// for the estimates; its image is dropped).
pub(crate) fn time_per_spp(scene: &Scene, kind: LightSamplerKind, plan: &Plan) -> Duration {
    let strategy = LightStrategy::build(kind, &scene.lights, scene.center, scene.radius);
    let settings = RenderSettings { budget: Budget::Spp(1), ..plan.settings(REFERENCE_SEED) };
    render(scene, &strategy, &settings, &mut ()).stats.elapsed
}
