//! Compaction of a small packing in both engines from one scene: the
//! barostat jams it and the stepwise compression squeezes it, with the
//! same pressure and box series in the native engine and in LAMMPS.

mod common;

use bpm::verify::tolerances::tolerance;
use bpm::verify::{compaction_deviation, run_native, small_compaction, LammpsLauncher};
use std::path::PathBuf;

#[test]
fn a_small_packing_jams_and_compresses_alike_in_both_engines() {
    let scene = small_compaction(3).unwrap();
    assert!(scene.stages[0].barostat.is_some() && scene.stages[0].reset_reference);
    let native = run_native(&scene, "compaction-native", 1).unwrap();
    let launcher = LammpsLauncher {
        bpm: PathBuf::from(env!("CARGO_BIN_EXE_bpm")),
        dir: common::scratch_dir("compaction"),
    };
    let lammps = launcher.run(&scene, "compaction", 1, true).unwrap();
    for d in compaction_deviation(&native.stages, &lammps.stages).unwrap() {
        let tol = tolerance(&d.observable);
        assert!(tol > 0.0, "no tolerance for {}", d.observable);
        assert!(
            d.max_deviation <= tol,
            "{} deviates by {:e} at step {} (tolerance {tol:e})",
            d.observable,
            d.max_deviation,
            d.at_step
        );
    }
    // It jammed (the barostat held the pressure near its target, far
    // below the compressed state's) and was compressed: the box shrank by
    // the protocol's strain after the barostat had shrunk it further.
    let pressure = |k: usize| native.stages[k].column("pressure").unwrap();
    let jam = pressure(0);
    let last = pressure(native.stages.len() - 1);
    assert!(jam.last().unwrap().abs() < 1e-5, "{jam:?}");
    assert!(*last.last().unwrap() > 1e-3, "{last:?}");
    let lx = |k: usize| native.stages[k].column("lx").unwrap();
    let (l0, l1) = (lx(0)[0], *lx(0).last().unwrap());
    // Unjammed, the barostat shrinks the volume by gain * P_T = 1e-6 per
    // step: at most 2% (0.66% in length) over its 20,000 steps.
    assert!(
        l1 < 0.995 * l0 && l1 > 0.993 * l0,
        "the barostat did not shrink the box as it should: {l0} -> {l1}"
    );
    // Each compression stage scales the box as exp(-rate t) in closed form
    // (rates 3e-5, 1e-4, 1e-4), to its last recorded row.
    for (k, rate) in [(1, 3e-5), (2, 1e-4), (3, 1e-4)] {
        let stage = &native.stages[k];
        let (t, l) = (stage.column("time").unwrap(), lx(k));
        let last = t.len() - 1;
        let expected = l[0] * (-rate * (t[last] - t[0])).exp();
        assert!(
            (l[last] / expected - 1.0).abs() < 1e-12,
            "stage {k}: {} against {expected}",
            l[last]
        );
    }
    let _ = std::fs::remove_dir_all(&launcher.dir);
}

