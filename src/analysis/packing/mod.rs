//! Analysis of a packing of bonded grains at one recorded state
//! (docs/protocols.md, "Compaction"): volume fraction by Monte Carlo over
//! particles and grain hulls, coordination numbers (force and geometric
//! contacts, rattlers removed), and each grain's volumetric strain and
//! asphericity from its convex hull.
//!
//! A state is given as positions (wrapped or not), grain ids, bonds and
//! the box, so it can come from either engine's checkpoints or from a
//! LAMMPS dump with a data file for the bonds. DEM spheres, one per grain,
//! are measured by [`spheres`].

pub mod contacts;
pub mod grains;
pub mod hull;
pub mod spheres;
pub mod volume_fraction;

pub use contacts::{coordination, force_contacts, geometric_contacts, Coordination};
pub use grains::{Grains, GrainsError};
pub use hull::{Hull, HullError};
pub use spheres::analyse_spheres;
pub use volume_fraction::{monte_carlo_volume_fraction, VolumeFraction};

use crate::engine::SimBox;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// One state of a packing.
#[derive(Clone, Copy, Debug)]
pub struct Snapshot<'a> {
    /// The box.
    pub simbox: &'a SimBox,
    /// Particle positions, wrapped or not.
    pub positions: &'a [[f64; 3]],
    /// Grain id per particle, `0..grains`.
    pub grain: &'a [u32],
    /// Bonds (particle index pairs), used to make grains whole.
    pub bonds: &'a [[usize; 2]],
}

/// How a state is measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AnalysisOptions {
    /// Particle diameter d: the pair force's range (grains touch when two
    /// of their particles are closer) and the particle size.
    pub diameter: f64,
    /// Monte Carlo points per state.
    pub mc_points: u64,
    /// Seed of the Monte Carlo points.
    pub mc_seed: u64,
    /// Grains with this many contacts or fewer are rattlers (paper: 2).
    pub max_rattler_contacts: usize,
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        Self {
            diameter: 1.0,
            mc_points: 1_000_000,
            mc_seed: 1,
            max_rattler_contacts: 2,
        }
    }
}

/// What later states are measured against, taken at the first state.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Reference {
    /// Hull volume of each grain (d^3).
    pub hull_volumes: Vec<f64>,
    /// Asphericity of each grain (alpha0).
    pub asphericities: Vec<f64>,
    /// Radius of each grain's sphere for phi_sphere: its largest
    /// centre-to-particle distance plus d/2.
    pub sphere_radii: Vec<f64>,
    /// Z_geometry's cutoff: twice the mean largest centre-to-particle
    /// distance, plus d.
    pub geometric_cutoff: f64,
}

/// The measurements of one state.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct PackingState {
    /// Box volume (d^3).
    pub box_volume: f64,
    /// Volume fraction of particles and grain hulls (Monte Carlo).
    pub phi_mc: f64,
    /// Its standard error.
    pub phi_mc_error: f64,
    /// Volume of the grains' reference spheres over the box volume.
    pub phi_sphere: f64,
    /// Coordination from force contacts, rattlers removed.
    pub z_force: f64,
    /// Rattlers among force contacts.
    pub rattlers_force: usize,
    /// Coordination from centre distances, rattlers removed.
    pub z_geometry: f64,
    /// Rattlers among geometric contacts.
    pub rattlers_geometry: usize,
    /// Grain pairs in force contact (rattlers included).
    pub force_contacts: usize,
    /// Mean and standard deviation of the grains' volumetric strain.
    pub eps_v_mean: f64,
    /// See `eps_v_mean`.
    pub eps_v_std: f64,
    /// Mean and standard deviation of the grains' asphericity.
    pub asphericity_mean: f64,
    /// See `asphericity_mean`.
    pub asphericity_std: f64,
    /// Mean of `alpha - alpha0` per grain.
    pub asphericity_excess_mean: f64,
    /// Volumetric strain `(V0 - V) / V0` of each grain.
    pub eps_v: Vec<f64>,
    /// Asphericity of each grain.
    pub asphericity: Vec<f64>,
}

