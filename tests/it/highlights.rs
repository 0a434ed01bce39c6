//! Light paths for the highlights of point and spot lights on glossy surfaces: the image they
//! give agrees with the path tracer's alone, with less noise, and stays bit-identical for any
//! thread count and any split into sample ranges.

use crate::render::{compare_films, floor_and_metal_wall};
use crate::split::ok;
use myriad::film::Film;
use myriad::light::SpotCurve;
use myriad::light_sampler::LightStrategy;
use myriad::math::{Rgb, Vec3A};
use myriad::render::{Budget, RenderSettings, render};
use myriad::scene::description::LightDesc;
use myriad::settings::{Clamp, LightSamplerKind};
use std::sync::Arc;

/// A diffuse floor and a glossy metal wall of `roughness` that mirrors a spot light aimed at
/// it onto the floor the camera sees, and with `point`, a point light that lights the floor
/// too. Without it the floor's light is almost all highlight: what light paths carry.
fn mirrored_lights(roughness: f32, point: bool) -> crate::common::TestScene {
    let mut lights = vec![LightDesc::Spot {
        name: Arc::from("spot"),
        position: Vec3A::new(0.7, 0.7, 0.4),
        direction: Vec3A::new(-0.7, -0.3, -1.4).normalize(),
        intensity: Rgb::new(3.0, 4.5, 9.0),
        inner_angle: 0.08,
        outer_angle: 0.15,
        curve: SpotCurve::Smoothstep,
        lamp: None,
    }];
    if point {
        lights.push(LightDesc::Point {
            name: Arc::from("point"),
            position: Vec3A::new(-0.6, 0.5, 0.2),
            intensity: Rgb::new(2.0, 1.5, 1.0),
            lamp: None,
        });
    }
    floor_and_metal_wall(roughness, lights)
}

/// A render of `scene` with light paths (`caustics`) or the path tracer alone.
fn render_scene(scene: &crate::common::TestScene, budget: Budget, seed: u64, caustics: bool) -> (Film, u64) {
    let strategy = LightStrategy::build(LightSamplerKind::Tree, &scene.lights, scene.center, scene.radius);
    let settings = RenderSettings {
        budget,
        seed,
        max_depth: 3,
        clamp: Clamp::OFF,
        guiding: false,
        caustics,
        resolution: scene.resolution,
        aovs: Default::default(),
    };
    let out = render(scene, &strategy, &settings, &mut ());
    (out.film, out.stats.rays.splats)
}

/// The z-score of the difference between two films' mean over the floor (the image's lower
/// half, where the wall's highlights land): where light paths carry most of the light.
fn floor_z(a: &Film, b: &Film) -> f64 {
    let w = a.size().x as usize;
    let floor = (a.size().y as usize / 2 * w)..(a.size().y as usize * w);
    let (d, v) = floor.fold((0.0, 0.0), |(d, v), i| {
        let diff = (a.mean(i) - b.mean(i)).element_sum() as f64 / 3.0;
        (d + diff, v + (a.variance_of_mean(i) + b.variance_of_mean(i)).element_sum() as f64 / 3.0)
    });
    d / v.sqrt()
}

/// The summed relative variance of a film's pixel means, relative to `reference`'s means
/// (as relMSE: variance / (mean² + 0.01), so that the bright highlight the camera sees on
/// the wall itself, which light paths do not take, does not outweigh the floor).
fn relative_variance(film: &Film, reference: &Film) -> f64 {
    (0..(film.size().x * film.size().y) as usize)
        .map(|i| {
            let m = reference.mean(i).element_sum() as f64 / 3.0;
            film.variance_of_mean(i).element_sum() as f64 / 3.0 / (m * m + 0.01)
        })
        .sum()
}

