//! Ready-made protocol stages (docs/protocols.md).

pub mod lid;

use super::model::{ForceField, ModelKind, Record, Scene, StageSpec};
use crate::engine::{Deformation, FlatWall, ShearRemap, Tether, TiltFactor, WallSide};
use serde::{Deserialize, Serialize};

/// Holds the configuration for `steps` steps, recording every `every`.
pub fn relax(steps: u64, dt: f64, every: u64) -> StageSpec {
    let mut s = StageSpec::hold("relax", steps, dt);
    s.record = Record {
        every,
        positions_every: 0,
    };
    s
}

/// Number of steps to reach `strain` at `rate` with time step `dt`.
pub fn steps_for_strain(strain: f64, rate: f64, dt: f64) -> u64 {
    (strain / (rate * dt)).abs().round().max(1.0) as u64
}

/// Isotropic compression to volumetric strain about `3 strain` at true
/// strain rate `rate` per dimension, affine remap.
pub fn isotropic_compression(strain: f64, rate: f64, dt: f64, records: u64) -> StageSpec {
    let steps = steps_for_strain(strain, rate, dt);
    let mut s = StageSpec::hold("compress", steps, dt);
    s.deformation = Some(Deformation::Isotropic {
        true_strain_rate: -rate.abs(),
    });
    s.record.every = (steps / records.max(1)).max(1);
    s
}

/// Simple shear by `xy` tilt to shear strain `strain` at rate `rate`.
pub fn simple_shear(strain: f64, rate: f64, dt: f64, records: u64) -> StageSpec {
    let steps = steps_for_strain(strain, rate, dt);
    let mut s = StageSpec::hold("shear", steps, dt);
    s.deformation = Some(Deformation::SimpleShear {
        remap: ShearRemap::X,
        tilt: TiltFactor::Xy,
        rate: rate.abs(),
    });
    s.record.every = (steps / records.max(1)).max(1);
    s
}

/// Strain and rate of the calibration runs.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct ModuliLoading {
    /// Final strain of both runs (volumetric strain is about 3x this).
    pub strain: f64,
    /// True strain rate of compression and engineering shear rate (1 / tau).
    pub rate: f64,
    /// Time step (tau).
    pub dt: f64,
    /// Rows recorded per run.
    pub records: u64,
}

impl Default for ModuliLoading {
    /// 0.5% strain at 1e-5 / tau, dt 0.1, 50 rows (docs/protocols.md "Calibration").
    fn default() -> Self {
        Self {
            strain: 0.005,
            rate: 1e-5,
            dt: 0.1,
            records: 50,
        }
    }
}

/// The compression and shear scenes of `solid` at `a_b`, of the paper's
/// model or its zero-net-multibody variant.
pub fn calibration_scenes(
    solid: &Scene,
    a_b: f64,
    zero_net: bool,
    loading: &ModuliLoading,
) -> [Scene; 2] {
    let mut base = solid.clone();
    base.force_field = ForceField {
        skin: solid.force_field.skin,
        zero_net_multibody: zero_net,
        ..ForceField::paper(a_b)
    };
    base.particles.velocities = None;
    let mut compress = base.clone();
    compress.stages = vec![isotropic_compression(
        loading.strain,
        loading.rate,
        loading.dt,
        loading.records,
    )];
    let mut shear = base;
    shear.stages = vec![simple_shear(
        loading.strain,
        loading.rate,
        loading.dt,
        loading.records,
    )];
    [compress, shear]
}

/// The Hertz squeeze of one grain (docs/protocols.md, "Hertz sphere
/// squeeze"); lengths in d, times in tau.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SqueezeParams {
    /// Speed of each wall towards the other (paper: 5e-4 d / tau).
    pub wall_speed: f64,
    /// Wall stiffness k and cutoff (paper: k = 1, cutoff d = 1).
    pub wall_stiffness: f64,
    /// Range of the wall force.
    pub wall_cutoff: f64,
    /// Lateral (x, y) tether of the centre of mass (paper: soft, 0.001 k).
    pub tether_stiffness: f64,
    /// Overlap `delta / R` to reach (each wall travels about its cutoff
    /// before contact, then `delta`).
    pub max_overlap: f64,
    /// Nominal grain radius R for the overlap target.
    pub radius: f64,
    /// Time step.
    pub dt: f64,
    /// Records over the run (wall forces and positions).
    pub records: u64,
}

