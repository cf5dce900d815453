//! Single grains (docs/protocols.md, "Grains"): spheres of bonded
//! particles cut from the bulk packing.
//!
//! - rough: a sphere of radius R cut from the bonded bulk solid, bonds kept;
//! - smoother: the same sphere cut before bonding, vibrated in a harmonic
//!   spherical cage whose radius oscillates with an exponentially decaying
//!   amplitude under viscous damping (the surface particles reorder into a
//!   smoother shape), then bonded within the bond cutoff.
//!
//! The grain is returned in a closed box with a margin around it, centred,
//! at rest, with no protocol stages; studies (the Hertz squeeze, packings)
//! add their own.

use super::bulk::{build_bulk, BulkParams};
use crate::engine::pairs_within;
use crate::engine::SphereWall;
use crate::kernels::Separation;
use crate::scene::load::reference_lengths;
use crate::scene::model::{Bonds, BoxSpec, Scene, StageSpec};
use crate::scene::rotation::centre_of;
use crate::scene::validate::{simbox_of, SceneError};
use serde::{Deserialize, Serialize};

/// How the grain's surface is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GrainKind {
    /// Cut from the bonded solid: the surface keeps the packing's roughness.
    Rough,
    /// Cut before bonding and vibrated in an oscillating spherical cage.
    Smoother,
}

impl GrainKind {
    /// The kind as written in file names, descriptions and the CLI.
    pub fn name(self) -> &'static str {
        match self {
            GrainKind::Rough => "rough",
            GrainKind::Smoother => "smoother",
        }
    }
}

/// Parameters of a grain (lengths in d, times in tau).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GrainParams {
    /// Rough or smoother.
    pub kind: GrainKind,
    /// Radius R of the cut sphere (paper: 10 d, about 5,000 particles).
    pub radius: f64,
    /// Seed of the bulk packing the grain is cut from.
    pub seed: u64,
    /// Multibody strength a_B of the force field the scene carries (k d).
    pub a_b: f64,
    /// Scale of every time of the build (bulk relax, thermal and quench;
    /// cage vibration and settling); 1 = the full protocol, smaller for
    /// quick tests.
    pub time_scale: f64,
    /// Smoother grains: mean cage radius minus R. The cage pushes particles
    /// closer than its cutoff (d) to it, so 1 d starts without contact.
    pub cage_offset: f64,
    /// Smoother grains: oscillation amplitude of the cage radius.
    pub cage_amplitude: f64,
    /// Smoother grains: oscillation period.
    pub cage_period: f64,
    /// Smoother grains: decay time of the amplitude.
    pub cage_decay: f64,
    /// Smoother grains: duration of the vibration.
    pub cage_time: f64,
    /// Smoother grains: viscous damping during the vibration (m / tau).
    pub cage_viscous: f64,
    /// Empty space between the grain and the closed box faces.
    pub margin: f64,
}

impl GrainParams {
    /// Defaults: the bulk build of the paper, and a cage that starts 1 d
    /// outside the cut sphere, swings by 1 d with a period of 100 tau and a
    /// decay time of 400 tau, for 2,000 tau under damping 0.1 m / tau (the
    /// paper gives the recipe, not these numbers).
    pub fn new(kind: GrainKind, radius: f64, seed: u64, a_b: f64) -> Self {
        Self {
            kind,
            radius,
            seed,
            a_b,
            time_scale: 1.0,
            cage_offset: 1.0,
            cage_amplitude: 1.0,
            cage_period: 100.0,
            cage_decay: 400.0,
            cage_time: 2000.0,
            cage_viscous: 0.1,
            margin: 3.0,
        }
    }

    /// Checks the parameters; the error names the offending one.
    pub fn validate(&self) -> Result<(), SceneError> {
        let bad = |field: &str, reason: String| SceneError::Invalid {
            field: field.into(),
            reason,
        };
        if !(self.radius.is_finite() && self.radius >= 1.5) {
            return Err(bad(
                "radius",
                format!("must be at least 1.5 d, got {}", self.radius),
            ));
        }
        if !self.a_b.is_finite() {
            return Err(bad("a_b", "must be finite".into()));
        }
        for (name, v) in [
            ("time_scale", self.time_scale),
            ("cage_period", self.cage_period),
            ("cage_decay", self.cage_decay),
            ("margin", self.margin),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(name, format!("must be positive, got {v}")));
            }
        }
        for (name, v) in [
            ("cage_offset", self.cage_offset),
            ("cage_amplitude", self.cage_amplitude),
            ("cage_time", self.cage_time),
            ("cage_viscous", self.cage_viscous),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(name, format!("must be >= 0, got {v}")));
            }
        }
        Ok(())
    }
}

