//! `myriad slurm`: a render as a Slurm job array, one sample range per task, and a merge job
//! that waits for them (`--dependency=afterok`); or a sampler comparison, one (sampler, seed)
//! run per task (and one for the reference), and a report job.
//!
//! Writes `render.sbatch` (task i, picked by `SLURM_ARRAY_TASK_ID`, renders its range of the
//! samples to `parts/part-i.part`, or its run to `runs/SAMPLER-SEED.part`) and `merge.sbatch`
//! (`myriad merge` of every part into the image, or `myriad compare --runs` over the runs)
//! into the job folder; with `submit`, hands both to `sbatch` and reports the job ids. Every path in the scripts is absolute: the cluster is assumed to share
//! one file system (the scene, the myriad binary and the job folder visible alike on every
//! node), as render clusters do.

use std::fmt;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::error::{Error, Result};
use crate::settings::LightSamplerKind;

/// A sampler comparison on the cluster: what `myriad compare` would render at equal spp.
#[derive(Clone, Debug)]
pub struct CompareJob {
    /// Samplers, in report order.
    pub samplers: Vec<LightSamplerKind>,
    /// Seeds per sampler: the runs use the seeds after `seed`.
    pub seeds: u32,
    /// The base seed.
    pub seed: u64,
    /// A reference to measure against; otherwise a task renders one.
    pub reference: Option<PathBuf>,
    /// spp and sampler of a rendered reference.
    pub reference_spp: u32,
    /// Sampler of a rendered reference.
    pub reference_sampler: LightSamplerKind,
}

/// What to put on the cluster.
#[derive(Clone, Debug, Default)]
pub struct SlurmOptions {
    /// Scene file.
    pub scene: PathBuf,
    /// Samples per pixel of the whole render.
    pub spp: u32,
    /// Array tasks (sample ranges).
    pub tasks: u32,
    /// The job folder: scripts, `parts/`, `logs/` and the merged image.
    pub out: PathBuf,
    /// `render` flags every task passes on (sampler, seed, resolution, AOVs...).
    pub render_args: Vec<String>,
    /// `sbatch` options for both jobs: partition, time limit, CPUs per task, memory.
    pub partition: Option<String>,
    /// Time limit per task (Slurm's format).
    pub time: Option<String>,
    /// CPUs per task; the tasks render with that many threads.
    pub cpus_per_task: Option<u32>,
    /// Memory per task (Slurm's format, e.g. 4G).
    pub mem: Option<String>,
    /// Submit with `sbatch` after writing the scripts.
    pub submit: bool,
    /// Compare samplers instead of rendering one image.
    pub compare: Option<CompareJob>,
}

/// What `slurm` wrote and submitted.
#[derive(Debug)]
pub struct SlurmReport {
    /// The job folder.
    pub out: PathBuf,
    /// What each task does, in words.
    pub tasks: Vec<String>,
    /// The render array's job id and the merge job's, when submitted.
    pub jobs: Option<(String, String)>,
    /// What the last job writes: the merged image, or the comparison's report folder.
    pub result: PathBuf,
}

/// Samples `0..spp` cut into `tasks` ranges whose sizes differ by at most one.
pub fn ranges(spp: u32, tasks: u32) -> Vec<(u32, u32)> {
    let at = |i: u32| (i as u64 * spp as u64 / tasks as u64) as u32;
    (0..tasks).map(|i| (at(i), at(i + 1))).collect()
}

/// A word for a bash script, quoted.
fn quoted(word: &str) -> String {
    format!("'{}'", word.replace('\'', r"'\''"))
}

fn absolute(p: &Path) -> Result<PathBuf> {
    std::path::absolute(p).map_err(|e| Error::io(p, e))
}

