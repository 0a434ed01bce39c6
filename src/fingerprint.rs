//! Fingerprints of what a result depends on, so that a cached result is reused only when
//! every input is the same: the bytes of every file, every setting, and the build of myriad.
//!
//! Owns: [`Fingerprint`] (BLAKE3 over labelled values and file contents) and [`build_id`].

use std::fmt::Display;
use std::path::Path;
use std::sync::OnceLock;

use crate::error::{Error, Result};

/// A hash being built from labelled parts.
pub struct Fingerprint(blake3::Hasher);

impl Fingerprint {
    /// A fingerprint for `purpose` (different purposes never share a value).
    pub fn new(purpose: &str) -> Self {
        let mut h = blake3::Hasher::new();
        h.update(purpose.as_bytes());
        Self(h)
    }

    /// Adds `label = value`.
    pub fn value(&mut self, label: &str, value: impl Display) -> &mut Self {
        // Length-prefixed, so that no two different sequences of parts hash alike.
        let text = format!("{label}={value}");
        self.0.update(&(text.len() as u64).to_le_bytes());
        self.0.update(text.as_bytes());
        self
    }

    /// Adds the path and the contents of a file.
    pub fn file(&mut self, path: &Path) -> Result<&mut Self> {
        let label = format!("file {}", path.display());
        self.contents(&label, path)
    }

    /// Adds the contents of a file under `label`, not its path: a copy of the file elsewhere
    /// (another machine's checkout) adds the same.
    pub fn contents(&mut self, label: &str, path: &Path) -> Result<&mut Self> {
        let contents = blake3::Hasher::new()
            .update_reader(std::fs::File::open(path).map_err(|e| Error::io(path, e))?)
            .map_err(|e| Error::io(path, e))?
            .finalize();
        Ok(self.value(label, contents.to_hex()))
    }

    /// The fingerprint, as 32 hex digits.
    pub fn finish(&self) -> String {
        self.0.finalize().to_hex()[..32].to_string()
    }
}

/// This version of myriad and the git revision it was built from: what a render's parts
/// must share to merge (builds of one revision on different machines do).
pub fn revision() -> &'static str {
    concat!(env!("CARGO_PKG_VERSION"), " ", env!("MYRIAD_GIT_REVISION"))
}

/// This build of myriad: its version, the git revision it was built from (`unknown` outside a
/// checkout) and a hash of the running executable, which tells apart builds of one revision
/// with uncommitted changes.
pub fn build_id() -> &'static str {
    static ID: OnceLock<String> = OnceLock::new();
    ID.get_or_init(|| {
        let exe = std::env::current_exe()
            .ok()
            .and_then(|p| Fingerprint::new("myriad executable").file(&p).ok().map(|f| f.finish()))
            .unwrap_or_else(|| "unreadable".into());
        format!("{} {} {exe}", env!("CARGO_PKG_VERSION"), env!("MYRIAD_GIT_REVISION"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_part_changes_the_fingerprint() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.bin");
        std::fs::write(&path, b"one").unwrap();
        let of = |spp: u32| Fingerprint::new("t").value("spp", spp).file(&path).unwrap().finish();
        let a = of(4);
        assert_eq!(a, of(4));
        assert_ne!(a, of(5));
        std::fs::write(&path, b"two").unwrap();
        assert_ne!(a, of(4));
        assert_ne!(Fingerprint::new("t").value("ab", "c").finish(), Fingerprint::new("t").value("a", "bc").finish());
        assert!(build_id().contains(env!("CARGO_PKG_VERSION")));
    }
}
