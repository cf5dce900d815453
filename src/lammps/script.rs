//! A scene as a LAMMPS driver script: `setup.in`, then per stage the force
//! field changes, velocity settings, one protocol template
//! (`lammps_inputs/stage_<protocol>.in`) with its variables, walls
//! (`wall.in`) and tether (`tether.in`), `stage_record.in`, the run and
//! `stage_end.in`.
//!
//! The script written to disk is exactly what the in-process harness
//! executes, so `lmp-bpm -in <tag>.in` repeats a harness run by hand. The
//! harness handles the `run` lines itself (in chunks at position
//! checkpoints) and reads the recorded rows back after each.

use super::datafile::{
    dem_pair_coeff, granular_wall_model, type_masses, uses_closure, write_reference_lengths,
    write_run_data_file, yes_no, ScriptVars,
};
use super::templates::{write_templates, FOLDER as TEMPLATE_FOLDER};
use crate::engine::{ActiveGranularWall, Deformation, ShearRemap, TiltFactor, WallSide};
use crate::kernels::{GranularMaterial, NormalDamping};
use crate::scene::observables::{
    closure_columns, energy_terms, lammps_energy_compute, rotates, stage_columns, Column,
    LAMMPS_CLOSURE_COMPUTE,
};
use crate::scene::run::{random_velocities, stage_seed};
use crate::scene::{ForceField, ModelKind, Scene, StageSpec};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Why a scene cannot be run through LAMMPS.
#[derive(Debug, thiserror::Error)]
pub enum ScriptError {
    /// A stage uses something the LAMMPS templates do not express yet.
    #[error("stage {index} (`{name}`) uses {what}, which the LAMMPS harness does not support yet; run it on the native engine")]
    Unsupported {
        /// Stage index.
        index: usize,
        /// Stage name.
        name: String,
        /// The feature.
        what: &'static str,
    },
    /// Writing an input file failed.
    #[error("writing {path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause (in the message, not chained, so it prints once).
        cause: std::io::Error,
    },
}

/// One line of the driver: a LAMMPS command, or the run of a stage.
#[derive(Clone, Debug)]
pub enum DriverLine {
    /// Passed to LAMMPS as is.
    Command(String),
    /// `run <steps>` of stage `stage`.
    Run {
        /// Stage index.
        stage: usize,
    },
}

/// What the harness needs to know about a stage to run and read it.
#[derive(Clone, Debug)]
pub struct StagePlan {
    /// Stage name.
    pub name: String,
    /// Steps.
    pub steps: u64,
    /// Time step.
    pub dt: f64,
    /// Steps between recorded rows (0 = none).
    pub every: u64,
    /// Steps between position checkpoints (0 = none).
    pub positions_every: u64,
    /// The recorded columns; those with a LAMMPS expression are the
    /// values of `fix bpm_record`, in order.
    pub columns: Vec<Column>,
}

/// The driver script of a scene and the plan of its stages.
#[derive(Clone, Debug)]
pub struct Driver {
    /// Lines in order.
    pub lines: Vec<DriverLine>,
    /// One plan per stage.
    pub stages: Vec<StagePlan>,
}

impl Driver {
    /// The script as LAMMPS input text.
    pub fn text(&self) -> String {
        self.lines
            .iter()
            .map(|l| match l {
                DriverLine::Command(c) => c.clone(),
                DriverLine::Run { stage } => {
                    format!("run             {}", self.stages[*stage].steps)
                }
            })
            .collect::<Vec<_>>()
            .join("\n")
            + "\n"
    }
}

/// LAMMPS variable that records column `name`.
fn record_variable(name: &str) -> String {
    format!("bpm_rec_{name}")
}

/// The `fix bpm_record` inputs of a stage's columns: one equal-style
/// variable per column LAMMPS records (`fix vector` takes only intensive
/// or only extensive values, and variables are intensive), and the list.
fn record_commands(columns: &[Column]) -> Vec<String> {
    let mut c = Vec::new();
    let mut names = Vec::new();
    for col in columns {
        if let Some(expr) = &col.lammps {
            let var = record_variable(&col.name);
            c.push(format!("variable        {var} equal {expr}"));
            names.push(format!("v_{var}"));
        }
    }
    c.push(format!(
        "variable        recorded string \"{}\"",
        names.join(" ")
    ));
    c
}

