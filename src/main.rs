//! The `myriad` command line: parses arguments, calls the library, prints reports. No math.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::builder::TypedValueParser;
use clap::{Args, Parser, Subcommand};
use myriad::commands::compare::CompareOptions;
use myriad::commands::diff::diff;
use myriad::commands::settings::RenderRequest;
use myriad::commands::{self, SceneOptions, info::info, render::RenderOptions};
use myriad::film::AovSet;
use myriad::geometry::TracerKind;
use myriad::io::LoadOptions;
use myriad::math::UVec2;
use myriad::scene::{BuildOptions, MAX_RESOLUTION};
use myriad::settings::{Clamp, LightSamplerKind};

/// myriad: a path tracer for scenes lit by very many lights.
///
/// Renders .ron scenes (with procedural light grids), glTF (.gltf, .glb) and .obj files to EXR, choosing
/// lights with one of several samplers (all, uniform, power, local, tree, learned, cells), compares the
/// samplers on your own scenes (`myriad compare`), streams to tev (`--display`), and splits a
/// render into sample ranges for a cluster (`--samples`, `merge`, `slurm`).
#[derive(Parser)]
#[command(version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Worker threads, 1 to 1024 (default: all cores). Results are identical for any value.
    #[arg(long, global = true, value_parser = clap::value_parser!(u16).range(1..=1024))]
    threads: Option<u16>,
    /// Most memory, in GB, a scene, an image or a file may make myriad allocate; larger
    /// inputs are refused before allocating [default: 3/4 of what the machine lets the
    /// process use; also MYRIAD_MAX_MEMORY].
    #[arg(long, global = true, value_parser = parse_gigabytes)]
    max_memory: Option<u64>,
    /// Replace output files even where they are read-only (without it, a read-only file is
    /// a file someone wanted kept, and myriad refuses to replace it).
    #[arg(long, global = true)]
    force: bool,
    /// Ray tracer: embree (Intel Embree, where this myriad was built with it: the fastest
    /// here), builtin (myriad's own), best (embree if built, else builtin). Images agree up
    /// to the last bits of hit points [default: MYRIAD_TRACER, else best].
    #[arg(long, global = true, value_parser = parse_tracer)]
    tracer: Option<TracerKind>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to EXR (linear RGB + optional AOVs) and a PNG preview.
    ///
    /// Without SCENE, renders the built-in Cornell box with a 5x5 grid of ceiling lights.
    /// Settings not given here come from the scene file's `render` block, then defaults
    /// (64 spp, max depth 8, sampler cells, seed 0).
    #[command(mut_arg("spp", |a| a.help("Samples per pixel [default: the scene's, else 64]")))]
    #[command(mut_arg("time", |a| a.help("Render whole passes until this many seconds are spent, instead of a fixed spp")))]
    Render(RenderArgs),
    /// Render a scene with several light samplers and measure each against a reference.
    ///
    /// Every sampler renders with the same seeds (equal spp: identical camera rays and BSDF
    /// directions, so differences come from the light choice alone), or for the same time.
    /// Writes each render, a false-colour error map, a labelled contact sheet, a plot of relMSE
    /// against time (SVG), report.md, report.json and report.html (a page to flip, zoom and
    /// read the images) to the output folder, and prints the table.
    #[command(mut_arg("spp", |a| a.help("Samples per pixel of every run: equal spp [default: the scene's, else 16]")))]
    #[command(mut_arg("time", |a| a.help("Seconds every run renders (whole passes), per sampler and seed: equal time")))]
    #[command(mut_arg("seed", |a| a.help("Base seed: the runs use the K seeds after it (--seeds K)")))]
    #[command(mut_arg("exposure", |a| a.help("Exposure of the previews, the contact sheet and the report page, in stops")))]
    Compare(CompareArgs),
    /// MSE and relMSE of IMAGE against REFERENCE (EXR files of the same size).
    Diff {
        /// The image to judge.
        image: PathBuf,
        /// The reference.
        reference: PathBuf,
        /// Write a false-colour relative-error PNG here.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write a self-contained HTML page here to flip between the two, zoom, change the
        /// exposure and see the error maps and pixel values (as compare's report.html).
        #[arg(long)]
        html: Option<PathBuf>,
    },
    /// Join the parts of a render split into sample ranges into one EXR.
    ///
    /// Each part comes from `myriad render SCENE --samples A..B` (on any machine, e.g. one
    /// Slurm array task each). The parts must come from the same myriad revision, scene
    /// contents and settings, with disjoint ranges; the image is bit-identical to one render
    /// of all their samples.
    Merge(MergeArgs),
    /// Write (and with --submit, submit) a render as a Slurm job array and a merge job.
    ///
    /// Task i of the array renders its range of the samples (`render --samples`) to
    /// OUT/parts/part-i.part; the merge job, which waits for every task (afterok), joins them
    /// into OUT/SCENE.exr, bit-identical to one render. The scene, the myriad binary and OUT
    /// must be on a file system every node sees.
    Slurm(SlurmArgs),
    /// Watch a scene converge in a window, switching light samplers live.
    ///
    /// The render refines pass after pass (1 spp at first, so an image appears at once) until
    /// --spp or --time, if given. Keys: 1-7 pick the sampler (all, uniform, power, local,
    /// tree, learned, cells; the accumulation restarts), + and - change the exposure, E flips to the
    /// false-colour relative error against the reference (--reference, or the one `myriad
    /// compare` cached in compare-NAME/), S saves the image so far as
    /// OUT-DIR/view-SAMPLER-Nspp.exr, R puts the camera back, Esc or Q closes. Mouse: drag
    /// to orbit, right-drag (or shift-drag) to pan, wheel to dolly. The image at N spp is
    /// the one `myriad render --spp N` makes with the same seed. Needs a display (X11).
    #[command(mut_arg("spp", |a| a.help("Stop refining at this many samples per pixel [default: no limit]")))]
    #[command(mut_arg("time", |a| a.help("Stop refining after this many seconds [default: no limit]")))]
    #[command(mut_arg("exposure", |a| a.help("Starting exposure, in stops (+ and - change it in the window)")))]
    #[command(mut_arg("quiet", |a| a.help("Print nothing on stderr while the window is open")))]
    View(ViewArgs),
    /// Load a scene and report what it holds: triangles, lights, power, build times, memory.
    Info {
        /// Scene file (.ron, .obj, .gltf or .glb); default: the built-in Cornell box.
        scene: Option<PathBuf>,
        /// Camera to use, by name (default: the scene's first); `auto` frames the whole scene.
        #[arg(long)]
        camera: Option<String>,
        #[command(flatten)]
        load: LoadArgs,
    },
}

