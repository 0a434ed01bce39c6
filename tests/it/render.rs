//! Image-level tests: analytic direct lighting, analytic enclosures, agreement between
//! samplers on a real scene, and determinism across thread counts.

use crate::common::{TestScene, polygon_irradiance, quad_light, scene_from, sidak, z_p_value};
use myriad::commands::load_scene;
use myriad::film::Film;
use myriad::light_sampler::LightStrategy;
use myriad::material::Material;
use myriad::math::{Mat4, Rgb, UVec2, Vec2, Vec3A};
use myriad::render::{Budget, OnPass, RenderSettings, render};
use myriad::scene::BuildOptions;
use myriad::scene::description::LightDesc;
use myriad::scene::shapes::{box_mesh, quad_mesh};
use myriad::settings::{Clamp, LightSamplerKind};

pub const ALL_KINDS: [LightSamplerKind; 7] = LightSamplerKind::EVERY;

pub fn render_with(scene: &TestScene, kind: LightSamplerKind, spp: u32, max_depth: u32, seed: u64) -> Film {
    render_guided(scene, kind, spp, max_depth, seed, false)
}

/// [`render_with`], with path guiding on or off.
pub fn render_guided(
    scene: &TestScene,
    kind: LightSamplerKind,
    spp: u32,
    max_depth: u32,
    seed: u64,
    guiding: bool,
) -> Film {
    let strategy = LightStrategy::build(kind, &scene.lights, scene.center, scene.radius);
    let resolution = scene.resolution;
    let settings = RenderSettings {
        budget: Budget::Spp(spp),
        seed,
        max_depth,
        clamp: Clamp::OFF,
        guiding,
        caustics: true,
        resolution,
        aovs: Default::default(),
    };
    render(scene, &strategy, &settings, &mut ()).film
}

/// Z-test of the image mean against `expected` per pixel, and the fraction of pixel values
/// beyond 3.29σ. Channels are averaged per pixel with the worst-case (fully correlated)
/// variance, since RGB of one path are strongly correlated. The standard error is the larger
/// of the film's own per-pixel variances and the spread of the residuals across pixels.
pub fn check_against(film: &Film, expected: &dyn Fn(usize) -> Rgb, alpha: f64, label: &str) {
    let residuals: Vec<(f64, f64)> = (0..(film.size().x * film.size().y) as usize)
        .map(|i| {
            let (m, v, e) = (film.mean(i), film.variance_of_mean(i), expected(i));
            let r = (0..3).map(|c| (m[c] - e[c]) as f64).sum::<f64>() / 3.0;
            let sd = (0..3).map(|c| (v[c] as f64).sqrt()).sum::<f64>() / 3.0;
            (r, sd * sd)
        })
        .collect();
    z_test_residuals(&residuals, alpha, label);
}

/// The shared statistic of [`check_against`] and [`compare_films`] over (residual, variance)
/// pairs.
pub fn z_test_residuals(residuals: &[(f64, f64)], alpha: f64, label: &str) {
    let k = residuals.len() as f64;
    let diff: f64 = residuals.iter().map(|r| r.0).sum();
    let var: f64 = residuals.iter().map(|r| r.1).sum();
    let sq: f64 = residuals.iter().map(|r| r.0 * r.0).sum();
    let across = k / (k - 1.0) * (sq - diff * diff / k);
    let z = diff / var.max(across).sqrt().max(1e-30);
    assert!(z_p_value(z) > alpha, "{label}: image mean differs by {} (z = {z})", diff / k);
    let outliers = residuals.iter().filter(|(r, v)| r.abs() > 3.29 * v.sqrt() + 1e-7).count();
    assert!(outliers as f64 <= 0.01 * k + 2.0, "{label}: {outliers} of {k} pixels beyond 3.29σ");
}

