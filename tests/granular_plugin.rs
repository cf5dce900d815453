//! The plugin's `pair_style bpm/granular` (DEM contacts with the
//! multi-contact closure) in Debian's LAMMPS: against the native engine on
//! one and two ranks, its contact memory through a restart file, and its
//! errors on bad input.

mod common;

use bpm::engine::MultiContact;
use bpm::scene::Scene;
use bpm::verify::scenes::{dem_trajectory, with_release, DemLoading};
use bpm::verify::tolerances::tolerance;
use bpm::verify::{compare_runs, max_relative_deviation, run_lmp_bpm, run_native, LammpsLauncher};
use std::path::{Path, PathBuf};

fn lmp() -> &'static Path {
    Path::new(env!("CARGO_BIN_EXE_lmp-bpm"))
}

fn workdir() -> PathBuf {
    common::scratch_dir("granular-plugin")
}

/// The 64 overlapping spheres of `bpm check` under `loading` with the
/// closure `mc` (rolling and twisting friction with `rolling_twisting`).
fn closure_scene(
    rolling_twisting: bool,
    loading: DemLoading,
    steps: u64,
    mc: MultiContact,
) -> Scene {
    let mut scene = dem_trajectory(3, rolling_twisting, loading, steps);
    scene.force_field.multicontact = Some(mc);
    scene
}

fn last(scene_run: &[bpm::scene::StageOutput], column: &str) -> Vec<f64> {
    scene_run[0].column(column).unwrap()
}

/// The advanced closure switching contacts off, compressed on one rank;
/// the standard one with rolling and twisting friction, sheared across
/// two ranks through list rebuilds: each trajectory within the check's
/// tolerances of the native one, and each far from plain Hertz's.
#[test]
fn the_closure_in_lammps_follows_the_native_engine_and_changes_the_stress() {
    let dir = workdir();
    let launcher = LammpsLauncher {
        bpm: PathBuf::from(env!("CARGO_BIN_EXE_bpm")),
        dir: dir.clone(),
    };
    for (rt, loading, mc, ranks, keep_history) in [
        (
            false,
            DemLoading::Compress,
            MultiContact::advanced(0.81, 0.015),
            1,
            false,
        ),
        (
            true,
            DemLoading::LeesEdwards,
            MultiContact::standard(0.82),
            2,
            false,
        ),
        (
            false,
            DemLoading::Walls,
            MultiContact::advanced(0.81, 0.015),
            2,
            false,
        ),
        (
            false,
            DemLoading::Walls,
            MultiContact::standard(0.82),
            1,
            true,
        ),
    ] {
        let mut scene = closure_scene(rt, loading, 800, mc);
        if loading == DemLoading::Walls {
            // The walls defined anew halfway: springs restart (or with
            // `keep_history` go on), loads kept.
            scene = with_release(scene);
            for wall in &mut scene.stages[1].granular_walls {
                wall.keep_history = keep_history;
            }
        }
        let tag = format!("{}-{ranks}-keep-{keep_history}", loading.name());
        let native = run_native(&scene, &tag, 1).unwrap();
        if keep_history {
            // The springs kept change the release's wall forces.
            let mut restarting = scene.clone();
            for wall in &mut restarting.stages[1].granular_walls {
                wall.keep_history = false;
            }
            let restarted = run_native(&restarting, &format!("{tag}-restart"), 1).unwrap();
            let (kept, fresh) = (
                native.stages[1].column("granular_wall0_force").unwrap(),
                restarted.stages[1].column("granular_wall0_force").unwrap(),
            );
            // Far above the trajectory tolerance, so the LAMMPS run's
            // agreement below shows the plugin keeps them too.
            let rows = |c: &[f64]| c.iter().map(|&f| [f]).collect::<Vec<[f64; 1]>>();
            let apart = max_relative_deviation(&rows(&fresh), &rows(&kept));
            assert!(apart > 1e-6, "kept {kept:?}, restarted {fresh:?}");
        }
        let lammps = launcher.run(&scene, &tag, ranks, false).unwrap();
        let deviations = compare_runs(&native.stages, &lammps.stages).unwrap();
        assert!(deviations
            .iter()
            .any(|d| d.observable == "multi-contact corrections"));
        for d in &deviations {
            let tol = tolerance(&format!("trajectory {}", d.observable));
            assert!(
                d.max_deviation <= tol,
                "{tag}: {} deviates by {:e} (step {}), tolerance {tol:e}",
                d.observable,
                d.max_deviation,
                d.at_step
            );
        }
        let largest = lammps.stages[0].column("mc_largest_correction").unwrap();
        // The first evaluation has no loads remembered, so no corrections.
        assert_eq!(largest[0], 0.0);
        assert!(largest[1..].iter().all(|&c| c > 0.01), "{largest:?}");
        if loading == DemLoading::Walls {
            // The walls' forces are compared, and the upper one presses.
            assert!(deviations.iter().any(|d| d.observable == "wall forces"));
            let force = last(&lammps.stages, "granular_wall1_force");
            assert!(force.iter().any(|&f| f > 1.0), "{force:?}");
        }
        if mc.max_penetration_ratio.is_some() && loading == DemLoading::Compress {
            let switched = last(&lammps.stages, "mc_switched_off");
            assert!(switched.iter().any(|&s| s > 0.0), "{switched:?}");
        }
        let mut plain = scene.clone();
        plain.force_field.multicontact = None;
        if keep_history {
            // LAMMPS's own walls, used without the closure, cannot keep
            // their springs: refused, not run otherwise.
            let mut hertz_walls = plain.clone();
            for stage in &mut hertz_walls.stages {
                if let Some(ff) = &mut stage.force_field {
                    ff.multicontact = None;
                }
            }
            let err =
                bpm::lammps::write_driver(&hertz_walls, &dir, "keep-plain", false).unwrap_err();
            assert!(err.to_string().contains("keep_history"), "{err}");
        }
        let hertz = run_native(&plain, &format!("{tag}-hertz"), 1).unwrap();
        let (p, q) = (
            last(&lammps.stages, "pressure"),
            last(&hertz.stages, "pressure"),
        );
        let (p, q) = (p[p.len() - 1], q[q.len() - 1]);
        assert!(
            (p - q).abs() > 0.05 * q.abs(),
            "{tag}: closure pressure {p}, Hertz {q}"
        );
    }
}

