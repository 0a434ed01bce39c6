//! The `myriad` command line: parses arguments, calls the library, prints reports. No math.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args, Parser, Subcommand};
use myriad::commands::compare::{CompareOptions, compare};
use myriad::commands::diff::diff;
use myriad::commands::{self, SceneOptions, info::info, render::RenderOptions};
use myriad::film::AovSet;
use myriad::io::LoadOptions;
use myriad::light_sampler::LightSamplerKind;
use myriad::math::UVec2;
use myriad::render::Budget;
use myriad::scene::{BuildOptions, MAX_RESOLUTION};

/// myriad: a path tracer for scenes lit by very many lights.
///
/// Renders .ron scenes (with procedural light grids), glTF (.gltf, .glb) and .obj files to EXR, choosing
/// lights with one of several samplers (all, uniform, power, local, tree), and compares the
/// samplers on your own scenes (`myriad compare`).
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
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to EXR (linear RGB + optional AOVs) and a PNG preview.
    ///
    /// Without SCENE, renders the built-in Cornell box with a 5x5 grid of ceiling lights.
    /// Settings not given here come from the scene file's `render` block, then defaults
    /// (64 spp, max depth 8, sampler tree, seed 0).
    Render(RenderArgs),
    /// Render a scene with several light samplers and measure each against a reference.
    ///
    /// Every sampler renders with the same seeds (equal spp: identical camera rays and BSDF
    /// directions, so differences come from the light choice alone), or for the same time.
    /// Writes each render, a false-colour error map, a labelled contact sheet, a plot of relMSE
    /// against time (SVG), report.md and report.json to the output folder, and prints the table.
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
    },
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
struct RenderArgs {
    /// Scene file (.ron, .obj, .gltf or .glb); default: the built-in Cornell box.
    scene: Option<PathBuf>,
    /// Output EXR.
    #[arg(short, long, default_value = "myriad.exr")]
    output: PathBuf,
    /// Samples per pixel.
    #[arg(long, conflicts_with = "time")]
    spp: Option<u32>,
    /// Render for this many seconds (whole passes) instead of a fixed spp.
    #[arg(long, value_parser = parse_seconds)]
    time: Option<Duration>,
    /// How next-event estimation picks lights.
    #[arg(long, value_enum)]
    sampler: Option<LightSamplerKind>,
    /// Random seed: the same seed gives the same image, whatever --threads is.
    #[arg(long)]
    seed: Option<u64>,
    /// Output size, e.g. 640x480 (the camera's vertical field of view is kept).
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<UVec2>,
    /// Maximum number of bounces (scattering events); 1 is direct lighting only.
    #[arg(long, conflicts_with = "direct_only")]
    max_depth: Option<u32>,
    /// Direct lighting only (same as --max-depth 1): isolates the light sampler's noise.
    #[arg(long)]
    direct_only: bool,
    /// Camera to use, by name (default: the scene's first); `auto` frames the whole scene
    /// from the front (for OBJ files, which carry no camera).
    #[arg(long)]
    camera: Option<String>,
    /// PNG preview path (default: the EXR path with .png).
    #[arg(long)]
    png: Option<PathBuf>,
    /// Do not write a PNG preview.
    #[arg(long, conflicts_with = "png")]
    no_png: bool,
    /// PNG preview exposure, in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = parse_exposure)]
    exposure: f32,
    /// Extra EXR channels, comma-separated: albedo, normal, depth, variance.
    #[arg(long, value_delimiter = ',', value_parser = ["albedo", "normal", "depth", "variance"])]
    aov: Vec<String>,
    /// Hide the progress bar.
    #[arg(long, short)]
    quiet: bool,
    #[command(flatten)]
    load: LoadArgs,
}

#[derive(Args)]
struct CompareArgs {
    /// Scene file (.ron, .obj, .gltf or .glb).
    scene: PathBuf,
    /// Samplers to compare, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "uniform,power,local,tree")]
    samplers: Vec<LightSamplerKind>,
    /// Equal spp: every sampler renders this many samples per pixel (default 16).
    #[arg(long, conflicts_with = "time")]
    spp: Option<u32>,
    /// Equal time: every sampler renders this many seconds (per seed).
    #[arg(long, value_parser = parse_seconds)]
    time: Option<Duration>,
    /// Reference EXR to measure against (default: render one and cache it in the output folder).
    #[arg(long, conflicts_with_all = ["reference_spp", "reference_sampler"])]
    reference: Option<PathBuf>,
    /// spp of the rendered reference.
    #[arg(long, default_value_t = 1024)]
    reference_spp: u32,
    /// Sampler of the rendered reference (default: all up to 64 lights, local up to 10^4, tree beyond).
    #[arg(long, value_enum)]
    reference_sampler: Option<LightSamplerKind>,
    /// Seeds per sampler: metrics become mean ± standard deviation, and the bias check gains power.
    #[arg(long, default_value_t = 1)]
    seeds: u32,
    /// Output folder (default: compare-<scene name>).
    #[arg(long)]
    out_dir: Option<PathBuf>,
    /// Image size, e.g. 320x240.
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<UVec2>,
    /// Maximum number of bounces.
    #[arg(long, conflicts_with = "direct_only")]
    max_depth: Option<u32>,
    /// Direct lighting only (same as --max-depth 1).
    #[arg(long)]
    direct_only: bool,
    /// Camera to use, by name (default: the scene's first); `auto` frames the whole scene
    /// from the front (for OBJ files, which carry no camera).
    #[arg(long)]
    camera: Option<String>,
    /// Exposure of the previews, in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = parse_exposure)]
    exposure: f32,
    /// Hide the progress bars.
    #[arg(long, short)]
    quiet: bool,
    #[command(flatten)]
    load: LoadArgs,
}

