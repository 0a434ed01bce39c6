//! Light through smooth glass: next-event estimation solves for the refractions
//! (`integrator::mnee`), and what it finds is the light BSDF sampling finds along the same
//! paths, with far less noise.

use crate::common::{TestScene, blender, scene_from};
use crate::render::render_with;
use crate::split::{myriad, text};
use myriad::light::{LampModel, SpotCurve};
use myriad::material::Material;
use myriad::math::{Mat4, Rgb, UVec2, Vec3A};
use myriad::scene::description::{LampShape, LightDesc};
use myriad::scene::shapes::{quad_mesh, sphere_mesh};
use myriad::settings::LightSamplerKind;

/// Samples per pixel and seeds of each set of renders: equal for both estimators, since the
/// light the ball reflects (found by BSDF sampling alone in both) is a rare hit at fewer.
const SPP: u32 = 512;
const SEEDS: u64 = 4;

/// A grey floor under a glass ball (radius 0.5, centre 0.8 m up, of `roughness`) with a lamp
/// facing down (an emissive quad): a small one inside the ball (`inside`: one refraction
/// between them) or a large one above it (two), seen from above at 32 × 24 pixels. (A small
/// lamp above the ball makes BSDF sampling alone too heavy-tailed to compare with: over 12
/// seeds its image mean stays 1.4 % under the connection's, where a 1.2 m lamp agrees to
/// 0.1 %.)
fn ball(inside: bool, roughness: f32) -> TestScene {
    ball_lit(inside, roughness, None)
}

/// The same ball, lit by `lamp` instead of the quad when there is one.
fn ball_lit(inside: bool, roughness: f32, lamp: Option<LightDesc>) -> TestScene {
    let floor = Material::diffuse("floor", Rgb::splat(0.8));
    let glass = Material { transmission: 1.0, roughness, ior: 1.5, ..Material::diffuse("glass", Rgb::ONE) };
    let lamp_material =
        Material { emission: Rgb::new(40.0, 30.0, 20.0), double_sided: false, ..Material::diffuse("lamp", Rgb::ZERO) };
    let (y, size) = if inside { (0.85, 0.2) } else { (1.6, 1.2) };
    let corner = Vec3A::new(-size / 2.0, y, -size / 2.0);
    let mut meshes = vec![
        (quad_mesh("floor", Vec3A::new(-3.0, 0.0, -3.0), Vec3A::Z * 6.0, Vec3A::X * 6.0, 0), Mat4::IDENTITY),
        (sphere_mesh("ball", Vec3A::new(0.0, 0.8, 0.0), 0.5, 4, 1), Mat4::IDENTITY),
    ];
    if lamp.is_none() {
        // Edges x then z: the front faces −y, down to the floor.
        meshes.push((quad_mesh("lamp", corner, Vec3A::X * size, Vec3A::Z * size, 2), Mat4::IDENTITY));
    }
    // A lamp, unlike the quad, shines up too and is seen through the ball: its own noise
    // (the pixels it covers in part) would hide the connection's gain, so its camera looks
    // down on the floor beside the ball, lit only through the glass.
    let (eye, at) = match lamp {
        None => (Vec3A::new(0.0, 3.0, 2.2), Vec3A::new(0.0, 0.0, 0.3)),
        Some(_) => (Vec3A::new(1.5, 2.0, 0.0), Vec3A::new(1.5, 0.0, 0.01)),
    };
    let lights = lamp.into_iter().collect();
    scene_from(vec![floor, glass, lamp_material], meshes, lights, eye, at, UVec2::new(32, 24))
}

/// Per seed ([`SEEDS`] of them from `first`), the mean of every 4 × 4-pixel region (RGB), with
/// light through glass found by next-event estimation (`solved`) or by BSDF sampling alone.
fn region_means(scene: &mut TestScene, solved: bool, first: u64) -> Vec<Vec<Rgb>> {
    scene.scene.caustics = solved;
    let (w, h) = (scene.resolution.x as usize, scene.resolution.y as usize);
    (0..SEEDS)
        .map(|seed| {
            let film = render_with(scene, LightSamplerKind::Tree, SPP, 6, first + seed);
            let mut sums = vec![Rgb::ZERO; (w / 4) * (h / 4)];
            (0..w * h).for_each(|i| sums[(i % w) / 4 + (i / w) / 4 * (w / 4)] += film.mean(i) / 16.0);
            sums
        })
        .collect()
}