/// The part of `setup_dem.in` that defines the spheres, with `edits`
/// applied, then `tail`: the script of a hand-written LAMMPS run.
fn dem_script(edits: &[(&str, &str)], tail: &str) -> String {
    let mut text = bpm::lammps::templates::template("setup_dem.in")
        .unwrap()
        .to_string();
    for (from, to) in edits {
        assert!(text.contains(from), "setup_dem.in has no `{from}`");
        text = text.replace(from, to);
    }
    text + tail
}

/// Runs `script` (named `tag`) on the spheres of `scene` with one rank.
fn run_script(scene: &Scene, tag: &str, script: &str) -> Result<String, String> {
    run_script_on(scene, tag, script, 1)
}

/// [`run_script`] on `ranks` MPI ranks.
fn run_script_on(scene: &Scene, tag: &str, script: &str, ranks: usize) -> Result<String, String> {
    let path = workdir().join(format!("{tag}.in"));
    std::fs::write(&path, script).unwrap();
    run_lmp_bpm(
        lmp(),
        scene,
        path.to_str().unwrap(),
        false,
        ranks,
        &workdir(),
        tag,
        &[],
        0,
    )
    .map_err(|e| e.to_string())
}

/// The rows `id x y z fx fy fz tqx tqy tqz` of a dump sorted by id.
fn read_rows(path: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut rows: Vec<Vec<f64>> = text
        .lines()
        .skip_while(|l| !l.starts_with("ITEM: ATOMS"))
        .skip(1)
        .map(|l| l.split_whitespace().map(|w| w.parse().unwrap()).collect())
        .collect();
    rows.sort_by(|a, b| a[0].total_cmp(&b[0]));
    rows
}

