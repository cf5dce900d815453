//! Checkpoints: a run stopped at any step and resumed (once or several
//! times) ends bit for bit as the run never stopped, for the bonded model
//! (force-field change, reference reset, deformation, barostat, tether,
//! walls) and for DEM spheres (contact and wall histories, the closure,
//! Lees-Edwards shear); checkpoints of another run are refused.

mod common;

use bpm::engine::{Barostat, Deformation, System, Tether};
use bpm::scene::builders::bulk::{build_bulk, BulkParams};
use bpm::scene::checkpoint::{CheckpointError, RunCheckpoint};
use bpm::scene::{
    build_system, run_scene, CheckpointEvery, CheckpointOptions, ForceField, RunError, RunOptions,
    Scene, StageOutput, StageSpec, VelocityInit,
};
use bpm::verify::scenes::with_release;
use bpm::verify::{dem_trajectory, DemLoading};
use std::path::{Path, PathBuf};

/// A small bonded solid through every kind of stage the bonded model has.
fn bonded_scene() -> Scene {
    let (mut scene, _) = build_bulk(&BulkParams::shortened(5.0, 4, 0.0), 1, false).unwrap();
    scene.force_field = ForceField::paper(0.5);
    let mut heat = StageSpec::hold("heat", 300, 0.05);
    heat.set_velocities = Some(VelocityInit { rms_speed: 0.02 });
    heat.record.every = 25;
    let mut compress = StageSpec::hold("compress", 400, 0.05);
    compress.deformation = Some(Deformation::Isotropic {
        true_strain_rate: -2e-4,
    });
    compress.record.every = 20;
    compress.record.positions_every = 100;
    let mut reset = StageSpec::hold("reset", 200, 0.05);
    reset.reset_reference = true;
    reset.force_field = Some(ForceField::paper(1.0));
    reset.tether = Some(Tether {
        grain: None,
        anchor: None,
        dims: [true; 3],
        stiffness: 5.0,
    });
    reset.record.every = 10;
    let mut jam = StageSpec::hold("barostat", 300, 0.05);
    jam.barostat = Some(Barostat {
        target_pressure: 0.01,
        gain: 0.1,
    });
    jam.viscous = 0.1;
    jam.record.every = 30;
    scene.stages = vec![heat, compress, reset, jam];
    scene
}

/// A grain squeezed between two closing harmonic walls in a closed box,
/// tethered: its pair list follows rigid motion (re-anchoring).
fn walled_scene() -> Scene {
    bpm::verify::grain_squeeze(2.0, 3, 0.5, 5e-3, 600).unwrap()
}

/// DEM spheres between granular walls, with the standard closure, the
/// walls turning back in a second stage.
fn dem_walls_scene() -> Scene {
    let mut scene = with_release(dem_trajectory(7, true, DemLoading::Walls, 800));
    scene.force_field.multicontact = Some(bpm::engine::MultiContact::standard(1.0));
    if let Some(ff) = &mut scene.stages[1].force_field {
        ff.multicontact = scene.force_field.multicontact;
    }
    scene
}

fn options(dir: &Path, resume: bool, stop_at: Option<u64>, threads: usize) -> RunOptions {
    let mut checkpoint =
        CheckpointOptions::new(dir.join("run.ck"), CheckpointEvery::Steps(97), resume);
    checkpoint.stop_at_step = stop_at;
    RunOptions {
        checkpoint: Some(checkpoint),
        ..RunOptions::quiet(threads)
    }
}

fn bits(rows: &[Vec<f64>]) -> Vec<Vec<u64>> {
    rows.iter()
        .map(|r| r.iter().map(|v| v.to_bits()).collect())
        .collect()
}

