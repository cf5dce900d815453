//! Elastic moduli of a packing at states saved during its compaction
//! (docs/protocols.md, "Compaction"). Each state is restarted with its
//! velocities zeroed and relaxed at fixed box (natively once, the three
//! loadings starting from the relaxed state; in LAMMPS in each of three
//! runs); then one run compresses (bulk modulus `K_P`), one shears (shear
//! modulus `G_P`) and one holds the box (the control). Near jamming the
//! packing still creeps when the relaxation ends; the control creeps
//! alike, so the loaded run's stress less the control's, row by row, is
//! the response to the loading alone. The moduli are least-squares slopes
//! of that response against the strain, with their standard errors; the
//! plain slopes (the control not subtracted, as the source study fits) are
//! kept beside them.

use super::{is_jammed, run_engine, CompactionEngine, StateRow};
use crate::analysis::fit::{fit_line, LineFit};
use crate::analysis::moduli::{
    compression_series, poisson_ratio, poisson_ratio_error, shear_series,
};
use crate::engine::{EngineState, System};
use crate::scene::load::reference_lengths;
use crate::scene::protocols::PackingModuliProtocol;
use crate::scene::run::Checkpoint;
use crate::scene::{build_system, Scene, StageOutput};
use crate::studies::{StudyRuntime, StudyStop};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Which states get their moduli measured, and how.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModuliOptions {
    /// States measured per run (0 = none), spread evenly in
    /// `ln(phi - phi_c)` over the compression.
    pub states: usize,
    /// The measurement.
    pub protocol: PackingModuliProtocol,
}

impl Default for ModuliOptions {
    fn default() -> Self {
        Self {
            states: 0,
            protocol: PackingModuliProtocol::paper(),
        }
    }
}

/// The moduli of one saved state of a compaction.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StateModuli {
    /// Stage of the state.
    pub stage: String,
    /// Global step of the state.
    pub step: u64,
    /// The state's volume fraction.
    pub phi_mc: f64,
    /// The state's `P / E_eff` (before the relaxation).
    pub p_over_e_eff: f64,
    /// The measurement.
    #[serde(flatten)]
    pub moduli: PackingModuli,
}

/// The elastic moduli of a packing state, measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PackingModuli {
    /// Pressure after the relaxation, as the loadings start (k/d).
    pub relaxed_pressure: f64,
    /// Bulk modulus `K_P` (k/d): slope of the pressure against the
    /// volumetric strain, less the control run's pressure at each row.
    pub bulk: f64,
    /// Its standard error.
    pub bulk_error: f64,
    /// Shear modulus `G_P` (k/d), from the shear stress less the
    /// control's.
    pub shear: f64,
    /// Its standard error.
    pub shear_error: f64,
    /// The packing's Poisson ratio from `K_P` and `G_P`.
    pub poisson: f64,
    /// Its standard error, propagated from those of `K_P` and `G_P`.
    pub poisson_error: f64,
    /// The bulk modulus without the control subtracted (the plain fit).
    pub bulk_uncorrected: f64,
    /// The shear modulus without the control subtracted.
    pub shear_uncorrected: f64,
    /// Wall-clock seconds of the measurement's runs (natively one
    /// relaxation and three loadings, in LAMMPS three full runs), summed
    /// over the sessions of a resumed study.
    pub seconds: f64,
}

/// Largest standard error, as a fraction of the modulus, of a measurement
/// that the fits and plots take as a modulus.
pub const MAX_RELATIVE_ERROR: f64 = 0.2;

/// Largest standard error of a Poisson ratio taken as measured.
pub const MAX_POISSON_ERROR: f64 = 0.05;

impl PackingModuli {
    /// Whether `K_P` is positive and known to within
    /// [`MAX_RELATIVE_ERROR`].
    pub fn bulk_is_reliable(&self) -> bool {
        self.bulk > 0.0 && self.bulk_error <= MAX_RELATIVE_ERROR * self.bulk
    }

