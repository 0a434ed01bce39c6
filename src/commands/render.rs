//! `myriad render`: scene file → EXR (+ PNG preview) with a summary.

use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::display::TevStream;
use super::progress::Progress;
use super::settings::{DEFAULT_SPP, RenderRequest};
use super::{DEFAULT_SCENE_NAME, LoadedScene, SceneOptions, human_duration, human_rate, load_scene};
use crate::error::{Error, Result};
use crate::film::AovSet;
use crate::integrator::timing::{PhaseTimes, TIMED_ONE_IN};
use crate::interrupt::Stop;
use crate::light_sampler::LightStrategy;
use crate::limits::human_bytes;
use crate::math::UVec2;
use crate::render::{Budget, RenderOutput, RenderSettings, render as render_scene};
use crate::scene::BuildOptions;
use crate::settings::LightSamplerKind;

/// Everything `render` can be told; `None` fields fall back to the scene, then to defaults.
#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    /// Scene file; `None` renders the built-in Cornell box.
    pub scene: Option<PathBuf>,
    /// EXR output path.
    pub output: PathBuf,
    /// PNG preview path; `None` puts it beside the EXR.
    pub png: Option<PathBuf>,
    /// Write no PNG preview.
    pub no_png: bool,
    /// Budget, sampler, seed and depth as the command line asks them.
    pub settings: RenderRequest,
    /// Output size.
    pub resolution: Option<UVec2>,
    /// Camera name.
    pub camera: Option<String>,
    /// How to read the scene file.
    pub load: crate::io::LoadOptions,
    /// Extra EXR channels.
    pub aovs: AovSet,
    /// PNG exposure in stops.
    pub exposure: f32,
    /// Draw a progress bar (only shown on a terminal).
    pub progress: bool,
    /// Stream every pass to the tev viewer at this address.
    pub display: Option<String>,
}

/// What a render did, for the summary.
pub struct RenderReport {
    /// The scene and its load timings.
    pub loaded: LoadedScene,
    /// The sampler asked for.
    pub sampler: LightSamplerKind,
    /// What chose the lights ([`LightStrategy::label`]).
    pub label: String,
    /// Its build time.
    pub sampler_build_time: Duration,
    /// Its memory.
    pub sampler_bytes: usize,
    /// The light tree's shape, when the sampler is built on one.
    pub tree: Option<crate::light_sampler::TreeStats>,
    /// What the `cells` sampler built during the render, when it is the sampler.
    pub cells: Option<crate::light_sampler::CellStats>,
    /// The settings rendered with.
    pub settings: RenderSettings,
    /// Film and statistics.
    pub output: RenderOutput,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// Loads, renders and writes the outputs. Output paths are checked before rendering, so a
/// bad path fails in milliseconds, not after the render.
pub fn render(opts: &RenderOptions) -> Result<RenderReport> {
    let outputs = Outputs::plan(opts)?;
    let scene_options = SceneOptions {
        load: opts.load,
        build: BuildOptions { resolution: opts.resolution, camera: opts.camera.clone(), ..Default::default() },
    };
    let loaded = load_scene(opts.scene.as_deref(), &scene_options)?;
    if loaded.scene.geometry.triangle_count() == 0
        && loaded.scene.lights.is_empty()
        && loaded.scene.environment.is_none()
    {
        return Err(Error::scene(
            &loaded.report.source,
            "scene",
            "holds nothing to render (no meshes, no lights, no environment): check that the export included the \
             objects (in Blender's glTF exporter, Include › Limit to: off), or pick another scene with --gltf-scene",
        ));
    }
    let resolved = opts.settings.resolve(&loaded.report.render, DEFAULT_SPP)?;
    let (settings, sampler) = (resolved.render_settings(loaded.report.resolution, opts.aovs), resolved.sampler);
    let scene = &loaded.scene;

    let t = Instant::now();
    let strategy = LightStrategy::build(sampler, &scene.lights, scene.center, scene.radius);
    let sampler_build_time = t.elapsed();

    let _busy = crate::interrupt::busy();
    if opts.progress {
        announce(&settings, &strategy.label(sampler));
    }
    let scene_name = opts.scene.as_deref().map_or(DEFAULT_SCENE_NAME.to_string(), |p| p.display().to_string());
    let display =
        opts.display.as_deref().map(|a| TevStream::connect(a, &format!("{scene_name} ({sampler})"), settings.aovs));
    let mut watch = (Progress::new(opts.progress, sampler.name()), display);
    let output = render_scene(scene, &strategy, &settings, &mut watch);
    if output.stats.stopped == Stop::Now {
        return Err(Error::Interrupted);
    }
    let made =
        Made { loaded: &loaded, scene_options: &scene_options, scene_name: &scene_name, sampler, settings: &settings };
    let written = outputs.write(opts, &made, &output)?;
    Ok(RenderReport {
        loaded,
        sampler,
        label: strategy.label(sampler),
        sampler_build_time,
        sampler_bytes: strategy.memory_bytes(),
        tree: strategy.tree_stats(),
        cells: strategy.cell_stats(),
        settings,
        output,
        written,
    })
}

/// Says on stderr what is about to render (beside the progress bar; a closed stderr does not
/// stop the render).
fn announce(settings: &RenderSettings, sampler: &str) {
    let res = settings.resolution;
    let budget = match settings.budget {
        Budget::Spp(n) => format!("{n} spp"),
        Budget::Samples(a, b) => format!("samples {a}..{b}"),
        Budget::Time(t) => format!("{} s", t.as_secs_f64()),
    };
    let _ = writeln!(
        std::io::stderr(),
        "rendering {} × {}, {budget}, sampler {sampler} (Ctrl-C: finish this pass and write it; twice: stop and \
         write nothing)",
        res.x,
        res.y
    );
}

/// How a render's film was made, for what is written beside it.
struct Made<'a> {
    loaded: &'a LoadedScene,
    scene_options: &'a SceneOptions,
    scene_name: &'a str,
    sampler: LightSamplerKind,
    settings: &'a RenderSettings,
}

