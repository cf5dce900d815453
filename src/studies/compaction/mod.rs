//! Compaction of grain packings (`bpm compact`, docs/protocols.md
//! "Compaction"): a packing is built (or read from a LAMMPS data file),
//! jammed with the Berendsen barostat and compressed isotropically at
//! stepwise-raised strain rates, in the native engine or in LAMMPS with
//! this project's styles, from one scene. Every recorded state is
//! analysed (volume fraction, coordination, grain strain and shape), and
//! the report, per-run folders and plots are written as the runs finish,
//! so a failure loses nothing already done.
//!
//! With a [`DemContact`] the same template and protocol compact DEM
//! spheres instead (one per grain, [`dem`]), the source study's comparison.

use crate::analysis::fragments::GrainFragments;
use crate::analysis::hertz::effective_modulus;
use crate::analysis::jamming::{
    coordination_law, departure, power_law_at, power_law_with_jamming_point, PowerLaw,
};
use crate::analysis::packing::{
    analyse, analyse_spheres, reference_of, AnalysisOptions, PackingState, Reference, Snapshot,
};
use crate::analysis::plot::PlotError;
use crate::analysis::slice::SliceFrame;
use crate::engine::SimBox;
use crate::file_error::FileError;
use crate::kernels::BondFailure;
use crate::options::InvalidOption;
use crate::scene::builders::grain::GrainKind;
use crate::scene::builders::packing::{
    break_contacts, build_packing, build_sphere_packing, separate_spheres, PackingParams,
    PackingSummary,
};
use crate::scene::datafile::{read_data_file, write_data_file};
use crate::scene::model::ModelKind;
use crate::scene::protocols::{compaction_scene, CompactionProtocol};
use crate::scene::run::Checkpoint;
use crate::scene::validate::{simbox_of, SceneError};
use crate::scene::{write_scene, ForceField, Scene, StageOutput};
use crate::studies::hertz::Moduli;
use crate::studies::{StudyRuntime, StudyStop};
use crate::verify::LammpsLauncher;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Where the packings come from.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PackingSource {
    /// Built here, one packing per seed.
    Build {
        /// Grains per packing.
        grains: usize,
        /// Rough or smoother grains.
        kind: GrainKind,
        /// Grain radius R (d).
        radius: f64,
        /// Different grains built per packing (reused with rotations).
        distinct_grains: usize,
        /// Volume fraction of the template's spheres.
        template_fraction: f64,
        /// Scale of the grain builds' times (1 = full protocol).
        time_scale: f64,
    },
    /// A LAMMPS data file, periodic in every dimension, image flags
    /// honoured: bonded grains (`atom_style bond`, molecule id = grain), or
    /// DEM spheres of one radius (`atom_style sphere`) with `--model dem`.
    File {
        /// The data file.
        path: PathBuf,
    },
}

/// Which engine compresses.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CompactionEngine {
    /// The native engine.
    Native,
    /// LAMMPS with this project's styles, as a child process.
    Lammps {
        /// MPI ranks.
        ranks: usize,
    },
}

/// What `bpm compact` runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CompactOptions {
    /// The packings.
    pub source: PackingSource,
    /// Multibody strength a_B (k d); the force field is otherwise the
    /// paper's. For DEM spheres it sets their E and nu (the solid's
    /// calibration at a_B).
    pub a_b: f64,
    /// The zero-net-multibody variant.
    pub zero_net: bool,
    /// One packing and run per seed.
    pub seeds: Vec<u64>,
    /// The protocol.
    pub protocol: CompactionProtocol,
    /// The engine.
    pub engine: CompactionEngine,
    /// How states are measured.
    pub analysis: AnalysisOptions,
    /// The packing's elastic moduli at some of the states.
    #[serde(default)]
    pub moduli: ModuliOptions,
    /// DEM spheres (one per grain, this contact) instead of bonded grains.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dem: Option<DemContact>,
    /// Bonds that break or yield during the compaction (the packing is
    /// built and stored elastic); absent, they stay elastic.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bond_failure: Option<BondFailure>,
    /// Bonded particles also touch through the contact law (the force
    /// field's `overlay_pair`): a bond squeezed below the contact distance
    /// meets the contact's repulsion, as upstream LAMMPS's `overlay/pair`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub overlay_pair: bool,
}

