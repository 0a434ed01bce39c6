//! What a new user tripped over, each through the binary as they ran it: every command's
//! help speaks of itself, a negative count is told it must be positive, a read-only output is
//! kept, a scene without lights says so, one triangle count, an OBJ face out of range names
//! its line, summaries name what actually chose the lights, and counts, names and settings
//! that cannot be planned are refused before anything is allocated or written.

use std::path::Path;

use crate::cli::GOOD as SCENE;
use crate::split::{myriad, ok, text};

/// A folder holding `SCENE` as scene.ron.
fn folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.ron"), SCENE).unwrap();
    dir
}

/// Runs `args` in `dir` expecting a clear failure that mentions every one of `needles`.
fn refused(args: &[&str], dir: &Path, needles: &[&str]) -> String {
    let out = myriad(args, dir);
    let t = text(&out);
    assert!(!out.status.success(), "{args:?} succeeded: {t}");
    assert!(!t.contains("panicked") && !t.contains("memory allocation"), "{args:?}: {t}");
    for n in needles {
        assert!(t.contains(n), "{args:?}: the message lacks '{n}':\n{t}");
    }
    t
}

#[test]
fn each_commands_help_speaks_of_itself() {
    let dir = folder();
    let help = |cmd: &str| ok(&[cmd, "--help"], dir.path());
    for (cmd, others) in
        [("render", ["compare:", "view:"]), ("compare", ["render:", "view:"]), ("view", ["compare:", "render:"])]
    {
        let h = help(cmd);
        for other in others {
            assert!(!h.contains(other), "`{cmd} --help` speaks of another command ({other}):\n{h}");
        }
    }
    assert!(help("render").contains("else 64"), "render's own default spp");
    assert!(help("compare").contains("every run") && help("compare").contains("else 16"));
    assert!(help("view").contains("no limit") && help("view").contains("Starting exposure"));
}

#[test]
fn a_negative_or_zero_count_is_told_it_must_be_positive() {
    let dir = folder();
    for (flag, value) in [("--spp", "-5"), ("--spp", "0"), ("--max-depth", "-1"), ("--seed", "-3")] {
        let t = refused(&["render", "scene.ron", flag, value], dir.path(), &[value]);
        assert!(!t.contains("unexpected argument"), "{flag} {value}: {t}");
        assert!(t.contains("positive whole number") || t.contains("is not a seed"), "{flag} {value}: {t}");
    }
    refused(&["compare", "scene.ron", "--seeds", "-2"], dir.path(), &["-2", "positive whole number"]);
    refused(&["slurm", "scene.ron", "--spp", "8", "--tasks", "-4"], dir.path(), &["-4", "positive whole number"]);
}

#[test]
fn a_read_only_output_is_kept_unless_forced() {
    let dir = folder();
    let d = dir.path();
    ok(&["render", "scene.ron", "-o", "out.exr", "--spp", "1", "-q"], d);
    let exr = d.join("out.exr");
    let before = std::fs::read(&exr).unwrap();
    let mut perms = std::fs::metadata(&exr).unwrap().permissions();
    perms.set_readonly(true);
    std::fs::set_permissions(&exr, perms).unwrap();
    refused(&["render", "scene.ron", "-o", "out.exr", "--spp", "2", "-q"], d, &["out.exr", "read-only", "--force"]);
    assert_eq!(std::fs::read(&exr).unwrap(), before, "the read-only image is untouched");
    ok(&["render", "scene.ron", "-o", "out.exr", "--spp", "2", "-q", "--force"], d);
    assert_ne!(std::fs::read(&exr).unwrap(), before, "--force replaces it");
}

#[test]
fn a_scene_without_lights_says_so() {
    let dir = folder();
    let dark = SCENE.replace(
        "lights: [ Quad(corner: (-0.2, 1.9, -0.2), edge1: (0.4, 0, 0), edge2: (0, 0, 0.4), radiance: (5, 5, 5)) ],",
        "lights: [],",
    );
    std::fs::write(dir.path().join("dark.ron"), dark).unwrap();
    let t = ok(&["render", "dark.ron", "-o", "dark.exr", "--spp", "1", "-q"], dir.path());
    assert!(t.contains("the scene has no lights") && t.contains("sampler cells (no lights)"), "{t}");
    assert!(!t.lines().any(|l| l.starts_with("cells")), "no line about the cells sampler: {t}");
    assert!(ok(&["info", "dark.ron"], dir.path()).contains("no lights"));
}