fn assert_same_stages(a: &[StageOutput], b: &[StageOutput]) {
    assert_eq!(a.len(), b.len(), "stage count");
    for (s, t) in a.iter().zip(b) {
        assert_eq!(s.name, t.name);
        assert_eq!(bits(&s.rows), bits(&t.rows), "rows of `{}`", s.name);
        assert_eq!(s.checkpoints.len(), t.checkpoints.len());
        for (p, q) in s.checkpoints.iter().zip(&t.checkpoints) {
            assert_eq!(p.step, q.step);
            assert_eq!(p.simbox, q.simbox);
            assert_eq!(p.positions, q.positions, "positions of `{}`", s.name);
            assert_eq!(p.images, q.images);
        }
        assert_eq!(s.neighbour_builds, t.neighbour_builds, "`{}`", s.name);
        assert_eq!(s.stopped_at, t.stopped_at);
    }
}

fn assert_same_state(a: &System, b: &System) {
    assert_eq!(a.step, b.step);
    assert_eq!(a.time.to_bits(), b.time.to_bits());
    assert_eq!(a.simbox, b.simbox);
    let (p, q) = (&a.particles, &b.particles);
    assert_eq!(p.x, q.x, "positions");
    assert_eq!(p.v, q.v, "velocities");
    assert_eq!(p.f, q.f, "forces");
    assert_eq!(p.image, q.image);
    assert_eq!(
        p.rotation.as_ref().map(|r| (&r.omega, &r.torque)),
        q.rotation.as_ref().map(|r| (&r.omega, &r.torque)),
        "spins"
    );
    assert_eq!(
        a.save_state().unwrap().model_state,
        b.save_state().unwrap().model_state,
        "model state (histories, reference lengths)"
    );
}

/// Runs `scene` straight through, then again stopped after each of
/// `stops` (global steps) and resumed from the checkpoint each time;
/// both must end identical.
fn assert_resumes_exactly(name: &str, scene: &Scene, stops: &[u64], threads: usize) {
    let dir = common::scratch_dir(name);
    let mut straight = build_system(scene, threads);
    let (expected, error) = run_scene(&mut straight, scene, &RunOptions::quiet(threads));
    assert!(error.is_none(), "{error:?}");
    for (i, &stop) in stops.iter().enumerate() {
        let mut sys = build_system(scene, threads);
        let (_, error) = run_scene(&mut sys, scene, &options(&dir, i > 0, Some(stop), threads));
        match error {
            Some(RunError::Interrupted { step, .. }) => assert_eq!(step, stop),
            other => panic!("stop at {stop}: {other:?}"),
        }
    }
    let mut resumed = build_system(scene, threads);
    let (stages, error) = run_scene(&mut resumed, scene, &options(&dir, true, None, threads));
    assert!(error.is_none(), "{error:?}");
    assert_same_stages(&expected, &stages);
    assert_same_state(&straight, &resumed);
    // The final checkpoint holds the finished run: resuming it again
    // gives the same stages and state at once.
    let mut again = build_system(scene, threads);
    let (stages, error) = run_scene(&mut again, scene, &options(&dir, true, None, threads));
    assert!(error.is_none(), "{error:?}");
    assert_same_stages(&expected, &stages);
    assert_same_state(&straight, &again);
}

#[test]
fn a_bonded_run_resumed_at_any_step_ends_bit_for_bit_as_without_stopping() {
    // Inside a stage, at a stage's last step (300) and first (301), and
    // between checkpoints of the schedule.
    let scene = bonded_scene();
    assert_resumes_exactly("ck-bonded", &scene, &[1, 300, 301, 555, 1013], 1);
    assert_resumes_exactly("ck-bonded-2", &scene, &[777], 2);
}