/// Why the study could not run (a run that stops is a result: it is
/// recorded with its message and the states it reached).
#[derive(Debug, thiserror::Error)]
pub enum CompactionError {
    /// An option is out of range.
    #[error(transparent)]
    Invalid(#[from] InvalidOption),
    /// A packing could not be built or read.
    #[error("packing: {0}")]
    Packing(String),
    /// A state could not be analysed.
    #[error("analysing {what}: {message}")]
    Analysis {
        /// Which state.
        what: String,
        /// Why.
        message: String,
    },
    /// A file is not a compaction report.
    #[error("{path}: not a compaction report: {message}")]
    NotAReport {
        /// The file.
        path: String,
        /// Why.
        message: String,
    },
    /// A plot could not be written.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// A file could not be written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The study stopped before its end (its checkpoint continues it).
    #[error(transparent)]
    Stopped(#[from] crate::studies::StudyStop),
    /// The report or its drawings could not be written or read back.
    #[error(transparent)]
    Output(#[from] crate::studies::output::OutputError),
}

impl CompactionError {
    /// Maps a failed measurement of `what` to [`CompactionError::Analysis`].
    pub fn analysing(
        what: impl Into<String>,
    ) -> impl FnOnce(crate::analysis::packing::PackingError) -> Self {
        let what = what.into();
        move |e| Self::Analysis {
            what,
            message: e.to_string(),
        }
    }
}

impl CompactOptions {
    /// What a study's checkpoint must have been written with to be resumed
    /// by these options: every option but the moduli's (the field is left
    /// out, so no moduli value, default or not, enters it). A resumed study
    /// may measure other states, or by another protocol, taking the
    /// packings and runs from the checkpoint (each measurement is kept
    /// under its step and protocol).
    pub fn checkpoint_identity(&self) -> serde_json::Value {
        let mut identity = serde_json::to_value(self).unwrap_or_default();
        if let Some(fields) = identity.as_object_mut() {
            fields.remove("moduli");
        }
        identity
    }

    /// Checks the options; the error names the one at fault.
    pub fn validate(&self) -> Result<(), InvalidOption> {
        let p = &self.protocol;
        let positive = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(InvalidOption::new(
                    name,
                    format!("must be positive, got {v}"),
                ))
            }
        };
        positive("--dt", p.dt)?;
        positive("--jam-gain", p.jam_gain)?;
        positive("--jam-time", p.jam_time)?;
        positive("--rate-start", p.rate_start)?;
        positive("--rate-end", p.rate_end)?;
        positive("--stage-time", p.stage_time)?;
        if !(p.jam_pressure.is_finite() && p.jam_pressure >= 0.0) {
            return Err(InvalidOption::new(
                "--jam-pressure",
                format!("must be finite and >= 0, got {}", p.jam_pressure),
            ));
        }
        if p.rate_end < p.rate_start {
            return Err(InvalidOption::new(
                "--rate-end",
                format!("must be at least --rate-start ({})", p.rate_start),
            ));
        }
        if !(p.unload_rate.is_finite() && p.unload_rate >= 0.0) {
            return Err(InvalidOption::new(
                "--unload-rate",
                format!("must be finite and >= 0, got {}", p.unload_rate),
            ));
        }
        // As long as the compression at the most: a rate too slow would
        // make a run without end.
        if p.unload_rate > 0.0 && p.unload_rate < p.rate_start {
            return Err(InvalidOption::new(
                "--unload-rate",
                format!(
                    "must be 0 or at least --rate-start ({}), got {}",
                    p.rate_start, p.unload_rate
                ),
            ));
        }
        if p.rate_levels == 0 {
            return Err(InvalidOption::new("--rate-levels", "must be at least 1"));
        }
        if !(p.volumetric_strain > 0.0 && p.volumetric_strain < 0.95) {
            return Err(InvalidOption::new(
                "--volumetric-strain",
                format!("must be in (0, 0.95), got {}", p.volumetric_strain),
            ));
        }
        let stages = p.rates().len();
        if stages > 1000 {
            return Err(InvalidOption::new(
                "--stage-time",
                format!("{stages} compression stages are needed to reach the strain: raise --stage-time or --rate-end"),
            ));
        }
        if p.states_per_stage == 0 {
            return Err(InvalidOption::new(
                "--states-per-stage",
                "must be at least 1",
            ));
        }
        if !(self.a_b.is_finite() && self.a_b > -1.0) {
            return Err(InvalidOption::new(
                "--a-b",
                format!("must be finite and above -1 (k d), got {}", self.a_b),
            ));
        }
        if p.states_per_stage > 1000 {
            return Err(InvalidOption::new(
                "--states-per-stage",
                format!(
                    "at most 1000 (every state is kept in memory), got {}",
                    p.states_per_stage
                ),
            ));
        }
        if self.seeds.is_empty() {
            return Err(InvalidOption::new("--seeds", "needs at least one value"));
        }
        if let Some(dem) = &self.dem {
            dem.validate()?;
            if dem.multicontact.is_some() && matches!(self.engine, CompactionEngine::Lammps { .. })
            {
                return Err(InvalidOption::new(
                    "--closure",
                    "runs in the native engine only: LAMMPS has no multi-contact closure (use --engine native)",
                ));
            }
            if self.zero_net {
                return Err(InvalidOption::new(
                    "--zero-net",
                    "is a bonded-grain option; DEM spheres have no multibody term",
                ));
            }
            if self.moduli.states > 0 {
                return Err(InvalidOption::new(
                    "--moduli-states",
                    "must be 0 with --model dem: a modulus run restarts from a recorded state, which keeps positions but not the contacts' friction history",
                ));
            }
        }
        if let Some(failure) = &self.bond_failure {
            let option = "--critical-strain, --plastic-strain";
            failure
                .check()
                .map_err(|e| InvalidOption::new(option, e.to_string()))?;
            if self.dem.is_some() {
                return Err(InvalidOption::new(
                    option,
                    "are bonded-grain options: DEM spheres have no bonds",
                ));
            }
            if self.zero_net {
                return Err(InvalidOption::new(
                    "--zero-net",
                    "does not combine with bonds that break or yield",
                ));
            }
            if matches!(self.engine, CompactionEngine::Lammps { .. }) {
                return Err(InvalidOption::new(
                    option,
                    "run in the native engine only: the harness's LAMMPS runs do not record \
                     broken bonds (use --engine native)",
                ));
            }
            if self.moduli.states > 0 {
                return Err(InvalidOption::new(
                    "--moduli-states",
                    "must be 0 with bonds that break or yield: a modulus run restarts from \
                     a recorded state with every bond intact and elastic",
                ));
            }
        }
        if self.overlay_pair {
            let refuse = |why: &str| Err(InvalidOption::new("--overlay-pair", why.to_string()));
            if self.dem.is_some() {
                return refuse("is a bonded-grain option: DEM spheres have no bonds");
            }
            if matches!(self.engine, CompactionEngine::Lammps { .. }) {
                return refuse(
                    "runs in the native engine only: the harness's LAMMPS runs exclude bonded \
                     pairs from contact (use --engine native)",
                );
            }
            if self.moduli.states > 0 {
                return refuse(
                    "needs --moduli-states 0: the modulus runs use the packing's own force \
                     field, without the overlay",
                );
            }
        }
        if self.moduli.states > 0 {
            let m = &self.moduli.protocol;
            positive("--moduli-relax-time", m.relax_time)?;
            positive("--moduli-rate", m.compression_rate)?;
            // Not command-line options: a scripted protocol can set them.
            positive("moduli shear_rate", m.shear_rate)?;
            if m.rows < 3 {
                return Err(InvalidOption::new(
                    "moduli rows",
                    "at least 3 rows are needed to fit a modulus with its error",
                ));
            }
            let small = |v: f64| v > 0.0 && v < 0.1;
            if !(small(m.volumetric_strain) && small(m.shear_strain)) {
                return Err(InvalidOption::new(
                    "moduli volumetric_strain and shear_strain",
                    "must be small and positive (below 0.1)",
                ));
            }
        }
        if self.analysis.mc_points < 1000 {
            return Err(InvalidOption::new("--mc-points", "must be at least 1000"));
        }
        if let CompactionEngine::Lammps { ranks } = self.engine {
            crate::options::validate_threads(ranks)
                .map_err(|_| InvalidOption::new("--ranks", "must be at least 1"))?;
        }
        match &self.source {
            PackingSource::Build {
                grains,
                radius,
                distinct_grains,
                template_fraction,
                time_scale,
                ..
            } => {
                if *grains < 2 {
                    return Err(InvalidOption::new("--grains", "must be at least 2"));
                }
                if !(radius.is_finite() && *radius >= 1.5) {
                    return Err(InvalidOption::new(
                        "--radius",
                        format!("must be at least 1.5 (d), got {radius}"),
                    ));
                }
                if *distinct_grains == 0 {
                    return Err(InvalidOption::new(
                        "--distinct-grains",
                        "must be at least 1",
                    ));
                }
                let max = crate::scene::builders::packing::MAX_TEMPLATE_FRACTION;
                if !(*template_fraction > 0.0 && *template_fraction <= max) {
                    return Err(InvalidOption::new(
                        "--template-fraction",
                        format!("must be in (0, {max}], got {template_fraction}"),
                    ));
                }
                positive("--time-scale", *time_scale)?;
            }
            PackingSource::File { path } => {
                if self.seeds.len() > 1 {
                    return Err(InvalidOption::new(
                        "--seeds",
                        "one seed with --packing: the file is the packing, so more seeds would repeat the same run",
                    ));
                }
                if !path.is_file() {
                    return Err(InvalidOption::new(
                        "--packing",
                        format!("{} is not a readable file", path.display()),
                    ));
                }
            }
        }
        Ok(())
    }

    fn force_field(&self) -> ForceField {
        let mut ff = ForceField::paper(self.a_b);
        ff.zero_net_multibody = self.zero_net;
        ff
    }

    /// The compaction scene of `packing`: the protocol's stages, with the
    /// bonds' failure rule if they break or yield.
    fn scene(&self, packing: &Scene) -> Scene {
        let mut scene = compaction_scene(packing, &self.protocol);
        scene.force_field.bond_failure = self.bond_failure;
        scene.force_field.overlay_pair = self.overlay_pair;
        scene
    }
}

/// One recorded state of a run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StateRow {
    /// Stage name.
    pub stage: String,
    /// Compression rate of the stage (1/tau; 0 while jamming).
    pub rate: f64,
    /// Global step.
    pub step: u64,
    /// Time (tau).
    pub time: f64,
    /// Pressure, virial and kinetic (k/d).
    pub pressure: f64,
    /// Pressure over E_eff.
    pub p_over_e_eff: f64,
    /// Kinetic energy per particle (k d^2).
    pub ke_per_particle: f64,
    /// The packing measurements.
    #[serde(flatten)]
    pub packing: PackingState,
    /// How far the grains have come apart, when bonds break.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fragments: Option<GrainFragments>,
}

