//! Built-in cross-check scenes.

use crate::engine::{Deformation, GranularWall, ShearRemap, TiltFactor, WallSide};
use crate::kernels::{
    GranularMaterial, NormalDamping, Separation, SpringDashpotSlider, Twisting, Unwrapped,
};
use crate::scene::builders::bulk::{build_bulk, BulkParams};
use crate::scene::builders::spheres::{sphere_lattice, SphereLattice};
use crate::scene::{ForceField, Scene, SceneError, StageSpec};
use rand::{Rng, SeedableRng};

/// A small bulk solid at its reference state (every bond at its `r0`, zero
/// velocities) with its bonds across the plane `z = L/2` removed: two bodies
/// that touch through pair contacts only. The build is
/// [`BulkParams::shortened`].
pub fn contact_solid_reference(size: f64, seed: u64, a_b: f64) -> Result<Scene, SceneError> {
    let mut s = build_bulk(&BulkParams::shortened(size, seed, 0.0), 1, false)?.0;
    s.force_field = ForceField::paper(a_b);
    let cut = 0.5 * size;
    let z = &s.particles.positions;
    let r0 = s.bonds.r0.clone().unwrap_or_default();
    let keep: Vec<usize> = (0..s.bonds.pairs.len())
        .filter(|&k| {
            let [i, j] = s.bonds.pairs[k];
            (z[i][2] < cut) == (z[j][2] < cut)
        })
        .collect();
    s.bonds.pairs = keep.iter().map(|&k| s.bonds.pairs[k]).collect();
    s.bonds.r0 = Some(keep.iter().map(|&k| r0[k]).collect());
    s.stages = vec![StageSpec::hold("point", 0, 0.1)];
    s.description = format!("contact solid L = {size} d at reference, seed {seed}, a_B = {a_b}");
    Ok(s)
}

/// [`contact_solid_reference`] compressed 1.5% with a small seeded jitter
/// and random velocities (rms about 0.05): bonds carry force, damping acts,
/// and the two halves press on each other through pair contacts.
pub fn contact_solid(size: f64, seed: u64, a_b: f64) -> Result<Scene, SceneError> {
    let mut s = contact_solid_reference(size, seed, a_b)?;
    let squeeze = 0.985;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5EED);
    for x in s.particles.positions.iter_mut() {
        for c in x.iter_mut() {
            *c = *c * squeeze + rng.gen_range(-5e-3..5e-3);
        }
    }
    s.simbox.lengths = s.simbox.lengths.map(|l| l * squeeze);
    let n = s.particles.positions.len();
    s.particles.velocities = Some(
        (0..n)
            .map(|_| {
                [
                    rng.gen_range(-0.05..0.05),
                    rng.gen_range(-0.05..0.05),
                    rng.gen_range(-0.05..0.05),
                ]
            })
            .collect(),
    );
    s.description = format!("contact solid L = {size} d, seed {seed}, a_B = {a_b}");
    Ok(s)
}