/// The small solid pulled apart while its bonds yield at 1% and break at
/// 3% strain (bonds leave the arrays and broken pairs become contacts
/// between checkpoints), then held with elastic bonds.
fn failing_scene() -> Scene {
    let (mut scene, _) = build_bulk(&BulkParams::shortened(5.0, 4, 0.0), 1, false).unwrap();
    scene.force_field = ForceField::paper(-0.5);
    scene.force_field.bond_failure = Some(bpm::kernels::BondFailure {
        plastic_strain: Some(0.01),
        ..bpm::kernels::BondFailure::breaking(0.03)
    });
    let mut pull = StageSpec::hold("pull", 700, 0.05);
    pull.deformation = Some(Deformation::Isotropic {
        true_strain_rate: 1e-3,
    });
    pull.record.every = 20;
    // The second stage's field has no failure rule: the bonds left keep
    // their rest lengths as reference lengths, and a checkpoint must still
    // carry the bonds that broke.
    let mut settle = StageSpec::hold("settle", 300, 0.05);
    settle.viscous = 0.1;
    settle.record.every = 20;
    settle.force_field = Some(ForceField::paper(-0.5));
    scene.stages = vec![pull, settle];
    scene
}

#[test]
fn a_run_whose_bonds_break_and_yield_resumes_exactly() {
    let scene = failing_scene();
    let mut sys = build_system(&scene, 1);
    let (_, error) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
    assert!(error.is_none(), "{error:?}");
    let model = sys.model_as::<bpm::engine::BpmModel>().unwrap();
    let broken = model.broken_bonds().len();
    assert!(broken > 100, "{broken} broken");
    // At the end of the pull, many bonds had yielded.
    let mut pulled = scene.clone();
    pulled.stages.truncate(1);
    let mut sys = build_system(&pulled, 1);
    let (_, error) = run_scene(&mut sys, &pulled, &RunOptions::quiet(1));
    assert!(error.is_none(), "{error:?}");
    let model = sys.model_as::<bpm::engine::BpmModel>().unwrap();
    let yielded = model
        .plastic_strains()
        .iter()
        .filter(|&&e| e != 0.0)
        .count();
    assert!(yielded > 100, "{yielded} yielded");
    assert_resumes_exactly("ck-failing", &scene, &[250, 555, 700, 701], 1);
    assert_resumes_exactly("ck-failing-2", &scene, &[333], 2);
}

#[test]
fn a_run_whose_every_bond_broke_resumes_exactly() {
    // Two bonded particles flying apart: the bond breaks early on, and
    // the checkpoints after it hold no bond.
    let scene: Scene = serde_json::from_value(serde_json::json!({
        "seed": 1,
        "box": {"lo": [0, 0, 0], "lengths": [12, 12, 12], "periodic": [true, true, true]},
        "particles": {"positions": [[5, 6, 6], [6, 6, 6]], "velocities": [[-0.2, 0, 0], [0.2, 0, 0]]},
        "bonds": {"pairs": [[0, 1]]},
        "force_field": {
            "bond": {"k": 1, "a": -0.5, "gamma": 0},
            "pair": {"k": 1, "d": 1, "a": 50, "gamma": 0},
            "bond_failure": {"critical_strain": 0.1}
        },
        "stages": [{"name": "fly", "steps": 400, "dt": 0.01, "record": {"every": 10}}]
    }))
    .unwrap();
    bpm::scene::validate(&scene).unwrap();
    assert_resumes_exactly("ck-all-broken", &scene, &[200, 350], 1);
}

#[test]
fn a_walled_bonded_run_resumes_exactly() {
    assert_resumes_exactly("ck-walled", &walled_scene(), &[123, 321], 1);
}

#[test]
fn dem_spheres_resume_with_their_contact_and_wall_histories() {
    // Stage one has 400 steps; the walls turn back at 401.
    let scene = dem_walls_scene();
    assert_resumes_exactly("ck-dem-walls", &scene, &[150, 400, 401, 650], 1);
}

#[test]
fn lees_edwards_shear_resumes_exactly_across_the_tilt_flip() {
    let scene = dem_trajectory(7, true, DemLoading::LeesEdwards, 1000);
    assert_resumes_exactly("ck-dem-le", &scene, &[420, 800], 1);
}

