//! The protocol of one run: the packings prepared by isotropic
//! compression, and a packing sheared fast, then slowly, with
//! Lees-Edwards boundaries.

use super::{
    SeriesSpec, ShearError, ShearOptions, PREPARATION_HOLD, PREPARATION_RATE, PROTOCOL,
    START_FRACTION,
};
use crate::engine::{Deformation, MultiContact, ShearRemap, TiltFactor};
use crate::kernels::{GranularMaterial, NormalDamping};
use crate::scene::builders::packing::template_centres;
use crate::scene::load::fnv1a;
use crate::scene::protocols::lid::liggghts_hertz_material;
use crate::scene::run::Recorders;
use crate::scene::{
    build_system, run_scene, run_stage, validate, ForceField, ModelKind, RunOptions, Scene,
    StageOutput, StageSpec,
};
use serde::{Deserialize, Serialize};

/// The normal stiffness scale of equal spheres, `k = 4/3 E*` with
/// `1/E* = 2 (1 - nu^2) / E`, in units of `E`: the study's stress unit.
pub fn stiffness(poisson_ratio: f64) -> f64 {
    2.0 / (3.0 * (1.0 - poisson_ratio * poisson_ratio))
}

/// The shear rate (1 / tau) of the dimensionless rate `rate = gamma_dot d
/// / sqrt(k / rho)`, with `d = 1` and `rho = 6 / pi` (unit mass).
pub fn shear_rate(rate: f64, poisson_ratio: f64) -> f64 {
    let density = 6.0 / std::f64::consts::PI;
    rate * (stiffness(poisson_ratio) / density).sqrt()
}

/// The shear rates (1 / tau) of the fast and the slow stage: the slow
/// one at dimensionless rate `rate`, the fast one `rate_factor` times it.
pub fn stage_rates(rate: f64, rate_factor: f64, poisson_ratio: f64) -> [f64; 2] {
    let slow = shear_rate(rate, poisson_ratio);
    [rate_factor * slow, slow]
}

/// Edge of the cube that `spheres` unit spheres fill to `phi`.
pub fn cube_edge(spheres: usize, phi: f64) -> f64 {
    (spheres as f64 * std::f64::consts::PI / (6.0 * phi)).cbrt()
}

/// A packing at one volume fraction, in a cube `[0, length)^3`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Packing {
    /// Volume fraction (exact: the box was rescaled to it).
    pub fraction: f64,
    /// Cube edge (d).
    pub length: f64,
    /// The volume fraction the compression reached before the rescale.
    pub reached: f64,
    /// Sphere centres.
    #[serde(skip)]
    pub centres: Vec<[f64; 3]>,
}

/// The frictionless Hertz spheres the packings are prepared with.
fn preparation_material() -> GranularMaterial {
    GranularMaterial {
        youngs_modulus: 1.0,
        poisson_ratio: 0.25,
        restitution: 0.5,
        damping: NormalDamping::CoeffRestitution,
        tangential_damping: 1.0,
        sliding_friction: 0.0,
        rolling: None,
        twisting: Default::default(),
    }
}

/// A periodic cube of DEM spheres of diameter 1 and mass 1.
fn periodic_cube(
    description: String,
    seed: u64,
    length: f64,
    centres: Vec<[f64; 3]>,
    force_field: ForceField,
) -> Scene {
    let n = centres.len();
    let mut scene =
        crate::scene::builders::periodic_cube(description, seed, length, centres, force_field);
    scene.model = ModelKind::Dem;
    scene.particles.radius = Some(vec![0.5; n]);
    scene
}