/// Two rough grains of radius `radius` (spheres cut from a quick bulk
/// solid at two places, docs/protocols.md "Grains"), side by side along x in a
/// closed box, their closest particles overlapping by 0.3 d, approaching
/// at 0.02 d / tau each: bonds, multibody volumes and grain-grain
/// contacts all act, without periodic images.
pub fn grain_pair(radius: f64, seed: u64, a_b: f64) -> Result<Scene, SceneError> {
    let size = (2.0 * radius + 3.0).max(6.0);
    let bulk = build_bulk(&BulkParams::shortened(size, seed, 0.0), 1, false)?.0;
    let simbox = crate::scene::validate::simbox_of(&bulk);
    let image = simbox.minimum_image();
    let r0 = crate::scene::load::reference_lengths(&bulk);
    let margin = 4.0;
    let (width, depth) = (
        4.0 * radius + 1.0 + 2.0 * margin,
        2.0 * radius + 2.0 * margin,
    );
    let mut positions = Vec::new();
    let mut velocities = Vec::new();
    let mut grain = Vec::new();
    let mut pairs = Vec::new();
    let mut lengths = Vec::new();
    let centre = simbox.centre();
    let gap = 2.0 * radius + 1.0 - 0.3;
    for (g, shift) in [0.0, 0.5 * size].into_iter().enumerate() {
        let cut = [centre[0], centre[1] + shift, centre[2]];
        let place = [
            margin + radius + 0.5 + g as f64 * gap,
            0.5 * depth,
            0.5 * depth,
        ];
        let mut index = vec![usize::MAX; bulk.particles.positions.len()];
        for (i, x) in bulk.particles.positions.iter().enumerate() {
            let d = image.delta(x, &cut);
            if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() <= radius {
                index[i] = positions.len();
                positions.push([place[0] + d[0], place[1] + d[1], place[2] + d[2]]);
                velocities.push([if g == 0 { 0.02 } else { -0.02 }, 0.0, 0.0]);
                grain.push(g as u32);
            }
        }
        for (k, &[i, j]) in bulk.bonds.pairs.iter().enumerate() {
            if index[i] != usize::MAX && index[j] != usize::MAX {
                pairs.push([index[i], index[j]]);
                lengths.push(r0[k]);
            }
        }
    }
    // Rough grains rarely have a particle exactly at radius R: slide grain 1
    // along x until the closest inter-grain pair is 0.3 d inside contact.
    let first = grain
        .iter()
        .position(|&g| g == 1)
        .unwrap_or(positions.len());
    let closest = |p: &[[f64; 3]]| {
        p[..first]
            .iter()
            .flat_map(|a| p[first..].iter().map(move |b| Unwrapped.distance(a, b)))
            .fold(f64::INFINITY, f64::min)
    };
    for _ in 0..50 {
        let shift = closest(&positions) - 0.7;
        if !shift.is_finite() || shift.abs() < 1e-12 {
            break;
        }
        for x in &mut positions[first..] {
            x[0] -= shift;
        }
    }
    Ok(Scene {
        version: crate::scene::SCENE_VERSION,
        model: crate::scene::ModelKind::Bpm,
        description: format!(
            "two rough grains R = {radius} d in contact, seed {seed}, a_B = {a_b}"
        ),
        seed,
        simbox: crate::scene::BoxSpec {
            lo: [0.0; 3],
            lengths: [width, depth, depth],
            tilt: [0.0; 3],
            periodic: [false; 3],
        },
        particles: crate::scene::Particles {
            positions,
            velocities: Some(velocities),
            angular_velocities: None,
            grain: Some(grain),
            mass: crate::scene::Mass::Uniform(1.0),
            radius: None,
            kind: None,
            ids: None,
        },
        bonds: crate::scene::Bonds {
            pairs,
            r0: Some(lengths),
            plastic_strain: None,
        },
        force_field: ForceField::paper(a_b),
        stages: vec![StageSpec::hold("point", 0, 0.1)],
        provenance: serde_json::json!({
            "builder": "verify::scenes::grain_pair", "radius": radius, "seed": seed,
            "bulk": BulkParams::shortened(size, seed, 0.0),
        }),
    })
}

/// `scene` with its stages replaced by one hold of `steps` steps that
/// records every 10 steps and positions five times.
pub fn as_trajectory(mut scene: Scene, steps: u64) -> Scene {
    let mut stage = StageSpec::hold("trajectory", steps, 0.1);
    stage.record.every = 10;
    stage.record.positions_every = (steps / 5).max(1);
    scene.stages = vec![stage];
    scene
}

/// `scene` restricted to the particles `keep` accepts (bonds among them,
/// with their reference lengths).
fn keep_particles(scene: &Scene, keep: impl Fn(usize) -> bool) -> Scene {
    let n = scene.particles.positions.len();
    let mut index = vec![usize::MAX; n];
    let mut out = scene.clone();
    let kept: Vec<usize> = (0..n).filter(|&i| keep(i)).collect();
    for (k, &i) in kept.iter().enumerate() {
        index[i] = k;
    }
    fn pick(v: &[[f64; 3]], kept: &[usize]) -> Vec<[f64; 3]> {
        kept.iter().map(|&i| v[i]).collect()
    }
    out.particles.positions = pick(&scene.particles.positions, &kept);
    out.particles.velocities = scene
        .particles
        .velocities
        .as_deref()
        .map(|v| pick(v, &kept));
    out.particles.grain = scene
        .particles
        .grain
        .as_ref()
        .map(|g| kept.iter().map(|&i| g[i]).collect());
    out.particles.ids = scene
        .particles
        .ids
        .as_ref()
        .map(|ids| kept.iter().map(|&i| ids[i]).collect());
    let r0 = crate::scene::load::reference_lengths(scene);
    let bonds: Vec<(usize, [usize; 2])> = scene
        .bonds
        .pairs
        .iter()
        .enumerate()
        .filter(|(_, [i, j])| index[*i] != usize::MAX && index[*j] != usize::MAX)
        .map(|(k, [i, j])| (k, [index[*i], index[*j]]))
        .collect();
    out.bonds.pairs = bonds.iter().map(|b| b.1).collect();
    out.bonds.r0 = Some(bonds.iter().map(|b| r0[b.0]).collect());
    out.bonds.plastic_strain = scene
        .bonds
        .plastic_strain
        .as_ref()
        .map(|e| bonds.iter().map(|b| e[b.0]).collect());
    out
}