impl SqueezeParams {
    /// The paper's squeeze of a grain of radius `radius` to `max_overlap`.
    pub fn paper(radius: f64, max_overlap: f64) -> Self {
        Self {
            wall_speed: 5e-4,
            wall_stiffness: 1.0,
            wall_cutoff: 1.0,
            tether_stiffness: 1e-3,
            max_overlap,
            radius,
            dt: 0.1,
            records: 1000,
        }
    }
}

/// `scene` (one grain in a closed box) with the squeeze stage: two flat
/// walls normal to z, one cutoff beyond the highest and lowest particles,
/// moving towards each other, and the centre of mass tethered in x and y.
pub fn hertz_squeeze(scene: &Scene, p: &SqueezeParams) -> Scene {
    let z = scene.particles.positions.iter().map(|x| x[2]);
    let (zmin, zmax) = z.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
        (a.min(z), b.max(z))
    });
    let travel = p.wall_cutoff + p.max_overlap * p.radius + 0.05 * p.radius;
    let steps = (travel / p.wall_speed / p.dt).ceil() as u64;
    let mut s = StageSpec::hold("squeeze", steps, p.dt);
    let wall = |side, position, velocity| FlatWall {
        axis: 2,
        side,
        position,
        velocity,
        stiffness: p.wall_stiffness,
        cutoff: p.wall_cutoff,
    };
    s.walls = vec![
        wall(WallSide::Lo, zmin - p.wall_cutoff, p.wall_speed),
        wall(WallSide::Hi, zmax + p.wall_cutoff, -p.wall_speed),
    ];
    s.tether = Some(Tether {
        grain: None,
        anchor: None,
        dims: [true, true, false],
        stiffness: p.tether_stiffness,
    });
    s.record.every = (steps / p.records.max(1)).max(1);
    let mut out = scene.clone();
    out.stages = vec![s];
    out
}