/// Mean and variance of the mean of each region over the seeds.
fn spread(runs: &[Vec<Rgb>]) -> Vec<(Rgb, Rgb)> {
    let n = runs.len() as f32;
    (0..runs[0].len())
        .map(|r| {
            let mean = runs.iter().fold(Rgb::ZERO, |a, run| a + run[r]) / n;
            let var = runs.iter().fold(Rgb::ZERO, |a, run| a + (run[r] - mean) * (run[r] - mean)) / ((n - 1.0) * n);
            (mean, var)
        })
        .collect()
}

/// Mean and variance of the mean of the whole image's sum over the seeds.
fn image_spread(runs: &[Vec<Rgb>]) -> (f64, f64) {
    let totals: Vec<f64> = runs.iter().map(|run| run.iter().map(|v| v.element_sum() as f64).sum()).collect();
    let n = totals.len() as f64;
    let mean = totals.iter().sum::<f64>() / n;
    (mean, totals.iter().map(|t| (t - mean) * (t - mean)).sum::<f64>() / ((n - 1.0) * n))
}

/// Renders `scene` with its light through glass solved for and with BSDF sampling alone
/// ([`SEEDS`] each) and asserts that both agree (image mean and 4 × 4-pixel regions) and,
/// with `least_gain`, that solving lowers the variance at least that many times.
fn assert_solved_is_what_bsdf_sampling_finds(mut scene: TestScene, what: &str, least_gain: Option<f64>) {
    assert!(scene.caustics, "{what}: smooth glass and a light behind it: the scene has caustics to solve for");
    let (solved, sampled) = (region_means(&mut scene, true, 100), region_means(&mut scene, false, 200));
    let (mut z2, mut our_var, mut their_var) = (0.0f64, 0.0, 0.0);
    for ((m, v), (m2, v2)) in spread(&solved).iter().zip(&spread(&sampled)) {
        for c in 0..3 {
            let z = (m[c] - m2[c]) as f64 / ((v[c] + v2[c]) as f64).max(1e-12).sqrt();
            z2 += z * z;
        }
        (our_var, their_var) = (our_var + v.element_sum() as f64, their_var + v2.element_sum() as f64);
    }
    let n = (3 * solved[0].len()) as f64;
    let ((ours, ours_var), (theirs, theirs_var)) = (image_spread(&solved), image_spread(&sampled));
    let z = (ours - theirs) / (ours_var + theirs_var).sqrt();
    let gain = their_var / our_var;
    eprintln!(
        "{what}: image mean {:.4} of BSDF sampling's (z {z:.1}), regions' mean z² {:.2}, variance {gain:.1}× lower",
        ours / theirs,
        z2 / n
    );
    // Over 3 degrees of freedom a t statistic beyond 5.84 has probability 1 %.
    assert!(z.abs() < 5.84, "{what}: image mean {} of BSDF sampling's: t = {z}", ours / theirs);
    // And its square averages 3 (Welch's, roughly).
    assert!(z2 / n < 3.0 + 5.0 * (6.0 / n).sqrt() + 0.5, "{what}: regions' mean z² {}", z2 / n);
    if let Some(least) = least_gain {
        assert!(gain > least, "{what}: solving for the refractions must pay: variance only {gain}× lower");
    }
}