/// The thermo series of a run, every recorded row.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RunSeries {
    /// Time (tau).
    pub time: Vec<f64>,
    /// Box volume (d^3).
    pub box_volume: Vec<f64>,
    /// Pressure (k/d).
    pub pressure: Vec<f64>,
    /// Kinetic energy per particle.
    pub ke_per_particle: Vec<f64>,
}

/// A coordination power law and its `Z_c`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct CoordinationFit {
    /// `Z - Z_c = B (phi - phi_c)^gamma`.
    pub law: PowerLaw,
    /// The fitted `Z_c`.
    pub z_c: f64,
}

/// The power laws of one run near jamming (analysis::jamming): `phi_c`
/// from the pressure, then the others at that `phi_c`, each over
/// `phi - phi_c <= FIT_WINDOW` on the jammed compression states
/// ([`is_jammed`]).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RunFits {
    /// `P / E_eff` against `phi_MC`, `phi_c` fitted.
    pub pressure: Option<PowerLaw>,
    /// `Z_force - Z_c`.
    pub z_force: Option<CoordinationFit>,
    /// `Z_geometry - Z_c`.
    pub z_geometry: Option<CoordinationFit>,
    /// Mean grain volumetric strain.
    pub eps_v: Option<PowerLaw>,
    /// Mean `alpha - alpha0`.
    pub asphericity: Option<PowerLaw>,
    /// Where the pressure leaves its power law for good: the smallest
    /// `phi - phi_c` from which every state's `P` exceeds the law by
    /// [`DEPARTURE_FACTOR`] (paper: near 0.1).
    #[serde(default)]
    pub pressure_departure: Option<f64>,
    /// The packing's bulk modulus `K_P / E_eff` (reliable measurements
    /// only, see [`PackingModuli::bulk_is_reliable`]; likewise for `G_P`).
    #[serde(default)]
    pub bulk_modulus: Option<PowerLaw>,
    /// The packing's shear modulus `G_P / E_eff`.
    #[serde(default)]
    pub shear_modulus: Option<PowerLaw>,
}

/// Largest `phi - phi_c` of the power-law fits: the paper finds them to
/// hold up to about 0.1.
pub const FIT_WINDOW: f64 = 0.1;

/// Whether a state is a compression state with a contact network (some
/// grain keeps three or more force contacts once rattlers are removed):
/// below jamming the pressure is kinetic and transient, and a power law in
/// `phi - phi_c` means nothing.
pub fn is_jammed(state: &StateRow) -> bool {
    state.stage.starts_with("compress") && state.packing.z_force > 0.0
}

/// How far above its power law the pressure must lie to count as having
/// left it.
pub const DEPARTURE_FACTOR: f64 = 1.25;

