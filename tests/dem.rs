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
    sys.setup(&drivers);
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
/// sliding friction under compression and under shear (1,000 steps, before
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
        for d in deviations {
            let tol = bpm::verify::tolerances::tolerance(&format!("trajectory {}", d.observable));
            assert!(
                d.max_deviation <= tol,
                "{name}: {} deviates by {:e} at step {} (tolerance {tol:e})",
                d.observable,
                d.max_deviation,
                d.at_step
            );
        }
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