#[derive(Args)]
struct ViewArgs {
    /// Scene file (.ron, .obj, .gltf or .glb); default: the built-in Cornell box.
    scene: Option<PathBuf>,
    /// The light sampler to start with.
    #[arg(long, value_parser = sampler_parser())]
    sampler: Option<LightSamplerKind>,
    /// Reference EXR for the error view (E), of the view's size.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Folder the save key (S) writes to.
    #[arg(long, default_value = ".")]
    out_dir: PathBuf,
    /// Close the window once --spp or --time is reached (for scripts and benchmarks).
    #[arg(long)]
    exit_when_done: bool,
    #[command(flatten)]
    common: CommonArgs,
}

#[derive(Args)]
struct RenderArgs {
    /// Scene file (.ron, .obj, .gltf or .glb); default: the built-in Cornell box.
    scene: Option<PathBuf>,
    /// Output EXR.
    #[arg(short, long, default_value = "myriad.exr")]
    output: PathBuf,
    /// How next-event estimation picks lights.
    #[arg(long, value_parser = sampler_parser())]
    sampler: Option<LightSamplerKind>,
    /// PNG preview path (default: the EXR path with .png).
    #[arg(long)]
    png: Option<PathBuf>,
    /// Do not write a PNG preview.
    #[arg(long, conflicts_with = "png")]
    no_png: bool,
    /// Extra EXR channels, comma-separated: albedo, normal, depth, variance.
    #[arg(long, value_delimiter = ',', value_parser = ["albedo", "normal", "depth", "variance"])]
    aov: Vec<String>,
    /// Stream the image to a running tev viewer after every pass (tev's TCP protocol; AOVs
    /// as extra channels) [default address: 127.0.0.1:14158]. Nothing listening: a warning,
    /// and the render goes on.
    #[arg(long, value_name = "[HOST:]PORT", num_args = 0..=1, default_missing_value = commands::display::DEFAULT_DISPLAY)]
    display: Option<String>,
    /// Render only samples A to B−1 of every pixel (exactly the samples a full render takes
    /// there) and write them as a part file for `myriad merge`: to -o when it ends in .part,
    /// else beside it as NAME.samples-A-B.part. No image and no preview are written.
    #[arg(long, value_name = "A..B", value_parser = parse_samples, conflicts_with_all = ["spp", "time"])]
    samples: Option<(u32, u32)>,
    #[command(flatten)]
    common: CommonArgs,
}