/// A diffuse floor watched from above, lit by three quads at its sides (outside the view) with
/// radiances a decade apart. Direct lighting only; each pixel must average ρ/π·E over its
/// footprint, E from Lambert's polygon formula.
#[test]
fn direct_light_under_quads_matches_lambert_formula() {
    let rho = 0.6f32;
    let lights = [
        (Vec3A::new(-1.6, 0.3, -0.5), Vec3A::new(0.0, 0.0, 1.0), Vec3A::new(0.4, 0.5, 0.0), 4.0f32),
        (Vec3A::new(1.6, 0.4, 0.6), Vec3A::new(0.0, 0.0, -1.2), Vec3A::new(-0.3, 0.6, 0.0), 40.0),
        (Vec3A::new(-0.6, 0.5, -1.7), Vec3A::new(1.0, 0.0, 0.0), Vec3A::new(0.0, 0.4, 0.4), 0.4),
    ];
    let descs: Vec<LightDesc> = lights.iter().map(|&(c, a, b, l)| quad_light(c, b, a, Rgb::splat(l), false)).collect();
    let floor =
        quad_mesh("floor", Vec3A::new(-5.0, 0.0, 5.0), Vec3A::new(10.0, 0.0, 0.0), Vec3A::new(0.0, 0.0, -10.0), 0);
    let res = UVec2::new(12, 12);
    let scene = scene_from(
        vec![Material::diffuse("floor", Rgb::splat(rho))],
        vec![(floor, Mat4::IDENTITY)],
        descs.clone(),
        Vec3A::new(0.0, 2.5, 0.0),
        Vec3A::ZERO,
        res,
    );
    // Expected pixel values by 8×8 quadrature over the pixel footprint.
    let irradiance = |p: Vec3A| -> f64 {
        descs
            .iter()
            .map(|d| {
                let LightDesc::Quad { corner, edge1, edge2, radiance, .. } = d else { unreachable!() };
                let n = edge1.cross(*edge2);
                if (p - *corner).dot(n) <= 0.0 {
                    return 0.0;
                }
                let q = [*corner, *corner + *edge1, *corner + *edge1 + *edge2, *corner + *edge2];
                polygon_irradiance(p, Vec3A::Y, &q, radiance.x as f64)
            })
            .sum()
    };
    let expected: Vec<f64> = (0..res.x * res.y)
        .map(|i| {
            let pixel = UVec2::new(i % res.x, i / res.x);
            let mut acc = 0.0;
            for s in 0..64 {
                let j = Vec2::new(((s % 8) as f32 + 0.5) / 8.0, ((s / 8) as f32 + 0.5) / 8.0);
                let ray = scene.camera.ray(pixel, res, j);
                let t = -ray.origin.y / ray.dir.y;
                acc += irradiance(ray.at(t));
            }
            acc / 64.0 * rho as f64 / std::f64::consts::PI
        })
        .collect();
    assert!(expected.iter().all(|e| *e > 0.0));
    let alpha = sidak(ALL_KINDS.len());
    for kind in ALL_KINDS {
        let film = render_with(&scene, kind, 256, 1, 3);
        check_against(&film, &|i| Rgb::splat(expected[i] as f32), alpha, kind.name());
    }
}

/// A box of side `size` whose faces point inwards: each quad (a,b,c,d) reversed to (a,d,c,b).
pub fn inward_box(size: f32) -> myriad::scene::description::MeshDesc {
    let mut mesh = box_mesh("inward box", Vec3A::splat(size), 0);
    for pair in mesh.triangles.chunks_exact_mut(2) {
        let [a, b, c] = pair[0];
        let d = pair[1][2];
        pair[0] = [a, d, c];
        pair[1] = [a, c, b];
    }
    mesh
}

/// A closed box whose inward faces all emit Le and reflect ρ: radiance is exactly
/// Le·(1 − ρ^(d+1))/(1 − ρ) at max depth d, and Le/(1 − ρ) with Russian roulette only.
#[test]
fn closed_emissive_box_renders_the_analytic_value() {
    let (le, rho) = (0.5f32, 0.5f32);
    let material =
        Material { emission: Rgb::splat(le), double_sided: false, ..Material::diffuse("wall", Rgb::splat(rho)) };
    let scene = scene_from(
        vec![material],
        vec![(inward_box(2.0), Mat4::IDENTITY)],
        vec![],
        Vec3A::new(0.1, -0.2, 0.3),
        Vec3A::new(1.0, 0.3, 0.2),
        UVec2::new(8, 8),
    );
    assert_eq!(scene.lights.len(), 6);
    let cases = [(3u32, le * (1.0 - rho.powi(4)) / (1.0 - rho)), (10_000, le / (1.0 - rho))];
    let alpha = sidak(ALL_KINDS.len() * cases.len());
    for kind in ALL_KINDS {
        for (depth, expect) in cases {
            let film = render_with(&scene, kind, 128, depth, 5);
            check_against(&film, &|_| Rgb::splat(expect), alpha, &format!("{kind} depth {depth}"));
        }
    }
}

