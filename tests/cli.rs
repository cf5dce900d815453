//! The `bpm` command line: it builds, runs, and fails cleanly on bad input.

mod common;

use std::process::Command;

fn bpm() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bpm"))
}

fn tmp(name: &str) -> std::path::PathBuf {
    common::scratch_dir("cli").join(name)
}

#[test]
fn build_then_run_writes_a_report_with_seed_and_parameters() {
    let scene = tmp("bulk.json");
    let out = tmp("out.json");
    let st = bpm()
        .args([
            "build",
            "bulk",
            "--size",
            "4",
            "--seed",
            "3",
            "--time-scale",
            "0.01",
            "--steps",
            "50",
            "-o",
        ])
        .arg(&scene)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    assert!(String::from_utf8_lossy(&st.stdout).contains("bonds per particle"));
    let st = bpm()
        .arg("run")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(report["seed"], 3);
    assert_eq!(report["provenance"]["parameters"]["seed"], 3);
    assert!(report["force_field"]["bond"]["k"].is_number());
    assert_eq!(report["stages"][0]["rows"].as_array().unwrap().len(), 51);
}

#[test]
fn a_bad_scene_fails_with_a_message_naming_the_field_and_no_panic() {
    let scene = tmp("bad.json");
    std::fs::write(
        &scene,
        r#"{"seed":1,"box":{"lo":[0,0,0],"lengths":[6,6,6],"periodic":[true,true,true]},
            "particles":{"positions":[[1,1,1],[2,1,1]]},"bonds":{"pairs":[[0,1]]},
            "force_field":{"bond":{"k":-1,"a":0,"gamma":1}},"stages":[{"name":"x","steps":1}]}"#,
    )
    .unwrap();
    let st = bpm()
        .arg("run")
        .arg(&scene)
        .arg("-o")
        .arg(tmp("never.json"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&st.stderr);
    assert_eq!(st.status.code(), Some(1));
    assert!(err.contains("force_field.bond.k"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn a_missing_file_and_bad_options_fail_cleanly() {
    let st = bpm()
        .args(["run", "/nonexistent/scene.json", "-o", "/tmp/x.json"])
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&st.stderr).contains("/nonexistent/scene.json"));
    let st = bpm()
        .args(["build", "bulk", "--size", "-3", "-o", "/tmp/x.json"])
        .output()
        .unwrap();
    assert!(!st.status.success());
    assert!(!String::from_utf8_lossy(&st.stderr).contains("panicked"));
}

#[test]
fn compare_compaction_refuses_folders_without_a_report_and_mismatched_labels() {
    let dir = tmp("compare");
    std::fs::create_dir_all(&dir).unwrap();
    let compare = |extra: &[&str]| {
        let st = bpm()
            .args(["compare-compaction", dir.to_str().unwrap()])
            .args(extra)
            .arg("-o")
            .arg(dir.join("out"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&st.stderr).to_string();
        assert_eq!(st.status.code(), Some(1), "{err}");
        assert!(!err.contains("panicked"), "{err}");
        err
    };
    assert!(compare(&[]).contains("compaction.json"));
    std::fs::write(dir.join("compaction.json"), "{\"runs\": 3}").unwrap();
    assert!(compare(&[]).contains("not a compaction report"));
    assert!(compare(&["--labels", "a,b"]).contains("--labels"));
}

#[test]
fn each_error_is_printed_once() {
    // A missing file and a malformed scene: the cause appears once, not
    // once in the message and again from the error chain.
    let bad = tmp("truncated.json");
    std::fs::write(&bad, "{\"seed\": 1").unwrap();
    for (scene, cause) in [
        (
            std::path::PathBuf::from("/nonexistent/scene.json"),
            "os error 2",
        ),
        (bad, "EOF while parsing"),
    ] {
        let out = bpm()
            .args(["run", scene.to_str().unwrap(), "-o"])
            .arg(tmp("never.json"))
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(stderr.matches(cause).count(), 1, "{stderr}");
    }
}

#[test]
fn out_of_range_options_are_refused_with_the_argument_named() {
    let x = tmp("never.json");
    let x = x.to_str().unwrap();
    let cases: [(&[&str], &str); 13] = [
        (&["--threads", "0", "bench"], "--threads must be at least 1"),
        (
            &["build", "bulk", "--time-scale", "0", "-o", x],
            "--time-scale must be positive, got 0",
        ),
        (
            &["build", "bulk", "--strain", "0", "-o", x],
            "--rate and --strain must be positive",
        ),
        (
            &["build", "bulk", "--a-b", "inf", "-o", x],
            "--a-b must be finite",
        ),
        (
            &["check", "--grain-radius", "1", "-o", x],
            "--grain-radius must be at least 1.5 (d), got 1",
        ),
        (
            &["check", "--a-b", "0,-1", "-o", x],
            "--a-b values must be finite and above -1 (k d), got -1",
        ),
        (
            &["calibrate", "--sizes", "4", "-o", x],
            "--sizes must be at least 5 (d), got 4",
        ),
        (
            &["calibrate", "--convergence-a-b", "-2", "-o", x],
            "a_B values must be finite and above -1 (k d), got -2",
        ),
        (
            &["run", x, "-o", x, "--dump", x, "--dump-every", "0"],
            "--dump-every must be at least 1",
        ),
        (
            &["compact", "--model", "dem", "--friction", "0.3,0", "-o", x],
            "--friction takes three values, mu_s,mu_r,mu_t; got 2",
        ),
        (
            &["compact", "--model", "dem", "--friction", "0.3,-1,0", "-o", x],
            "--friction mu_s, mu_r and mu_t must be finite and >= 0, got [0.3, -1.0, 0.0]",
        ),
        (
            &["compact", "--restitution", "0.9", "-o", x],
            "--restitution is a DEM option: add --model dem",
        ),
        (
            &["compact", "--model", "dem", "--moduli-states", "2", "-o", x],
            "--moduli-states must be 0 with --model dem: a modulus run restarts from a recorded state, which keeps positions but not the contacts' friction history",
        ),
    ];
    for (args, message) in cases {
        let out = bpm().args(args).output().unwrap();
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(stderr.trim(), format!("error: {message}"), "{args:?}");
    }
}

#[test]
fn grain_builds_exports_and_imports_through_the_command_line() {
    let scene = tmp("grain.json");
    let data = tmp("grain.data");
    let again = tmp("grain-again.json");
    let run = |args: &[&str]| {
        let out = bpm().args(args).output().unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    let s = scene.to_str().unwrap();
    let d = data.to_str().unwrap();
    let a = again.to_str().unwrap();
    let printed = run(&[
        "build",
        "grain",
        "--kind",
        "rough",
        "--radius",
        "2.5",
        "--time-scale",
        "0.05",
        "-o",
        s,
    ]);
    assert!(printed.contains("roughness"), "{printed}");
    run(&["export", s, "-o", d]);
    run(&["import", d, "--boundary", "f", "f", "f", "-o", a]);
    let (first, second) = (
        bpm::scene::read_scene_unvalidated(&scene).unwrap(),
        bpm::scene::read_scene_unvalidated(&again).unwrap(),
    );
    assert_eq!(first.particles.positions, second.particles.positions);
    assert_eq!(first.bonds.pairs, second.bonds.pairs);
    // A malformed file: exit 1, the line named.
    std::fs::write(&data, "title\n\n2 atoms\n0 1 xlo xhi\n").unwrap();
    let out = bpm().args(["import", d, "-o", a]).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("ylo yhi"), "{err}");
}

/// `bpm bench` on a small solid and a small packing: every section runs,
/// ends with the goals table, and the JSON holds the cases, the Debian
/// LAMMPS timings, the compaction workload and the goals with their
/// verdicts.
#[test]
fn bench_prints_every_goal_and_writes_them_as_json() {
    let out = tmp("bench/bench.json");
    let st = bpm()
        .args([
            "bench",
            "--size",
            "5",
            "--steps",
            "20",
            "--replicas",
            "1,2",
            "--packing-grains",
            "13",
            "--packing-radius",
            "1.5",
            "--packing-steps",
            "20",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&st.stdout);
    assert!(
        st.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&st.stderr)
    );
    for figure in [
        "native speed-up over upstream LAMMPS",
        "native bond pass against Debian bond_style harmonic",
        "plugin loop time / upstream",
        "plugin bond time / Debian bond_style harmonic",
        "sizes timed on 1 and 2 threads",
        "packing: native speed-up over upstream LAMMPS",
        "packing: compaction stages",
        "packing: 2-thread speed-up",
    ] {
        assert!(
            stdout.contains(&format!("goal: {figure}")),
            "{figure}: {stdout}"
        );
    }
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(
        report["cases"].as_array().unwrap().len(),
        8,
        "2 sizes x 2 a_B x 2 thread counts"
    );
    let goals = report["goals"].as_array().unwrap();
    assert!(goals.len() >= 6);
    assert!(goals.iter().all(|g| g["goal"].is_string()));
    // lmp-bpm is built with bpm, so Debian's LAMMPS is always measured.
    let debian = report["debian"]["timings"].as_array().unwrap();
    assert_eq!(debian.len(), 7);
    assert!(debian.iter().all(|t| t["bond_ns"].as_f64().unwrap() > 0.0));
    assert!(out.with_extension("svg").is_file());
    let packing = report["packing"]["cases"].as_array().unwrap();
    assert_eq!(packing.len(), 4, "2 a_B x 2 thread counts");
    assert!(packing
        .iter()
        .all(|c| c["ns_per_particle_step"].as_f64().unwrap() > 0.0
            && !c["name"].as_str().unwrap().contains("stopped")));
    assert_eq!(report["packing_workload"]["grains"], 13);
}
