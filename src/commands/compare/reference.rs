//! The image a comparison measures against: given, or rendered with a seed no run uses and
//! cached in the output folder under a fingerprint of everything it depends on (reused when
//! the same comparison runs again), and judged for its own noise.

use std::path::Path;
use std::time::Duration;

use super::plan::{CompareOptions, REFERENCE_SEED, budget_words};
use crate::commands::LoadedScene;
use crate::commands::progress::Progress;
use crate::compare::metrics::REL_MSE_EPSILON;
use crate::compare::report::ReferenceInfo;
use crate::error::{Error, Result};
use crate::film::AovSet;
use crate::fingerprint::Fingerprint;
use crate::interrupt::Stop;
use crate::light_sampler::LightStrategy;
use crate::math::{Rgb, UVec2};
use crate::render::{Budget, RenderSettings, render};
use crate::settings::{Clamp, LightSamplerKind};

/// The reference image and its per-pixel variance (zero when unknown).
pub(crate) struct Reference {
    pub(crate) pixels: Vec<Rgb>,
    pub(crate) variance: Vec<Rgb>,
    pub(crate) info: ReferenceInfo,
}

/// A reference as read from disk: RGB, variance (zeros when absent) and header attributes.
pub struct ReferenceFile {
    /// Its RGB.
    pub pixels: Vec<Rgb>,
    /// Its variance layer (zeros when absent).
    pub variance: Vec<Rgb>,
    /// Its header attributes.
    pub meta: Vec<(String, String)>,
}

/// Reads an EXR's RGB (and variance when present), checking its size.
pub fn read_reference(path: &Path, size: UVec2) -> Result<ReferenceFile> {
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
pub(crate) fn reference_budget(opts: &CompareOptions, runs: Budget, per_spp: Duration) -> Budget {
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

/// Everything the rendered reference depends on: the bytes of every file the scene was read
/// from, how it was read and built, every render setting, and this build of myriad.
pub(crate) fn reference_key(
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
pub(crate) fn reference(
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
    // Never clamped: the reference is the unbiased picture.
    let settings = RenderSettings {
        budget,
        seed: REFERENCE_SEED,
        max_depth,
        clamp: Clamp::OFF,
        guiding: false,
        caustics: true,
        resolution: size,
        aovs,
    };
    let out = render(scene, &strategy, &settings, &mut Progress::new(opts.progress, "ref"));
    // A reference stopped short is not the reference its key describes.
    if out.stats.stopped != Stop::No {
        return Err(Error::Interrupted);
    }
    let mut meta = crate::commands::provenance::provenance(
        &opts.scene.display().to_string(),
        sampler,
        scene.geometry.accel.tracer().name(),
        &settings,
        &out.stats,
    );
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

/// An image's noise as relMSE would see it: the mean over pixels of its variance of the mean
/// over (`image`² + ε), `image` a low-noise estimate of the truth.
pub(crate) fn relative_noise(variance: &[Rgb], image: &[Rgb]) -> f64 {
    variance
        .iter()
        .zip(image)
        .map(|(v, p)| (0..3).map(|c| v[c] as f64 / ((p[c] as f64).powi(2) + REL_MSE_EPSILON)).sum::<f64>() / 3.0)
        .sum::<f64>()
        / image.len().max(1) as f64
}

/// Measures the reference's own noise against the least noisy run's (both over that run's
/// image, so a noisy reference does not judge itself): flagged beyond [`NOISY_REFERENCE`].
pub(crate) fn judge_reference(info: &mut ReferenceInfo, variance: &[Rgb], image: &[Rgb], run_noise: f64) {
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
