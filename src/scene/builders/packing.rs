//! Packings of bonded grains for compaction (docs/protocols.md,
//! "Compaction"), stress-free and just below jamming.
//!
//! 1. **Template.** `grains` spheres of the grains' volume-equivalent
//!    radius (`R_eq`: the sphere with the volume of the grain's convex hull
//!    joined with its particles, by Monte Carlo) at random centres in a
//!    periodic cube sized for volume fraction `template_fraction`; overlaps
//!    are removed by overdamped soft-sphere dynamics (harmonic repulsion,
//!    viscous damping) until no two spheres overlap.
//! 2. **Placement.** `distinct_grains` grains are built (seeds `seed`,
//!    `seed + 1`, ...); sphere `i` gets grain `i mod distinct_grains`,
//!    rotated uniformly at random about its centre of mass. Grains are
//!    stored whole (unwrapped); both engines map them across the periodic
//!    faces at load.
//! 3. **Relaxation.** Grains reach beyond `R_eq`, so neighbours overlap a
//!    little: overlapping grains are pushed apart as rigid bodies
//!    (translations along the line of centres, a quarter of the deepest
//!    overlap each per sweep) until none touches. Rigid moves, not dynamics:
//!    under a soft repulsion the rough surfaces of deformable grains
//!    interlock and stay overlapped.
//! 4. **Contacts broken.** While two particles of different grains are
//!    closer than d, the box and the grain centres expand by 0.1% (grains
//!    move rigidly).
//!
//! The compaction's first stage then zeroes velocities and resets every
//! bond's reference length, so the packing starts stress-free.
//!
//! DEM spheres for the comparison ([`build_sphere_packing`]) sit at the
//! template's centres: step 1 only.

use super::grain::{build_grain, GrainKind, GrainParams};
use crate::engine::pairs_within;
use crate::engine::SimBox;
use crate::kernels::{GranularMaterial, PairCoeffs, Separation};
use crate::scene::load::reference_lengths;
use crate::scene::model::{Bonds, ForceField, Mass, ModelKind, Scene, StageSpec};
use crate::scene::rotation::{centre_of, uniform_rotation};
use crate::scene::validate::{simbox_of, SceneError};
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// Parameters of a packing (lengths in d).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PackingParams {
    /// Number of grains (paper: 1,024).
    pub grains: usize,
    /// The grains: kind, radius R, a_B, build times; its seed is the first
    /// grain's.
    pub grain: GrainParams,
    /// How many different grains are built and reused (rotated) across the
    /// packing.
    pub distinct_grains: usize,
    /// Volume fraction of the template spheres (paper: 0.57).
    pub template_fraction: f64,
    /// Seed of the template and of the rotations.
    pub seed: u64,
}

/// Largest template fraction: overdamped soft spheres jam near 0.64, and
/// relax ever more slowly as they approach it.
pub const MAX_TEMPLATE_FRACTION: f64 = 0.62;

impl PackingParams {
    /// `grains` grains of `kind` and radius `radius` at `a_b`, the paper's
    /// template fraction 0.57, and four distinct grains.
    pub fn new(grains: usize, kind: GrainKind, radius: f64, a_b: f64, seed: u64) -> Self {
        Self {
            grains,
            grain: GrainParams::new(kind, radius, seed, a_b),
            distinct_grains: 4,
            template_fraction: 0.57,
            seed,
        }
    }

    /// Checks the parameters; the error names the offending one.
    pub fn validate(&self) -> Result<(), SceneError> {
        let bad = |field: &str, reason: String| SceneError::Invalid {
            field: field.into(),
            reason,
        };
        self.grain.validate()?;
        if self.grains < 2 {
            return Err(bad(
                "grains",
                format!("must be at least 2, got {}", self.grains),
            ));
        }
        if self.distinct_grains == 0 {
            return Err(bad("distinct_grains", "must be at least 1".into()));
        }
        let f = self.template_fraction;
        if !(f.is_finite() && f > 0.0 && f <= MAX_TEMPLATE_FRACTION) {
            return Err(bad(
                "template_fraction",
                format!("must be in (0, {MAX_TEMPLATE_FRACTION}], got {f}"),
            ));
        }
        Ok(())
    }
}

