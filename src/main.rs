//! The `myriad` command line: parses arguments, calls the library, prints reports. No math.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args, Parser, Subcommand};
use myriad::commands::{self, info::info, render::RenderOptions};
use myriad::film::AovSet;
use myriad::light_sampler::LightSamplerKind;
use myriad::math::UVec2;
use myriad::scene::BuildOptions;

/// myriad: a path tracer for scenes lit by very many lights.
///
/// Renders .ron scenes (with procedural light grids) and .obj files to EXR, choosing
/// lights with one of several samplers so you can see which wins on your scene.
#[derive(Parser)]
#[command(version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Worker threads (default: all cores). Results are identical for any value.
    #[arg(long, global = true)]
    threads: Option<usize>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to EXR (linear RGB + optional AOVs) and a PNG preview.
    ///
    /// Without SCENE, renders the built-in Cornell box with a 5x5 grid of ceiling lights.
    /// Settings not given here come from the scene file's `render` block, then defaults
    /// (64 spp, max depth 8, sampler tree, seed 0).
    Render(RenderArgs),
    /// Load a scene and report what it holds: triangles, lights, power, build times, memory.
    Info {
        /// Scene file (.ron or .obj); default: the built-in Cornell box.
        scene: Option<PathBuf>,
        /// Camera to use, by name.
        #[arg(long)]
        camera: Option<String>,
    },
}

#[derive(Args)]
struct RenderArgs {
    /// Scene file (.ron or .obj); default: the built-in Cornell box.
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
    /// Camera to use, by name.
    #[arg(long)]
    camera: Option<String>,
    /// PNG preview path (default: the EXR path with .png).
    #[arg(long)]
    png: Option<PathBuf>,
    /// Do not write a PNG preview.
    #[arg(long, conflicts_with = "png")]
    no_png: bool,
    /// PNG preview exposure, in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// Extra EXR channels, comma-separated: albedo, normal, depth, variance.
    #[arg(long, value_delimiter = ',', value_parser = ["albedo", "normal", "depth", "variance"])]
    aov: Vec<String>,
    /// Hide the progress bar.
    #[arg(long, short)]
    quiet: bool,
}

fn parse_seconds(s: &str) -> Result<Duration, String> {
    let v: f64 = s.parse().map_err(|_| format!("'{s}' is not a number of seconds"))?;
    if v > 0.0 && v.is_finite() { Ok(Duration::from_secs_f64(v)) } else { Err("the time must be positive".into()) }
}

fn parse_resolution(s: &str) -> Result<UVec2, String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT, e.g. 640x480"))?;
    let (w, h): (u32, u32) = (w.trim().parse().map_err(|_| "bad width")?, h.trim().parse().map_err(|_| "bad height")?);
    if w == 0 || h == 0 || w > 32768 || h > 32768 {
        return Err("width and height must be between 1 and 32768".into());
    }
    Ok(UVec2::new(w, h))
}

fn run(cli: Cli) -> myriad::Result<()> {
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
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
            };
            println!("{}", commands::render::render(&opts)?);
        }
        Command::Info { scene, camera } => {
            print!("{}", info(scene.as_deref(), &BuildOptions { resolution: None, camera })?);
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