/// A run stopped in a restart file and resumed ends where the run that
/// wrote it ends: the contact memory (sliding, rolling and twisting
/// springs, and the loads the closure reads) is in the restart file, and
/// the pair style's coefficients too. A resumed run that lost the memory
/// differs by the springs' forces.
#[test]
fn a_restart_keeps_the_contact_memory_and_the_closure() {
    let scene = closure_scene(
        true,
        DemLoading::Hold,
        0,
        MultiContact::advanced(0.81, 0.015),
    );
    let dir = workdir();
    let restart = dir.join("granular.restart");
    let dump = |name: &str| dir.join(format!("{name}.dump"));
    let motion = "fix             move all nve/sphere\ntimestep        0.01\n";
    let write = |name: &str| {
        format!(
            "write_dump      all custom {} id x y z fx fy fz tqx tqy tqz modify sort id format float %.17g\n",
            dump(name).display()
        )
    };
    let continuous = dem_script(
        &[],
        &format!(
            "{motion}run 300\nwrite_restart   {}\nrun 300\n{}",
            restart.display(),
            write("continuous")
        ),
    );
    run_script(&scene, "restart-write", &continuous).unwrap();
    let resume = |name: &str, forget: bool| {
        format!(
            "units lj\nread_restart    {}\nnewton          off\ncomm_modify     vel yes\nneighbor        {} bin\nneigh_modify    delay 0 every 1 check yes\natom_modify     sort 0 0.0\n{}{motion}run 300\n{}",
            restart.display(),
            scene.force_field.skin,
            // The restart's rows reach the fix when the first run creates
            // it, and are dropped after that run's set-up: a fix made anew
            // after `run 0` starts empty.
            if forget { "run 0\nunfix BPM_CONTACTS\n" } else { "" },
            write(name)
        )
    };
    let cols = |rows: &[Vec<f64>], from: usize| -> Vec<[f64; 3]> {
        rows.iter()
            .map(|r| [r[from], r[from + 1], r[from + 2]])
            .collect()
    };
    let a = read_rows(&dump("continuous"));
    assert_eq!(a.len(), 64);
    // Resumed on the rank that wrote it, and on two ranks: then each rank
    // receives the rows of the atoms it owns.
    for ranks in [1, 2] {
        let name = format!("resumed-np{ranks}");
        run_script_on(
            &scene,
            &format!("restart-read-np{ranks}"),
            &resume(&name, false),
            ranks,
        )
        .unwrap();
        let b = read_rows(&dump(&name));
        assert_eq!(a.len(), b.len());
        let dx = cols(&a, 1)
            .iter()
            .zip(&cols(&b, 1))
            .map(|(p, q)| common::dist(p, q))
            .fold(0.0, f64::max);
        let df = max_relative_deviation(&cols(&b, 4), &cols(&a, 4));
        let dt = max_relative_deviation(&cols(&b, 7), &cols(&a, 7));
        println!("restart on {ranks} rank(s): positions {dx:e} d, forces {df:e}, torques {dt:e}");
        assert!(
            dx <= tolerance("restart positions")
                && df <= tolerance("restart forces")
                && dt <= tolerance("restart forces"),
            "after restart on {ranks} rank(s): positions differ by {dx:e} d, forces by {df:e}, torques by {dt:e}"
        );
    }
    // Without the memory (fix removed after reading), the springs restart
    // unloaded and the run goes elsewhere.
    run_script(&scene, "restart-forget", &resume("forgot", true)).unwrap();
    let c = read_rows(&dump("forgot"));
    let lost = max_relative_deviation(&cols(&c, 7), &cols(&a, 7));
    assert!(
        lost > 1e-3,
        "torques without the memory differ by only {lost:e}"
    );
}