/// Where a render's results go, checked before it starts: a part for a sample range (for
/// `merge`, no image), else the EXR; and the preview.
struct Outputs {
    part: Option<((u32, u32), PathBuf)>,
    png: Option<PathBuf>,
}

impl Outputs {
    /// The outputs `opts` asks for, each checked to be writable.
    fn plan(opts: &RenderOptions) -> Result<Self> {
        let part = match opts.settings.samples {
            Some((a, b)) if a >= b => {
                return Err(Error::Usage(format!("--samples {a}..{b} is empty: give A..B with A < B")));
            }
            Some(range) => Some((range, super::provenance::part_path(&opts.output, range))),
            None => None,
        };
        let png = (!opts.no_png && part.is_none())
            .then(|| opts.png.clone().unwrap_or_else(|| super::preview_path(&opts.output)));
        if part.is_none() {
            check_outputs(&opts.output, png.as_deref())?;
        }
        crate::io::check_writable(part.as_ref().map_or(&opts.output, |p| &p.1))?;
        if let Some(p) = &png {
            crate::io::check_writable(p)?;
        }
        Ok(Self { part, png })
    }

    /// Writes the render's results; the files written.
    fn write(self, opts: &RenderOptions, made: &Made, output: &RenderOutput) -> Result<Vec<PathBuf>> {
        let mut written = Vec::new();
        if let Some(((first, _), path)) = self.part {
            // Stopped after a pass, the part holds the samples rendered: a range of its own.
            let range = (first, first + output.film.spp());
            if range.0 == range.1 {
                return Err(Error::Interrupted);
            }
            let hash = super::provenance::scene_fingerprint(made.loaded, made.scene_options)?;
            let header = super::provenance::part_header(
                made.scene_name,
                hash,
                made.sampler,
                made.loaded.report.stats.tracer,
                made.settings,
                range,
                &output.stats,
            );
            crate::io::part::write(&path, &header, &output.film)?;
            written.push(path);
        } else {
            let meta = super::provenance::provenance(
                made.scene_name,
                made.sampler,
                made.loaded.report.stats.tracer,
                made.settings,
                &output.stats,
            );
            crate::io::exr::write(&opts.output, &output.film.layers(made.settings.aovs), &meta)?;
            written.push(opts.output.clone());
        }
        if let Some(p) = self.png {
            crate::io::png::write(&p, output.film.size(), &output.film.means(), opts.exposure)?;
            written.push(p);
        }
        Ok(written)
    }
}

/// The EXR output is not a picture format's name and not the preview's path.
fn check_outputs(exr: &Path, png: Option<&Path>) -> Result<()> {
    crate::io::exr::check_name(exr)?;
    let same = |a: &Path, b: &Path| std::path::absolute(a).ok() == std::path::absolute(b).ok();
    if let Some(png) = png.filter(|p| same(p, exr)) {
        return Err(Error::Usage(format!(
            "--png {} is the EXR output's own path; the preview would overwrite the image",
            png.display()
        )));
    }
    Ok(())
}

/// Renders a path list for the summary.
fn paths(ps: &[PathBuf]) -> String {
    ps.iter().map(|p: &PathBuf| Path::display(p).to_string()).collect::<Vec<_>>().join(", ")
}

/// Where the timed paths spent their time (with `caustics`, also in connections through
/// glass), and the tracer's speed per thread by kind of ray.
fn write_time_shares(f: &mut fmt::Formatter<'_>, time: &PhaseTimes, caustics: bool) -> fmt::Result {
    let Some([trace, choice, glass, rest]) = time.shares() else { return Ok(()) };
    let (closest, shadow) = time.rays_per_second();
    let rate = |r: Option<f64>| r.map_or("-".into(), |r| format!("{}rays/s", human_rate(r)));
    let connections =
        if caustics { format!("connections through glass {:.0} %, ", 100.0 * glass) } else { String::new() };
    writeln!(
        f,
        "time       tracing {:.0} % (camera+bounce {}, shadow {} per thread), light choice {:.0} %, \
         {connections}shading and the rest {:.0} % (on 1 in {TIMED_ONE_IN} paths)",
        100.0 * trace,
        rate(closest),
        rate(shadow),
        100.0 * choice,
        100.0 * rest
    )
}

