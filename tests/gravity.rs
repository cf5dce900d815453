//! Gravity (`force_field.gravity`): an exact free fall in both particle
//! models, a settled bed's weight on its floor, and the same trajectories
//! as LAMMPS's `fix gravity`.

mod common;

use bpm::scene::{build_system, run_scene, validate, RunOptions, Scene};
use bpm::verify::{
    compare_runs, dem_check_material, dem_trajectory, grain_squeeze, run_native, DemLoading,
    LammpsLauncher,
};
use std::path::PathBuf;

/// One particle (a bonded-model particle, or a DEM sphere of radius 0.5)
/// at rest at height 50 in a box closed in z, under gravity `g` along -z,
/// for 100 steps of 0.1.
fn falling(model: &str, g: f64) -> Scene {
    let mut scene = serde_json::json!({
        "model": model, "seed": 1,
        "box": {"lo": [0, 0, 0], "lengths": [10, 10, 100], "periodic": [true, true, false]},
        "particles": {"positions": [[5.0, 5.0, 50.0]]},
        "force_field": {"gravity": [0.0, 0.0, -g]},
        "stages": [{"name": "fall", "steps": 100, "dt": 0.1, "record": {"every": 10}}]
    });
    if model == "dem" {
        scene["particles"]["radius"] = serde_json::json!([0.5]);
        scene["force_field"]["granular"] = serde_json::to_value(dem_check_material(false)).unwrap();
    } else {
        scene["force_field"]["pair"] = serde_json::json!({"k": 1, "d": 1, "a": 50, "gamma": 1});
    }
    let scene: Scene = serde_json::from_value(scene).unwrap();
    validate(&scene).unwrap();
    scene
}

/// Velocity Verlet integrates a constant force exactly: after time t the
/// particle has fallen g t^2 / 2 and moves at g t, to round-off, and its
/// kinetic plus gravitational energy (recorded in `e_external`) stays put.
#[test]
fn a_free_particle_falls_as_a_constant_acceleration_dictates() {
    let g = 0.5;
    for model in ["bpm", "dem"] {
        let scene = falling(model, g);
        let mut sys = build_system(&scene, 1);
        let (stages, error) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
        assert!(error.is_none(), "{model}: {error:?}");
        let t = 10.0;
        let z = sys.particles.x[0][2];
        let vz = sys.particles.v[0][2];
        assert!(
            (z - (50.0 - 0.5 * g * t * t)).abs() < 1e-12 * 50.0,
            "{model}: z = {z}"
        );
        assert!((vz + g * t).abs() < 1e-12 * g * t, "{model}: vz = {vz}");
        assert_eq!(sys.particles.x[0][0], 5.0, "{model}: no sideways force");
        let kinetic = stages[0].column("e_kinetic").unwrap();
        let external = stages[0].column("e_external").unwrap();
        let mass = sys.particles.mass[0];
        assert!(
            (external[0] - mass * g * 50.0).abs() < 1e-12,
            "{model}: the energy at rest is -m g . x: {}",
            external[0]
        );
        let total: Vec<f64> = kinetic.iter().zip(&external).map(|(k, u)| k + u).collect();
        let drop = mass * g * 25.0;
        assert!(
            kinetic.last().unwrap() > &(0.99 * drop),
            "{model}: {kinetic:?}"
        );
        for e in &total {
            assert!(
                (e - total[0]).abs() < 1e-9 * drop,
                "{model}: energy drifts: {total:?}"
            );
        }
    }
}

