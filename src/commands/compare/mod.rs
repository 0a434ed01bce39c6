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

mod output;
mod plan;
mod reference;
mod runs;

pub use plan::{CompareOptions, DEFAULT_SAMPLERS, REFERENCE_SEED, default_out_dir, run_part};
pub use reference::{MAX_REFERENCE_TIME, NOISY_REFERENCE, REFERENCE_FACTOR, REFERENCE_SAMPLER, read_reference};

use std::io::Write;
use std::time::Duration;

use super::{SceneOptions, human_duration, load_scene};
use crate::compare::images::{SheetColumn, preview_picture};
use crate::compare::report::{CompareReport, SamplerResult};
use crate::error::{Error, Result};
use crate::guiding::GuideStats;
use crate::limits::human_bytes;
use crate::math::Rgb;
use crate::render::Budget;
use crate::scene::{BuildOptions, Scene};
use crate::settings::LightSamplerKind;
use output::write_report;
use plan::{Plan, budget_words, time_per_spp};
use reference::{judge_reference, reference, reference_budget};
use runs::SamplerRuns;

/// Runs the comparison and writes every output into `opts.out_dir`: reference → each sampler
/// with each seed → ranking → contact sheet, plot and reports.
pub fn compare(opts: &CompareOptions) -> Result<CompareReport> {
    let scene_options = SceneOptions {
        load: opts.load,
        build: BuildOptions { resolution: opts.resolution, camera: opts.camera.clone(), ..Default::default() },
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
        Some(_) => super::provenance::scene_fingerprint(&loaded, &scene_options)?,
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
    let guiding = guiding_summary(plan.guiding, samplers.iter().filter_map(|s| s.guide));
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
        clamp: plan.clamp.to_string(),
        guiding,
        caustics: crate::settings::on_off(plan.caustics).to_string(),
        threads: rayon::current_num_threads(),
        reference: reference.info,
        samplers: results,
        files: Vec::new(),
    };
    write_report(opts, report, &columns, &pictures)
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

/// Each sampler's efficiency against the best one's.
fn rank(results: &mut [SamplerResult]) {
    let best = results.iter().map(|r| r.efficiency.mean).fold(0.0f64, f64::max);
    for r in results {
        r.efficiency_vs_best = if best > 0.0 { r.efficiency.mean / best } else { 0.0 };
    }
}

/// The report's word on path guiding: `off`, or `on` with the most any run learned into and
/// the longest it took to learn.
fn guiding_summary(on: bool, stats: impl Iterator<Item = GuideStats>) -> String {
    let (mut memory, mut time, mut regions) = (0, Duration::ZERO, 0);
    for g in stats {
        (memory, time, regions) = (memory.max(g.memory_bytes), time.max(g.learning_time), regions.max(g.regions));
    }
    match on {
        false => "off".into(),
        true => format!(
            "on ({regions} regions, {} learned in {} per run at most)",
            human_bytes(memory as u64),
            human_duration(time)
        ),
    }
}