/// A closed box tessellated into `2·6·k²` inward-facing emissive triangles (k = 41: 20 172
/// lights) has the same analytic radiance: a many-light scene whose image mean is known
/// exactly, for the per-point samplers.
#[test]
fn tessellated_emissive_box_renders_the_analytic_value() {
    let (le, rho, k) = (0.5f32, 0.5f32, 41usize);
    let material =
        Material { emission: Rgb::splat(le), double_sided: false, ..Material::diffuse("wall", Rgb::splat(rho)) };
    let mut mesh = myriad::scene::description::MeshDesc { name: "box".into(), material: 0, ..Default::default() };
    let coarse = inward_box(2.0);
    for pair in coarse.triangles.chunks_exact(2) {
        let [a, b, _] = pair[0].map(|i| coarse.positions[i as usize]);
        let d = coarse.positions[pair[1][2] as usize];
        let base = mesh.positions.len() as u32;
        for j in 0..=k {
            for i in 0..=k {
                let (s, t) = (i as f32 / k as f32, j as f32 / k as f32);
                mesh.positions.push(a + (b - a) * s + (d - a) * t);
            }
        }
        let at = |i: usize, j: usize| base + (j * (k + 1) + i) as u32;
        for j in 0..k {
            for i in 0..k {
                mesh.triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                mesh.triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
    let eye = Vec3A::new(0.1, -0.2, 0.3);
    let scene = scene_from(
        vec![material],
        vec![(mesh, Mat4::IDENTITY)],
        vec![],
        eye,
        Vec3A::new(1.0, 0.3, 0.2),
        UVec2::new(6, 6),
    );
    // Every cell of a face is a parallelogram: one quad light.
    assert_eq!(scene.lights.len(), 6 * k * k);
    let expect = le * (1.0 - rho.powi(3)) / (1.0 - rho);
    let kinds = [LightSamplerKind::Local, LightSamplerKind::Tree, LightSamplerKind::Cells];
    for kind in kinds {
        let film = render_with(&scene, kind, 96, 2, 8);
        check_against(&film, &|_| Rgb::splat(expect), sidak(kinds.len()), kind.name());
    }
}

fn scene_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

/// Every one-light sampler agrees with `all` on the predecessor project's 9×9 Cornell box (image-mean
/// z-test and per-pixel outliers, with both films' variances).
#[test]
fn samplers_agree_on_cornell_9x9() {
    let opts = BuildOptions { resolution: Some(UVec2::new(32, 24)), camera: None, ..Default::default() };
    let scene = TestScene::from(load_scene(Some(&scene_path("cornell-9x9.ron")), &opts.clone().into()).unwrap());
    let reference = render_with(&scene, LightSamplerKind::All, 64, 3, 11);
    let kinds = &ALL_KINDS[1..];
    let alpha = sidak(kinds.len());
    for &kind in kinds {
        let film = render_with(&scene, kind, 64, 3, 12);
        compare_films(&film, &reference, alpha, kind.name());
    }
}

/// A diffuse floor and a glossy metal wall of roughness `roughness` behind it, seen from
/// above at 24 × 18, lit by `lamps`: paths meet both kinds of vertex.
pub fn floor_and_metal_wall(roughness: f32, lamps: Vec<LightDesc>) -> TestScene {
    let metal = Material { metallic: 1.0, roughness, ..Material::diffuse("metal", Rgb::new(0.9, 0.7, 0.5)) };
    let floor =
        quad_mesh("floor", Vec3A::new(-2.0, 0.0, 2.0), Vec3A::new(4.0, 0.0, 0.0), Vec3A::new(0.0, 0.0, -4.0), 0);
    let wall = quad_mesh("wall", Vec3A::new(-2.0, 0.0, -1.0), Vec3A::new(4.0, 0.0, 0.0), Vec3A::new(0.0, 2.0, 0.0), 1);
    scene_from(
        vec![Material::diffuse("floor", Rgb::splat(0.7)), metal],
        vec![(floor, Mat4::IDENTITY), (wall, Mat4::IDENTITY)],
        lamps,
        Vec3A::new(0.0, 1.4, 2.4),
        Vec3A::new(0.0, 0.2, -0.4),
        UVec2::new(24, 18),
    )
}

/// The default over a few lights takes every light at diffuse points and the tree's one at
/// glossy ones, and weighs a BSDF ray that meets a lamp by whichever the vertex it left from
/// did. With both kinds of vertex on the paths (a diffuse floor, a glossy metal wall, two
/// coloured lamps close above them) it agrees with `all` and with the tree.
#[test]
fn every_light_at_diffuse_points_agrees_with_all_and_the_tree() {
    // Large lamps low over the floor, facing it (edge1 × edge2 points down): BSDF rays from
    // the floor meet them often, so a wrong MIS weight there shows.
    let lamps = vec![
        quad_light(Vec3A::new(-1.2, 0.4, -0.8), Vec3A::X, Vec3A::Z, Rgb::new(3.0, 0.5, 0.2), false),
        quad_light(Vec3A::new(0.2, 0.35, -0.6), Vec3A::X * 0.8, Vec3A::Z * 0.8, Rgb::new(0.2, 0.5, 2.5), true),
    ];
    let scene = floor_and_metal_wall(0.4, lamps);
    let strategy = LightStrategy::build(LightSamplerKind::Cells, &scene.lights, scene.center, scene.radius);
    assert!(matches!(strategy, LightStrategy::EveryAtDiffuse(_)), "{strategy:?}");
    let reference = render_with(&scene, LightSamplerKind::All, 1024, 3, 1);
    for (kind, seed) in [(LightSamplerKind::Cells, 2), (LightSamplerKind::Tree, 3)] {
        compare_films(&render_with(&scene, kind, 1024, 3, seed), &reference, sidak(2), kind.name());
    }
}

/// At glossy points the tree weighs clusters by the BSDF's lobe too: point lights that a
/// near-mirror metal wall reflects towards the camera, and a lamp whose light BSDF rays from
/// the wall meet (weighed by the pmf of the same lobe-weighted choice), agree with `all`.
#[test]
fn lobe_weighted_choice_at_glossy_points_agrees_with_all() {
    let point = |x: f32, z: f32, intensity: Rgb| LightDesc::Point {
        name: std::sync::Arc::from("point"),
        position: Vec3A::new(x, 0.6, z),
        intensity,
        lamp: None,
    };
    let mut lamps: Vec<_> = [(-1.0, 0.3), (0.1, 0.8), (0.9, -0.2), (-0.3, -0.6)]
        .iter()
        .enumerate()
        .map(|(i, &(x, z))| point(x, z, Rgb::new(0.6, 0.4, 0.3) * (1 + i) as f32))
        .collect();
    // A panel between the camera and the wall, facing the wall: the camera sees it mirrored.
    lamps.push(quad_light(Vec3A::new(-0.6, 0.5, 0.3), Vec3A::X * 0.8, Vec3A::Y * 0.6, Rgb::new(0.5, 1.0, 2.0), true));
    let scene = floor_and_metal_wall(0.3, lamps);
    let reference = render_with(&scene, LightSamplerKind::All, 1024, 3, 1);
    for (kind, seed) in [(LightSamplerKind::Tree, 2), (LightSamplerKind::Cells, 3)] {
        compare_films(&render_with(&scene, kind, 1024, 3, seed), &reference, sidak(2), kind.name());
    }
}

/// Over more than 1024 lights the default's tables choose among clusters of them at diffuse
/// points and the tree at glossy ones; with both kinds of point on the paths (a diffuse floor,
/// a glossy metal wall, 1 200 small lamps of three colours close above them) it agrees with
/// the tree, and the BSDF rays that meet a lamp are weighed by what chose at their vertex.
#[test]
fn cells_over_clusters_agrees_with_the_tree_at_diffuse_and_glossy_points() {
    let colours = [Rgb::new(3.0, 0.5, 0.2), Rgb::new(0.2, 0.5, 2.5), Rgb::splat(1.5)];
    let lamps: Vec<_> = (0..1200)
        .map(|i| {
            let corner =
                Vec3A::new(-1.8 + (i % 40) as f32 * 0.09, 0.3 + (i % 7) as f32 * 0.1, -0.9 + (i / 40) as f32 * 0.09);
            quad_light(corner, Vec3A::X * 0.08, Vec3A::Z * 0.08, colours[i % 3] * 5.0, i % 5 == 0)
        })
        .collect();
    let scene = floor_and_metal_wall(0.3, lamps);
    let strategy = LightStrategy::build(LightSamplerKind::Cells, &scene.lights, scene.center, scene.radius);
    assert_eq!(strategy.label(LightSamplerKind::Cells), "cells");
    let reference = render_with(&scene, LightSamplerKind::Tree, 512, 3, 1);
    compare_films(&render_with(&scene, LightSamplerKind::Cells, 512, 3, 2), &reference, 0.01, "cells");
}

/// Two independent renders of the same thing agree: image-mean z-test and few outliers.
pub fn compare_films(a: &Film, b: &Film, alpha: f64, label: &str) {
    let residuals: Vec<(f64, f64)> = (0..(a.size().x * a.size().y) as usize)
        .map(|i| {
            let (d, va, vb) = (a.mean(i) - b.mean(i), a.variance_of_mean(i), b.variance_of_mean(i));
            let r = (d.x + d.y + d.z) as f64 / 3.0;
            let sd = (0..3).map(|c| ((va[c] + vb[c]) as f64).sqrt()).sum::<f64>() / 3.0;
            (r, sd * sd)
        })
        .collect();
    z_test_residuals(&residuals, alpha, label);
}

#[test]
fn same_seed_gives_identical_pixels_for_any_thread_count() {
    // `learned` too: what it learns between passes must not depend on the threads either;
    // and `cells`, whose tables whichever thread comes first builds.
    // Path guiding, which learns between passes as well.
    for kind in [LightSamplerKind::Power, LightSamplerKind::Learned, LightSamplerKind::Cells] {
        identical_for_any_thread_count(kind, false);
    }
    identical_for_any_thread_count(LightSamplerKind::Tree, true);
}

fn identical_for_any_thread_count(kind: LightSamplerKind, guiding: bool) {
    let opts = BuildOptions { resolution: Some(UVec2::new(24, 18)), camera: None, ..Default::default() };
    let films: Vec<Film> = [1usize, 2, 3]
        .iter()
        .map(|&threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let scene = TestScene::from(load_scene(None, &opts.clone().into()).unwrap());
                render_guided(&scene, kind, 20, 8, 42, guiding)
            })
        })
        .collect();
    for f in &films[1..] {
        let n = (f.size().x * f.size().y) as usize;
        for i in 0..n {
            assert_eq!(
                f.mean(i).to_array().map(f32::to_bits),
                films[0].mean(i).to_array().map(f32::to_bits),
                "pixel {i}"
            );
            assert_eq!(f.variance_of_mean(i), films[0].variance_of_mean(i));
        }
    }
    // A different seed gives a different image.
    let scene = TestScene::from(load_scene(None, &opts.clone().into()).unwrap());
    let other = render_with(&scene, kind, 8, 8, 43);
    assert!((0..24 * 18).any(|i| other.mean(i) != films[0].mean(i)));
}