/// The `#SBATCH` lines both jobs share.
fn directives(opts: &SlurmOptions, name: &str, log: &str) -> String {
    let mut s = format!("#SBATCH --job-name={name}\n#SBATCH --output={log}\n");
    for (flag, value) in [("partition", &opts.partition), ("time", &opts.time), ("mem", &opts.mem)] {
        if let Some(v) = value {
            s += &format!("#SBATCH --{flag}={v}\n");
        }
    }
    if let Some(c) = opts.cpus_per_task {
        s += &format!("#SBATCH --cpus-per-task={c}\n");
    }
    s
}

/// One array task: what it does, in words, and its command line.
struct Task {
    what: String,
    command: Vec<String>,
}

/// Writes the two job scripts (and submits them when asked).
pub fn slurm(opts: &SlurmOptions) -> Result<SlurmReport> {
    let exe = std::env::current_exe().map_err(|e| Error::io("myriad executable", e))?;
    let (scene, out) = (absolute(&opts.scene)?, absolute(&opts.out)?);
    if !scene.is_file() {
        return Err(Error::Usage(format!("{}: no such scene file", scene.display())));
    }
    let stem = scene.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let text = |p: &Path| p.to_string_lossy().into_owned();
    let mut common: Vec<String> = vec!["--quiet".into()];
    common.extend(opts.render_args.iter().cloned());
    if let Some(c) = opts.cpus_per_task {
        common.extend(["--threads".into(), c.to_string()]);
    }
    let render = |extra: Vec<String>| {
        let mut c = vec![text(&exe), "render".into(), text(&scene)];
        c.extend(extra);
        c.extend(common.iter().cloned());
        c
    };
    let (tasks, last, result) = match &opts.compare {
        None => image_tasks(opts, &out, &render, &exe, &stem)?,
        Some(job) => compare_tasks(opts, job, &out, &render, &exe, &scene)?,
    };
    for dir in [out.clone(), out.join("parts"), out.join("runs"), out.join("logs")] {
        crate::io::ensure_dir(&dir)?;
    }
    write_scripts(opts, &out, &stem, &scene, &tasks, &last)?;
    let jobs = if opts.submit { Some(submit(&out)?) } else { None };
    Ok(SlurmReport { out, tasks: tasks.into_iter().map(|t| t.what).collect(), jobs, result })
}

/// The tasks of one image (each a range of the samples) and the merge job's command line.
fn image_tasks(
    opts: &SlurmOptions,
    out: &Path,
    render: &dyn Fn(Vec<String>) -> Vec<String>,
    exe: &Path,
    stem: &str,
) -> Result<(Vec<Task>, Vec<String>, PathBuf)> {
    if opts.spp == 0 {
        return Err(Error::Usage("--spp must be at least 1".into()));
    }
    if opts.tasks == 0 || opts.tasks > opts.spp {
        return Err(Error::Usage(format!(
            "--tasks {} does not fit {} spp: give 1 to {} tasks (each renders at least one sample)",
            opts.tasks, opts.spp, opts.spp
        )));
    }
    crate::limits::check_runs(opts.tasks as u64, format_args!("--tasks {}", opts.tasks)).map_err(Error::Usage)?;
    let text = |p: &Path| p.to_string_lossy().into_owned();
    let parts: Vec<PathBuf> = (0..opts.tasks).map(|i| out.join("parts").join(format!("part-{i}.part"))).collect();
    let tasks = ranges(opts.spp, opts.tasks)
        .into_iter()
        .zip(&parts)
        .map(|((a, b), part)| Task {
            what: format!("samples {a}..{b}"),
            command: render(vec!["--samples".into(), format!("{a}..{b}"), "-o".into(), text(part)]),
        })
        .collect();
    let image = out.join(format!("{stem}.exr"));
    let mut merge = vec![text(exe), "merge".into()];
    merge.extend(parts.iter().map(|p| text(p)));
    merge.extend(["-o".into(), text(&image), "--png".into()]);
    Ok((tasks, merge, image))
}