/// Prepares one packing per volume fraction of `opts`, all from one
/// chain: random centres at volume fraction 0.45, then frictionless Hertz
/// spheres compressed isotropically to each fraction in turn and left to
/// rest there; each saved state is rescaled to its exact fraction.
pub fn prepare_packings(opts: &ShearOptions) -> Result<Vec<Packing>, ShearError> {
    let fail = |m: String| ShearError::Preparation(m);
    let start_length = cube_edge(opts.spheres, START_FRACTION);
    let (centres, _) = template_centres(opts.spheres, 1.0, start_length, opts.seed, 1)
        .map_err(|e| fail(e.to_string()))?;
    let mut field = ForceField::dem(preparation_material());
    field.skin = opts.skin;
    let mut scene = periodic_cube(
        "shear packing preparation".into(),
        opts.seed,
        start_length,
        centres,
        field,
    );
    let mut sorted = opts.fractions.clone();
    sorted.sort_by(f64::total_cmp);
    // A compression to each fraction and a rest there, in turn; the
    // compressions' step counts round, so each fraction is reached only
    // nearly and the next compression starts from where the last ended.
    let true_strain = |phi: f64, from: f64| (phi / from).ln() / 3.0;
    let mut from = START_FRACTION;
    for &phi in &sorted {
        let steps = (true_strain(phi, from) / (PREPARATION_RATE * opts.dt))
            .round()
            .max(1.0) as u64;
        from *= (3.0 * PREPARATION_RATE * opts.dt * steps as f64).exp();
        let mut compress = StageSpec::hold(&format!("compress to {phi}"), steps, opts.dt);
        compress.deformation = Some(Deformation::Isotropic {
            true_strain_rate: -PREPARATION_RATE,
        });
        let mut rest = StageSpec::hold(
            &format!("rest at {phi}"),
            (PREPARATION_HOLD / opts.dt).round() as u64,
            opts.dt,
        );
        rest.zero_velocities = true;
        scene.stages.extend([compress, rest]);
    }
    validate(&scene).map_err(|e| fail(e.to_string()))?;
    let mut sys = build_system(&scene, 1);
    let mut files = Recorders::open(&Default::default()).map_err(|e| fail(e.to_string()))?;
    let mut packings = Vec::new();
    for (k, &phi) in sorted.iter().enumerate() {
        for j in [2 * k, 2 * k + 1] {
            let stage = &scene.stages[j];
            run_stage(
                &mut sys,
                stage,
                j,
                opts.seed,
                &RunOptions::quiet(1),
                &mut files,
            )
            .map_err(|e| fail(format!("{}: {e}", stage.name)))?;
        }
        let simbox = &sys.simbox;
        let reached = opts.spheres as f64 * std::f64::consts::PI / 6.0 / simbox.volume();
        let length = cube_edge(opts.spheres, phi);
        let scale = length / simbox.lengths[0];
        let centres = sys
            .particles
            .x
            .iter()
            .map(|x| [0, 1, 2].map(|d| ((x[d] - simbox.lo[d]) * scale).rem_euclid(length)))
            .collect();
        packings.push(Packing {
            fraction: phi,
            length,
            reached,
            centres,
        });
    }
    Ok(packings)
}

/// Everything that decides a run's recorded series: a run's file is
/// reused only when its key is equal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunKey {
    /// Version of the protocol.
    pub protocol: u32,
    /// Spheres.
    pub spheres: usize,
    /// Seed of the packing.
    pub seed: u64,
    /// Volume fraction.
    pub fraction: f64,
    /// The curve.
    pub series: SeriesSpec,
    /// The closure, if any.
    pub multicontact: Option<MultiContact>,
    /// Dimensionless slow rate.
    pub rate: f64,
    /// Fast over slow rate.
    pub rate_factor: f64,
    /// Strains of the fast and slow stage.
    pub strains: [f64; 2],
    /// Rows per unit strain.
    pub records_per_strain: f64,
    /// Time step.
    pub dt: f64,
    /// Restitution.
    pub restitution: f64,
    /// Skin.
    pub skin: f64,
    /// 64-bit FNV-1a of the run's scene as JSON: the packing, material,
    /// closure, initial velocities and stages. A change to any of them,
    /// by an option or by the code that prepares them, makes a new key.
    pub scene_fnv1a: String,
}

/// One recorded stage of a run: pressures in units of `k`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StageSeries {
    /// "fast" or "slow".
    pub name: String,
    /// Shear rate (1 / tau).
    pub shear_rate: f64,
    /// Shear strain since the stage began.
    pub strain: Vec<f64>,
    /// Pressure over `k`.
    pub pressure: Vec<f64>,
    /// Shear stress `-p_xy` over `k`.
    pub shear_stress: Vec<f64>,
    /// The closure's largest correction over the radius (0 for Hertz).
    pub largest_correction: Vec<f64>,
    /// Contacts the advanced closure switched off.
    pub switched_off: Vec<f64>,
    /// Steps the stage completed.
    pub steps: u64,
    /// Whether it ran to its end.
    pub complete: bool,
}

