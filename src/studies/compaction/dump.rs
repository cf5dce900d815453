//! `bpm analyse-packing`: the packing analysis of a LAMMPS dump a user
//! brings, against its data file's stress-free state.

use super::CompactionError;
use crate::analysis::packing::{analyse, reference_of, AnalysisOptions, PackingState, Snapshot};
use crate::scene::datafile::read_data_file;
use crate::scene::validate::simbox_of;
use crate::scene::ForceField;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One dump frame of a packing, measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FrameState {
    /// Step of the frame.
    pub step: u64,
    /// The measurements.
    #[serde(flatten)]
    pub packing: PackingState,
}

/// What `bpm analyse-packing` writes.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DumpAnalysis {
    /// bpm version.
    pub version: String,
    /// The command line.
    pub command: String,
    /// The data file: bonds, grains, and the reference state.
    pub data: String,
    /// The dump.
    pub dump: String,
    /// How states were measured.
    pub analysis: AnalysisOptions,
    /// One entry per frame.
    pub frames: Vec<FrameState>,
}

/// Measures every frame of a LAMMPS text dump (columns `id mol x y z`,
/// optional image flags; atom ids as in the data file) of the packing in
/// the data file `data` (atom_style bond, molecule id = grain), against
/// the data file's own state as the reference (hull volumes and shapes at
/// the stress-free start).
pub fn analyse_dump(
    data: &Path,
    dump: &Path,
    analysis: &AnalysisOptions,
    command: &str,
) -> Result<DumpAnalysis, CompactionError> {
    let scene = read_data_file(data, [true; 3], ForceField::paper(0.0), 1)
        .map_err(|e| CompactionError::Packing(e.to_string()))?;
    let frames = crate::scene::trajectory::read_dump(dump)
        .map_err(|e| CompactionError::Packing(e.to_string()))?;
    let grain = scene
        .particles
        .grain
        .clone()
        .ok_or_else(|| CompactionError::Packing("the data file has no molecule ids".into()))?;
    let simbox = simbox_of(&scene);
    let start = Snapshot {
        simbox: &simbox,
        positions: &scene.particles.positions,
        grain: &grain,
        bonds: &scene.bonds.pairs,
    };
    let reference = reference_of(&start, analysis)
        .map_err(CompactionError::analysing(data.display().to_string()))?;
    let mut out = Vec::with_capacity(frames.len());
    for f in &frames {
        if f.x.len() != grain.len() {
            return Err(CompactionError::Packing(format!(
                "{} step {}: {} atoms, the data file has {}",
                dump.display(),
                f.step,
                f.x.len(),
                grain.len()
            )));
        }
        if !f.simbox.periodic.iter().all(|&p| p) {
            return Err(CompactionError::Packing(format!(
                "{} step {}: the box is not periodic in every dimension (BOX BOUNDS pp pp pp needed)",
                dump.display(),
                f.step
            )));
        }
        if f.id != scene.particles.ids {
            return Err(CompactionError::Packing(format!(
                "{} step {}: the atom ids differ from the data file's",
                dump.display(),
                f.step
            )));
        }
        if f.grain != grain {
            return Err(CompactionError::Packing(format!(
                "{} step {}: the molecule ids differ from the data file's",
                dump.display(),
                f.step
            )));
        }
        let fbox = f.simbox.clone();
        let snap = Snapshot {
            simbox: &fbox,
            positions: &f.x,
            grain: &grain,
            bonds: &scene.bonds.pairs,
        };
        out.push(FrameState {
            step: f.step,
            packing: analyse(&snap, &reference, analysis).map_err(CompactionError::analysing(
                format!("{} step {}", dump.display(), f.step),
            ))?,
        });
    }
    Ok(DumpAnalysis {
        version: crate::VERSION.into(),
        command: command.into(),
        data: data.display().to_string(),
        dump: dump.display().to_string(),
        analysis: analysis.clone(),
        frames: out,
    })
}
