//! `bpm hertz` as a library call: a small smoother grain squeezed in both
//! engines gives the same force curve, and the report holds what the
//! study promises.

mod common;

use bpm::scene::builders::grain::{build_grain, GrainKind, GrainParams};
use bpm::scene::checkpoint::StudyCheckpoint;
use bpm::scene::CheckpointEvery;
use bpm::studies::hertz::{run_hertz, GrainSource, HertzOptions, Moduli, SqueezeEngine};
use bpm::studies::StudyRuntime;
use bpm::verify::tolerances::tolerance;
use bpm::verify::LammpsLauncher;

#[test]
fn both_engines_squeeze_a_grain_file_to_the_same_curve() {
    let dir = common::scratch_dir("hertz");
    let mut p = GrainParams::new(GrainKind::Smoother, 3.0, 5, -0.5);
    p.time_scale = 0.2;
    let (grain, _) = build_grain(&p, 1, false).unwrap();
    let file = dir.join("grain.json");
    bpm::scene::write_scene(&file, &grain).unwrap();
    let launcher = LammpsLauncher {
        bpm: env!("CARGO_BIN_EXE_bpm").into(),
        dir: dir.join("lammps"),
    };
    let mut reports = Vec::new();
    for engine in [SqueezeEngine::Native, SqueezeEngine::Lammps] {
        let opts = HertzOptions {
            source: GrainSource::File {
                path: file.clone(),
                radius: 3.0,
            },
            seeds: vec![5],
            a_b: -0.5,
            rotations: 2,
            max_overlap: 0.15,
            moduli: Moduli::paper_fits(-0.5),
            engine,
            records: 200,
            threads: 1,
        };
        let out = dir.join(format!("{engine:?}"));
        let report = run_hertz(
            &opts,
            &out,
            &launcher,
            &StudyRuntime::plain(1, false),
            &mut |_| {},
        )
        .unwrap();
        assert!(out.join("hertz.json").exists() && out.join("hertz.svg").exists());
        assert_eq!(report.squeezes.len(), 2);
        for s in &report.squeezes {
            assert!(s.curve.contact_record.is_some(), "the walls never touched");
            assert_eq!(s.curve.wall_gap.len(), s.curve.force.len());
        }
        // Two rotations of one grain touch the walls at different points.
        assert_ne!(
            report.squeezes[0].curve.force,
            report.squeezes[1].curve.force
        );
        assert!(report.ensemble.deviation.is_some());
        reports.push(report);
    }
    for (a, b) in reports[0].squeezes.iter().zip(&reports[1].squeezes) {
        let scale = a.curve.force.iter().fold(0.0f64, |m, f| m.max(f.abs()));
        let worst = a
            .curve
            .force
            .iter()
            .zip(&b.curve.force)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f64, f64::max);
        eprintln!(
            "rotation {}: force deviation {:e}",
            a.rotation,
            worst / scale
        );
        assert!(worst / scale <= tolerance("trajectory wall forces"));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The readable LAMMPS input `lammps_inputs/hertz_squeeze.in`, run by hand
/// as a LAMMPS user would, gives the native squeeze's force to the digits
/// it prints.
#[test]
fn the_readable_lammps_squeeze_input_gives_the_native_curve() {
    use bpm::scene::protocols::{hertz_squeeze, SqueezeParams};
    let dir = common::scratch_dir("hertz-input");
    let mut p = GrainParams::new(GrainKind::Smoother, 3.0, 5, 0.0);
    p.time_scale = 0.2;
    let (mut grain, _) = build_grain(&p, 1, false).unwrap();
    grain.force_field = bpm::scene::ForceField::paper(0.0);
    let data = dir.join("grain.data");
    std::fs::write(&data, bpm::scene::datafile::write_data_file(&grain)).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_lmp-bpm"))
        .current_dir(&dir)
        .args([
            "-in",
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/lammps_inputs/hertz_squeeze.in"
            ),
        ])
        .args([
            "-log", "none", "-var", "aB", "0", "-var", "travel", "1.0", "-var", "every", "2000",
        ])
        .arg("-var")
        .arg("data")
        .arg(&data)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    let rows: Vec<[f64; 3]> = text
        .lines()
        .skip_while(|l| !l.starts_with("Step v_gap v_force"))
        .skip(1)
        .map_while(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .filter_map(|w| w.parse().ok())
                .collect();
            (v.len() == 3).then(|| [v[0], v[1], v[2]])
        })
        .collect();
    assert_eq!(rows.len(), 11, "{text}");
    let mut params = SqueezeParams::paper(3.0, 0.2);
    // 35,000 steps in 35 records: one every 1,000 steps, at LAMMPS's rows.
    params.records = 35;
    let scene = hertz_squeeze(&grain, &params);
    let native = bpm::verify::run_native(&scene, "native", 1).unwrap();
    let stage = &native.stages[0];
    let step = stage.column("step").unwrap();
    let f0 = stage.column("wall0_force").unwrap();
    let f1 = stage.column("wall1_force").unwrap();
    for [s, _, force] in &rows[1..] {
        let k = step.iter().position(|t| t == s).unwrap();
        let mean = 0.5 * (f0[k] + f1[k]);
        // LAMMPS prints 10 significant digits.
        assert!(
            (force - mean).abs() <= 1e-9 * mean.abs(),
            "step {s}: {force} vs {mean}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `bpm hertz-sweep` in miniature: one case per radius and a_B, each with
/// its deviation and run times, and the saved grain squeezed again by
/// `bpm hertz --grain` repeats the sweep's curve exactly.
#[test]
fn the_sweep_saves_grains_that_squeeze_to_the_same_curve_again() {
    use bpm::scene::builders::grain::GrainKind;
    use bpm::studies::hertz_sweep::{run_hertz_sweep, SweepOptions};
    let dir = common::scratch_dir("hertz-sweep");
    let launcher = LammpsLauncher {
        bpm: env!("CARGO_BIN_EXE_bpm").into(),
        dir: dir.join("lammps"),
    };
    let opts = SweepOptions {
        kind: GrainKind::Smoother,
        radii: vec![3.0, 4.0],
        a_bs: vec![0.0, -0.5],
        seed: 3,
        rotations: 1,
        max_overlap: 0.1,
        records: 200,
        engine: SqueezeEngine::Native,
        threads: 1,
        time_scale: 0.05,
    };
    // Checkpointed, and stopped at step 150 of the last case's squeeze:
    // the resumed sweep must end with the curve a straight squeeze of the
    // same grain gives (`again`, below), bit for bit.
    let path = dir.join("sweep.ck");
    let session = |resume: bool| {
        let checkpoint = StudyCheckpoint::open(
            &path,
            CheckpointEvery::Steps(100),
            resume,
            "hertz-sweep",
            &opts,
            1,
        )
        .unwrap();
        StudyRuntime {
            checkpoint: Some(checkpoint),
            ..StudyRuntime::plain(1, false)
        }
    };
    let first = session(false);
    let checkpoint = first.checkpoint.clone().unwrap();
    let mut cases = 0;
    let stopped = run_hertz_sweep(&opts, &dir, &launcher, &first, &mut |_| {
        cases += 1;
        if cases == 3 {
            checkpoint.stop_runs_at(Some(150));
        }
    })
    .unwrap_err();
    assert!(stopped.to_string().contains("--resume"), "{stopped}");
    let second = session(true);
    let (parts, run) = second.checkpoint.as_ref().unwrap().summary();
    assert_eq!(parts.len(), 5, "two grains and three squeezes: {parts:?}");
    assert_eq!(run, Some(("R4-aB-0.5/seed3-rot0".to_string(), 150)));
    let report = run_hertz_sweep(&opts, &dir, &launcher, &second, &mut |_| {}).unwrap();
    assert_eq!(report.cases.len(), 4);
    for c in &report.cases {
        assert!(c.deviation.is_some(), "R = {} a_B = {}", c.radius, c.a_b);
        assert!(c.seconds_per_squeeze > 0.0 && c.grain.seconds > 0.0);
        assert!(dir.join(&c.folder).join("hertz.json").exists());
    }
    assert!(dir.join("sweep.json").exists() && dir.join("sweep.svg").exists());
    let case = &report.cases[3];
    assert_eq!((case.radius, case.a_b), (4.0, -0.5));
    let again = run_hertz(
        &HertzOptions {
            source: GrainSource::File {
                path: dir.join("grains/smoother-R4-s3.json"),
                radius: 4.0,
            },
            seeds: vec![3],
            a_b: -0.5,
            rotations: 1,
            max_overlap: 0.1,
            moduli: Moduli::paper_fits(-0.5),
            engine: SqueezeEngine::Native,
            records: 200,
            threads: 1,
        },
        &dir.join("again"),
        &launcher,
        &StudyRuntime::plain(1, false),
        &mut |_| {},
    )
    .unwrap();
    let swept: bpm::studies::hertz::HertzReport = serde_json::from_str(
        &std::fs::read_to_string(dir.join(&case.folder).join("hertz.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(again.squeezes[0].curve.force, swept.squeezes[0].curve.force);
    let _ = std::fs::remove_dir_all(&dir);
}