/// One rough grain of radius `radius` between two flat harmonic walls
/// normal to z (stiffness k, cutoff d) that start 0.2 d clear of it and
/// close at `speed` each, its centre of mass tethered softly in x and y:
/// the Hertz squeeze set-up of docs/protocols.md at test scale. Records every 10
/// steps (wall forces included) and positions five times over `steps`.
pub fn grain_squeeze(
    radius: f64,
    seed: u64,
    a_b: f64,
    speed: f64,
    steps: u64,
) -> Result<Scene, SceneError> {
    let pair = grain_pair(radius, seed, a_b)?;
    let grain = pair.particles.grain.clone().unwrap_or_default();
    let mut s = keep_particles(&pair, |i| grain[i] == 0);
    s.particles.velocities = None;
    let z: Vec<f64> = s.particles.positions.iter().map(|x| x[2]).collect();
    let (lo, hi) = z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let cutoff = 1.0;
    let walls = vec![
        crate::engine::FlatWall {
            axis: 2,
            side: crate::engine::WallSide::Lo,
            position: lo - cutoff - 0.2,
            velocity: speed,
            stiffness: 1.0,
            cutoff,
        },
        crate::engine::FlatWall {
            axis: 2,
            side: crate::engine::WallSide::Hi,
            position: hi + cutoff + 0.2,
            velocity: -speed,
            stiffness: 1.0,
            cutoff,
        },
    ];
    let mut stage = StageSpec::hold("squeeze", steps, 0.1);
    stage.walls = walls;
    stage.tether = Some(crate::engine::Tether {
        grain: Some(0),
        anchor: None,
        dims: [true, true, false],
        stiffness: 1e-2,
    });
    stage.record.every = 10;
    stage.record.positions_every = (steps / 5).max(1);
    s.stages = vec![stage];
    s.description = format!("rough grain R = {radius} d squeezed between flat walls at {speed} d/tau each, seed {seed}, a_B = {a_b}");
    s.provenance = serde_json::json!({
        "builder": "verify::scenes::grain_squeeze", "radius": radius, "seed": seed, "speed": speed, "from": pair.provenance,
    });
    Ok(s)
}

/// The compaction cross-check's scene: 16 rough grains of radius 2 (built
/// with a twentieth of the grain protocol's times, two distinct grains)
/// jammed by the barostat (gain 1 per step, 2,000 tau) and compressed at
/// 3e-5 then 1e-4 per tau to 25% volumetric strain: about 33,000 steps of
/// 650 particles that form and rearrange contacts.
pub fn small_compaction(seed: u64) -> Result<Scene, SceneError> {
    use crate::scene::builders::grain::GrainKind;
    use crate::scene::builders::packing::{build_packing, PackingParams};
    use crate::scene::protocols::{compaction_scene, CompactionProtocol};
    let mut params = PackingParams::new(16, GrainKind::Rough, 2.0, 0.0, seed);
    params.grain.time_scale = 0.05;
    params.distinct_grains = 2;
    let (packing, _) = build_packing(&params, 1, false)?;
    let protocol = CompactionProtocol {
        jam_gain: 1.0,
        jam_time: 2000.0,
        rate_start: 3e-5,
        rate_end: 1e-4,
        rate_levels: 2,
        stage_time: 500.0,
        volumetric_strain: 0.25,
        rows_per_stage: 50,
        states_per_stage: 2,
        ..CompactionProtocol::paper()
    };
    Ok(compaction_scene(&packing, &protocol))
}

/// The sphere material of the DEM cross-check scenes: E = 100 k/d, nu =
/// 1/4, e = 1/2 (Tsuji), x_gt = 1, mu_s = 0.3; with `rolling_twisting`,
/// rolling (k_r = 10 k, gamma_r = 0.5, mu_r = 0.1) and Marshall twisting.
pub fn dem_check_material(rolling_twisting: bool) -> GranularMaterial {
    GranularMaterial {
        youngs_modulus: 100.0,
        poisson_ratio: 0.25,
        restitution: 0.5,
        damping: NormalDamping::Tsuji,
        tangential_damping: 1.0,
        sliding_friction: 0.3,
        rolling: rolling_twisting.then_some(SpringDashpotSlider {
            stiffness: 10.0,
            damping: 0.5,
            friction: 0.1,
        }),
        twisting: if rolling_twisting {
            Twisting::Marshall
        } else {
            Twisting::None
        },
    }
}

