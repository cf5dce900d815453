//! One force evaluation of a scene in both engines.

use crate::engine::StageDrivers;
use crate::lammps::{write_data_file, write_reference_lengths, write_templates, ScriptVars};
use crate::scene::{build_system, Scene};
use serde::Serialize;
use std::path::Path;
use std::process::Command;

/// Why a single point (or another `lmp-bpm` run) failed. Each message
/// carries its cause (not chained again, so it prints once).
#[derive(Debug, thiserror::Error)]
pub enum SinglePointError {
    /// A file could not be written or read.
    #[error("{action} {path}: {cause}")]
    File {
        /// "writing", "reading".
        action: &'static str,
        /// The file.
        path: String,
        /// The cause.
        cause: std::io::Error,
    },
    /// The embedded input templates could not be written.
    #[error("writing the LAMMPS input templates: {cause}")]
    Templates {
        /// The cause (names the file).
        cause: std::io::Error,
    },
    /// `lmp-bpm` could not be started.
    #[error("starting {program}: {cause}")]
    Start {
        /// The executable.
        program: String,
        /// The cause.
        cause: std::io::Error,
    },
    /// `lmp-bpm` ran and failed.
    #[error("lmp-bpm ({ranks} ranks) failed on {input}:\n{output}")]
    Lammps {
        /// MPI ranks.
        ranks: usize,
        /// The input script.
        input: String,
        /// Its screen output.
        output: String,
    },
    /// LAMMPS's output or dump lacks something or is malformed.
    #[error("{0}")]
    Output(String),
}

fn file_error(
    action: &'static str,
    path: &Path,
) -> impl FnOnce(std::io::Error) -> SinglePointError {
    let path = path.display().to_string();
    move |cause| SinglePointError::File {
        action,
        path,
        cause,
    }
}

/// Wall-clock limit of a single-point LAMMPS run (it takes about a second):
/// a hung LAMMPS (e.g. NaN positions) fails instead of stalling.
pub const CHECK_LIMIT_SECONDS: u32 = 120;

/// Forces, pressure tensor and energies of one evaluation.
#[derive(Clone, Debug, Serialize)]
pub struct SinglePoint {
    /// Per-particle forces, by particle index.
    pub forces: Vec<[f64; 3]>,
    /// Pressure tensor `[xx, yy, zz, xy, xz, yz]`.
    pub pressure: [f64; 6],
    /// `[bond, pair]` energies.
    pub energies: [f64; 2],
}

/// Runs `lmp_bpm` on the template `input` (an absolute path, or a name in
/// `lammps_inputs/`, run from the embedded copy written to `<dir>/inputs/`)
/// for `scene`, files in `dir` named after `tag`, on
/// `ranks` MPI ranks; `extra` adds `-var` pairs. Returns the output; a
/// LAMMPS error, a crash or `limit_seconds` without finishing is an error.
#[allow(clippy::too_many_arguments)]
pub fn run_lmp_bpm(
    lmp_bpm: &Path,
    scene: &Scene,
    input: &str,
    newton: bool,
    ranks: usize,
    dir: &Path,
    tag: &str,
    extra: &[(&str, String)],
    limit_seconds: u32,
) -> Result<String, SinglePointError> {
    let data = dir.join(format!("{tag}.data"));
    std::fs::write(&data, write_data_file(scene)).map_err(file_error("writing", &data))?;
    let r0 = Path::new(&format!("{}.r0", data.display())).to_path_buf();
    std::fs::write(&r0, write_reference_lengths(scene)).map_err(file_error("writing", &r0))?;
    let inputs = write_templates(dir).map_err(|cause| SinglePointError::Templates { cause })?;
    let vars = ScriptVars::of(scene, &data.display().to_string(), newton, &inputs);
    let input = if Path::new(input).is_absolute() {
        input.to_string()
    } else {
        inputs.join(input).display().to_string()
    };
    let mut cmd = limited_launch(limit_seconds, ranks);
    cmd.arg(lmp_bpm)
        .args(["-in", &input, "-log", "none"])
        .args(vars.args());
    for (k, v) in extra {
        cmd.args(["-var", k, v]);
    }
    let out = cmd.output().map_err(|cause| SinglePointError::Start {
        program: lmp_bpm.display().to_string(),
        cause,
    })?;
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    if !out.status.success() {
        return Err(SinglePointError::Lammps {
            ranks,
            input,
            output: text,
        });
    }
    Ok(text)
}

