//! DEM spheres: the native engine against LAMMPS's own `pair_style
//! granular` (Debian LAMMPS 29Sep2021), and the model's physics in the
//! engine (contact history across pair-list rebuilds).

mod common;

use bpm::verify::{dem_lattice, lammps_single_point, max_relative_deviation, native_single_point};
use std::path::Path;

fn lmp() -> &'static Path {
    Path::new(env!("CARGO_BIN_EXE_lmp-bpm"))
}

#[test]
fn step_zero_forces_and_torques_match_lammps_granular() {
    let dir = common::scratch_dir("dem-point");
    for rolling_twisting in [false, true] {
        let scene = dem_lattice(7, rolling_twisting);
        let native = native_single_point(&scene);
        for (ranks, newton) in [(1, true), (2, false)] {
            let tag = format!("rt{rolling_twisting}-np{ranks}");
            let lammps = lammps_single_point(lmp(), &scene, newton, ranks, &dir, &tag).unwrap();
            let f = max_relative_deviation(&lammps.forces, &native.forces);
            let t = max_relative_deviation(&lammps.torques, &native.torques);
            let p = max_relative_deviation(&[lammps.pressure], &[native.pressure]);
            eprintln!("{tag}: forces {f:e} torques {t:e} stress {p:e}");
            let tol = bpm::verify::tolerances::tolerance;
            assert!(
                f <= tol("step-0 forces")
                    && t <= tol("step-0 torques")
                    && p <= tol("step-0 stress"),
                "{tag}: {f:e} {t:e} {p:e}"
            );
        }
    }
}

fn launcher(name: &str) -> bpm::verify::LammpsLauncher {
    bpm::verify::LammpsLauncher {
        bpm: std::path::PathBuf::from(env!("CARGO_BIN_EXE_bpm")),
        dir: common::scratch_dir(&format!("dem-{name}")),
    }
}

/// The rotational energy and stress after `steps` of `scene` on the native
/// engine, with the pair-list skin `skin` (d).
fn native_end(scene: &bpm::scene::Scene, skin: f64) -> (f64, [f64; 6], usize, u64) {
    let mut scene = scene.clone();
    scene.force_field.skin = skin;
    let mut sys = bpm::scene::build_system(&scene, 1);
    let drivers = bpm::engine::StageDrivers {
        dt: scene.stages[0].dt,
        deformation: scene.stages[0].deformation.clone(),
        ..Default::default()
    };
    sys.setup(&drivers).unwrap();
    let start = sys.simbox.clone();
    for step in 1..=scene.stages[0].steps {
        sys.step(&drivers, step, &start).unwrap();
    }
    sys.compute_forces(&drivers, 0.0, true);
    let dem = sys.model_as::<bpm::engine::DemModel>().unwrap();
    (
        sys.particles.rotational_energy(),
        sys.pressure_tensor(),
        dem.contacts().remembered(),
        sys.neighbours.builds,
    )
}

/// Sheared spheres rebuild their pair list often with a thin skin and
/// rarely with a thick one; the contact histories must survive every
/// rebuild, so the two runs differ by round-off only (a lost history
/// resets a tangential spring, a change of order one).
#[test]
fn contact_history_survives_pair_list_rebuilds() {
    let scene = bpm::verify::dem_trajectory(7, true, bpm::verify::DemLoading::Shear, 1500);
    let (e_thin, p_thin, kept_thin, builds_thin) = native_end(&scene, 0.05);
    let (e_thick, p_thick, kept_thick, builds_thick) = native_end(&scene, 0.6);
    assert!(
        builds_thin > 5 * builds_thick,
        "{builds_thin} vs {builds_thick} builds"
    );
    assert!(
        kept_thin > 50 && kept_thin == kept_thick,
        "{kept_thin} vs {kept_thick} contacts"
    );
    let scale = p_thick.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (a, b) in p_thin.iter().zip(&p_thick) {
        assert!((a - b).abs() < 1e-10 * scale, "{p_thin:?} vs {p_thick:?}");
    }
    assert!(
        (e_thin - e_thick).abs() < 1e-8 * e_thick,
        "{e_thin} vs {e_thick}"
    );
}

/// Plain Hertz, the standard closure and the advanced closure (whose
/// small ratio switches most contacts off).
fn closures() -> [Option<bpm::engine::MultiContact>; 3] {
    use bpm::engine::MultiContact;
    [
        None,
        Some(MultiContact::standard(1.5)),
        Some(MultiContact::advanced(1.5, 1e-3)),
    ]
}