/// What the builder reports besides the scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PackingSummary {
    /// Grains.
    pub grains: usize,
    /// Particles.
    pub particles: usize,
    /// Bonds.
    pub bonds: usize,
    /// Largest centre-to-particle distance of the built grains plus d/2.
    pub outer_radius: f64,
    /// Mean volume-equivalent radius R_eq of the built grains: the radius
    /// of the template's spheres.
    pub template_radius: f64,
    /// Edge of the cubic box (d).
    pub box_length: f64,
    /// Steps of overdamped relaxation the template needed.
    pub template_steps: u64,
    /// Sweeps of rigid relaxation of the placed grains.
    pub relax_sweeps: u64,
    /// Linear expansion of the box after the template (1 = none): room
    /// for grains jammed as rigid bodies, and the breaking of contacts.
    pub expansion: f64,
    /// Volume fraction of the template's spheres in the final box.
    pub sphere_fraction: f64,
    /// Wall-clock seconds of the build.
    pub seconds: f64,
}

/// The template: `n` sphere centres of diameter `diameter` in a periodic
/// cube of edge `length`, relaxed until no two overlap by more than
/// `1e-9 diameter`. Returns the centres and the relaxation steps.
pub fn template_centres(
    n: usize,
    diameter: f64,
    length: f64,
    seed: u64,
    threads: usize,
) -> Result<(Vec<[f64; 3]>, u64), SceneError> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let positions: Vec<[f64; 3]> = (0..n)
        .map(|_| [0, 1, 2].map(|_| rng.gen::<f64>() * length))
        .collect();
    let soft = ForceField {
        pair: Some(PairCoeffs {
            k: 1.0,
            d: diameter,
            a: 0.0,
            gamma: 0.0,
        }),
        ..ForceField::paper(0.0)
    };
    const CHUNK: u64 = 2000;
    const MAX_CHUNKS: u64 = 200;
    let mut relax = StageSpec::hold("relax template", CHUNK, 0.1);
    relax.viscous = 1.0;
    let mut scene = super::periodic_cube("packing template".into(), seed, length, positions, soft);
    scene.stages = vec![relax];
    let simbox = simbox_of(&scene);
    for chunk in 1..=MAX_CHUNKS {
        let sys = super::run_build_stages(&scene, "packing template", threads, false)?;
        scene.particles.positions = sys.particles.x.clone();
        let worst = pairs_within(&simbox, &scene.particles.positions, diameter)
            .iter()
            .fold(0.0, |w: f64, &(_, _, r)| w.max(diameter - r));
        if worst <= 1e-9 * diameter {
            return Ok((scene.particles.positions, chunk * CHUNK));
        }
    }
    Err(SceneError::Invalid {
        field: "template_fraction".into(),
        reason: format!(
            "the template spheres still overlap after {} steps of relaxation: use a lower fraction",
            MAX_CHUNKS * CHUNK
        ),
    })
}

/// Pairs of particles of different grains closer than `contact`.
fn grain_contacts(simbox: &SimBox, x: &[[f64; 3]], grain: &[u32], contact: f64) -> usize {
    pairs_within(simbox, x, contact)
        .iter()
        .filter(|&&(i, j, _)| grain[i] != grain[j])
        .count()
}

