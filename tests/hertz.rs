//! `bpm hertz` as a library call: a small smoother grain squeezed in both
//! engines gives the same force curve, and the report holds what the
//! study promises.

mod common;

use bpm::scene::builders::grain::{build_grain, GrainKind, GrainParams};
use bpm::studies::hertz::{run_hertz, GrainSource, HertzOptions, Moduli, SqueezeEngine};
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
        let report = run_hertz(&opts, &out, &launcher, &mut |_| {}).unwrap();
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
