//! The stability map (`bpm stability`, docs/protocols.md "Stability
//! map"): the largest stable timestep of the bulk solid against `a_B` and
//! the damping `Gamma`, found by bisection ([`stable_limit`]); the
//! prediction from the solid's stiffest vibration mode ([`stiffest_mode`],
//! [`crate::kernels::verlet_limit`]); and the moduli near the incompressible limit, where
//! the shear modulus vanishes.
//!
//! A trial at timestep `dt` starts the solid with random velocities (rms
//! 0.03 d/tau, which excite every mode) and compresses it isotropically at a
//! constant true strain rate for a fixed simulated time (and at least
//! [`MIN_TRIAL_STEPS`] steps). It is *stable* when it finishes without an
//! engine error (a bond out of the model's range, a non-finite value), its
//! energy (kinetic plus bond and contact) never exceeds `growth_limit`
//! times the initial kinetic energy plus the spring energy of the imposed
//! strain, and (with damping) no bond ends more than `residual_strain_limit`
//! away from the imposed strain. Damping and a stable integrator can only lose energy (the
//! compression adds at most that spring energy); an unstable mode creates
//! it. Neither kinetic energy nor faults are enough: with damping, the
//! stiffest mode (localised on a few particles) can grow, flip its cluster
//! into another arrangement and calm down again without a bond leaving the
//! model's range, leaving bond strains of 0.1 to 0.4 behind (measured at L
//! = 6, 1-3% above the limit). Without damping the thermal motion never
//! decays, and near the incompressible limit its bond strains reach 0.1 in
//! a solid that is merely soft, so undamped trials are judged on energy and
//! faults alone (an undamped blow-up does not calm down).

pub mod cli;

use crate::analysis::plot::{Mark, Panel, Series};
use crate::engine::StageDrivers;
use crate::file_error::FileError;
use crate::kernels::verlet_limit;
use crate::kernels::Separation;
use crate::options::InvalidOption;
use crate::scene::{build_system, protocols, ForceField, Scene, VelocityInit};
use crate::scene::{run_native_report, RunOptions};
use crate::studies::calibration::{measure_moduli, paper_solid, CalibrationEngine, Loading};
use crate::studies::output::{self, OutputError, Provenance, StudyOutput, StudyReport};
use crate::verify::engines::HarnessError;
use rand::{Rng, SeedableRng};
use serde::Serialize;
use std::path::Path;

