//! What a stage records: its rows, its position records and its timing,
//! the same type for both engines (the LAMMPS harness reads its runs back
//! into it) and inside checkpoints.

use super::observables::Column;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Observables of one stage.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StageOutput {
    /// Stage name.
    pub name: String,
    /// Steps run.
    pub steps: u64,
    /// The recorded columns (names, what they measure, how LAMMPS records
    /// them).
    pub columns: Vec<Column>,
    /// One row per recorded step; empty when rows were streamed to
    /// `rows_file`.
    pub rows: Vec<Vec<f64>>,
    /// The thermo file the rows were streamed to, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rows_file: Option<PathBuf>,
    /// Position checkpoints.
    pub checkpoints: Vec<Checkpoint>,
    /// Wall-clock time of the stage (s).
    pub wall_seconds: f64,
    /// Wall-clock seconds per part of the step.
    pub timers: std::collections::BTreeMap<String, f64>,
    /// How many times the pair list was built.
    pub neighbour_builds: u64,
    /// The step within the stage at which it failed, if it did; the rows
    /// and checkpoints run up to it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_at: Option<u64>,
}

impl StageOutput {
    /// The recorded series of column `name`.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.columns.iter().position(|c| c.name == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }
}

impl crate::analysis::Recorded for StageOutput {
    fn name(&self) -> &str {
        &self.name
    }

    fn column(&self, name: &str) -> Option<Vec<f64>> {
        StageOutput::column(self, name)
    }
}

/// Positions at one step.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Global step.
    pub step: u64,
    /// Box lower corner, edge lengths and tilts at that step (d).
    pub simbox: [[f64; 3]; 3],
    /// Positions; wrapped into the box at the last neighbour-list build, so
    /// compare them through the minimum image.
    pub positions: Vec<[f64; 3]>,
    /// Periodic image flags: `positions + images . box vectors` are the
    /// unwrapped positions, so grains crossing periodic faces come out
    /// whole.
    #[serde(default)]
    pub images: Vec<[i32; 3]>,
    /// The bonds broken since the run began (particle index pairs), when
    /// bonds break; the intact bonds at that step are the others.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub broken_bonds: Vec<[usize; 2]>,
}