/// The fits of a run's compression states and of the moduli measured at
/// some of them (`e_eff` normalises the moduli).
pub fn fit_run(states: &[StateRow], moduli: &[StateModuli], e_eff: f64) -> RunFits {
    let compressed: Vec<&StateRow> = states.iter().filter(|s| is_jammed(s)).collect();
    let phi: Vec<f64> = compressed.iter().map(|s| s.packing.phi_mc).collect();
    let of = |f: &dyn Fn(&StateRow) -> f64| compressed.iter().map(|s| f(s)).collect::<Vec<f64>>();
    let Some(pressure) =
        power_law_with_jamming_point(&phi, &of(&|s| s.p_over_e_eff), FIT_WINDOW, 0.05, 5)
    else {
        return RunFits::default();
    };
    let phi_c = pressure.phi_c;
    let modulus_law = |reliable: fn(&PackingModuli) -> bool, f: fn(&PackingModuli) -> f64| {
        let (x, y): (Vec<f64>, Vec<f64>) = moduli
            .iter()
            .filter(|m| reliable(&m.moduli))
            .map(|m| (m.phi_mc, f(&m.moduli) / e_eff))
            .unzip();
        power_law_at(&x, &y, phi_c, FIT_WINDOW)
    };
    let z = |f: &dyn Fn(&StateRow) -> f64| {
        coordination_law(&phi, &of(f), phi_c, FIT_WINDOW, 5)
            .map(|(law, z_c)| CoordinationFit { law, z_c })
    };
    RunFits {
        pressure: Some(pressure),
        pressure_departure: departure(&phi, &of(&|s| s.p_over_e_eff), &pressure, DEPARTURE_FACTOR),
        z_force: z(&|s| s.packing.z_force),
        z_geometry: z(&|s| s.packing.z_geometry),
        eps_v: power_law_at(&phi, &of(&|s| s.packing.eps_v_mean), phi_c, FIT_WINDOW),
        asphericity: power_law_at(
            &phi,
            &of(&|s| s.packing.asphericity_excess_mean),
            phi_c,
            FIT_WINDOW,
        ),
        bulk_modulus: modulus_law(PackingModuli::bulk_is_reliable, |m| m.bulk),
        shear_modulus: modulus_law(PackingModuli::shear_is_reliable, |m| m.shear),
    }
}

/// One packing compressed in one engine.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CompactionRun {
    /// Seed of the packing (and of its run).
    pub seed: u64,
    /// Grains.
    pub grains: usize,
    /// Particles.
    pub particles: usize,
    /// How the packing was built (absent for a file).
    pub packing: Option<PackingSummary>,
    /// Linear expansion that broke the packing's contacts (1 = none).
    pub expansion: f64,
    /// Wall-clock seconds of the run (engine only).
    pub run_seconds: f64,
    /// Wall-clock seconds of the analysis of its states.
    pub analysis_seconds: f64,
    /// Why the run stopped early or a state could not be measured, if so;
    /// the native engine keeps the states up to there, a failed LAMMPS run
    /// returns none.
    pub stopped: Option<String>,
    /// Thermo series.
    pub series: RunSeries,
    /// Recorded states: the stress-free packing first, then every checkpoint.
    pub states: Vec<StateRow>,
    /// The packing's elastic moduli at some states.
    #[serde(default)]
    pub moduli: Vec<StateModuli>,
    /// Why a state's moduli could not be measured, if so.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub moduli_failures: Vec<String>,
    /// Power laws near jamming.
    #[serde(default)]
    pub fits: RunFits,
    /// The run's folder (scene, data file).
    pub folder: String,
}

/// What `bpm compact` writes to `compaction.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CompactionReport {
    /// bpm version.
    pub version: String,
    /// The command line.
    pub command: String,
    /// The options.
    pub options: CompactOptions,
    /// E_eff (k/d) that normalises the pressure, and its constants.
    pub e_eff: f64,
    /// K and nu behind E_eff.
    pub moduli: Moduli,
    /// The compression stages' rates (1/tau), in order.
    pub rates: Vec<f64>,
    /// What the run's reader should know (e.g. a known flaw of the engine
    /// for these options).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Threads of the run: a built packing depends on them (absent in
    /// reports of versions that did not record it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threads: Option<usize>,
    /// One run per seed.
    pub runs: Vec<CompactionRun>,
}

/// Unwraps the grains of a packing read from a file through its bonds, so
/// each grain is whole whatever image flags the file had.
fn whole_grains(scene: &mut Scene) -> Result<(), CompactionError> {
    let grain = scene
        .particles
        .grain
        .clone()
        .ok_or_else(|| CompactionError::Packing("the data file has no molecule ids".into()))?;
    let simbox = simbox_of(scene);
    let grains = crate::analysis::packing::Grains::from_bonds(
        &simbox,
        &scene.particles.positions,
        &grain,
        &scene.bonds.pairs,
    )
    .map_err(|e| CompactionError::Packing(e.to_string()))?;
    for (members, positions) in grains.members.iter().zip(&grains.positions) {
        for (&i, x) in members.iter().zip(positions) {
            scene.particles.positions[i] = *x;
        }
    }
    Ok(())
}

