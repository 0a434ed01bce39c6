//! Renders split into sample ranges: the part a `render --samples A..B` writes, and
//! `myriad merge`, which joins parts into the image one render of all their samples makes.
//!
//! Every random number is addressed by (seed, pixel, sample, bounce, dimension) and the film
//! sums in fixed point, so a part holds exactly the sums samples `A..B` add to a full render;
//! a merge checks that the parts belong together (same myriad revision, scene contents and
//! settings; disjoint ranges; no gap unless allowed) and adds them.

use std::fmt;
use std::path::PathBuf;

use super::preview_path;
use crate::error::{Error, Result};
use crate::film::Film;
use crate::io::part::{self, PartHeader};
use crate::limits::check_memory;
use crate::settings::on_off;

/// What to merge.
#[derive(Clone, Debug)]
pub struct MergeOptions {
    /// Part files, in any order.
    pub parts: Vec<PathBuf>,
    /// EXR output.
    pub output: PathBuf,
    /// Also write a PNG preview beside it.
    pub png: bool,
    /// PNG exposure in stops.
    pub exposure: f32,
    /// Merge parts whose ranges leave samples out (reported) instead of refusing.
    pub allow_gaps: bool,
}

/// What a merge did, for the summary.
#[derive(Debug)]
pub struct MergeReport {
    /// The parts' common header (first part's scene name, the merged range's ends).
    pub header: PartHeader,
    /// Sample ranges merged, in order.
    pub ranges: Ranges,
    /// Ranges no part held, when gaps were allowed.
    pub gaps: Ranges,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// Reads, checks and merges the parts, and writes the image.
pub fn merge(opts: &MergeOptions) -> Result<MergeReport> {
    let png = opts.png.then(|| preview_path(&opts.output));
    crate::io::exr::check_name(&opts.output)?;
    crate::io::check_writable(&opts.output)?;
    if let Some(p) = &png {
        crate::io::check_writable(p)?;
    }
    // Headers first (every check before any sums are read), then one part's sums at a time.
    let mut parts = Vec::with_capacity(opts.parts.len());
    for path in &opts.parts {
        parts.push((path.clone(), part::read_header(path)?));
    }
    let Some((first_path, first)) = parts.first() else {
        return Err(Error::Usage("merge needs at least one part file".into()));
    };
    let identity = first.render_identity();
    for (path, h) in &parts[1..] {
        if h.render_identity() != identity {
            return Err(Error::Input {
                path: path.clone(),
                message: format!(
                    "does not belong with {}: {}; render every part with the same myriad, scene and settings",
                    first_path.display(),
                    difference(first, h)
                ),
            });
        }
    }
    parts.sort_by_key(|(_, h)| h.samples);
    let (ranges, gaps) = check_ranges(&parts, opts.allow_gaps)?;
    let mut header = parts[0].1.clone();
    header.samples = [ranges[0].0, ranges.last().expect("one part at least").1];
    let pixels = header.resolution[0] as u64 * header.resolution[1] as u64;
    let film_bytes = pixels * Film::bytes_per_pixel(header.aov_set().wants_first_hit(), header.light_paths) as u64;
    // The sum so far, the part being read, and the part's file bytes.
    check_memory(3 * film_bytes, "merging these parts").map_err(Error::Usage)?;
    let mut film: Option<Film> = None;
    for (path, _) in &parts {
        let (_, f) = part::read(path)?;
        match film.as_mut() {
            Some(acc) => acc.merge(&f),
            None => film = Some(f),
        }
    }
    let film = film.expect("one part at least");
    let written = write_merged(opts, &header, &film, png)?;
    Ok(MergeReport { header, ranges, gaps, written })
}

/// Sample ranges `first..end`.
type Ranges = Vec<(u32, u32)>;

/// The sample ranges of the sorted parts, and the gaps between them; an overlap is an
/// error, and so is a gap unless `allow_gaps`.
fn check_ranges(parts: &[(PathBuf, PartHeader)], allow_gaps: bool) -> Result<(Ranges, Ranges)> {
    let ranges: Ranges = parts.iter().map(|(_, h)| (h.samples[0], h.samples[1])).collect();
    let mut gaps = Vec::new();
    if ranges[0].0 > 0 {
        gaps.push((0, ranges[0].0));
    }
    for (i, w) in ranges.windows(2).enumerate() {
        let ((a0, a1), (b0, b1)) = (w[0], w[1]);
        if b0 < a1 {
            return Err(Error::Input {
                path: parts[i + 1].0.clone(),
                message: format!(
                    "holds samples {b0}..{b1}, which overlap {a0}..{a1} of {}: each sample may be merged once",
                    parts[i].0.display()
                ),
            });
        }
        if b0 > a1 {
            gaps.push((a1, b0));
        }
    }
    if !gaps.is_empty() && !allow_gaps {
        let list: Vec<String> = gaps.iter().map(|(a, b)| format!("{a}..{b}")).collect();
        return Err(Error::Usage(format!(
            "no part holds samples {}: render them (myriad render ... --samples A..B), or pass --allow-gaps to \
             merge what there is",
            list.join(", ")
        )));
    }
    Ok((ranges, gaps))
}

/// What differs between two parts' identities, for the message.
fn difference(a: &PartHeader, b: &PartHeader) -> String {
    let fields = [
        ("myriad", a.myriad.clone(), b.myriad.clone()),
        ("scene contents", a.scene_hash.clone(), b.scene_hash.clone()),
        ("sampler", a.sampler.clone(), b.sampler.clone()),
        ("tracer", a.tracer.clone(), b.tracer.clone()),
        ("seed", a.seed.to_string(), b.seed.to_string()),
        ("max depth", a.max_depth.to_string(), b.max_depth.to_string()),
        ("clamp", a.clamp.to_string(), b.clamp.to_string()),
        ("guiding", on_off(a.guiding).into(), on_off(b.guiding).into()),
        ("caustics", on_off(a.caustics).into(), on_off(b.caustics).into()),
        ("resolution", format!("{:?}", a.resolution), format!("{:?}", b.resolution)),
        ("AOVs", a.aovs.join(","), b.aovs.join(",")),
    ];
    let diffs: Vec<String> =
        fields.into_iter().filter(|(_, x, y)| x != y).map(|(n, x, y)| format!("{n} {y} (not {x})")).collect();
    diffs.join(", ")
}

/// Writes the merged image (EXR with the provenance a render writes, and the preview).
fn write_merged(opts: &MergeOptions, header: &PartHeader, film: &Film, png: Option<PathBuf>) -> Result<Vec<PathBuf>> {
    let h = header;
    let mut meta = super::provenance::image_provenance(
        &h.scene,
        &h.sampler,
        &h.tracer,
        film.spp(),
        h.seed,
        h.max_depth,
        h.clamp,
        h.guiding,
        h.caustics,
    );
    meta.push(("myriad.samples".into(), format!("{}..{}", h.samples[0], h.samples[1])));
    meta.push(("myriad.parts_revision".into(), h.myriad.clone()));
    crate::io::exr::write(&opts.output, &film.layers(h.aov_set()), &meta)?;
    let mut written = vec![opts.output.clone()];
    if let Some(p) = png {
        crate::io::png::write(&p, film.size(), &film.means(), opts.exposure)?;
        written.push(p);
    }
    Ok(written)
}

impl fmt::Display for MergeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let h = &self.header;
        let ranges: Vec<String> = self.ranges.iter().map(|(a, b)| format!("{a}..{b}")).collect();
        writeln!(f, "merged     {} parts of {} ({})", self.ranges.len(), h.scene, ranges.join(", "))?;
        let spp: u32 = self.ranges.iter().map(|(a, b)| b - a).sum();
        writeln!(
            f,
            "image      {} × {}, {spp} spp, sampler {}, seed {}, max depth {}",
            h.resolution[0], h.resolution[1], h.sampler, h.seed, h.max_depth
        )?;
        if !self.gaps.is_empty() {
            let gaps: Vec<String> = self.gaps.iter().map(|(a, b)| format!("{a}..{b}")).collect();
            writeln!(f, "gaps       samples {} are missing (--allow-gaps)", gaps.join(", "))?;
        }
        let written: Vec<String> = self.written.iter().map(|p| p.display().to_string()).collect();
        write!(f, "wrote      {}", written.join(", "))
    }
}