#[derive(Args)]
struct SlurmArgs {
    /// Scene file (.ron, .obj, .gltf or .glb).
    scene: PathBuf,
    /// Samples per pixel of the whole render.
    #[arg(long, value_parser = parse_count, allow_negative_numbers = true)]
    spp: u32,
    /// Array tasks: the samples are cut into this many ranges (not for --compare).
    #[arg(long, required_unless_present = "compare", value_parser = parse_count, allow_negative_numbers = true)]
    tasks: Option<u32>,
    /// Job folder (default: slurm-<scene name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Submit both jobs with sbatch and print their ids.
    #[arg(long)]
    submit: bool,
    /// sbatch --partition for both jobs.
    #[arg(long)]
    partition: Option<String>,
    /// sbatch --time (Slurm's time limit per job, e.g. 1:00:00).
    #[arg(long)]
    time: Option<String>,
    /// sbatch --cpus-per-task; each task renders with that many threads.
    #[arg(long, value_parser = parse_count, allow_negative_numbers = true)]
    cpus_per_task: Option<u32>,
    /// sbatch --mem per task (e.g. 4G).
    #[arg(long)]
    mem: Option<String>,
    /// Light sampler of the render.
    #[arg(long, value_parser = sampler_parser())]
    sampler: Option<LightSamplerKind>,
    /// Random seed.
    #[arg(long, value_parser = parse_seed, allow_negative_numbers = true)]
    seed: Option<u64>,
    /// Maximum scattering events.
    #[arg(long, value_parser = parse_count, allow_negative_numbers = true)]
    max_depth: Option<u32>,
    /// Sample clamping: INDIRECT or DIRECT,INDIRECT.
    #[arg(long, value_parser = parse_clamp, allow_negative_numbers = true)]
    clamp: Option<Clamp>,
    /// Path guiding: on or off.
    #[arg(long, value_parser = parse_on_off)]
    guiding: Option<bool>,
    /// Caustics (light through smooth glass, point and spot lights' highlights off glossy
    /// surfaces) solved for: on or off.
    #[arg(long, value_parser = parse_on_off)]
    caustics: Option<bool>,
    /// Output size, e.g. 640x480.
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<UVec2>,
    /// Camera, by name.
    #[arg(long)]
    camera: Option<String>,
    /// Extra EXR channels, comma-separated: albedo, normal, depth, variance.
    #[arg(long, value_delimiter = ',', value_parser = ["albedo", "normal", "depth", "variance"])]
    aov: Vec<String>,
    /// Compare these samplers (comma-separated) instead of rendering one image: one task per
    /// sampler and seed at --spp, one for the reference, and a report job (`myriad compare
    /// --runs`) whose metrics equal a one-machine `compare` at equal spp. --tasks is ignored.
    #[arg(long, value_parser = sampler_parser(), value_delimiter = ',', conflicts_with = "aov")]
    compare: Option<Vec<LightSamplerKind>>,
    /// Seeds per sampler of a comparison (the runs use the seeds after --seed).
    #[arg(long, default_value_t = 1, requires = "compare", value_parser = parse_count, allow_negative_numbers = true)]
    seeds: u32,
    /// Reference EXR of a comparison (default: a task renders one).
    #[arg(long, requires = "compare")]
    reference: Option<PathBuf>,
    /// spp of a comparison's rendered reference.
    #[arg(long, default_value_t = 1024, requires = "compare", value_parser = parse_count, allow_negative_numbers = true)]
    reference_spp: u32,
    /// Sampler of a comparison's rendered reference.
    #[arg(long, value_parser = sampler_parser(), default_value = "tree", requires = "compare")]
    reference_sampler: LightSamplerKind,
}

