//! One sampler's runs, seed after seed: each rendered (or read from a part rendered
//! elsewhere), measured against the reference, and summed into the statistics over seeds;
//! the first run's render and error map are written as soon as it is done.

use std::path::Path;
use std::time::Instant;

use super::plan::{CompareOptions, Plan, run_part};
use super::reference::{Reference, relative_noise};
use crate::commands::progress::Progress;
use crate::commands::{LoadedScene, file_name};
use crate::compare::images::{SheetColumn, error_picture, preview_picture};
use crate::compare::metrics::{
    TRIMMED_SHARE, bias_check, efficiency, error_metrics, relative_error_map, trimmed_rel_mse,
};
use crate::compare::report::{RunResult, SamplerResult, Stat, num};
use crate::error::{Error, Result};
use crate::film::{AovSet, Film};
use crate::guiding::GuideStats;
use crate::interrupt::Stop;
use crate::light_sampler::LightStrategy;
use crate::math::{Rgb, UVec2};
use crate::render::{RenderObserver, render};
use crate::scene::Scene;
use crate::settings::{LightSamplerKind, on_off};

/// One sampler's renders, seed after seed: its strategy built once, each run's numbers, the
/// statistics over seeds, and what the first seed's run left for the report.
pub(crate) struct SamplerRuns {
    pub(crate) kind: LightSamplerKind,
    pub(crate) strategy: LightStrategy,
    pub(crate) build_seconds: f64,
    /// The most the strategy held in any run (a learning one holds more once it has learned).
    pub(crate) memory_bytes: usize,
    /// What path guiding learned in the run that learned most (guided runs only).
    pub(crate) guide: Option<GuideStats>,
    pub(crate) runs: Vec<RunResult>,
    pub(crate) seeds: SeedStatistics,
    pub(crate) first: Option<FirstRun>,
}

/// The first seed's run, once its render and error map are written: what the report and the
/// contact sheet show of it.
pub(crate) struct FirstRun {
    pub(crate) pixels: Vec<Rgb>,
    /// Its own noise (relMSE of its variance of the mean), to judge the reference by.
    pub(crate) noise: f64,
    pub(crate) column: SheetColumn,
    pub(crate) files: Vec<String>,
}

/// Watches one run: its progress bar, and the relMSE after every pass.
pub(crate) struct Convergence<'a> {
    pub(crate) progress: Progress,
    pub(crate) reference: &'a [Rgb],
    pub(crate) points: Vec<(f64, f64)>,
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
pub(crate) struct Run {
    pub(crate) film: Film,
    pub(crate) seconds: f64,
    pub(crate) convergence: Vec<(f64, f64)>,
}

/// Renders one run of `strategy` with `seed`.
pub(crate) fn render_run(
    opts: &CompareOptions,
    plan: &Plan,
    scene: &Scene,
    strategy: &LightStrategy,
    kind: LightSamplerKind,
    seed: u64,
    reference: &Reference,
) -> Result<(Run, usize, Option<GuideStats>)> {
    let mut watch = Convergence {
        progress: Progress::new(opts.progress, kind.name()),
        reference: &reference.pixels,
        points: vec![],
    };
    let name = format!("{kind} seed {seed}");
    let mut display =
        opts.display.as_deref().map(|a| crate::commands::display::TevStream::connect(a, &name, AovSet::default()));
    let r = render(scene, strategy, &plan.settings(seed), &mut (&mut watch, &mut display));
    if r.stats.stopped != Stop::No {
        return Err(Error::Interrupted);
    }
    let memory = r.stats.learned.map_or(0, |l| l.memory_bytes);
    let run = Run { film: r.film, seconds: r.stats.elapsed.as_secs_f64(), convergence: watch.points };
    Ok((run, memory, r.stats.guide))
}

