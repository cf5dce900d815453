//! The periodic bulk solid (docs/protocols.md, "Bulk solid").
//!
//! Random fill at volume fraction 0.64, overlap removal by overdamped
//! dynamics (`a_P = 0`, viscous damping), an undamped thermal run at rms
//! speed 0.03, a quench with pair damping restored, then bonds between all
//! pairs closer than 1.5 d and zero velocities.

use crate::engine::{pairs_within, BondTopology, System};
use crate::kernels::PairCoeffs;
use crate::options::{validate_strain_and_rate, InvalidOption};
use crate::scene::model::{Bonds, ForceField, Scene, StageSpec, VelocityInit};
use crate::scene::protocols;
use crate::scene::validate::SceneError;
use rand::{Rng, SeedableRng};
use serde::Serialize;

/// Parameters of the bulk builder (times in tau, lengths in d).
#[derive(Clone, Debug, Serialize)]
pub struct BulkParams {
    /// Box side `L`.
    pub size: f64,
    /// Target volume fraction of the random fill.
    pub volume_fraction: f64,
    /// Seed of the fill and of the thermal velocities.
    pub seed: u64,
    /// Duration of the overdamped overlap removal.
    pub relax_time: f64,
    /// Viscous damping during overlap removal (m / tau).
    pub relax_viscous: f64,
    /// Duration of the undamped thermal run.
    pub thermal_time: f64,
    /// Rms speed of the thermal run.
    pub thermal_rms_speed: f64,
    /// Duration of the quench with pair damping.
    pub quench_time: f64,
    /// Bond every pair closer than this.
    pub bond_cutoff: f64,
    /// Time step.
    pub dt: f64,
    /// Force field of the final solid (its pair part drives the build).
    pub force_field: ForceField,
}

impl BulkParams {
    /// The paper's protocol for a box of side `size` and multibody `a_b`.
    pub fn paper(size: f64, seed: u64, a_b: f64) -> Self {
        Self {
            size,
            volume_fraction: 0.64,
            seed,
            relax_time: 100.0,
            relax_viscous: 1.0,
            thermal_time: 1000.0,
            thermal_rms_speed: 0.03,
            quench_time: 3000.0,
            bond_cutoff: 1.5,
            dt: 0.1,
            force_field: ForceField::paper(a_b),
        }
    }
}

/// Largest box side: some 8e7 particles, about what 24 GiB holds while
/// the fill is bonded.
pub const MAX_SIZE: f64 = 400.0;

fn validate_size(size: f64) -> Result<(), InvalidOption> {
    if !(size.is_finite() && size > 3.0 && size <= MAX_SIZE) {
        return Err(InvalidOption::new(
            "--size",
            format!("must be a number above 3 and at most {MAX_SIZE} (d), got {size}"),
        ));
    }
    Ok(())
}

fn validate_a_b(a_b: f64) -> Result<(), InvalidOption> {
    if !a_b.is_finite() {
        return Err(InvalidOption::new("--a-b", "must be finite"));
    }
    Ok(())
}

impl BulkParams {
    /// Checks the box side (above 3 d: the fill needs room for the bond
    /// cutoff), a_B (finite) and the build's times and time step
    /// (positive).
    pub fn validate(&self) -> Result<(), InvalidOption> {
        validate_size(self.size)?;
        validate_a_b(self.force_field.bond.a)?;
        if !(self.volume_fraction > 0.0 && self.volume_fraction < 0.75) {
            return Err(InvalidOption::new(
                "volume_fraction",
                format!("must be in (0, 0.75), got {}", self.volume_fraction),
            ));
        }
        for (option, t) in [
            ("relax_time", self.relax_time),
            ("thermal_time", self.thermal_time),
            ("quench_time", self.quench_time),
            ("dt", self.dt),
        ] {
            if !(t.is_finite() && t > 0.0) {
                return Err(InvalidOption::new(
                    option,
                    format!("must be positive, got {t}"),
                ));
            }
        }
        Ok(())
    }

    /// The paper's protocol with short stages (relax 20, thermal 50, quench
    /// 100 tau): a quick solid for cross-checks and tests, not for physics.
    pub fn shortened(size: f64, seed: u64, a_b: f64) -> Self {
        Self {
            relax_time: 20.0,
            thermal_time: 50.0,
            quench_time: 100.0,
            ..Self::paper(size, seed, a_b)
        }
    }
}

