//! How big an input may be: every size a file or an option can set is checked against what
//! it will make myriad allocate, before allocating, so that absurd sizes are errors that say
//! the limit and how to raise it, never an out-of-memory abort.
//!
//! Owns: the memory limit (default: three quarters of the least of the machine's memory, the
//! control group's limit and the process's address-space and data limits; `--max-memory` or
//! `MYRIAD_MAX_MEMORY`, in GB, override it), the measured cost per item that the checks
//! multiply by, and the range of coordinates and powers myriad's f32 arithmetic can hold.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

/// Largest |coordinate| of any vertex, light or camera, in metres (a terametre): f32 areas
/// and BVH quantisation overflow not far past 10¹⁸.
pub const MAX_COORDINATE: f32 = 1e12;

/// Largest power of one light, in watts: importances divide it by squared distances, which
/// must stay finite in f32.
pub const MAX_POWER: f32 = 1e30;

/// Bytes per pixel of a render: the film's fixed-point sums (96 bytes, 112 more with AOVs,
/// 96 more for light paths' splats), the output channels and their copy in the EXR writer,
/// the preview.
pub const BYTES_PER_PIXEL: u64 = 456;

/// Bytes per triangle in the world: vertices and attributes, the BVH, the description it was
/// built from.
pub const BYTES_PER_TRIANGLE: u64 = 220;

/// Bytes per light beyond its triangles: the light, its bounds, every sampler's tables.
pub const BYTES_PER_LIGHT: u64 = 480;

/// Bytes per placement of a shared mesh (the top-level BVH's entry and transform).
pub const BYTES_PER_INSTANCE: u64 = 160;

/// Most renders one command may plan: a comparison's runs (samplers × seeds), a Slurm job
/// array's tasks. Each is a whole render, so more than this is a typo, not a plan; and
/// Slurm's own array limit (`MaxArraySize`) is 1001 by default and rarely raised past 10⁴.
pub const MAX_RUNS: u64 = 10_000;

/// `Err(message)` when `runs` renders (`what`, e.g. "4 samplers × 100000 seeds") exceed
/// [`MAX_RUNS`].
pub fn check_runs(runs: u64, what: impl std::fmt::Display) -> Result<(), String> {
    if runs <= MAX_RUNS {
        return Ok(());
    }
    Err(format!("{what} would be {runs} renders; myriad plans at most {MAX_RUNS} in one command"))
}

/// Environment variable that sets the memory limit, in GB.
pub const MEMORY_ENV: &str = "MYRIAD_MAX_MEMORY";

/// Where the memory limit comes from, for messages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MemoryLimit {
    /// Bytes.
    pub bytes: u64,
    /// What set it.
    pub source: &'static str,
}

static OVERRIDE: AtomicU64 = AtomicU64::new(0);
static DEFAULT: OnceLock<MemoryLimit> = OnceLock::new();

/// Sets the limit for the rest of the process (`--max-memory`).
pub fn set_memory_limit(bytes: u64) {
    OVERRIDE.store(bytes.max(1), Ordering::SeqCst);
}

/// The memory limit in force.
pub fn memory_limit() -> MemoryLimit {
    match OVERRIDE.load(Ordering::SeqCst) {
        0 => *DEFAULT.get_or_init(default_limit),
        bytes => MemoryLimit { bytes, source: "set by --max-memory" },
    }
}

/// Parses a size in GB (`"16"`, `"0.5"`) into bytes.
pub fn parse_gb(text: &str) -> Option<u64> {
    let gb: f64 = text.trim().parse().ok()?;
    (gb > 0.0 && gb <= 1e9).then_some((gb * 1e9) as u64)
}