/// The packing of `seed`, built or read and made contact-free: bonded
/// grains, or DEM spheres when `opts.dem` is set (`moduli` gives their
/// material). Returns the scene, the build's summary (none for a file) and
/// the linear expansion that made it contact-free.
fn packing(
    opts: &CompactOptions,
    moduli: &Moduli,
    seed: u64,
    threads: usize,
) -> Result<(Scene, Option<PackingSummary>, f64), CompactionError> {
    let packing_error = |e: SceneError| CompactionError::Packing(e.to_string());
    match &opts.source {
        PackingSource::Build {
            grains,
            kind,
            radius,
            distinct_grains,
            template_fraction,
            time_scale,
        } => {
            let mut p = PackingParams::new(*grains, *kind, *radius, opts.a_b, seed);
            p.distinct_grains = *distinct_grains;
            p.template_fraction = *template_fraction;
            p.grain.time_scale = *time_scale;
            let (scene, summary) = match &opts.dem {
                None => {
                    let (mut scene, summary) =
                        build_packing(&p, threads, false).map_err(packing_error)?;
                    scene.force_field = opts.force_field();
                    (scene, summary)
                }
                Some(dem) => {
                    // The rolling and twisting springs depend on the
                    // spheres' radius and mass, known once they are built.
                    let placeholder = dem.material_of(moduli, 1.0, 1.0);
                    let (mut scene, summary) =
                        build_sphere_packing(&p, placeholder, threads, false)
                            .map_err(packing_error)?;
                    let material = dem.material_of(
                        moduli,
                        summary.template_radius,
                        scene.particles.mass.mean(),
                    );
                    scene.force_field = dem.force_field(material);
                    (scene, summary)
                }
            };
            let expansion = summary.expansion;
            Ok((scene, Some(summary), expansion))
        }
        PackingSource::File { path } => {
            let mut scene = read_packing_file(path, opts, moduli, seed)?;
            let expansion = match &opts.dem {
                None => {
                    whole_grains(&mut scene)?;
                    break_contacts(&mut scene).map_err(packing_error)?
                }
                Some(dem) => {
                    let radius = uniform_radius(&scene).ok_or_else(|| {
                        CompactionError::Packing(format!(
                            "{}: the spheres differ in radius; the packing analysis measures spheres of one radius",
                            path.display()
                        ))
                    })?;
                    let material = dem.material_of(moduli, radius, scene.particles.mass.mean());
                    scene.force_field = dem.force_field(material);
                    separate_spheres(&mut scene).map_err(packing_error)?
                }
            };
            Ok((scene, None, expansion))
        }
    }
}

/// Reads a packing data file of the model `opts` asks for (bonded grains,
/// or spheres with `opts.dem`); a file of the other model, or with a
/// tilted box, is refused with a message that says so.
fn read_packing_file(
    path: &Path,
    opts: &CompactOptions,
    moduli: &Moduli,
    seed: u64,
) -> Result<Scene, CompactionError> {
    let spheres = ForceField::dem(DemContact::default().material_of(moduli, 1.0, 1.0));
    let (wanted, other) = match opts.dem {
        None => (opts.force_field(), spheres),
        Some(_) => (spheres, opts.force_field()),
    };
    let scene = read_data_file(path, [true; 3], wanted, seed).map_err(|e| {
        let message = match read_data_file(path, [true; 3], other, seed) {
            Ok(_) if opts.dem.is_some() => format!(
                "{}: this file holds bonded grains (atom_style bond); --model dem needs spheres (atom_style sphere)",
                path.display()
            ),
            Ok(_) => format!(
                "{}: this file holds DEM spheres (atom_style sphere); compact them with --model dem",
                path.display()
            ),
            Err(_) => e.to_string(),
        };
        CompactionError::Packing(message)
    })?;
    if scene.simbox.tilt.iter().any(|&t| t != 0.0) {
        return Err(CompactionError::Packing(format!(
            "{}: the box is tilted; compaction needs an orthogonal periodic box",
            path.display()
        )));
    }
    Ok(scene)
}

/// Grains of a packing (a DEM sphere is a grain).
fn grain_count(packing: &Scene) -> usize {
    match &packing.particles.grain {
        _ if packing.model == ModelKind::Dem => packing.particles.positions.len(),
        Some(g) => g.iter().max().map_or(0, |m| *m as usize + 1),
        None => 0,
    }
}

/// The spheres' common radius, if they have one (to 1e-12 relative).
fn uniform_radius(scene: &Scene) -> Option<f64> {
    let radii = scene.particles.radius.as_deref()?;
    let r = *radii.first()?;
    radii
        .iter()
        .all(|&x| (x - r).abs() <= 1e-12 * r)
        .then_some(r)
}

fn simbox_of_checkpoint(c: &Checkpoint, periodic: [bool; 3]) -> SimBox {
    SimBox {
        lo: c.simbox[0],
        lengths: c.simbox[1],
        tilt: c.simbox[2],
        periodic,
    }
}

fn column(stage: &StageOutput, name: &str) -> Vec<f64> {
    stage.column(name).unwrap_or_default()
}

/// Runs a scene in the chosen engine (LAMMPS's files are `folder/tag.*`;
/// a native run is checkpointed as the study's part `key`).
fn run_engine(
    scene: &Scene,
    engine: &CompactionEngine,
    folder: &Path,
    tag: &str,
    key: &str,
    runtime: &StudyRuntime,
    bpm: Option<&Path>,
) -> Result<EngineRun, CompactionError> {
    let start = std::time::Instant::now();
    Ok(match engine {
        CompactionEngine::Native => {
            let outcome = runtime.run_scene(key, scene)?;
            (
                outcome.stages,
                outcome.error.map(|e| e.to_string()),
                outcome.wall_seconds,
            )
        }
        CompactionEngine::Lammps { ranks } => {
            let Some(bpm) = bpm else {
                return Ok((
                    Vec::new(),
                    Some("no bpm executable to run LAMMPS with".into()),
                    0.0,
                ));
            };
            let launcher = LammpsLauncher {
                bpm: bpm.to_path_buf(),
                dir: folder.to_path_buf(),
            };
            match launcher.run(scene, tag, *ranks, true) {
                Ok(run) => (run.stages, None, run.seconds),
                Err(e) => (
                    Vec::new(),
                    Some(e.to_string()),
                    start.elapsed().as_secs_f64(),
                ),
            }
        }
    })
}

/// A run's stages (those done, the last possibly partial), its stop
/// message if any, and its wall-clock seconds.
type EngineRun = (Vec<StageOutput>, Option<String>, f64);

/// How the states of a packing are measured.
enum Meter {
    /// Bonded grains, against their stress-free shapes.
    Grains {
        /// Grain of each particle.
        grain: Vec<u32>,
        /// The stress-free packing's grains.
        reference: Reference,
    },
    /// DEM spheres of one radius.
    Spheres {
        /// Their radius.
        radius: f64,
    },
}