/// The protocol stages appended to a built bulk solid (`bpm build bulk
/// --protocol`: the variants' docs are its help).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BulkProtocol {
    /// No stages: only the solid.
    None,
    /// Hold and record.
    Relax,
    /// Isotropic compression (bulk modulus).
    Compress,
    /// Simple shear by xy tilt (shear modulus).
    Shear,
}

/// What `bpm build bulk` builds: the paper's solid ([`BulkParams::paper`])
/// with its relax, thermal and quench times scaled, and protocol stages.
#[derive(Clone, Debug)]
pub struct BulkBuild {
    /// Box side L (d).
    pub size: f64,
    /// Seed of the fill and thermal velocities.
    pub seed: u64,
    /// Multibody strength a_B (k d).
    pub a_b: f64,
    /// Protocol stages to append.
    pub protocol: BulkProtocol,
    /// Steps of the relax protocol.
    pub steps: u64,
    /// Strain of compress and shear.
    pub strain: f64,
    /// Strain rate of compress and shear (1 / tau).
    pub rate: f64,
    /// Scale of the build's relax, thermal and quench times (1 = the paper's).
    pub time_scale: f64,
}

impl BulkBuild {
    /// Checks `--size`, `--time-scale`, `--rate` and `--strain` (whatever
    /// the protocol) and `--a-b`, in that order.
    pub fn validate(&self) -> Result<(), InvalidOption> {
        validate_size(self.size)?;
        if !(self.time_scale.is_finite() && self.time_scale > 0.0) {
            return Err(InvalidOption::new(
                "--time-scale",
                format!("must be positive, got {}", self.time_scale),
            ));
        }
        validate_strain_and_rate(self.strain, self.rate)?;
        validate_a_b(self.a_b)
    }

    /// The builder's parameters: the paper's, times scaled.
    pub fn params(&self) -> BulkParams {
        let mut params = BulkParams::paper(self.size, self.seed, self.a_b);
        params.relax_time *= self.time_scale;
        params.thermal_time *= self.time_scale;
        params.quench_time *= self.time_scale;
        params
    }

    /// The protocol's stages at time step `dt`: relax records every
    /// hundredth step, compress and shear 50 rows.
    pub fn stages(&self, dt: f64) -> Vec<StageSpec> {
        match self.protocol {
            BulkProtocol::None => vec![],
            BulkProtocol::Relax => {
                vec![protocols::relax(self.steps, dt, (self.steps / 100).max(1))]
            }
            BulkProtocol::Compress => {
                vec![protocols::isotropic_compression(
                    self.strain,
                    self.rate,
                    dt,
                    50,
                )]
            }
            BulkProtocol::Shear => vec![protocols::simple_shear(self.strain, self.rate, dt, 50)],
        }
    }
}

/// What the builder reports besides the scene.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct BulkSummary {
    /// Particles.
    pub particles: usize,
    /// Bonds.
    pub bonds: usize,
    /// Mean bonds per particle (paper: about 15).
    pub mean_bonds_per_particle: f64,
    /// Largest pair overlap `d - r` after the quench.
    pub max_overlap: f64,
    /// Wall-clock seconds of the build.
    pub seconds: f64,
}

fn steps(time: f64, dt: f64) -> u64 {
    (time / dt).round() as u64
}