#[test]
fn light_through_smooth_glass_is_solved_for_and_is_what_bsdf_sampling_finds() {
    // Above the ball BSDF sampling finds the large lamp well by itself: only inside must the
    // solved connections pay. Glass as rough as smooth glass may be (0.1) is crossed as
    // smooth by the paths the connection also finds (with next-event estimation at its
    // vertices on those paths as well, the lamp inside came out 8 % too bright).
    for (inside, roughness, least_gain) in [(true, 0.0, Some(10.0)), (true, 0.1, Some(10.0)), (false, 0.0, None)] {
        let what =
            format!("lamp {} (roughness {roughness})", if inside { "inside the ball" } else { "above the ball" });
        assert_solved_is_what_bsdf_sampling_finds(ball(inside, roughness), &what, least_gain);
    }
}

#[test]
fn blender_lamps_inside_smooth_glass_are_solved_for_too() {
    // Blender's point lamp of radius 0.1 inside the ball, as its default disk facing each
    // receiver (which turns to the last refraction of a chain), and a spot lamp (its cone
    // towards the floor in view): BSDF sampling finds each by hitting it; the connection
    // must agree and pay. (A sphere lamp is left to BSDF sampling: its connections, over
    // the cap the receiver sees, did not lower the variance.)
    let (position, intensity) = (Vec3A::new(0.05, 0.85, 0.0), Rgb::new(3.0, 2.5, 2.0));
    let disk = LampShape { radius: 0.1, model: LampModel::FacingDisk, camera_visible: false };
    let lamp = Some(disk);
    let point = LightDesc::Point { name: "lamp".into(), position, intensity, lamp };
    let spot = LightDesc::Spot {
        name: "spot".into(),
        position,
        direction: Vec3A::new(1.2, -1.0, 0.0).normalize(),
        intensity,
        inner_angle: 0.4,
        outer_angle: 0.6,
        curve: SpotCurve::default(),
        lamp,
    };
    for (what, light) in [("point lamp inside the ball", point), ("spot lamp inside the ball", spot)] {
        assert_solved_is_what_bsdf_sampling_finds(ball_lit(true, 0.0, Some(light)), what, Some(10.0));
    }
    let sphere = LightDesc::Point {
        name: "lamp".into(),
        position,
        intensity,
        lamp: Some(LampShape { model: LampModel::Sphere, ..disk }),
    };
    assert!(!ball_lit(true, 0.0, Some(sphere)).caustics, "a sphere lamp is not connected through glass");
}

#[test]
fn a_spot_light_inside_smooth_glass_is_connected_as_the_small_lamp_it_stands_for() {
    // A point-like spot's caustic is the connection's alone (BSDF sampling cannot hit it):
    // it must light the floor as a spot lamp of radius 1 cm does.
    let spot = |lamp| LightDesc::Spot {
        name: "spot".into(),
        position: Vec3A::new(0.05, 0.85, 0.0),
        direction: Vec3A::new(1.2, -1.0, 0.0).normalize(),
        intensity: Rgb::new(3.0, 2.5, 2.0),
        inner_angle: 0.4,
        outer_angle: 0.6,
        curve: SpotCurve::default(),
        lamp,
    };
    let small = Some(LampShape { radius: 0.01, model: LampModel::FacingDisk, camera_visible: false });
    let point_like = region_means(&mut ball_lit(true, 0.0, Some(spot(None))), true, 600);
    let lamp = region_means(&mut ball_lit(true, 0.0, Some(spot(small))), true, 700);
    let ((ours, ours_var), (theirs, theirs_var)) = (image_spread(&point_like), image_spread(&lamp));
    let z = (ours - theirs) / (ours_var + theirs_var).sqrt();
    eprintln!("spot: image mean {:.4} of the 1 cm lamp's (t {z:.1})", ours / theirs);
    assert!(z.abs() < 5.84 && (ours / theirs - 1.0).abs() < 0.02, "image mean {} of the lamp's", ours / theirs);
}

