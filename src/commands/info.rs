//! `myriad info`: what a scene holds once loaded and built.

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use super::{LoadedScene, SceneOptions, human_duration, load_scene};
use crate::error::Result;
use crate::light_sampler::{LEARN_UNTIL, LearnedLayout, LearnedSampler, TreeStats};
use crate::limits::human_bytes;
use crate::material::AlphaMode;

/// Everything `info` reports.
pub struct InfoReport {
    /// The loaded scene and timings.
    pub loaded: LoadedScene,
    /// The light tree built over its lights (none without lights).
    pub tree: Option<TreeStats>,
    /// How the `learned` sampler would learn over that tree.
    pub learned: Option<LearnedLayout>,
}

/// Loads and builds the scene and its light tree, and gathers their statistics.
pub fn info(path: Option<&Path>, options: &SceneOptions) -> Result<InfoReport> {
    let mut options = options.clone();
    options.build.frame_without_camera = true;
    let loaded = load_scene(path, &options)?;
    let learned = (!loaded.scene.lights.is_empty())
        .then(|| LearnedSampler::new(&loaded.scene.lights, loaded.scene.center, loaded.scene.radius));
    let (tree, learned) = (learned.as_ref().map(|l| l.tree().stats()), learned.map(|l| l.layout()));
    Ok(InfoReport { loaded, tree, learned })
}

impl fmt::Display for InfoReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (s, r) = (&self.loaded.scene, &self.loaded.report);
        let st = &r.stats;
        let res = r.resolution;
        writeln!(f, "scene        {}", r.source)?;
        writeln!(f, "camera       '{}', {} × {} px", r.camera_name, res.x, res.y)?;
        writeln!(
            f,
            "cameras      {}{}",
            st.cameras.len(),
            if st.cameras.is_empty() { String::new() } else { format!(" ({})", st.cameras.join(", ")) }
        )?;
        writeln!(f, "bounds       centre {:.3}, radius {:.3} m", s.center, s.radius)?;
        writeln!(
            f,
            "triangles    {} ({} emissive, {} stored) in {} instances of {} meshes",
            st.triangles, st.emissive_triangles, st.stored_triangles, st.instances, st.meshes
        )?;
        writeln!(f, "materials    {}", s.materials.len())?;
        for m in &s.materials {
            let alpha = match m.alpha {
                AlphaMode::Opaque => String::new(),
                AlphaMode::Mask(c) => format!(", alpha mask at {c}"),
                AlphaMode::Blend => ", alpha blend (stochastic)".into(),
            };
            let ignored =
                if m.ignored.is_empty() { String::new() } else { format!("; not rendered: {}", m.ignored.join(", ")) };
            writeln!(f, "  {:<24} {}{alpha}{ignored}", format!("'{}'", m.name), m.model_name())?;
        }
        let mut kinds: BTreeMap<&str, usize> = BTreeMap::new();
        for l in &s.lights {
            *kinds.entry(l.kind_name()).or_default() += 1;
        }
        let kinds: Vec<String> = kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
        writeln!(
            f,
            "lights       {} ({})",
            s.lights.len(),
            if kinds.is_empty() { "none".into() } else { kinds.join(", ") }
        )?;
        writeln!(f, "total power  {:.4} W (luminance)", s.total_power())?;
        writeln!(f, "load         {}", human_duration(self.loaded.load_time))?;
        writeln!(
            f,
            "build        {} (BVH {} for the {} tracer)",
            human_duration(st.build_time),
            human_duration(st.bvh_build_time),
            st.tracer
        )?;
        let per_tri = st.geometry_bytes as f64 / st.triangles.max(1) as f64;
        let per_light = st.light_bytes as f64 / s.lights.len().max(1) as f64;
        writeln!(
            f,
            "memory       geometry + BVH {} ({per_tri:.0} B/triangle), lights {} ({per_light:.0} B/light)",
            human_bytes(st.geometry_bytes as u64),
            human_bytes(st.light_bytes as u64)
        )?;
        if let Some(t) = &self.tree {
            writeln!(
                f,
                "light tree   built in {}: {} nodes ({}-wide), depth {}, {} ({:.0} B/light)",
                human_duration(t.build_time),
                t.nodes,
                crate::light_sampler::TREE_WIDTH,
                t.depth,
                human_bytes(t.memory_bytes as u64),
                t.memory_bytes as f64 / s.lights.len() as f64
            )?;
        }
        if let Some(l) = &self.learned {
            writeln!(
                f,
                "learned      {} clusters under {} top nodes, cells of {:.3} m × 7 normal bins, learns until {} spp, at most {}",
                l.clusters,
                l.top_nodes,
                l.cell_size,
                LEARN_UNTIL,
                human_bytes(l.max_bytes as u64)
            )?;
        }
        writeln!(
            f,
            "guiding      {} (--guiding): learns until {} spp, regions halved past {} records per √spp, at most {} with these threads",
            crate::settings::on_off(r.render.guiding.unwrap_or(crate::commands::settings::DEFAULT_GUIDING)),
            crate::guiding::GUIDE_UNTIL,
            crate::guiding::SPLIT_SAMPLES,
            human_bytes(crate::guiding::max_bytes(rayon::current_num_threads()) as u64)
        )?;
        let smooth: Vec<String> =
            s.materials.iter().filter(|m| m.smooth_glass().is_some()).map(|m| format!("'{}'", m.name)).collect();
        writeln!(
            f,
            "caustics     {}",
            if s.caustics && r.render.caustics.unwrap_or(crate::commands::settings::DEFAULT_CAUSTICS) {
                format!(
                    "light from emissive surfaces, lamps, point and directional lights through smooth glass ({}) is solved for (--caustics)",
                    smooth.join(", ")
                )
            } else if s.caustics {
                format!(
                    "off (the scene file's render.caustics): light through smooth glass ({}) is left to BSDF sampling",
                    smooth.join(", ")
                )
            } else if smooth.is_empty() {
                "no smooth solid glass: nothing to solve for".into()
            } else {
                "no emissive surface, lamp, point or directional light to solve for through smooth glass".into()
            }
        )?;
        let paths = crate::integrator::light_paths::LightPaths::new(s, r.resolution);
        let caustics = r.render.caustics.unwrap_or(crate::commands::settings::DEFAULT_CAUSTICS);
        writeln!(
            f,
            "highlights   {}",
            match (paths.map_or(0, |p| p.lights()), caustics) {
                (0, _) => "no point or spot light whose highlight off a glossy surface the camera sees (or a lens): no light paths".to_string(),
                (n, true) => format!(
                    "light paths from {n} point and spot lights bring their highlights off glossy surfaces, one per {} camera samples (--caustics)",
                    (1.0 / crate::integrator::light_paths::RATE).round()
                ),
                (n, false) => format!(
                    "off (the scene file's render.caustics): {n} point and spot lights' highlights left to the path tracer"
                ),
            }
        )?;
        for (name, what) in &r.extensions {
            writeln!(f, "extension    {name}: {what}")?;
        }
        for w in &r.warnings {
            writeln!(f, "warning      {w}")?;
        }
        Ok(())
    }
}