/// Both strategies weighed against each other give the path tracer's image (within noise,
/// image mean and per pixel) at two roughnesses, and with much less variance where the wall
/// mirrors the lights sharply. A wrong weight, density or importance moves the image (a
/// fifth too much light from light paths fails it; the path tracer's own noise is the limit). (The
/// path tracer alone needs many samples at the lower roughness: with fewer, most pixels
/// have not yet met the rare samples that carry their highlight, and their own variance
/// does not say so.)
#[test]
fn light_paths_agree_with_the_path_tracer_and_take_the_highlights_noise_away() {
    for (roughness, point, spp_alone, at_least) in [(0.2, false, 16384, 3.0), (0.35, true, 16384, 1.3)] {
        let scene = mirrored_lights(roughness, point);
        let (traced, splats) = render_scene(&scene, Budget::Spp(1024), 1, true);
        let (alone, none) = render_scene(&scene, Budget::Spp(spp_alone), 2, false);
        assert!(splats > 3000 && none == 0, "{splats} splats with light paths, {none} without");
        if point {
            // (Under the spot alone most pixels are all but black, and light paths bring them
            // light the path tracer's 16384 samples never met: its per-pixel variance is no
            // yardstick there.)
            compare_films(&traced, &alone, 0.01, &format!("light paths at roughness {roughness}"));
        }
        let z = floor_z(&traced, &alone);
        assert!(z.abs() < 3.5, "roughness {roughness}: the floor's mean differs by z = {z:.2}");
        let gain =
            relative_variance(&alone, &traced) * spp_alone as f64 / (relative_variance(&traced, &traced) * 1024.0);
        assert!(gain > at_least, "roughness {roughness}: variance per sample only {gain:.2}× lower");
    }
}

/// Splats from any worker land in any pixel: their sums are integers, so the image is the
/// same bits for any thread count, and samples 0..5 and 5..12 merge to the render of 0..12.
#[test]
fn light_paths_keep_images_identical_across_threads_and_sample_ranges() {
    let scene = mirrored_lights(0.2, true);
    let in_pool = |threads: usize, budget: Budget| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| render_scene(&scene, budget, 7, true).0)
    };
    let whole = in_pool(1, Budget::Spp(12));
    assert!(whole.has_splats());
    assert!(whole.same_sums(&in_pool(3, Budget::Spp(12))), "3 threads differ from 1");
    let mut merged = in_pool(2, Budget::Samples(0, 5));
    merged.merge(&in_pool(3, Budget::Samples(5, 12)));
    assert!(merged.same_sums(&whole), "merged sample ranges differ from one render");
    let bytes = Film::from_sums_bytes(whole.size(), 12, false, true, &whole.sums_bytes()).expect("sums read back");
    assert!(bytes.same_sums(&whole), "a part's bytes lose the splats");
}

/// What a user sees: `info` says which lights light paths start from, the render summary
/// counts them and what they brought, a part file says it holds their splats, and
/// `--caustics off` turns them off.
#[test]
fn the_summary_info_and_parts_say_what_light_paths_did() {
    let dir = tempfile::tempdir().unwrap();
    let materials = crate::common::blender("materials.glb");
    let materials = materials.to_str().unwrap();
    let info = ok(&["info", materials], dir.path());
    assert!(info.contains("highlights   light paths from 2 point and spot lights"), "{info}");
    let out = ok(&["render", materials, "--spp", "8", "--resolution", "32x24"], dir.path());
    let line = out.lines().find(|l| l.starts_with("highlights")).unwrap_or_default();
    assert!(
        line.contains("light paths from 2 point and spot lights") && line.contains("off a glossy surface"),
        "{out}"
    );
    let off = ok(&["render", materials, "--spp", "8", "--resolution", "32x24", "--caustics", "off"], dir.path());
    assert!(!off.contains("highlights"), "{off}");
    // punctual.glb's one glossy (Principled) material mirrors its point and spot lights nowhere
    // the camera sees: the probes find no highlight, and no light path is traced.
    let punctual = crate::common::blender("punctual.glb");
    let punctual = punctual.to_str().unwrap();
    assert!(ok(&["info", punctual], dir.path()).contains("highlights   no point or spot light whose highlight"));
    let open = ok(&["render", punctual, "--spp", "2", "--resolution", "32x24"], dir.path());
    assert!(!open.contains("highlights"), "{open}");
    // Two parts merge to the bits of one render, splats and all.
    let size = ["--resolution", "32x24"];
    ok(&[&["render", materials, "--samples", "0..3", "-o", "a.part"][..], &size].concat(), dir.path());
    ok(&[&["render", materials, "--samples", "3..4", "-o", "b.part"][..], &size].concat(), dir.path());
    let part = std::fs::read(dir.path().join("a.part")).unwrap();
    assert!(String::from_utf8_lossy(&part[..400]).contains("\"light_paths\":true"));
    ok(&["merge", "a.part", "b.part", "-o", "merged.exr"], dir.path());
    ok(&[&["render", materials, "--spp", "4", "-o", "whole.exr"][..], &size].concat(), dir.path());
    let diff = ok(&["diff", "merged.exr", "whole.exr"], dir.path());
    assert!(diff.contains("MSE     0\n"), "{diff}");
}