/// What the builder reports besides the scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GrainSummary {
    /// Particles.
    pub particles: usize,
    /// Bonds.
    pub bonds: usize,
    /// Mean bonds per particle (interior about 15, fewer at the surface).
    pub mean_bonds_per_particle: f64,
    /// Surface shape: see [`Roughness`].
    pub roughness: Roughness,
    /// Wall-clock seconds of the build.
    pub seconds: f64,
}

/// The spread of the outermost particles' distances from the centre of
/// mass. The sphere of directions is split into `cells` cells of about
/// equal area (nearest of a Fibonacci lattice of directions); in each, the
/// largest distance of a particle whose direction falls there is the
/// surface height.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct Roughness {
    /// Direction cells.
    pub cells: usize,
    /// Mean surface height (d).
    pub mean_height: f64,
    /// Standard deviation of the surface height (d): the roughness.
    pub sd_height: f64,
    /// Largest centre-to-particle distance (d).
    pub max_distance: f64,
}

/// `n` directions spread nearly uniformly over the sphere.
fn fibonacci_directions(n: usize) -> Vec<[f64; 3]> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|k| {
            let z = 1.0 - (2.0 * k as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * k as f64;
            [r * phi.cos(), r * phi.sin(), z]
        })
        .collect()
}

/// The roughness of the grain at `x`, measured from its centre of mass with
/// about one direction cell per `area` d^2 of the sphere of radius R.
pub fn roughness(x: &[[f64; 3]], area: f64) -> Roughness {
    let c = centre_of(x);
    let rel: Vec<[f64; 3]> = x
        .iter()
        .map(|p| [p[0] - c[0], p[1] - c[1], p[2] - c[2]])
        .collect();
    let dist = |p: &[f64; 3]| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    let max_distance = rel.iter().map(dist).fold(0.0, f64::max);
    let cells = ((4.0 * std::f64::consts::PI * max_distance * max_distance / area).round()
        as usize)
        .clamp(6, 5000);
    let dirs = fibonacci_directions(cells);
    let mut height = vec![f64::NAN; cells];
    for p in &rel {
        let r = dist(p);
        if r == 0.0 {
            continue;
        }
        let cell = (0..cells)
            .max_by(|&a, &b| {
                let da = dirs[a][0] * p[0] + dirs[a][1] * p[1] + dirs[a][2] * p[2];
                let db = dirs[b][0] * p[0] + dirs[b][1] * p[1] + dirs[b][2] * p[2];
                da.total_cmp(&db)
            })
            .unwrap_or(0);
        if height[cell].is_nan() || r > height[cell] {
            height[cell] = r;
        }
    }
    let h: Vec<f64> = height.into_iter().filter(|h| !h.is_nan()).collect();
    let n = h.len().max(1) as f64;
    let mean = h.iter().sum::<f64>() / n;
    let var = h.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    Roughness {
        cells,
        mean_height: mean,
        sd_height: var.sqrt(),
        max_distance,
    }
}