/// A checkpoint of `scene` stopped at step 100, in `dir`.
fn stopped_checkpoint(dir: &Path, scene: &Scene) -> PathBuf {
    let mut sys = build_system(scene, 1);
    let (_, error) = run_scene(&mut sys, scene, &options(dir, false, Some(100), 1));
    assert!(matches!(error, Some(RunError::Interrupted { .. })));
    dir.join("run.ck")
}

fn resume_error(dir: &Path, scene: &Scene, threads: usize) -> String {
    let mut sys = build_system(scene, threads);
    let (_, error) = run_scene(&mut sys, scene, &options(dir, true, None, threads));
    error.expect("refused").to_string()
}

#[test]
fn a_checkpoint_of_another_run_or_a_damaged_one_is_refused() {
    let dir = common::scratch_dir("ck-refused");
    let scene = walled_scene();
    let path = stopped_checkpoint(&dir, &scene);
    let good = std::fs::read(&path).unwrap();

    let mut other = scene.clone();
    other.force_field.bond.k *= 1.0 + 1e-12;
    let message = resume_error(&dir, &other, 1);
    assert!(message.contains("another scene"), "{message}");

    let message = resume_error(&dir, &scene, 2);
    assert!(message.contains("--threads 1"), "{message}");

    std::fs::write(&path, &good[..good.len() / 2]).unwrap();
    let message = resume_error(&dir, &scene, 1);
    assert!(message.contains("damaged or truncated"), "{message}");

    std::fs::write(&path, b"{\"not\": \"a checkpoint\"}").unwrap();
    let message = resume_error(&dir, &scene, 1);
    assert!(message.contains("not a bpm checkpoint"), "{message}");

    // Another version of the program: its header line names it.
    let format = bpm::scene::checkpoint::CHECKPOINT_FORMAT;
    let header = format!("bpm checkpoint format {format} version {}\n", bpm::VERSION);
    assert!(good.starts_with(header.as_bytes()), "the header line");
    let mut other = format!("bpm checkpoint format {format} version 0.0.1\n").into_bytes();
    other.extend_from_slice(&good[header.len()..]);
    std::fs::write(&path, other).unwrap();
    let message = resume_error(&dir, &scene, 1);
    assert!(message.contains("written by bpm 0.0.1"), "{message}");

    std::fs::remove_file(&path).unwrap();
    match RunCheckpoint::read(&path, &scene, 1) {
        Err(CheckpointError::Io { .. }) => {}
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_resumed_run_must_stream_to_the_same_files() {
    let dir = common::scratch_dir("ck-files");
    let scene = walled_scene();
    stopped_checkpoint(&dir, &scene);
    let mut opts = options(&dir, true, None, 1);
    opts.files.thermo = Some(dir.join("rows.txt"));
    let mut sys = build_system(&scene, 1);
    let (_, error) = run_scene(&mut sys, &scene, &opts);
    let message = error.expect("refused").to_string();
    assert!(
        message.contains("streamed thermo rows to no file"),
        "{message}"
    );
}

/// `bpm run` of a 626-particle solid for 60,000 steps (a few seconds),
/// streaming rows and a dump; `extra` arguments appended.
fn bpm_run(dir: &Path, name: &str, extra: &[&str]) -> std::process::Command {
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_bpm"));
    command
        .current_dir(dir)
        .args(["run", "scene.json", "-o"])
        .arg(format!("{name}.json"))
        .arg("--thermo")
        .arg(format!("{name}.thermo"))
        .arg("--dump")
        .arg(format!("{name}.dump"))
        .args(["--dump-every", "5000", "--final-scene"])
        .arg(format!("{name}-final.json"))
        .args(extra);
    command
}

fn long_run_dir(name: &str) -> PathBuf {
    let dir = common::scratch_dir(name);
    let (mut scene, _) = build_bulk(&BulkParams::shortened(8.0, 2, 0.5), 1, false).unwrap();
    let mut relax = StageSpec::hold("relax", 60_000, 0.05);
    relax.set_velocities = Some(VelocityInit { rms_speed: 0.02 });
    relax.record.every = 100;
    scene.stages = vec![relax];
    bpm::scene::write_scene(&dir.join("scene.json"), &scene).unwrap();
    let straight = bpm_run(&dir, "straight", &[]).output().unwrap();
    assert!(straight.status.success(), "{straight:?}");
    dir
}

/// Starts the checkpointed run and waits for its first checkpoint.
fn start_until_checkpoint(dir: &Path, extra: &[&str]) -> std::process::Child {
    let checkpoint = dir.join("run.ck");
    let _ = std::fs::remove_file(&checkpoint);
    let mut args = vec!["--checkpoint", "run.ck", "--checkpoint-every", "3000"];
    args.extend(extra);
    let mut child = bpm_run(dir, "piece", &args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !checkpoint.exists() {
        assert!(start.elapsed().as_secs() < 60, "no checkpoint written");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    assert!(
        child.try_wait().unwrap().is_none(),
        "the run ended before it could be stopped: lengthen it"
    );
    child
}

fn assert_same_files(dir: &Path) {
    for (a, b) in [
        ("straight.thermo", "piece.thermo"),
        ("straight.dump", "piece.dump"),
        ("straight-final.json", "piece-final.json"),
    ] {
        let (a, b) = (dir.join(a), dir.join(b));
        assert!(
            std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
            "{} and {} differ",
            a.display(),
            b.display()
        );
    }
}

#[test]
fn bpm_run_killed_outright_resumes_to_the_same_files() {
    let dir = long_run_dir("ck-cli-kill");
    let mut child = start_until_checkpoint(&dir, &[]);
    std::thread::sleep(std::time::Duration::from_millis(150));
    child.kill().unwrap();
    child.wait().unwrap();
    let resumed = bpm_run(
        &dir,
        "piece",
        &[
            "--checkpoint",
            "run.ck",
            "--checkpoint-every",
            "3000",
            "--resume",
        ],
    )
    .output()
    .unwrap();
    assert!(resumed.status.success(), "{resumed:?}");
    assert_same_files(&dir);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("piece.json")).unwrap()).unwrap();
    let resumed_at = report["resumed_at"][0].as_u64().expect("resumed_at");
    assert!(resumed_at > 0 && resumed_at % 3000 == 0, "{resumed_at}");
}

#[test]
fn bpm_run_stopped_by_a_signal_writes_a_checkpoint_and_resumes_exactly() {
    let dir = long_run_dir("ck-cli-signal");
    let child = start_until_checkpoint(&dir, &["--progress-log", "progress.jsonl"]);
    std::thread::sleep(std::time::Duration::from_millis(100));
    let signal = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(signal.success());
    let stopped = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&stopped.stderr);
    assert!(!stopped.status.success());
    assert!(stderr.contains("run.ck continues the run"), "{stderr}");
    // The checkpoint is of the step where the signal stopped the run, not
    // of the schedule's last one.
    let step: u64 = stderr
        .split("stopped at step ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .expect("the step in the message");
    let resumed = bpm_run(
        &dir,
        "piece",
        &[
            "--checkpoint",
            "run.ck",
            "--resume",
            "--progress-log",
            "progress.jsonl",
        ],
    )
    .output()
    .unwrap();
    assert!(resumed.status.success(), "{resumed:?}");
    assert_same_files(&dir);
    let log = std::fs::read_to_string(dir.join("progress.jsonl")).unwrap();
    let lines: Vec<serde_json::Value> = log
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let events: Vec<(&str, u64)> = lines
        .iter()
        .map(|l| (l["event"].as_str().unwrap(), l["done"].as_u64().unwrap()))
        .collect();
    assert_eq!(
        events.first(),
        Some(&("start", 0)),
        "the first session starts at 0: {events:?}"
    );
    assert!(
        events.contains(&("start", step)),
        "the second starts where the first stopped: {events:?}"
    );
    assert_eq!(events.last(), Some(&("finish", 60_000)), "{events:?}");
}