    /// Whether `G_P` is positive and known to within
    /// [`MAX_RELATIVE_ERROR`]. Near jamming `G_P` is close to zero and
    /// often fails this while the Poisson ratio is still well measured.
    pub fn shear_is_reliable(&self) -> bool {
        self.shear > 0.0 && self.shear_error <= MAX_RELATIVE_ERROR * self.shear
    }

    /// Whether both moduli are reliable.
    pub fn is_reliable(&self) -> bool {
        self.bulk_is_reliable() && self.shear_is_reliable()
    }

    /// Whether the Poisson ratio is measured: `K_P` reliable, `G_P` not
    /// negative beyond two standard errors (a packing that yields under
    /// shear has no elastic Poisson ratio), and the ratio known to within
    /// [`MAX_POISSON_ERROR`].
    pub fn poisson_is_reliable(&self) -> bool {
        self.bulk_is_reliable()
            && self.shear + 2.0 * self.shear_error > 0.0
            && self.poisson_error <= MAX_POISSON_ERROR
    }

    /// The fraction of the plain fit of `K_P` that is creep of the
    /// unloaded packing: `(uncorrected - K_P) / K_P`.
    pub fn bulk_creep_fraction(&self) -> f64 {
        (self.bulk_uncorrected - self.bulk) / self.bulk
    }

    /// The same for `G_P`.
    pub fn shear_creep_fraction(&self) -> f64 {
        (self.shear_uncorrected - self.shear) / self.shear
    }
}

/// The states to measure: `count` jammed compression states spread evenly in
/// `ln(phi - phi_c)` from the first jammed state to the last (each target
/// takes the nearest state not taken yet), or evenly over the compression
/// states when there is no `phi_c`. Returns indices into `states`.
pub fn pick_states(states: &[StateRow], phi_c: Option<f64>, count: usize) -> Vec<usize> {
    let compressed: Vec<usize> = (0..states.len())
        .filter(|&i| is_jammed(&states[i]))
        .collect();
    if count == 0 || compressed.is_empty() {
        return Vec::new();
    }
    let position: Vec<(usize, f64)> = match phi_c {
        Some(phi_c) => compressed
            .iter()
            .filter(|&&i| states[i].packing.phi_mc > phi_c)
            .map(|&i| (i, (states[i].packing.phi_mc - phi_c).ln()))
            .collect(),
        None => compressed.iter().map(|&i| (i, i as f64)).collect(),
    };
    let Some(lo) = position.iter().map(|p| p.1).reduce(f64::min) else {
        return Vec::new();
    };
    let hi = position.iter().map(|p| p.1).fold(lo, f64::max);
    let mut chosen: Vec<usize> = Vec::new();
    for k in 0..count.min(position.len()) {
        let target = if count > 1 {
            lo + (hi - lo) * k as f64 / (count - 1) as f64
        } else {
            hi
        };
        let best = position
            .iter()
            .filter(|(i, _)| !chosen.contains(i))
            .min_by(|a, b| (a.1 - target).abs().total_cmp(&(b.1 - target).abs()));
        if let Some(&(i, _)) = best {
            chosen.push(i);
        }
    }
    chosen.sort_unstable();
    chosen
}

/// The three scenes that measure the moduli of `state`, a checkpoint of
/// the compaction of `packing`: its box and positions, velocities zero,
/// the bonds' reference lengths those of the stress-free packing (the
/// compaction reset them there); then the protocol's compression, shear
/// and unloaded control.
pub fn moduli_scenes(
    packing: &Scene,
    state: &Checkpoint,
    protocol: &PackingModuliProtocol,
) -> [Scene; 3] {
    let mut base = packing.clone();
    base.bonds.r0 = Some(reference_lengths(packing));
    base.simbox.lo = state.simbox[0];
    base.simbox.lengths = state.simbox[1];
    base.simbox.tilt = state.simbox[2];
    base.particles.positions = state.positions.clone();
    base.particles.velocities = None;
    [
        protocol.compression_stages(),
        protocol.shear_stages(),
        protocol.control_stages(),
    ]
    .map(|stages| {
        let mut scene = base.clone();
        scene.stages = stages;
        scene
    })
}