#[test]
fn pass_boundaries_do_not_change_pixels() {
    // A fixed-spp render runs passes of 1, 1, 2, 4 samples; an equal-time render runs passes
    // sized by the clock. Both add each pixel's samples in index order, so whatever spp the
    // timed render reached, a fixed-spp render of that many samples matches it bit for bit.
    let opts = BuildOptions { resolution: Some(UVec2::new(8, 6)), camera: None, ..Default::default() };
    let scene = load_scene(None, &opts.clone().into()).unwrap().scene;
    let strategy = LightStrategy::build(LightSamplerKind::Uniform, &scene.lights, scene.center, scene.radius);
    let resolution = UVec2::new(8, 6);
    let settings = RenderSettings {
        budget: Budget::Spp(8),
        seed: 9,
        max_depth: 4,
        clamp: Clamp::OFF,
        guiding: false,
        caustics: true,
        resolution,
        aovs: Default::default(),
    };
    let mut passes = Vec::new();
    render(&scene, &strategy, &settings, &mut OnPass(|f: &myriad::film::Film, _| passes.push(f.spp())));
    assert_eq!(passes, [1, 2, 4, 8]);
    let timed = RenderSettings { budget: Budget::Time(std::time::Duration::from_millis(200)), ..settings };
    let mut timed_passes = Vec::new();
    let out = render(&scene, &strategy, &timed, &mut OnPass(|f: &myriad::film::Film, _| timed_passes.push(f.spp())));
    assert!(timed_passes.len() > 1 && timed_passes.windows(2).all(|w| w[0] < w[1]));
    let fixed = RenderSettings { budget: Budget::Spp(out.stats.spp), ..settings };
    let again = render(&scene, &strategy, &fixed, &mut ()).film;
    for i in 0..48 {
        assert_eq!(out.film.mean(i), again.mean(i), "pixel {i}");
    }
}