/// Writes `render.sbatch` (the array: a `case` per task) and `merge.sbatch` (`last`).
fn write_scripts(
    opts: &SlurmOptions,
    out: &Path,
    stem: &str,
    scene: &Path,
    tasks: &[Task],
    last: &[String],
) -> Result<()> {
    let cases: String = tasks
        .iter()
        .enumerate()
        .map(|(i, t)| {
            format!("    {i}) exec {} ;;\n", t.command.iter().map(|w| quoted(w)).collect::<Vec<_>>().join(" "))
        })
        .collect();
    let array = format!(
        "#!/bin/bash\n# Written by myriad slurm: {n} tasks over {scene}, task i doing the i-th line below.\n\
         # Re-run one failed task alone with: sbatch --array=I {script}\n{dirs}#SBATCH --array=0-{top}\n\
         set -euo pipefail\ncase \"${{SLURM_ARRAY_TASK_ID:?run me with sbatch}}\" in\n{cases}    *) echo \"no task $SLURM_ARRAY_TASK_ID\" >&2; exit 2 ;;\nesac\n",
        n = tasks.len(),
        scene = scene.display(),
        script = out.join("render.sbatch").display(),
        dirs = directives(opts, &format!("myriad-{stem}"), &format!("{}/logs/render-%a.out", out.display())),
        top = tasks.len() - 1,
    );
    let finish = format!(
        "#!/bin/bash\n# Written by myriad slurm: runs when every task of render.sbatch has succeeded.\n{dirs}\
         set -euo pipefail\nexec {cmd}\n",
        dirs = directives(opts, &format!("myriad-{stem}-merge"), &format!("{}/logs/merge.out", out.display())),
        cmd = last.iter().map(|w| quoted(w)).collect::<Vec<_>>().join(" "),
    );
    crate::io::write_text(&out.join("render.sbatch"), &array)?;
    crate::io::write_text(&out.join("merge.sbatch"), &finish)
}

/// The tasks of a comparison (each sampler with each seed, then the reference unless given)
/// and the report job's command line.
fn compare_tasks(
    opts: &SlurmOptions,
    job: &CompareJob,
    out: &Path,
    render: &dyn Fn(Vec<String>) -> Vec<String>,
    exe: &Path,
    scene: &Path,
) -> Result<(Vec<Task>, Vec<String>, PathBuf)> {
    let count = job.samplers.len() as u64 * job.seeds as u64 + job.reference.is_none() as u64;
    let what = format_args!("{} sampler(s) × --seeds {} and a reference", job.samplers.len(), job.seeds);
    crate::limits::check_runs(count, what).map_err(Error::Usage)?;
    if opts.spp == 0 || job.seeds == 0 {
        return Err(Error::Usage("--spp and --seeds must be at least 1".into()));
    }
    let text = |p: &Path| p.to_string_lossy().into_owned();
    let (runs, report) = (out.join("runs"), out.join("report"));
    let mut tasks = Vec::new();
    for &kind in &job.samplers {
        for seed in (1..=job.seeds as u64).map(|k| job.seed.wrapping_add(k)) {
            let part = text(&super::compare::run_part(&runs, kind, seed));
            let range = format!("0..{}", opts.spp);
            let args =
                words(&["--samples", &range, "--sampler", kind.name(), "--seed", &seed.to_string(), "-o", &part]);
            tasks.push(Task { what: format!("{kind} seed {seed}"), command: render(args) });
        }
    }
    let reference = job.reference.clone().unwrap_or_else(|| out.join("reference.exr"));
    if job.reference.is_none() {
        let (spp, seed) = (job.reference_spp.to_string(), super::compare::REFERENCE_SEED.to_string());
        let sampler = job.reference_sampler.name();
        let args = words(&["--spp", &spp, "--sampler", sampler, "--seed", &seed, "--aov", "variance", "--no-png"]);
        let args = [args, vec!["-o".into(), text(&reference)]].concat();
        tasks.push(Task { what: format!("reference ({sampler}, {spp} spp)"), command: render(args) });
    }
    let samplers: Vec<&str> = job.samplers.iter().map(|k| k.name()).collect();
    let (seeds, seed, spp) = (job.seeds.to_string(), job.seed.to_string(), opts.spp.to_string());
    let (exe, scene, runs, reference, report_dir) =
        (text(exe), text(scene), text(&runs), text(&reference), text(&report));
    let mut cmd =
        words(&[&exe, "compare", &scene, "--samplers", &samplers.join(","), "--seeds", &seeds, "--seed", &seed]);
    cmd.extend(words(&[
        "--spp",
        &spp,
        "--runs",
        &runs,
        "--reference",
        &reference,
        "--out-dir",
        &report_dir,
        "--quiet",
    ]));
    cmd.extend(opts.render_args.iter().cloned());
    Ok((tasks, cmd, report))
}