/// The readable LAMMPS script (lammps_inputs/compaction.in) runs the same
/// protocol as the scene: from the same packing data file, its box and
/// pressure at the end of the jam and of each full compression stage are
/// the native engine's; `analyse-packing` measures its dump.
#[test]
fn the_lammps_compaction_script_follows_the_protocol_and_its_dump_is_measured() {
    use bpm::analysis::packing::AnalysisOptions;
    use bpm::scene::datafile::write_data_file;
    use bpm::studies::compaction::analyse_dump;
    let scene = small_compaction(3).unwrap();
    let native = run_native(&scene, "compaction-script-native", 1).unwrap();

    let dir = common::scratch_dir("compaction-script");
    let data = dir.join("packing.data");
    std::fs::write(&data, write_data_file(&scene)).unwrap();
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("lammps_inputs/compaction.in");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_lmp-bpm"))
        .current_dir(&dir)
        .args(["-in", script.to_str().unwrap(), "-log", "none"])
        .args(["-var", "data", data.to_str().unwrap()])
        .args(["-var", "gain", "1.0", "-var", "jamtime", "2000"])
        .args([
            "-var", "rate0", "3e-5", "-var", "rate1", "1e-4", "-var", "levels", "2",
        ])
        .args(["-var", "stagetime", "500", "-var", "vstrain", "0.25"])
        .args(["-var", "dumpevery", "10000"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    // "<what>: step S volume V pressure P" lines, one per stage end.
    let ends: Vec<(u64, f64, f64)> = text
        .lines()
        .filter(|l| l.starts_with("jammed:") || l.starts_with("compression stage"))
        .filter_map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            let at = |k: &str| w.iter().position(|x| *x == k).map(|i| w[i + 1]);
            Some((
                at("step")?.parse().ok()?,
                at("volume")?.parse().ok()?,
                at("pressure")?.parse().ok()?,
            ))
        })
        .collect();
    assert_eq!(ends.len(), 4, "{text}");
    let mut compared = 0;
    for stage in &native.stages {
        let steps = stage.column("step").unwrap();
        let (x, y, z) = (
            stage.column("lx").unwrap(),
            stage.column("ly").unwrap(),
            stage.column("lz").unwrap(),
        );
        let p = stage.column("pressure").unwrap();
        let scale = p.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let last = steps.len() - 1;
        if let Some(&(_, volume, pressure)) = ends.iter().find(|e| e.0 as f64 == steps[last]) {
            let native_volume = x[last] * y[last] * z[last];
            assert!(
                (volume / native_volume - 1.0).abs() <= tolerance("compaction box"),
                "{}: script {volume} native {native_volume}",
                stage.name
            );
            assert!(
                (pressure - p[last]).abs() / scale <= tolerance("compaction pressure"),
                "{}: script {pressure} native {}",
                stage.name,
                p[last]
            );
            compared += 1;
        }
    }
    // The jam and the two full stages end on a recorded step; the last,
    // shortened stage ends between records.
    assert_eq!(compared, 3);

    let report = analyse_dump(
        &data,
        &dir.join("states.dump"),
        &AnalysisOptions {
            mc_points: 50_000,
            ..AnalysisOptions::default()
        },
        "test",
    )
    .unwrap();
    let first = &report.frames[0].packing;
    let end = &report.frames.last().unwrap().packing;
    assert_eq!(report.frames[0].step, 0);
    assert!(first.eps_v_mean.abs() < 1e-12 && first.asphericity_excess_mean.abs() < 1e-12);
    assert_eq!(first.force_contacts, 0);
    assert!(end.eps_v_mean > 1e-3 && end.z_force > 4.0, "{end:?}");
    assert!(end.phi_mc > first.phi_mc + 0.05);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The packing-moduli measurement (restart from a saved state, relax,
/// compress or shear, fit) on a solid whose moduli the calibration
/// measures independently: a bulk solid saved at 0.1% linear compression.
/// Its relaxed pressure is then K times the volumetric strain, which holds
/// only if the restart keeps the stress-free reference lengths; K and G
/// match the calibration's, and LAMMPS's match the native engine's. In a
/// study's checkpoint, LAMMPS's runs are kept as they finish.
#[test]
fn packing_moduli_of_a_compressed_solid_match_its_calibration_in_both_engines() {
    use bpm::scene::builders::bulk::{build_bulk, BulkParams};
    use bpm::scene::checkpoint::StudyCheckpoint;
    use bpm::scene::protocols::PackingModuliProtocol;
    use bpm::scene::run::Checkpoint;
    use bpm::scene::CheckpointEvery;
    use bpm::studies::calibration::{measure_moduli, CalibrationEngine, Loading};
    use bpm::studies::compaction::moduli::{measure_state, MeasureStop};
    use bpm::studies::compaction::CompactionEngine;
    use bpm::studies::{StudyRuntime, StudyStop};
    use std::sync::atomic::Ordering;

    let solid = build_bulk(&BulkParams::shortened(6.0, 4, 0.0), 1, false)
        .unwrap()
        .0;
    let (calibrated, [compressed, _]) = measure_moduli(
        &solid,
        0.0,
        false,
        &Loading::default(),
        &CalibrationEngine::Native(1),
        "calibration",
    )
    .unwrap();
    let scale = 0.999;
    let lo = solid.simbox.lo;
    let state = Checkpoint {
        step: 7,
        simbox: [
            lo,
            solid.simbox.lengths.map(|l| l * scale),
            solid.simbox.tilt,
        ],
        positions: solid
            .particles
            .positions
            .iter()
            .map(|x| std::array::from_fn(|d| lo[d] + (x[d] - lo[d]) * scale))
            .collect(),
        images: Vec::new(),
        broken_bonds: Vec::new(),
    };
    let protocol = PackingModuliProtocol {
        relax_time: 200.0,
        compression_rate: 1e-5,
        shear_rate: 2e-5,
        ..PackingModuliProtocol::paper()
    };
    let dir = common::scratch_dir("packing-moduli");
    let bpm = PathBuf::from(env!("CARGO_BIN_EXE_bpm"));
    let native = measure_state(
        &solid,
        &state,
        &protocol,
        &CompactionEngine::Native,
        &dir,
        None,
        &plain(),
    )
    .unwrap();
    // LAMMPS's three runs are kept in a study's checkpoint as they finish,
    // beneath the state's key: here the shear run fails (a `bpm` that
    // refuses it) and the compression, run before it, stays kept.
    let path = dir.join("study.ck");
    let open = |resume| {
        StudyCheckpoint::open(
            &path,
            CheckpointEvery::Steps(1000),
            resume,
            "compact",
            &(),
            1,
        )
        .unwrap()
    };
    let refusing = dir.join("bpm-refusing-shear");
    std::fs::write(
        &refusing,
        format!(
            "#!/bin/sh\ncase \"$*\" in *-shear/*) echo refused >&2; exit 3;; esac\nexec '{}' \"$@\"\n",
            bpm.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(
        &refusing,
        std::os::unix::fs::PermissionsExt::from_mode(0o755),
    )
    .unwrap();
    let measure_in_lammps = |checkpoint: &StudyCheckpoint, bpm: Option<&std::path::Path>| {
        let runtime = StudyRuntime {
            checkpoint: Some(checkpoint.clone()),
            ..plain()
        };
        measure_state(
            &solid,
            &state,
            &protocol,
            &CompactionEngine::Lammps { ranks: 1 },
            &dir,
            bpm,
            &runtime.scoped("state"),
        )
    };
    let kept = ["state/compress", "state/control", "state/shear"].map(String::from);
    let first = open(false);
    let e = measure_in_lammps(&first, Some(&refusing)).unwrap_err();
    assert!(matches!(e, MeasureStop::Failed(_)), "{e:?}");
    assert_eq!(open(true).summary(), (vec![kept[0].clone()], None));
    // Resumed from the file, the measurement runs the other two.
    let lammps = measure_in_lammps(&open(true), Some(&bpm)).unwrap();
    assert_eq!(open(true).summary(), (kept.to_vec(), None));
    assert!(lammps.seconds > 0.0);
    // Measured again from the kept runs, with no LAMMPS to run: the same
    // moduli, bit for bit.
    let resumed = open(true);
    let again = measure_in_lammps(&resumed, None).unwrap();
    assert_eq!(
        [
            again.bulk,
            again.shear,
            again.relaxed_pressure,
            again.seconds
        ]
        .map(f64::to_bits),
        [
            lammps.bulk,
            lammps.shear,
            lammps.relaxed_pressure,
            lammps.seconds
        ]
        .map(f64::to_bits)
    );
    // A stop asked for after the first run ends the measurement before the
    // next (without LAMMPS, running it would fail instead), keeping it.
    resumed.drop_parts(|k| k != "state/compress");
    resumed.stop_flag().store(true, Ordering::SeqCst);
    match measure_in_lammps(&resumed, None) {
        Err(MeasureStop::Stopped(StudyStop::Interrupted(stopped))) => assert_eq!(stopped, path),
        other => panic!("not stopped as asked: {:?}", other.map(|_| ())),
    }
    assert_eq!(resumed.summary(), (vec![kept[0].clone()], None));
    let strain = 1.0 - scale.powi(3);
    // The built solid's own pressure (contacts between unbonded
    // neighbours) adds to the strain's.
    let p0 = compressed.stages[0].column("pressure").unwrap()[0];
    let expected_pressure = p0 + calibrated.k * strain;
    assert!(
        (native.relaxed_pressure / expected_pressure - 1.0).abs() < 0.02,
        "relaxed pressure {} against K eps_V = {expected_pressure}",
        native.relaxed_pressure
    );
    assert!(native.is_reliable(), "{native:?}");
    // A solid at rest does not creep: the control changes nothing.
    assert!(
        native.bulk_creep_fraction().abs() < 1e-3 && native.shear_creep_fraction().abs() < 1e-3,
        "{native:?}"
    );
    assert!(
        (native.bulk / calibrated.k - 1.0).abs() < 0.02
            && (native.shear / calibrated.g - 1.0).abs() < 0.02,
        "K {} G {} against the calibration's {} {}",
        native.bulk,
        native.shear,
        calibrated.k,
        calibrated.g
    );
    assert!(
        (native.poisson - calibrated.nu).abs() < 0.01,
        "nu {} against {}",
        native.poisson,
        calibrated.nu
    );
    for (ours, theirs, what) in [
        (native.bulk, lammps.bulk, "K"),
        (native.shear, lammps.shear, "G"),
    ] {
        let d = (ours / theirs - 1.0).abs();
        assert!(d <= tolerance(what), "{what}: engines differ by {d:e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `bpm compact` end to end on a tiny packing: states measured, moduli at
/// the picked states, report, plots and slice picture written; `--refit`
/// reproduces the fits; a study compared with itself agrees from its
/// first state.
#[test]
fn a_tiny_compaction_study_measures_moduli_and_writes_its_report() {
    use bpm::analysis::packing::AnalysisOptions;
    use bpm::scene::builders::grain::GrainKind;
    use bpm::scene::protocols::PackingModuliProtocol;
    use bpm::studies::compaction::{
        compare, refit, run_compaction, CompactOptions, CompactionEngine, ModuliOptions,
        PackingSource,
    };
    let dir = common::scratch_dir("tiny-compaction");
    let opts = CompactOptions {
        source: PackingSource::Build {
            grains: 12,
            kind: GrainKind::Rough,
            radius: 2.0,
            distinct_grains: 4,
            template_fraction: 0.57,
            time_scale: 0.2,
        },
        a_b: 0.0,
        zero_net: false,
        seeds: vec![1],
        protocol: tiny_protocol(),
        engine: CompactionEngine::Native,
        analysis: AnalysisOptions {
            mc_points: 20_000,
            ..Default::default()
        },
        moduli: ModuliOptions {
            states: 2,
            protocol: PackingModuliProtocol {
                relax_time: 200.0,
                compression_rate: 1e-6,
                shear_rate: 2e-6,
                ..PackingModuliProtocol::paper()
            },
        },
        dem: None,
        bond_failure: None,
        overlay_pair: false,
    };
    let report = run_compaction(&opts, &plain(), None, &dir, "test", &mut |_| {}).unwrap();
    let run = &report.runs[0];
    assert!(run.stopped.is_none(), "{:?}", run.stopped);
    assert_eq!(run.moduli.len() + run.moduli_failures.len(), 2);
    // The most compressed state is a solid packing: both moduli positive,
    // a Poisson ratio inside the isotropic bounds.
    let last = run.moduli.last().unwrap();
    let state = run.states.last().unwrap();
    assert_eq!((last.step, &last.stage), (state.step, &state.stage));
    assert!(
        last.moduli.bulk > 0.0 && last.moduli.shear > 0.0,
        "{last:?}"
    );
    assert!(last.moduli.poisson > -1.0 && last.moduli.poisson < 0.5);
    for file in [
        "compaction.json",
        "compaction.svg",
        "jamming.svg",
        "distributions.svg",
        "moduli.svg",
        "seed-1/slices.svg",
    ] {
        assert!(dir.join(file).is_file(), "{file} not written");
    }
    let text = std::fs::read_to_string(dir.join("compaction.txt")).unwrap();
    assert!(text.contains("K_P exponent") && text.contains("dalpha skew"));
    let again = refit(&dir).unwrap();
    assert_eq!(
        serde_json::to_value(&again.runs[0].fits).unwrap(),
        serde_json::to_value(&run.fits).unwrap()
    );
    let a = compare::read_study(&dir, "a").unwrap();
    let b = compare::read_study(&dir, "b").unwrap();
    let first_compressed = run
        .states
        .iter()
        .filter(|s| s.stage.starts_with("compress") && s.p_over_e_eff > 0.0)
        .map(|s| s.packing.phi_mc)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(
        compare::joins_at(&a.report, &b.report),
        Some(first_compressed)
    );
    let last_phi = state.packing.phi_mc;
    let mid = 0.5 * (first_compressed + last_phi);
    assert_eq!(
        compare::pressure_ratio(&a.report, &b.report, mid),
        Some(1.0)
    );
    assert_eq!(
        compare::pressure_ratio(&a.report, &b.report, last_phi + 0.01),
        None
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `bpm compact --model dem` end to end on a tiny packing: one sphere per
/// grain of the bonded solid's E_eff, jammed and compressed by the same
/// protocol (no bond reset), every state measured as spheres: `phi_sphere`
/// is the spheres' volume over the box's, equal to `phi_MC` while no two
/// overlap and above it once they do; the report has no grain-shape
/// output.
#[test]
fn a_tiny_dem_compaction_compresses_spheres_and_reports_both_volume_fractions() {
    use bpm::kernels::GranularCoeffs;
    use bpm::studies::compaction::{
        compare, run_compaction, CompactionEngine, DemContact, PackingSource,
    };
    let dir = common::scratch_dir("tiny-dem-compaction");
    let dem = DemContact {
        friction: [0.15, 0.1, 0.1],
        ..DemContact::default()
    };
    let mut opts = tiny_study(Some(dem), 50_000);
    let report = run_compaction(&opts, &plain(), None, &dir, "test", &mut |_| {}).unwrap();
    let run = &report.runs[0];
    assert!(run.stopped.is_none(), "{:?}", run.stopped);
    assert_eq!((run.grains, run.particles), (16, 16));
    assert_eq!(run.expansion, run.packing.as_ref().unwrap().expansion);
    let scene: bpm::scene::Scene =
        serde_json::from_str(&std::fs::read_to_string(dir.join("seed-3/scene.json")).unwrap())
            .unwrap();
    assert_eq!(scene.model, bpm::scene::ModelKind::Dem);
    assert!(scene.stages.iter().all(|s| !s.reset_reference));
    assert_eq!(scene.stages[0].name, "jam");
    let material = scene.force_field.granular.unwrap();
    assert_eq!(material.sliding_friction, 0.15);
    assert_eq!(material.rolling.unwrap().friction, 0.1);
    // The springs are those of the built spheres' radius and mass.
    let (radius, mass) = (
        scene.particles.radius.as_ref().unwrap()[0],
        scene.particles.mass.values(16)[0],
    );
    assert!(radius > 1.5 && mass > 20.0, "{radius} {mass}");
    assert_eq!(material, dem.material_of(&report.moduli, radius, mass));
    let k_n = GranularCoeffs::of(&material).normal_stiffness;
    assert!((k_n / (4.0 / 3.0 * report.e_eff) - 1.0).abs() < 1e-12);
    let spheres = 16.0 * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
    for s in &run.states {
        let p = &s.packing;
        assert!((p.phi_sphere - spheres / p.box_volume).abs() < 1e-12 * p.phi_sphere);
        assert!(p.eps_v.is_empty() && p.asphericity.is_empty());
    }
    let (start, end) = (&run.states[0], run.states.last().unwrap());
    assert_eq!(start.packing.force_contacts, 0);
    let mc = |s: &bpm::studies::compaction::StateRow| 4.0 * s.packing.phi_mc_error;
    assert!((start.packing.phi_mc - start.packing.phi_sphere).abs() < mc(start));
    assert!(end.stage.starts_with("compress") && end.p_over_e_eff > 0.0);
    assert!(end.packing.z_force > 4.0, "{}", end.packing.z_force);
    assert!(
        end.packing.phi_sphere > end.packing.phi_mc + 0.05,
        "{} against {}",
        end.packing.phi_sphere,
        end.packing.phi_mc
    );
    for file in [
        "compaction.json",
        "compaction.svg",
        "jamming.svg",
        "seed-3/slices.svg",
    ] {
        assert!(dir.join(file).is_file(), "{file} not written");
    }
    assert!(!dir.join("distributions.svg").exists());
    let study = compare::read_study(&dir, "dem").unwrap();
    let table = compare::comparison_table(&[study], "test");
    // Pressures the compression passes through have their phi_sphere,
    // rising with the pressure.
    let row = table
        .lines()
        .skip_while(|l| !l.starts_with("phi_sphere (spheres) where P / E_eff first reaches"))
        .nth(1)
        .unwrap();
    let phis: Vec<f64> = row
        .split_whitespace()
        .filter_map(|c| c.parse().ok())
        .collect();
    assert!(phis.len() >= 3, "{row}");
    assert!(phis.windows(2).all(|w| w[0] < w[1]), "{row}");
    assert!(
        phis[0] > 0.55 && phis[phis.len() - 1] <= end.packing.phi_sphere,
        "{row}"
    );
    // A sphere file is not a packing of grains.
    let mut grains = opts.clone();
    grains.dem = None;
    grains.source = PackingSource::File {
        path: dir.join("seed-3/packing.data"),
    };
    let e = run_compaction(
        &grains,
        &plain(),
        None,
        &dir.join("grains"),
        "test",
        &mut |_| {},
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("compact them with --model dem"),
        "{e}"
    );
    // What a DEM study cannot do is refused, naming the option.
    opts.moduli.states = 2;
    let e = run_compaction(&opts, &plain(), None, &dir, "test", &mut |_| {}).unwrap_err();
    assert!(e.to_string().contains("--moduli-states"), "{e}");
    opts.moduli.states = 0;
    opts.zero_net = true;
    let e = run_compaction(&opts, &plain(), None, &dir, "test", &mut |_| {}).unwrap_err();
    assert!(e.to_string().contains("--zero-net"), "{e}");
    // LAMMPS's history flaw for rolling and twisting is recorded with the
    // run (here one that cannot start: no bpm executable to launch).
    opts.zero_net = false;
    opts.engine = CompactionEngine::Lammps { ranks: 1 };
    let lammps = dir.join("lammps");
    let report = run_compaction(&opts, &plain(), None, &lammps, "test", &mut |_| {}).unwrap();
    assert!(report.warnings[0].contains("rolling and twisting"));
    let stopped = report.runs[0].stopped.as_deref().unwrap();
    assert!(stopped.contains("no bpm executable"), "{stopped}");
    let table = std::fs::read_to_string(lammps.join("compaction.txt")).unwrap();
    assert!(table.contains("# warning: LAMMPS negates"), "{table}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `bpm mc-calibrate` end to end on a tiny grain study: the grains'
/// packing is compressed again as spheres with plain Hertz and the
/// closures; each sphere study carries its closure, a larger prefactor
/// stiffens the spheres, the fit picks a law of the grid, a second call
/// reuses every study, and the closure is refused where it cannot run.
#[test]
fn closures_are_calibrated_against_a_tiny_grain_study() {
    use bpm::studies::compaction::{run_compaction, CompactOptions, CompactionEngine, DemContact};
    use bpm::studies::mcdem::calibration::{run_calibration, CalibrationOptions, Law, DISTANCES};
    let dir = common::scratch_dir("tiny-closure-calibration");
    // Enough states near jamming for the fit of phi_c.
    let mut grains = tiny_study(None, 20_000);
    grains.protocol.states_per_stage = 12;
    let grains_dir = dir.join("grains");
    let g = run_compaction(&grains, &plain(), None, &grains_dir, "test", &mut |_| {}).unwrap();
    assert!(g.runs[0].stopped.is_none(), "{:?}", g.runs[0].stopped);
    assert!(
        g.runs[0].fits.pressure.is_some(),
        "the grains' phi_c is not fitted"
    );
    let opts = CalibrationOptions {
        grains: vec![grains_dir.clone()],
        gammas: vec![0.5, 2.0],
        advanced_gammas: vec![1.0],
        mprs: vec![0.1],
        reach: 0.1,
        volumetric_strain: 0.25,
        window: [0.05, 0.15],
        ..CalibrationOptions::default()
    };
    let out = dir.join("calibration");
    let report = run_calibration(
        &opts,
        &bpm::studies::StudyRuntime::plain(1, false),
        &out,
        "test",
        &mut |_| {},
    )
    .unwrap();
    let study = &report.studies[0];
    assert_eq!(study.label, "grains");
    let laws: Vec<Law> = study.variants.iter().map(|v| v.law).collect();
    assert_eq!(laws, opts.laws());
    for v in &study.variants {
        assert!(v.stopped.is_none(), "{:?}: {:?}", v.law, v.stopped);
        let scene: bpm::scene::Scene = serde_json::from_str(
            &std::fs::read_to_string(v.folder.join("seed-3/scene.json")).unwrap(),
        )
        .unwrap();
        let m = scene.force_field.multicontact;
        match v.law {
            Law::Hertz => assert!(m.is_none()),
            Law::Standard { gamma } => {
                let m = m.unwrap();
                assert_eq!(
                    (m.prefactor, m.max_penetration_ratio, m.reach),
                    (gamma, None, 0.1)
                );
            }
            Law::Advanced { gamma, mpr } => {
                let m = m.unwrap();
                assert_eq!(
                    (m.prefactor, m.max_penetration_ratio, m.reach),
                    (gamma, Some(mpr), 0.1)
                );
            }
        }
    }
    // From the same packing, a larger prefactor needs more pressure at the
    // same distance from jamming, at the furthest distance all reach.
    let ratios = |k: usize| &study.variants[k].ratio_at_distance;
    let common_far = (0..DISTANCES.len())
        .rev()
        .find(|&i| (0..3).all(|k| ratios(k)[i].is_some()))
        .expect("the spheres reach no common distance");
    let at = |k: usize| ratios(k)[common_far].unwrap();
    assert!(
        at(0) < at(1) && at(1) < at(2),
        "at phi - phi_c = {}: Hertz {}, gamma 0.5 {}, gamma 2 {}",
        DISTANCES[common_far],
        at(0),
        at(1),
        at(2)
    );
    // Every sphere variant is measured from plain Hertz's jamming point,
    // which the closures hardly move.
    let hertz_phi_c = study.variants[0].phi_c.unwrap();
    for v in &study.variants {
        assert_eq!(v.phi_c, Some(hertz_phi_c));
        assert!((v.own_phi_c.unwrap() - hertz_phi_c).abs() < 0.01, "{v:?}");
        assert!(!v.curve.is_empty());
    }
    assert!(matches!(
        study.best_standard.expect("no standard fit").law,
        Law::Standard { .. }
    ));
    for file in ["calibration.json", "calibration.svg", "calibration.txt"] {
        assert!(out.join(file).is_file(), "{file} not written");
    }
    // A second call reuses every complete study and finds the same; one
    // left without its run (as if interrupted) is run again, bit for bit.
    let interrupted = study.variants[1].folder.join("compaction.json");
    let mut record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&interrupted).unwrap()).unwrap();
    record["runs"] = serde_json::json!([]);
    std::fs::write(&interrupted, record.to_string()).unwrap();
    let mut said = Vec::new();
    let again = run_calibration(
        &opts,
        &bpm::studies::StudyRuntime::plain(1, false),
        &out,
        "test",
        &mut |m| said.push(m.to_string()),
    )
    .unwrap();
    let count = |what: &str| said.iter().filter(|m| m.contains(what)).count();
    assert_eq!((count("reused"), count("incomplete")), (3, 1), "{said:?}");
    assert_eq!(
        serde_json::to_value(&again.studies).unwrap(),
        serde_json::to_value(&report.studies).unwrap()
    );
    // The spheres' study of a grain study is not a grain study; LAMMPS
    // has no closure.
    let e = run_calibration(
        &CalibrationOptions {
            grains: vec![study.variants[0].folder.clone()],
            ..opts.clone()
        },
        &bpm::studies::StudyRuntime::plain(1, false),
        &dir.join("wrong"),
        "test",
        &mut |_| {},
    )
    .unwrap_err();
    assert!(e.to_string().contains("DEM spheres"), "{e}");
    // The grains' packing is rebuilt only with their thread count.
    assert_eq!(g.threads, Some(1));
    let e = run_calibration(
        &opts,
        &bpm::studies::StudyRuntime::plain(2, false),
        &dir.join("wrong"),
        "test",
        &mut |_| {},
    )
    .unwrap_err();
    assert!(e.to_string().contains("--threads"), "{e}");
    let lammps = CompactOptions {
        engine: CompactionEngine::Lammps { ranks: 1 },
        dem: Some(DemContact {
            multicontact: Some(bpm::engine::dem::MultiContact::standard(0.82)),
            ..DemContact::default()
        }),
        ..grains
    };
    let e = lammps.validate().unwrap_err();
    assert!(e.to_string().contains("--closure"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A study of 16 rough grains of R = 2 d (seed 3, built in a twentieth of
/// the full time), by the tiny protocol, without moduli: as grains, or
/// as DEM spheres with `dem`.
fn tiny_study(
    dem: Option<bpm::studies::compaction::DemContact>,
    mc_points: u64,
) -> bpm::studies::compaction::CompactOptions {
    use bpm::studies::compaction::{CompactionEngine, ModuliOptions, PackingSource};
    bpm::studies::compaction::CompactOptions {
        source: PackingSource::Build {
            grains: 16,
            kind: bpm::scene::builders::grain::GrainKind::Rough,
            radius: 2.0,
            distinct_grains: 2,
            template_fraction: 0.57,
            time_scale: 0.05,
        },
        a_b: 0.0,
        zero_net: false,
        seeds: vec![3],
        protocol: tiny_protocol(),
        engine: CompactionEngine::Native,
        analysis: bpm::analysis::packing::AnalysisOptions {
            mc_points,
            ..Default::default()
        },
        moduli: ModuliOptions {
            states: 0,
            ..ModuliOptions::default()
        },
        dem,
        bond_failure: None,
        overlay_pair: false,
    }
}

/// A compaction protocol of a few thousand steps: jam for 2e3 tau, then
/// two rates to 40% volumetric strain.
fn tiny_protocol() -> bpm::scene::protocols::CompactionProtocol {
    bpm::scene::protocols::CompactionProtocol {
        jam_gain: 1.0,
        jam_time: 2e3,
        rate_start: 1e-5,
        rate_end: 1e-4,
        rate_levels: 2,
        stage_time: 1e3,
        volumetric_strain: 0.4,
        ..bpm::scene::protocols::CompactionProtocol::paper()
    }
}

/// One thread, no progress bars, no checkpoint.
fn plain() -> bpm::studies::StudyRuntime {
    bpm::studies::StudyRuntime::plain(1, false)
}

/// A report's runs as JSON without wall times and folders, which differ
/// between sessions.
fn runs_without_times(report: &bpm::studies::compaction::CompactionReport) -> serde_json::Value {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(map) => {
                map.retain(|k, _| !k.contains("seconds") && k != "folder");
                map.values_mut().for_each(strip);
            }
            serde_json::Value::Array(items) => items.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let mut runs = serde_json::to_value(&report.runs).unwrap();
    strip(&mut runs);
    runs
}

#[test]
fn a_compaction_study_stopped_twice_resumes_to_the_same_report() {
    use bpm::scene::checkpoint::StudyCheckpoint;
    use bpm::scene::CheckpointEvery;
    use bpm::studies::compaction::{run_compaction, CompactionError};
    use bpm::studies::{StudyRuntime, StudyStop};
    use std::sync::atomic::Ordering;
    let mut opts = tiny_study(None, 20_000);
    opts.moduli.states = 2;
    opts.moduli.protocol.relax_time = 100.0;
    opts.moduli.protocol.compression_rate = 1e-5;
    opts.moduli.protocol.shear_rate = 2e-5;
    let straight_dir = common::scratch_dir("ck-study-straight");
    let straight =
        run_compaction(&opts, &plain(), None, &straight_dir, "test", &mut |_| {}).unwrap();
    assert_eq!(straight.runs[0].moduli.len(), 2);

    let dir = common::scratch_dir("ck-study");
    let path = dir.join("study.ck");
    let session = |resume: bool| {
        let checkpoint = StudyCheckpoint::open(
            &path,
            CheckpointEvery::Steps(700),
            resume,
            "compact",
            &opts.checkpoint_identity(),
            1,
        )
        .unwrap();
        StudyRuntime {
            checkpoint: Some(checkpoint),
            ..plain()
        }
    };
    let stopped = |e: CompactionError| {
        assert!(
            matches!(e, CompactionError::Stopped(StudyStop::Interrupted(_))),
            "{e}"
        );
    };
    // Stopped by a signal's flag a moment into the run, at whatever step
    // it has reached.
    let first = session(false);
    let flag = first.checkpoint.as_ref().unwrap().stop_flag();
    let e = run_compaction(&opts, &first, None, &dir, "test", &mut |line| {
        if line.contains("running") {
            let flag = flag.clone();
            std::thread::spawn(move || {
                std::thread::sleep(std::time::Duration::from_millis(300));
                flag.store(true, Ordering::SeqCst);
            });
        }
    })
    .unwrap_err();
    stopped(e);
    // The run continues from its checkpoint; the study is stopped again
    // after its first moduli measurement.
    let second = session(true);
    let (parts, run) = second.checkpoint.as_ref().unwrap().summary();
    assert_eq!(parts, ["seed-3/packing"]);
    let (key, step) = run.expect("stopped inside the run");
    assert!(key == "seed-3/run" && step > 1, "{key} {step}");
    let flag = second.checkpoint.as_ref().unwrap().stop_flag();
    let mut lines = Vec::new();
    let e = run_compaction(&opts, &second, None, &dir, "test", &mut |line| {
        lines.push(line.to_string());
        if line.contains("moduli 1/2") {
            flag.store(true, Ordering::SeqCst);
        }
    })
    .unwrap_err();
    stopped(e);
    assert!(lines.iter().any(|l| l.contains("moduli 1/2")), "{lines:?}");
    // Stopped again in the middle of the second measurement: ten steps
    // into its first loading (its steps count on from its relaxation's).
    let third = session(true);
    let relax_steps = opts.moduli.protocol.relax_stage().steps;
    third
        .checkpoint
        .as_ref()
        .unwrap()
        .stop_runs_at(Some(relax_steps + 10));
    let mut lines = Vec::new();
    let e = run_compaction(&opts, &third, None, &dir, "test", &mut |line| {
        lines.push(line.to_string())
    })
    .unwrap_err();
    stopped(e);
    assert!(!lines.iter().any(|l| l.contains("moduli 2/2")), "{lines:?}");
    let (parts, run) = session(true).checkpoint.as_ref().unwrap().summary();
    let measuring = format!("seed-3/moduli-{}/", straight.runs[0].moduli[1].step);
    // Parts of a part (a measurement's steps) have a third `/`.
    let steps: Vec<&String> = parts
        .iter()
        .filter(|p| p.matches('/').count() > 2)
        .collect();
    assert!(
        steps.len() == 1 && steps[0].starts_with(&measuring) && steps[0].ends_with("/relaxed"),
        "the second measurement's relaxed state kept, the first's steps dropped: {parts:?}"
    );
    let (key, step) = run.expect("stopped inside the loading");
    assert!(
        key.starts_with(&measuring) && key.ends_with("/compress"),
        "{key}"
    );
    assert_eq!(step, relax_steps + 10);
    // Kept to be resumed below with other moduli options.
    let midway = dir.join("midway.ck");
    std::fs::copy(&path, &midway).unwrap();
    let mut lines = Vec::new();
    let resumed = run_compaction(&opts, &session(true), None, &dir, "test", &mut |line| {
        lines.push(line.to_string())
    })
    .unwrap();
    assert_eq!(runs_without_times(&straight), runs_without_times(&resumed));
    // The finished run and the first measurement came from the checkpoint.
    assert!(lines.iter().any(|l| l.contains("moduli 2/2")), "{lines:?}");
    let (parts, run) = session(true).checkpoint.as_ref().unwrap().summary();
    assert!(run.is_none());
    assert!(
        parts.iter().all(|p| p.matches('/').count() <= 2),
        "only whole parts are left: {parts:?}"
    );
    // Resumed with another moduli protocol, the study takes the packing
    // and the run from the checkpoint (its wall time comes back to the
    // bit) and measures the moduli anew.
    let mut relaxed_longer = opts.clone();
    relaxed_longer.moduli.protocol.relax_time = 150.0;
    assert_eq!(
        relaxed_longer.checkpoint_identity(),
        opts.checkpoint_identity()
    );
    let remeasured = run_compaction(
        &relaxed_longer,
        &session(true),
        None,
        &dir,
        "test",
        &mut |_| {},
    )
    .unwrap();
    let (a, b) = (&resumed.runs[0], &remeasured.runs[0]);
    assert_eq!(a.run_seconds.to_bits(), b.run_seconds.to_bits());
    assert_eq!(
        serde_json::to_value(&a.states).unwrap(),
        serde_json::to_value(&b.states).unwrap()
    );
    assert_eq!(b.moduli.len(), 2);
    assert!(b.moduli_failures.is_empty(), "{:?}", b.moduli_failures);
    for (m, n) in a.moduli.iter().zip(&b.moduli) {
        assert_eq!(m.step, n.step);
        assert_ne!(m.moduli.bulk, n.moduli.bulk);
    }
    // Resumed from the middle of the second measurement with other moduli
    // options, the study drops the steps that measurement kept (they would
    // not be read again) and measures as from a finished run.
    let from_midway = StudyRuntime {
        checkpoint: Some(
            StudyCheckpoint::open(
                &midway,
                CheckpointEvery::Steps(700),
                true,
                "compact",
                &opts.checkpoint_identity(),
                1,
            )
            .unwrap(),
        ),
        ..plain()
    };
    let again = run_compaction(
        &relaxed_longer,
        &from_midway,
        None,
        &dir,
        "test",
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(runs_without_times(&again), runs_without_times(&remeasured));
    let (parts, run) = StudyCheckpoint::open(
        &midway,
        CheckpointEvery::Steps(700),
        true,
        "compact",
        &opts.checkpoint_identity(),
        1,
    )
    .unwrap()
    .summary();
    assert!(run.is_none());
    assert!(
        parts.iter().all(|p| p.matches('/').count() <= 2),
        "no stale steps are left: {parts:?}"
    );
    // Options other than the checkpoint's are refused.
    let mut other = opts.clone();
    other.seeds = vec![4];
    let e = StudyCheckpoint::open(
        &path,
        CheckpointEvery::Steps(700),
        true,
        "compact",
        &other.checkpoint_identity(),
        1,
    )
    .unwrap_err();
    assert!(e.to_string().contains("other options"), "{e}");
}

/// The native moduli measurement relaxes a state once and starts its
/// three loadings from the relaxed state: the records equal those of the
/// three full runs (relaxation and loading each), bit for bit, on one and
/// two threads.
#[test]
fn the_moduli_loadings_branch_from_one_relaxation_as_three_full_runs() {
    use bpm::scene::checkpoint::StudyCheckpoint;
    use bpm::scene::protocols::PackingModuliProtocol;
    use bpm::scene::{build_system, run_scene, CheckpointEvery, RunOptions};
    use bpm::studies::compaction::moduli::{moduli_scenes, relax_once_then_load, MeasureStop};
    use bpm::studies::{StudyRuntime, StudyStop};
    let packing = small_compaction(3).unwrap();
    // A saved state of the packing, jostled, so the relaxation has
    // something to relax.
    let jostle = common::random_rows(packing.particles.positions.len(), 0.03, 11);
    let b = &packing.simbox;
    let state = bpm::scene::Checkpoint {
        step: 0,
        simbox: [b.lo, b.lengths, b.tilt],
        positions: packing
            .particles
            .positions
            .iter()
            .zip(&jostle)
            .map(|(x, dx)| [0, 1, 2].map(|k| x[k] + dx[k]))
            .collect(),
        images: Vec::new(),
        broken_bonds: Vec::new(),
    };
    let protocol = PackingModuliProtocol {
        dt: 0.05,
        relax_time: 15.0,
        compression_rate: 1e-5,
        shear_rate: 2e-5,
        rows: 8,
        ..PackingModuliProtocol::paper()
    };
    let scenes = moduli_scenes(&packing, &state, &protocol);
    for threads in [1, 2] {
        let branched = relax_once_then_load(&scenes, &StudyRuntime::plain(threads, false)).unwrap();
        for (scene, runs) in scenes.iter().zip(&branched) {
            let mut sys = build_system(scene, threads);
            let (full, error) = run_scene(&mut sys, scene, &RunOptions::quiet(threads));
            assert!(error.is_none(), "{error:?}");
            assert_eq!(full.len(), 2);
            for (a, b) in full.iter().zip(runs) {
                assert_eq!(a.name, b.name);
                assert!(!a.rows.is_empty());
                assert_eq!(a.rows, b.rows, "stage {} on {threads} thread(s)", a.name);
            }
        }
        // Not vacuous: the relaxation moved the pressure, and the
        // compression's pressure left the control's.
        let p = |k: usize, s: usize| branched[k][s].column("pressure").unwrap();
        let relax = p(0, 0);
        assert!(relax[0] != *relax.last().unwrap(), "{relax:?}");
        assert!(p(0, 1).last() != p(2, 1).last());
    }
    // Scenes that differ before their loadings cannot share a relaxation.
    let mut other = scenes.clone();
    other[2].stages[0].dt = 0.04;
    let e = relax_once_then_load(&other, &plain()).unwrap_err();
    assert!(matches!(e, MeasureStop::Failed(_)), "{e:?}");
    assert!(e.to_string().contains("differ only in their second"), "{e}");
    // A stop asked for (here at step 5 of the relaxation) ends the
    // measurement, naming the study's checkpoint, which keeps the run under
    // way; it is not taken for a failed measurement. A stop asked for
    // between runs ends it before the next.
    let dir = common::scratch_dir("moduli-stop");
    let path = dir.join("study.ck");
    let checkpoint =
        StudyCheckpoint::open(&path, CheckpointEvery::Steps(100), false, "compact", &(), 1)
            .unwrap();
    checkpoint.stop_runs_at(Some(5));
    let runtime = StudyRuntime {
        checkpoint: Some(checkpoint.clone()),
        ..plain()
    };
    for _ in 0..2 {
        match relax_once_then_load(&scenes, &runtime) {
            Err(MeasureStop::Stopped(StudyStop::Interrupted(stopped_at))) => {
                assert_eq!(stopped_at, path)
            }
            other => panic!("not stopped as asked: {:?}", other.map(|_| ())),
        }
        let written =
            StudyCheckpoint::open(&path, CheckpointEvery::Steps(100), true, "compact", &(), 1)
                .unwrap();
        assert_eq!(
            written.summary(),
            (vec![], Some(("relaxed".to_string(), 5)))
        );
        checkpoint
            .stop_flag()
            .store(true, std::sync::atomic::Ordering::SeqCst);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Grains whose bonds break, compressed: every state counts the broken
/// bonds and the grains' fragments. Bonds never mend, so the broken share
/// and the loose particles only grow and the whole grains only dwindle,
/// and grains in pieces are flagged. LAMMPS and modulus runs, which do
/// not keep broken bonds, are refused.
#[test]
fn breakable_grains_come_apart_as_they_are_compressed() {
    use bpm::kernels::BondFailure;
    use bpm::studies::compaction::{run_compaction, CompactOptions, CompactionEngine};
    let dir = common::scratch_dir("breakable-compaction");
    let opts = CompactOptions {
        bond_failure: Some(BondFailure::breaking(0.05)),
        ..tiny_study(None, 5_000)
    };
    let report = run_compaction(&opts, &plain(), None, &dir, "test", &mut |_| {}).unwrap();
    let run = &report.runs[0];
    assert!(run.stopped.is_none(), "{:?}", run.stopped);
    let fragments: Vec<_> = run.states.iter().map(|s| s.fragments.unwrap()).collect();
    assert_eq!(fragments[0].broken_fraction, 0.0);
    assert_eq!(fragments[0].whole_grains, 1.0);
    for pair in fragments.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        assert!(b.broken_fraction >= a.broken_fraction, "{a:?} then {b:?}");
        assert!(b.whole_grains <= a.whole_grains, "{a:?} then {b:?}");
        assert!(b.loose_particles >= a.loose_particles, "{a:?} then {b:?}");
    }
    let last = fragments.last().unwrap();
    assert!(last.broken_fraction > 0.0, "no bond broke: {last:?}");
    // Grains in pieces are flagged: their shape measures take a grain as
    // one body.
    let in_pieces = fragments.iter().any(|f| f.whole_grains < 1.0);
    assert!(in_pieces, "no grain came apart: {last:?}");
    assert_eq!(
        report.warnings.iter().any(|w| w.contains("in pieces")),
        in_pieces
    );
    assert!(last.largest_fragment > 0.0 && last.largest_fragment <= 1.0);
    let (scene, _) = bpm::scene::read_scene(&dir.join("seed-3/scene.json")).unwrap();
    assert_eq!(scene.force_field.bond_failure, opts.bond_failure);
    assert!(dir.join("fragments.svg").is_file());
    let text = std::fs::read_to_string(dir.join("compaction.txt")).unwrap();
    assert!(text.contains("the grains' fragments against the pressure"));

    let refused = |o: CompactOptions, said: &str| {
        let e = o.validate().unwrap_err().to_string();
        assert!(e.contains(said), "{e:?} lacks {said:?}");
    };
    refused(
        CompactOptions {
            engine: CompactionEngine::Lammps { ranks: 1 },
            ..opts.clone()
        },
        "native engine only",
    );
    let mut with_moduli = opts.clone();
    with_moduli.moduli.states = 2;
    refused(with_moduli, "--moduli-states");
    refused(
        CompactOptions {
            bond_failure: Some(BondFailure::breaking(-1.0)),
            ..opts.clone()
        },
        "eps_c = -1",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Unloading after the compression: the box expands back to its jammed
/// size and the packing rests. Elastic grains recover their volume;
/// grains whose bonds yielded (eps_p = 0.02) keep most of their
/// compression. The table shows it.
#[test]
fn yielding_grains_keep_a_strain_after_unloading() {
    use bpm::kernels::BondFailure;
    use bpm::studies::compaction::{run_compaction, CompactOptions};
    let residual = |failure: Option<BondFailure>, name: &str| {
        let dir = common::scratch_dir(name);
        let mut opts = CompactOptions {
            bond_failure: failure,
            ..tiny_study(None, 5_000)
        };
        opts.protocol.unload_rate = 1e-4;
        let report = run_compaction(&opts, &plain(), None, &dir, "test", &mut |_| {}).unwrap();
        let run = &report.runs[0];
        assert!(run.stopped.is_none(), "{:?}", run.stopped);
        let stages: Vec<&str> = run.states.iter().map(|s| s.stage.as_str()).collect();
        assert!(stages.contains(&"unload") && stages.last() == Some(&"rest"));
        let loaded = run
            .states
            .iter()
            .rev()
            .find(|s| s.stage.starts_with("compress"))
            .unwrap();
        let rested = run.states.last().unwrap();
        // Back at the jammed box: looser than the compressed packing.
        assert!(rested.packing.phi_mc < loaded.packing.phi_mc);
        let text = std::fs::read_to_string(dir.join("compaction.txt")).unwrap();
        assert!(text.contains("# unloaded: the box expanded back"), "{text}");
        let _ = std::fs::remove_dir_all(&dir);
        (loaded.packing.eps_v_mean, rested.packing.eps_v_mean)
    };
    let plastic = BondFailure {
        critical_strain: 1.0,
        breaks: false,
        smooth: false,
        plastic_strain: Some(0.02),
        normalize: false,
    };
    let (elastic_loaded, elastic_left) = residual(None, "unload-elastic");
    let (plastic_loaded, plastic_left) = residual(Some(plastic), "unload-plastic");
    // eps_V = 1 - V / V_0: positive when compressed.
    let said = format!(
        "eps_V loaded, left: elastic {elastic_loaded:.5}, {elastic_left:.5}; \
         plastic {plastic_loaded:.5}, {plastic_left:.5}"
    );
    assert!(elastic_loaded > 0.01 && plastic_loaded > 0.01, "{said}");
    assert!(elastic_left.abs() < 0.05 * elastic_loaded, "{said}");
    assert!(plastic_left > 0.5 * plastic_loaded, "{said}");
}
