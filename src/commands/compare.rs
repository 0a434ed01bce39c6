//! `myriad compare`: render one scene with several light samplers at equal spp or equal
//! time, measure each against a reference, and write renders, error maps, a contact sheet, a
//! convergence plot and reports.
//!
//! Every sampler renders with the same seeds (1..=K), so at equal spp the camera rays and
//! BSDF directions are identical and differences come from the light choice alone. The
//! reference is rendered with a seed no compared run uses (or given), and cached in the
//! output folder under a key of everything that determines it.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::render::progress_bar;
use super::{DEFAULT_MAX_DEPTH, SceneOptions, load_scene};
use crate::compare::images::{SheetColumn, contact_sheet, error_picture, preview_picture};
use crate::compare::metrics::{bias_check, efficiency, error_metrics, relative_error_map};
use crate::compare::plot::{Curve, convergence_svg};
use crate::compare::report::{CompareReport, ReferenceInfo, RunResult, SamplerResult, Stat};
use crate::error::{Error, Result};
use crate::film::{AovSet, Film, Layers};
use crate::fingerprint::Fingerprint;
use crate::interrupt::Stop;
use crate::light_sampler::{LightSamplerKind, LightStrategy};
use crate::math::{Rgb, UVec2};
use crate::render::{Budget, RenderSettings, render};
use crate::scene::{BuildOptions, Scene};

/// The reference's seed: no compared run (seeds 1..=K) uses it.
pub const REFERENCE_SEED: u64 = 0x5eed_0000_0000_0000;
/// Significance of the bias flag (before the Šidák correction over samplers).
pub const BIAS_ALPHA: f64 = 0.001;

/// What to compare and how.
#[derive(Clone, Debug)]
pub struct CompareOptions {
    /// Scene file.
    pub scene: PathBuf,
    /// Samplers, in report order.
    pub samplers: Vec<LightSamplerKind>,
    /// Equal spp or equal time, per sampler and seed.
    pub budget: Budget,
    /// A reference EXR to measure against; otherwise one is rendered (and cached).
    pub reference: Option<PathBuf>,
    /// spp of a rendered reference.
    pub reference_spp: u32,
    /// Sampler of a rendered reference; default: `all` up to 64 lights, `local` up to 10⁴,
    /// `tree` beyond (local's O(n) per point makes it impractical there).
    pub reference_sampler: Option<LightSamplerKind>,
    /// Seeds per sampler (mean ± standard deviation over them).
    pub seeds: u32,
    /// Output folder.
    pub out_dir: PathBuf,
    /// Image size.
    pub resolution: Option<UVec2>,
    /// Maximum scattering events.
    pub max_depth: Option<u32>,
    /// Camera name.
    pub camera: Option<String>,
    /// How to read the scene file.
    pub load: crate::io::LoadOptions,
    /// Exposure of the previews, stops.
    pub exposure: f32,
    /// Show progress bars.
    pub progress: bool,
}

/// The reference image and its per-pixel variance (zero when unknown).
struct Reference {
    pixels: Vec<Rgb>,
    variance: Vec<Rgb>,
    info: ReferenceInfo,
}

fn rgb_of(layers: &Layers, prefix: &str) -> Option<Vec<Rgb>> {
    let ch = |c: &str| layers.channel(&if prefix.is_empty() { c.to_string() } else { format!("{prefix}.{c}") });
    let (r, g, b) = (ch("R")?, ch("G")?, ch("B")?);
    Some((0..r.data.len()).map(|i| Rgb::new(r.data[i], g.data[i], b.data[i])).collect())
}

/// A reference as read from disk: RGB, variance (zeros when absent) and header attributes.
struct ReferenceFile {
    pixels: Vec<Rgb>,
    variance: Vec<Rgb>,
    meta: Vec<(String, String)>,
}

/// Reads an EXR's RGB (and variance when present), checking its size.
fn read_reference(path: &Path, size: UVec2) -> Result<ReferenceFile> {
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
        rgb_of(&layers, "").ok_or_else(|| Error::Input { path: path.into(), message: "no R, G, B channels".into() })?;
    let variance = rgb_of(&layers, "variance").unwrap_or_else(|| vec![Rgb::ZERO; pixels.len()]);
    Ok(ReferenceFile { pixels, variance, meta })
}

fn default_reference_sampler(lights: usize) -> LightSamplerKind {
    match lights {
        0..=64 => LightSamplerKind::All,
        65..=10_000 => LightSamplerKind::Local,
        _ => LightSamplerKind::Tree,
    }
}

/// Everything the rendered reference depends on: the bytes of every file the scene was read
/// from, how it was read and built, every render setting, and this build of myriad.
fn reference_key(opts: &CompareOptions, scene: &Scene, sampler: LightSamplerKind, max_depth: u32) -> Result<String> {
    let mut key = Fingerprint::new("myriad compare reference");
    for input in &scene.inputs {
        key.file(input)?;
    }
    let size = scene.camera.resolution();
    key.value("gltf_scene", format!("{:?}", opts.load.gltf_scene))
        .value("punctual_scale", opts.load.punctual_scale.to_bits())
        .value("camera", opts.camera.as_deref().unwrap_or("-"))
        .value("resolution", format!("{}x{}", size.x, size.y))
        .value("sampler", sampler.name())
        .value("spp", opts.reference_spp)
        .value("max_depth", max_depth)
        .value("seed", REFERENCE_SEED)
        .value("build", crate::fingerprint::build_id());
    Ok(key.finish())
}