impl Meter {
    /// The meter of `packing`'s particle model; fails, naming the grain,
    /// when a grain's stress-free shape cannot be measured (fewer than four
    /// particles, flat or collinear ones).
    fn of(packing: &Scene, analysis: &AnalysisOptions) -> Result<Self, CompactionError> {
        if packing.model == ModelKind::Dem {
            let radius = uniform_radius(packing)
                .ok_or_else(|| CompactionError::Packing("the spheres differ in radius".into()))?;
            return Ok(Self::Spheres { radius });
        }
        let grain = packing.particles.grain.clone().unwrap_or_default();
        let simbox = simbox_of(packing);
        let start = Snapshot {
            simbox: &simbox,
            positions: &packing.particles.positions,
            grain: &grain,
            bonds: &packing.bonds.pairs,
        };
        let reference =
            reference_of(&start, analysis).map_err(CompactionError::analysing("the packing"))?;
        Ok(Self::Grains { grain, reference })
    }

    /// The state of `packing`'s particles at `positions` in `simbox`.
    fn measure(
        &self,
        packing: &Scene,
        simbox: &SimBox,
        positions: &[[f64; 3]],
        analysis: &AnalysisOptions,
    ) -> Result<PackingState, crate::analysis::packing::PackingError> {
        match self {
            Self::Grains { grain, reference } => {
                let snap = Snapshot {
                    simbox,
                    positions,
                    grain,
                    bonds: &packing.bonds.pairs,
                };
                analyse(&snap, reference, analysis)
            }
            Self::Spheres { radius } => analyse_spheres(simbox, positions, *radius, analysis),
        }
    }
}

/// Measures the stress-free packing and every checkpoint of `stages`; a
/// state that cannot be measured ends the list, and its error is returned
/// beside the states before it.
fn states_of(
    scene: &Scene,
    meter: &Meter,
    stages: &[StageOutput],
    opts: &CompactOptions,
    e_eff: f64,
    rates: &[f64],
) -> Result<(Vec<StateRow>, RunSeries, Option<String>), CompactionError> {
    let n = scene.particles.positions.len() as f64;
    let simbox = simbox_of(scene);
    let mut rows = vec![StateRow {
        stage: "start".into(),
        rate: 0.0,
        step: 0,
        time: 0.0,
        pressure: 0.0,
        p_over_e_eff: 0.0,
        ke_per_particle: 0.0,
        packing: meter
            .measure(scene, &simbox, &scene.particles.positions, &opts.analysis)
            .map_err(CompactionError::analysing("the packing"))?,
        fragments: fragments_of(scene, opts, &[]),
    }];
    let mut series = RunSeries::default();
    let mut failed = None;
    for (k, stage) in stages.iter().enumerate() {
        let steps = column(stage, "step");
        let time = column(stage, "time");
        let pressure = column(stage, "pressure");
        let ke = column(stage, "e_kinetic");
        let [lx, ly, lz] = ["lx", "ly", "lz"].map(|c| column(stage, c));
        for r in 0..steps.len() {
            // A stage's first row repeats the previous stage's last step,
            // with forces recomputed after that step's box change (one
            // step's affine strain, unrelaxed): keep the earlier row.
            if k > 0 && r == 0 {
                continue;
            }
            series.time.push(time[r]);
            series.box_volume.push(lx[r] * ly[r] * lz[r]);
            series.pressure.push(pressure[r]);
            series.ke_per_particle.push(ke[r] / n);
        }
        let rate = if k == 0 {
            0.0
        } else {
            rates.get(k - 1).copied().unwrap_or(0.0)
        };
        for c in &stage.checkpoints {
            let Some(r) = steps.iter().position(|&s| s as u64 == c.step) else {
                continue;
            };
            // Stage 0's first checkpoint is the start, measured above.
            if r == 0 {
                continue;
            }
            if failed.is_some() {
                break;
            }
            let cbox = simbox_of_checkpoint(c, scene.simbox.periodic);
            let packing = match meter.measure(scene, &cbox, &c.positions, &opts.analysis) {
                Ok(p) => p,
                Err(e) => {
                    failed = Some(format!(
                        "analysing stage {} step {}: {e} (states from there on are not measured)",
                        stage.name, c.step
                    ));
                    break;
                }
            };
            rows.push(StateRow {
                stage: stage.name.clone(),
                rate,
                step: c.step,
                time: time[r],
                pressure: pressure[r],
                p_over_e_eff: pressure[r] / e_eff,
                ke_per_particle: ke[r] / n,
                packing,
                fragments: fragments_of(scene, opts, &c.broken_bonds),
            });
        }
    }
    Ok((rows, series, failed))
}

/// A warning, if some grains of the run came apart: the grain measures
/// take each grain as one body.
fn pieces_warning(seed: u64, states: &[StateRow]) -> Option<String> {
    let first = states
        .iter()
        .find(|s| s.fragments.is_some_and(|f| f.whole_grains < 1.0))?;
    Some(format!(
        "seed {seed}: from P/E_eff = {:.2e} (phi_MC {:.4}, stage {}) on, some grains are in \
         pieces; phi_MC, Z, eps_V and the asphericity take each grain as one body (its \
         particles' convex hull), which a grain in pieces is not: read them as the grains' \
         extent, not their shape",
        first.p_over_e_eff, first.packing.phi_mc, first.stage
    ))
}

/// The grains' fragments with `broken` bonds broken, when bonds break.
fn fragments_of(
    scene: &Scene,
    opts: &CompactOptions,
    broken: &[[usize; 2]],
) -> Option<GrainFragments> {
    opts.bond_failure.filter(|f| f.breaks)?;
    let grain = scene.particles.grain.as_deref()?;
    Some(GrainFragments::of(
        grain,
        grain_count(scene),
        &scene.bonds.pairs,
        broken,
    ))
}

/// The checkpoint of a measured state.
fn checkpoint_of<'a>(stages: &'a [StageOutput], row: &StateRow) -> Option<&'a Checkpoint> {
    stages
        .iter()
        .filter(|s| s.name == row.stage)
        .flat_map(|s| &s.checkpoints)
        .find(|c| c.step == row.step)
}