/// The three scenes of one state run in `engine`, each its relaxation and
/// its loading (or hold), and the runs' wall-clock seconds.
type Measured = ([Vec<StageOutput>; 3], f64);

/// Runs the three scenes of one state in `engine`; each must return its
/// relaxation and its loading (or hold). Natively see
/// [`relax_once_then_load`]; in LAMMPS each finished run is a part of
/// `runtime`'s checkpoint (`compress`, `shear`, `control`), and a stop
/// asked for ends the measurement before the next run.
fn run_all(
    scenes: &[Scene; 3],
    engine: &CompactionEngine,
    folder: &Path,
    tag: &str,
    bpm: Option<&Path>,
    runtime: &StudyRuntime,
) -> Result<Measured, MeasureStop> {
    if *engine == CompactionEngine::Native {
        let runs = relax_once_then_load(scenes, runtime)?;
        // The runs' own wall times add up over the sessions of a resumed
        // study; this session's clock would miss the parts taken from its
        // checkpoint.
        let seconds = [&runs[0][0], &runs[0][1], &runs[1][1], &runs[2][1]]
            .iter()
            .map(|s| s.wall_seconds)
            .sum();
        return Ok((runs, seconds));
    }
    let mut out: [Vec<StageOutput>; 3] = Default::default();
    let mut seconds = 0.0;
    // Each finished run is a part of the study (beneath the state's), so
    // a study stopped or killed during the second or third run keeps the
    // first. A LAMMPS run does not see a stop; one killed with the study
    // fails, and is made again from its start.
    let plain = StudyRuntime::plain(runtime.threads, false);
    for (k, (scene, kind)) in scenes.iter().zip(LOADINGS).enumerate() {
        let run = runtime.part(kind, || {
            let (stages, stopped, run_seconds) = run_engine(
                scene,
                engine,
                folder,
                &format!("{tag}-{kind}"),
                kind,
                &plain,
                bpm,
            )
            .map_err(|e| e.to_string())?;
            if let Some(m) = stopped {
                return Err(MeasureStop::Failed(format!("the {kind} run stopped: {m}")));
            }
            if stages.len() != 2 {
                return Err(MeasureStop::Failed(format!(
                    "the {kind} run returned {} stages, not 2",
                    stages.len()
                )));
            }
            Ok(LammpsRun {
                stages,
                seconds: run_seconds,
            })
        })?;
        seconds += run.seconds;
        out[k] = run.stages;
    }
    Ok((out, seconds))
}

/// A finished LAMMPS run of a measurement, as its part keeps it.
#[derive(Serialize, Deserialize)]
struct LammpsRun {
    stages: Vec<StageOutput>,
    seconds: f64,
}

/// The loadings of a state's three scenes, in order.
const LOADINGS: [&str; 3] = ["compress", "shear", "control"];

/// The part (and run) of a native measurement's relaxation.
const RELAXED: &str = "relaxed";

/// The parts a measurement keeps beneath its own in a study's checkpoint:
/// natively its relaxed state and loadings ([`relax_once_then_load`]), in
/// LAMMPS its three runs.
pub const KEPT_STEPS: [&str; 4] = [RELAXED, LOADINGS[0], LOADINGS[1], LOADINGS[2]];

/// A state relaxed for its moduli: the relaxation's records and the
/// engine's state at its end, where each loading starts.
#[derive(Serialize, Deserialize)]
struct Relaxed {
    records: StageOutput,
    state: EngineState,
}