/// Loads the given reference, reuses a cached one, or renders and caches a new one.
fn reference(opts: &CompareOptions, scene: &Scene, max_depth: u32) -> Result<Reference> {
    let size = scene.camera.resolution();
    if let Some(path) = &opts.reference {
        let ReferenceFile { pixels, variance, .. } = read_reference(path, size)?;
        let info =
            ReferenceInfo { path: path.display().to_string(), origin: "given".into(), reused: false, seconds: 0.0 };
        return Ok(Reference { pixels, variance, info });
    }
    let sampler = opts.reference_sampler.unwrap_or_else(|| default_reference_sampler(scene.lights.len()));
    let origin = format!("{sampler}, {} spp, seed {REFERENCE_SEED:#x}", opts.reference_spp);
    let key = reference_key(opts, scene, sampler, max_depth)?;
    let path = opts.out_dir.join("reference.exr");
    if path.exists()
        && let Ok(ReferenceFile { pixels, variance, meta }) = read_reference(&path, size)
        && meta.iter().any(|(k, v)| k == "myriad.reference_key" && *v == key)
    {
        let info = ReferenceInfo { path: path.display().to_string(), origin, reused: true, seconds: 0.0 };
        return Ok(Reference { pixels, variance, info });
    }
    let strategy = LightStrategy::build(sampler, &scene.lights, scene.radius);
    let aovs = AovSet { variance: true, ..Default::default() };
    let settings = RenderSettings { budget: Budget::Spp(opts.reference_spp), seed: REFERENCE_SEED, max_depth, aovs };
    let pb = progress_bar(opts.progress, "ref");
    let out = render(scene, &strategy, &settings, Some(&pb), &mut |_, _| {});
    pb.finish_and_clear();
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
        origin,
        reused: false,
        seconds: out.stats.elapsed.as_secs_f64(),
    };
    Ok(Reference { pixels, variance, info })
}