/// Expands the box of `scene` (orthogonal, periodic) by 0.1% at a time,
/// moving each grain rigidly with it, until no two particles of different
/// grains are closer than the pair range d; grains must be whole in
/// `scene`. Returns the linear expansion factor (1 when nothing touched).
pub fn break_contacts(scene: &mut Scene) -> Result<f64, SceneError> {
    let contact = scene.force_field.pair.map_or(0.0, |p| p.d);
    let grain = scene
        .particles
        .grain
        .clone()
        .unwrap_or_else(|| vec![0; scene.particles.positions.len()]);
    let count = grain.iter().map(|&g| g as usize + 1).max().unwrap_or(0);
    let mut total = 1.0;
    const STEP: f64 = 1.001;
    for _ in 0..2000 {
        let simbox = simbox_of(scene);
        if grain_contacts(&simbox, &scene.particles.positions, &grain, contact) == 0 {
            return Ok(total);
        }
        let mut centres = grain_centres(&scene.particles.positions, &grain, count);
        expand_rigidly(scene, &mut centres, &grain, STEP);
        total *= STEP;
    }
    Err(SceneError::Invalid {
        field: "packing".into(),
        reason: format!("grains still touch after expanding the box by {total:.3}"),
    })
}

/// Radius of the sphere with the volume of the grain at `rel` (positions
/// about its centre): its convex hull joined with its particles (diameter
/// `d`), by Monte Carlo with 200,000 points (standard error about 0.1%).
fn equivalent_radius(rel: &[[f64; 3]], d: f64, seed: u64) -> Result<f64, SceneError> {
    use crate::analysis::packing::{monte_carlo_volume_fraction, Hull};
    let extent = rel
        .iter()
        .map(|x| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt())
        .fold(0.0, f64::max);
    let side = 2.0 * (extent + d);
    let simbox = SimBox {
        lo: [-0.5 * side; 3],
        lengths: [side; 3],
        tilt: [0.0; 3],
        periodic: [true; 3],
    };
    let hull = Hull::of(rel).map_err(|e| SceneError::Invalid {
        field: "grain".into(),
        reason: format!("the built grain has no convex hull: {e}"),
    })?;
    let phi = monte_carlo_volume_fraction(&simbox, &[hull], rel, 0.5 * d, 200_000, seed);
    Ok((phi.phi * side.powi(3) * 3.0 / (4.0 * std::f64::consts::PI)).cbrt())
}

/// Pushes overlapping grains apart as rigid bodies (translations only, so
/// rough surfaces cannot interlock): in each sweep every pair of grains
/// with particles closer than `d` moves apart along the line of their
/// centres by a quarter of its deepest overlap each (plus `1e-3 d`), until
/// no two particles of different grains are closer than `d`. Grains too
/// crowded to separate (jammed as rigid bodies) get room: every 500 sweeps
/// without success the box and the grain centres expand by 0.5%. Returns
/// the sweeps and the linear expansion.
fn relax_overlaps(scene: &mut Scene, centres: &mut [[f64; 3]]) -> Result<(u64, f64), SceneError> {
    let d = scene.force_field.pair.map_or(0.0, |p| p.d);
    let grain = scene.particles.grain.clone().unwrap_or_default();
    let mut simbox = simbox_of(scene);
    let mut image = simbox.minimum_image();
    const MAX_SWEEPS: u64 = 50_000;
    const EXPAND_EVERY: u64 = 500;
    let mut expansion = 1.0;
    for sweep in 0..MAX_SWEEPS {
        // Ordered, so the shifts are summed in the same order every run.
        let mut deepest = std::collections::BTreeMap::<(u32, u32), f64>::new();
        for (i, j, r) in pairs_within(&simbox, &scene.particles.positions, d) {
            let (a, b) = (grain[i].min(grain[j]), grain[i].max(grain[j]));
            if a != b {
                let e = deepest.entry((a, b)).or_insert(0.0);
                *e = e.max(d - r + 1e-3 * d);
            }
        }
        if deepest.is_empty() {
            return Ok((sweep, expansion));
        }
        if sweep > 0 && sweep % EXPAND_EVERY == 0 {
            // Jammed as rigid bodies: give them room.
            expand_rigidly(scene, centres, &grain, 1.005);
            expansion *= 1.005;
            simbox = simbox_of(scene);
            image = simbox.minimum_image();
            continue;
        }
        let mut shift = vec![[0.0; 3]; centres.len()];
        for (&(a, b), &overlap) in &deepest {
            let (a, b) = (a as usize, b as usize);
            let n = image.delta(&centres[b], &centres[a]);
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt().max(1e-12);
            for k in 0..3 {
                let m = 0.25 * overlap * n[k] / len;
                shift[a][k] -= m;
                shift[b][k] += m;
            }
        }
        for (c, s) in centres.iter_mut().zip(&shift) {
            for k in 0..3 {
                c[k] += s[k];
            }
        }
        for (x, &g) in scene.particles.positions.iter_mut().zip(&grain) {
            for k in 0..3 {
                x[k] += shift[g as usize][k];
            }
        }
    }
    Err(SceneError::Invalid {
        field: "template_fraction".into(),
        reason: format!(
            "placed grains still overlap after {MAX_SWEEPS} sweeps of rigid relaxation: use a lower fraction"
        ),
    })
}

