//! `myriad compare` and `myriad diff` as users run them.

use myriad::commands::compare::{CompareOptions, compare};
use myriad::commands::diff::{DiffOptions, diff};
use myriad::commands::settings::RenderRequest;
use myriad::math::UVec2;
use myriad::render::Budget;
use myriad::settings::LightSamplerKind;
use std::path::{Path, PathBuf};
use std::time::Duration;

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-9x9.ron")
}

fn options(out_dir: &Path, samplers: Vec<LightSamplerKind>, budget: Budget) -> CompareOptions {
    CompareOptions {
        scene: scene(),
        samplers: Some(samplers),
        settings: RenderRequest {
            spp: budget.fixed().map(|(_, n)| n),
            time: match budget {
                Budget::Time(t) => Some(t),
                _ => None,
            },
            max_depth: Some(3),
            ..Default::default()
        },
        reference: None,
        reference_spp: Some(64),
        reference_time: None,
        reference_sampler: None,
        seeds: 2,
        out_dir: out_dir.to_path_buf(),
        resolution: Some(UVec2::new(40, 30)),
        camera: None,
        load: Default::default(),
        exposure: 0.0,
        progress: false,
        runs: None,
        display: None,
    }
}

/// Parses the numbers of a report.md table row ("a ± b" cells give a).
fn row_numbers(md: &str, sampler: &str) -> Vec<f64> {
    let line = md.lines().find(|l| l.starts_with(&format!("| {sampler} |"))).expect("row present");
    line.split('|')
        .skip(2)
        .filter_map(|c| c.split('±').next().and_then(|x| x.trim().trim_end_matches(" **biased?**").parse::<f64>().ok()))
        .collect()
}

