//! What an output says about how it was made: the provenance attributes of an EXR, and the
//! identity of a part (a render of one sample range) that `merge` checks parts against.
//!
//! Owns: [`image_provenance`] and [`provenance`] (the `myriad.*` header attributes every
//! written image carries), [`scene_fingerprint`] (the scene a render saw, by contents), and
//! [`part_path`] / [`part_header`] (where a part goes and what it says of itself). `render`,
//! `merge`, `compare` and `view` all write through here, so they agree.

use std::path::{Path, PathBuf};

use super::{LoadedScene, SceneOptions};
use crate::error::Result;
use crate::fingerprint::{Fingerprint, revision};
use crate::io::part::PartHeader;
use crate::render::{RenderSettings, RenderStats};
use crate::settings::{Clamp, LightSamplerKind};

/// Header attributes recording how an image was made: this myriad's version and git
/// revision, the scene, the sampler, the ray tracer, spp, seed, depth and, when they are
/// not the default, the sample clamping (which biases the image), path guiding and light
/// through glass left unsolved.
#[allow(clippy::too_many_arguments)]
pub fn image_provenance(
    scene: &str,
    sampler: &str,
    tracer: &str,
    spp: u32,
    seed: u64,
    max_depth: u32,
    clamp: Clamp,
    guiding: bool,
    caustics: bool,
) -> Vec<(String, String)> {
    let clamped = clamp.is_on().then(|| ("myriad.clamp", clamp.to_string()));
    let guided = guiding.then(|| ("myriad.guiding", "on".to_string()));
    let unsolved = (!caustics).then(|| ("myriad.caustics", "off".to_string()));
    [
        ("myriad.version", env!("CARGO_PKG_VERSION").to_string()),
        ("myriad.git_revision", env!("MYRIAD_GIT_REVISION").to_string()),
        ("myriad.scene", scene.to_string()),
        ("myriad.sampler", sampler.to_string()),
        ("myriad.tracer", tracer.to_string()),
        ("myriad.spp", spp.to_string()),
        ("myriad.seed", seed.to_string()),
        ("myriad.max_depth", max_depth.to_string()),
    ]
    .into_iter()
    .chain(clamped)
    .chain(guided)
    .chain(unsolved)
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

/// A render's [`image_provenance`] and its render time; `tracer`: the scene's
/// (`SceneStats::tracer`).
pub fn provenance(
    scene: &str,
    sampler: LightSamplerKind,
    tracer: &str,
    settings: &RenderSettings,
    stats: &RenderStats,
) -> Vec<(String, String)> {
    let s = settings;
    let (name, spp) = (sampler.name(), stats.spp);
    let mut meta = image_provenance(scene, name, tracer, spp, s.seed, s.max_depth, s.clamp, s.guiding, s.caustics);
    meta.push(("myriad.render_seconds".into(), format!("{:.6}", stats.elapsed.as_secs_f64())));
    meta
}

/// Where the part of samples `a..b` goes for `-o output`: `output` itself when it ends in
/// `.part`, else beside it as `<stem>.samples-A-B.part`.
pub fn part_path(output: &Path, (a, b): (u32, u32)) -> PathBuf {
    if output.extension().is_some_and(|e| e.eq_ignore_ascii_case("part")) {
        return output.to_path_buf();
    }
    let stem = output.file_stem().map_or("myriad".into(), |s| s.to_string_lossy().into_owned());
    output.with_file_name(format!("{stem}.samples-{a}-{b}.part"))
}

/// Fingerprint of the scene a render sees: the contents of every file it read (not their
/// paths, so another machine's copy matches), how it was read, the camera and the size.
pub fn scene_fingerprint(loaded: &LoadedScene, options: &SceneOptions) -> Result<String> {
    let mut key = Fingerprint::new("myriad scene");
    for (i, input) in loaded.report.inputs.iter().enumerate() {
        key.contents(&format!("input {i}"), input)?;
    }
    let size = loaded.report.resolution;
    key.value("gltf_scene", format!("{:?}", options.load.gltf_scene))
        .value("punctual_scale", options.load.punctual_scale.to_bits())
        .value("camera", options.build.camera.as_deref().unwrap_or("-"))
        .value("resolution", format!("{}x{}", size.x, size.y));
    Ok(key.finish())
}

/// The header of the part a render of samples `samples` wrote with `tracer`.
pub fn part_header(
    scene: &str,
    scene_hash: String,
    sampler: LightSamplerKind,
    tracer: &str,
    settings: &RenderSettings,
    samples: (u32, u32),
    stats: &RenderStats,
) -> PartHeader {
    PartHeader {
        myriad: revision().to_string(),
        scene: scene.to_string(),
        scene_hash,
        sampler: sampler.name().to_string(),
        tracer: tracer.to_string(),
        seed: settings.seed,
        max_depth: settings.max_depth,
        clamp: settings.clamp,
        guiding: settings.guiding,
        caustics: settings.caustics,
        light_paths: stats.light_path_lights > 0,
        resolution: settings.resolution.to_array(),
        aovs: settings.aovs.names(),
        samples: [samples.0, samples.1],
        render_seconds: stats.elapsed.as_secs_f64(),
    }
}