/// Why the stability study could not finish.
#[derive(Debug, thiserror::Error)]
pub enum StabilityError {
    /// An option is out of range.
    #[error(transparent)]
    Invalid(#[from] InvalidOption),
    /// The solid could not be built.
    #[error(transparent)]
    Harness(#[from] HarnessError),
    /// The report could not be written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The report or its drawings could not be written or read back.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The study stopped before its end (its checkpoint continues it).
    #[error(transparent)]
    Stopped(#[from] crate::studies::StudyStop),
}

/// What `bpm stability` runs.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct StabilityOptions {
    /// Box side L of the bulk solid (d).
    pub size: f64,
    /// Seeds of the solids (one solid per seed).
    pub seeds: Vec<u64>,
    /// Multibody strengths (k d).
    pub a_b: Vec<f64>,
    /// Bond and pair damping values Gamma (sqrt(k m)).
    pub gammas: Vec<f64>,
    /// Bisection bracket of the timestep (tau): smallest and largest tried.
    pub dt_range: (f64, f64),
    /// Simulated time of every trial (tau).
    pub time: f64,
    /// Linear strain of the compression over `time`.
    pub strain: f64,
    /// Rms speed of the initial random velocities (d / tau).
    pub rms_speed: f64,
    /// Energy over the reference (initial kinetic energy plus the spring
    /// energy of the imposed strain) that counts as unstable.
    pub growth_limit: f64,
    /// Largest bond strain left at the end beyond the imposed strain that
    /// still counts as stable.
    pub residual_strain_limit: f64,
    /// Relative width of the final bracket.
    pub precision: f64,
    /// Also measure K, G and nu at every a_B (dt 0.1, the calibration
    /// protocol on the same solid).
    pub moduli: bool,
    /// Map the zero-net-multibody variant instead of the paper's model
    /// (absent from reports written before the variant existed).
    #[serde(default)]
    pub zero_net: bool,
}

impl Default for StabilityOptions {
    fn default() -> Self {
        Self {
            size: 10.0,
            seeds: vec![1],
            a_b: vec![
                3.0, 2.0, 1.0, 0.5, 0.0, -0.25, -0.5, -0.75, -0.9, -1.0, -1.1, -1.2,
            ],
            gammas: vec![1.0, 0.0],
            dt_range: (0.005, 1.0),
            time: 100.0,
            strain: 0.01,
            rms_speed: 0.03,
            growth_limit: 10.0,
            residual_strain_limit: 0.1,
            precision: 0.02,
            moduli: true,
            zero_net: false,
        }
    }
}

impl StabilityOptions {
    /// Checks every option; the message names the option.
    pub fn validate(&self) -> Result<(), InvalidOption> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !(positive(self.size) && self.size >= 4.0) {
            return Err(InvalidOption::new(
                "--size",
                format!("must be at least 4 (d), got {}", self.size),
            ));
        }
        if self.seeds.is_empty() || self.a_b.is_empty() || self.gammas.is_empty() {
            return Err(InvalidOption::new(
                "--seeds, --a-b and --gamma",
                "need at least one value each",
            ));
        }
        if let Some(a) = self.a_b.iter().find(|a| !a.is_finite()) {
            return Err(InvalidOption::new(
                "--a-b",
                format!("values must be finite, got {a}"),
            ));
        }
        if let Some(g) = self.gammas.iter().find(|g| !(g.is_finite() && **g >= 0.0)) {
            return Err(InvalidOption::new(
                "--gamma",
                format!("values must be finite and >= 0, got {g}"),
            ));
        }
        let (lo, hi) = self.dt_range;
        if !(positive(lo) && positive(hi) && lo < hi) {
            return Err(InvalidOption::new(
                "--dt-min and --dt-max",
                format!("need 0 < dt-min < dt-max, got {lo} and {hi}"),
            ));
        }
        if !(positive(self.time) && self.time / lo <= 1e7) {
            return Err(InvalidOption::new(
                "--time",
                format!(
                    "must be positive and at most 1e7 steps of dt-min, got {}",
                    self.time
                ),
            ));
        }
        if !(positive(self.strain) && self.strain < 0.5) {
            return Err(InvalidOption::new(
                "--strain",
                format!("must be in (0, 0.5), got {}", self.strain),
            ));
        }
        if !(positive(self.rms_speed) && positive(self.growth_limit) && self.growth_limit > 1.0) {
            return Err(InvalidOption::new(
                "--rms-speed and --growth",
                "need a positive speed and a growth above 1",
            ));
        }
        if !positive(self.residual_strain_limit) {
            return Err(InvalidOption::new(
                "--residual-strain",
                format!("must be positive, got {}", self.residual_strain_limit),
            ));
        }
        if !(positive(self.precision) && self.precision < 1.0) {
            return Err(InvalidOption::new(
                "--precision",
                format!("must be in (0, 1), got {}", self.precision),
            ));
        }
        Ok(())
    }
}

/// One run at one timestep.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Trial {
    /// Timestep (tau).
    pub dt: f64,
    /// Steps run (or planned, for a run that stopped).
    pub steps: u64,
    /// The verdict.
    pub stable: bool,
    /// Largest energy over the reference (NaN when it stopped).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub growth: f64,
    /// Largest bond strain at the end beyond the imposed strain (NaN when
    /// it stopped).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub residual_strain: f64,
    /// Why it counts as unstable (empty when stable).
    pub reason: String,
    /// Wall seconds.
    pub seconds: f64,
}

/// The stability limit of one solid at one `(a_B, Gamma)`.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Limit {
    /// Multibody strength (k d).
    pub a_b: f64,
    /// Damping (sqrt(k m)).
    pub gamma: f64,
    /// Seed of the solid.
    pub seed: u64,
    /// Largest timestep found stable (NaN: none in the bracket).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub dt_stable: f64,
    /// Smallest timestep found unstable (NaN: none in the bracket).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub dt_unstable: f64,
    /// Every trial, in the order run.
    pub trials: Vec<Trial>,
}