#[test]
fn compare_writes_every_output_and_the_reports_agree() {
    let dir = tempfile::tempdir().unwrap();
    let kinds = vec![LightSamplerKind::Power, LightSamplerKind::Tree];
    let report = compare(&options(dir.path(), kinds, Budget::Spp(8))).unwrap();
    for f in [
        "reference.exr",
        "power.exr",
        "tree.exr",
        "power-error.png",
        "tree-error.png",
        "contact-sheet.png",
        "convergence.svg",
        "report.md",
        "report.json",
        "report.html",
    ] {
        let len = std::fs::metadata(dir.path().join(f)).map(|m| m.len()).unwrap_or(0);
        assert!(len > 0, "{f} missing or empty");
    }
    assert!(!report.reference.reused);
    let md = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(md.contains("![") && md.contains("contact-sheet.png") && md.contains("convergence.svg"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap()).unwrap();
    for (i, name) in ["power", "tree"].iter().enumerate() {
        let s = &json["samplers"][i];
        assert_eq!(s["sampler"], *name);
        assert_eq!(s["runs"].as_array().unwrap().len(), 2, "two seeds");
        let row = row_numbers(&md, name);
        // spp, time, MSE, relMSE, efficiency, vs best, relMSE and efficiency 99.9 %, build,
        // memory, bias z
        let json_vals = [
            s["spp"]["mean"].as_f64().unwrap(),
            s["seconds"]["mean"].as_f64().unwrap(),
            s["mse"]["mean"].as_f64().unwrap(),
            s["rel_mse"]["mean"].as_f64().unwrap(),
            s["efficiency"]["mean"].as_f64().unwrap(),
            s["efficiency_vs_best"].as_f64().unwrap(),
            s["rel_mse_trimmed"]["mean"].as_f64().unwrap(),
            s["efficiency_trimmed"].as_f64().unwrap(),
            s["build_seconds"].as_f64().unwrap(),
            s["memory_bytes"].as_f64().unwrap(),
            s["bias"]["z"].as_f64().unwrap(),
        ];
        assert_eq!(row.len(), json_vals.len(), "{name}: {row:?}");
        for (a, b) in row.iter().zip(json_vals) {
            assert!((a - b).abs() <= 1e-3 * b.abs() + 1e-9, "{name}: table {a} vs json {b}");
        }
        assert_eq!(s["spp"]["mean"].as_f64().unwrap(), 8.0);
        // The efficiency of the mean error and time, not the mean of the runs' efficiencies.
        let (rel_mse, seconds) = (s["rel_mse"]["mean"].as_f64().unwrap(), s["seconds"]["mean"].as_f64().unwrap());
        let efficiency = s["efficiency"]["mean"].as_f64().unwrap();
        assert!((efficiency * rel_mse * seconds - 1.0).abs() < 1e-9, "{name}: {efficiency} vs {rel_mse}, {seconds}");
        // Without its worst pixels a run has less error, never more.
        let trimmed = s["rel_mse_trimmed"]["mean"].as_f64().unwrap();
        assert!(trimmed > 0.0 && trimmed < rel_mse, "{name}: {trimmed} vs {rel_mse}");
        assert!(!s["bias"]["flagged"].as_bool().unwrap(), "{name} flagged as biased: {}", s["bias"]);
    }
    // Running again reuses the cached reference.
    let again = compare(&options(dir.path(), vec![LightSamplerKind::Uniform], Budget::Spp(2))).unwrap();
    assert!(again.reference.reused);
}

#[test]
fn the_bias_flag_fires_for_a_biased_estimator() {
    // A direct-lighting-only estimator judged against a full-transport reference: the
    // missing indirect light is a bias the check must catch.
    let dir = tempfile::tempdir().unwrap();
    let full = compare(&options(dir.path(), vec![LightSamplerKind::Tree], Budget::Spp(4))).unwrap();
    assert!(!full.samplers[0].bias.flagged);
    let mut truncated = options(dir.path(), vec![LightSamplerKind::Tree, LightSamplerKind::Power], Budget::Spp(4));
    truncated.reference = Some(dir.path().join("reference.exr"));
    truncated.settings.max_depth = Some(1);
    let report = compare(&truncated).unwrap();
    for s in &report.samplers {
        assert!(s.bias.flagged && s.bias.z < 0.0, "{}: {:?}", s.sampler, s.bias);
    }
}

#[test]
fn equal_time_reports_what_each_sampler_reached() {
    // How the passes fill the budget is tested on a synthetic clock (`render::tests`); here,
    // on a real one that a loaded machine can slow down at will, only what holds at any speed.
    let dir = tempfile::tempdir().unwrap();
    let mut opts = options(
        dir.path(),
        vec![LightSamplerKind::Power, LightSamplerKind::Local],
        Budget::Time(Duration::from_millis(300)),
    );
    opts.seeds = 1;
    let report = compare(&opts).unwrap();
    for s in &report.samplers {
        let run = &s.runs[0];
        assert!(run.spp >= 1 && run.seconds > 0.0, "{}: {} spp in {} s", s.sampler, run.spp, run.seconds);
        let times: Vec<f64> = run.convergence.iter().map(|p| p.0).collect();
        assert!(!times.is_empty() && times.windows(2).all(|w| w[0] < w[1]), "{}: {times:?}", s.sampler);
        assert!(times.last().unwrap() <= &run.seconds, "{}: passes end within the run", s.sampler);
        assert!(run.convergence.iter().all(|p| p.1 > 0.0), "{}: relMSE after each pass", s.sampler);
    }
    assert!(report.samplers.iter().all(|s| s.efficiency.mean > 0.0));
}

#[test]
fn diff_measures_and_refuses_mismatched_images() {
    let dir = tempfile::tempdir().unwrap();
    compare(&options(dir.path(), vec![LightSamplerKind::Power], Budget::Spp(2))).unwrap();
    let (a, r) = (dir.path().join("power.exr"), dir.path().join("reference.exr"));
    let png = dir.path().join("err.png");
    let html = dir.path().join("diff.html");
    let ask = |image: &Path, error_png: Option<&Path>, html: Option<&Path>| DiffOptions {
        image: image.into(),
        reference: r.clone(),
        error_png: error_png.map(Into::into),
        html: html.map(Into::into),
    };
    let d = diff(&ask(&a, Some(&png), Some(&html))).unwrap();
    assert!(d.metrics.rel_mse > 0.0 && png.exists());
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("myriad diff: power.exr against reference.exr") && page.contains("myriad-data"));
    assert_eq!(diff(&DiffOptions { reference: a.clone(), ..ask(&a, None, None) }).unwrap().metrics.rel_mse, 0.0);
    // A smaller image is a clear error naming both sizes.
    let mut small = options(dir.path(), vec![LightSamplerKind::Power], Budget::Spp(1));
    small.resolution = Some(UVec2::new(20, 15));
    small.out_dir = dir.path().join("small");
    compare(&small).unwrap();
    let e = diff(&ask(&dir.path().join("small/power.exr"), None, None)).err().unwrap().to_string();
    assert!(e.contains("20 × 15") && e.contains("40 × 30"), "{e}");
}

