//! Everything that touches files: scene loaders, image writers and readers.
//!
//! Owns: choosing a loader by extension ([`load_scene`]), the RON, OBJ and glTF loaders, EXR
//! and PNG output, and [`write_atomically`], which every output goes through so that a crash,
//! a full disk or Ctrl-C never leaves a truncated file (write a temporary file beside the
//! target, then rename it over).

pub mod environment;
pub mod exr;
pub mod gltf;
pub mod image_file;
pub mod obj;
pub mod part;
pub mod png;
pub mod ron;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::{Error, Result};
use crate::scene::SceneDescription;

/// Choices made when reading scene files.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadOptions {
    /// The glTF scene to load (default: the file's default scene, else its first).
    pub gltf_scene: Option<usize>,
    /// Factor from glTF punctual light units (cd, lux) to radiometric ones (W/sr, W/m²):
    /// 1/683 for files written with 683 lm/W, as Blender's exporter does in its default
    /// "Standard" lighting mode; 1 for files whose intensities are already radiometric.
    pub punctual_scale: f32,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self { gltf_scene: None, punctual_scale: 1.0 / 683.0 }
    }
}

/// Loads a scene file, choosing the loader by extension (`.ron`, `.obj`, `.gltf`, `.glb`).
/// A dependency's panic on a file becomes an error naming it ([`crate::guard`]).
pub fn load_scene(path: &Path, options: &LoadOptions) -> Result<SceneDescription> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
    let file = path.display().to_string();
    crate::guard::contain(&file, || match ext.as_str() {
        "ron" => ron::load(path, options),
        "obj" => obj::load_scene(path),
        "gltf" | "glb" => gltf::load(path, options),
        _ => Err(Error::scene(
            &file,
            "file name",
            format!("unknown scene format '.{ext}'; myriad reads .ron, .obj, .gltf and .glb scenes"),
        )),
    })
}

/// `text` without a leading UTF-8 byte-order mark, which some editors write.
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// The temporary path an output is written to before being renamed to `path`.
fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.myriad-tmp-{}", std::process::id()))
}

/// Whether outputs may replace read-only files (`--force`).
static REPLACE_READ_ONLY: AtomicBool = AtomicBool::new(false);

/// Lets outputs replace read-only files for the rest of the process (`--force`), or not.
pub fn replace_read_only(yes: bool) {
    REPLACE_READ_ONLY.store(yes, Ordering::Relaxed);
}

/// An error when `path` is an existing read-only file and `--force` was not given: someone
/// made it read-only to keep it, so it is not replaced behind their back (a rename would).
fn check_not_read_only(path: &Path) -> Result<()> {
    let read_only = std::fs::metadata(path).is_ok_and(|m| m.is_file() && m.permissions().readonly());
    if read_only && !REPLACE_READ_ONLY.load(Ordering::Relaxed) {
        return Err(Error::Output {
            path: path.into(),
            message: "exists and is read-only; myriad does not replace it: make it writable (chmod u+w), write \
                      elsewhere, or pass --force"
                .into(),
        });
    }
    Ok(())
}

/// Checks, before a long render, that `path` can be written: its folder exists and accepts a
/// new file, and it is not a read-only file. Nothing is left behind.
pub fn check_writable(path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(Error::Output { path: path.into(), message: "is a directory; give a file name".into() });
    }
    check_not_read_only(path)?;
    let tmp = temp_path(path);
    std::fs::File::create(&tmp)
        .map_err(|e| Error::Output { path: path.into(), message: format!("cannot be written: {e}") })?;
    let _ = std::fs::remove_file(&tmp);
    Ok(())
}

/// Writes `path` whole or not at all: `write` fills a temporary file beside it, which then
/// replaces `path` by a rename; a read-only `path` is refused unless `--force`. On any
/// error, or when the user has asked to stop at once ([`crate::interrupt`]), the temporary
/// file is removed and `path` is left as it was.
pub fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    check_not_read_only(path)?;
    let tmp = temp_path(path);
    let _busy = crate::interrupt::busy();
    let result = write(&tmp).and_then(|()| {
        if crate::interrupt::requested() == crate::interrupt::Stop::Now {
            return Err(Error::Interrupted);
        }
        std::fs::rename(&tmp, path)
            .map_err(|e| Error::Output { path: path.into(), message: format!("cannot be replaced: {e}") })
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Writes `text` to `path` atomically.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    write_atomically(path, |tmp| std::fs::write(tmp, text).map_err(|e| Error::io(path, e)))
}

/// Creates `dir` (and its parents) if it does not exist.
pub fn ensure_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .map_err(|e| Error::Output { path: dir.into(), message: format!("cannot create the folder: {e}") })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_the_old_file_and_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.txt");
        std::fs::write(&target, "old").unwrap();
        let err = write_atomically(&target, |tmp| {
            std::fs::write(tmp, "half").unwrap();
            Err(Error::Usage("boom".into()))
        });
        assert!(err.is_err());
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        write_atomically(&target, |tmp| std::fs::write(tmp, "new").map_err(|e| Error::io(tmp, e))).unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
    }

    #[test]
    fn unwritable_targets_are_refused_up_front() {
        let dir = tempfile::tempdir().unwrap();
        assert!(check_writable(&dir.path().join("no/such/dir/x.exr")).is_err());
        assert!(check_writable(dir.path()).is_err());
        assert!(check_writable(&dir.path().join("x.exr")).is_ok());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
