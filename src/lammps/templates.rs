//! The LAMMPS input templates of `lammps_inputs/`, compiled into the
//! binary, so an installed `bpm` (`cargo install`) never reads the source
//! tree. Each run writes them into its own work folder
//! ([`write_templates`]) and points `${inputs}` at that copy; the files in
//! `lammps_inputs/` stay the readable originals for LAMMPS users.
//! `tests/templates.rs` fails when a file there is missing from
//! [`TEMPLATES`].

use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

macro_rules! templates {
    ($($name:literal),* $(,)?) => {
        /// Every file of `lammps_inputs/`: its path relative to that folder
        /// (`/`-separated) and its text.
        pub const TEMPLATES: &[(&str, &str)] = &[
            $(($name, include_str!(concat!("../../lammps_inputs/", $name))),)*
        ];
    };
}

templates![
    "bench_bonds.in",
    "bond_pull/pull.in",
    "block_tension/block.in",
    "block_tension/tension.in",
    "impact/impact.in",
    "compaction.in",
    "hertz_squeeze.in",
    "plugin_load_example.in",
    "restart_read.in",
    "restart_write.in",
    "granular_wall.in",
    "bpm_granular_wall.in",
    "setup.in",
    "setup_dem.in",
    "single_point.in",
    "single_point_dem.in",
    "stage_barostat.in",
    "stage_begin.in",
    "stage_compress.in",
    "stage_end.in",
    "stage_hold.in",
    "stage_record.in",
    "stage_shear.in",
    "stage_shear_end.in",
    "tether.in",
    "wall.in",
    "upstream_compare/README.md",
    "upstream_compare/ours.in",
    "upstream_compare/tail.in",
    "upstream_compare/upstream.in",
];

/// Name of the folder [`write_templates`] creates in a work folder.
pub const FOLDER: &str = "inputs";

/// The text of the template `name` (e.g. `"setup.in"`,
/// `"upstream_compare/ours.in"`).
pub fn template(name: &str) -> Option<&'static str> {
    TEMPLATES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

/// Writes every template into `<dir>/inputs/` (creating it) and returns
/// that folder as an absolute path: the value of `${inputs}`.
///
/// Files that already hold the same text are left alone; others are
/// replaced atomically (write a temporary file, then rename), so runs that
/// share a work folder, or the ranks of one MPI run, never read a
/// half-written template.
pub fn write_templates(dir: &Path) -> io::Result<PathBuf> {
    static UNIQUE: AtomicU64 = AtomicU64::new(0);
    let folder = std::path::absolute(dir.join(FOLDER))?;
    let context =
        |path: &Path, e: io::Error| io::Error::new(e.kind(), format!("{}: {e}", path.display()));
    for (name, text) in TEMPLATES {
        let path = folder.join(name);
        if std::fs::read(&path).is_ok_and(|old| old == text.as_bytes()) {
            continue;
        }
        let parent = path.parent().unwrap_or(&folder);
        std::fs::create_dir_all(parent).map_err(|e| context(parent, e))?;
        let tmp = path.with_file_name(format!(
            ".{}.{}-{}.tmp",
            path.file_name().unwrap_or_default().to_string_lossy(),
            std::process::id(),
            UNIQUE.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::write(&tmp, text).map_err(|e| context(&tmp, e))?;
        std::fs::rename(&tmp, &path).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            context(&path, e)
        })?;
    }
    Ok(folder)
}