#[test]
fn bad_input_of_the_granular_style_gets_a_clear_lammps_error() {
    let scene = closure_scene(false, DemLoading::Hold, 0, MultiContact::standard(0.82));
    let coeff = "pair_coeff      * * ${granular}";
    let material = "hertz/material 100 0.5 0.25 damping tsuji tangential mindlin NULL 1 0.3";
    // (name, edits of setup_dem.in, expected words of the error)
    type Case<'a> = (&'a str, Vec<(&'a str, String)>, &'a str);
    let cases: Vec<Case> = vec![
        (
            "newton_on",
            vec![("newton          ${newton}", "newton on".into())],
            "newton off",
        ),
        (
            "ghost_velocity",
            vec![("comm_modify     vel yes", "".into())],
            "comm_modify vel yes",
        ),
        (
            "per_type",
            vec![(coeff, format!("pair_coeff 1 1 {material}"))],
            "one material for every type",
        ),
        (
            "unknown",
            vec![(
                coeff,
                format!("pair_coeff * * {material} multicontact 0.8 bogus"),
            )],
            "unknown keyword `bogus`",
        ),
        (
            "negative_modulus",
            vec![(
                coeff,
                format!("pair_coeff * * {}", material.replace(" 100 ", " -100 ")),
            )],
            "youngs_modulus",
        ),
        (
            "reach",
            vec![(
                coeff,
                format!("pair_coeff * * {material} multicontact 0.8 reach 0"),
            )],
            "reach",
        ),
        (
            "slots",
            vec![(
                coeff,
                format!("pair_coeff * * {material} multicontact 0.8 slots 2"),
            )],
            "more than 2 contacts",
        ),
        (
            // A reach of one radius sum: the cutoff exceeds half the box.
            "small_box",
            vec![(
                coeff,
                format!("pair_coeff * * {material} multicontact 0.8 reach 1"),
            )],
            "twice the neighbour-list range",
        ),
        (
            // The pair cutoff alone would fit, but with this skin the list
            // could hold two images of one partner.
            "skin_window",
            vec![(
                "neighbor        ${skin} bin",
                "neighbor        1.7 bin".into(),
            )],
            "twice the neighbour-list range",
        ),
        ("no_coeff", vec![(coeff, "".into())], "oeffs are not set"),
    ];
    for (tag, edits, expected) in cases {
        let edits: Vec<(&str, &str)> = edits.iter().map(|(a, b)| (*a, b.as_str())).collect();
        let script = dem_script(&edits, "run 0\n");
        let err = match run_script(&scene, tag, &script) {
            Ok(out) => panic!("{tag}: LAMMPS accepted bad input:\n{out}"),
            Err(e) => e,
        };
        assert!(
            err.contains(expected),
            "{tag}: expected `{expected}` in:\n{err}"
        );
        assert!(
            !err.contains("Segmentation") && !err.contains("panicked"),
            "{tag}: crashed:\n{err}"
        );
    }
    // LAMMPS's own granular wall runs, but its load is not in the closure:
    // a warning says so.
    let walled = dem_script(
        &[("boundary        ${boundary}", "boundary        p p f")],
        "fix wall all wall/gran hooke 1000 NULL 50 NULL 0.5 0 zplane -5 NULL\nrun 0\n",
    );
    let out = run_script(&scene, "walled", &walled).unwrap();
    assert!(
        out.contains("fix wall (wall/gran) is not a contact of the multi-contact closure"),
        "{out}"
    );
    // The plugin's wall: bad definitions, and an atom behind its plane.
    let closed = (
        "boundary        ${boundary}",
        "boundary        p p f".to_string(),
    );
    let wall = |args: &str| format!("fix w all bpm/granular/wall {args} {material}\n");
    let wall_cases: Vec<Case> = vec![
        (
            "wall_number",
            vec![closed.clone()],
            "the number must be at least 1",
        ),
        ("wall_axis", vec![closed.clone()], "expected x, y or z"),
        (
            "wall_side",
            vec![closed.clone()],
            "expected lo (atoms above the plane)",
        ),
        (
            "wall_material",
            vec![closed.clone()],
            "belongs to pair_coeff",
        ),
        (
            "wall_keep_late",
            vec![closed.clone()],
            "`keep_history` goes right after the velocity",
        ),
        ("wall_group", vec![closed.clone()], "use group all"),
        ("wall_twice", vec![closed.clone()], "share a number"),
        ("wall_periodic", vec![], "periodic along z"),
        // The plane moves with the step count.
        ("wall_reset", vec![closed.clone()], "time-dependent fix"),
        (
            "wall_pair",
            vec![
                closed.clone(),
                ("pair_style      ${pair}", "pair_style granular".into()),
                (coeff, format!("pair_coeff * * {material}")),
            ],
            "needs pair_style bpm/granular",
        ),
        (
            "wall_through",
            vec![closed],
            "reached the plane of fix bpm/granular/wall number 1",
        ),
    ];
    for (tag, edits, expected) in wall_cases {
        let fix = match tag {
            "wall_number" => wall("0 z lo -5 0"),
            "wall_axis" => wall("1 q lo -5 0"),
            "wall_side" => wall("1 z up -5 0"),
            "wall_material" => wall("1 z lo -5 0").replace("\n", " multicontact 0.8\n"),
            "wall_keep_late" => wall("1 z lo -5 0").replace("\n", " keep_history\n"),
            "wall_group" => format!(
                "group one id 1\n{}",
                wall("1 z lo -5 0").replace(" all ", " one ")
            ),
            "wall_twice" => wall("1 z lo -5 0") + &wall("1 z hi 50 0").replace("fix w ", "fix w2 "),
            "wall_through" => wall("1 z lo 3 0"),
            "wall_reset" => wall("1 z lo -5 0") + "reset_timestep 10\n",
            _ => wall("1 z lo -5 0"),
        };
        let edits: Vec<(&str, &str)> = edits.iter().map(|(a, b)| (*a, b.as_str())).collect();
        let script = dem_script(&edits, &format!("{fix}run 0\n"));
        let err = match run_script(&scene, tag, &script) {
            Ok(out) => panic!("{tag}: LAMMPS accepted bad input:\n{out}"),
            Err(e) => e,
        };
        assert!(
            err.contains(expected),
            "{tag}: expected `{expected}` in:\n{err}"
        );
    }
    // A wall clear of the atoms: no force on it, its position reported.
    let clear = dem_script(
        &[("boundary        ${boundary}", "boundary        p p f")],
        &format!(
            "{}thermo_style custom step f_w[1] f_w[2]\nrun 0\n",
            wall("1 z lo -5 0")
        ),
    );
    let out = run_script(&scene, "wall_clear", &clear).unwrap();
    assert!(
        out.lines()
            .any(|l| l.split_whitespace().collect::<Vec<_>>() == ["0", "0", "-5"]),
        "{out}"
    );
    let atomic = "units lj\natom_style atomic\nnewton off\nregion b block 0 5 0 5 0 5\ncreate_box 1 b\ncreate_atoms 1 single 1 1 1\nmass 1 1\ncomm_modify vel yes\npair_style bpm/granular\npair_coeff * * hertz/material 100 0.5 0.25 damping tsuji tangential mindlin NULL 1 0.3\nrun 0\n";
    let err = run_script(&scene, "atomic", atomic).unwrap_err();
    assert!(err.contains("atom_style sphere"), "{err}");
}