/// The three scenes of one state in the native engine, their common
/// relaxation run once: each loading starts from the relaxed state, saved
/// and restored whole. A run continued from a saved state is the run that
/// did not stop, so the records are those of three full runs, bit for
/// bit, for one relaxation's steps instead of three (at a relaxation of
/// 1e4 tau and the default --moduli-rate, 1.6e5 steps instead of 3.6e5;
/// at the paper's slower rates, 7e5 instead of 9e5).
///
/// With a checkpoint in `runtime` (scoped to the state), the relaxed
/// state and each finished loading are parts of the study (`relaxed`,
/// `compress`, `shear`, `control`), and the run under way is checkpointed
/// with the study: a stop or a kill loses at most the interval between
/// two checkpoints, not the measurement.
pub fn relax_once_then_load(
    scenes: &[Scene; 3],
    runtime: &StudyRuntime,
) -> Result<[Vec<StageOutput>; 3], MeasureStop> {
    let first = &scenes[0];
    // The scenes differ only in their loading stage (`moduli_scenes`).
    let same_start = |s: &Scene| {
        s.stages.len() == 2 && {
            let mut loading_replaced = s.clone();
            loading_replaced.stages[1] = first.stages[1].clone();
            loading_replaced == *first
        }
    };
    if !scenes.iter().all(same_start) {
        return Err(MeasureStop::Failed(
            "the moduli's scenes must differ only in their second (loading) stage".into(),
        ));
    }
    let with_stage = |scene: &Scene, k: usize| Scene {
        stages: vec![scene.stages[k].clone()],
        ..scene.clone()
    };
    let relaxation = with_stage(first, 0);
    let relaxed = runtime.part(RELAXED, || {
        let mut sys = build_system(&relaxation, runtime.threads);
        let records = run_one_stage(runtime, RELAXED, "relaxation", &mut sys, &relaxation)?;
        let state = sys.save_state().map_err(|e| e.to_string())?;
        Ok::<_, MeasureStop>(Relaxed { records, state })
    })?;
    let mut out: [Vec<StageOutput>; 3] = Default::default();
    for ((scene, kind), runs) in scenes.iter().zip(LOADINGS).zip(&mut out) {
        let loading = with_stage(scene, 1);
        let records = runtime.part(kind, || {
            let mut sys = build_system(&loading, runtime.threads);
            sys.restore(relaxed.state.clone())
                .map_err(|e| e.to_string())?;
            run_one_stage(runtime, kind, kind, &mut sys, &loading)
        })?;
        *runs = vec![relaxed.records.clone(), records];
    }
    Ok(out)
}

/// Runs `scene`, of one stage, on `sys` as the study's run `key` (that of
/// the part it computes), named `kind` in messages; its records.
fn run_one_stage(
    runtime: &StudyRuntime,
    key: &str,
    kind: &str,
    sys: &mut System,
    scene: &Scene,
) -> Result<StageOutput, MeasureStop> {
    let mut outcome = runtime.run_system(key, sys, scene)?;
    if let Some(e) = outcome.error {
        return Err(MeasureStop::Failed(format!("the {kind} run stopped: {e}")));
    }
    outcome
        .stages
        .pop()
        .ok_or_else(|| MeasureStop::Failed(format!("the {kind} run recorded no stage")))
}