/// Contacts formed four at a time give the one-at-a-time path's
/// trajectory bit for bit: sliding spheres under compression, affine
/// shear, Lees-Edwards shear (partners' image velocities) and between
/// granular walls, with plain Hertz and with the standard and advanced
/// multi-contact closures (corrected surfaces), over enough steps for
/// round-off to show; positions, spins, recorded rows and every contact
/// history must be identical.
#[test]
fn contact_blocks_follow_the_one_contact_path_bit_for_bit() {
    use bpm::verify::{dem_trajectory, DemLoading};
    let run = |scene: &bpm::scene::Scene, blocks: bool| {
        let mut sys = bpm::scene::build_system(scene, 1);
        sys.model_as_mut::<bpm::engine::DemModel>()
            .unwrap()
            .set_contact_blocks(blocks);
        let (stages, error) =
            bpm::scene::run_scene(&mut sys, scene, &bpm::scene::RunOptions::quiet(1));
        assert!(error.is_none(), "{error:?}");
        let histories = history_bits(sys.model_as::<bpm::engine::DemModel>().unwrap());
        let rows: Vec<Vec<u64>> = stages
            .iter()
            .flat_map(|s| &s.rows)
            .map(|r| r.iter().map(|v| v.to_bits()).collect())
            .collect();
        let spins = &sys.particles.rotation.as_ref().unwrap().omega;
        (bits(&sys.particles.x), bits(spins), rows, histories)
    };
    for loading in [
        DemLoading::Compress,
        DemLoading::Shear,
        DemLoading::LeesEdwards,
        DemLoading::Walls,
    ] {
        for closure in closures() {
            let mut scene = dem_trajectory(3, false, loading, 1000);
            scene.force_field.multicontact = closure;
            let case = format!("{loading:?} {closure:?}");
            let blocks = run(&scene, true);
            let touching = touching(&blocks.3);
            assert!(touching > 20, "{case}: {touching} touching pairs");
            let one = run(&scene, false);
            assert!(blocks.0 == one.0, "{case}: positions differ");
            assert!(blocks.1 == one.1, "{case}: spins differ");
            assert!(blocks.2 == one.2, "{case}: recorded rows differ");
            assert!(blocks.3 == one.3, "{case}: contact histories differ");
        }
    }
}

/// A uniform drift changes no relative motion: held spheres with rolling
/// and twisting friction lose the same rotational energy whether they
/// drift across the periodic box or not. (LAMMPS 2021 fails this:
/// results/dem/divergence.txt.)
#[test]
fn rolling_and_twisting_friction_do_not_see_a_uniform_drift() {
    let rest = bpm::verify::dem_trajectory(7, true, bpm::verify::DemLoading::Hold, 4000);
    let mut drifting = rest.clone();
    for v in drifting.particles.velocities.iter_mut().flatten() {
        v[0] += 0.5;
        v[1] += 0.3;
    }
    let (e_rest, _, _, _) = native_end(&rest, 0.3);
    let (e_drift, _, _, builds) = native_end(&drifting, 0.3);
    assert!(builds > 20, "the drift crosses the box: {builds} rebuilds");
    // The spheres settle: rotational energy falls by about 1e8 from 0.14.
    assert!(e_rest < 1e-8, "{e_rest}");
    assert!(
        (e_rest - e_drift).abs() < 1e-9 * e_rest,
        "{e_rest} vs {e_drift}"
    );
}