pub use crate::scene::datafile::needs_triclinic;

fn check_supported(index: usize, stage: &StageSpec, scene: &Scene) -> Result<(), ScriptError> {
    let unsupported = |what| ScriptError::Unsupported {
        index,
        name: stage.name.clone(),
        what,
    };
    // LAMMPS's fix wall/region stops at particles beyond the surface and
    // reports a force vector, not the summed magnitude the native engine
    // records.
    if stage.sphere_wall.is_some() {
        return Err(unsupported("a spherical wall"));
    }
    if scene
        .bonds
        .plastic_strain
        .as_ref()
        .is_some_and(|e| e.iter().any(|&e| e != 0.0))
    {
        return Err(unsupported(
            "bonds with plastic strains (`bonds.plastic_strain`): the harness's LAMMPS runs take only reference lengths",
        ));
    }
    let overlaid = |ff: &ForceField| ff.overlay_pair;
    if overlaid(&scene.force_field) || stage.force_field.as_ref().is_some_and(overlaid) {
        return Err(unsupported(
            "contacts overlaid on bonds (`overlay_pair`): the harness's LAMMPS runs exclude bonded pairs from contact (`special_bonds lj 0 1 1`)",
        ));
    }
    let fails = |ff: &ForceField| ff.bond_failure.is_some_and(|f| f.is_live());
    if fails(&scene.force_field) || stage.force_field.as_ref().is_some_and(fails) {
        return Err(unsupported(
            "bonds that break or yield (`bond_failure`): the harness's LAMMPS runs use the elastic `bpm/multibody`",
        ));
    }
    if stage.barostat.is_some() {
        if !scene.simbox.periodic.iter().all(|&p| p) {
            return Err(unsupported(
                "a barostat in a box that is not periodic in every dimension (fix press/berendsen iso scales all three)",
            ));
        }
        if needs_triclinic(scene) {
            return Err(unsupported(
                "a barostat in a triclinic box (fix press/berendsen needs an orthogonal one)",
            ));
        }
    }
    let dem = scene.model == ModelKind::Dem;
    let restitution_form = |ff: &ForceField| {
        ff.granular
            .is_some_and(|m| m.damping == NormalDamping::CoeffRestitution)
    };
    let closure = uses_closure(scene);
    // LAMMPS's own granular walls are defined anew each stage; the
    // plugin's (with the closure) can keep their springs.
    if !closure && stage.granular_walls.iter().any(|w| w.keep_history) {
        return Err(unsupported(
            "granular walls that keep their friction springs across stages (`keep_history`) with plain Hertz contacts: LAMMPS's fix wall/gran/region is defined anew each stage (with the multi-contact closure the plugin's walls keep them)",
        ));
    }
    // The plugin's pair style and walls have the restitution form;
    // LAMMPS's do not.
    if !closure
        && (restitution_form(&scene.force_field)
            || stage.force_field.as_ref().is_some_and(restitution_form)
            || stage
                .granular_walls
                .iter()
                .any(|w| w.material.damping == NormalDamping::CoeffRestitution))
    {
        return Err(unsupported(
            "the restitution form of the DEM damping (LAMMPS 29Sep2021 has only `damping tsuji`)",
        ));
    }
    if !dem && type_masses(scene).is_none() {
        return Err(unsupported(
            "masses that differ within a particle type (LAMMPS's atom_style bond has one mass per type)",
        ));
    }
    if matches!(stage.deformation, Some(Deformation::Isotropic { .. }))
        && !scene.simbox.periodic.iter().all(|&p| p)
    {
        return Err(unsupported(
            "isotropic deformation of a box that is not periodic in every dimension",
        ));
    }
    Ok(())
}

fn g(v: f64) -> String {
    format!("{v:.17e}")
}

