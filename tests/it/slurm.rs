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
    (words[3].trim_end_matches(',').to_string(), words[5].to_string())
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