/// The mean position of each grain's particles.
fn grain_centres(x: &[[f64; 3]], grain: &[u32], count: usize) -> Vec<[f64; 3]> {
    let mut sums = vec![[0.0; 3]; count];
    let mut n = vec![0usize; count];
    for (x, &g) in x.iter().zip(grain) {
        for d in 0..3 {
            sums[g as usize][d] += x[d];
        }
        n[g as usize] += 1;
    }
    sums.iter()
        .zip(&n)
        .map(|(s, &k)| s.map(|v| v / k.max(1) as f64))
        .collect()
}

/// Scales the (orthogonal) box of `scene` by `factor` about its lower
/// corner and moves each grain rigidly so its centre scales with it.
fn expand_rigidly(scene: &mut Scene, centres: &mut [[f64; 3]], grain: &[u32], factor: f64) {
    let lo = scene.simbox.lo;
    let shift: Vec<[f64; 3]> = centres
        .iter()
        .map(|c| [0, 1, 2].map(|d| (factor - 1.0) * (c[d] - lo[d])))
        .collect();
    for (c, s) in centres.iter_mut().zip(&shift) {
        for d in 0..3 {
            c[d] += s[d];
        }
    }
    for (x, &g) in scene.particles.positions.iter_mut().zip(grain) {
        for d in 0..3 {
            x[d] += shift[g as usize][d];
        }
    }
    scene.simbox.lengths = scene.simbox.lengths.map(|l| l * factor);
}

/// One built grain: particle positions relative to its centre of mass,
/// bonds, reference lengths.
type BuiltGrain = (Vec<[f64; 3]>, Vec<[usize; 2]>, Vec<f64>);

/// A built packing's grains and the template of their centres.
struct Template {
    /// The distinct grains.
    built: Vec<BuiltGrain>,
    /// Largest centre-to-particle distance plus d/2.
    outer_radius: f64,
    /// Mean volume-equivalent radius of the grains (the template spheres').
    template_radius: f64,
    /// Volume of one template sphere.
    sphere: f64,
    /// Box edge.
    length: f64,
    /// Template centres.
    centres: Vec<[f64; 3]>,
    /// Steps of the template's relaxation.
    template_steps: u64,
}