/// Writes the slice picture of a run: the stress-free packing, the last
/// state of the jam and the last state measured.
fn write_slices(
    packing: &Scene,
    stages: &[StageOutput],
    states: &[StateRow],
    path: &Path,
) -> Result<(), CompactionError> {
    // A DEM sphere is its own grain, drawn at its diameter.
    let (grain, diameter) = match uniform_radius(packing) {
        Some(r) if packing.model == ModelKind::Dem => (
            (0..packing.particles.positions.len() as u32).collect(),
            2.0 * r,
        ),
        _ => (
            packing.particles.grain.clone().unwrap_or_default(),
            packing.force_field.pair.as_ref().map_or(1.0, |p| p.d),
        ),
    };
    let start_box = simbox_of(packing);
    let caption = |what: &str, s: &StateRow| {
        format!(
            "{what}: phi_MC {:.3}, P/E_eff {:.1e}",
            s.packing.phi_mc, s.p_over_e_eff
        )
    };
    let mut boxes = Vec::new();
    let mut picked = Vec::new();
    let jammed = states.iter().rev().find(|s| s.stage == "jam");
    let last = states
        .last()
        .filter(|s| s.stage != "start" && s.stage != "jam");
    for (what, row) in [("jammed", jammed), ("end", last)] {
        let Some(row) = row else { continue };
        if let Some(c) = checkpoint_of(stages, row) {
            boxes.push(simbox_of_checkpoint(c, packing.simbox.periodic));
            picked.push((caption(what, row), &c.positions));
        }
    }
    let mut frames = vec![SliceFrame {
        title: states
            .first()
            .map_or("start".into(), |s| caption("start", s)),
        simbox: &start_box,
        positions: &packing.particles.positions,
        grain: &grain,
    }];
    for ((title, positions), simbox) in picked.into_iter().zip(&boxes) {
        frames.push(SliceFrame {
            title,
            simbox,
            positions,
            grain: &grain,
        });
    }
    crate::analysis::slice::write_slices(path, &frames, diameter)?;
    Ok(())
}

