//! K and G of a solid measured on either engine: the calibration's
//! compression and shear scenes ([`calibration_scenes`]) run through the
//! harness, their slopes taken by [`Moduli::measured`]. `bpm check` uses
//! it, as does every command that measures the solid.

use super::engines::{run_native, EngineRun, HarnessError, LammpsLauncher};
use crate::analysis::moduli::Moduli;
use crate::scene::protocols::{calibration_scenes, ModuliLoading};
use crate::scene::Scene;

/// Which engine runs a calibration.
#[derive(Clone, Debug)]
pub enum CalibrationEngine {
    /// The native engine with this many threads.
    Native(usize),
    /// LAMMPS with our styles on this many ranks.
    Lammps(LammpsLauncher, usize),
}

impl CalibrationEngine {
    /// Short name for reports.
    pub fn name(&self) -> String {
        match self {
            Self::Native(_) => "native".into(),
            Self::Lammps(_, ranks) => format!("lammps-np{ranks}"),
        }
    }

    fn run(&self, scene: &Scene, tag: &str) -> Result<EngineRun, HarnessError> {
        match self {
            Self::Native(threads) => run_native(scene, tag, *threads),
            Self::Lammps(launcher, ranks) => launcher.run(scene, tag, *ranks, true),
        }
    }
}

/// Measures K and G of `solid` at `a_b` (with the zero-net variant or
/// without) on `engine`; `tag` names the runs. Returns the moduli and the
/// two runs.
pub fn measure_moduli(
    solid: &Scene,
    a_b: f64,
    zero_net: bool,
    loading: &ModuliLoading,
    engine: &CalibrationEngine,
    tag: &str,
) -> Result<(Moduli, [EngineRun; 2]), HarnessError> {
    let [compress, shear] = calibration_scenes(solid, a_b, zero_net, loading);
    let c = engine.run(&compress, &format!("{tag}-compress"))?;
    let s = engine.run(&shear, &format!("{tag}-shear"))?;
    let moduli =
        Moduli::measured(a_b, &c.stages[0], &s.stages[0], c.seconds + s.seconds).map_err(|e| {
            HarnessError::Native {
                scene: tag.into(),
                message: e.to_string(),
            }
        })?;
    Ok((moduli, [c, s]))
}