/// Builds the distinct grains and the template of centres (steps 1 of the
/// module doc), shared by bonded grains and DEM spheres so both start from
/// the same centres.
fn template(
    params: &PackingParams,
    threads: usize,
    progress: bool,
) -> Result<Template, SceneError> {
    params.validate()?;
    let distinct = params.distinct_grains.min(params.grains);
    let mut built = Vec::with_capacity(distinct);
    for k in 0..distinct {
        let mut p = params.grain.clone();
        p.seed = params.grain.seed + k as u64;
        let (scene, _) = build_grain(&p, threads, progress)?;
        let c = centre_of(&scene.particles.positions);
        let rel: Vec<[f64; 3]> = scene
            .particles
            .positions
            .iter()
            .map(|x| [x[0] - c[0], x[1] - c[1], x[2] - c[2]])
            .collect();
        let r0 = reference_lengths(&scene);
        built.push((rel, scene.bonds.pairs.clone(), r0));
    }
    let pair_d = ForceField::paper(params.grain.a_b)
        .pair
        .map_or(1.0, |p| p.d);
    let outer_radius = built
        .iter()
        .flat_map(|(rel, _, _)| rel.iter())
        .map(|x| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt())
        .fold(0.0, f64::max)
        + 0.5 * pair_d;
    let mut template_radius = 0.0;
    for (rel, _, _) in &built {
        template_radius += equivalent_radius(rel, pair_d, params.seed)? / distinct as f64;
    }
    let diameter = 2.0 * template_radius;
    let sphere = std::f64::consts::PI / 6.0 * diameter.powi(3);
    let length = (params.grains as f64 * sphere / params.template_fraction).cbrt();
    // The template's contact range must stay below half the box.
    let skin = ForceField::paper(0.0).skin;
    let reach = diameter + skin;
    if length <= 2.0 * reach {
        let needed =
            (params.template_fraction * (2.0 * reach).powi(3) / sphere).floor() as usize + 1;
        return Err(SceneError::Invalid {
            field: "grains".into(),
            reason: format!(
                "{} grains of radius {template_radius:.2} d fill a box of {length:.2} d, less than twice their template diameter plus skin: use at least {needed}",
                params.grains
            ),
        });
    }
    let (centres, template_steps) =
        template_centres(params.grains, diameter, length, params.seed, threads)?;
    Ok(Template {
        built,
        outer_radius,
        template_radius,
        sphere,
        length,
        centres,
        template_steps,
    })
}

/// Builds the packing; the returned scene holds no protocol stages.
pub fn build_packing(
    params: &PackingParams,
    threads: usize,
    progress: bool,
) -> Result<(Scene, PackingSummary), SceneError> {
    let start = std::time::Instant::now();
    let Template {
        built,
        outer_radius,
        template_radius,
        sphere,
        length,
        centres,
        template_steps,
    } = template(params, threads, progress)?;
    let distinct = built.len();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(params.seed ^ 0x9e37_79b9_7f4a_7c15);
    let mut positions = Vec::new();
    let mut grain = Vec::new();
    let mut pairs = Vec::new();
    let mut r0 = Vec::new();
    for (i, c) in centres.iter().enumerate() {
        let (rel, bonds, lengths) = &built[i % distinct];
        let rot = uniform_rotation([rng.gen(), rng.gen(), rng.gen()]);
        let offset = positions.len();
        for x in rel {
            let r = [0, 1, 2].map(|a| (0..3).map(|b| rot[a][b] * x[b]).sum::<f64>());
            positions.push([c[0] + r[0], c[1] + r[1], c[2] + r[2]]);
            grain.push(i as u32);
        }
        pairs.extend(bonds.iter().map(|[a, b]| [a + offset, b + offset]));
        r0.extend_from_slice(lengths);
    }
    let mut force_field = ForceField::paper(params.grain.a_b);
    force_field.zero_net_multibody = false;
    let description = format!(
        "packing of {} {} grains, R = {} d, a_B = {}, seed {}",
        params.grains,
        params.grain.kind.name(),
        params.grain.radius,
        params.grain.a_b,
        params.seed
    );
    let mut scene = super::periodic_cube(description, params.seed, length, positions, force_field);
    scene.particles.grain = Some(grain);
    scene.bonds = Bonds {
        pairs,
        r0: Some(r0),
        plastic_strain: None,
    };
    let mut grain_centres = centres.clone();
    let (relax_sweeps, crowding) = relax_overlaps(&mut scene, &mut grain_centres)?;
    let expansion = crowding * break_contacts(&mut scene)?;
    let box_length = scene.simbox.lengths[0];
    let summary = PackingSummary {
        grains: params.grains,
        particles: scene.particles.positions.len(),
        bonds: scene.bonds.pairs.len(),
        outer_radius,
        template_radius,
        box_length,
        template_steps,
        relax_sweeps,
        expansion,
        sphere_fraction: params.grains as f64 * sphere / box_length.powi(3),
        seconds: start.elapsed().as_secs_f64(),
    };
    scene.provenance = serde_json::json!({
        "builder": "packing",
        "version": crate::VERSION,
        "parameters": params,
        "summary": summary,
    });
    Ok((scene, summary))
}

