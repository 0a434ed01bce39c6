//! `myriad slurm --submit` on a real Slurm: the one-node cluster `tools/slurm-local.sh start`
//! runs on this machine (CI starts it and sets MYRIAD_SLURM_TESTS=1; elsewhere the test runs
//! when `sinfo` answers and says why it is skipped when not).

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::split::{ok, same_pixels};

/// Whether a Slurm cluster answers here; with MYRIAD_SLURM_TESTS=1 it must.
fn cluster() -> bool {
    let up = Command::new("sinfo").arg("-h").output().is_ok_and(|o| o.status.success() && !o.stdout.is_empty());
    let required = std::env::var("MYRIAD_SLURM_TESTS").is_ok_and(|v| v == "1");
    assert!(up || !required, "MYRIAD_SLURM_TESTS=1 but no Slurm answers: run tools/slurm-local.sh start");
    if !up {
        eprintln!("skipped: no Slurm here (tools/slurm-local.sh start runs one, as root)");
    }
    up
}

/// Waits until `squeue` lists none of `jobs` (a minute at most).
fn wait_for(jobs: &[&str]) {
    let start = Instant::now();
    loop {
        let o = Command::new("squeue").args(["-h", "-j", &jobs.join(",")]).output().expect("squeue runs");
        if String::from_utf8_lossy(&o.stdout).trim().is_empty() {
            return;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "jobs {jobs:?} still queued after 2 minutes");
        std::thread::sleep(Duration::from_millis(300));
    }
}

/// The job ids `slurm --submit` printed: (render array, merge).
fn job_ids(said: &str) -> (String, String) {
    let line = said.lines().find(|l| l.starts_with("submitted")).unwrap_or_else(|| panic!("{said}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    // "submitted  array ID, then ID (...)"
    (words[2].trim_end_matches(',').to_string(), words[4].to_string())
}

#[test]
fn a_submitted_job_array_merges_to_the_one_machine_image_and_a_task_reruns_alone() {
    if !cluster() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-9x9.ron");
    let scene = scene.to_str().unwrap();
    let settings = ["--resolution", "24x18", "--max-depth", "4", "--seed", "3"];
    let job = d.join("job");
    let said = ok(
        &[
            &["slurm", scene, "--spp", "8", "--tasks", "4", "--cpus-per-task", "1", "--submit", "--out"][..],
            &[job.to_str().unwrap()],
            &settings,
        ]
        .concat(),
        d,
    );
    let (render, merge) = job_ids(&said);
    wait_for(&[&render, &merge]);
    let image = job.join("cornell-9x9.exr");
    let log = std::fs::read_to_string(job.join("logs/merge.out")).unwrap_or_default();
    assert!(image.exists(), "the merge job wrote nothing:\n{said}\n{log}");
    ok(&[&["render", scene, "--spp", "8", "-o", "one.exr"][..], &settings].concat(), d);
    same_pixels(&image, &d.join("one.exr"));

    // A lost task is rendered again by its array index alone, and the merge by hand agrees.
    std::fs::remove_file(job.join("parts/part-2.part")).unwrap();
    let o = Command::new("sbatch").args(["--parsable", "--array=2"]).arg(job.join("render.sbatch")).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    wait_for(&[String::from_utf8_lossy(&o.stdout).trim()]);
    let parts: Vec<String> = (0..4).map(|i| job.join(format!("parts/part-{i}.part")).display().to_string()).collect();
    ok(&[&["merge"][..], &parts.iter().map(String::as_str).collect::<Vec<_>>(), &["-o", "again.exr"]].concat(), d);
    same_pixels(&d.join("again.exr"), &d.join("one.exr"));
}

/// One sampler's measurements in a compare report: (sampler, [(seed, mse, relMSE)], bias z).
type Measured = (String, Vec<(u64, f64, f64)>, f64);

/// What a compare report.json measured of each sampler.
fn metrics(report: &Path) -> Vec<Measured> {
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
    json["samplers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            let runs = s["runs"].as_array().unwrap();
            let runs = runs
                .iter()
                .map(|r| (r["seed"].as_u64().unwrap(), r["mse"].as_f64().unwrap(), r["rel_mse"].as_f64().unwrap()));
            (s["sampler"].as_str().unwrap().to_string(), runs.collect(), s["bias"]["z"].as_f64().unwrap())
        })
        .collect()
}

#[test]
fn a_comparison_on_the_cluster_reports_what_one_machine_measures() {
    if !cluster() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-5x5.ron");
    let scene = scene.to_str().unwrap();
    let settings = ["--resolution", "16x12", "--max-depth", "3", "--spp", "8"];
    let job = d.join("job");
    let said = ok(
        &[
            &["slurm", scene, "--compare", "uniform,tree", "--seeds", "2", "--reference-spp", "32"][..],
            &["--submit", "--cpus-per-task", "1", "--out", job.to_str().unwrap()],
            &settings,
        ]
        .concat(),
        d,
    );
    assert!(said.contains("tasks      5"), "2 samplers × 2 seeds and the reference:\n{said}");
    let (array, report) = job_ids(&said);
    wait_for(&[&array, &report]);
    let cluster_report = job.join("report/report.json");
    let log = std::fs::read_to_string(job.join("logs/merge.out")).unwrap_or_default();
    assert!(cluster_report.exists(), "the report job wrote nothing:\n{log}");
    let reference = job.join("reference.exr");
    let reference = reference.to_str().unwrap();
    ok(
        &[
            &["compare", scene, "--samplers", "uniform,tree", "--seeds", "2", "--reference", reference, "-q"][..],
            &["--out-dir", "local"],
            &settings,
        ]
        .concat(),
        d,
    );
    assert_eq!(metrics(&cluster_report), metrics(&d.join("local/report.json")));
}
