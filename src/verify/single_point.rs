//! One force evaluation of a scene in both engines.

use super::launch::{LammpsChild, LaunchError, Work};
use crate::engine::StageDrivers;
use crate::file_error::FileError;
use crate::lammps::{write_reference_lengths, write_run_data_file, write_templates, ScriptVars};
use crate::scene::{build_system, ModelKind, Scene};
use serde::Serialize;
use std::path::Path;

/// Why a single point (or another `lmp-bpm` run) failed. Each message
/// carries its cause (not chained again, so it prints once).
#[derive(Debug, thiserror::Error)]
pub enum SinglePointError {
    /// A file or folder could not be created, written or read.
    #[error(transparent)]
    File(#[from] FileError),
    /// The embedded input templates could not be written.
    #[error("writing the LAMMPS input templates: {cause}")]
    Templates {
        /// The cause (names the file).
        cause: std::io::Error,
    },
    /// `lmp-bpm` could not be started, or failed.
    #[error(transparent)]
    Launch(#[from] LaunchError),
    /// LAMMPS's output or dump lacks something or is malformed.
    #[error("{0}")]
    Output(String),
}

/// Forces, torques, pressure tensor and energies of one evaluation.
#[derive(Clone, Debug, Serialize)]
pub struct SinglePoint {
    /// Per-particle forces, by particle index.
    pub forces: Vec<[f64; 3]>,
    /// Per-particle torques of rotating particles (DEM); empty otherwise.
    pub torques: Vec<[f64; 3]>,
    /// Pressure tensor `[xx, yy, zz, xy, xz, yz]`.
    pub pressure: [f64; 6],
    /// `[bond, pair]` energies (zero for DEM, which has none).
    pub energies: [f64; 2],
}

/// Runs `lmp_bpm` on the template `input` (an absolute path, or a name in
/// `lammps_inputs/`, run from the embedded copy written to `<dir>/inputs/`)
/// for `scene`, files in `dir` named after `tag`, on
/// `ranks` MPI ranks; `extra` adds `-var` pairs; `steps` is what the input
/// runs in all (with the scene's particles, it sets the time limit:
/// [`Work::time_limit`]). Returns the screen output; a LAMMPS error, a crash
/// or no result within the time limit is an error.
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
    steps: u64,
) -> Result<String, SinglePointError> {
    let data = dir.join(format!("{tag}.data"));
    std::fs::write(&data, write_run_data_file(scene)).map_err(FileError::on("writing", &data))?;
    if scene.model == ModelKind::Bpm {
        let r0 = Path::new(&format!("{}.r0", data.display())).to_path_buf();
        std::fs::write(&r0, write_reference_lengths(scene))
            .map_err(FileError::on("writing", &r0))?;
    }
    let inputs = write_templates(dir).map_err(|cause| SinglePointError::Templates { cause })?;
    let vars = ScriptVars::of(scene, &data.display().to_string(), newton, &inputs);
    let input = if Path::new(input).is_absolute() {
        input.to_string()
    } else {
        inputs.join(input).display().to_string()
    };
    let mut args: Vec<String> = vec!["-in".into(), input.clone(), "-log".into(), "none".into()];
    args.extend(vars.args());
    for (k, v) in extra {
        args.extend(["-var".to_string(), k.to_string(), v.clone()]);
    }
    Ok(
        LammpsChild::debian(lmp_bpm).run(
            &input,
            args,
            ranks,
            Work::steps_of(scene, steps),
            None,
        )?,
    )
}

/// Rows of a LAMMPS custom dump sorted by id, without the id column.
pub fn read_dump(path: &Path) -> Result<Vec<Vec<f64>>, SinglePointError> {
    let text = std::fs::read_to_string(path).map_err(FileError::on("reading", path))?;
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

/// One evaluation through LAMMPS: with our styles for the bonded particle
/// model (`single_point.in`), with LAMMPS's `pair_style granular` for DEM
/// spheres (`single_point_dem.in`, which also dumps torques).
pub fn lammps_single_point(
    lmp_bpm: &Path,
    scene: &Scene,
    newton: bool,
    ranks: usize,
    dir: &Path,
    tag: &str,
) -> Result<SinglePoint, SinglePointError> {
    let dump = dir.join(format!("{tag}.dump"));
    let dem = scene.model == ModelKind::Dem;
    if scene
        .force_field
        .granular
        .is_some_and(|m| m.damping == crate::kernels::NormalDamping::CoeffRestitution)
    {
        return Err(SinglePointError::Output(
            "the restitution form of the DEM damping has no LAMMPS 29Sep2021 counterpart (only `damping tsuji`)".into(),
        ));
    }
    let out = run_lmp_bpm(
        lmp_bpm,
        scene,
        if dem {
            "single_point_dem.in"
        } else {
            "single_point.in"
        },
        newton,
        ranks,
        dir,
        tag,
        &[("dump", dump.display().to_string())],
        0,
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
    let e = if dem {
        vec![0.0; 2]
    } else {
        numbers("BPM_ENERGY")?
    };
    if p.len() != 6 || e.len() != 2 {
        return Err(output("unexpected BPM_PRESSURE or BPM_ENERGY line".into()));
    }
    let rows = read_dump(&dump)?;
    let width = if dem { 6 } else { 3 };
    if rows.len() != scene.particles.positions.len() || rows.iter().any(|r| r.len() != width) {
        return Err(output(format!(
            "dump has {} atoms with {:?} values, scene {} atoms with {width}",
            rows.len(),
            rows.first().map(Vec::len),
            scene.particles.positions.len()
        )));
    }
    Ok(SinglePoint {
        forces: rows.iter().map(|v| [v[0], v[1], v[2]]).collect(),
        torques: if dem {
            rows.iter().map(|v| [v[3], v[4], v[5]]).collect()
        } else {
            Vec::new()
        },
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
    })
    .expect("a stage without granular walls sets up on any model");
    let terms = &sys.report.interactions.terms;
    SinglePoint {
        forces: sys.particles.f.clone(),
        torques: sys
            .particles
            .rotation
            .as_ref()
            .map_or_else(Vec::new, |r| r.torque.clone()),
        pressure: sys.pressure_tensor(),
        energies: if scene.model == ModelKind::Bpm {
            [
                terms[crate::engine::bpm::BOND_TERM].energy,
                terms[crate::engine::bpm::PAIR_TERM].energy,
            ]
        } else {
            [0.0; 2]
        },
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