/// The compaction protocol (docs/protocols.md, "Compaction"): jam with the
/// Berendsen barostat, then compress isotropically at a true strain rate
/// raised stepwise. Times in tau, pressures in k/d.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CompactionProtocol {
    /// Time step.
    pub dt: f64,
    /// Barostat target pressure of the jamming stage (paper: 1e-6).
    pub jam_pressure: f64,
    /// Barostat gain per step (d/k; paper: 0.1).
    pub jam_gain: f64,
    /// Duration of the jamming stage (paper: 2e5).
    pub jam_time: f64,
    /// First true strain rate per dimension (paper: 1e-9 / tau).
    pub rate_start: f64,
    /// Last true strain rate (paper: 1e-6 / tau).
    pub rate_end: f64,
    /// Rates from first to last, spaced geometrically.
    pub rate_levels: usize,
    /// Duration of each compression stage (paper: 2e5).
    pub stage_time: f64,
    /// Volumetric strain of the box after jamming, `1 - V / V_jam`, at
    /// which compression stops; stages at the last rate are added until
    /// it is reached.
    pub volumetric_strain: f64,
    /// Thermo rows per stage.
    pub rows_per_stage: u64,
    /// Recorded states (position checkpoints) per stage.
    pub states_per_stage: u64,
    /// True strain rate of the unloading after the compression (1/tau):
    /// the box expands back to its jammed size, then rests as long; 0
    /// (the default) for none.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub unload_rate: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl CompactionProtocol {
    /// The paper's protocol (about 2e7 steps; far beyond this machine for
    /// a packing of 1,024 grains).
    pub fn paper() -> Self {
        Self {
            dt: 0.1,
            jam_pressure: 1e-6,
            jam_gain: 0.1,
            jam_time: 2e5,
            rate_start: 1e-9,
            rate_end: 1e-6,
            rate_levels: 10,
            stage_time: 2e5,
            volumetric_strain: 0.6,
            rows_per_stage: 100,
            states_per_stage: 4,
            unload_rate: 0.0,
        }
    }

    /// The compression rate of each compression stage, in order.
    pub fn rates(&self) -> Vec<f64> {
        let levels = self.rate_levels.max(1);
        let ratio = if levels > 1 {
            (self.rate_end / self.rate_start).powf(1.0 / (levels - 1) as f64)
        } else {
            1.0
        };
        let target = -(1.0 - self.volumetric_strain).ln() / 3.0;
        let mut rates = Vec::new();
        let mut strain = 0.0;
        let mut k = 0;
        while strain < target * (1.0 - 1e-12) && rates.len() < 100_000 {
            let rate = if k + 1 >= levels {
                self.rate_end
            } else {
                self.rate_start * ratio.powi(k as i32)
            };
            rates.push(rate);
            strain += rate * self.stage_time;
            k += 1;
        }
        rates
    }

    /// The stages: `jam` (velocities zeroed, bond reference lengths reset,
    /// barostat), then `compress-K` at each rate; the last is shortened so
    /// the box's true volumetric strain after jamming is exactly
    /// `-ln(1 - volumetric_strain)`; with an unload rate, `unload` (the box
    /// expanding back to its jammed size at about that rate) and `rest`
    /// (held as long).
    pub fn stages(&self) -> Vec<StageSpec> {
        let record = |stage: &mut StageSpec| {
            let states = self.states_per_stage.max(1);
            let rows = self.rows_per_stage.max(states);
            // Rows fall on every state, so each state has its pressure.
            let per_state = (stage.steps / states).max(1);
            let every = (per_state / (rows / states).max(1)).max(1);
            let positions_every = (per_state / every).max(1) * every;
            stage.record = Record {
                every,
                positions_every,
            };
        };
        let mut jam = StageSpec::hold("jam", steps_for_time(self.jam_time, self.dt), self.dt);
        jam.zero_velocities = true;
        jam.reset_reference = true;
        jam.barostat = Some(crate::engine::Barostat {
            target_pressure: self.jam_pressure,
            gain: self.jam_gain,
        });
        record(&mut jam);
        let mut stages = vec![jam];
        let target = -(1.0 - self.volumetric_strain).ln() / 3.0;
        let mut strain = 0.0;
        for (k, rate) in self.rates().into_iter().enumerate() {
            let time = self.stage_time.min((target - strain) / rate);
            let steps = steps_for_time(time, self.dt);
            strain += rate * steps as f64 * self.dt;
            let mut s = StageSpec::hold(&format!("compress-{k}"), steps, self.dt);
            s.deformation = Some(Deformation::Isotropic {
                true_strain_rate: -rate,
            });
            record(&mut s);
            stages.push(s);
        }
        if self.unload_rate > 0.0 {
            let mut unload = StageSpec::hold(
                "unload",
                steps_for_time(strain / self.unload_rate, self.dt),
                self.dt,
            );
            record(&mut unload);
            // Cut to a whole number of state intervals, so the last state
            // recorded is the stage's end; then back by exactly the strain
            // applied (isotropic strains compose): the jammed box.
            unload.steps = unload.record.positions_every * self.states_per_stage.max(1);
            unload.deformation = Some(Deformation::Isotropic {
                true_strain_rate: strain / (unload.steps as f64 * self.dt),
            });
            let rest = StageSpec {
                name: "rest".into(),
                deformation: None,
                ..unload.clone()
            };
            stages.extend([unload, rest]);
        }
        stages
    }
}

/// The compaction scene of a packing: its stages are the protocol's
/// (DEM spheres have no bonds whose reference the jam could reset).
pub fn compaction_scene(packing: &Scene, protocol: &CompactionProtocol) -> Scene {
    let mut scene = packing.clone();
    scene.stages = protocol.stages();
    if scene.model == ModelKind::Dem {
        for stage in &mut scene.stages {
            stage.reset_reference = false;
        }
    }
    scene
}

/// Steps of `dt` in `time`, at least 1.
pub fn steps_for_time(time: f64, dt: f64) -> u64 {
    (time / dt).round().max(1.0) as u64
}

/// The elastic moduli of a packing at a saved state (docs/protocols.md,
/// "Compaction"): velocities zeroed, a relaxation at fixed box, then
/// either a small isotropic compression or, from the same relaxed state,
/// a small simple shear; the moduli are the slopes of stress against
/// strain over the loading. Times in tau.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PackingModuliProtocol {
    /// Time step.
    pub dt: f64,
    /// Relaxation at fixed box before each loading (paper: 1e4).
    pub relax_time: f64,
    /// Volumetric strain `(V0 - V) / V0` of the compression (paper: 6e-4).
    pub volumetric_strain: f64,
    /// True strain rate per dimension of the compression (paper: 1e-8).
    pub compression_rate: f64,
    /// Shear strain `xy / ly` (paper: 4e-4).
    pub shear_strain: f64,
    /// Shear strain rate (paper: 2e-8).
    pub shear_rate: f64,
    /// Thermo rows per stage; the loading's rows are the fit's points.
    pub rows: u64,
}