#[test]
fn a_progressive_render_in_passes_of_its_own_is_the_render_and_a_called_off_pass_says_so() {
    // The viewer drives `Progressive` itself (passes of 3, then 5) and calls passes off when
    // its view changes: the image at 8 spp is `render`'s, and a called-off pass is None.
    let resolution = UVec2::new(8, 6);
    let scene =
        load_scene(None, &BuildOptions { resolution: Some(resolution), camera: None, ..Default::default() }.into())
            .unwrap()
            .scene;
    let strategy = LightStrategy::build(LightSamplerKind::Learned, &scene.lights, scene.center, scene.radius);
    let settings = RenderSettings {
        budget: Budget::Spp(8),
        seed: 4,
        max_depth: 3,
        clamp: Clamp::OFF,
        guiding: false,
        caustics: true,
        resolution,
        aovs: Default::default(),
    };
    let mut progressive = myriad::render::Progressive::new(&scene, &strategy, &settings);
    let go_on = std::sync::atomic::AtomicBool::new(false);
    let mut spp = 0;
    while spp < 8 {
        spp += progressive.pass_unless(if spp == 0 { 3 } else { 5 }, None, Some(&go_on)).unwrap();
    }
    let whole = render(&scene, &strategy, &settings, &mut ()).film;
    for i in 0..48 {
        assert_eq!(progressive.film().mean(i), whole.mean(i), "pixel {i}");
    }
    let stop = std::sync::atomic::AtomicBool::new(true);
    let mut called_off = myriad::render::Progressive::new(&scene, &strategy, &settings);
    assert_eq!(called_off.pass_unless(4, None, Some(&stop)), None);
}