/// Runs the study: for each seed a packing, its compaction in the chosen
/// engine and the analysis of its states; writes `compaction.json`, the
/// plots and each run's scene and data file into `dir` as it goes.
/// `bpm` is this program's executable (needed for the LAMMPS engine).
///
/// With a checkpoint in `runtime`, each seed's packing, run and moduli
/// measurements are kept in it as they finish, and the native run under
/// way is checkpointed into it: the same call with the checkpoint resumed
/// takes what is kept and continues the run where it stopped, and ends
/// with the same report.
pub fn run_compaction(
    opts: &CompactOptions,
    runtime: &StudyRuntime,
    bpm: Option<&Path>,
    dir: &Path,
    command: &str,
    print: &mut dyn FnMut(&str),
) -> Result<CompactionReport, CompactionError> {
    let threads = runtime.threads;
    opts.validate()?;
    std::fs::create_dir_all(dir).map_err(FileError::on("creating", dir))?;
    let moduli = Moduli::paper_fits(opts.a_b);
    let e_eff = effective_modulus(moduli.k, moduli.nu);
    let mut report = CompactionReport {
        version: crate::VERSION.into(),
        command: command.into(),
        options: opts.clone(),
        e_eff,
        moduli,
        rates: opts.protocol.rates(),
        warnings: Vec::new(),
        threads: Some(threads),
        runs: Vec::new(),
    };
    if let (Some(dem), CompactionEngine::Lammps { .. }) = (&opts.dem, &opts.engine) {
        if dem.friction[1] > 0.0 || dem.friction[2] > 0.0 {
            let warning = "LAMMPS negates every history value of a contact when a neighbour-list rebuild swaps the pair's order, which is wrong for the rolling and twisting springs (docs/model.md); this run's rolling and twisting friction inherits that";
            print(&format!("warning: {warning}"));
            report.warnings.push(warning.into());
        }
    }
    for &seed in &opts.seeds {
        let folder = dir.join(format!("seed-{seed}"));
        std::fs::create_dir_all(&folder).map_err(FileError::on("creating", &folder))?;
        let (packing, summary, expansion) = runtime
            .part(&format!("seed-{seed}/packing"), || {
                packing(opts, &report.moduli, seed, threads)
            })?;
        // Every grain must have a hull before hours of running, not after.
        let meter = Meter::of(&packing, &opts.analysis)?;
        // Built DEM spheres are separated by far less (below 1e-8).
        if expansion > 1.0 + 1e-6 {
            print(&format!(
                "seed {seed}: the box was expanded by {expansion:.4} (linear) to give the grains room"
            ));
        }
        let data = folder.join("packing.data");
        crate::whole_file::write_whole(&data, write_data_file(&packing).as_bytes())?;
        let scene = opts.scene(&packing);
        let scene_path = folder.join("scene.json");
        write_scene(&scene_path, &scene).map_err(|e| CompactionError::Packing(e.to_string()))?;
        print(&format!(
            "seed {seed}: {} grains, {} particles, box {:.2} d; running {} steps ({} stages)",
            grain_count(&packing),
            packing.particles.positions.len(),
            packing.simbox.lengths[0],
            scene.stages.iter().map(|s| s.steps).sum::<u64>(),
            scene.stages.len()
        ));
        let key = format!("seed-{seed}/run");
        let (stages, stopped, run_seconds) = runtime.part(&key, || {
            run_engine(&scene, &opts.engine, &folder, "lammps", &key, runtime, bpm)
        })?;
        if let Some(m) = &stopped {
            print(&format!("seed {seed}: the run stopped: {m}"));
        }
        let t = std::time::Instant::now();
        let (states, series, unmeasured) =
            states_of(&packing, &meter, &stages, opts, e_eff, &report.rates)?;
        let stopped = match (stopped, unmeasured) {
            (Some(a), Some(b)) => Some(format!("{a}; {b}")),
            (a, b) => a.or(b),
        };
        if let Some(warning) = pieces_warning(seed, &states) {
            print(&format!("warning: {warning}"));
            report.warnings.push(warning);
        }
        report.runs.push(CompactionRun {
            seed,
            grains: grain_count(&packing),
            particles: packing.particles.positions.len(),
            packing: summary,
            expansion,
            run_seconds,
            analysis_seconds: t.elapsed().as_secs_f64(),
            stopped,
            series,
            moduli: Vec::new(),
            moduli_failures: Vec::new(),
            fits: fit_run(&states, &[], e_eff),
            states,
            folder: folder.display().to_string(),
        });
        write_report(&report, dir)?;
        // A picture that cannot be drawn costs only the picture.
        let measured = report.runs.last().map_or(&[][..], |r| &r.states);
        if let Err(e) = write_slices(&packing, &stages, measured, &folder.join("slices.svg")) {
            print(&format!(
                "seed {seed}: the slice picture was not written: {e}"
            ));
        }
        // The loading's last state; an unloading's is in the table.
        let last = report.runs.last().and_then(|r| {
            r.states
                .iter()
                .rev()
                .find(|s| s.stage.starts_with("compress"))
        });
        if let Some(s) = last {
            let mut shape = if opts.dem.is_some() {
                format!("phi_sphere = {:.4}", s.packing.phi_sphere)
            } else {
                format!("eps_V = {:.3}", s.packing.eps_v_mean)
            };
            if let Some(f) = s.fragments {
                shape += &format!(
                    ", {:.2}% of the bonds broken, {:.1}% of the grains whole",
                    100.0 * f.broken_fraction,
                    100.0 * f.whole_grains
                );
            }
            print(&format!(
                "seed {seed}: {run_seconds:.0} s; last loaded state phi_MC = {:.4}, P/E_eff = {:.3e}, Z_force = {:.2}, {shape}",
                s.packing.phi_mc, s.p_over_e_eff, s.packing.z_force
            ));
        }
        let last = report.runs.len() - 1;
        let picked = pick_states(
            &report.runs[last].states,
            report.runs[last].fits.pressure.map(|p| p.phi_c),
            opts.moduli.states,
        );
        // Keyed by the protocol too: a study resumed with another
        // protocol measures anew (`checkpoint_identity`).
        let protocol = serde_json::to_string(&opts.moduli.protocol).unwrap_or_default();
        let key_of = |step: u64| format!("seed-{seed}/moduli-{step}/{protocol}");
        if let Some(checkpoint) = &runtime.checkpoint {
            // The kept steps of a measurement left unfinished by a study
            // now resumed with other moduli options are not read again:
            // drop them rather than write them at every checkpoint.
            let measuring: Vec<String> = picked
                .iter()
                .map(|&i| runtime.key_in_checkpoint(&key_of(report.runs[last].states[i].step)))
                .collect();
            let moduli = runtime.key_in_checkpoint(&format!("seed-{seed}/moduli-"));
            checkpoint.drop_parts(|k| {
                k.starts_with(&moduli)
                    && k.rsplit_once('/').is_some_and(|(parent, step)| {
                        moduli::KEPT_STEPS.contains(&step) && !measuring.iter().any(|m| m == parent)
                    })
            });
        }
        for (k, &i) in picked.iter().enumerate() {
            let run = &mut report.runs[last];
            let row = run.states[i].clone();
            let Some(checkpoint) = checkpoint_of(&stages, &row) else {
                continue;
            };
            let key = key_of(row.step);
            // A state's runs are kept in the study's checkpoint as they go,
            // under the state's key (`moduli::run_all`).
            let scoped = runtime.scoped(&key);
            let measured = runtime.part(&key, || {
                let measured = moduli::measure_state(
                    &packing,
                    checkpoint,
                    &opts.moduli.protocol,
                    &opts.engine,
                    &folder,
                    bpm,
                    &scoped,
                );
                // A LAMMPS run under way does not see a stop; one killed
                // with the study fails, and is run again rather than the
                // state kept as a failure (a real failure recurs on
                // resume). Its finished runs are kept (`moduli::run_all`).
                let asked = runtime.checkpoint.as_ref().filter(|c| c.stop_requested());
                match (measured, asked) {
                    (Err(moduli::MeasureStop::Stopped(stop)), _) => {
                        Err(CompactionError::from(stop))
                    }
                    (Err(_), Some(checkpoint)) => Err(CompactionError::from(
                        StudyStop::Interrupted(checkpoint.path()),
                    )),
                    (other, _) => Ok(other.map_err(|e| e.to_string())),
                }
            })?;
            match measured {
                Ok(moduli) => {
                    let m = StateModuli {
                        stage: row.stage.clone(),
                        step: row.step,
                        phi_mc: row.packing.phi_mc,
                        p_over_e_eff: row.p_over_e_eff,
                        moduli,
                    };
                    print(&format!(
                        "seed {seed}: moduli {}/{} at phi_MC = {:.4}: K_P/E_eff = {:.3e}, G_P/E_eff = {:.3e}, nu_P = {:.3} ({:.0} s)",
                        k + 1,
                        picked.len(),
                        m.phi_mc,
                        m.moduli.bulk / e_eff,
                        m.moduli.shear / e_eff,
                        m.moduli.poisson,
                        m.moduli.seconds
                    ));
                    run.moduli.push(m);
                }
                Err(e) => {
                    let message = format!("moduli at step {}: {e}", row.step);
                    print(&format!("seed {seed}: {message}"));
                    run.moduli_failures.push(message);
                }
            }
            run.fits = fit_run(&run.states, &run.moduli, e_eff);
            write_report(&report, dir)?;
        }
    }
    Ok(report)
}

pub mod cli;
pub mod compare;
pub mod dem;
mod dump;
pub mod moduli;
mod report;

pub use dem::{youngs_modulus, DemContact};
pub use dump::{analyse_dump, DumpAnalysis, FrameState};
pub use moduli::{pick_states, ModuliOptions, PackingModuli, StateModuli};
pub use report::{read_report, refit, table, write_report};