/// `Err(message)` when [`MEMORY_ENV`] is set to something other than a positive number of
/// GB: the command line refuses it as it refuses `--max-memory abc`, rather than fall back
/// to the default the user meant to replace.
pub fn check_memory_env() -> Result<(), String> {
    match std::env::var(MEMORY_ENV) {
        Ok(text) if parse_gb(&text).is_none() => Err(format!(
            "{MEMORY_ENV}={text} is not a positive number of gigabytes (e.g. {MEMORY_ENV}=8); set it to one, or \
             unset it for the default limit"
        )),
        Err(std::env::VarError::NotUnicode(_)) => Err(format!("{MEMORY_ENV} is not text; set it to a number of GB")),
        _ => Ok(()),
    }
}

fn default_limit() -> MemoryLimit {
    if let Some(bytes) = std::env::var(MEMORY_ENV).ok().as_deref().and_then(parse_gb) {
        return MemoryLimit { bytes, source: "set by MYRIAD_MAX_MEMORY" };
    }
    match machine::available() {
        Some(bytes) => MemoryLimit { bytes: bytes / 4 * 3, source: "3/4 of what this machine lets the process use" },
        None => MemoryLimit { bytes: 8_000_000_000, source: "the default when the machine's memory is unknown" },
    }
}

/// `Err(message)` when `bytes` exceed the memory limit; `what` names what needs them.
pub fn check_memory(bytes: u64, what: impl std::fmt::Display) -> Result<(), String> {
    let limit = memory_limit();
    if bytes <= limit.bytes {
        return Ok(());
    }
    Err(format!(
        "{what} needs about {} of memory, more than myriad's limit of {} ({}); if the machine has \
         the memory, raise the limit with --max-memory GB (or {MEMORY_ENV})",
        human_bytes(bytes),
        human_bytes(limit.bytes),
        limit.source
    ))
}

/// Formats a byte count for people.
pub fn human_bytes(b: u64) -> String {
    let b = b as f64;
    if b >= 1e9 {
        format!("{:.2} GB", b / 1e9)
    } else if b >= 1e6 {
        format!("{:.1} MB", b / 1e6)
    } else if b >= 1e3 {
        format!("{:.1} kB", b / 1e3)
    } else {
        format!("{b} B")
    }
}

/// What the operating system says the process may use.
mod machine {
    /// The least of physical memory, the cgroup limit and the address-space and data limits.
    pub fn available() -> Option<u64> {
        [physical(), cgroup(), rlimit()].into_iter().flatten().min()
    }

    fn physical() -> Option<u64> {
        let info = std::fs::read_to_string("/proc/meminfo").ok()?;
        let kb: u64 = info.lines().find(|l| l.starts_with("MemTotal:"))?.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb * 1024)
    }

    fn cgroup() -> Option<u64> {
        ["/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"]
            .iter()
            .find_map(|p| std::fs::read_to_string(p).ok()?.trim().parse().ok())
    }

    #[cfg(unix)]
    fn rlimit() -> Option<u64> {
        [libc::RLIMIT_AS, libc::RLIMIT_DATA]
            .into_iter()
            .filter_map(|resource| {
                let mut r = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
                // SAFETY: getrlimit writes one rlimit struct, which `r` is.
                let ok = unsafe { libc::getrlimit(resource, &mut r) } == 0;
                (ok && r.rlim_cur != libc::RLIM_INFINITY).then_some(r.rlim_cur)
            })
            .min()
    }

    #[cfg(not(unix))]
    fn rlimit() -> Option<u64> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_limit_is_known_and_refusals_say_how_to_raise_it() {
        let limit = memory_limit();
        assert!(limit.bytes > 0);
        assert!(check_memory(1000, "a small image").is_ok());
        let e = check_memory(u64::MAX, "a 16384 × 16384 image").unwrap_err();
        assert!(e.contains("16384 × 16384") && e.contains("--max-memory") && e.contains(MEMORY_ENV), "{e}");
        assert_eq!(parse_gb("0.5"), Some(500_000_000));
        assert_eq!(parse_gb("-1"), None);
        assert_eq!(parse_gb("NaN"), None);
    }
}