/// Eight DEM spheres dropped onto a granular floor in a box periodic in x
/// and y come to rest: the floor then carries their weight, every other
/// force having cancelled.
#[test]
fn a_settled_bed_presses_its_floor_with_its_weight() {
    let g = 0.05;
    let mut positions = Vec::new();
    for k in 0..8 {
        let (i, j, layer) = (k % 2, (k / 2) % 2, k / 4);
        positions.push([
            1.2 + 2.4 * i as f64 + 0.1 * layer as f64,
            1.1 + 2.4 * j as f64,
            1.2 + 2.2 * layer as f64,
        ]);
    }
    let material = dem_check_material(false);
    let scene: Scene = serde_json::from_value(serde_json::json!({
        "model": "dem", "seed": 1,
        "box": {"lo": [0, 0, -1], "lengths": [4.8, 4.8, 12], "periodic": [true, true, false]},
        "particles": {"positions": positions, "radius": vec![1.0; 8]},
        "force_field": {"granular": material, "gravity": [0.0, 0.0, -g]},
        "stages": [{
            "name": "settle", "steps": 40000, "dt": 0.01, "viscous": 0.5,
            "granular_walls": [{"axis": 2, "side": "lo", "position": 0.0, "material": material}],
            "record": {"every": 1000}
        }]
    }))
    .unwrap();
    validate(&scene).unwrap();
    let mut sys = build_system(&scene, 1);
    let (stages, error) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
    assert!(error.is_none(), "{error:?}");
    let weight: f64 = sys.particles.mass.iter().map(|m| m * g).sum();
    let floor = *stages[0]
        .column("granular_wall0_force")
        .unwrap()
        .last()
        .unwrap();
    let speed = sys
        .particles
        .v
        .iter()
        .map(|v| v.iter().map(|c| c * c).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    assert!(speed < 1e-6, "not settled: largest speed {speed:e}");
    assert!(
        (floor - weight).abs() < 1e-6 * weight,
        "floor force {floor} against weight {weight}"
    );
    // Two layers: the upper spheres rest on the lower ones, not on the floor.
    let lowest = sys
        .particles
        .x
        .iter()
        .map(|x| x[2])
        .fold(f64::MAX, f64::min);
    let highest = sys
        .particles
        .x
        .iter()
        .map(|x| x[2])
        .fold(f64::MIN, f64::max);
    assert!(highest - lowest > 1.0, "one layer: {lowest} .. {highest}");
}

fn launcher(name: &str) -> LammpsLauncher {
    LammpsLauncher {
        bpm: PathBuf::from(env!("CARGO_BIN_EXE_bpm")),
        dir: common::scratch_dir(&format!("gravity-{name}")),
    }
}

/// Every compared observable of `scene` within its tolerance between the
/// native engine and LAMMPS; returns the native run's `e_external`.
fn assert_agree(scene: &Scene, name: &str) -> Vec<f64> {
    let l = launcher(name);
    let native = run_native(scene, name, 1).unwrap();
    let lammps = l.run(scene, name, 1, true).unwrap();
    let deviations = compare_runs(&native.stages, &lammps.stages).unwrap();
    assert!(deviations.iter().any(|d| d.observable == "positions"));
    assert!(deviations.iter().any(|d| d.observable == "external energy"));
    common::assert_within_trajectory_tolerances(name, &deviations);
    let _ = std::fs::remove_dir_all(&l.dir);
    native.stages[0].column("e_external").unwrap()
}

/// A bonded grain falls onto the lower of two closing walls: LAMMPS's
/// `fix gravity` (with its energy in `e_external`) gives the same
/// trajectory, wall forces and energies as the native engine.
#[test]
fn a_grain_falling_between_walls_agrees_with_lammps() {
    let mut scene = grain_squeeze(2.5, 6, -0.5, 0.01, 300).unwrap();
    scene.force_field.gravity = Some([0.0, 0.0, -0.005]);
    let external = assert_agree(&scene, "grain");
    // The walls start clear of the grain: all of the first row's external
    // energy is gravity's, -m g . x.
    let sys = build_system(&scene, 1);
    let potential: f64 = sys
        .particles
        .x
        .iter()
        .zip(&sys.particles.mass)
        .map(|(x, m)| m * 0.005 * x[2])
        .sum();
    assert!(potential > 1.0, "{potential}");
    assert!(
        (external[0] - potential).abs() < 1e-12 * potential,
        "{} against {potential}",
        external[0]
    );
}

/// DEM spheres between two granular walls, with gravity along one wall
/// normal, against LAMMPS's `pair_style granular` and `fix gravity`.
#[test]
fn dem_spheres_between_walls_agree_with_lammps() {
    let mut scene = dem_trajectory(7, false, DemLoading::Walls, 1000);
    scene.force_field.gravity = Some([0.0, 0.0, -0.01]);
    let native = run_native(&scene, "dem-native", 1).unwrap();
    let without = {
        let mut s = scene.clone();
        s.force_field.gravity = None;
        run_native(&s, "dem-native-without", 1).unwrap()
    };
    let lower = |run: &bpm::verify::EngineRun| {
        *run.stages[0]
            .column("granular_wall0_force")
            .unwrap()
            .last()
            .unwrap()
    };
    assert!(
        lower(&native) > lower(&without),
        "gravity loads the lower wall: {} against {}",
        lower(&native),
        lower(&without)
    );
    assert_agree(&scene, "dem");
}

#[test]
fn a_gravity_that_is_not_finite_is_refused_by_name() {
    let mut scene = falling("bpm", 0.5);
    scene.force_field.gravity = Some([0.0, f64::NAN, -1.0]);
    let err = validate(&scene).unwrap_err().to_string();
    assert!(err.contains("force_field.gravity[1]"), "{err}");
}