/// 64 DEM spheres of radius 1 +- 10% on a jittered lattice 0.95 diameters
/// apart, so most neighbours overlap, moving (velocity components up to
/// 0.05 d/tau) and spinning (up to 0.05 / tau): every term of the contact
/// force acts. One hold stage of 0 steps.
pub fn dem_lattice(seed: u64, rolling_twisting: bool) -> Scene {
    let mut scene = sphere_lattice(&SphereLattice {
        per_side: 4,
        radius: 1.0,
        polydispersity: 0.1,
        spacing: 0.95,
        jitter: 0.05,
        speed: 0.05,
        spin: 0.05,
        density: 1.0,
        material: dem_check_material(rolling_twisting),
        seed,
    });
    scene.stages = vec![StageSpec::hold("point", 0, 0.01)];
    scene
}

/// How a DEM cross-check trajectory loads its spheres.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DemLoading {
    /// The box held.
    Hold,
    /// Isotropic compression at true strain rate -1e-3 / tau.
    Compress,
    /// Simple shear (xy) at 1e-2 / tau.
    Shear,
    /// Lees-Edwards simple shear (xy, remap v) at 6e-2 / tau: the tilt
    /// passes half a box length and flips once in 1,000 steps.
    LeesEdwards,
    /// Between two granular walls normal to z (the box closed in z): the
    /// lower one fixed, pressing on the bottom layer from the start, with
    /// rolling and twisting friction (mu_s = 0.5); the upper one rigid
    /// (E = 1e4), starting clear of the spheres and closing at 0.02
    /// d/tau.
    Walls,
}

impl DemLoading {
    /// Its name in verdicts.
    pub fn name(self) -> &'static str {
        match self {
            DemLoading::Hold => "hold",
            DemLoading::Compress => "compress",
            DemLoading::Shear => "shear",
            DemLoading::LeesEdwards => "lees-edwards",
            DemLoading::Walls => "walls",
        }
    }
}

/// [`dem_lattice`] run for `steps` steps of 0.01 tau under `loading`,
/// recording every 50 steps and positions five times.
pub fn dem_trajectory(seed: u64, rolling_twisting: bool, loading: DemLoading, steps: u64) -> Scene {
    let mut scene = dem_lattice(seed, rolling_twisting);
    let mut stage = StageSpec::hold(loading.name(), steps, 0.01);
    stage.deformation = match loading {
        DemLoading::Hold | DemLoading::Walls => None,
        DemLoading::Compress => Some(Deformation::Isotropic {
            true_strain_rate: -1e-3,
        }),
        DemLoading::Shear => Some(Deformation::SimpleShear {
            remap: ShearRemap::X,
            tilt: TiltFactor::Xy,
            rate: 1e-2,
        }),
        DemLoading::LeesEdwards => Some(Deformation::SimpleShear {
            remap: ShearRemap::V,
            tilt: TiltFactor::Xy,
            rate: 6e-2,
        }),
    };
    if loading == DemLoading::Walls {
        between_walls(&mut scene, &mut stage);
    }
    stage.record.every = 50;
    stage.record.positions_every = (steps / 5).max(1);
    scene.stages = vec![stage];
    scene
}

/// A walled scene's one stage split in two halves: the second,
/// `release`, redefines every wall where the first left it, moving the
/// other way. Its first evaluation is where a stage's walls restart their
/// friction springs and keep their load (for the multi-contact closure).
/// It sets the scene's force field again (in LAMMPS a `pair_coeff`, which
/// makes the pair style's kernels anew), which changes nothing.
pub fn with_release(mut scene: Scene) -> Scene {
    let mut squeeze = scene.stages.remove(0);
    squeeze.steps /= 2;
    let elapsed = squeeze.steps as f64 * squeeze.dt;
    let mut release = squeeze.clone();
    release.name = "release".into();
    release.force_field = Some(scene.force_field.clone());
    for wall in &mut release.granular_walls {
        wall.position = wall.position_at(elapsed);
        wall.velocity = -wall.velocity;
    }
    scene.stages = vec![squeeze, release];
    scene
}

/// Closes the lattice's box in z, with room beyond its faces, and puts
/// the spheres between the two granular walls of [`DemLoading::Walls`].
fn between_walls(scene: &mut Scene, stage: &mut StageSpec) {
    let top = scene.simbox.lengths[2];
    scene.simbox.periodic[2] = false;
    scene.simbox.lo[2] = -0.5;
    scene.simbox.lengths[2] = top + 1.0;
    let spheres = dem_check_material(false);
    let lower = GranularMaterial {
        sliding_friction: 0.5,
        ..dem_check_material(true)
    };
    let upper = GranularMaterial {
        youngs_modulus: 1e4,
        ..spheres
    };
    stage.granular_walls = vec![
        GranularWall {
            axis: 2,
            side: WallSide::Lo,
            position: 0.0,
            velocity: 0.0,
            material: lower,
            keep_history: false,
        },
        GranularWall {
            axis: 2,
            side: WallSide::Hi,
            position: top + 0.3,
            velocity: -0.02,
            material: upper,
            keep_history: false,
        },
    ];
}