impl Limit {
    /// The limit as one table row.
    pub fn row(&self) -> String {
        format!(
            "{:>6} {:>6} {:>5} {:>10.4} {:>11.4} {:>7}",
            self.a_b,
            self.gamma,
            self.seed,
            self.dt_stable,
            self.dt_unstable,
            self.trials.len()
        )
    }
}

/// The stiffest vibration mode of one solid at one a_B.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Mode {
    /// Multibody strength (k d).
    pub a_b: f64,
    /// Seed of the solid.
    pub seed: u64,
    /// Largest eigenvalue (modulus) of the mass-weighted force Jacobian
    /// (k / m), by power iteration.
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub lambda: f64,
    /// Damping rate of that mode per unit Gamma (1 / tau).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub damping: f64,
    /// The undamped velocity-Verlet limit `2 / sqrt(lambda)` (tau).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub dt_undamped: f64,
}

/// K, G and nu at one a_B (dt 0.1), or why they could not be measured.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct ModuliRow {
    /// Multibody strength (k d).
    pub a_b: f64,
    /// Bulk modulus (k / d): the fitted slope, NaN when a run failed.
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub k: f64,
    /// Shear modulus (k / d), as `k`.
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub g: f64,
    /// Poisson ratio.
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub nu: f64,
    /// Why the slopes are not moduli: the engine error of a failed run, or
    /// a solid that is not stable (a negative slope, or no stable timestep
    /// in the map at this a_B).
    pub error: Option<String>,
}

/// Everything `bpm stability` measured.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct StabilityReport {
    /// Program, version and command.
    #[serde(flatten)]
    pub provenance: Provenance,
    /// The options (seeds included: every run can be repeated).
    pub options: StabilityOptions,
    /// The criterion, in words.
    pub criterion: String,
    /// Particles of each solid, by seed.
    pub particles: Vec<(u64, usize)>,
    /// One limit per seed, a_B and Gamma.
    pub limits: Vec<Limit>,
    /// The stiffest mode per seed and a_B.
    pub modes: Vec<Mode>,
    /// Moduli per a_B (first seed).
    pub moduli: Vec<ModuliRow>,
}

/// Fewest steps of a trial: an instability just past the limit grows by
/// little per step and needs steps, not simulated time, to show.
pub const MIN_TRIAL_STEPS: u64 = 1000;

/// The criterion of [`Trial::stable`], in words.
pub fn criterion(opts: &StabilityOptions) -> String {
    format!(
        "a trial starts the solid with random velocities (rms {} d/tau) and compresses it \
         isotropically to linear strain {} over {} tau (at least {MIN_TRIAL_STEPS} steps); it is \
         stable when it finishes without an engine error (a bond shorter than 0.2 r0 or longer \
         than 3 r0, a non-finite value), its kinetic plus bond and contact energy never \
         exceeds {} times the initial kinetic energy plus the spring energy of the imposed \
         strain (k/2 sum (strain r0)^2), and, with damping, no bond ends more than {} away \
         from the imposed strain; bisection in log dt to a relative bracket of {}",
        opts.rms_speed,
        opts.strain,
        opts.time,
        opts.growth_limit,
        opts.residual_strain_limit,
        opts.precision
    )
}

/// `solid` at rest with the paper's force field at `a_b` (and the solid's
/// choice of the zero-net variant), with bond and contact damping `gamma`.
fn solid_at(solid: &Scene, a_b: f64, gamma: f64) -> Scene {
    let mut scene = solid.clone();
    let mut ff = ForceField {
        skin: solid.force_field.skin,
        zero_net_multibody: solid.force_field.zero_net_multibody,
        ..ForceField::paper(a_b)
    };
    ff.bond.gamma = gamma;
    if let Some(p) = &mut ff.pair {
        p.gamma = gamma;
    }
    scene.force_field = ff;
    scene.particles.velocities = None;
    scene
}

