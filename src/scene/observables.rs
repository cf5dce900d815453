//! The recorded columns of a stage, declared once.
//!
//! A stage's thermo row is the list of [`Column`]s that [`stage_columns`]
//! derives from the particle model (its energy terms) and the stage (its
//! walls, sphere wall). The native engine fills a row with
//! [`Column::native_value`]; the LAMMPS driver records each column through
//! its [`Column::lammps`] expression; the comparison groups columns by
//! [`Column::observable`], the key of the tolerance table. Nothing else
//! lists column names.

use super::model::StageSpec;
use crate::engine::{BpmModel, DemModel, EnergyTerm, System};
use serde::{Deserialize, Serialize};

/// What a column measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Global step.
    Step,
    /// Simulated time (tau).
    Time,
    /// Box edge length or tilt: 0..3 = lx, ly, lz; 3..6 = xy, xz, yz (d).
    Box(usize),
    /// Pressure-tensor component `[xx, yy, zz, xy, xz, yz]` (k / d^2 in
    /// 3D reduced units), positive in compression.
    Stress(usize),
    /// Mean of the diagonal of the pressure tensor.
    Pressure,
    /// Energy of the model's term with this index (k d^2).
    ModelEnergy(usize),
    /// Translational kinetic energy.
    Kinetic,
    /// Rotational kinetic energy of spheres.
    Rotational,
    /// Energy of walls and tether.
    External,
    /// Normal force on flat wall `w` (k d), >= 0.
    WallForce(usize),
    /// Position of flat wall `w` (d).
    WallPosition(usize),
    /// Summed force magnitude on the spherical wall (k d).
    SphereWallForce,
    /// Normal force on granular wall `w` (k d), positive when pushed.
    GranularWallForce(usize),
    /// Position of granular wall `w` (d).
    GranularWallPosition(usize),
    /// The multi-contact closure's largest correction over its sphere's
    /// radius.
    LargestCorrection,
    /// Contacts (or terms) the advanced closure switched off.
    SwitchedOff,
    /// Bonds intact.
    Bonds,
    /// Bonds broken since the run began.
    BrokenBonds,
}

/// One recorded column.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Column {
    /// Name in reports and thermo files.
    pub name: String,
    /// What it measures.
    pub quantity: Quantity,
    /// The compared observable it belongs to (a key of the tolerance table).
    pub observable: String,
    /// LAMMPS equal-style expression that records it, or `None` when the
    /// harness derives it (step, time, mean pressure) or LAMMPS cannot.
    pub lammps: Option<String>,
}

const BOX_NAMES: [&str; 6] = ["lx", "ly", "lz", "xy", "xz", "yz"];
const STRESS_NAMES: [&str; 6] = ["pxx", "pyy", "pzz", "pxy", "pxz", "pyz"];

/// LAMMPS compute id of model energy term `column`.
pub fn lammps_energy_compute(column: &str) -> String {
    format!("bpm_{column}")
}

/// The columns of a stage of a model with energy terms `terms` whose
/// particles rotate or not: step, time, box, stress, pressure, the model's
/// energies, kinetic (and rotational) and external energy, then each flat
/// wall's force and position, each granular wall's, and the sphere wall's
/// force.
pub fn stage_columns(terms: &[EnergyTerm], rotational: bool, stage: &StageSpec) -> Vec<Column> {
    let col = |name: &str, quantity, observable: &str, lammps: Option<String>| Column {
        name: name.to_string(),
        quantity,
        observable: observable.to_string(),
        lammps,
    };
    let mut c = vec![
        col("step", Quantity::Step, "step", None),
        col("time", Quantity::Time, "time", None),
    ];
    for (k, name) in BOX_NAMES.iter().enumerate() {
        c.push(col(name, Quantity::Box(k), "box", Some(name.to_string())));
    }
    for (k, name) in STRESS_NAMES.iter().enumerate() {
        let expr = format!("c_thermo_press[{}]", k + 1);
        c.push(col(name, Quantity::Stress(k), "stress", Some(expr)));
    }
    // The harness takes the mean of the recorded diagonal: LAMMPS's scalar
    // pressure counts 3N - 3 kinetic degrees of freedom.
    c.push(col("pressure", Quantity::Pressure, "stress", None));
    for (k, term) in terms.iter().enumerate() {
        let expr = format!("c_{}", lammps_energy_compute(term.column));
        c.push(col(
            term.column,
            Quantity::ModelEnergy(k),
            term.observable,
            Some(expr),
        ));
    }
    c.push(col(
        "e_kinetic",
        Quantity::Kinetic,
        "kinetic energy",
        Some("c_bpm_ke".into()),
    ));
    if rotational {
        c.push(col(
            "e_rotational",
            Quantity::Rotational,
            "kinetic energy",
            Some("c_bpm_erotate".into()),
        ));
    }
    c.push(col(
        "e_external",
        Quantity::External,
        "external energy",
        Some("v_bpm_eext".into()),
    ));
    for w in 0..stage.walls.len() {
        c.push(col(
            &format!("wall{w}_force"),
            Quantity::WallForce(w),
            "wall forces",
            Some(format!("v_bpm_wall{w}_force")),
        ));
        c.push(col(
            &format!("wall{w}_position"),
            Quantity::WallPosition(w),
            "wall positions",
            Some(format!("v_bpm_wall{w}_position")),
        ));
    }
    for w in 0..stage.granular_walls.len() {
        c.push(col(
            &format!("granular_wall{w}_force"),
            Quantity::GranularWallForce(w),
            "wall forces",
            Some(format!("v_bpm_gwall{w}_force")),
        ));
        c.push(col(
            &format!("granular_wall{w}_position"),
            Quantity::GranularWallPosition(w),
            "wall positions",
            Some(format!("v_bpm_gwall{w}_position")),
        ));
    }
    if stage.sphere_wall.is_some() {
        c.push(col(
            "sphere_wall_force",
            Quantity::SphereWallForce,
            "sphere wall force",
            None,
        ));
    }
    c
}