fn write(path: &Path, text: &str) -> Result<(), ScriptError> {
    std::fs::write(path, text).map_err(|cause| ScriptError::Io {
        path: path.to_path_buf(),
        cause,
    })
}

/// A native dump of velocities, read by `read_dump ... vx vy vz`.
fn velocity_dump(v: &[[f64; 3]]) -> String {
    let mut s = format!(
        "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n{}\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 1\n0 1\nITEM: ATOMS id vx vy vz\n",
        v.len()
    );
    for (i, v) in v.iter().enumerate() {
        let _ = writeln!(s, "{} {} {} {}", i + 1, g(v[0]), g(v[1]), g(v[2]));
    }
    s
}

/// The commands of a stage's force field; `closure_style`: the scene runs
/// with `pair_style bpm/granular` ([`uses_closure`]).
fn force_field_commands(ff: &ForceField, closure_style: bool) -> Vec<String> {
    if let Some(material) = &ff.granular {
        return vec![
            format!(
                "pair_coeff      * * {}",
                dem_pair_coeff(material, ff.multicontact.as_ref(), closure_style)
            ),
            format!("neighbor        {} bin", g(ff.skin)),
        ];
    }
    let pair = ff.pair.unwrap_or(crate::kernels::PairCoeffs {
        k: 0.0,
        d: 1.0,
        a: 0.0,
        gamma: 0.0,
    });
    vec![
        format!(
            "bond_style      bpm/multibody zero_net {}",
            yes_no(ff.zero_net_multibody)
        ),
        format!(
            "bond_coeff      1 {} {} {}",
            g(ff.bond.k),
            g(ff.bond.a),
            g(ff.bond.gamma)
        ),
        format!(
            "pair_coeff      * * {} {} {} {}",
            g(pair.k),
            g(pair.d),
            g(pair.a),
            g(pair.gamma)
        ),
        format!("neighbor        {} bin", g(ff.skin)),
    ]
}

/// Commands that set up a stage's walls and tether (after its template, so
/// after `reset_timestep`) and remove them after its run.
struct ExternalCommands {
    /// Before the template: what `stage_record.in` names.
    variables: Vec<String>,
    begin: Vec<String>,
    end: Vec<String>,
}