impl SlurmArgs {
    /// The `render` flags every task passes on (a comparison's tasks set sampler and seed
    /// themselves).
    fn render_args(&self) -> Vec<String> {
        let mut a = Vec::new();
        let mut flag = |name: &str, value: Option<String>| {
            if let Some(v) = value {
                a.extend([format!("--{name}"), v]);
            }
        };
        let single = self.compare.is_none();
        flag("sampler", self.sampler.filter(|_| single).map(|s| s.name().to_string()));
        flag("seed", self.seed.filter(|_| single).map(|s| s.to_string()));
        flag("max-depth", self.max_depth.map(|d| d.to_string()));
        flag("clamp", self.clamp.map(|c| format!("{},{}", c.direct, c.indirect)));
        flag("guiding", self.guiding.map(|g| myriad::settings::on_off(g).to_string()));
        flag("caustics", self.caustics.map(|c| myriad::settings::on_off(c).to_string()));
        flag("resolution", self.resolution.map(|r| format!("{}x{}", r.x, r.y)));
        flag("camera", self.camera.clone());
        flag("aov", (!self.aov.is_empty()).then(|| self.aov.join(",")));
        a
    }
}

#[derive(Args)]
struct MergeArgs {
    /// Part files written by `myriad render --samples A..B`, in any order.
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// Output EXR.
    #[arg(short, long)]
    output: PathBuf,
    /// Also write a PNG preview beside the EXR.
    #[arg(long)]
    png: bool,
    /// Exposure of the PNG preview, in stops.
    #[arg(long, default_value_t = 0.0, value_parser = parse_exposure, allow_hyphen_values = true)]
    exposure: f32,
    /// Merge even when the parts' ranges leave samples out (the summary lists them).
    #[arg(long)]
    allow_gaps: bool,
}

#[derive(Args)]
struct CompareArgs {
    /// Scene file (.ron, .obj, .gltf or .glb).
    scene: PathBuf,
    /// Samplers to compare, comma-separated [default: uniform,power,local,tree,cells and the
    /// scene file's own sampler].
    #[arg(long, value_parser = sampler_parser(), value_delimiter = ',')]
    samplers: Option<Vec<LightSamplerKind>>,
    /// Reference EXR to measure against (default: render one and cache it in the output folder).
    #[arg(long, conflicts_with_all = ["reference_spp", "reference_time", "reference_sampler"])]
    reference: Option<PathBuf>,
    /// spp of the rendered reference [default: 16 × each run's spp, or 16 × its time with
    /// --time, at most 10 minutes; a timing pass estimates it first].
    #[arg(long, conflicts_with = "reference_time", value_parser = parse_count, allow_negative_numbers = true)]
    reference_spp: Option<u32>,
    /// Seconds (whole passes) of the rendered reference, instead of an spp.
    #[arg(long, value_parser = parse_seconds, allow_negative_numbers = true)]
    reference_time: Option<Duration>,
    /// Sampler of the rendered reference [default: tree, the unbiased sampler that converges
    /// fastest; all and local cost O(n) per point].
    #[arg(long, value_parser = sampler_parser())]
    reference_sampler: Option<LightSamplerKind>,
    /// Seeds per sampler: metrics become mean ± standard deviation, and the bias check gains power.
    #[arg(long, default_value_t = 1, value_parser = parse_count, allow_negative_numbers = true)]
    seeds: u32,
    /// Output folder (default: compare-<scene name>).
    #[arg(long)]
    out_dir: Option<PathBuf>,
    /// Stream each run to a running tev viewer as it renders, one image per sampler and seed
    /// [default address: 127.0.0.1:14158].
    #[arg(long, value_name = "[HOST:]PORT", num_args = 0..=1, default_missing_value = myriad::commands::display::DEFAULT_DISPLAY)]
    display: Option<String>,
    /// Measure runs rendered elsewhere instead of rendering them: DIR/SAMPLER-SEED.part, each
    /// from `render --samples 0..SPP --sampler SAMPLER --seed SEED` (what `myriad slurm
    /// --compare` writes). Equal spp only; the report's timings are the runs' own.
    #[arg(long, value_name = "DIR", conflicts_with = "time")]
    runs: Option<PathBuf>,
    #[command(flatten)]
    common: CommonArgs,
}

