//! Partial renders on disk: one sample range's exact sums and what a merge must check.
//!
//! A part file is the magic line `myriad part 1`, one line of JSON ([`PartHeader`]: which
//! scene, settings and myriad revision made it, which samples it holds), then the film's
//! fixed-point sums (`Film::sums_bytes`). Parts of one render merge by adding their sums, so
//! the merged image is bit-identical to one render of the union of their sample ranges.

use std::io::Write;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::write_atomically;
use crate::error::{Error, Result};
use crate::film::Film;
use crate::math::UVec2;

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
    /// Seed.
    pub seed: u64,
    /// Maximum scattering events.
    pub max_depth: u32,
    /// Image size.
    pub resolution: [u32; 2],
    /// AOV names kept (albedo, normal, depth, variance).
    pub aovs: Vec<String>,
    /// The samples held: `first..end` of every pixel.
    pub samples: [u32; 2],
    /// Wall time the part took to render.
    pub render_seconds: f64,
}

impl PartHeader {
    /// The header with what may differ between parts of one render blanked out: parts
    /// merge only when these are equal.
    pub fn render_identity(&self) -> PartHeader {
        PartHeader { scene: String::new(), samples: [0, 0], render_seconds: 0.0, ..self.clone() }
    }

    /// Whether the film keeps first-hit sums.
    fn first_hit(&self) -> bool {
        self.aovs.iter().any(|a| a != "variance")
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

/// Reads a part file: its header and its film.
pub fn read(path: &Path) -> Result<(PartHeader, Film)> {
    let bad =
        |what: String| Error::Input { path: path.to_path_buf(), message: format!("not a whole part file: {what}") };
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let rest = bytes
        .strip_prefix(MAGIC)
        .ok_or_else(|| bad("does not start with 'myriad part 1': not a part `myriad render --samples` wrote".into()))?;
    let end = rest.iter().take(MAX_HEADER).position(|&b| b == b'\n').ok_or_else(|| bad("no header line".into()))?;
    let header: PartHeader =
        serde_json::from_slice(&rest[..end]).map_err(|e| bad(format!("its header is not readable: {e}")))?;
    let [first, last] = header.samples;
    if first >= last {
        return Err(bad(format!("holds samples {first}..{last}, an empty range")));
    }
    let size = UVec2::new(header.resolution[0], header.resolution[1]);
    Film::from_sums_bytes(size, last - first, header.first_hit(), &rest[end + 1..])
        .map(|film| (header.clone(), film))
        .ok_or_else(|| {
            bad(format!(
                "is cut short or padded: {} bytes of sums for {} × {} pixels (truncated copy?)",
                rest.len() - end - 1,
                size.x,
                size.y
            ))
        })
}