/// Short trajectories agree with LAMMPS within the tolerance table:
/// sliding friction under compression, under affine and Lees-Edwards shear
/// (through a tilt flip) and between granular walls (1,000 steps, before
/// sheared spheres' chaos amplifies round-off), rolling and twisting
/// friction held for `bpm check`'s 2,000 steps with its skin, at several
/// seeds (LAMMPS 2021 flips those histories when a rebuild swaps a pair's
/// order; with that skin no rebuild happens).
#[test]
fn trajectories_under_compression_and_shear_follow_lammps() {
    use bpm::verify::{dem_trajectory, DemLoading};
    let mut cases = vec![
        (7, false, DemLoading::Compress, 1000),
        (7, false, DemLoading::Shear, 1000),
        (7, false, DemLoading::LeesEdwards, 1000),
        (7, false, DemLoading::Walls, 1000),
    ];
    cases.extend([1, 2, 3, 7].map(|seed| (seed, true, DemLoading::Hold, 2000)));
    for (seed, rolling_twisting, loading, steps) in cases {
        let mut scene = dem_trajectory(seed, rolling_twisting, loading, steps);
        if rolling_twisting {
            scene.force_field.skin = bpm::verify::check::DEM_STILL_SKIN;
        }
        let name = format!("{}-rt{rolling_twisting}-seed{seed}", loading.name());
        let native = bpm::verify::run_native(&scene, &name, 1).unwrap();
        if rolling_twisting {
            assert_eq!(native.stages[0].neighbour_builds, 1, "{name}: rebuilt");
        }
        let lammps = launcher(&name).run(&scene, &name, 1, true).unwrap();
        let deviations = bpm::verify::compare_runs(&native.stages, &lammps.stages).unwrap();
        assert!(deviations.iter().any(|d| d.observable == "positions"));
        common::assert_within_trajectory_tolerances(&name, &deviations);
    }
}

/// A DEM scene written as a LAMMPS data file (`atom_style sphere`) and
/// read back is the same scene: positions, radii, masses (through LAMMPS's
/// density, to round-off), velocities and angular velocities.
#[test]
fn sphere_data_file_round_trip() {
    let scene = dem_lattice(3, true);
    let dir = common::scratch_dir("dem-datafile");
    let path = dir.join("spheres.data");
    std::fs::write(&path, bpm::scene::datafile::write_data_file(&scene)).unwrap();
    let back = bpm::scene::datafile::read_data_file(&path, [true; 3], scene.force_field.clone(), 3)
        .unwrap();
    assert_eq!(back.model, bpm::scene::ModelKind::Dem);
    assert_eq!(back.force_field, scene.force_field);
    let close = |a: &[f64], b: &[f64], tol: f64| {
        a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= tol * y.abs().max(1.0))
    };
    let flat = |v: &[[f64; 3]]| v.iter().flatten().copied().collect::<Vec<f64>>();
    let p = &scene.particles;
    let q = &back.particles;
    assert_eq!(flat(&q.positions), flat(&p.positions));
    assert_eq!(q.radius, p.radius);
    assert!(close(&q.mass.values(64), &p.mass.values(64), 1e-15));
    assert_eq!(q.velocities, p.velocities);
    assert_eq!(q.angular_velocities, p.angular_velocities);
    // Without a material, a sphere file is refused with the reason.
    let err = bpm::scene::datafile::read_data_file(
        &path,
        [true; 3],
        bpm::scene::ForceField::paper(0.0),
        3,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("--granular"), "{err}");
}