/// The trial scene: `solid` at `(a_b, gamma)` with the study's protocol at `dt`.
fn trial_scene(solid: &Scene, a_b: f64, gamma: f64, dt: f64, opts: &StabilityOptions) -> Scene {
    let mut scene = solid_at(solid, a_b, gamma);
    let steps = ((opts.time / dt).ceil() as u64).max(MIN_TRIAL_STEPS);
    let rate = opts.strain / (steps as f64 * dt);
    let mut stage = protocols::isotropic_compression(opts.strain, rate, dt, 100);
    stage.set_velocities = Some(VelocityInit {
        rms_speed: opts.rms_speed,
    });
    scene.stages = vec![stage];
    scene
}

/// Runs one trial.
pub fn trial(solid: &Scene, a_b: f64, gamma: f64, dt: f64, opts: &StabilityOptions) -> Trial {
    let scene = trial_scene(solid, a_b, gamma, dt, opts);
    let steps = scene.stages[0].steps;
    let start = std::time::Instant::now();
    let tag = format!("stability aB={a_b} gamma={gamma} dt={dt}");
    let r0 = crate::scene::load::reference_lengths(&scene);
    let (report, sys) = run_native_report(&scene, Path::new(&tag), 0, &RunOptions::quiet(1));
    let mut verdict = Verdict {
        growth: f64::NAN,
        residual_strain: f64::NAN,
        reason: String::new(),
    };
    if let Some(error) = report.error {
        verdict.reason = error;
    } else if let Some(stage) = report.stages.first() {
        let column = |name: &str| stage.column(name).unwrap_or_default();
        let (kinetic, bond, pair) = (column("e_kinetic"), column("e_bond"), column("e_pair"));
        let most = (0..kinetic.len())
            .map(|r| kinetic[r] + bond.get(r).unwrap_or(&0.0) + pair.get(r).unwrap_or(&0.0))
            .fold(f64::NEG_INFINITY, f64::max);
        let strain_energy: f64 = r0
            .iter()
            .map(|r0| 0.5 * scene.force_field.bond.k * (opts.strain * r0).powi(2))
            .sum();
        verdict.growth = most / (kinetic.first().copied().unwrap_or(f64::NAN) + strain_energy);
        verdict.residual_strain = largest_bond_strain(&sys, &scene.bonds.pairs, &r0) - opts.strain;
        // NaN counts as past the limit.
        if verdict.growth.is_nan() || verdict.growth > opts.growth_limit {
            verdict.reason = format!("energy reached {:.3} times the reference", verdict.growth);
        } else if gamma > 0.0
            && (verdict.residual_strain.is_nan()
                || verdict.residual_strain > opts.residual_strain_limit)
        {
            verdict.reason = format!(
                "a bond ended {:.3} away from the imposed strain: the structure changed",
                verdict.residual_strain
            );
        }
    }
    Trial {
        dt,
        steps,
        stable: verdict.reason.is_empty(),
        growth: verdict.growth,
        residual_strain: verdict.residual_strain,
        reason: verdict.reason,
        seconds: start.elapsed().as_secs_f64(),
    }
}

struct Verdict {
    growth: f64,
    residual_strain: f64,
    reason: String,
}

/// Largest `|r / r0 - 1|` over the bonds `pairs` in the final state of `sys`.
fn largest_bond_strain(sys: &crate::engine::System, pairs: &[[usize; 2]], r0: &[f64]) -> f64 {
    let sep = sys.simbox.minimum_image();
    let x = &sys.particles.x;
    pairs
        .iter()
        .zip(r0)
        .map(|([i, j], r0)| (sep.distance(&x[*i], &x[*j]) / r0 - 1.0).abs())
        .fold(0.0, f64::max)
}