/// The flags `render` and `compare` share. Settings not given come from the scene file's
/// `render` block, then the defaults.
#[derive(Args)]
struct CommonArgs {
    /// Samples per pixel.
    #[arg(long, conflicts_with = "time", value_parser = parse_count, allow_negative_numbers = true)]
    spp: Option<u32>,
    /// Seconds to render (whole passes) instead of a fixed spp.
    #[arg(long, value_parser = parse_seconds, allow_negative_numbers = true)]
    time: Option<Duration>,
    /// Random seed: the same seed gives the same image, whatever --threads is.
    #[arg(long, value_parser = parse_seed, allow_negative_numbers = true)]
    seed: Option<u64>,
    /// Output size, e.g. 640x480 (the camera's vertical field of view is kept).
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<UVec2>,
    /// Maximum number of bounces (scattering events); 1 is direct lighting only [default: the
    /// scene's, else 8].
    #[arg(long, conflicts_with = "direct_only", value_parser = parse_count, allow_negative_numbers = true)]
    max_depth: Option<u32>,
    /// Direct lighting only (same as --max-depth 1): isolates the light sampler's noise.
    #[arg(long)]
    direct_only: bool,
    /// Clamp fireflies as Cycles does: INDIRECT, or DIRECT,INDIRECT (Blender's Clamp Direct and
    /// Clamp Indirect; 0 = none). A sample's contribution whose channels sum above the limit is
    /// scaled down to it. It biases the picture darker: off unless given [default: the
    /// scene's, else off].
    #[arg(long, value_parser = parse_clamp, allow_negative_numbers = true)]
    clamp: Option<Clamp>,
    /// Path guiding: on (paths learn, between passes, where light came from and go there more
    /// often) or off [default: the scene's, else off].
    #[arg(long, value_parser = parse_on_off)]
    guiding: Option<bool>,
    /// Caustics: light through smooth glass (a lamp in a glass globe, the sun through a glass
    /// ball) and the highlights glossy surfaces throw from point and spot lights. On:
    /// next-event estimation solves for the refractions, and light paths traced from the
    /// lights bring the highlights, at some cost per sample; off: both left to BSDF sampling,
    /// which finds them by luck (a point light's or the sun's through glass never) [default:
    /// the scene's, else on].
    #[arg(long, value_parser = parse_on_off)]
    caustics: Option<bool>,
    /// Camera to use, by name (default: the scene's first); `auto` frames the whole scene
    /// from the front (for OBJ files, which carry no camera).
    #[arg(long)]
    camera: Option<String>,
    /// Exposure of the PNG preview, in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = parse_exposure)]
    exposure: f32,
    /// Hide the progress bars.
    #[arg(long, short)]
    quiet: bool,
    #[command(flatten)]
    load: LoadArgs,
}

