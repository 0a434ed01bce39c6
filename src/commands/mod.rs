//! The user-facing commands as library functions: what `myriad render`, `info`, `compare` and
//! `diff` do, minus argument parsing and printing (which stay in `main.rs`).
//!
//! Owns: loading a scene from a path or the built-in default, resolving settings (command
//! line over scene file over myriad's defaults), timing every stage, and the reports the
//! binary prints. Tests call these functions exactly as the binary does.

pub mod compare;
pub mod diff;
pub mod display;
pub mod info;
pub mod merge;
pub mod progress;
pub mod provenance;
pub mod render;
pub mod settings;
pub mod slurm;
pub mod view;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::error::Result;
use crate::io::LoadOptions;
use crate::scene::{self, BuildOptions, Scene, SceneDescription, SceneReport};

/// The scene built into the binary: the predecessor project's Cornell box with a 5 × 5 ceiling grid.
pub const DEFAULT_SCENE: &str = include_str!("../../scenes/cornell-5x5.ron");

/// Name under which [`DEFAULT_SCENE`] appears in messages and file headers.
pub const DEFAULT_SCENE_NAME: &str = "<built-in cornell-5x5>";

/// How to read and build a scene.
#[derive(Clone, Debug, Default)]
pub struct SceneOptions {
    /// Reading the file (glTF scene, punctual light units).
    pub load: LoadOptions,
    /// Building it (resolution, camera).
    pub build: BuildOptions,
}

impl From<BuildOptions> for SceneOptions {
    fn from(build: BuildOptions) -> Self {
        Self { build, load: LoadOptions::default() }
    }
}

/// A scene loaded and built, with what the build found and how long each stage took.
pub struct LoadedScene {
    /// The scene.
    pub scene: Scene,
    /// Source, camera, the file's settings, counts, warnings, files read.
    pub report: SceneReport,
    /// Time to read and parse the file(s).
    pub load_time: Duration,
}

/// Reads the scene at `path` (or the built-in default when `None`).
pub fn load_description(path: Option<&Path>, options: &LoadOptions) -> Result<SceneDescription> {
    match path {
        Some(p) => crate::io::load_scene(p, options),
        None => crate::io::ron::parse(DEFAULT_SCENE, DEFAULT_SCENE_NAME, Path::new("."), options),
    }
}

/// Loads and builds a scene (BVH built in the current rayon pool).
pub fn load_scene(path: Option<&Path>, options: &SceneOptions) -> Result<LoadedScene> {
    let start = Instant::now();
    let desc = load_description(path, &options.load)?;
    let load_time = start.elapsed();
    let source = desc.source.clone();
    let (scene, report) = crate::guard::contain(&source, || scene::build(desc, &options.build))?;
    Ok(LoadedScene { scene, report, load_time })
}

/// `out.exr` → `out.png`.
pub fn preview_path(exr: &Path) -> PathBuf {
    exr.with_extension("png")
}

/// Formats a duration for people.
pub fn human_duration(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s >= 100.0 {
        format!("{:.0} s", s)
    } else if s >= 1.0 {
        format!("{s:.2} s")
    } else {
        format!("{:.1} ms", s * 1e3)
    }
}

/// Formats a rate (per second) with an SI prefix.
pub fn human_rate(r: f64) -> String {
    if r >= 1e9 {
        format!("{:.2} G", r / 1e9)
    } else if r >= 1e6 {
        format!("{:.2} M", r / 1e6)
    } else if r >= 1e3 {
        format!("{:.1} k", r / 1e3)
    } else {
        format!("{r:.1} ")
    }
}

/// The last component of `p`, for titles and captions.
pub fn file_name(p: &Path) -> String {
    p.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned())
}