/// The largest stable timestep of `solid` at `(a_b, gamma)` within the
/// bracket, by bisection in `log dt`; `log` receives each trial.
pub fn stable_limit(
    solid: &Scene,
    seed: u64,
    a_b: f64,
    gamma: f64,
    opts: &StabilityOptions,
    log: &mut dyn FnMut(&Trial),
) -> Limit {
    let mut trials = Vec::new();
    let mut run = |dt: f64, trials: &mut Vec<Trial>| {
        let t = trial(solid, a_b, gamma, dt, opts);
        log(&t);
        let stable = t.stable;
        trials.push(t);
        stable
    };
    let (lo, hi) = opts.dt_range;
    let (mut stable, mut unstable) = (f64::NAN, f64::NAN);
    if !run(lo, &mut trials) {
        unstable = lo;
    } else if run(hi, &mut trials) {
        stable = hi;
    } else {
        let (mut a, mut b) = (lo, hi);
        while b / a > 1.0 + opts.precision {
            let mid = (a * b).sqrt();
            if run(mid, &mut trials) {
                a = mid;
            } else {
                b = mid;
            }
        }
        stable = a;
        unstable = b;
    }
    Limit {
        a_b,
        gamma,
        seed,
        dt_stable: stable,
        dt_unstable: unstable,
        trials,
    }
}

/// The solid at `a_b` with bond and contact damping `gamma`, at rest.
fn system_at(solid: &Scene, a_b: f64, gamma: f64) -> crate::engine::System {
    let mut sys = build_system(&solid_at(solid, a_b, gamma), 1);
    sys.setup(&StageDrivers {
        dt: 0.1,
        ..StageDrivers::default()
    })
    .expect("a stage without granular walls sets up on any model");
    sys
}

/// `-M^-1 dF/dx . u` (`by_velocity`: `-M^-1 dF/dv . u`) of `sys` about its
/// current state, by central differences with step `1e-6` along `u`.
fn force_jacobian_times(
    sys: &mut crate::engine::System,
    u: &[[f64; 3]],
    by_velocity: bool,
) -> Vec<[f64; 3]> {
    let h = 1e-6;
    let drivers = StageDrivers {
        dt: 0.1,
        ..StageDrivers::default()
    };
    let base = if by_velocity {
        sys.particles.v.clone()
    } else {
        sys.particles.x.clone()
    };
    let mut forces_at = |s: f64| {
        let moved = base
            .iter()
            .zip(u)
            .map(|(a, b)| [0, 1, 2].map(|d| a[d] + s * b[d]));
        let target = if by_velocity {
            &mut sys.particles.v
        } else {
            &mut sys.particles.x
        };
        for (t, m) in target.iter_mut().zip(moved) {
            *t = m;
        }
        sys.compute_forces(&drivers, 0.0, false);
        sys.particles.f.clone()
    };
    let plus = forces_at(h);
    let minus = forces_at(-h);
    if by_velocity {
        sys.particles.v = base;
    } else {
        sys.particles.x = base;
    }
    plus.iter()
        .zip(&minus)
        .zip(&sys.particles.mass)
        .map(|((p, m), w)| [0, 1, 2].map(|d| -(p[d] - m[d]) / (2.0 * h * w)))
        .collect()
}

fn dot_all(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
        .sum()
}

/// The stiffest vibration mode of `solid` at `a_b`, undamped, at rest:
/// power iteration (`iterations` products from a seeded random start) on
/// the mass-weighted force Jacobian. Returns its eigenvalue (modulus)
/// `lambda` and the damping rate `c` that unit bond damping gives that
/// mode (`u . M^-1 C u` for the unit mode `u`).
pub fn stiffest_mode(solid: &Scene, a_b: f64, seed: u64, iterations: usize) -> (f64, f64) {
    let mut sys = system_at(solid, a_b, 0.0);
    let n = sys.particles.len();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut u: Vec<[f64; 3]> = (0..n)
        .map(|_| [0; 3].map(|_| rng.gen_range(-1.0..1.0)))
        .collect();
    let mut lambda = f64::NAN;
    for _ in 0..iterations {
        let scale = 1.0 / dot_all(&u, &u).sqrt();
        u.iter_mut().flatten().for_each(|c| *c *= scale);
        let ju = force_jacobian_times(&mut sys, &u, false);
        lambda = dot_all(&ju, &ju).sqrt();
        u = ju;
    }
    let scale = 1.0 / dot_all(&u, &u).sqrt();
    u.iter_mut().flatten().for_each(|c| *c *= scale);
    let mut damped = system_at(solid, a_b, 1.0);
    let cu = force_jacobian_times(&mut damped, &u, true);
    (lambda, dot_all(&u, &cu))
}