/// Reads one run rendered elsewhere (see [`CompareOptions::runs`]), checking that it is the
/// run this plan would render.
pub(crate) fn load_run(dir: &Path, plan: &Plan, scene_hash: &str, kind: LightSamplerKind, seed: u64) -> Result<Run> {
    let path = run_part(dir, kind, seed);
    let (h, film) = crate::io::part::read(&path)?;
    let spp = plan.budget.fixed().map_or(0, |f| f.1);
    let wanted = [
        ("sampler", h.sampler.clone(), kind.name().to_string()),
        ("seed", h.seed.to_string(), seed.to_string()),
        ("samples", format!("{}..{}", h.samples[0], h.samples[1]), format!("0..{spp}")),
        ("max depth", h.max_depth.to_string(), plan.max_depth.to_string()),
        ("clamp", h.clamp.to_string(), plan.clamp.to_string()),
        ("guiding", on_off(h.guiding).into(), on_off(plan.guiding).into()),
        ("caustics", on_off(h.caustics).into(), on_off(plan.caustics).into()),
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
    pub(crate) fn build(kind: LightSamplerKind, scene: &Scene, size: UVec2) -> Self {
        let t = Instant::now();
        let strategy = LightStrategy::build(kind, &scene.lights, scene.center, scene.radius);
        let build_seconds = t.elapsed().as_secs_f64();
        let memory_bytes = strategy.memory_bytes();
        let seeds = SeedStatistics::new((size.x * size.y) as usize);
        Self { kind, strategy, build_seconds, memory_bytes, guide: None, runs: Vec::new(), seeds, first: None }
    }

    /// Renders (or, with `runs`, reads) the run with `seed` and measures it against the
    /// reference; the first one's render and error map are written.
    pub(crate) fn run(
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
                let (run, memory, guide) = render_run(opts, plan, &loaded.scene, &fresh, kind, seed, reference)?;
                self.memory_bytes = self.memory_bytes.max(memory).max(fresh.memory_bytes());
                if let Some(g) = guide
                    && self.guide.is_none_or(|h| g.memory_bytes > h.memory_bytes)
                {
                    self.guide = Some(g);
                }
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
            let named = (kind, self.strategy.label(kind));
            self.first = Some(write_first(opts, plan, named, &run.film, &result, reference)?);
        }
        self.runs.push(result);
        Ok(())
    }

    /// The sampler's numbers over its seeds, its contact-sheet column and its first image.
    pub(crate) fn finish(self, plan: &Plan, reference: &Reference) -> (SamplerResult, SheetColumn, Vec<Rgb>) {
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
            label: self.strategy.label(self.kind),
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
pub(crate) struct SeedStatistics {
    pub(crate) count: u32,
    pub(crate) sum: Vec<Rgb>,
    pub(crate) sum_sq: Vec<Rgb>,
    /// Σ of the films' own variance-of-the-mean estimates.
    pub(crate) film_variance: Vec<Rgb>,
}

impl SeedStatistics {
    pub(crate) fn new(pixels: usize) -> Self {
        Self {
            count: 0,
            sum: vec![Rgb::ZERO; pixels],
            sum_sq: vec![Rgb::ZERO; pixels],
            film_variance: vec![Rgb::ZERO; pixels],
        }
    }

    pub(crate) fn add(&mut self, film: &Film) {
        self.count += 1;
        for (i, p) in film.means().into_iter().enumerate() {
            self.sum[i] += p;
            self.sum_sq[i] += p * p;
            self.film_variance[i] += film.variance_of_mean(i);
        }
    }

    /// The mean, and its variance: the films' own estimate, or with several seeds the
    /// spread across them where larger (unlike the films' estimate it exists at 1 spp).
    pub(crate) fn finish(self) -> (Vec<Rgb>, Vec<Rgb>) {
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
pub(crate) fn write_first(
    opts: &CompareOptions,
    plan: &Plan,
    (kind, label): (LightSamplerKind, String),
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
    let meta = crate::commands::provenance::provenance(
        &opts.scene.display().to_string(),
        kind,
        plan.tracer,
        &plan.settings(run.seed),
        &stats,
    );
    crate::io::exr::write(&exr, &film.layers(AovSet::default()), &meta)?;
    let errors = error_picture(size, &relative_error_map(&pixels, &reference.pixels));
    crate::io::png::write_srgb8(&err_png, size, errors.bytes.clone())?;
    let column = SheetColumn {
        title: label,
        caption: format!("{} spp, {:.2} s\nrelMSE {}", run.spp, run.seconds, num(run.rel_mse)),
        render: preview_picture(size, &pixels, opts.exposure),
        error: Some(errors),
    };
    let variance: Vec<Rgb> = (0..pixels.len()).map(|i| film.variance_of_mean(i)).collect();
    let noise = relative_noise(&variance, &pixels);
    Ok(FirstRun { pixels, noise, column, files: vec![file_name(&exr), file_name(&err_png)] })
}