/// LAMMPS's compute of the multi-contact closure's two values (`compute
/// pair bpm/granular`: the pair style's largest correction and switched-off
/// count).
pub const LAMMPS_CLOSURE_COMPUTE: &str = "bpm_mc";

/// The columns a stage adds when its spheres have the multi-contact
/// closure.
pub fn closure_columns() -> Vec<Column> {
    let col = |name: &str, quantity, index: usize| Column {
        name: name.into(),
        quantity,
        observable: "multi-contact corrections".into(),
        lammps: Some(format!("c_{LAMMPS_CLOSURE_COMPUTE}[{index}]")),
    };
    vec![
        col("mc_largest_correction", Quantity::LargestCorrection, 1),
        col("mc_switched_off", Quantity::SwitchedOff, 2),
    ]
}

/// The columns a stage adds when its bonds break or yield: bonds intact
/// and bonds broken. The harness's LAMMPS runs refuse such scenes.
pub fn failure_columns() -> Vec<Column> {
    let col = |name: &str, quantity| Column {
        name: name.into(),
        quantity,
        observable: "bond counts".into(),
        lammps: None,
    };
    vec![
        col("bonds", Quantity::Bonds),
        col("broken_bonds", Quantity::BrokenBonds),
    ]
}

/// The declaration of a column every bonded-particle stage records (box,
/// stress, pressure, energies, step, time), by name.
pub fn standard_column(name: &str) -> Option<Column> {
    let plain = StageSpec::hold("", 0, 0.1);
    stage_columns(&crate::engine::bpm::ENERGY_TERMS, false, &plain)
        .into_iter()
        .find(|c| c.name == name)
}

/// The names of `columns`.
pub fn column_names(columns: &[Column]) -> Vec<String> {
    columns.iter().map(|c| c.name.clone()).collect()
}

impl Column {
    /// The column's value for the native engine's current state.
    pub fn native_value(&self, sys: &System, pressure: &[f64; 6]) -> f64 {
        let b = &sys.simbox;
        let r = &sys.report;
        let dem = sys.model_as::<DemModel>().map(DemModel::report);
        let bpm = sys.model_as::<BpmModel>();
        match self.quantity {
            Quantity::Step => sys.step as f64,
            Quantity::Time => sys.time,
            Quantity::Box(k) if k < 3 => b.lengths[k],
            Quantity::Box(k) => b.tilt[k - 3],
            Quantity::Stress(k) => pressure[k],
            Quantity::Pressure => (pressure[0] + pressure[1] + pressure[2]) / 3.0,
            Quantity::ModelEnergy(k) => r.interactions.terms[k].energy,
            Quantity::Kinetic => sys.kinetic_energy(),
            Quantity::Rotational => sys.particles.rotational_energy(),
            Quantity::External => r.external.energy,
            Quantity::WallForce(w) => r.external.wall_forces[w],
            Quantity::WallPosition(w) => r.external.wall_positions[w],
            Quantity::SphereWallForce => r.external.sphere_wall_force,
            // Validation admits granular walls and the closure only with
            // DEM spheres, whose report holds them.
            Quantity::GranularWallForce(w) => dem.map_or(f64::NAN, |d| d.walls[w].force),
            Quantity::GranularWallPosition(w) => dem.map_or(f64::NAN, |d| d.wall_positions[w]),
            Quantity::LargestCorrection => dem.and_then(|d| d.closure).map_or(0.0, |c| c.largest),
            Quantity::SwitchedOff => dem
                .and_then(|d| d.closure)
                .map_or(0.0, |c| c.switched_off as f64),
            Quantity::Bonds => bpm.map_or(0.0, |m| m.bonds().len() as f64),
            Quantity::BrokenBonds => bpm.map_or(0.0, |m| m.broken_bonds().len() as f64),
        }
    }

    /// Whether LAMMPS records the column (else the harness derives it).
    pub fn recorded_by_lammps(&self) -> bool {
        self.lammps.is_some()
    }
}

/// One row of `columns` for the native engine's current state.
pub fn native_row(columns: &[Column], sys: &System) -> Vec<f64> {
    let p = sys.pressure_tensor();
    columns.iter().map(|c| c.native_value(sys, &p)).collect()
}

/// Whether a scene's model rotates its particles (what its
/// [`crate::engine::ParticleModel::rotational`] returns), without building
/// the model.
pub fn rotates(model: super::model::ModelKind) -> bool {
    model == super::model::ModelKind::Dem
}

/// The energy terms of a scene's model (what its
/// [`crate::engine::ParticleModel::energy_terms`] returns), without
/// building the model.
pub fn energy_terms(model: super::model::ModelKind) -> &'static [EnergyTerm] {
    match model {
        super::model::ModelKind::Bpm => &crate::engine::bpm::ENERGY_TERMS,
        super::model::ModelKind::Dem => &[],
    }
}