/// With `closure`, granular walls are `fix bpm/granular/wall`
/// (`bpm_granular_wall.in`), contacts of the plugin's pair style;
/// otherwise LAMMPS's `fix wall/gran/region` (`granular_wall.in`).
fn external_commands(
    stage: &StageSpec,
    spheres: Option<&GranularMaterial>,
    closure: bool,
    gravity: Option<[f64; 3]>,
) -> ExternalCommands {
    let mut begin = Vec::new();
    let mut end = Vec::new();
    let mut energies = vec!["0".to_string()];
    for (w, wall) in stage.walls.iter().enumerate() {
        let (face, sign) = match wall.side {
            WallSide::Lo => ("lo", -1),
            WallSide::Hi => ("hi", 1),
        };
        let axis = ["x", "y", "z"][wall.axis.min(2)];
        for (name, value) in [
            ("wall", w.to_string()),
            ("face", format!("{axis}{face}")),
            ("wall_start", g(wall.position)),
            ("wall_velocity", g(wall.velocity)),
            ("wall_k", g(wall.stiffness)),
            ("wall_cutoff", g(wall.cutoff)),
            ("wall_sign", sign.to_string()),
        ] {
            begin.push(format!("variable        {name} string {value}"));
        }
        begin.push("include         ${inputs}/wall.in".into());
        end.push(format!("unfix           bpm_wall{w}"));
        energies.push(format!("v_bpm_wall{w}_energy"));
    }
    for (w, wall) in stage.granular_walls.iter().enumerate() {
        let Some(spheres) = spheres else { break };
        if closure {
            let axis = ["x", "y", "z"][wall.axis.min(2)];
            let side = match wall.side {
                WallSide::Lo => "lo",
                WallSide::Hi => "hi",
            };
            for (name, value) in [
                ("wall", w.to_string()),
                // The wall's contacts are kept under its number: the same
                // place in the list each stage keeps its load.
                ("wall_number", (w + 1).to_string()),
                ("axis", axis.to_string()),
                ("side", side.to_string()),
                ("wall_start", g(wall.position)),
                ("wall_velocity", g(wall.velocity)),
                (
                    "wall_material",
                    format!(
                        "{}{}",
                        if wall.keep_history {
                            "keep_history "
                        } else {
                            ""
                        },
                        dem_pair_coeff(&wall.material, None, true)
                    ),
                ),
            ] {
                begin.push(format!("variable        {name} string \"{value}\""));
            }
            begin.push("include         ${inputs}/bpm_granular_wall.in".into());
            end.push(format!("unfix           bpm_gwall{w}"));
            continue;
        }
        let c = ActiveGranularWall::new(wall, spheres);
        let (sign, normal) = match wall.side {
            WallSide::Lo => (1, 1.0),
            WallSide::Hi => (-1, -1.0),
        };
        let axis = ["x", "y", "z"][wall.axis.min(2)];
        let along = |value: String, other: &str| {
            let mut v = [other.to_string(), other.to_string(), other.to_string()];
            v[wall.axis.min(2)] = value;
            v.join(" ")
        };
        for (name, value) in [
            ("wall", w.to_string()),
            ("axis", axis.to_string()),
            ("axis_column", (wall.axis + 1).to_string()),
            ("wall_start", g(wall.position)),
            ("wall_velocity", g(wall.velocity)),
            ("wall_sign", sign.to_string()),
            ("point", along(g(wall.position), "0")),
            ("normal", along(format!("{normal}"), "0")),
            ("move", along(format!("v_bpm_gwall{w}_shift"), "NULL")),
            (
                "wall_model",
                granular_wall_model(c.coeffs(), &wall.material),
            ),
        ] {
            begin.push(format!("variable        {name} string \"{value}\""));
        }
        begin.push("include         ${inputs}/granular_wall.in".into());
        end.push(format!("unfix           bpm_gwall{w}"));
        end.push(format!("uncompute       bpm_gwall{w}_sum"));
        end.push(format!("region          bpm_gwall{w} delete"));
    }
    if let Some(t) = &stage.tether {
        begin.push(match t.grain {
            Some(g) => format!("group           bpm_tether molecule {}", g + 1),
            None => "group           bpm_tether type 1".into(),
        });
        for (d, name) in ["tether_x", "tether_y", "tether_z"].iter().enumerate() {
            let value = if !t.dims[d] {
                "NULL".to_string()
            } else if let Some(anchor) = t.anchor {
                g(anchor[d])
            } else {
                // The group's centre of mass now, at the stage start, as
                // the native engine anchors it.
                format!("$(xcm(bpm_tether,{}):%.17g)", ["x", "y", "z"][d])
            };
            begin.push(format!("variable        {name} string {value}"));
        }
        begin.push(format!(
            "variable        tether_k string {}",
            g(t.stiffness)
        ));
        begin.push("include         ${inputs}/tether.in".into());
        end.push("unfix           bpm_tether".into());
        end.push("group           bpm_tether delete".into());
        energies.push("v_bpm_tether_energy".into());
    }
    // Last, as the native engine adds gravity after the other terms. LAMMPS
    // takes a magnitude and a direction and multiplies them back, as
    // `Gravity::new` does.
    if let Some(a) = gravity {
        let magnitude = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        if magnitude > 0.0 {
            begin.push(format!(
                "fix             bpm_gravity all gravity {} vector {} {} {}",
                g(magnitude),
                g(a[0]),
                g(a[1]),
                g(a[2])
            ));
            end.push("unfix           bpm_gravity".into());
            energies.push("f_bpm_gravity".into());
        }
    }
    let variables = vec![format!(
        "variable        bpm_eext equal {}",
        energies.join("+")
    )];
    ExternalCommands {
        variables,
        begin,
        end,
    }
}