/// Options for reading scene files.
#[derive(Args)]
struct LoadArgs {
    /// glTF scene to load, by index (default: the file's default scene, else its first).
    #[arg(long)]
    gltf_scene: Option<usize>,
    /// Factor from glTF punctual light units (cd, lux) to W/sr and W/m² [default: 1/683, as
    /// Blender's exporter writes them in its "Standard" lighting mode; use 1 for files whose
    /// intensities are already radiometric].
    #[arg(long)]
    punctual_scale: Option<f32>,
}

impl LoadArgs {
    fn options(&self) -> LoadOptions {
        let d = LoadOptions::default();
        LoadOptions { gltf_scene: self.gltf_scene, punctual_scale: self.punctual_scale.unwrap_or(d.punctual_scale) }
    }
}

fn parse_seconds(s: &str) -> Result<Duration, String> {
    let v: f64 = s.parse().map_err(|_| format!("'{s}' is not a number of seconds"))?;
    if !(v > 0.0) {
        return Err("the time must be positive".into());
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

fn parse_exposure(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|_| format!("'{s}' is not a number of stops"))?;
    if v.is_finite() && v.abs() <= 64.0 { Ok(v) } else { Err("the exposure must be between -64 and 64 stops".into()) }
}

fn parse_gigabytes(s: &str) -> Result<u64, String> {
    myriad::limits::parse_gb(s).ok_or_else(|| format!("'{s}' is not a positive number of gigabytes"))
}

/// Runs the command; the exit status (130 for a render the user stopped, whose partial
/// result was written).
fn run(cli: Cli) -> myriad::Result<ExitCode> {
    if let Some(bytes) = cli.max_memory {
        myriad::limits::set_memory_limit(bytes);
    }
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
            .map_err(|e| myriad::Error::Usage(format!("cannot start {n} threads: {e}")))?;
    }
    match cli.command {
        Command::Render(a) => {
            let opts = RenderOptions {
                scene: a.scene,
                output: a.output,
                png: a.png,
                no_png: a.no_png,
                spp: a.spp,
                time: a.time,
                sampler: a.sampler,
                seed: a.seed,
                resolution: a.resolution,
                max_depth: a.max_depth,
                direct_only: a.direct_only,
                camera: a.camera,
                aovs: AovSet {
                    albedo: a.aov.iter().any(|s| s == "albedo"),
                    normal: a.aov.iter().any(|s| s == "normal"),
                    depth: a.aov.iter().any(|s| s == "depth"),
                    variance: a.aov.iter().any(|s| s == "variance"),
                },
                exposure: a.exposure,
                progress: !a.quiet,
                load: a.load.options(),
            };
            let report = commands::render::render(&opts)?;
            let stopped = report.output.stats.stopped != myriad::interrupt::Stop::No;
            say(report);
            if stopped {
                return Ok(ExitCode::from(myriad::interrupt::EXIT_STATUS));
            }
        }
        Command::Compare(a) => {
            let out_dir = a.out_dir.unwrap_or_else(|| {
                PathBuf::from(format!(
                    "compare-{}",
                    a.scene.file_stem().map_or("scene".into(), |s| s.to_string_lossy())
                ))
            });
            let opts = CompareOptions {
                scene: a.scene,
                samplers: a.samplers,
                budget: match a.time {
                    Some(t) => Budget::Time(t),
                    None => Budget::Spp(a.spp.unwrap_or(16).max(1)),
                },
                reference: a.reference,
                reference_spp: a.reference_spp.max(1),
                reference_sampler: a.reference_sampler,
                seeds: a.seeds.max(1),
                out_dir: out_dir.clone(),
                resolution: a.resolution,
                max_depth: if a.direct_only { Some(1) } else { a.max_depth },
                camera: a.camera,
                exposure: a.exposure,
                progress: !a.quiet,
                load: a.load.options(),
            };
            let report = compare(&opts)?;
            say(report.table());
            for s in report.samplers.iter().filter(|s| s.bias.flagged) {
                say(format!(
                    "warning: {} disagrees with the reference (z = {:.1}): biased sampler or unconverged reference",
                    s.sampler, s.bias.z
                ));
            }
            say(format!(
                "wrote {} (report.md, report.json, contact-sheet.png, convergence.svg, per-sampler EXR and error maps)",
                out_dir.display()
            ));
        }
        Command::Diff { image, reference, out } => {
            say(diff(&image, &reference, out.as_deref())?);
        }
        Command::Info { scene, camera, load } => {
            let options = SceneOptions { load: load.options(), build: BuildOptions { resolution: None, camera } };
            say(info(scene.as_deref(), &options)?);
        }
    }
    Ok(ExitCode::SUCCESS)
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