/// `bpm cross-check` on a scene file with the closure: both rank counts
/// judged, every verdict passing, the report written; a rank count of 0 is
/// refused by name.
#[test]
fn cross_check_runs_a_scene_file_through_both_engines() {
    let dir = workdir().join("cross-check");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = closure_scene(
        false,
        DemLoading::Compress,
        200,
        MultiContact::advanced(0.81, 0.015),
    );
    let path = dir.join("closure.json");
    bpm::scene::write_scene(&path, &scene).unwrap();
    let bpm = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_bpm"))
            .arg("cross-check")
            .arg(&path)
            .args(args)
            .output()
            .unwrap()
    };
    let out = bpm(&["--ranks", "1,2", "-o", dir.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("cross_check.json")).unwrap())
            .unwrap();
    let verdicts = report["verdicts"].as_array().unwrap();
    assert!(verdicts.len() >= 10, "{report}");
    assert!(verdicts.iter().all(|v| v["pass"] == true));
    assert!(verdicts.iter().any(|v| v["lammps"] == "np2 newton off"
        && v["observable"] == "trajectory multi-contact corrections"));
    assert_eq!(report["time_ratios"].as_array().unwrap().len(), 2);
    let refused = bpm(&["--ranks", "0", "-o", dir.to_str().unwrap()]);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--ranks"));
}

