//! `myriad slurm`: a render as a Slurm job array, one sample range per task, and a merge job
//! that waits for them (`--dependency=afterok`).
//!
//! Writes `render.sbatch` (task i renders its range of the samples, picked by
//! `SLURM_ARRAY_TASK_ID`, to `parts/part-i.part`) and `merge.sbatch` (`myriad merge` of every
//! part into the image) into the job folder; with `submit`, hands both to `sbatch` and
//! reports the job ids. Every path in the scripts is absolute: the cluster is assumed to share
//! one file system (the scene, the myriad binary and the job folder visible alike on every
//! node), as render clusters do.

use std::fmt;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::error::{Error, Result};

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
}

/// What `slurm` wrote and submitted.
#[derive(Debug)]
pub struct SlurmReport {
    /// The job folder.
    pub out: PathBuf,
    /// Sample range of each task.
    pub ranges: Vec<(u32, u32)>,
    /// The render array's job id and the merge job's, when submitted.
    pub jobs: Option<(String, String)>,
    /// The image the merge job writes.
    pub image: PathBuf,
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

/// Writes the two job scripts (and submits them when asked).
pub fn slurm(opts: &SlurmOptions) -> Result<SlurmReport> {
    if opts.tasks == 0 || opts.tasks > opts.spp {
        return Err(Error::Usage(format!(
            "--tasks {} does not fit {} spp: give 1 to {} tasks (each renders at least one sample)",
            opts.tasks, opts.spp, opts.spp
        )));
    }
    let exe = std::env::current_exe().map_err(|e| Error::io("myriad executable", e))?;
    let (scene, out) = (absolute(&opts.scene)?, absolute(&opts.out)?);
    if !scene.is_file() {
        return Err(Error::Usage(format!("{}: no such scene file", scene.display())));
    }
    for dir in [out.clone(), out.join("parts"), out.join("logs")] {
        crate::io::ensure_dir(&dir)?;
    }
    let stem = scene.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let image = out.join(format!("{stem}.exr"));
    let ranges = ranges(opts.spp, opts.tasks);
    let q = |p: &Path| quoted(&p.to_string_lossy());
    let list: Vec<String> = ranges.iter().map(|(a, b)| format!("{a}..{b}")).collect();
    let mut args: Vec<String> = opts.render_args.iter().map(|a| quoted(a)).collect();
    if let Some(c) = opts.cpus_per_task {
        args.push(format!("--threads {c}"));
    }
    let render = format!(
        "#!/bin/bash\n# Written by myriad slurm: task i renders samples RANGES[i] of {scene} ({spp} spp in {n} \
         tasks).\n# Re-run one failed task alone with: sbatch --array=I {script}\n{dirs}#SBATCH --array=0-{last}\n\
         set -euo pipefail\nRANGES=({list})\ni=${{SLURM_ARRAY_TASK_ID:?run me with sbatch, or set SLURM_ARRAY_TASK_ID}}\n\
         exec {exe} render {sq} --samples \"${{RANGES[$i]}}\" -o {parts}/part-$i.part --quiet {args}\n",
        scene = scene.display(),
        spp = opts.spp,
        n = opts.tasks,
        script = out.join("render.sbatch").display(),
        dirs = directives(opts, &format!("myriad-{stem}"), &format!("{}/logs/render-%a.out", out.display())),
        last = opts.tasks - 1,
        list = list.join(" "),
        exe = q(&exe),
        sq = q(&scene),
        parts = q(&out.join("parts")),
        args = args.join(" "),
    );
    let parts: Vec<String> = (0..opts.tasks).map(|i| q(&out.join("parts").join(format!("part-{i}.part")))).collect();
    let merge = format!(
        "#!/bin/bash\n# Written by myriad slurm: joins the render array's parts into {image}.\n{dirs}set -euo pipefail\n\
         exec {exe} merge {parts} -o {iq} --png\n",
        image = image.display(),
        dirs = directives(opts, &format!("myriad-{stem}-merge"), &format!("{}/logs/merge.out", out.display())),
        exe = q(&exe),
        parts = parts.join(" "),
        iq = q(&image),
    );
    crate::io::write_text(&out.join("render.sbatch"), &render)?;
    crate::io::write_text(&out.join("merge.sbatch"), &merge)?;
    let jobs = if opts.submit { Some(submit(&out)?) } else { None };
    Ok(SlurmReport { out, ranges, jobs, image })
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
        let spans: Vec<String> = self.ranges.iter().map(|(a, b)| format!("{a}..{b}")).collect();
        writeln!(f, "tasks      {} (samples {})", self.ranges.len(), spans.join(", "))?;
        writeln!(f, "scripts    {d}/render.sbatch (job array), {d}/merge.sbatch (after it)")?;
        match &self.jobs {
            Some((render, merge)) => {
                writeln!(f, "submitted  render array {render}, merge {merge} (runs when every task succeeded)")?;
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
        write!(f, "image      {} (and its .png)", self.image.display())
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