/// A run as recorded: its key, its stages and how it ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecordedRun {
    /// What was run.
    pub key: RunKey,
    /// The version of `bpm` that ran it (not part of the key).
    pub version: String,
    /// The stages, in order (the last one partial if the run stopped).
    pub stages: Vec<StageSeries>,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Why the run stopped early, if it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
}

#[cfg(test)]
impl RecordedRun {
    /// A complete run of `series` at `fraction` whose pressure (over `k`)
    /// is `fast` and `slow` throughout its two stages.
    pub(crate) fn steady_for_tests(
        opts: &ShearOptions,
        series: SeriesSpec,
        fraction: f64,
        fast: f64,
        slow: f64,
    ) -> Self {
        let packing = Packing {
            fraction,
            length: cube_edge(opts.spheres, fraction),
            reached: fraction,
            centres: Vec::new(),
        };
        let key = RunKey::new(opts, &series, &packing);
        let stage = |name: &str, strain: f64, p: f64| StageSeries {
            name: name.into(),
            strain: (0..=40).map(|k| strain * k as f64 / 40.0).collect(),
            pressure: vec![p; 41],
            shear_stress: vec![0.25 * p; 41],
            largest_correction: vec![0.0; 41],
            switched_off: vec![0.0; 41],
            complete: true,
            ..Default::default()
        };
        Self {
            version: String::new(),
            stages: vec![
                stage("fast", key.strains[0], fast),
                stage("slow", key.strains[1], slow),
            ],
            key,
            seconds: 1.0,
            stopped: None,
        }
    }
}

/// The material of a run's spheres.
pub fn material(series: &SeriesSpec, restitution: f64) -> GranularMaterial {
    liggghts_hertz_material(series.poisson_ratio, restitution, series.friction)
}

impl RunKey {
    /// The key of the run of `series` at `packing`.
    pub fn new(opts: &ShearOptions, series: &SeriesSpec, packing: &Packing) -> Self {
        let mut key = Self {
            protocol: PROTOCOL,
            spheres: opts.spheres,
            seed: opts.seed,
            fraction: packing.fraction,
            series: *series,
            multicontact: series.law.multicontact(&opts.closures, opts.reach),
            rate: opts.rate,
            rate_factor: opts.rate_factor,
            strains: [opts.strain_fast, opts.strain_slow],
            records_per_strain: opts.records_per_strain,
            dt: opts.dt,
            restitution: opts.restitution,
            skin: opts.skin,
            scene_fnv1a: String::new(),
        };
        let scene = serde_json::to_vec(&shear_scene(&key, packing))
            .expect("a scene serialises (plain numbers and strings)");
        key.scene_fnv1a = format!("{:016x}", fnv1a(&scene));
        key
    }

    /// The file name of the run under `runs/`.
    pub fn file_name(&self) -> String {
        format!(
            "{}-mu{}-nu{}-phi{}.json",
            self.series.law.name(),
            self.series.friction,
            self.series.poisson_ratio,
            self.fraction
        )
    }

    /// The shear rates (1 / tau) of the fast and slow stage.
    pub fn shear_rates(&self) -> [f64; 2] {
        stage_rates(self.rate, self.rate_factor, self.series.poisson_ratio)
    }
}

/// The scene of one run: the packing sheared fast, then slowly, with
/// Lees-Edwards boundaries (`xy` tilt, gradient along y). The spheres
/// start on the fast shear's streaming profile, spinning with its
/// vorticity.
pub fn shear_scene(key: &RunKey, packing: &Packing) -> Scene {
    let [fast, slow] = key.shear_rates();
    let mut field = ForceField::dem(material(&key.series, key.restitution));
    field.multicontact = key.multicontact;
    field.skin = key.skin;
    let mut scene = periodic_cube(
        format!(
            "{} unit spheres at volume fraction {} sheared with Lees-Edwards boundaries, {} contacts, friction {}, Poisson's ratio {} (bpm mc-shear)",
            key.spheres,
            key.fraction,
            key.series.law.name(),
            key.series.friction,
            key.series.poisson_ratio
        ),
        key.seed,
        packing.length,
        packing.centres.clone(),
        field,
    );
    scene.particles.velocities = Some(
        packing
            .centres
            .iter()
            .map(|x| [fast * x[1], 0.0, 0.0])
            .collect(),
    );
    scene.particles.angular_velocities = Some(vec![[0.0, 0.0, -0.5 * fast]; packing.centres.len()]);
    scene.stages = [
        ("fast", fast, key.strains[0]),
        ("slow", slow, key.strains[1]),
    ]
    .map(|(name, rate, strain)| {
        let steps = (strain / (rate * key.dt)).round().max(1.0) as u64;
        let mut stage = StageSpec::hold(name, steps, key.dt);
        stage.deformation = Some(Deformation::SimpleShear {
            tilt: TiltFactor::Xy,
            rate,
            remap: ShearRemap::V,
        });
        stage.record.every =
            ((steps as f64 / (strain * key.records_per_strain)).round() as u64).max(1);
        stage
    })
    .to_vec();
    scene
}

