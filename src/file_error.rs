//! The error of a file or folder operation, shared by the studies and the
//! harness.

use std::path::Path;

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