impl CommonArgs {
    /// The render settings asked for (`sampler`: the one `render` names).
    fn request(&self, sampler: Option<LightSamplerKind>) -> RenderRequest {
        RenderRequest {
            spp: self.spp,
            time: self.time,
            samples: None,
            sampler,
            seed: self.seed,
            max_depth: self.max_depth,
            direct_only: self.direct_only,
            clamp: self.clamp,
            guiding: self.guiding,
            caustics: self.caustics,
        }
    }
}

/// Options for reading scene files.
#[derive(Args)]
struct LoadArgs {
    /// glTF scene to load, by index (default: the file's default scene, else its first).
    #[arg(long, value_parser = parse_index, allow_negative_numbers = true)]
    gltf_scene: Option<usize>,
    /// Factor from glTF punctual light units (cd, lux) to W/sr and W/m² [default: 1/683, as
    /// Blender's exporter writes them in its "Standard" lighting mode; use 1 for files whose
    /// intensities are already radiometric].
    #[arg(long, value_parser = parse_scale, allow_negative_numbers = true)]
    punctual_scale: Option<f32>,
}

impl LoadArgs {
    fn options(&self) -> LoadOptions {
        let d = LoadOptions::default();
        LoadOptions { gltf_scene: self.gltf_scene, punctual_scale: self.punctual_scale.unwrap_or(d.punctual_scale) }
    }
}

/// Light samplers by name, with the names listed in `--help` and in errors.
fn sampler_parser() -> impl TypedValueParser<Value = LightSamplerKind> {
    clap::builder::PossibleValuesParser::new(LightSamplerKind::EVERY.map(LightSamplerKind::name))
        .try_map(|s| s.parse::<LightSamplerKind>())
}

fn parse_seconds(s: &str) -> Result<Duration, String> {
    let v: f64 = s.parse().map_err(|_| format!("'{s}' is not a number of seconds"))?;
    if !(v > 0.0) {
        return Err(format!("{s} is not allowed: the time must be a positive number of seconds"));
    }
    Duration::try_from_secs_f64(v).map_err(|_| format!("{s} seconds is longer than myriad can count"))
}

fn parse_resolution(s: &str) -> Result<UVec2, String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT, e.g. 640x480"))?;
    let (w, h): (u32, u32) = (w.trim().parse().map_err(|_| "bad width")?, h.trim().parse().map_err(|_| "bad height")?);
    if w == 0 || h == 0 || w > MAX_RESOLUTION || h > MAX_RESOLUTION {
        return Err(format!("width and height must be between 1 and {MAX_RESOLUTION}"));
    }
    Ok(UVec2::new(w, h))
}

fn parse_samples(s: &str) -> Result<(u32, u32), String> {
    let (a, b) = s.split_once("..").ok_or_else(|| format!("'{s}' is not a sample range A..B, e.g. 0..16"))?;
    let (a, b): (u32, u32) = (
        a.trim().parse().map_err(|_| format!("'{a}' is not a sample index"))?,
        b.trim().parse().map_err(|_| format!("'{b}' is not a sample index"))?,
    );
    if a >= b {
        return Err(format!("{a}..{b} holds no samples: A must be below B"));
    }
    Ok((a, b))
}

/// A count (spp, seeds, tasks, depth): a whole number from 1 up. Options that take one accept
/// hyphen values, so that `--spp -5` reaches here and is told what is wrong with it.
fn parse_count(s: &str) -> Result<u32, String> {
    match s.trim().parse::<i128>() {
        Ok(n) if (1..=u32::MAX as i128).contains(&n) => Ok(n as u32),
        Ok(n) if n < 1 => Err(format!("{n} is not allowed: give a positive whole number (1, 2, 3, ...)")),
        Ok(_) => Err(format!("{s} is more than myriad can count: at most {}", u32::MAX)),
        Err(_) => Err(format!("'{s}' is not a whole number")),
    }
}