/// Builds the bulk solid; the returned scene holds no protocol stages.
pub fn build_bulk(
    params: &BulkParams,
    threads: usize,
    progress: bool,
) -> Result<(Scene, BulkSummary), SceneError> {
    params.validate().map_err(|e| SceneError::Invalid {
        field: e.option.into(),
        reason: e.requirement,
    })?;
    let start = std::time::Instant::now();
    let l = params.size;
    let pair = params.force_field.pair.unwrap_or(PairCoeffs {
        k: 1.0,
        d: 1.0,
        a: 50.0,
        gamma: 1.0,
    });
    let sphere_volume = std::f64::consts::PI / 6.0 * pair.d.powi(3);
    let n = (params.volume_fraction * l * l * l / sphere_volume).round() as usize;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(params.seed);
    let positions: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            [
                rng.gen::<f64>() * l,
                rng.gen::<f64>() * l,
                rng.gen::<f64>() * l,
            ]
        })
        .collect();
    let soft = ForceField {
        pair: Some(PairCoeffs { a: 0.0, ..pair }),
        ..params.force_field.clone()
    };
    let mut relax = StageSpec::hold("relax", steps(params.relax_time, params.dt), params.dt);
    relax.viscous = params.relax_viscous;
    let mut thermal = StageSpec::hold(
        "thermalise",
        steps(params.thermal_time, params.dt),
        params.dt,
    );
    thermal.force_field = Some(ForceField {
        pair: Some(PairCoeffs { gamma: 0.0, ..pair }),
        ..params.force_field.clone()
    });
    thermal.set_velocities = Some(VelocityInit {
        rms_speed: params.thermal_rms_speed,
    });
    let mut quench = StageSpec::hold("quench", steps(params.quench_time, params.dt), params.dt);
    quench.force_field = Some(ForceField {
        pair: Some(pair),
        ..params.force_field.clone()
    });
    let mut scene = super::periodic_cube(
        format!("bulk solid, L = {l} d, seed {}", params.seed),
        params.seed,
        l,
        positions,
        soft,
    );
    scene.stages = vec![relax, thermal, quench];
    scene.provenance =
        serde_json::json!({ "builder": "bulk", "version": crate::VERSION, "parameters": params });
    let mut sys = super::run_build_stages(&scene, "bulk builder", threads, progress)?;
    sys.particles.wrap(&sys.simbox, None);
    sort_spatially(&mut sys.particles.x, &sys.simbox, 2.0 * pair.d);
    let max_overlap = max_overlap(&sys, pair.d);
    let bonds = bond_within(&sys, params.bond_cutoff);
    scene.particles.positions = sys.particles.x.clone();
    scene.bonds = Bonds {
        pairs: bonds.pairs().collect(),
        r0: Some(bonds.r0.clone()),
        plastic_strain: None,
    };
    scene.force_field = params.force_field.clone();
    scene.stages = Vec::new();
    let summary = BulkSummary {
        particles: n,
        bonds: bonds.len(),
        mean_bonds_per_particle: 2.0 * bonds.len() as f64 / n as f64,
        max_overlap,
        seconds: start.elapsed().as_secs_f64(),
    };
    if let serde_json::Value::Object(m) = &mut scene.provenance {
        m.insert(
            "summary".into(),
            serde_json::to_value(&summary).unwrap_or_default(),
        );
    }
    Ok((scene, summary))
}

/// Renumbers particles in the order of cubic cells of side about `cell`
/// (z slowest, then y, then x, rows alternating direction), so bonded
/// partners sit close in memory: the bond pass then mostly hits cache.
pub fn sort_spatially(x: &mut [[f64; 3]], simbox: &crate::engine::SimBox, cell: f64) {
    let faces = simbox.face_distances();
    let nb: Vec<usize> = faces
        .iter()
        .map(|f| ((f / cell).floor() as usize).max(1))
        .collect();
    let key = |p: &[f64; 3]| {
        let s = simbox.to_fractional(p);
        let b: Vec<usize> = (0..3)
            .map(|d| ((s[d].rem_euclid(1.0) * nb[d] as f64) as usize).min(nb[d] - 1))
            .collect();
        let y = if b[2] % 2 == 0 {
            b[1]
        } else {
            nb[1] - 1 - b[1]
        };
        let row = b[2] * nb[1] + y;
        let xk = if row % 2 == 0 { b[0] } else { nb[0] - 1 - b[0] };
        (row * nb[0] + xk, s[0].to_bits())
    };
    x.sort_by_key(key);
}

/// Bonds every pair of `sys` closer than `cutoff`, with that distance as `r0`.
pub fn bond_within(sys: &System, cutoff: f64) -> BondTopology {
    BondTopology::new(
        sys.len(),
        &pairs_within(&sys.simbox, &sys.particles.x, cutoff),
    )
}

fn max_overlap(sys: &System, d: f64) -> f64 {
    pairs_within(&sys.simbox, &sys.particles.x, d)
        .iter()
        .fold(0.0, |worst, &(_, _, r)| f64::max(worst, d - r))
}