impl fmt::Display for RenderReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (s, r) = (&self.loaded.scene, &self.loaded.report);
        let st = &self.output.stats;
        let res = self.output.film.size();
        writeln!(
            f,
            "scene      {} ({} triangles, {} lights, {} × {} px)",
            r.source,
            r.stats.triangles,
            s.lights.len(),
            res.x,
            res.y
        )?;
        writeln!(
            f,
            "prepare    load {}, build {} (BVH {}, {} tracer), sampler {} built in {} ({})",
            human_duration(self.loaded.load_time),
            human_duration(r.stats.build_time),
            human_duration(r.stats.bvh_build_time),
            r.stats.tracer,
            self.label,
            human_duration(self.sampler_build_time),
            human_bytes(self.sampler_bytes as u64)
        )?;
        if let Some(t) = &self.tree {
            writeln!(f, "tree       {} nodes ({}-wide), depth {}", t.nodes, crate::light_sampler::TREE_WIDTH, t.depth)?;
        }
        writeln!(
            f,
            "render     {} spp in {} with {} threads, max depth {}, seed {}",
            st.spp,
            human_duration(st.elapsed),
            rayon::current_num_threads(),
            self.settings.max_depth,
            self.settings.seed
        )?;
        writeln!(
            f,
            "speed      {}samples/s, {}rays/s ({} camera+bounce, {} shadow)",
            human_rate(st.samples_per_second()),
            human_rate(st.rays_per_second()),
            st.rays.rays,
            st.rays.shadow_rays
        )?;
        write_time_shares(f, &st.rays.time, s.caustics && self.settings.caustics)?;
        if s.caustics && self.settings.caustics {
            let (tried, solved) = (st.rays.glass_tried, st.rays.glass_solved);
            writeln!(
                f,
                "caustics   {tried} light samples behind smooth glass, {solved} reached through it ({:.0} %)",
                100.0 * solved as f64 / tried.max(1) as f64
            )?;
        } else if s.caustics {
            writeln!(f, "caustics   off (--caustics): light through smooth glass left to BSDF sampling")?;
        }
        if st.light_path_lights > 0 {
            let (paths, splats) = (st.rays.light_paths, st.rays.splats);
            writeln!(
                f,
                "highlights {paths} light paths from {} point and spot lights, {splats} of them off a glossy surface to the image ({:.1} %)",
                st.light_path_lights,
                100.0 * splats as f64 / paths.max(1) as f64
            )?;
        }
        if self.sampler == LightSamplerKind::Cells && self.cells.is_none() && !s.lights.is_empty() {
            let lights = self.loaded.scene.lights.len();
            let chose = if lights <= crate::light_sampler::EVERY_LIGHT_UP_TO {
                "every light was sampled at diffuse points, the tree chose one elsewhere"
            } else {
                "the tree chose everywhere"
            };
            writeln!(
                f,
                "cells      not used with {lights} lights (its tables are for {} lights or more, within a quarter of the memory limit): {chose}",
                crate::light_sampler::CELLS_MIN_LIGHTS,
            )?;
        }
        if let Some(c) = &self.cells {
            let over = match c.clusters {
                0 => String::new(),
                n => format!(
                    " over {n} clusters of lights at diffuse points (the tree chooses within them, and at glossy points)"
                ),
            };
            writeln!(
                f,
                "cells      {} tables{over} in cells of {:.3} m and their parts (halvings up to {}: {} split, {} left to the tree), {}",
                c.tables,
                c.edge,
                c.halvings,
                c.splits,
                c.on_tree,
                human_bytes(c.memory_bytes as u64)
            )?;
        }
        if let Some(l) = &st.learned {
            writeln!(
                f,
                "learned    {} cells from {} light samples (passes up to {} spp), {} in {}",
                l.cells,
                l.samples,
                crate::light_sampler::LEARN_UNTIL.min(st.learned_at),
                human_bytes(l.memory_bytes as u64),
                human_duration(l.learning_time)
            )?;
        }
        if let Some(g) = &st.guide {
            writeln!(
                f,
                "guiding    {} regions, {} quadtree nodes, from {} path vertices (passes up to {} spp), {} in {}",
                g.regions,
                g.nodes,
                g.records,
                st.learned_at,
                human_bytes(g.memory_bytes as u64),
                human_duration(g.learning_time)
            )?;
        }
        if st.stopped == Stop::AfterPass {
            writeln!(f, "stopped    interrupted after {} spp; the files hold what was rendered", st.spp)?;
        }
        if st.non_finite_samples > 0 {
            writeln!(f, "warning    {} samples were not finite and counted as black", st.non_finite_samples)?;
        }
        for w in &r.warnings {
            writeln!(f, "warning    {w}")?;
        }
        write!(f, "wrote      {}", paths(&self.written))
    }
}
