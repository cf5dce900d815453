//! DEM sphere scenes: spheres on a jittered cubic lattice in a periodic
//! cube, pressed into each other and set moving, for tests and the engine
//! cross-check.

use super::periodic_cube;
use crate::kernels::GranularMaterial;
use crate::scene::model::{Mass, ModelKind, Scene};
use crate::scene::ForceField;
use rand::{Rng, SeedableRng};

/// What [`sphere_lattice`] builds.
#[derive(Clone, Debug)]
pub struct SphereLattice {
    /// Spheres per box side (the scene has `per_side^3`).
    pub per_side: usize,
    /// Mean sphere radius (d).
    pub radius: f64,
    /// Radii are uniform in `radius (1 +- polydispersity)`.
    pub polydispersity: f64,
    /// Lattice spacing over the mean diameter: below 1, neighbours overlap.
    pub spacing: f64,
    /// Each coordinate is moved by up to this times the radius.
    pub jitter: f64,
    /// Velocity components are uniform in `+-speed` (d / tau).
    pub speed: f64,
    /// Angular velocity components are uniform in `+-spin` (1 / tau).
    pub spin: f64,
    /// Mass density (m / d^3): a sphere's mass is `4/3 pi r^3` times this.
    pub density: f64,
    /// The sphere material.
    pub material: GranularMaterial,
    /// Seed of every draw.
    pub seed: u64,
}

/// The scene of `p` (no stages yet).
pub fn sphere_lattice(p: &SphereLattice) -> Scene {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(p.seed ^ 0xD3E5);
    let spacing = 2.0 * p.radius * p.spacing;
    let length = spacing * p.per_side as f64;
    let mut positions = Vec::new();
    let mut radius = Vec::new();
    for a in 0..p.per_side {
        for b in 0..p.per_side {
            for c in 0..p.per_side {
                let mut x = [a, b, c].map(|k| (k as f64 + 0.5) * spacing);
                for xd in x.iter_mut() {
                    *xd += p.jitter * p.radius * rng.gen_range(-1.0..1.0);
                }
                positions.push(x);
                radius.push(p.radius * (1.0 + p.polydispersity * rng.gen_range(-1.0..1.0)));
            }
        }
    }
    let n = positions.len();
    let mut draw = |scale: f64| -> Vec<[f64; 3]> {
        (0..n)
            .map(|_| [0; 3].map(|_| scale * rng.gen_range(-1.0..1.0)))
            .collect()
    };
    let velocities = draw(p.speed);
    let angular_velocities = draw(p.spin);
    let mass = radius
        .iter()
        .map(|r| p.density * 4.0 / 3.0 * std::f64::consts::PI * r * r * r)
        .collect();
    let mut scene = periodic_cube(
        format!(
            "{n} DEM spheres of radius {} +- {}%, lattice spacing {} diameters, seed {}",
            p.radius,
            100.0 * p.polydispersity,
            p.spacing,
            p.seed
        ),
        p.seed,
        length,
        positions,
        ForceField::dem(p.material),
    );
    scene.model = ModelKind::Dem;
    scene.particles.radius = Some(radius);
    scene.particles.mass = Mass::PerParticle(mass);
    scene.particles.velocities = Some(velocities);
    scene.particles.angular_velocities = Some(angular_velocities);
    scene.provenance = serde_json::json!({
        "builder": "sphere_lattice",
        "per_side": p.per_side,
        "radius": p.radius,
        "polydispersity": p.polydispersity,
        "spacing": p.spacing,
        "jitter": p.jitter,
        "speed": p.speed,
        "spin": p.spin,
        "density": p.density,
        "seed": p.seed,
    });
    scene
}