/// Writes the data file, reference lengths, velocity files and the driver
/// script `<dir>/<tag>.in` of `scene`, and the input templates into
/// `<dir>/inputs/` (`${inputs}` of the driver); returns the driver.
pub fn write_driver(
    scene: &Scene,
    dir: &Path,
    tag: &str,
    newton: bool,
) -> Result<Driver, ScriptError> {
    for (i, stage) in scene.stages.iter().enumerate() {
        check_supported(i, stage, scene)?;
    }
    // Absolute paths, so the script runs by hand from any folder.
    let dir = &dir.canonicalize().map_err(|cause| ScriptError::Io {
        path: dir.to_path_buf(),
        cause,
    })?;
    let inputs = write_templates(dir).map_err(|cause| ScriptError::Io {
        path: dir.join(TEMPLATE_FOLDER),
        cause,
    })?;
    let data = dir.join(format!("{tag}.data"));
    write(&data, &write_run_data_file(scene))?;
    let dem = scene.model == ModelKind::Dem;
    if !dem {
        write(
            Path::new(&format!("{}.r0", data.display())),
            &write_reference_lengths(scene),
        )?;
    }
    let mut lines = vec![DriverLine::Command(format!(
        "# Scene `{}` (seed {}) through LAMMPS with bpm's styles; written by bpm {}.\n# By hand: lmp-bpm -in {tag}.in [-var aB -0.8 ...] (any variable of setup.in)",
        scene.description.replace('\n', " "),
        scene.seed,
        crate::VERSION
    ))];
    let cmd = |lines: &mut Vec<DriverLine>, c: String| lines.push(DriverLine::Command(c));
    // Index style: a `-var name value` on the command line takes precedence,
    // so a hand run can change e.g. a_B without editing the script.
    for (name, value) in ScriptVars::of(scene, &data.display().to_string(), newton, &inputs).vars {
        cmd(
            &mut lines,
            format!("variable        {name} index \"{value}\""),
        );
    }
    let setup = if dem { "setup_dem.in" } else { "setup.in" };
    cmd(&mut lines, format!("include         ${{inputs}}/{setup}"));
    cmd(
        &mut lines,
        "# What the recorded columns measure (declared in src/scene/observables.rs)".into(),
    );
    for term in energy_terms(scene.model) {
        cmd(
            &mut lines,
            format!(
                "compute         {} all {}",
                lammps_energy_compute(term.column),
                term.lammps_compute
            ),
        );
    }
    cmd(&mut lines, "compute         bpm_ke all ke".into());
    if rotates(scene.model) {
        cmd(
            &mut lines,
            "compute         bpm_erotate all erotate/sphere".into(),
        );
    }
    let triclinic = needs_triclinic(scene);
    let n = scene.particles.positions.len();
    let mut stages = Vec::with_capacity(scene.stages.len());
    // The spheres' material in force at each stage (granular walls mix
    // theirs with it).
    let mut spheres = scene.force_field.granular.as_ref();
    // Whether the closure is on at each stage, as the native engine records
    // its columns.
    let mut closure_on = scene.force_field.multicontact.is_some();
    let mut gravity = scene.force_field.gravity;
    if uses_closure(scene) {
        cmd(
            &mut lines,
            format!("compute         {LAMMPS_CLOSURE_COMPUTE} all pair bpm/granular"),
        );
    }
    for (i, stage) in scene.stages.iter().enumerate() {
        cmd(
            &mut lines,
            format!("\n# Stage {i} `{}`: {} steps", stage.name, stage.steps),
        );
        if let Some(ff) = &stage.force_field {
            for c in force_field_commands(ff, uses_closure(scene)) {
                cmd(&mut lines, c);
            }
        }
        if stage.reset_reference {
            cmd(&mut lines, "fix_modify      BPM_REFERENCE reset".into());
        }
        if stage.zero_velocities {
            cmd(&mut lines, "velocity        all set 0 0 0".into());
            if rotates(scene.model) {
                cmd(&mut lines, "set             group all omega 0 0 0".into());
            }
        }
        if let Some(init) = &stage.set_velocities {
            let file = dir.join(format!("{tag}.stage{i}.velocities"));
            write(
                &file,
                &velocity_dump(&random_velocities(n, init, stage_seed(scene.seed, i))),
            )?;
            cmd(
                &mut lines,
                format!(
                    "read_dump       {} 0 vx vy vz box no # the native engine's seeded draw",
                    file.display()
                ),
            );
        }
        let every = if stage.record.every > 0 {
            stage.record.every
        } else {
            0
        };
        for (name, value) in [
            ("dt", g(stage.dt)),
            ("viscous", g(stage.viscous)),
            ("every", every.to_string()),
        ] {
            cmd(&mut lines, format!("variable        {name} string {value}"));
        }
        if let Some(m) = stage
            .force_field
            .as_ref()
            .and_then(|ff| ff.granular.as_ref())
        {
            spheres = Some(m);
        }
        if let Some(ff) = &stage.force_field {
            gravity = ff.gravity;
        }
        let external = external_commands(stage, spheres, uses_closure(scene), gravity);
        lines.extend(external.variables.into_iter().map(DriverLine::Command));
        if let Some(ff) = &stage.force_field {
            closure_on = ff.multicontact.is_some();
        }
        let mut columns = stage_columns(energy_terms(scene.model), rotates(scene.model), stage);
        if closure_on {
            columns.extend(closure_columns());
        }
        let template = match &stage.deformation {
            None if stage.barostat.is_some() => {
                let b = stage.barostat.as_ref().expect("checked by the guard");
                for (name, value) in [
                    ("target_pressure", g(b.target_pressure)),
                    ("modulus", g(b.modulus())),
                ] {
                    cmd(&mut lines, format!("variable        {name} string {value}"));
                }
                "stage_barostat.in"
            }
            None => "stage_hold.in",
            Some(Deformation::Isotropic { true_strain_rate }) => {
                cmd(
                    &mut lines,
                    format!("variable        rate string {}", g(*true_strain_rate)),
                );
                cmd(
                    &mut lines,
                    format!("variable        triclinic string {}", u8::from(triclinic)),
                );
                "stage_compress.in"
            }
            Some(Deformation::SimpleShear { tilt, rate, remap }) => {
                let name = match tilt {
                    TiltFactor::Xy => "xy",
                    TiltFactor::Xz => "xz",
                    TiltFactor::Yz => "yz",
                };
                let remap = match remap {
                    ShearRemap::X => "x",
                    ShearRemap::V => "v",
                };
                for (var, value) in [
                    ("rate", g(*rate)),
                    ("tilt", name.into()),
                    ("remap", remap.into()),
                ] {
                    cmd(&mut lines, format!("variable        {var} string {value}"));
                }
                "stage_shear.in"
            }
        };
        cmd(
            &mut lines,
            format!("include         ${{inputs}}/{template}"),
        );
        lines.extend(external.begin.into_iter().map(DriverLine::Command));
        lines.extend(
            record_commands(&columns)
                .into_iter()
                .map(DriverLine::Command),
        );
        cmd(
            &mut lines,
            "include         ${inputs}/stage_record.in".into(),
        );
        lines.push(DriverLine::Run { stage: i });
        cmd(&mut lines, "include         ${inputs}/stage_end.in".into());
        match stage.deformation {
            Some(Deformation::SimpleShear { .. }) => cmd(
                &mut lines,
                "include         ${inputs}/stage_shear_end.in".into(),
            ),
            Some(Deformation::Isotropic { .. }) => {
                cmd(&mut lines, "unfix           bpm_deform".into())
            }
            None => {}
        }
        if stage.barostat.is_some() {
            cmd(&mut lines, "unfix           bpm_barostat".into());
        }
        lines.extend(external.end.into_iter().map(DriverLine::Command));
        stages.push(StagePlan {
            name: stage.name.clone(),
            steps: stage.steps,
            dt: stage.dt,
            every,
            positions_every: stage.record.positions_every,
            columns,
        });
    }
    let driver = Driver { lines, stages };
    write(&dir.join(format!("{tag}.in")), &driver.text())?;
    Ok(driver)
}