/// Why a state could not be analysed.
#[derive(Debug, thiserror::Error)]
pub enum PackingError {
    /// Grains could not be formed.
    #[error(transparent)]
    Grains(#[from] GrainsError),
    /// A grain has no usable hull.
    #[error("grain {grain}: {error}")]
    Hull {
        /// The grain.
        grain: usize,
        /// Why.
        error: HullError,
    },
    /// The box is not periodic in every dimension.
    #[error("the packing analysis needs a box periodic in every dimension")]
    NotPeriodic,
    /// The state does not match the reference.
    #[error("the state has {got} grains, its reference {expected}")]
    Mismatch {
        /// Grains in the state.
        got: usize,
        /// Grains in the reference.
        expected: usize,
    },
}

fn hulls_of(grains: &Grains) -> Result<Vec<Hull>, PackingError> {
    grains
        .positions
        .par_iter()
        .enumerate()
        .map(|(grain, p)| Hull::of(p).map_err(|error| PackingError::Hull { grain, error }))
        .collect()
}

fn whole_grains(s: &Snapshot) -> Result<Grains, PackingError> {
    if !s.simbox.periodic.iter().all(|&p| p) {
        return Err(PackingError::NotPeriodic);
    }
    Ok(Grains::from_bonds(s.simbox, s.positions, s.grain, s.bonds)?)
}

/// The reference of a packing from its first state.
pub fn reference_of(s: &Snapshot, opts: &AnalysisOptions) -> Result<Reference, PackingError> {
    let grains = whole_grains(s)?;
    let hulls = hulls_of(&grains)?;
    let mean_extent = grains.extents.iter().sum::<f64>() / grains.len().max(1) as f64;
    Ok(Reference {
        hull_volumes: hulls.iter().map(|h| h.volume).collect(),
        asphericities: hulls.iter().map(Hull::asphericity).collect(),
        sphere_radii: grains
            .extents
            .iter()
            .map(|e| e + 0.5 * opts.diameter)
            .collect(),
        geometric_cutoff: 2.0 * mean_extent + opts.diameter,
    })
}

fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var.sqrt())
}

/// Measures state `s` against `reference`.
pub fn analyse(
    s: &Snapshot,
    reference: &Reference,
    opts: &AnalysisOptions,
) -> Result<PackingState, PackingError> {
    let grains = whole_grains(s)?;
    if grains.len() != reference.hull_volumes.len() {
        return Err(PackingError::Mismatch {
            got: grains.len(),
            expected: reference.hull_volumes.len(),
        });
    }
    let hulls = hulls_of(&grains)?;
    let box_volume = s.simbox.volume();
    let phi = monte_carlo_volume_fraction(
        s.simbox,
        &hulls,
        s.positions,
        0.5 * opts.diameter,
        opts.mc_points,
        opts.mc_seed,
    );
    let sphere_volume: f64 = reference
        .sphere_radii
        .iter()
        .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
        .sum();
    let force = force_contacts(s.simbox, s.positions, s.grain, opts.diameter);
    let geometric = geometric_contacts(s.simbox, &grains.centres, reference.geometric_cutoff);
    let zf = coordination(grains.len(), &force, opts.max_rattler_contacts);
    let zg = coordination(grains.len(), &geometric, opts.max_rattler_contacts);
    let eps_v: Vec<f64> = hulls
        .iter()
        .zip(&reference.hull_volumes)
        .map(|(h, v0)| (v0 - h.volume) / v0)
        .collect();
    let asphericity: Vec<f64> = hulls.iter().map(Hull::asphericity).collect();
    let excess: Vec<f64> = asphericity
        .iter()
        .zip(&reference.asphericities)
        .map(|(a, a0)| a - a0)
        .collect();
    let (eps_v_mean, eps_v_std) = mean_std(&eps_v);
    let (asphericity_mean, asphericity_std) = mean_std(&asphericity);
    Ok(PackingState {
        box_volume,
        phi_mc: phi.phi,
        phi_mc_error: phi.error,
        phi_sphere: sphere_volume / box_volume,
        z_force: zf.z,
        rattlers_force: zf.rattlers,
        z_geometry: zg.z,
        rattlers_geometry: zg.rattlers,
        force_contacts: force.len(),
        eps_v_mean,
        eps_v_std,
        asphericity_mean,
        asphericity_std,
        asphericity_excess_mean: mean_std(&excess).0,
        eps_v,
        asphericity,
    })
}