/// Runs the study; `log` receives each line of progress.
///
/// With a checkpoint in `runtime`, each solid, mode, limit and moduli
/// measurement is kept in it as it finishes, and a resumed study takes
/// them from there.
pub fn run_stability(
    opts: &StabilityOptions,
    runtime: &crate::studies::StudyRuntime,
    command: &str,
    log: &mut dyn FnMut(&str),
) -> Result<StabilityReport, StabilityError> {
    let threads = runtime.threads;
    opts.validate()?;
    let mut report = StabilityReport {
        provenance: Provenance::new(command),
        options: opts.clone(),
        criterion: criterion(opts),
        particles: Vec::new(),
        limits: Vec::new(),
        modes: Vec::new(),
        moduli: Vec::new(),
    };
    for (n, &seed) in opts.seeds.iter().enumerate() {
        let (mut solid, summary) = runtime.part(&format!("seed-{seed}/solid"), || {
            paper_solid(opts.size, seed, threads).map_err(StabilityError::from)
        })?;
        solid.force_field.zero_net_multibody = opts.zero_net;
        report.particles.push((seed, summary.particles));
        log(&format!(
            "solid L={} seed {seed}: {} particles",
            opts.size, summary.particles
        ));
        for &a_b in &opts.a_b {
            let mode = runtime.part(&format!("seed-{seed}/aB{a_b}/mode"), || {
                let (lambda, damping) = stiffest_mode(&solid, a_b, seed, 500);
                Ok::<_, StabilityError>(Mode {
                    a_b,
                    seed,
                    lambda,
                    damping,
                    dt_undamped: verlet_limit(lambda, 0.0),
                })
            })?;
            log(&format!(
                "  a_B={a_b}: stiffest mode lambda = {:.4} k/m (unit damping gives it c = {:.4} /tau), undamped Verlet limit {:.4} tau",
                mode.lambda, mode.damping, mode.dt_undamped
            ));
            report.modes.push(mode);
            for &gamma in &opts.gammas {
                let key = format!("seed-{seed}/aB{a_b}/gamma{gamma}");
                let limit = runtime.part(&key, || {
                    Ok::<_, StabilityError>(stable_limit(
                        &solid,
                        seed,
                        a_b,
                        gamma,
                        opts,
                        &mut |t| {
                            log(&format!(
                                "    a_B={a_b} Gamma={gamma} dt={:.5}: {} ({} steps, {:.1} s){}",
                                t.dt,
                                if t.stable { "stable" } else { "UNSTABLE" },
                                t.steps,
                                t.seconds,
                                if t.reason.is_empty() {
                                    String::new()
                                } else {
                                    format!(": {}", t.reason)
                                }
                            ))
                        },
                    ))
                })?;
                log(&format!("  limit {}", limit.row()));
                report.limits.push(limit);
            }
            if n == 0 && opts.moduli {
                let no_stable_timestep = report
                    .limits
                    .iter()
                    .filter(|l| l.a_b == a_b && l.seed == seed)
                    .all(|l| !l.dt_stable.is_finite());
                let row = runtime.part(&format!("aB{a_b}/moduli"), || {
                    Ok::<_, StabilityError>(match measure_moduli(
                    &solid,
                    a_b,
                    opts.zero_net,
                    &Loading::default(),
                    &CalibrationEngine::Native(threads),
                    &format!("moduli aB={a_b}"),
                ) {
                    Ok((m, _)) => ModuliRow {
                        a_b,
                        k: m.k,
                        g: m.g,
                        nu: m.nu,
                        // A fit of a solid that rearranged under the load:
                        // the slopes are not moduli.
                        error: if m.k <= 0.0 || m.g <= 0.0 {
                            Some(format!(
                                "K = {:.4}, G = {:.4}: not a stable solid under this load, no moduli",
                                m.k, m.g
                            ))
                        } else if no_stable_timestep {
                            Some(format!(
                                "K = {:.4}, G = {:.4} fitted, but no timestep of the map was stable at this a_B: no moduli",
                                m.k, m.g
                            ))
                        } else {
                            None
                        },
                    },
                    Err(e) => ModuliRow {
                        a_b,
                        k: f64::NAN,
                        g: f64::NAN,
                        nu: f64::NAN,
                        error: Some(e.to_string()),
                    },
                })
                })?;
                log(&format!(
                    "  a_B={a_b}: K = {:.4}, G = {:.4}, nu = {:.4}{}",
                    row.k,
                    row.g,
                    row.nu,
                    row.error
                        .as_deref()
                        .map(|e| format!(" ({e})"))
                        .unwrap_or_default()
                ));
                report.moduli.push(row);
            }
        }
    }
    Ok(report)
}