/// A simple cubic lattice of equal, overlapping spheres moving with the
/// streaming profile of a shear along x with gradient along y: every pair
/// of neighbouring layers slides by the same amount, so under Lees-Edwards
/// boundaries the layers across the sheared face do too, and every sphere
/// feels no net force. With static images (`remap x`), the top and bottom
/// layers see a velocity jump of the whole flow across that face instead.
#[test]
fn a_uniform_shear_flow_is_homogeneous_under_lees_edwards_boundaries() {
    use bpm::engine::{Deformation, ShearRemap, StageDrivers, TiltFactor};
    use bpm::scene::builders::spheres::{sphere_lattice, SphereLattice};
    let rate = 1e-3;
    let mut scene = sphere_lattice(&SphereLattice {
        per_side: 4,
        radius: 1.0,
        polydispersity: 0.0,
        spacing: 0.97,
        jitter: 0.0,
        speed: 0.0,
        spin: 0.0,
        density: 1.0,
        material: bpm::verify::dem_check_material(false),
        seed: 1,
    });
    scene.particles.angular_velocities = None;
    let net_forces = |remap: ShearRemap| {
        let mut sys = bpm::scene::build_system(&scene, 1);
        let drivers = StageDrivers {
            dt: 0.01,
            deformation: Some(Deformation::SimpleShear {
                tilt: TiltFactor::Xy,
                rate,
                remap,
            }),
            ..Default::default()
        };
        let ly = sys.simbox.lengths[1];
        let streaming = bpm::engine::LeesEdwards {
            tilt_rate: [rate * ly, 0.0, 0.0],
        };
        for (x, v) in sys.particles.x.iter().zip(sys.particles.v.iter_mut()) {
            *v = streaming.streaming_velocity(&sys.simbox, x);
        }
        sys.setup(&drivers).unwrap();
        let largest = sys
            .particles
            .f
            .iter()
            .map(|f| f.iter().map(|c| c.abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        let volume = sys.simbox.volume();
        let virial = sys.interaction_tally().virial.map(|w| w / volume);
        (largest, sys.pressure_tensor(), virial)
    };
    let (lees_edwards, p_le, w_le) = net_forces(ShearRemap::V);
    let (static_images, p_x, w_x) = net_forces(ShearRemap::X);
    // Static images: the top and bottom layers feel the tangential dashpot
    // of the velocity jump across the face, 1.3e-2 k d here. Lees-Edwards:
    // what is left is the round-off of the normal forces, which are of
    // order 1 k d and cancel (measured 1.6e-14).
    assert!(static_images > 1e-2, "{static_images}");
    assert!(lees_edwards < 1e-12, "{lees_edwards}");
    // The stress: peculiar velocities are all zero under Lees-Edwards, so
    // only the contacts' virial remains; the affine remap counts the flow
    // as thermal motion, sum m u_x^2 / V in xx.
    assert!(
        (p_le[0] - w_le[0]).abs() < 1e-15 * w_le[0].abs(),
        "{p_le:?} vs virial {w_le:?}"
    );
    assert!(p_le[3] == w_le[3]);
    assert!(p_x[0] - w_x[0] > 1e-8, "{p_x:?} vs virial {w_x:?}");
}

/// The rebound speed over the impact speed of a head-on collision at
/// `speed`, in the native engine: a sphere of radius 1 thrown at a
/// granular wall of its own material (`wall`) or two such spheres thrown
/// at each other.
fn rebound(wall: bool, speed: f64) -> f64 {
    use bpm::engine::{ExternalTerms, GranularWall, StageDrivers, WallSide};
    let material = bpm::verify::dem_check_material(false);
    let (positions, velocities) = if wall {
        (vec![[5.0, 5.0, 1.0 + 1e-9]], vec![[0.0, 0.0, -speed]])
    } else {
        (
            vec![[5.0, 5.0, 4.0], [5.0, 5.0, 6.0 + 1e-9]],
            vec![[0.0, 0.0, 0.5 * speed], [0.0, 0.0, -0.5 * speed]],
        )
    };
    let n = positions.len();
    let scene: bpm::scene::Scene = serde_json::from_value(serde_json::json!({
        "model": "dem", "seed": 1,
        "box": {"lo": [0, 0, -1], "lengths": [10, 10, 12], "periodic": [true, true, false]},
        "particles": {"positions": positions, "velocities": velocities, "radius": vec![1.0; n]},
        "force_field": {"granular": material},
        "stages": [{"name": "bounce", "steps": 0}]
    }))
    .unwrap();
    bpm::scene::validate(&scene).unwrap();
    let mut sys = bpm::scene::build_system(&scene, 1);
    let plane = GranularWall {
        axis: 2,
        side: WallSide::Lo,
        position: 0.0,
        velocity: 0.0,
        material,
        keep_history: false,
    };
    let drivers = StageDrivers {
        dt: 1e-3,
        external: ExternalTerms {
            granular_walls: if wall { vec![plane] } else { Vec::new() },
            ..Default::default()
        },
        ..Default::default()
    };
    sys.setup(&drivers).unwrap();
    let start = sys.simbox.clone();
    let closing = |sys: &bpm::engine::System| {
        let v = &sys.particles.v;
        if wall {
            -v[0][2]
        } else {
            v[0][2] - v[1][2]
        }
    };
    let mut touched = false;
    for step in 1..=100_000 {
        sys.step(&drivers, step, &start).unwrap();
        let pushing = sys.particles.f[0][2] != 0.0;
        touched |= pushing;
        if touched && !pushing {
            if wall {
                // The wall's recorded force is the sphere's, both zero now.
                assert_eq!(wall_forces(&sys), vec![0.0]);
            }
            return -closing(&sys) / speed;
        }
        if wall && pushing {
            let f = wall_forces(&sys)[0];
            assert_eq!(f, sys.particles.f[0][2], "the wall feels what it pushes");
        }
    }
    panic!("no rebound");
}

/// The normal force on each granular wall at the last evaluation.
fn wall_forces(sys: &bpm::engine::System) -> Vec<f64> {
    let dem = sys
        .model_as::<bpm::engine::DemModel>()
        .expect("DEM spheres");
    dem.report().walls.iter().map(|w| w.force).collect()
}

/// A sphere rebounds from a wall of its own material as it does from an
/// equal sphere: with Hertz contacts and damping that scales as
/// sqrt(m_eff k_n a), the restitution depends on neither the effective
/// mass nor the effective radius. At e = 1/2 Tsuji's damping gives 0.616
/// (docs/model.md).
#[test]
fn a_sphere_rebounds_from_a_wall_as_from_an_equal_sphere() {
    for speed in [0.05, 0.2] {
        let (off_wall, off_sphere) = (rebound(true, speed), rebound(false, speed));
        eprintln!("speed {speed}: wall {off_wall}, sphere {off_sphere}");
        // Measured within 3.2e-5 of each other (the collisions' time
        // discretisation, contact time / dt about 1,500).
        assert!(
            (off_wall - off_sphere).abs() < 2e-4,
            "{off_wall} vs {off_sphere}"
        );
        assert!((off_wall - 0.616).abs() < 3e-3, "{off_wall}");
    }
}

/// A sphere pushed through a granular wall's plane stops the run with an
/// error naming the wall and the sphere.
#[test]
fn a_sphere_through_a_granular_wall_stops_the_run() {
    let material = bpm::verify::dem_check_material(false);
    let scene: bpm::scene::Scene = serde_json::from_value(serde_json::json!({
        "model": "dem", "seed": 1,
        "box": {"lo": [0, 0, -1], "lengths": [10, 10, 12], "periodic": [true, true, false]},
        "particles": {"positions": [[5.0, 5.0, 2.0], [2.0, 2.0, 6.0]], "radius": [1.0, 1.0]},
        "force_field": {"granular": material},
        "stages": [{"name": "crush", "steps": 1000, "dt": 0.01,
                    "granular_walls": [{"axis": 2, "side": "lo", "position": 0.0, "velocity": 150.0,
                                        "material": material}]}]
    }))
    .unwrap();
    bpm::scene::validate(&scene).unwrap();
    let mut sys = bpm::scene::build_system(&scene, 1);
    let (_, err) = bpm::scene::run_scene(&mut sys, &scene, &bpm::scene::RunOptions::quiet(1));
    let err = err.expect("the run must stop").to_string();
    assert!(
        err.contains("sphere 0 reached the plane of granular wall 0"),
        "{err}"
    );
}

/// The tangential force of a sphere sliding between a floor and a lid,
/// before and after the walls are set again for a new stage
/// (`keep_history` on both or neither; with `swapped` the new stage lists
/// the lid first).
fn friction_across_a_stage(keep_history: bool, swapped: bool) -> (f64, f64) {
    use bpm::engine::{ExternalTerms, GranularWall, StageDrivers, WallSide};
    let material = bpm::kernels::GranularMaterial {
        sliding_friction: 0.5,
        ..bpm::verify::dem_check_material(false)
    };
    let scene: bpm::scene::Scene = serde_json::from_value(serde_json::json!({
        "model": "dem", "seed": 1,
        "box": {"lo": [0, 0, -1], "lengths": [10, 10, 12], "periodic": [true, true, false]},
        "particles": {"positions": [[5.0, 5.0, 1.0]], "velocities": [[0.01, 0.0, 0.0]], "radius": [1.0]},
        "force_field": {"granular": material},
        "stages": [{"name": "slide", "steps": 0}]
    }))
    .unwrap();
    let mut sys = bpm::scene::build_system(&scene, 1);
    let wall = |side, position| GranularWall {
        axis: 2,
        side,
        position,
        velocity: 0.0,
        material,
        keep_history,
    };
    let drivers_with = |granular_walls| StageDrivers {
        dt: 1e-3,
        external: ExternalTerms {
            granular_walls,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut walls = vec![wall(WallSide::Lo, 0.0), wall(WallSide::Hi, 1.99)];
    let drivers = drivers_with(walls.clone());
    sys.setup(&drivers).unwrap();
    let start = sys.simbox.clone();
    for step in 1..=200 {
        sys.step(&drivers, step, &start).unwrap();
    }
    let before = sys.particles.f[0][0];
    if swapped {
        walls.reverse();
    }
    sys.setup(&drivers_with(walls)).unwrap();
    (before, sys.particles.f[0][0])
}

/// Walls set again for a new stage restart their contacts' friction
/// springs, unless they keep their histories: then the tangential force
/// goes on as if no stage had started. A wall keeps only the springs of
/// the wall at its place in the last stage's list, if on its axis and
/// side: listed in another order, they restart.
#[test]
fn walls_keep_their_friction_springs_across_stages_only_when_asked() {
    let (before, kept) = friction_across_a_stage(true, false);
    let (same_before, restarted) = friction_across_a_stage(false, false);
    let (_, reordered) = friction_across_a_stage(true, true);
    assert_eq!(before, same_before);
    assert_eq!(reordered, restarted);
    eprintln!("before {before:e}, kept {kept:e}, restarted {restarted:e}");
    assert!(before < 0.0, "friction opposes the sliding: {before:e}");
    // The stage's first evaluation sees the step's full velocities where
    // the step's own saw half-step ones, which moves the damping part
    // (measured 0.11% of the force); a restarted spring leaves 11%.
    assert!(
        (kept - before).abs() < 0.01 * before.abs(),
        "{kept:e} vs {before:e}"
    );
    assert!(
        restarted.abs() < 0.2 * before.abs(),
        "{restarted:e} vs {before:e}"
    );
}

/// What a DEM evaluation leaves: the contact histories and the closure's
/// corrections (bits), and the forces, torques, report and stress.
struct Evaluation {
    forces: Vec<[f64; 3]>,
    torques: Vec<[f64; 3]>,
    histories: Vec<u64>,
    corrections: Vec<u64>,
    report: bpm::engine::DemReport,
    stress: [f64; 6],
}

/// Values per contact history in [`history_bits`].
const HISTORY_VALUES: usize = 8;

/// Every contact history's values (tangential, rolling, twist, normal
/// force), as bits, contact after contact.
fn history_bits(dem: &bpm::engine::DemModel) -> Vec<u64> {
    let values = dem.contacts().history.iter().flat_map(|h| {
        let springs = h.tangential.iter().chain(&h.rolling);
        springs.chain([&h.twist, &h.normal_force])
    });
    values.map(|v| v.to_bits()).collect()
}

/// Contacts whose recorded normal force is not 0 in `histories`
/// ([`history_bits`]).
fn touching(histories: &[u64]) -> usize {
    let normal_forces = histories
        .chunks(HISTORY_VALUES)
        .map(|h| h[HISTORY_VALUES - 1]);
    normal_forces.filter(|&f| f != 0).count()
}

fn evaluation(sys: &bpm::engine::System) -> Evaluation {
    let dem = sys.model_as::<bpm::engine::DemModel>().unwrap();
    let histories = history_bits(dem);
    let corrections = dem.closure_pass().map_or(Vec::new(), |c| {
        let walls = (0..dem.walls().len()).flat_map(|w| c.wall_corrections(w));
        let pairs = c.pair_corrections().iter().flatten();
        pairs.chain(walls).map(|v| v.to_bits()).collect()
    });
    Evaluation {
        forces: sys.particles.f.clone(),
        torques: sys.particles.rotation.as_ref().unwrap().torque.clone(),
        histories,
        corrections,
        report: dem.report().clone(),
        stress: sys.pressure_tensor(),
    }
}

fn bits(v: &[[f64; 3]]) -> Vec<u64> {
    v.iter().flatten().map(|x| x.to_bits()).collect()
}

/// Largest difference between two sets of rows, and their largest value.
fn difference(got: &[[f64; 3]], want: &[[f64; 3]]) -> (f64, f64) {
    let pairs = got.iter().flatten().zip(want.iter().flatten());
    let worst = pairs.fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let scale = want.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    (worst, scale)
}

/// The contact pass and the multi-contact closure share their work among
/// threads: one step from the same state on 1, 2 and 3 threads gives the
/// same contact histories and closure corrections bit for bit (each
/// contact is formed once, from the same half-step velocities, and each
/// sphere's contacts are corrected in the same order), and the same
/// forces and torques up to the order of their sums; the same thread
/// count twice gives the same bits. Evaluations in a row on a team that
/// grows and shrinks (each from the histories the last one left, on the
/// buffers it left) give the one-thread sequence's histories and
/// corrections bit for bit. With Hertz contacts formed four at a time, and
/// one at a time (rolling and twisting friction).
#[test]
fn threads_share_the_contact_pass_and_the_closure() {
    use bpm::engine::{ExternalTerms, StageDrivers};
    use bpm::verify::{dem_trajectory, DemLoading};
    let cases = [
        (DemLoading::Compress, false),
        (DemLoading::LeesEdwards, false),
        (DemLoading::Walls, false),
        (DemLoading::Compress, true),
    ];
    for (loading, rolling_twisting) in cases {
        for closure in closures() {
            let case = format!("{loading:?} rolling {rolling_twisting} {closure:?}");
            let mut scene = dem_trajectory(3, rolling_twisting, loading, 400);
            scene.force_field.multicontact = closure;
            let mut sys = bpm::scene::build_system(&scene, 1);
            let stage_start = sys.simbox.clone();
            let (_, error) =
                bpm::scene::run_scene(&mut sys, &scene, &bpm::scene::RunOptions::quiet(1));
            assert!(error.is_none(), "{case}: {error:?}");
            let spec = &scene.stages[0];
            let drivers = StageDrivers {
                dt: spec.dt,
                external: ExternalTerms {
                    granular_walls: spec.granular_walls.clone(),
                    ..Default::default()
                },
                deformation: spec.deformation.clone(),
                tally_every: 1,
                ..Default::default()
            };
            let saved = (
                sys.particles.clone(),
                sys.neighbours.clone(),
                sys.simbox.clone(),
                sys.model.save_state().unwrap(),
            );
            let step = sys.step;
            let restore = |sys: &mut bpm::engine::System| {
                sys.particles = saved.0.clone();
                sys.neighbours = saved.1.clone();
                sys.simbox = saved.2.clone();
                sys.model.restore_state(saved.3.clone()).unwrap();
            };
            let mut one_step = |threads: usize| {
                restore(&mut sys);
                sys.threads = threads;
                sys.step(&drivers, step + 1, &stage_start).unwrap();
                evaluation(&sys)
            };
            let serial = one_step(1);
            let touching = touching(&serial.histories);
            assert!(touching > 20, "{case}: {touching} touching pairs");
            if closure.is_some() {
                // The advanced closure's small ratio switches most off.
                let corrected = serial
                    .corrections
                    .iter()
                    .filter(|&&b| f64::from_bits(b) != 0.0);
                let switched_off = serial.report.closure.unwrap().switched_off;
                assert!(
                    corrected.count() + switched_off > 20,
                    "{case}: too few corrections"
                );
            }
            for threads in [2, 3] {
                let shared = one_step(threads);
                let on = format!("{case}, {threads} threads");
                assert!(
                    shared.histories == serial.histories,
                    "{on}: histories differ"
                );
                assert!(
                    shared.corrections == serial.corrections,
                    "{on}: corrections differ"
                );
                assert_eq!(shared.report, serial.report, "{on}: reports differ");
                for (what, got, want) in [
                    ("force", &shared.forces, &serial.forces),
                    ("torque", &shared.torques, &serial.torques),
                ] {
                    let (worst, scale) = difference(got, want);
                    assert!(scale > 0.0, "{on}: no {what}s");
                    assert!(
                        worst <= 1e-13 * scale,
                        "{on}: {what}s differ by {worst:e} of {scale:e}"
                    );
                }
                let stress_scale = serial.stress.iter().fold(0.0f64, |m, s| m.max(s.abs()));
                for (a, b) in shared.stress.iter().zip(&serial.stress) {
                    assert!((a - b).abs() <= 1e-12 * stress_scale, "{on}: stress");
                }
                let again = one_step(threads);
                assert!(
                    bits(&again.forces) == bits(&shared.forces)
                        && bits(&again.torques) == bits(&shared.torques),
                    "{on}: not reproducible"
                );
            }
            let elapsed = spec.steps as f64 * spec.dt;
            let mut in_a_row = |teams: &[usize]| -> Vec<(Vec<u64>, Vec<u64>)> {
                restore(&mut sys);
                teams
                    .iter()
                    .map(|&threads| {
                        sys.threads = threads;
                        sys.compute_forces(&drivers, elapsed, true);
                        let e = evaluation(&sys);
                        (e.histories, e.corrections)
                    })
                    .collect()
            };
            assert!(
                in_a_row(&[3, 2, 1, 3, 2]) == in_a_row(&[1; 5]),
                "{case}: evaluations in a row on changing teams differ"
            );
        }
    }
}