/// A grey floor under a smooth glass ball (radius 0.5, centre 0.8 m up) in the sun from
/// nearly straight above, seen low from the side at 32 × 24 pixels; `as_surface`: the sun
/// made an emissive quad of the same irradiance, 1 m² at 30 m.
fn sunlit_ball(as_surface: bool) -> TestScene {
    let floor = Material::diffuse("floor", Rgb::splat(0.8));
    let glass = Material { transmission: 1.0, roughness: 0.0, ior: 1.5, ..Material::diffuse("glass", Rgb::ONE) };
    let mut meshes = vec![
        (quad_mesh("floor", Vec3A::new(-3.0, 0.0, -3.0), Vec3A::Z * 6.0, Vec3A::X * 6.0, 0), Mat4::IDENTITY),
        (sphere_mesh("ball", Vec3A::new(0.0, 0.8, 0.0), 0.5, 4, 1), Mat4::IDENTITY),
    ];
    let (towards_sun, irradiance) = (Vec3A::new(0.05, 1.0, 0.02).normalize(), 2.0);
    let mut lights = vec![];
    let mut emission = Rgb::ZERO;
    if as_surface {
        // 1 m² at 30 m: 1/900 sr, so radiance 900 × the irradiance.
        let (a, b) = towards_sun.any_orthonormal_pair();
        let (a, b) = if a.cross(b).dot(towards_sun) > 0.0 { (b, a) } else { (a, b) };
        meshes.push((quad_mesh("sun", towards_sun * 30.0 - (a + b) * 0.5, a, b, 2), Mat4::IDENTITY));
        emission = Rgb::splat(irradiance * 900.0);
    } else {
        lights.push(LightDesc::Directional {
            name: "sun".into(),
            direction: -towards_sun,
            irradiance: Rgb::splat(irradiance),
            angle: 0.0,
            camera_visible: false,
        });
    }
    let emitter = Material { emission, double_sided: false, ..Material::diffuse("emitter", Rgb::ZERO) };
    // Low, from the side: the caustic under the ball is seen directly, not through the ball
    // (which would show the sharp one brighter than the blurred one by refocusing it).
    let eye = Vec3A::new(2.5, 0.45, 0.3);
    scene_from(vec![floor, glass, emitter], meshes, lights, eye, Vec3A::ZERO, UVec2::new(32, 24))
}

#[test]
fn the_sun_through_smooth_glass_is_solved_for_as_the_emitter_it_stands_for() {
    // Smooth glass leaves a delta light's caustic to next-event estimation at the glass, which
    // never lines up with it: without the connection the light through the ball is lost.
    // With it the picture is that of a small, far emissive quad of the same irradiance, whose
    // connections the tests above compare with BSDF sampling. (A point light against a small
    // emissive sphere cannot be compared so: the sphere is seen through the ball. The point's
    // density is checked against moving the receiver in integrator::mnee's unit test.)
    let mut sun = sunlit_ball(false);
    assert!(sun.caustics, "smooth glass and a delta light: a connection to make");
    let solved = region_means(&mut sun, true, 300);
    let lost = region_means(&mut sun, false, 400);
    let surface = region_means(&mut sunlit_ball(true), true, 500);
    let ((ours, ours_var), (theirs, theirs_var)) = (image_spread(&solved), image_spread(&surface));
    let (without, _) = image_spread(&lost);
    let z = (ours - theirs) / (ours_var + theirs_var).sqrt();
    eprintln!(
        "sun: image mean {:.4} of the emitter's (t {z:.1}); without the connection {:.4}",
        ours / theirs,
        without / theirs
    );
    assert!(z.abs() < 5.84 && (ours / theirs - 1.0).abs() < 0.02, "image mean {} of the emitter's", ours / theirs);
    assert!(without / ours < 0.99, "without the connection the caustic must be missing: {}", without / ours);
}