impl PackingModuliProtocol {
    /// The paper's protocol: 5e5 steps per state.
    pub fn paper() -> Self {
        Self {
            dt: 0.1,
            relax_time: 1e4,
            volumetric_strain: 6e-4,
            compression_rate: 1e-8,
            shear_strain: 4e-4,
            shear_rate: 2e-8,
            rows: 50,
        }
    }

    /// The relaxation, recording its pressure (to measure what drift is
    /// left when the loading starts).
    pub fn relax_stage(&self) -> StageSpec {
        let steps = steps_for_time(self.relax_time, self.dt);
        let mut s = relax(steps, self.dt, (steps / self.rows.max(1)).max(1));
        s.zero_velocities = true;
        s
    }

    fn compression(&self) -> StageSpec {
        let linear = -(1.0 - self.volumetric_strain).ln() / 3.0;
        isotropic_compression(linear, self.compression_rate, self.dt, self.rows)
    }

    fn shear(&self) -> StageSpec {
        simple_shear(self.shear_strain, self.shear_rate, self.dt, self.rows)
    }

    /// Relaxation then compression: each box length shrinks at the true
    /// strain rate until the volume has lost `volumetric_strain`.
    pub fn compression_stages(&self) -> Vec<StageSpec> {
        vec![self.relax_stage(), self.compression()]
    }

    /// Relaxation then simple shear by `xy` tilt.
    pub fn shear_stages(&self) -> Vec<StageSpec> {
        vec![self.relax_stage(), self.shear()]
    }

    /// The control: relaxation, then the box held for as long as either
    /// loading lasts, recorded on every step either loading records, so
    /// the creep of the unloaded packing can be subtracted row by row.
    pub fn control_stages(&self) -> Vec<StageSpec> {
        let (c, s) = (self.compression(), self.shear());
        let gcd = |mut a: u64, mut b: u64| {
            while b != 0 {
                (a, b) = (b, a % b);
            }
            a
        };
        let mut hold = StageSpec::hold("hold", c.steps.max(s.steps), self.dt);
        hold.record.every = gcd(c.record.every, s.record.every).max(1);
        vec![self.relax_stage(), hold]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unloading takes the box back to its jammed size (the true
    /// strains of compression and unloading cancel to round-off), and its
    /// last recorded state is each unloading stage's end.
    #[test]
    fn unloading_returns_the_box_to_its_jammed_size() {
        let protocol = CompactionProtocol {
            jam_time: 100.0,
            rate_start: 1e-5,
            rate_end: 1e-4,
            rate_levels: 3,
            stage_time: 1e3,
            volumetric_strain: 0.4,
            unload_rate: 3e-4,
            ..CompactionProtocol::paper()
        };
        let stages = protocol.stages();
        let names: Vec<&str> = stages.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names.first(), Some(&"jam"));
        assert_eq!(&names[names.len() - 2..], ["unload", "rest"]);
        let log_scale: f64 = stages
            .iter()
            .filter_map(|s| match s.deformation {
                Some(Deformation::Isotropic { true_strain_rate }) => {
                    Some(true_strain_rate * s.steps as f64 * s.dt)
                }
                _ => None,
            })
            .sum();
        assert!(log_scale.abs() < 1e-12, "{log_scale}");
        let unload = &stages[stages.len() - 2];
        let Some(Deformation::Isotropic { true_strain_rate }) = unload.deformation else {
            panic!("the unloading does not expand the box");
        };
        // Cut by less than a row interval per state (4 of about 25 rows
        // here): a little faster than asked.
        let ratio = true_strain_rate / protocol.unload_rate;
        assert!((1.0..1.0 + 4.0 / 100.0 + 1e-9).contains(&ratio), "{ratio}");
        for stage in &stages[stages.len() - 2..] {
            assert_eq!(
                stage.steps % stage.record.positions_every,
                0,
                "{}",
                stage.name
            );
            assert_eq!(
                stage.steps / stage.record.positions_every,
                protocol.states_per_stage
            );
            assert_eq!(stage.record.positions_every % stage.record.every, 0);
        }
        assert!(stages.last().unwrap().deformation.is_none());
        let without = CompactionProtocol {
            unload_rate: 0.0,
            ..protocol
        };
        assert_eq!(without.stages().len(), stages.len() - 2);
    }
}
