//! The ray tracers (`--tracer`): each renders what the other does, a build without Embree
//! says so and traces anyway, and the tracer in use is reported and kept apart in merges.

use std::path::Path;
use std::process::Command;

use myriad::commands::{SceneOptions, load_scene};
use myriad::film::Film;
use myriad::geometry::TracerKind;
use myriad::math::UVec2;
use myriad::scene::BuildOptions;
use myriad::settings::LightSamplerKind;

use crate::common::{TestScene, blender, cornell};
use crate::render::render_with;
use crate::split::{myriad, text};

fn render(path: &Path, tracer: TracerKind) -> (Film, TracerKind) {
    let build = BuildOptions { resolution: Some(UVec2::new(48, 36)), tracer, ..Default::default() };
    let loaded = load_scene(Some(path), &SceneOptions { build, load: Default::default() }).unwrap();
    let built = loaded.scene.geometry.accel.tracer();
    (render_with(&TestScene::from(loaded), LightSamplerKind::Tree, 16, 6, 3), built)
}

const EMBREE_BUILT: bool = TracerKind::BUILT.len() > 1;

/// Alpha cut-outs (Embree's filter functions), instances (its instanced scenes) and glossy
/// materials: the same seed gives images that agree to the last bits of their hit points.
/// Measured: at most 0.0007 % of the light apart; a wrong instance transform (a bug found this
/// way) or a filter that lets nothing through moves them by whole percents.
#[test]
fn both_tracers_render_the_same_images() {
    if !EMBREE_BUILT {
        eprintln!("skipped: this build has no Embree (apt-get install libembree-dev)");
        return;
    }
    for path in [
        cornell("gltf").with_file_name("cornell-cutout.gltf"),
        blender("instanced_lamps.glb"),
        blender("materials.glb"),
    ] {
        let (a, ta) = render(&path, TracerKind::Builtin);
        let (b, tb) = render(&path, TracerKind::Embree);
        assert_eq!((ta, tb), (TracerKind::Builtin, TracerKind::Embree));
        let n = (a.size().x * a.size().y) as usize;
        let (mut diff, mut sum, mut differing) = (0.0f64, 0.0f64, 0);
        for i in 0..n {
            let (x, y) = (a.mean(i), b.mean(i));
            differing += (x != y) as usize;
            diff += (x - y).abs().element_sum() as f64;
            sum += (x + y).element_sum() as f64 / 2.0;
        }
        let relative = diff / sum.max(1e-30);
        let name = path.file_name().unwrap().to_string_lossy();
        assert!(relative < 1e-4, "{name}: the tracers' images differ by {:.3} % of their light", 100.0 * relative);
        eprintln!("{name}: {differing} of {n} pixels differ, by {:.4} % of the light", 100.0 * relative);
    }
}

#[test]
fn the_tracer_is_named_in_the_summary_info_and_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cornell("ron");
    let scene = scene.to_str().unwrap();
    let out = myriad(&["--tracer", "builtin", "render", scene, "--spp", "2", "--resolution", "16x12"], dir.path());
    assert!(out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("builtin tracer"), "{}", text(&out));
    assert!(text(&out).contains("time       tracing"), "{}", text(&out));
    let exr = std::fs::read(dir.path().join("myriad.exr")).unwrap();
    assert!(exr.windows(b"myriad.tracer".len()).any(|w| w == b"myriad.tracer"));
    let out = myriad(&["info", scene, "--tracer", "builtin"], dir.path());
    assert!(text(&out).contains("for the builtin tracer"), "{}", text(&out));

    let out = myriad(&["--tracer", "embree", "info", scene], dir.path());
    assert!(out.status.success(), "{}", text(&out));
    if EMBREE_BUILT {
        assert!(text(&out).contains("for the embree tracer"), "{}", text(&out));
    } else {
        assert!(text(&out).contains("built without Embree") && text(&out).contains("libembree-dev"), "{}", text(&out));
    }
}

#[test]
fn an_unknown_tracer_is_refused_with_the_choices() {
    let dir = tempfile::tempdir().unwrap();
    let out = myriad(&["--tracer", "optix", "info"], dir.path());
    assert!(!out.status.success());
    assert!(text(&out).contains("'optix' is no tracer; use best, builtin or embree"), "{}", text(&out));
    let out = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(["info"])
        .current_dir(dir.path())
        .env("MYRIAD_TRACER", "fast")
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(text(&out).contains("MYRIAD_TRACER=fast names no tracer"), "{}", text(&out));
}

/// Parts traced by different tracers do not add up to the bits of one render: merge says
/// which field differs.
#[test]
fn parts_of_different_tracers_are_not_merged() {
    if !EMBREE_BUILT {
        eprintln!("skipped: this build has no Embree");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = cornell("ron");
    let scene = scene.to_str().unwrap();
    for (tracer, range) in [("builtin", "0..2"), ("embree", "2..4")] {
        let args = ["--tracer", tracer, "render", scene, "--resolution", "16x12", "--samples", range, "-o", "x.exr"];
        let out = myriad(&args, dir.path());
        assert!(out.status.success(), "{}", text(&out));
    }
    let out = myriad(&["merge", "x.samples-0-2.part", "x.samples-2-4.part", "-o", "m.exr"], dir.path());
    assert!(!out.status.success());
    assert!(text(&out).contains("tracer embree (not builtin)"), "{}", text(&out));
}