#[test]
fn info_and_the_summary_say_what_is_solved_for_through_glass() {
    let dir = tempfile::tempdir().unwrap();
    let glass = blender("glass.glb");
    let glass = glass.to_str().unwrap();
    let out = myriad(&["info", glass], dir.path());
    assert!(text(&out).contains("caustics     light from emissive surfaces, lamps, point and directional lights through smooth glass ('clear_glass', 'tinted_glass', 'globe_glass')"), "{}", text(&out));
    let out = myriad(&["render", glass, "--spp", "2", "--resolution", "32x24"], dir.path());
    assert!(out.status.success(), "{}", text(&out));
    let time = text(&out).lines().find(|l| l.starts_with("time")).map(str::to_string).unwrap_or_default();
    assert!(time.contains("connections through glass"), "{time}");
    let line = text(&out).lines().find(|l| l.starts_with("caustics")).map(str::to_string).unwrap_or_default();
    let numbers: Vec<u64> = line.split_whitespace().filter_map(|w| w.parse().ok()).collect();
    assert!(
        line.contains("light samples behind smooth glass")
            && numbers.len() == 2
            && numbers[1] > 0
            && numbers[1] <= numbers[0],
        "{line}"
    );
    // Without smooth glass: a line in `info` that says so, none in the summary.
    let materials = blender("materials.glb");
    let materials = materials.to_str().unwrap();
    assert!(text(&myriad(&["info", materials], dir.path())).contains("caustics     no smooth solid glass"));
    let out = myriad(&["render", materials, "--spp", "1", "--resolution", "16x12"], dir.path());
    assert!(!text(&out).lines().any(|l| l.starts_with("caustics")), "{}", text(&out));
    assert!(!text(&out).contains("connections through glass"), "{}", text(&out));
}

#[test]
fn caustics_are_switched_anywhere_and_every_output_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::copy(blender("glass.glb"), d.join("glass.glb")).unwrap();
    let render = |scene: &str, extra: &[&str], out: &str| {
        crate::split::ok(&[&["render", scene, "--spp", "2", "--resolution", "32x24", "-o", out][..], extra].concat(), d)
    };
    let caustics_of = |name: &str| {
        let (_, meta) = myriad::io::exr::read(&d.join(name)).unwrap();
        meta.into_iter().find(|(k, _)| k == "myriad.caustics").map(|(_, v)| v)
    };
    let on = render("glass.glb", &["--caustics", "on"], "on.exr");
    let off = render("glass.glb", &["--caustics", "off"], "off.exr");
    assert!(on.contains("reached through it") && off.contains("caustics   off (--caustics)"), "{on}\n{off}");
    assert_eq!((caustics_of("on.exr"), caustics_of("off.exr").as_deref()), (None, Some("off")));
    // The scene file's switch gives the command line's image, and the command line wins.
    let scene = |render: &str| {
        format!(
            "(\n    camera: Perspective(eye: (0, 2, 6), look_at: (0, 1, 0), yfov_deg: 40),\n    \
             film: (resolution: (32, 24)),\n{render}    objects: [Mesh(path: \"glass.glb\")],\n)\n"
        )
    };
    std::fs::write(d.join("solved.ron"), scene("")).unwrap();
    std::fs::write(d.join("unsolved.ron"), scene("    render: (caustics: false),\n")).unwrap();
    render("solved.ron", &["--caustics", "off"], "cli-off.exr");
    render("unsolved.ron", &[], "file-off.exr");
    crate::split::same_pixels(&d.join("cli-off.exr"), &d.join("file-off.exr"));
    render("solved.ron", &[], "file-on.exr");
    render("unsolved.ron", &["--caustics", "on"], "cli-on.exr");
    crate::split::same_pixels(&d.join("cli-on.exr"), &d.join("file-on.exr"));
    let info = crate::split::ok(&["info", "unsolved.ron"], d);
    assert!(info.contains("caustics     off (the scene file's render.caustics)"), "{info}");
    let out = myriad(&["render", "glass.glb", "--caustics", "maybe"], d);
    assert!(!out.status.success() && text(&out).contains("on or off"), "{}", text(&out));
    // compare solves in its runs as asked (its reference always does) and says so.
    let args = ["compare", "glass.glb", "--samplers", "tree", "--spp", "2", "--reference-spp", "4"];
    crate::split::ok(&[&args[..], &["--resolution", "16x12", "--caustics", "off", "--out-dir", "cmp"]].concat(), d);
    let report = std::fs::read_to_string(d.join("cmp/report.md")).unwrap();
    assert!(report.contains("caustics off"), "{report}");
}