#[test]
fn the_image_size_is_a_render_setting_not_part_of_the_scene() {
    // A scene built for 8 × 6 renders at 16 × 12 exactly as one built for 16 × 12 does.
    let built = |w, h| {
        let opts = BuildOptions { resolution: Some(UVec2::new(w, h)), camera: None, ..Default::default() };
        load_scene(None, &opts.into()).unwrap().scene
    };
    let (small, large) = (built(8, 6), built(16, 12));
    let strategy = LightStrategy::build(LightSamplerKind::Power, &small.lights, small.center, small.radius);
    let resolution = UVec2::new(16, 12);
    let settings = RenderSettings {
        budget: Budget::Spp(4),
        seed: 3,
        max_depth: 4,
        clamp: Clamp::OFF,
        guiding: false,
        caustics: true,
        resolution,
        aovs: Default::default(),
    };
    let a = render(&small, &strategy, &settings, &mut ()).film;
    let b = render(&large, &strategy, &settings, &mut ()).film;
    assert_eq!(a.size(), resolution);
    assert_eq!(a.means(), b.means());
}

/// `learned` stays unbiased where it learns most: behind the walls of the office floor it
/// moves samples off hidden lamps, and its image agrees with the tree's (independent seeds).
#[test]
fn learned_agrees_with_the_tree_where_lights_are_hidden() {
    let opts = BuildOptions { resolution: Some(UVec2::new(32, 24)), camera: None, ..Default::default() };
    let scene = TestScene::from(load_scene(Some(&scene_path("offices.ron")), &opts.clone().into()).unwrap());
    let reference = render_with(&scene, LightSamplerKind::Tree, 64, 3, 21);
    for seed in [22, 23] {
        let film = render_with(&scene, LightSamplerKind::Learned, 64, 3, seed);
        compare_films(&film, &reference, sidak(2), "learned");
    }
}