/// Runs the comparison and writes every output into `opts.out_dir`.
pub fn compare(opts: &CompareOptions) -> Result<CompareReport> {
    if opts.samplers.is_empty() || opts.seeds == 0 {
        return Err(Error::Usage("give at least one sampler and one seed".into()));
    }
    let scene_options = SceneOptions {
        load: opts.load,
        build: BuildOptions { resolution: opts.resolution, camera: opts.camera.clone() },
    };
    // The scene must load before the output folder is made: a broken scene leaves nothing.
    let loaded = load_scene(Some(&opts.scene), &scene_options)?;
    // Ctrl-C stops the comparison (after the pass under way) and writes no report.
    let _busy = crate::interrupt::busy();
    crate::io::ensure_dir(&opts.out_dir)?;
    let scene = &loaded.scene;
    let max_depth = opts.max_depth.or(scene.render.max_depth).unwrap_or(DEFAULT_MAX_DEPTH);
    let size = scene.camera.resolution();
    let reference = reference(opts, scene, max_depth)?;
    let out = |name: &str| opts.out_dir.join(name);
    let file = |p: &Path| p.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned());

    let mut results = Vec::new();
    let mut columns = vec![SheetColumn {
        title: "reference".into(),
        caption: reference.info.origin.replacen(", seed", "\nseed", 1),
        render: preview_picture(size, &reference.pixels, opts.exposure),
        error: None,
    }];
    let alpha = 1.0 - (1.0 - BIAS_ALPHA).powf(1.0 / opts.samplers.len() as f64);
    for &kind in &opts.samplers {
        let t = Instant::now();
        let strategy = LightStrategy::build(kind, &scene.lights, scene.radius);
        let build_seconds = t.elapsed().as_secs_f64();
        let mut runs = Vec::new();
        let mut first: Option<Film> = None;
        let (mut mean, mut mean_var) =
            (vec![Rgb::ZERO; reference.pixels.len()], vec![Rgb::ZERO; reference.pixels.len()]);
        let mut sum_sq = vec![Rgb::ZERO; reference.pixels.len()];
        for seed in 1..=opts.seeds as u64 {
            let settings = RenderSettings { budget: opts.budget, seed, max_depth, aovs: AovSet::default() };
            let pb = progress_bar(opts.progress, kind.name());
            let mut convergence = Vec::new();
            let r = render(scene, &strategy, &settings, Some(&pb), &mut |film, elapsed| {
                if let Ok(m) = error_metrics(&film.means(), &reference.pixels) {
                    convergence.push((elapsed.as_secs_f64(), m.rel_mse));
                }
            });
            pb.finish_and_clear();
            if r.stats.stopped != Stop::No {
                return Err(Error::Interrupted);
            }
            let pixels = r.film.means();
            let m = error_metrics(&pixels, &reference.pixels)?;
            let seconds = r.stats.elapsed.as_secs_f64();
            for i in 0..pixels.len() {
                mean[i] += pixels[i] / opts.seeds as f32;
                sum_sq[i] += pixels[i] * pixels[i];
                mean_var[i] += r.film.variance_of_mean(i) / (opts.seeds * opts.seeds) as f32;
            }
            runs.push(RunResult {
                seed,
                seconds,
                spp: r.stats.spp,
                mse: m.mse,
                rel_mse: m.rel_mse,
                efficiency: efficiency(m.rel_mse, seconds),
                convergence,
            });
            first.get_or_insert(r.film);
        }
        if opts.seeds > 1 {
            // The spread across seeds also estimates the variance of the mean, and unlike the
            // films' own estimate it exists at 1 spp; take the larger of the two.
            let k = opts.seeds as f32;
            for i in 0..mean.len() {
                let across = (sum_sq[i] - k * mean[i] * mean[i]).max(Rgb::ZERO) / (k * (k - 1.0));
                mean_var[i] = mean_var[i].max(across);
            }
        }
        let film = first.expect("at least one seed");
        let pixels = film.means();
        let (exr, err_png) = (out(&format!("{kind}.exr")), out(&format!("{kind}-error.png")));
        let meta = super::render::provenance(
            &opts.scene.display().to_string(),
            kind,
            &RenderSettings { budget: opts.budget, seed: 1, max_depth, aovs: AovSet::default() },
            &crate::render::RenderStats {
                spp: runs[0].spp,
                elapsed: std::time::Duration::from_secs_f64(runs[0].seconds),
                ..Default::default()
            },
        );
        crate::io::exr::write(&exr, &film.layers(AovSet::default()), &meta)?;
        let errors = error_picture(size, &relative_error_map(&pixels, &reference.pixels));
        crate::io::png::write_srgb8(&err_png, size, errors.bytes.clone())?;
        let stat = |f: &dyn Fn(&RunResult) -> f64| Stat::of(&runs.iter().map(f).collect::<Vec<_>>());
        let result = SamplerResult {
            sampler: kind.name().into(),
            build_seconds,
            memory_bytes: strategy.memory_bytes(),
            seconds: stat(&|r| r.seconds),
            spp: stat(&|r| r.spp as f64),
            mse: stat(&|r| r.mse),
            rel_mse: stat(&|r| r.rel_mse),
            efficiency: stat(&|r| r.efficiency),
            efficiency_vs_best: 0.0,
            bias: bias_check(&mean, &mean_var, &reference.pixels, &reference.variance, alpha),
            files: vec![file(&exr), file(&err_png)],
            runs,
        };
        columns.push(SheetColumn {
            title: kind.name().into(),
            caption: format!(
                "{} spp, {:.2} s\nrelMSE {}",
                result.runs[0].spp,
                result.runs[0].seconds,
                crate::compare::report::num(result.runs[0].rel_mse)
            ),
            render: preview_picture(size, &pixels, opts.exposure),
            error: Some(errors),
        });
        results.push(result);
    }
    let best = results.iter().map(|r| r.efficiency.mean).fold(0.0f64, f64::max);
    for r in &mut results {
        r.efficiency_vs_best = if best > 0.0 { r.efficiency.mean / best } else { 0.0 };
    }

    let mode = match opts.budget {
        Budget::Spp(n) => format!("equal spp ({n})"),
        Budget::Time(t) => format!("equal time ({} s)", t.as_secs_f64()),
    };
    let mut report = CompareReport {
        scene: opts.scene.display().to_string(),
        mode,
        resolution: [size.x, size.y],
        max_depth,
        threads: rayon::current_num_threads(),
        reference: reference.info,
        samplers: results,
        files: Vec::new(),
    };
    let sheet = contact_sheet(&columns);
    let (sheet_path, plot_path, md_path, json_path) =
        (out("contact-sheet.png"), out("convergence.svg"), out("report.md"), out("report.json"));
    crate::io::png::write_srgb8(&sheet_path, sheet.size, sheet.bytes)?;
    let curves: Vec<Curve> = report
        .samplers
        .iter()
        .map(|s| Curve { name: s.sampler.clone(), points: s.runs[0].convergence.clone() })
        .collect();
    let svg = convergence_svg(&format!("{} ({})", file(&opts.scene), report.mode), &curves)
        .map_err(|m| Error::Output { path: plot_path.clone(), message: m })?;
    crate::io::write_text(&plot_path, &svg)?;
    report.files = [&sheet_path, &plot_path, &md_path, &json_path].iter().map(|p| file(p)).collect();
    crate::io::write_text(&md_path, &report.markdown(&file(&sheet_path), &file(&plot_path)))?;
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| Error::Output { path: json_path.clone(), message: e.to_string() })?;
    crate::io::write_text(&json_path, &json)?;
    Ok(report)
}
