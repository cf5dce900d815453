//! Files written whole: into a temporary file beside the target, then
//! renamed over it, so a failure (a full disk, a kill) leaves the earlier
//! complete file, never half of one. Results, plots and reports are
//! written this way; the rename replaces the target (a symbolic link
//! itself, not what it points to), and it is atomic but not synced to the
//! disk (a power loss may lose the newest file, not mix two).

use crate::file_error::FileError;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Writes `bytes` to `path` whole. A target that exists and is not a
/// regular file (a device, a pipe: `-o /dev/stdout`) is written directly,
/// since no file can be renamed over it.
pub fn write_whole(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    if path.exists() && !path.is_file() {
        return std::fs::write(path, bytes).map_err(FileError::on("writing", path));
    }
    // Unique within the process too: two threads may write beside each other.
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let temporary = path.with_file_name(format!(
        ".{name}.{}-{}.tmp",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    let written =
        std::fs::write(&temporary, bytes).and_then(|()| std::fs::rename(&temporary, path));
    written.map_err(|cause| {
        let _ = std::fs::remove_file(&temporary);
        FileError::on("writing", path)(cause)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_keeps_the_earlier_file_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("bpm-whole-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("table.txt");
        write_whole(&path, b"complete\n").unwrap();
        write_whole(&path, b"replaced\n").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "replaced\n");
        // A folder in the target's place: the rename fails, the error names
        // the target, and the temporary file is removed.
        let blocked = dir.join("blocked");
        std::fs::create_dir_all(blocked.join("inside")).unwrap();
        let err = write_whole(&blocked, b"half").unwrap_err();
        assert!(err.to_string().contains("blocked"), "{err}");
        assert!(!err.to_string().contains(".tmp"), "{err}");
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "replaced\n");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_device_is_written_directly() {
        write_whole(Path::new("/dev/null"), b"nothing").unwrap();
    }
}