/// Writes `DIR/stability.json` and `DIR/stability.svg`.
pub fn write_report(report: &StabilityReport, dir: &Path) -> Result<(), StabilityError> {
    output::write_report(report, dir)?;
    Ok(())
}

/// Rewrites `DIR/stability.svg` (and the JSON) from an earlier
/// `stability.json` without running anything.
pub fn replot(json: &Path, dir: &Path) -> Result<StabilityReport, StabilityError> {
    Ok(output::replot(json, dir)?)
}

impl StudyReport for StabilityReport {
    const JSON: &'static str = "stability.json";

    fn check(&self) -> Result<(), String> {
        self.options.validate().map_err(|e| e.to_string())
    }

    /// `stability.svg`: the limits against a_B beside the stiffest mode's
    /// prediction, and the moduli.
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        let report = self;
        let mut limits = Panel {
            title: format!(
                "Largest stable timestep, bulk solid L = {}{}",
                report.options.size,
                if report.options.zero_net {
                    ", zero-net variant"
                } else {
                    ""
                }
            ),
            x_label: "a_B (k d)".into(),
            y_label: "dt (tau)".into(),
            log_y: true,
            ..Panel::default()
        };
        for &gamma in &report.options.gammas {
            for &seed in &report.options.seeds {
                let points = report
                    .limits
                    .iter()
                    .filter(|l| l.gamma == gamma && l.seed == seed && l.dt_stable.is_finite())
                    .map(|l| (l.a_b, l.dt_stable))
                    .collect();
                limits.series.push(Series::new(
                    format!("measured, Gamma = {gamma}, seed {seed}"),
                    points,
                    Mark::LinePoints,
                ));
            }
        }
        // The modes of the first seed (validated options have one).
        let first = report.options.seeds.first().copied();
        let modes: Vec<&Mode> = report
            .modes
            .iter()
            .filter(|m| Some(m.seed) == first)
            .collect();
        limits.series.push(Series::new(
            "2 / sqrt(lambda_max), undamped",
            modes.iter().map(|m| (m.a_b, m.dt_undamped)).collect(),
            Mark::Rings,
        ));
        for &gamma in report.options.gammas.iter().filter(|g| **g > 0.0) {
            limits.series.push(Series::new(
                format!("Verlet limit of that mode, Gamma = {gamma}"),
                modes
                    .iter()
                    .map(|m| (m.a_b, verlet_limit(m.lambda, gamma * m.damping)))
                    .collect(),
                Mark::Rings,
            ));
        }
        let mut moduli = Panel {
            title: "Moduli at dt = 0.1 (calibration protocol)".into(),
            x_label: "a_B (k d)".into(),
            y_label: "nu, G/K".into(),
            ..Panel::default()
        };
        let ok: Vec<&ModuliRow> = report.moduli.iter().filter(|m| m.error.is_none()).collect();
        moduli.series.push(Series::new(
            "Poisson ratio nu",
            ok.iter().map(|m| (m.a_b, m.nu)).collect(),
            Mark::LinePoints,
        ));
        moduli.series.push(Series::new(
            "G / K",
            ok.iter().map(|m| (m.a_b, m.g / m.k)).collect(),
            Mark::LinePoints,
        ));
        out.svg("stability.svg", &[limits, moduli])?;
        Ok(())
    }
}