/// A glTF file whose one triangle is placed by three nodes (an instanced mesh), with a camera.
const INSTANCED: &str = r#"{
  "asset": {"version": "2.0"},
  "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
  "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
  "nodes": [{"mesh": 0}, {"mesh": 0, "translation": [2, 0, 0]}, {"mesh": 0, "translation": [4, 0, 0]},
            {"camera": 0, "translation": [2, 0.5, 6]}],
  "scenes": [{"nodes": [0, 1, 2, 3]}]
}"#;

#[test]
fn the_memory_refusal_counts_triangles_as_the_summary_does() {
    let dir = folder();
    std::fs::write(dir.path().join("three.gltf"), INSTANCED).unwrap();
    let info = ok(&["info", "three.gltf"], dir.path());
    assert!(info.contains("triangles    3 (0 emissive, 1 stored)"), "{info}");
    let t = refused(&["--max-memory", "0.000001", "info", "three.gltf"], dir.path(), &["memory"]);
    assert!(t.contains("3 triangles (1 stored"), "the same 3 triangles, 1 of them stored: {t}");
}

#[test]
fn an_obj_face_out_of_range_names_its_line() {
    let dir = folder();
    std::fs::write(dir.path().join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n").unwrap();
    refused(&["info", "bad.obj", "--camera", "auto"], dir.path(), &["bad.obj", "line 5", "vertex 9", "3 vertices"]);
}

#[test]
fn compare_names_what_actually_chose_the_lights() {
    let dir = folder();
    let t = ok(
        &["compare", "scene.ron", "--samplers", "cells,tree", "--spp", "1", "--reference-spp", "2", "-q"],
        dir.path(),
    );
    // One light: the default takes it at every diffuse point; the tree is the tree.
    assert!(t.contains("| cells (as every light at diffuse points, tree elsewhere) |"), "{t}");
    assert!(t.contains("| tree |"), "{t}");
}

#[test]
fn counts_that_cannot_be_planned_are_refused_before_anything_is_allocated() {
    let dir = folder();
    let d = dir.path();
    // Each of these once aborted allocating gigabytes.
    let huge = u32::MAX.to_string();
    refused(&["slurm", "scene.ron", "--spp", &huge, "--tasks", &huge, "--out", "job"], d, &["10000", "--tasks"]);
    refused(&["compare", "scene.ron", "--seeds", &huge, "--spp", "1"], d, &["10000", "--seeds"]);
    refused(
        &["slurm", "scene.ron", "--spp", "4", "--compare", "uniform,power", "--seeds", "10000000", "--out", "job"],
        d,
        &["10000", "--seeds"],
    );
    let left: Vec<_> = std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left, ["scene.ron"], "nothing written");
}

#[test]
fn merge_writes_exr_only_under_an_exr_name() {
    let dir = folder();
    let d = dir.path();
    ok(&["render", "scene.ron", "--samples", "0..1", "-o", "p.part", "-q"], d);
    refused(&["merge", "p.part", "-o", "m.png"], d, &["m.png", ".exr"]);
    assert!(!d.join("m.png").exists());
}

#[test]
fn a_bad_memory_setting_in_the_environment_is_refused_like_the_option() {
    let dir = folder();
    for value in ["abc", "0", "-5"] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_myriad"))
            .args(["info", "scene.ron"])
            .env("MYRIAD_MAX_MEMORY", value)
            .current_dir(dir.path())
            .output()
            .unwrap();
        let t = text(&out);
        assert!(!out.status.success() && t.contains(&format!("MYRIAD_MAX_MEMORY={value}")), "{value}: {t}");
        assert!(t.contains("gigabytes"), "{t}");
    }
}

#[test]
fn a_damaged_exr_is_named_as_damaged() {
    let dir = folder();
    let d = dir.path();
    ok(&["render", "scene.ron", "-o", "a.exr", "--spp", "1", "--no-png", "-q"], d);
    let mut bytes = std::fs::read(d.join("a.exr")).unwrap();
    // A 16 × 12 image is one chunk of 16 scan lines: its offset table is one u64 pointing just
    // past itself. Pointing it past the end of any file made the exr crate's seek fail with a
    // bare "Invalid argument (os error 22)".
    let table = (0..bytes.len() - 8)
        .find(|&p| u64::from_le_bytes(bytes[p..p + 8].try_into().unwrap()) == p as u64 + 8)
        .expect("the offset table");
    bytes[table + 7] = 0x9d;
    std::fs::write(d.join("b.exr"), &bytes).unwrap();
    let t = refused(&["diff", "b.exr", "a.exr"], d, &["b.exr", "damaged"]);
    assert!(!t.contains("a.exr:"), "the damaged file is the one named: {t}");
}
