//! Partial renders on disk: one sample range's exact sums and what a merge must check.
//!
//! A part file is the magic line `myriad part 1`, one line of JSON ([`PartHeader`]: which
//! scene, settings and myriad revision made it, which samples it holds), then the film's
//! fixed-point sums (`Film::sums_bytes`). Parts of one render merge by adding their sums, so
//! the merged image is bit-identical to one render of the union of their sample ranges.

use std::io::{BufRead, Read, Write};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::write_atomically;
use crate::error::{Error, Result};
use crate::film::{AovSet, Film};
use crate::math::UVec2;
use crate::settings::Clamp;

/// The first line of every part file.
const MAGIC: &[u8] = b"myriad part 1\n";
/// Longest header line read.
const MAX_HEADER: usize = 1 << 16;

/// What a part says of itself.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartHeader {
    /// myriad's version and git revision.
    pub myriad: String,
    /// The scene as the command line named it (for messages).
    pub scene: String,
    /// Fingerprint of the scene's contents (every file read) and of how it was loaded.
    pub scene_hash: String,
    /// Light sampler.
    pub sampler: String,
    /// Ray tracer (`builtin`, `embree`): tracers differ in the last bits of hit points, so
    /// only parts of one tracer add up to the bits one render gives. Empty in parts written
    /// before myriad recorded it.
    #[serde(default)]
    pub tracer: String,
    /// Seed.
    pub seed: u64,
    /// Maximum scattering events.
    pub max_depth: u32,
    /// Sample clamping (off in parts written before myriad had it).
    #[serde(default)]
    pub clamp: Clamp,
    /// Path guiding (off in parts written before myriad had it).
    #[serde(default)]
    pub guiding: bool,
    /// Light through smooth glass solved for (on in parts written before it could be
    /// turned off).
    #[serde(default = "on")]
    pub caustics: bool,
    /// Whether light paths to the camera were traced (the film then holds their splats;
    /// off in parts written before myriad traced them).
    #[serde(default)]
    pub light_paths: bool,
    /// Image size.
    pub resolution: [u32; 2],
    /// AOV names kept (albedo, normal, depth, variance).
    pub aovs: Vec<String>,
    /// The samples held: `first..end` of every pixel.
    pub samples: [u32; 2],
    /// Wall time the part took to render.
    pub render_seconds: f64,
}

/// What a missing switch that is on by default reads as.
fn on() -> bool {
    true
}

impl PartHeader {
    /// The header with what may differ between parts of one render blanked out: parts
    /// merge only when these are equal.
    pub fn render_identity(&self) -> PartHeader {
        PartHeader { scene: String::new(), samples: [0, 0], render_seconds: 0.0, ..self.clone() }
    }

    /// The AOVs the part keeps.
    pub fn aov_set(&self) -> AovSet {
        AovSet::from_names(&self.aovs)
    }

    /// Whether the film keeps first-hit sums.
    fn first_hit(&self) -> bool {
        self.aov_set().wants_first_hit()
    }
}

/// Writes `film` (the samples `header.samples` say) to `path`, whole or not at all.
pub fn write(path: &Path, header: &PartHeader, film: &Film) -> Result<()> {
    let json = serde_json::to_string(header).expect("a header serialises");
    write_atomically(path, |tmp| {
        let mut f = std::io::BufWriter::new(std::fs::File::create(tmp).map_err(|e| Error::io(tmp, e))?);
        f.write_all(MAGIC)
            .and_then(|_| f.write_all(json.as_bytes()))
            .and_then(|_| f.write_all(b"\n"))
            .and_then(|_| f.write_all(&film.sums_bytes()))
            .and_then(|_| f.flush())
            .map_err(|e| Error::io(tmp, e))
    })
}

fn bad(path: &Path, what: String) -> Error {
    Error::Input { path: path.to_path_buf(), message: format!("not a whole part file: {what}") }
}

/// Reads a part file's header alone (and checks that the file is as long as it says).
pub fn read_header(path: &Path) -> Result<PartHeader> {
    let mut f = std::io::BufReader::new(std::fs::File::open(path).map_err(|e| Error::io(path, e))?);
    let mut magic = vec![0u8; MAGIC.len()];
    if f.read_exact(&mut magic).is_err() || magic != MAGIC {
        return Err(bad(
            path,
            "it does not start with 'myriad part 1' (`myriad render --samples` writes parts)".into(),
        ));
    }
    let mut line = Vec::new();
    f.by_ref().take(MAX_HEADER as u64).read_until(b'\n', &mut line).map_err(|e| Error::io(path, e))?;
    if line.pop() != Some(b'\n') {
        return Err(bad(path, "it has no header line".into()));
    }
    let header: PartHeader =
        serde_json::from_slice(&line).map_err(|e| bad(path, format!("its header is not readable: {e}")))?;
    let [first, last] = header.samples;
    if first >= last {
        return Err(bad(path, format!("it holds samples {first}..{last}, an empty range")));
    }
    let expected = sums_len(&header).ok_or_else(|| {
        bad(path, format!("its header claims {} × {} pixels", header.resolution[0], header.resolution[1]))
    })?;
    let file = std::fs::metadata(path).map_err(|e| Error::io(path, e))?.len();
    let have = file.saturating_sub((MAGIC.len() + line.len() + 1) as u64);
    if have != expected {
        return Err(bad(
            path,
            format!(
                "it has {have} bytes of sums for {} × {} pixels, which need {expected} (a truncated copy?)",
                header.resolution[0], header.resolution[1]
            ),
        ));
    }
    Ok(header)
}

/// Bytes of sums a part of this header holds (`None` beyond what a u64 counts).
fn sums_len(h: &PartHeader) -> Option<u64> {
    (h.resolution[0] as u64 * h.resolution[1] as u64)
        .checked_mul(Film::bytes_per_pixel(h.first_hit(), h.light_paths) as u64)
}

/// Reads a part file: its header and its film.
pub fn read(path: &Path) -> Result<(PartHeader, Film)> {
    let header = read_header(path)?;
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let sums = sums_len(&header).and_then(|n| bytes.len().checked_sub(n as usize)).map(|start| &bytes[start..]);
    let size = UVec2::new(header.resolution[0], header.resolution[1]);
    let spp = header.samples[1] - header.samples[0];
    let film = sums
        .and_then(|sums| Film::from_sums_bytes(size, spp, header.first_hit(), header.light_paths, sums))
        .ok_or_else(|| bad(path, "it changed while it was read".into()))?;
    Ok((header, film))
}