/// The walls' motion goes into the restart file: a run between two
/// moving walls (the upper one pressing on the spheres by the restart),
/// resumed with the same walls defined again, ends where the run that
/// wrote the file ends. Walls defined under new IDs start again where
/// given (their springs unloaded), and the run goes elsewhere; a wall
/// defined differently under a saved ID is refused.
#[test]
fn a_restart_keeps_the_walls_moving_from_where_they_were() {
    use bpm::lammps::datafile::dem_pair_coeff;
    let mut scene = closure_scene(false, DemLoading::Walls, 0, MultiContact::standard(1.0));
    let walls = scene.stages[0].granular_walls.clone();
    scene.stages.clear();
    let dir = workdir();
    let restart = dir.join("walls.restart");
    let dump = |name: &str| dir.join(format!("walls-{name}.dump"));
    let write = |name: &str| {
        format!(
            "write_dump      all custom {} id x y z fx fy fz tqx tqy tqz modify sort id format float %.17g\n",
            dump(name).display()
        )
    };
    let define_walls = |prefix: &str, velocity_scale: f64| -> String {
        walls
            .iter()
            .enumerate()
            .map(|(w, wall)| {
                format!(
                    "fix             {prefix}{w} all bpm/granular/wall {} {} {} {:.17e} {:.17e} {}\n",
                    w + 1,
                    ["x", "y", "z"][wall.axis],
                    match wall.side {
                        bpm::engine::WallSide::Lo => "lo",
                        bpm::engine::WallSide::Hi => "hi",
                    },
                    wall.position,
                    wall.velocity * velocity_scale,
                    dem_pair_coeff(&wall.material, None, true)
                )
            })
            .collect()
    };
    let motion = "fix             move all nve/sphere\ntimestep        0.01\n";
    let continuous = dem_script(
        &[],
        &format!(
            "{}{motion}run 400\nwrite_restart   {}\nrun 400\n{}",
            define_walls("wall", 1.0),
            restart.display(),
            write("continuous")
        ),
    );
    run_script(&scene, "walls-restart-write", &continuous).unwrap();
    let resume = |name: &str, walls: &str| {
        format!(
            "units lj\nread_restart    {}\nnewton          off\ncomm_modify     vel yes\nneighbor        {} bin\nneigh_modify    delay 0 every 1 check yes\natom_modify     sort 0 0.0\n{walls}{motion}run 400\n{}",
            restart.display(),
            scene.force_field.skin,
            write(name)
        )
    };
    let positions = |name: &str| -> Vec<[f64; 3]> {
        read_rows(&dump(name))
            .iter()
            .map(|r| [r[1], r[2], r[3]])
            .collect()
    };
    let largest_shift = |a: &[[f64; 3]], b: &[[f64; 3]]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| common::dist(p, q))
            .fold(0.0, f64::max)
    };
    let straight = positions("continuous");
    run_script(
        &scene,
        "walls-restart-read",
        &resume("resumed", &define_walls("wall", 1.0)),
    )
    .unwrap();
    let shift = largest_shift(&straight, &positions("resumed"));
    println!("walls through a restart: positions differ by {shift:e} d");
    assert!(
        shift <= tolerance("restart positions"),
        "positions differ by {shift:e} d after the restart"
    );
    run_script(
        &scene,
        "walls-restart-new",
        &resume("new-walls", &define_walls("fresh", 1.0)),
    )
    .unwrap();
    let moved = largest_shift(&straight, &positions("new-walls"));
    assert!(
        moved > 1e-3,
        "walls started afresh move the spheres by only {moved:e} d"
    );
    let refused = run_script(
        &scene,
        "walls-restart-other",
        &resume("other", &define_walls("wall", 2.0)),
    )
    .unwrap_err();
    assert!(refused.contains("the restart file's wall is"), "{refused}");
}