#[test]
fn the_cached_reference_is_keyed_on_every_input() {
    // A RON scene placing an OBJ whose MTL sets the lamp: a change to any file, or to how the
    // scene is read or rendered, must render the reference again.
    let dir = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cornell");
    for f in ["cornell.obj", "cornell.mtl"] {
        std::fs::copy(data.join(f), dir.path().join(f)).unwrap();
    }
    let scene = dir.path().join("box.ron");
    std::fs::write(
        &scene,
        r#"Scene(camera: Perspective(eye: (0, 1, 4.4), look_at: (0, 1, 0), yfov_deg: 37),
                objects: [Mesh(path: "cornell.obj")])"#,
    )
    .unwrap();
    let mut opts = options(&dir.path().join("out"), vec![LightSamplerKind::Power], Budget::Spp(1));
    (opts.scene, opts.seeds, opts.reference_spp, opts.resolution) = (scene, 1, Some(2), Some(UVec2::new(16, 12)));
    let reused = |opts: &CompareOptions| compare(opts).unwrap().reference.reused;
    assert!(!reused(&opts), "first run renders");
    assert!(reused(&opts), "same inputs reuse");
    let mtl = dir.path().join("cornell.mtl");
    let text = std::fs::read_to_string(&mtl).unwrap();
    std::fs::write(&mtl, text.replace("Ke 17 12 4", "Ke 17 12 5")).unwrap();
    assert!(!reused(&opts), "an edited material library renders again");
    assert!(reused(&opts));
    opts.load.punctual_scale = 1.0;
    assert!(!reused(&opts), "another punctual scale renders again");
    opts.reference_spp = Some(3);
    assert!(!reused(&opts), "another reference spp renders again");
    opts.settings.max_depth = Some(2);
    assert!(!reused(&opts), "another depth renders again");
    opts.camera = Some("camera".into());
    assert!(!reused(&opts), "another camera option renders again");
    assert!(reused(&opts));
}

#[test]
fn compare_takes_what_the_scene_file_asks_unless_the_command_line_says_otherwise() {
    // The scene's spp, seed, depth and sampler, resolved as `render` resolves them.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-5x5.ron")).unwrap();
    let scene = dir.path().join("box.ron");
    std::fs::write(
        &scene,
        text.replace("render: (spp: 64, max_depth: 8)", "render: (spp: 2, max_depth: 2, seed: 7, sampler: all)"),
    )
    .unwrap();
    let mut opts = options(&dir.path().join("out"), vec![], Budget::Spp(1));
    (opts.scene, opts.samplers, opts.settings, opts.reference_spp) = (scene, None, RenderRequest::default(), Some(2));
    let report = compare(&opts).unwrap();
    let names: Vec<&str> = report.samplers.iter().map(|s| s.sampler.as_str()).collect();
    assert_eq!(names, ["uniform", "power", "local", "tree", "cells", "all"]);
    assert_eq!(report.max_depth, 2);
    for s in &report.samplers {
        let seeds: Vec<(u64, u32)> = s.runs.iter().map(|r| (r.seed, r.spp)).collect();
        assert_eq!(seeds, [(8, 2), (9, 2)], "{}", s.sampler);
    }
    opts.settings = RenderRequest { spp: Some(1), seed: Some(0), max_depth: Some(1), ..Default::default() };
    opts.samplers = Some(vec![LightSamplerKind::Power]);
    let report = compare(&opts).unwrap();
    assert_eq!((report.max_depth, report.samplers[0].runs[0].seed, report.samplers[0].runs[0].spp), (1, 1, 1));
}

#[test]
fn the_default_reference_is_the_tree_at_a_multiple_of_the_runs_and_a_noisy_one_is_flagged() {
    // 81 lights: beyond what `all` or `local` should render a reference of.
    let dir = tempfile::tempdir().unwrap();
    let mut opts = options(dir.path(), vec![LightSamplerKind::Uniform], Budget::Spp(4));
    (opts.reference_spp, opts.seeds) = (None, 1);
    let report = compare(&opts).unwrap();
    assert!(
        report.reference.origin.starts_with("tree, 64 spp"),
        "16 × 4 spp with the tree: {}",
        report.reference.origin
    );
    // An 8-spp reference against 128-spp runs moves what it judges: flagged, with the spp it needs.
    let dir = tempfile::tempdir().unwrap();
    let mut opts = options(dir.path(), vec![LightSamplerKind::Tree], Budget::Spp(128));
    (opts.reference_spp, opts.seeds) = (Some(8), 1);
    let report = compare(&opts).unwrap();
    let r = &report.reference;
    assert!(r.too_noisy && r.needed_spp.is_some_and(|n| n > 80), "{r:?} {:?}", report.samplers[0].rel_mse);
    let md = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(md.contains("too noisy to judge by") && md.contains("--reference-spp"), "{md}");
}