/// `timeout <limit> [mpirun.openmpi ... -np <ranks>]`, ready for the
/// program and its arguments: Debian's LAMMPS links Open MPI, so its
/// `mpirun` (not MPICH's, also installed) starts the ranks; as root, without
/// binding (two ranks on a shared two-core machine).
pub fn limited_launch(limit_seconds: u32, ranks: usize) -> Command {
    let mut cmd = Command::new("timeout");
    cmd.arg(limit_seconds.to_string());
    if ranks > 1 {
        cmd.args([
            "mpirun.openmpi",
            "--allow-run-as-root",
            "--oversubscribe",
            "--bind-to",
            "none",
            "-np",
            &ranks.to_string(),
        ]);
    }
    cmd.env("OMPI_MCA_btl_vader_single_copy_mechanism", "none");
    cmd
}

/// Rows of a LAMMPS custom dump sorted by id, without the id column.
pub fn read_dump(path: &Path) -> Result<Vec<Vec<f64>>, SinglePointError> {
    let text = std::fs::read_to_string(path).map_err(file_error("reading", path))?;
    text.lines()
        .skip_while(|l| !l.starts_with("ITEM: ATOMS"))
        .skip(1)
        .map(|line| {
            line.split_whitespace()
                .skip(1)
                .map(|t| {
                    t.parse::<f64>().map_err(|e| {
                        SinglePointError::Output(format!(
                            "bad number {t} in {}: {e}",
                            path.display()
                        ))
                    })
                })
                .collect()
        })
        .collect()
}

/// One evaluation through LAMMPS with our styles (`single_point.in`).
pub fn lammps_single_point(
    lmp_bpm: &Path,
    scene: &Scene,
    newton: bool,
    ranks: usize,
    dir: &Path,
    tag: &str,
) -> Result<SinglePoint, SinglePointError> {
    let dump = dir.join(format!("{tag}.dump"));
    let out = run_lmp_bpm(
        lmp_bpm,
        scene,
        "single_point.in",
        newton,
        ranks,
        dir,
        tag,
        &[("dump", dump.display().to_string())],
        CHECK_LIMIT_SECONDS,
    )?;
    let output = |m: String| SinglePointError::Output(m);
    let numbers = |key: &str| -> Result<Vec<f64>, SinglePointError> {
        let line = out
            .lines()
            .find(|l| l.starts_with(key))
            .ok_or_else(|| output(format!("no {key} line in the LAMMPS output")))?;
        line.split_whitespace()
            .skip(1)
            .map(|v| {
                v.parse::<f64>()
                    .map_err(|e| output(format!("bad {key} value {v}: {e}")))
            })
            .collect()
    };
    let p = numbers("BPM_PRESSURE")?;
    let e = numbers("BPM_ENERGY")?;
    if p.len() != 6 || e.len() != 2 {
        return Err(output("unexpected BPM_PRESSURE or BPM_ENERGY line".into()));
    }
    let forces: Vec<[f64; 3]> = read_dump(&dump)?
        .iter()
        .map(|v| [v[0], v[1], v[2]])
        .collect();
    if forces.len() != scene.particles.positions.len() {
        return Err(output(format!(
            "dump has {} atoms, scene {}",
            forces.len(),
            scene.particles.positions.len()
        )));
    }
    Ok(SinglePoint {
        forces,
        pressure: [p[0], p[1], p[2], p[3], p[4], p[5]],
        energies: [e[0], e[1]],
    })
}

/// One evaluation by the native engine.
pub fn native_single_point(scene: &Scene) -> SinglePoint {
    let mut sys = build_system(scene, 1);
    sys.setup(&StageDrivers {
        dt: 0.1,
        ..Default::default()
    });
    SinglePoint {
        forces: sys.particles.f.clone(),
        pressure: sys.pressure_tensor(),
        energies: [
            sys.report.interactions.terms[crate::engine::bpm::BOND_TERM].energy,
            sys.report.interactions.terms[crate::engine::bpm::PAIR_TERM].energy,
        ],
    }
}

/// Largest component difference of the rows `a` and `b` (forces: `N = 3`,
/// a pressure tensor: one row of `N = 6`), relative to the largest
/// component of `b`. A NaN anywhere makes the result NaN, which fails every
/// tolerance.
pub fn max_relative_deviation<const N: usize>(a: &[[f64; N]], b: &[[f64; N]]) -> f64 {
    let scale = b.iter().flatten().map(|v| v.abs()).fold(0.0, nan_max);
    let dev = a
        .iter()
        .zip(b)
        .flat_map(|(p, q)| p.iter().zip(q).map(|(x, y)| (x - y).abs()))
        .fold(0.0, nan_max);
    dev / scale
}

/// The larger of `m` and `v`, where NaN wins (`f64::max` would drop it).
pub fn nan_max(m: f64, v: f64) -> f64 {
    if v.is_nan() || v > m {
        v
    } else {
        m
    }
}