/// A closed box with `margin` around the points, and the points moved so
/// their bounding box is centred in it.
fn closed_box_around(x: &mut [[f64; 3]], margin: f64) -> BoxSpec {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in x.iter() {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let lengths = [0, 1, 2].map(|d| hi[d] - lo[d] + 2.0 * margin);
    for p in x.iter_mut() {
        for d in 0..3 {
            p[d] += margin - lo[d];
        }
    }
    BoxSpec {
        lo: [0.0; 3],
        lengths,
        tilt: [0.0; 3],
        periodic: [false; 3],
    }
}

/// Builds one grain.
pub fn build_grain(
    params: &GrainParams,
    threads: usize,
    progress: bool,
) -> Result<(Scene, GrainSummary), SceneError> {
    params.validate()?;
    let start = std::time::Instant::now();
    let r = params.radius;
    // A periodic solid wider than the sphere, so the cut sees no image.
    let mut bulk_params = BulkParams::paper(2.0 * r + 3.0, params.seed, params.a_b);
    bulk_params.relax_time *= params.time_scale;
    bulk_params.thermal_time *= params.time_scale;
    bulk_params.quench_time *= params.time_scale;
    let bond_cutoff = bulk_params.bond_cutoff;
    let (bulk, _) = build_bulk(&bulk_params, threads, progress)?;
    let simbox = simbox_of(&bulk);
    let image = simbox.minimum_image();
    let centre = simbox.centre();
    let mut index = vec![usize::MAX; bulk.particles.positions.len()];
    let mut x = Vec::new();
    for (i, p) in bulk.particles.positions.iter().enumerate() {
        let d = image.delta(p, &centre);
        if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() <= r {
            index[i] = x.len();
            x.push([centre[0] + d[0], centre[1] + d[1], centre[2] + d[2]]);
        }
    }
    let n = x.len();
    let mut scene = bulk.clone();
    scene.description = format!(
        "{} grain R = {r} d, seed {}, a_B = {}",
        params.kind.name(),
        params.seed,
        params.a_b
    );
    scene.particles.velocities = None;
    scene.particles.grain = None;
    let margin = params.margin + params.cage_offset + params.cage_amplitude;
    scene.simbox = closed_box_around(&mut x, margin);
    scene.particles.positions = x;
    let (pairs, lengths): (Vec<[usize; 2]>, Vec<f64>) = match params.kind {
        GrainKind::Rough => {
            // Bonds of the solid whose both ends are in the sphere, with
            // their reference lengths.
            let r0 = reference_lengths(&bulk);
            bulk.bonds
                .pairs
                .iter()
                .zip(r0)
                .filter(|(&[i, j], _)| index[i] != usize::MAX && index[j] != usize::MAX)
                .map(|(&[i, j], r0)| ([index[i], index[j]], r0))
                .unzip()
        }
        GrainKind::Smoother => {
            let x = vibrate_in_cage(&scene, params, threads, progress)?;
            scene.particles.positions = x;
            let simbox = simbox_of(&scene);
            pairs_within(&simbox, &scene.particles.positions, bond_cutoff)
                .into_iter()
                .map(|(i, j, r)| ([i, j], r))
                .unzip()
        }
    };
    scene.bonds = Bonds {
        pairs,
        r0: Some(lengths),
        plastic_strain: None,
    };
    scene.stages = Vec::new();
    let bonds = scene.bonds.pairs.len();
    let summary = GrainSummary {
        particles: n,
        bonds,
        mean_bonds_per_particle: 2.0 * bonds as f64 / n.max(1) as f64,
        roughness: roughness(&scene.particles.positions, 4.0),
        seconds: start.elapsed().as_secs_f64(),
    };
    scene.provenance = serde_json::json!({
        "builder": "grain",
        "version": crate::VERSION,
        "parameters": params,
        "bulk": bulk_params,
        "summary": summary,
    });
    Ok((scene, summary))
}

/// The smoother grain's vibration: the unbonded sphere in an oscillating
/// harmonic cage under viscous damping; returns the final positions.
fn vibrate_in_cage(
    grain: &Scene,
    params: &GrainParams,
    threads: usize,
    progress: bool,
) -> Result<Vec<[f64; 3]>, SceneError> {
    // The cage has the contacts' stiffness and range (k and d by default).
    let (stiffness, cutoff) = grain.force_field.pair.map_or((1.0, 1.0), |p| (p.k, p.d));
    let mut cage = grain.clone();
    cage.bonds = Bonds::default();
    let centre = centre_of(&cage.particles.positions);
    let dt = 0.1;
    let mut stage = StageSpec::hold(
        "vibrate",
        (params.cage_time * params.time_scale / dt).round() as u64,
        dt,
    );
    stage.viscous = params.cage_viscous;
    stage.sphere_wall = Some(SphereWall {
        centre,
        radius: params.radius + params.cage_offset,
        velocity: 0.0,
        amplitude: params.cage_amplitude,
        period: params.cage_period,
        decay_time: params.cage_decay,
        stiffness,
        cutoff,
    });
    // Then settle without the cage, still damped, so nothing moves when
    // bonds are made.
    let mut settle = StageSpec::hold(
        "settle",
        (200.0 * params.time_scale / dt).round() as u64,
        dt,
    );
    settle.viscous = params.cage_viscous;
    cage.stages = vec![stage, settle];
    let sys = super::run_build_stages(&cage, "grain builder (cage vibration)", threads, progress)?;
    Ok(sys.particles.x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roughness_of_a_sampled_sphere_surface_is_small_and_of_a_cube_is_not() {
        // Points on a sphere of radius 5, each with its antipode so the
        // centre of mass is exactly the centre: heights all 5.
        let dirs = fibonacci_directions(1000);
        let mut sphere: Vec<[f64; 3]> = dirs
            .iter()
            .flat_map(|u| [u.map(|c| 5.0 * c), u.map(|c| -5.0 * c)])
            .collect();
        sphere.push([0.0; 3]);
        let r = roughness(&sphere, 1.0);
        assert!(
            (r.mean_height - 5.0).abs() < 1e-9 && r.sd_height < 1e-9,
            "{r:?}"
        );
        // A cube's surface: heights from half the side to half the diagonal.
        let mut cube = Vec::new();
        for i in 0..=10 {
            for j in 0..=10 {
                for k in 0..=10 {
                    cube.push([i as f64 - 5.0, j as f64 - 5.0, k as f64 - 5.0]);
                }
            }
        }
        let c = roughness(&cube, 1.0);
        assert!(c.sd_height > 0.5, "{c:?}");
        assert!((c.max_distance - 75f64.sqrt()).abs() < 1e-12);
    }
}
