//! `myriad compare` and `myriad diff` as users run them.

use myriad::commands::compare::{CompareOptions, compare};
use myriad::commands::diff::diff;
use myriad::light_sampler::LightSamplerKind;
use myriad::math::UVec2;
use myriad::render::Budget;
use std::path::{Path, PathBuf};
use std::time::Duration;

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-9x9.ron")
}

fn options(out_dir: &Path, samplers: Vec<LightSamplerKind>, budget: Budget) -> CompareOptions {
    CompareOptions {
        scene: scene(),
        samplers,
        budget,
        reference: None,
        reference_spp: 64,
        reference_sampler: None,
        seeds: 2,
        out_dir: out_dir.to_path_buf(),
        resolution: Some(UVec2::new(40, 30)),
        max_depth: Some(3),
        camera: None,
        load: Default::default(),
        exposure: 0.0,
        progress: false,
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
        // spp, time, MSE, relMSE, efficiency, vs best, build, memory, bias z
        let json_vals = [
            s["spp"]["mean"].as_f64().unwrap(),
            s["seconds"]["mean"].as_f64().unwrap(),
            s["mse"]["mean"].as_f64().unwrap(),
            s["rel_mse"]["mean"].as_f64().unwrap(),
            s["efficiency"]["mean"].as_f64().unwrap(),
            s["efficiency_vs_best"].as_f64().unwrap(),
            s["build_seconds"].as_f64().unwrap(),
            s["memory_bytes"].as_f64().unwrap(),
            s["bias"]["z"].as_f64().unwrap(),
        ];
        assert_eq!(row.len(), json_vals.len(), "{name}: {row:?}");
        for (a, b) in row.iter().zip(json_vals) {
            assert!((a - b).abs() <= 1e-3 * b.abs() + 1e-9, "{name}: table {a} vs json {b}");
        }
        assert_eq!(s["spp"]["mean"].as_f64().unwrap(), 8.0);
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
    truncated.max_depth = Some(1);
    let report = compare(&truncated).unwrap();
    for s in &report.samplers {
        assert!(s.bias.flagged && s.bias.z < 0.0, "{}: {:?}", s.sampler, s.bias);
    }
}

#[test]
fn equal_time_stays_near_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let mut opts = options(
        dir.path(),
        vec![LightSamplerKind::Power, LightSamplerKind::Local],
        Budget::Time(Duration::from_millis(600)),
    );
    opts.seeds = 1;
    let report = compare(&opts).unwrap();
    for s in &report.samplers {
        let t = s.runs[0].seconds;
        assert!((t - 0.6).abs() <= 0.06, "{}: {t} s for a 0.6 s budget", s.sampler);
        assert!(s.runs[0].convergence.len() >= 5, "passes give a convergence curve");
    }
}

#[test]
fn diff_measures_and_refuses_mismatched_images() {
    let dir = tempfile::tempdir().unwrap();
    compare(&options(dir.path(), vec![LightSamplerKind::Power], Budget::Spp(2))).unwrap();
    let (a, r) = (dir.path().join("power.exr"), dir.path().join("reference.exr"));
    let png = dir.path().join("err.png");
    let d = diff(&a, &r, Some(&png)).unwrap();
    assert!(d.metrics.rel_mse > 0.0 && png.exists());
    assert_eq!(diff(&a, &a, None).unwrap().metrics.rel_mse, 0.0);
    // A smaller image is a clear error naming both sizes.
    let mut small = options(dir.path(), vec![LightSamplerKind::Power], Budget::Spp(1));
    small.resolution = Some(UVec2::new(20, 15));
    small.out_dir = dir.path().join("small");
    compare(&small).unwrap();
    let e = diff(&dir.path().join("small/power.exr"), &r, None).err().unwrap().to_string();
    assert!(e.contains("20 × 15") && e.contains("40 × 30"), "{e}");
}