/// Why a state's moduli were not measured.
#[derive(Debug, thiserror::Error)]
pub enum MeasureStop {
    /// A run failed, or the measurement could not be made: the state has
    /// no moduli.
    #[error("{0}")]
    Failed(String),
    /// The study stopped (asked to, or its checkpoint failed): its
    /// checkpoint continues the measurement.
    #[error(transparent)]
    Stopped(#[from] StudyStop),
}

impl From<String> for MeasureStop {
    fn from(reason: String) -> Self {
        MeasureStop::Failed(reason)
    }
}

/// The response to a loading: `loaded - control` at each of the loaded
/// rows' steps (`loaded` and `control` as `(step, value)` columns).
pub fn response_to_loading(
    loaded: (&[f64], &[f64]),
    control: (&[f64], &[f64]),
) -> Result<Vec<f64>, String> {
    loaded
        .0
        .iter()
        .zip(loaded.1)
        .map(|(step, v)| {
            control
                .0
                .iter()
                .position(|s| s == step)
                .map(|k| v - control.1[k])
                .ok_or_else(|| format!("the control recorded no row at step {step}"))
        })
        .collect()
}

/// `column` of a stage and its steps.
fn stepped_column(stage: &StageOutput, column: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
    match (stage.column("step"), stage.column(column)) {
        (Some(steps), Some(values)) => Ok((steps, values)),
        _ => Err(format!(
            "stage `{}` recorded no `step` or `{column}` column",
            stage.name
        )),
    }
}

/// `loaded[column] - control[column]` at the loaded stage's rows.
fn less_control(
    loaded: &StageOutput,
    control: &StageOutput,
    column: &str,
) -> Result<Vec<f64>, String> {
    let (ls, lv) = stepped_column(loaded, column)?;
    let (cs, cv) = stepped_column(control, column)?;
    response_to_loading((&ls, &lv), (&cs, &cv))
}

fn slope_fit(x: &[f64], y: &[f64], what: &str) -> Result<LineFit, String> {
    fit_line(x, y)
        .filter(|f| f.line.slope.is_finite() && f.slope_error.is_finite())
        .ok_or_else(|| format!("no finite {what} slope through {} rows", x.len()))
}

/// Measures the moduli of `state`, a checkpoint of the compaction of
/// `packing`, in `engine`; LAMMPS runs write their files into
/// `folder/moduli-STEP-{compress,shear,control}.*`. The runs are kept in
/// `runtime`'s checkpoint, if it has one, as they finish ([`run_all`]).
pub fn measure_state(
    packing: &Scene,
    state: &Checkpoint,
    protocol: &PackingModuliProtocol,
    engine: &CompactionEngine,
    folder: &Path,
    bpm: Option<&Path>,
    runtime: &StudyRuntime,
) -> Result<PackingModuli, MeasureStop> {
    let scenes = moduli_scenes(packing, state, protocol);
    let ([compress, shear, control], seconds) = run_all(
        &scenes,
        engine,
        folder,
        &format!("moduli-{}", state.step),
        bpm,
        runtime,
    )?;
    let (volumetric, pressure) = compression_series(&compress[1]).map_err(|e| e.to_string())?;
    let (shear_strain, shear_stress) = shear_series(&shear[1]).map_err(|e| e.to_string())?;
    let pressure_response = less_control(&compress[1], &control[1], "pressure")?;
    // The shear stress is -P_xy.
    let stress_response: Vec<f64> = less_control(&shear[1], &control[1], "pxy")?
        .iter()
        .map(|d| -d)
        .collect();
    let k = slope_fit(&volumetric, &pressure_response, "bulk")?;
    let g = slope_fit(&shear_strain, &stress_response, "shear")?;
    let (bulk, shear_modulus) = (k.line.slope, g.line.slope);
    Ok(PackingModuli {
        relaxed_pressure: pressure.first().copied().unwrap_or(f64::NAN),
        bulk,
        bulk_error: k.slope_error,
        shear: shear_modulus,
        shear_error: g.slope_error,
        poisson: poisson_ratio(bulk, shear_modulus),
        poisson_error: poisson_ratio_error(bulk, shear_modulus, k.slope_error, g.slope_error),
        bulk_uncorrected: slope_fit(&volumetric, &pressure, "bulk")?.line.slope,
        shear_uncorrected: slope_fit(&shear_strain, &shear_stress, "shear")?.line.slope,
        seconds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(stage: &str, phi: f64) -> StateRow {
        StateRow {
            stage: stage.into(),
            rate: 0.0,
            step: 0,
            time: 0.0,
            pressure: 0.0,
            p_over_e_eff: 0.0,
            ke_per_particle: 0.0,
            packing: crate::analysis::packing::PackingState {
                phi_mc: phi,
                z_force: 5.0,
                ..Default::default()
            },
            fragments: None,
        }
    }

    fn measured(shear: f64, shear_error: f64, poisson_error: f64) -> PackingModuli {
        PackingModuli {
            relaxed_pressure: 1e-3,
            bulk: 1.0,
            bulk_error: 0.01,
            shear,
            shear_error,
            poisson: 0.45,
            poisson_error,
            bulk_uncorrected: 1.0,
            shear_uncorrected: shear,
            seconds: 0.0,
        }
    }

    #[test]
    fn reliability_is_judged_per_modulus() {
        // G near zero: not a reliable G, but nu_P is measured.
        let near_jamming = measured(-0.001, 0.001, 0.01);
        assert!(near_jamming.bulk_is_reliable() && !near_jamming.shear_is_reliable());
        assert!(near_jamming.poisson_is_reliable() && !near_jamming.is_reliable());
        // G negative by three errors: the packing yields, no nu_P.
        assert!(!measured(-0.003, 0.001, 0.01).poisson_is_reliable());
        // nu_P too uncertain, or not a number.
        assert!(!measured(0.1, 0.001, 0.06).poisson_is_reliable());
        assert!(!measured(0.1, 0.001, f64::NAN).poisson_is_reliable());
        let good = measured(0.1, 0.01, 0.01);
        assert!(good.is_reliable() && good.poisson_is_reliable());
        assert!(!measured(0.1, 0.03, 0.01).shear_is_reliable());
    }

    #[test]
    fn the_control_s_creep_is_subtracted_row_by_row() {
        // The control creeps linearly in time; the loaded run adds
        // 2.5 x strain on top. Rows of the control every 5 steps, of the
        // loading every 10: matched by step.
        let control_steps: Vec<f64> = (0..=20).map(|k| 100.0 + 5.0 * k as f64).collect();
        let creep = |step: f64| 0.3 - 1e-3 * (step - 100.0);
        let control: Vec<f64> = control_steps.iter().map(|&s| creep(s)).collect();
        let steps: Vec<f64> = (0..=10).map(|k| 100.0 + 10.0 * k as f64).collect();
        let strain: Vec<f64> = steps.iter().map(|s| 1e-4 * (s - 100.0)).collect();
        let loaded: Vec<f64> = steps
            .iter()
            .zip(&strain)
            .map(|(&s, e)| creep(s) + 2.5 * e)
            .collect();
        let response = response_to_loading((&steps, &loaded), (&control_steps, &control)).unwrap();
        let fit = slope_fit(&strain, &response, "test").unwrap();
        assert!((fit.line.slope - 2.5).abs() < 1e-9, "{fit:?}");
        // Without the control the creep, -1e-3 per step over 1e-4 strain
        // per step, would add -10 to the slope.
        let plain = slope_fit(&strain, &loaded, "test").unwrap();
        assert!((plain.line.slope + 7.5).abs() < 1e-9, "{plain:?}");
        // A loaded row the control did not record is an error.
        let err = response_to_loading((&[103.0], &[0.0]), (&control_steps, &control));
        assert!(err.unwrap_err().contains("103"));
    }

    #[test]
    fn states_are_picked_evenly_in_the_log_of_the_distance_to_jamming() {
        let mut states = vec![state("start", 0.45), state("jam", 0.52)];
        for phi in [0.50, 0.51, 0.52, 0.55, 0.60, 0.70, 0.90] {
            states.push(state("compress-0", phi));
        }
        // phi - phi_c from 0.005 to 0.395: the middle of the log range,
        // 0.044, is nearest 0.045 (phi = 0.55); the jam state and the
        // unjammed one are never picked.
        assert_eq!(pick_states(&states, Some(0.505), 3), vec![3, 5, 8]);
        assert_eq!(pick_states(&states, Some(0.505), 100).len(), 6);
        assert_eq!(pick_states(&states, None, 2), vec![2, 8]);
        assert!(pick_states(&states, Some(0.505), 0).is_empty());
        assert!(pick_states(&states[..2], Some(0.505), 3).is_empty());
        // A compression state without a contact network is never picked.
        states[8].packing.z_force = 0.0;
        assert_eq!(pick_states(&states, Some(0.505), 3), vec![3, 5, 7]);
    }
}
