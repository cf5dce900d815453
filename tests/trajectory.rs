//! Trajectories and thermo rows on disk: both engines write the same dump
//! format with the same numbers, streamed rows equal in-memory rows, and a
//! scene of a format this build does not know is refused.

mod common;

use bpm::scene::trajectory::read_dump;
use bpm::scene::{
    run_native_report, write_scene, DumpOptions, OutputFiles, RunOptions, Scene, StageSpec,
};
use bpm::verify::tolerances::tolerance;
use bpm::verify::{as_trajectory, contact_solid};
use std::path::{Path, PathBuf};
use std::process::Command;

fn bpm_exe() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_bpm"))
}

/// A contact solid whose particles cross the periodic faces during the
/// run (so image flags matter), recording every 25 steps.
fn moving_solid() -> Scene {
    let mut s = as_trajectory(contact_solid(6.0, 3, -0.5).unwrap(), 200);
    // A drift across the box: every particle crosses a face.
    for v in s
        .particles
        .velocities
        .get_or_insert_with(Vec::new)
        .iter_mut()
    {
        v[0] += 0.2;
    }
    s.stages[0].record.every = 25;
    s
}

fn run_bpm(args: &[&str]) {
    let out = Command::new(bpm_exe()).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "bpm {args:?} failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn max_rel(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let scale = common::max_abs(a).max(f64::MIN_POSITIVE);
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |d| (p[d] - q[d]).abs()))
        .fold(0.0f64, |m, d| if d.is_nan() { f64::NAN } else { m.max(d) })
        / scale
}

