//! The library's error type: every failure a user can cause, with where it happened.

use std::path::PathBuf;

/// What went wrong, and where.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file (or folder) the operation was on.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        source: std::io::Error,
    },
    /// A scene is malformed or inconsistent. `location` is `line:col` for syntax errors, or
    /// the object (`objects[3] Box`, `material 'red'`, `mesh 2 primitive 0`) otherwise.
    #[error("{file}: {location}: {message}")]
    Scene {
        /// The scene file.
        file: String,
        /// Where in it.
        location: String,
        /// What is wrong, and when possible how to fix it.
        message: String,
    },
    /// An output file could not be produced (nothing was written in its place).
    #[error("{}: {message}", path.display())]
    Output {
        /// The output path.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// An input file (image, reference) is unreadable or unsuitable.
    #[error("{}: {message}", path.display())]
    Input {
        /// The input file that was refused.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// An option has a value that cannot work.
    #[error("{0}")]
    Usage(String),
    /// The user stopped the work (Ctrl-C, SIGTERM) before anything was written.
    #[error("interrupted: nothing was written, and earlier outputs are as they were")]
    Interrupted,
}

impl Error {
    /// Shorthand for [`Error::Scene`].
    pub fn scene(file: impl Into<String>, location: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Scene { file: file.into(), location: location.into(), message: message.into() }
    }

    /// Shorthand for [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