/// Expands the (orthogonal) box of a DEM scene and its sphere centres
/// uniformly about the box's lower corner, just enough that no two spheres
/// touch (by `1e-9` relative beyond contact); returns the linear factor (1
/// when none touched). Spheres without radii have the default one. Two
/// spheres at one point cannot be separated so: an error names them.
pub fn separate_spheres(scene: &mut Scene) -> Result<f64, SceneError> {
    let n = scene.particles.positions.len();
    let radii = scene
        .particles
        .radius
        .clone()
        .unwrap_or_else(|| vec![crate::engine::particles::DEFAULT_RADIUS; n]);
    let largest = radii.iter().copied().fold(0.0, f64::max);
    let simbox = simbox_of(scene);
    let mut needed: f64 = 1.0;
    for (i, j, r) in pairs_within(&simbox, &scene.particles.positions, 2.0 * largest) {
        let contact = radii[i] + radii[j];
        if r <= 1e-9 * contact {
            return Err(SceneError::Invalid {
                field: "particles.positions".into(),
                reason: format!("spheres {i} and {j} sit at one point"),
            });
        }
        needed = needed.max(contact / r);
    }
    if needed <= 1.0 {
        return Ok(1.0);
    }
    let factor = needed * (1.0 + 1e-9);
    let lo = scene.simbox.lo;
    for x in &mut scene.particles.positions {
        for d in 0..3 {
            x[d] = lo[d] + (x[d] - lo[d]) * factor;
        }
    }
    scene.simbox.lengths = scene.simbox.lengths.map(|l| l * factor);
    Ok(factor)
}

/// DEM spheres at the centres of the same template as [`build_packing`]
/// (same parameters, same seed, so the same centres): one sphere per grain
/// with the grains' volume-equivalent radius `R_eq` (the template's, so the
/// spheres fill the template's volume fraction) and the mean mass of the
/// built grains (unit-mass particles), of `material`. The template leaves
/// overlaps of up to `1e-9` diameters; box and centres are expanded
/// uniformly until no two spheres touch ([`separate_spheres`]: a
/// stress-free start, as for the grains). The scene holds no protocol
/// stages.
pub fn build_sphere_packing(
    params: &PackingParams,
    material: GranularMaterial,
    threads: usize,
    progress: bool,
) -> Result<(Scene, PackingSummary), SceneError> {
    let start = std::time::Instant::now();
    let t = template(params, threads, progress)?;
    let particles_per_grain =
        t.built.iter().map(|(rel, _, _)| rel.len()).sum::<usize>() as f64 / t.built.len() as f64;
    let description = format!(
        "{} DEM spheres of radius {:.4} d (R_eq of {} grains, R = {} d), seed {}",
        params.grains,
        t.template_radius,
        params.grain.kind.name(),
        params.grain.radius,
        params.seed
    );
    let mut scene = super::periodic_cube(
        description,
        params.seed,
        t.length,
        t.centres,
        ForceField::dem(material),
    );
    scene.model = ModelKind::Dem;
    scene.particles.radius = Some(vec![t.template_radius; params.grains]);
    scene.particles.mass = Mass::Uniform(particles_per_grain);
    let expansion = separate_spheres(&mut scene)?;
    let length = scene.simbox.lengths[0];
    let summary = PackingSummary {
        grains: params.grains,
        particles: params.grains,
        bonds: 0,
        outer_radius: t.outer_radius,
        template_radius: t.template_radius,
        box_length: length,
        template_steps: t.template_steps,
        relax_sweeps: 0,
        expansion,
        sphere_fraction: params.grains as f64 * t.sphere / length.powi(3),
        seconds: start.elapsed().as_secs_f64(),
    };
    scene.provenance = serde_json::json!({
        "builder": "sphere packing",
        "version": crate::VERSION,
        "parameters": params,
        "summary": summary,
    });
    Ok((scene, summary))
}