/// Reads one stage's recorded rows, pressures over `k`.
fn stage_series(output: &StageOutput, spec: &StageSpec, rate: f64, k: f64) -> StageSeries {
    let column = |name: &str| output.column(name).unwrap_or_default();
    let optional = |name: &str| {
        output
            .column(name)
            .unwrap_or_else(|| vec![0.0; output.rows.len()])
    };
    let time = column("time");
    let t0 = time.first().copied().unwrap_or(0.0);
    StageSeries {
        name: spec.name.clone(),
        shear_rate: rate,
        strain: time.iter().map(|t| (t - t0) * rate).collect(),
        pressure: column("pressure").iter().map(|p| p / k).collect(),
        shear_stress: column("pxy").iter().map(|p| -p / k).collect(),
        largest_correction: optional("mc_largest_correction"),
        switched_off: optional("mc_switched_off"),
        steps: output.stopped_at.unwrap_or(spec.steps),
        complete: output.stopped_at.is_none(),
    }
}

/// Runs one point on one thread.
pub fn run_point(key: &RunKey, packing: &Packing) -> RecordedRun {
    let start = std::time::Instant::now();
    let scene = shear_scene(key, packing);
    let k = stiffness(key.series.poisson_ratio);
    if let Err(e) = validate(&scene) {
        return RecordedRun {
            key: key.clone(),
            version: crate::VERSION.to_string(),
            stages: Vec::new(),
            seconds: 0.0,
            stopped: Some(format!("invalid scene: {e}")),
        };
    }
    let mut sys = build_system(&scene, 1);
    let (outputs, err) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
    let rates = key.shear_rates();
    RecordedRun {
        key: key.clone(),
        version: crate::VERSION.to_string(),
        stages: outputs
            .iter()
            .zip(&scene.stages)
            .zip(rates)
            .map(|((out, spec), rate)| stage_series(out, spec, rate, k))
            .collect(),
        seconds: start.elapsed().as_secs_f64(),
        stopped: err.map(|e| e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_key_changes_with_its_packing() {
        use crate::studies::mcdem::shear::Grid;
        let opts = ShearOptions::grid(Grid::Quick);
        let mut packing = Packing {
            fraction: 0.9,
            length: cube_edge(2, 0.9),
            reached: 0.9,
            centres: vec![[0.1, 0.2, 0.3], [0.9, 0.8, 0.7]],
        };
        let key = RunKey::new(&opts, &opts.series[0], &packing);
        assert_eq!(key, RunKey::new(&opts, &opts.series[0], &packing));
        packing.centres[1][2] += 1e-12;
        let moved = RunKey::new(&opts, &opts.series[0], &packing);
        assert_ne!(key.scene_fnv1a, moved.scene_fnv1a);
        // The closure is in the scene too.
        let advanced = RunKey::new(&opts, &opts.series[2], &packing);
        assert_ne!(moved.scene_fnv1a, advanced.scene_fnv1a);
    }

    #[test]
    fn rates_and_stiffness_follow_their_definitions() {
        // nu = 0.5: k = 2 / (3 * 0.75) = 8/9.
        assert!((stiffness(0.5) - 8.0 / 9.0).abs() < 1e-15);
        // gamma_dot = rate sqrt(k / rho) with rho = 6 / pi.
        let expected = 2e-3 * (8.0 / 9.0 * std::f64::consts::PI / 6.0).sqrt();
        assert!((shear_rate(2e-3, 0.5) - expected).abs() < 1e-18);
        // 256 unit spheres at 0.65 fill a cube of edge 5.91.
        assert!((cube_edge(256, 0.65) - 5.908017).abs() < 1e-6);
    }
}