/// A seed: a whole number from 0 to 2⁶⁴ − 1.
fn parse_seed(s: &str) -> Result<u64, String> {
    match s.trim().parse::<i128>() {
        Ok(n) if (0..=u64::MAX as i128).contains(&n) => Ok(n as u64),
        _ => Err(format!("'{s}' is not a seed: give a whole number from 0 to {}", u64::MAX)),
    }
}

/// `on` or `off`.
fn parse_on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("give on or off, not '{s}'")),
    }
}

/// A `--clamp`: INDIRECT or DIRECT,INDIRECT, each a finite number ≥ 0.
fn parse_clamp(s: &str) -> Result<Clamp, String> {
    s.parse()
}

/// An index into a file's list (a glTF scene): a whole number from 0.
fn parse_index(s: &str) -> Result<usize, String> {
    s.trim().parse::<usize>().map_err(|_| format!("'{s}' is not an index: give a whole number from 0"))
}

/// A positive, finite factor.
fn parse_scale(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("'{s}' is not a positive number")),
    }
}

fn parse_exposure(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|_| format!("'{s}' is not a number of stops"))?;
    if v.is_finite() && v.abs() <= 64.0 { Ok(v) } else { Err("the exposure must be between -64 and 64 stops".into()) }
}

fn parse_tracer(s: &str) -> Result<TracerKind, String> {
    TracerKind::parse(s).ok_or_else(|| format!("'{s}' is no tracer; use best, builtin or embree"))
}

fn parse_gigabytes(s: &str) -> Result<u64, String> {
    myriad::limits::parse_gb(s).ok_or_else(|| format!("'{s}' is not a positive number of gigabytes"))
}