#[test]
fn both_engines_write_the_same_dump_with_image_flags() {
    let dir = common::scratch_dir("trajectory-dump");
    let scene = moving_solid();
    let scene_path = dir.join("scene.json");
    write_scene(&scene_path, &scene).unwrap();
    let dump = |engine: &str| dir.join(format!("{engine}.dump"));
    for engine in ["native", "lammps"] {
        let out = dir.join(format!("{engine}.json"));
        let d = dump(engine);
        run_bpm(&[
            "run",
            scene_path.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--engine",
            engine,
            "--dump",
            d.to_str().unwrap(),
            "--dump-every",
            "50",
            "--dump-forces",
        ]);
    }
    let native = read_dump(&dump("native")).unwrap();
    let lammps = read_dump(&dump("lammps")).unwrap();
    let steps: Vec<u64> = native.iter().map(|f| f.step).collect();
    assert_eq!(steps, vec![0, 50, 100, 150, 200]);
    assert_eq!(lammps.iter().map(|f| f.step).collect::<Vec<_>>(), steps);
    let n = scene.particles.positions.len();
    let start = bpm::scene::validate::simbox_of(&scene);
    let mut crossed = 0;
    for (a, b) in native.iter().zip(&lammps) {
        assert_eq!(a.x.len(), n);
        assert_eq!((&a.grain, &a.kind), (&b.grain, &b.kind));
        // Unwrapped positions: the engines wrap at different moments, the
        // image flags make up for it.
        let (ua, ub) = (a.unwrapped(), b.unwrapped());
        let worst = ua
            .iter()
            .zip(&ub)
            .map(|(p, q)| common::dist(p, q))
            .fold(0.0f64, f64::max);
        assert!(
            worst <= tolerance("trajectory positions"),
            "step {}: unwrapped positions differ by {worst:e} d",
            a.step
        );
        let dv = max_rel(&a.v, &b.v);
        eprintln!("step {}: positions {worst:e} d, velocities {dv:e}", a.step);
        assert!(
            dv <= tolerance("trajectory velocities"),
            "step {}: velocities differ by {dv:e} (relative)",
            a.step
        );
        // LAMMPS's frame at a stage start shows the last evaluation's
        // forces (none yet before the first run); later frames match.
        if a.step > 0 {
            // Absolute (k d): a particle's net force is a near-cancelling
            // sum of bond forces of order k d, so its round-off is too.
            let (fa, fb) = (a.f.as_ref().unwrap(), b.f.as_ref().unwrap());
            let df = max_rel(fa, fb) * common::max_abs(fa);
            eprintln!("step {}: forces {df:e} k d", a.step);
            assert!(
                df <= tolerance("trajectory forces"),
                "step {}: forces differ by {df:e} k d",
                a.step
            );
        }
        // Unwrapped positions continue the scene's positions: a drift of
        // 0.2 d/tau for 20 tau is 4 d, not a box length.
        for (u, x0) in ua.iter().zip(&scene.particles.positions) {
            let dx = u[0] - x0[0];
            assert!(dx.abs() < 0.5 * start.lengths[0] + 5.0, "jump {dx}");
        }
        crossed = a.image.iter().filter(|m| m[0] != 0).count();
    }
    assert!(
        crossed > n / 2,
        "only {crossed} of {n} particles crossed a face"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn streamed_thermo_rows_equal_the_rows_kept_in_memory() {
    let dir = common::scratch_dir("trajectory-thermo");
    let mut scene = moving_solid();
    scene.stages.push(StageSpec {
        record: bpm::scene::Record {
            every: 10,
            positions_every: 0,
        },
        ..StageSpec::hold("hold", 60, 0.1)
    });
    let (memory, _) = run_native_report(&scene, Path::new("scene"), 0, &RunOptions::quiet(1));
    let file = dir.join("thermo.txt");
    let opts = RunOptions {
        files: OutputFiles {
            thermo: Some(file.clone()),
            dump: Some(DumpOptions {
                path: dir.join("t.dump"),
                every: 100,
                forces: false,
            }),
        },
        ..RunOptions::quiet(1)
    };
    let (streamed, _) = run_native_report(&scene, Path::new("scene"), 0, &opts);
    assert!(streamed.error.is_none() && memory.error.is_none());
    assert!(streamed.stages.iter().all(|s| s.rows.is_empty()));
    let text = std::fs::read_to_string(&file).unwrap();
    let mut rows = vec![Vec::new(); 2];
    let mut stage = 0;
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("# stage ") {
            stage = rest.split_whitespace().next().unwrap().parse().unwrap();
        } else if let Some(names) = line.strip_prefix("# ") {
            let expected: Vec<&str> = memory.stages[stage]
                .columns
                .iter()
                .map(|c| c.name.as_str())
                .collect();
            assert_eq!(names.split(' ').collect::<Vec<_>>(), expected);
        } else {
            let row: Vec<f64> = line.split(' ').map(|v| v.parse().unwrap()).collect();
            rows[stage].push(row);
        }
    }
    for (k, stage) in memory.stages.iter().enumerate() {
        assert!(!stage.rows.is_empty());
        // Bit for bit: the file holds every digit.
        assert_eq!(rows[k], stage.rows, "stage {k}");
    }
    // A dump every 100 global steps over 260 steps: 0, 100, 200.
    let frames = read_dump(&dir.join("t.dump")).unwrap();
    assert_eq!(
        frames.iter().map(|f| f.step).collect::<Vec<_>>(),
        vec![0, 100, 200]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn scene_formats_old_load_and_newer_are_refused() {
    let dir = common::scratch_dir("trajectory-version");
    let scene = moving_solid();
    let mut json = serde_json::to_value(&scene).unwrap();
    // Version 1: no version, model or per-particle arrays.
    let obj = json.as_object_mut().unwrap();
    obj.remove("version");
    obj.remove("model");
    let old = dir.join("old.json");
    std::fs::write(&old, serde_json::to_string(&json).unwrap()).unwrap();
    let (loaded, _) = bpm::scene::read_scene(&old).unwrap();
    assert_eq!(loaded.version, 1);
    assert_eq!(loaded.particles, scene.particles);
    json["version"] = serde_json::json!(bpm::scene::SCENE_VERSION + 1);
    let newer = dir.join("newer.json");
    std::fs::write(&newer, serde_json::to_string(&json).unwrap()).unwrap();
    let err = bpm::scene::read_scene(&newer).unwrap_err().to_string();
    assert!(err.contains("`version`") && err.contains("newer"), "{err}");
    json["version"] = serde_json::json!(2);
    // A model this build does not know is refused, naming those it knows.
    json["model"] = serde_json::json!("ellipsoids");
    std::fs::write(&newer, serde_json::to_string(&json).unwrap()).unwrap();
    let err = bpm::scene::read_scene(&newer).unwrap_err().to_string();
    assert!(
        err.contains("ellipsoids") && err.contains("bpm") && err.contains("dem"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn per_particle_masses_and_types_agree_between_engines() {
    let mut scene = moving_solid();
    let n = scene.particles.positions.len();
    // Every third particle is type 2 with mass 2.5.
    let kind: Vec<u32> = (0..n).map(|i| if i % 3 == 0 { 2 } else { 1 }).collect();
    let mass: Vec<f64> = kind
        .iter()
        .map(|&t| if t == 2 { 2.5 } else { 1.0 })
        .collect();
    scene.particles.kind = Some(kind);
    scene.particles.mass = bpm::scene::Mass::PerParticle(mass.clone());
    let native = bpm::verify::run_native(&scene, "masses", 1).unwrap();
    let launcher = bpm::verify::LammpsLauncher {
        bpm: bpm_exe(),
        dir: common::scratch_dir("trajectory-masses"),
    };
    let lammps = launcher.run(&scene, "masses", 1, true).unwrap();
    let deviations = bpm::verify::compare_runs(&native.stages, &lammps.stages).unwrap();
    assert!(deviations.len() >= 6);
    for d in &deviations {
        let tol = tolerance(&format!("trajectory {}", d.observable));
        assert!(
            d.max_deviation <= tol,
            "{} deviates by {:e} (tolerance {tol:e})",
            d.observable,
            d.max_deviation
        );
    }
    // The masses matter: the same scene with unit masses moves otherwise.
    let mut light = scene.clone();
    light.particles.mass = bpm::scene::Mass::Uniform(1.0);
    let other = bpm::verify::run_native(&light, "light", 1).unwrap();
    let p = |s: &[bpm::scene::StageOutput]| s[0].column("e_kinetic").unwrap();
    assert_ne!(p(&native.stages), p(&other.stages));
    // Momentum is conserved with unequal masses.
    let mut sys = bpm::scene::build_system(&scene, 1);
    let momentum = |sys: &bpm::engine::System| {
        let p = &sys.particles;
        (0..3)
            .map(|d| p.v.iter().zip(&p.mass).map(|(v, m)| m * v[d]).sum::<f64>())
            .collect::<Vec<_>>()
    };
    let before = momentum(&sys);
    let (_, err) = bpm::scene::run_scene(&mut sys, &scene, &RunOptions::quiet(1));
    assert!(err.is_none());
    let after = momentum(&sys);
    for d in 0..3 {
        assert!(
            (after[d] - before[d]).abs() < 1e-10,
            "{before:?} -> {after:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&launcher.dir);
}
