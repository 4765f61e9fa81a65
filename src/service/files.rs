//! What can be wrong with the daemon's own files, checkpoints and journals: which file, and
//! whether the OS refused it or its contents are not usable.

use std::path::{Path, PathBuf};

/// A checkpoint or journal file that cannot be read, written or used.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// It could not be read (or written).
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// Not the kind of file expected, a different format version, truncated, or damaged.
    #[error("{}: {reason}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

impl FileError {
    /// An [`FileError::Io`] about `path`, for `map_err`.
    pub(crate) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> FileError + '_ {
        move |source| FileError::Io {
            path: path.to_owned(),
            source,
        }
    }

    /// An [`FileError::Invalid`] about `path`, for `map_err`.
    pub(crate) fn invalid(path: &Path) -> impl FnOnce(String) -> FileError + '_ {
        move |reason| FileError::Invalid {
            path: path.to_owned(),
            reason,
        }
    }
}