/// Owned words of a command line.
fn words(list: &[&str]) -> Vec<String> {
    list.iter().map(|w| w.to_string()).collect()
}

/// `sbatch --parsable` of the array, then of the merge after it; the two job ids.
fn submit(out: &Path) -> Result<(String, String)> {
    let sbatch = |args: &[&str]| -> Result<String> {
        let o = Command::new("sbatch").arg("--parsable").args(args).current_dir(out).output().map_err(|e| {
            Error::Usage(format!(
                "could not run sbatch ({e}): is this a Slurm login node? The scripts are in {}",
                out.display()
            ))
        })?;
        if !o.status.success() {
            return Err(Error::Usage(format!(
                "sbatch {} failed: {}",
                args.join(" "),
                String::from_utf8_lossy(&o.stderr).trim()
            )));
        }
        // "id" or "id;cluster".
        let text = String::from_utf8_lossy(&o.stdout);
        Ok(text.trim().split(';').next().unwrap_or_default().to_string())
    };
    let render = sbatch(&[&out.join("render.sbatch").to_string_lossy()])?;
    let merge = sbatch(&[&format!("--dependency=afterok:{render}"), &out.join("merge.sbatch").to_string_lossy()])?;
    Ok((render, merge))
}

impl fmt::Display for SlurmReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let d = self.out.display();
        let shown: Vec<&str> = self.tasks.iter().take(6).map(String::as_str).collect();
        let more = if self.tasks.len() > 6 { format!(", … ({} more)", self.tasks.len() - 6) } else { String::new() };
        writeln!(f, "tasks      {}: {}{more}", self.tasks.len(), shown.join(", "))?;
        writeln!(f, "scripts    {d}/render.sbatch (job array), {d}/merge.sbatch (after it)")?;
        match &self.jobs {
            Some((render, merge)) => {
                writeln!(f, "submitted  array {render}, then {merge} (runs when every task succeeded)")?;
                writeln!(
                    f,
                    "follow     squeue -j {render},{merge}   (sacct -j {render}, where accounting is on); logs in {d}/logs"
                )?;
                writeln!(
                    f,
                    "re-run     a failed task i: sbatch --array=i {d}/render.sbatch, then sbatch {d}/merge.sbatch"
                )?;
            }
            None => writeln!(
                f,
                "submit     sbatch {d}/render.sbatch, then sbatch --dependency=afterok:ID {d}/merge.sbatch"
            )?,
        }
        write!(f, "result     {}", self.result.display())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_tile_the_samples_evenly() {
        assert_eq!(ranges(10, 4), [(0, 2), (2, 5), (5, 7), (7, 10)]);
        assert_eq!(ranges(4, 4), [(0, 1), (1, 2), (2, 3), (3, 4)]);
        let r = ranges(1000, 7);
        assert!(r.windows(2).all(|w| w[0].1 == w[1].0) && r[0].0 == 0 && r[6].1 == 1000);
        assert!(r.iter().all(|(a, b)| (142..=143).contains(&(b - a))));
    }

    #[test]
    fn words_are_quoted_for_bash() {
        assert_eq!(quoted("a b"), "'a b'");
        assert_eq!(quoted("it's"), r"'it'\''s'");
    }
}
