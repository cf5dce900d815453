//! Errors of file and folder operations and of the text formats read
//! here (LAMMPS data files, dumps), shared by the scene, the studies and
//! the harness.

use std::path::{Path, PathBuf};

/// A file or folder could not be created, written or read. The message
/// carries the cause once (it is not also chained as a source).
#[derive(Debug, thiserror::Error)]
#[error("{action} {path}: {cause}")]
pub struct FileError {
    /// "creating", "writing", "reading".
    pub action: &'static str,
    /// The file or folder.
    pub path: String,
    /// The cause.
    pub cause: std::io::Error,
}

impl FileError {
    /// A `map_err` adapter: `fs::write(p, t).map_err(FileError::on("writing", p))`.
    pub fn on(action: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> FileError {
        let path = path.display().to_string();
        move |cause| FileError {
            action,
            path,
            cause,
        }
    }
}

/// A text file of a known format (LAMMPS data file, dump, thermo file)
/// that could not be read, written or parsed.
#[derive(Debug, thiserror::Error)]
pub enum TextFileError {
    /// The file could not be created, written or read.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause (in the message, not chained, so it prints once).
        cause: std::io::Error,
    },
    /// The file does not follow the format.
    #[error("{path}, line {line}: {reason}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// Line number, from 1 (0: the file as a whole).
        line: usize,
        /// What is wrong.
        reason: String,
    },
}