/// Runs the command; the exit status (130 for a render the user stopped, whose partial
/// result was written).
fn run(cli: Cli) -> myriad::Result<ExitCode> {
    if let Some(bytes) = cli.max_memory {
        myriad::limits::set_memory_limit(bytes);
    } else {
        myriad::limits::check_memory_env().map_err(myriad::Error::Usage)?;
    }
    myriad::io::replace_read_only(cli.force);
    match cli.tracer {
        Some(t) => t.choose_for_process(),
        None => drop(TracerKind::from_env().map_err(myriad::Error::Usage)?),
    }
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
            .map_err(|e| myriad::Error::Usage(format!("cannot start {n} threads: {e}")))?;
    }
    match cli.command {
        Command::Render(a) => return render(a),
        Command::View(a) => return view(a),
        Command::Compare(a) => compare(a)?,
        Command::Slurm(a) => {
            let out = a.out.clone().unwrap_or_else(|| {
                PathBuf::from(format!("slurm-{}", a.scene.file_stem().map_or("scene".into(), |s| s.to_string_lossy())))
            });
            let compare = a.compare.clone().map(|samplers| commands::slurm::CompareJob {
                samplers,
                seeds: a.seeds,
                seed: a.seed.unwrap_or(0),
                reference: a.reference.clone(),
                reference_spp: a.reference_spp,
                reference_sampler: a.reference_sampler,
            });
            say(commands::slurm::slurm(&commands::slurm::SlurmOptions {
                compare,
                render_args: a.render_args(),
                scene: a.scene,
                spp: a.spp,
                tasks: a.tasks.unwrap_or(1),
                out,
                partition: a.partition,
                time: a.time,
                cpus_per_task: a.cpus_per_task,
                mem: a.mem,
                submit: a.submit,
            })?)
        }
        Command::Merge(a) => say(commands::merge::merge(&commands::merge::MergeOptions {
            parts: a.parts,
            output: a.output,
            png: a.png,
            exposure: a.exposure,
            allow_gaps: a.allow_gaps,
        })?),
        Command::Diff { image, reference, out, html } => {
            say(diff(&myriad::commands::diff::DiffOptions { image, reference, error_png: out, html })?)
        }
        Command::Info { scene, camera, load } => {
            let options = SceneOptions {
                load: load.options(),
                build: BuildOptions { resolution: None, camera, ..Default::default() },
            };
            say(info(scene.as_deref(), &options)?);
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn render(a: RenderArgs) -> myriad::Result<ExitCode> {
    let opts = RenderOptions {
        scene: a.scene,
        output: a.output,
        png: a.png,
        no_png: a.no_png,
        settings: RenderRequest { samples: a.samples, ..a.common.request(a.sampler) },
        resolution: a.common.resolution,
        camera: a.common.camera,
        aovs: AovSet::from_names(&a.aov),
        exposure: a.common.exposure,
        progress: !a.common.quiet,
        load: a.common.load.options(),
        display: a.display,
    };
    let report = commands::render::render(&opts)?;
    let stopped = report.output.stats.stopped != myriad::interrupt::Stop::No;
    say(report);
    Ok(if stopped { ExitCode::from(myriad::interrupt::EXIT_STATUS) } else { ExitCode::SUCCESS })
}

fn view(a: ViewArgs) -> myriad::Result<ExitCode> {
    let opts = myriad::commands::view::ViewOptions {
        scene: a.scene,
        settings: a.common.request(a.sampler),
        resolution: a.common.resolution,
        camera: a.common.camera,
        load: a.common.load.options(),
        exposure: a.common.exposure,
        reference: a.reference,
        out_dir: a.out_dir,
        exit_when_done: a.exit_when_done,
        quiet: a.common.quiet,
    };
    let report = myriad::commands::view::view(&opts)?;
    say(&report);
    Ok(if report.interrupted { ExitCode::from(myriad::interrupt::EXIT_STATUS) } else { ExitCode::SUCCESS })
}

fn compare(a: CompareArgs) -> myriad::Result<()> {
    let out_dir = a.out_dir.unwrap_or_else(|| myriad::commands::compare::default_out_dir(Some(&a.scene)));
    let opts = CompareOptions {
        scene: a.scene,
        samplers: a.samplers,
        settings: a.common.request(None),
        reference: a.reference,
        reference_spp: a.reference_spp,
        reference_time: a.reference_time,
        reference_sampler: a.reference_sampler,
        seeds: a.seeds,
        out_dir: out_dir.clone(),
        resolution: a.common.resolution,
        camera: a.common.camera,
        exposure: a.common.exposure,
        progress: !a.common.quiet,
        load: a.common.load.options(),
        runs: a.runs,
        display: a.display,
    };
    let report = myriad::commands::compare::compare(&opts)?;
    say(report.table());
    if let Some(w) = report.reference.warning() {
        say(format!("warning: {w}"));
    }
    for s in report.samplers.iter().filter(|s| s.bias.flagged) {
        say(format!(
            "warning: {} disagrees with the reference (z = {:.1}): biased sampler or unconverged reference",
            s.sampler, s.bias.z
        ));
    }
    say(format!(
        "wrote {} (report.html to look at, report.md, report.json, contact-sheet.png, convergence.svg, per-sampler EXR and error maps)",
        out_dir.display()
    ));
    Ok(())
}

/// Prints to stdout; a closed pipe (`myriad … | head`) ends the output quietly instead of
/// panicking as `println!` does.
fn say(text: impl std::fmt::Display) {
    use std::io::Write;
    let _ = writeln!(std::io::stdout(), "{text}");
}

/// Prints to stderr; a closed stderr is no reason to panic.
fn tell(text: impl std::fmt::Display) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{text}");
}

fn main() -> ExitCode {
    // First, before any code built with the extensions it checks for.
    myriad::cpu::require_build_features();
    start()
}

/// Everything after the CPU check, kept out of `main` so that none of it is scheduled before.
#[inline(never)]
fn start() -> ExitCode {
    if let Err(e) = myriad::interrupt::install() {
        tell(format!("warning: Ctrl-C will stop myriad without cleaning up ({e})"));
    }
    match run(Cli::parse()) {
        Ok(code) => code,
        Err(e @ myriad::Error::Interrupted) => {
            tell(e);
            ExitCode::from(myriad::interrupt::EXIT_STATUS)
        }
        Err(e) => {
            tell(format!("error: {e}"));
            ExitCode::FAILURE
        }
    }
}
