//! The Blender add-on (blender/myriad_blender) as users run it, in Blender's `bpy` module: F12
//! on one-factor .blend files (each Blender light kind and shape, a sun angle, the world as a
//! colour and as an HDRI, emissive meshes, Principled materials, the camera's fit, shift and
//! depth of field) renders what Cycles renders of them (tests/data/blender/addon, made by
//! tools/make_blender_addon_scenes.py); the Render Result is myriad's own image, bit for bit,
//! with Denoising Albedo and Normal passes; bad input is a Blender error or warning naming
//! what is wrong; Esc (a stop) ends myriad at once and leaves no image.
//!
//! It needs the peers venv (`tools/peers/setup_venv.sh`: Python 3.11 with `bpy` 5.0); CI sets
//! it up and MYRIAD_BLENDER_TESTS=1, elsewhere the test says why it is skipped.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

use crate::common::blender;
use crate::formats::agrees_with_cycles_pixel_by_pixel;

/// The Python with Blender's `bpy` module: MYRIAD_BPY_PYTHON, else the peers venv's.
fn bpy_python() -> Option<PathBuf> {
    let candidate = std::env::var_os("MYRIAD_BPY_PYTHON")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache/myriad-peers/bin/python")));
    let found =
        candidate.filter(|p| Command::new(p).args(["-c", "import bpy"]).output().is_ok_and(|o| o.status.success()));
    let required = std::env::var("MYRIAD_BLENDER_TESTS").is_ok_and(|v| v == "1");
    assert!(
        found.is_some() || !required,
        "MYRIAD_BLENDER_TESTS=1 but no Python with bpy: run tools/peers/setup_venv.sh"
    );
    if found.is_none() {
        eprintln!("skipped: no Python with Blender's bpy module (tools/peers/setup_venv.sh makes one)");
    }
    found
}

/// The mean of every channel of an EXR's RGB.
fn exr_mean(path: &Path) -> [f64; 3] {
    let (layers, _) = myriad::io::exr::read(path).unwrap();
    let rgb = layers.rgb().unwrap();
    let mut m = [0.0; 3];
    for p in &rgb {
        for c in 0..3 {
            m[c] += p[c] as f64 / rgb.len() as f64;
        }
    }
    m
}

fn text(v: &Value) -> String {
    v.as_str().map_or_else(|| v.to_string(), str::to_string)
}

#[test]
fn f12_renders_what_cycles_renders_and_bad_input_is_reported() {
    let Some(python) = bpy_python() else { return };
    let out = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scenes = blender("addon");
    let run = Command::new(&python)
        .arg(root.join("blender/tests/addon_tests.py"))
        .args([&scenes, out.path()])
        .env("MYRIAD_BIN", env!("CARGO_BIN_EXE_myriad"))
        .output()
        .unwrap();
    let log = format!("{}{}", String::from_utf8_lossy(&run.stdout), String::from_utf8_lossy(&run.stderr));
    assert!(run.status.success(), "the add-on's script failed:\n{log}");
    assert!(!log.contains("Traceback"), "a traceback reached the user:\n{log}");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("summary.json")).unwrap()).unwrap();

    let rendered = summary["scenes"].as_object().unwrap();
    assert!(rendered.len() >= 14, "{rendered:?}");
    for (name, r) in rendered {
        assert!(r["error"].is_null(), "{name}: {}", r["error"]);
        let keep = Path::new(r["keep"].as_str().unwrap());
        // F12's Render Result is myriad's image, bit for bit.
        let rgb = |p: &Path| myriad::io::exr::read(p).unwrap().0.rgb().unwrap();
        let (result, own) = (rgb(&out.path().join(format!("{name}.exr"))), rgb(&keep.join("render.exr")));
        assert!(result == own, "{name}: the Render Result is not myriad's image");
        // The exported scene renders what Cycles renders: every region within noise, and the
        // image mean within 1 %.
        let reference = scenes.join(format!("{name}.cycles.exr"));
        agrees_with_cycles_pixel_by_pixel(&keep.join("scene.ron"), &reference, 256);
        let (ours, theirs) = (exr_mean(&keep.join("render.exr")), exr_mean(&reference));
        for c in 0..3 {
            let ratio = ours[c] / theirs[c];
            assert!((ratio - 1.0).abs() < 0.01, "{name}: channel {c} mean {} against Cycles' {}", ours[c], theirs[c]);
        }
    }

    // The passes Blender's Denoise node takes: a grey scene's albedo is its grey, and the
    // Denoise node, fed myriad's image, albedo and normal, keeps the image's mean.
    let p = &summary["passes"];
    assert!(p["errors"] == serde_json::json!([null, null]), "{p}");
    let outputs = text(&p["outputs"]);
    assert!(outputs.contains("Denoising Albedo") && outputs.contains("Denoising Normal"), "{outputs}");
    let albedo = exr_mean(Path::new(p["albedo"].as_str().unwrap()));
    assert!(albedo.iter().all(|a| (a - 0.5).abs() < 1e-3), "the stage is grey 0.5: {albedo:?}");
    let first = rendered.keys().next().unwrap();
    let (denoised, noisy) =
        (exr_mean(Path::new(p["denoised"].as_str().unwrap())), exr_mean(&out.path().join(format!("{first}.exr"))));
    for c in 0..3 {
        assert!((denoised[c] / noisy[c] - 1.0).abs() < 0.03, "denoised {denoised:?} against {noisy:?}");
    }
    assert_eq!(summary["export_operator"], serde_json::json!(["FINISHED"]));
    let clamped = text(&summary["clamped_render_block"]);
    assert!(
        clamped.contains("clamp: (direct: 0, indirect: 10)")
            && clamped.contains("guiding: true")
            && clamped.contains("caustics: false"),
        "{clamped}"
    );

    // Bad input: errors and warnings that name what is wrong, no traceback.
    let bad = &summary["bad_inputs"];
    let missing = text(&bad["missing_binary"]);
    assert!(missing.contains("/nonexistent/myriad") && missing.contains("Executable"), "{missing}");
    assert!(text(&bad["wrong_binary"]).contains("is not myriad"), "{}", bad["wrong_binary"]);
    let warnings = text(&bad["warnings"]);
    for needle in ["material 'skin'", "'Blend Mix'", "subsurface", "light 'window portal'"] {
        assert!(warnings.contains(needle), "no warning with {needle}: {warnings}");
    }
    assert!(text(&bad["no_camera"]).contains("no active camera"), "{}", bad["no_camera"]);

    // Esc: myriad ends at once and writes nothing.
    let stopped = &summary["stopped"];
    assert!(stopped["saw_an_image"] == true, "{stopped}");
    assert!(stopped["seconds"].as_f64().unwrap() < 5.0 && stopped["status"] != 0, "{stopped}");
    assert!(stopped["image_left"] == false, "{stopped}");
}

#[test]
fn the_extension_zip_holds_the_manifest_and_the_package() {
    let out = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let run = Command::new("python3").arg(root.join("blender/build.py")).arg(out.path()).output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let zip = PathBuf::from(String::from_utf8_lossy(&run.stdout).trim());
    let bytes = std::fs::read(&zip).unwrap();
    assert!(bytes.starts_with(b"PK\x03\x04"), "a zip");
    let listed = |name: &str| bytes.windows(name.len()).any(|w| w == name.as_bytes());
    for name in ["blender_manifest.toml", "__init__.py", "engine.py", "export/materials.py"] {
        assert!(listed(name), "{name} missing from {}", zip.display());
    }
}
