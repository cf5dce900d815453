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
    let cases: [(&[&str], &str); 17] = [
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
        (
            &["crush", "--no-break", "-o", x],
            "--no-break without --plastic-strain: the bonds would neither break nor yield",
        ),
        (
            &["crush", "--critical-strain", "0.05", "--plastic-strain", "0.06", "-o", x],
            "the plastic strain eps_p = 0.06 must be below the critical strain eps_c = 0.05: a bond would break before it yields",
        ),
        (
            &["compact", "--plastic-strain", "0.05", "-o", x],
            "bonds that break need --critical-strain (or give --no-break)",
        ),
        (
            &["compact", "--critical-strain", "0.1", "--engine", "lammps", "-o", x],
            "--critical-strain, --plastic-strain run in the native engine only: the harness's LAMMPS runs do not record broken bonds (use --engine native)",
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
            "--dem-spheres",
            "12",
            "--dem-steps",
            "20",
            "--dem-replicas",
            "1,2",
            "--liggghts-steps",
            "100",
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
        "plugin loop time / upstream's, solid squeezed 1%",
        "DEM bed, Hertz: LIGGGHTS time / native's",
        "DEM bed: standard closure's cost / native Hertz's",
        "DEM bed: advanced closure's cost / native Hertz's",
        "periodic DEM bed: sizes timed on 1 and 2 threads, 12 to 96 spheres",
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
    // The periodic DEM bed and its copies: Hertz and the closure, 1 and 2
    // threads, spheres in contact.
    let bed = &report["dem_bed"];
    assert!(bed["contacts_per_sphere"].as_f64().unwrap() > 1.0, "{bed}");
    for law in ["hertz", "closure"] {
        let cases = bed[law].as_array().unwrap();
        assert_eq!(cases.len(), 4, "2 sizes x 2 thread counts: {bed}");
        assert!(cases
            .iter()
            .all(|c| c["ns_per_particle_step"].as_f64().unwrap() > 0.0
                && !c["name"].as_str().unwrap().contains("stopped")));
        assert_eq!(cases[2]["particles"], 96);
    }
    assert!(
        stdout.lines().any(|l| l.starts_with("DEM bed ")
            && l.contains(" 96 spheres ")
            && l.contains("closure cost / Hertz's")),
        "{stdout}"
    );
    // The LIGGGHTS case where LIGGGHTS is installed, a note where not.
    assert_eq!(report["liggghts_steps"], 100);
    if bpm::studies::bench::LiggghtsInstall::locate().is_ok() {
        let speeds = report["liggghts"]["speeds"].as_array().unwrap();
        assert_eq!(speeds.len(), 2, "{}", report["liggghts"]);
        assert!(speeds
            .iter()
            .all(|s| s["liggghts_over_native"].as_f64().unwrap() > 0.0));
    } else {
        assert!(report["liggghts"].is_null());
        assert!(stdout.contains("LIGGGHTS case skipped"), "{stdout}");
    }
}

/// A LIGGGHTS sphere file (header as LIGGGHTS writes it), spheres of
/// diameter about 0.02 (SI metres), atom ids not 1..N.
const LIGGGHTS_SPHERES: &str = "LIGGGHTS data file

 3  atoms

 1  atom types

 -0.0101  0.1701 xlo xhi
 -0.0101  0.1701 ylo yhi
 -0.0101  0.4101 zlo zhi

Atoms

4 1 0.0192 2500 0.0281955 0.15621 0.0747432
9 1 0.0216 2500 0.0872805 0.139893 0.04861
2 1 0.0210 2500 0.137187 0.0207118 0.104042
";

const MATERIAL: &str = r#"{"youngs_modulus": 5e6, "poisson_ratio": 0.25, "restitution": 0.5, "tangential_damping": 1, "sliding_friction": 0.3}"#;

/// `bpm import` of small spheres: the skin follows their size (and says
/// so) unless `--skin` is given; `--gravity` sets the scene's gravity; bad
/// values of either are refused with the option named, never a panic.
#[test]
fn import_sizes_the_skin_to_the_spheres_and_takes_skin_and_gravity() {
    let data = tmp("spheres.data");
    let scene = tmp("spheres.json");
    std::fs::write(&data, LIGGGHTS_SPHERES).unwrap();
    let (d, s) = (data.to_str().unwrap(), scene.to_str().unwrap());
    let import = |extra: &[&str]| {
        let mut args = vec!["import", d, "--granular", MATERIAL, "-o", s];
        args.extend_from_slice(extra);
        bpm().args(&args).output().unwrap()
    };
    let read = || bpm::scene::read_scene_unvalidated(&scene).unwrap();
    // Mean diameter 0.0206: skin 0.15 x 0.0206 = 0.00309.
    let out = import(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed = String::from_utf8_lossy(&out.stdout);
    assert!(
        printed.contains(
            "skin set to 0.00309 (0.15 of the mean diameter 0.0206); override with --skin"
        ),
        "{printed}"
    );
    let imported = read();
    assert_eq!(imported.force_field.skin, 0.00309);
    assert_eq!(imported.force_field.gravity, None);
    assert_eq!(imported.particles.ids.as_deref(), Some(&[2, 4, 9][..]));
    // --skin overrides, silently; --gravity takes three numbers.
    let out = import(&["--skin", "0.005", "--gravity", "0", "0", "-9.81"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!String::from_utf8_lossy(&out.stdout).contains("skin set"));
    let imported = read();
    assert_eq!(imported.force_field.skin, 0.005);
    assert_eq!(imported.force_field.gravity, Some([0.0, 0.0, -9.81]));
    for (bad, named) in [
        (&["--skin", "0"][..], "--skin"),
        (&["--skin", "-1"], "--skin"),
        (&["--skin", "inf"], "--skin"),
        (&["--gravity", "0", "nan", "1"], "--gravity"),
        (&["--gravity", "0", "1"], "--gravity"),
        (&["--gravity", "0", "x", "1"], "--gravity"),
    ] {
        let out = import(bad);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{bad:?} accepted");
        assert!(err.contains(named), "{bad:?}: {err}");
        assert!(!err.contains("panicked"), "{bad:?}: {err}");
    }
    // The rule: 0.15 x the mean diameter to 3 digits, outside [0.5, 2] only.
    use bpm::scene::cli::skin_for_diameter;
    for inside in [0.5, 1.0, 2.0] {
        assert_eq!(skin_for_diameter(inside), None);
    }
    assert_eq!(skin_for_diameter(3.0), Some(0.45));
    assert_eq!(skin_for_diameter(0.0123456), Some(0.00185));
    assert_eq!(skin_for_diameter(12345.0), Some(1850.0));
    // The help says how ids, the skin and gravity are handled.
    let help = bpm().args(["import", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    for words in [
        "--skin",
        "--gravity <GX> <GY> <GZ>",
        "particles.ids",
        "LIGGGHTS",
        "Angles",
    ] {
        assert!(help.contains(words), "`{words}` missing from:\n{help}");
    }
}

/// A bonded data file with atom ids 3, 8, 20: `bpm import` keeps them, and
/// a run on either engine writes them in its dump (the LAMMPS harness's
/// own data file numbers the atoms 1..N); the native final scene keeps
/// them too.
#[test]
fn imported_atom_ids_survive_a_run_on_either_engine() {
    let data = tmp("ids.data");
    let scene = tmp("ids.json");
    std::fs::write(
        &data,
        "LAMMPS data file\n\n3 atoms\n2 bonds\n1 atom types\n1 bond types\n\n0 8 xlo xhi\n0 8 ylo yhi\n0 8 zlo zhi\n\nAtoms # bond\n\n20 1 1 3.9 3 3\n3 1 1 3 3 3\n8 1 1 3 3.95 3\n\nBonds\n\n1 1 3 20\n2 1 8 3\n",
    )
    .unwrap();
    let out = bpm()
        .arg("import")
        .arg(&data)
        .arg("-o")
        .arg(&scene)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&scene).unwrap()).unwrap();
    assert_eq!(doc["particles"]["ids"], serde_json::json!([3, 8, 20]));
    doc["stages"] = serde_json::json!([{"name": "hold", "steps": 20, "dt": 0.01}]);
    std::fs::write(&scene, doc.to_string()).unwrap();
    for engine in ["native", "lammps"] {
        let dump = tmp(&format!("ids-{engine}.dump"));
        let fin = tmp(&format!("ids-{engine}-final.json"));
        let work = tmp(&format!("ids-{engine}-work"));
        let mut args: Vec<std::ffi::OsString> = vec![
            "run".into(),
            scene.clone().into(),
            "-o".into(),
            tmp(&format!("ids-{engine}.out.json")).into(),
            "--engine".into(),
            engine.into(),
            "--dump".into(),
            dump.clone().into(),
            "--dump-every".into(),
            "10".into(),
            "--workdir".into(),
            work.clone().into(),
        ];
        if engine == "native" {
            args.extend(["--final-scene".into(), fin.clone().into()]);
        }
        let out = bpm().args(&args).output().unwrap();
        assert!(
            out.status.success(),
            "{engine}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let frames = bpm::scene::trajectory::read_dump(&dump).unwrap();
        assert_eq!(frames.len(), 3, "{engine}");
        // Atom 20, the last particle, starts at x = 3.9.
        assert_eq!(frames[0].x[2], [3.9, 3.0, 3.0], "{engine}");
        for f in &frames {
            assert_eq!(
                f.id.as_deref(),
                Some(&[3, 8, 20][..]),
                "{engine} step {}",
                f.step
            );
        }
        if engine == "native" {
            let fin = bpm::scene::read_scene_unvalidated(&fin).unwrap();
            assert_eq!(fin.particles.ids.as_deref(), Some(&[3, 8, 20][..]));
        } else {
            let run_data = std::fs::read_dir(&work)
                .unwrap()
                .map(|e| e.unwrap().path())
                .find(|p| p.extension().is_some_and(|e| e == "data"))
                .expect("the harness writes its data file");
            let text = std::fs::read_to_string(run_data).unwrap();
            assert!(text.contains("\nBonds\n\n1 1 1 3\n2 1 2 1\n"), "{text}");
        }
    }
}

#[test]
fn stability_and_large_strain_replot_their_committed_reports_and_refuse_another() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for (command, folder, json, svg) in [
        ("stability", "stability", "stability.json", "stability.svg"),
        (
            "large-strain",
            "large-strain",
            "large_strain.json",
            "large_strain.svg",
        ),
    ] {
        let out = tmp(&format!("replot-{command}"));
        let committed = root.join("results").join(folder).join(json);
        let st = bpm()
            .args([command, "--from"])
            .arg(&committed)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&st.stderr);
        assert!(st.status.success(), "{command}: {err}");
        assert!(out.join(svg).exists(), "{command}: no {svg}");
        // The report is written again from what was read; only options
        // added since (at their defaults) may be new.
        let before: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&committed).unwrap()).unwrap();
        let after: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join(json)).unwrap()).unwrap();
        assert_eq!(before["command"], after["command"], "{command}");
        assert_eq!(before["program"], after["program"], "{command}");

        // Without -o the replot writes beside the JSON it read, not into
        // the study's default folder (which may hold another report).
        let beside = tmp(&format!("replot-{command}-beside"));
        std::fs::create_dir_all(&beside).unwrap();
        std::fs::copy(&committed, beside.join(json)).unwrap();
        let st = bpm()
            .args([command, "--from"])
            .arg(beside.join(json))
            .current_dir(&beside)
            .output()
            .unwrap();
        assert!(
            st.status.success(),
            "{command}: {}",
            String::from_utf8_lossy(&st.stderr)
        );
        assert!(
            beside.join(svg).exists(),
            "{command}: no {svg} beside the JSON"
        );
        assert!(
            !beside.join("results").exists(),
            "{command}: wrote a default folder"
        );

        // A report whose options are out of range (edited by hand) is
        // refused with the option named, not drawn.
        let mut edited: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&committed).unwrap()).unwrap();
        edited["options"]["a_b"] = serde_json::json!([]);
        std::fs::write(beside.join(json), edited.to_string()).unwrap();
        let st = bpm()
            .args([command, "--from"])
            .arg(beside.join(json))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&st.stderr);
        assert_eq!(st.status.code(), Some(1), "{command}: {err}");
        assert!(
            err.contains("--a-b") && !err.contains("panicked"),
            "{command}: {err}"
        );

        // Another study's report is refused, naming the file.
        let other = root.join("results/accuracy/accuracy.json");
        let st = bpm()
            .args([command, "--from"])
            .arg(&other)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&st.stderr);
        assert_eq!(st.status.code(), Some(1), "{command}: {err}");
        assert!(
            err.contains("accuracy.json") && err.contains(&format!("not a valid {json}")),
            "{command}: {err}"
        );
        assert!(!err.contains("panicked"), "{command}: {err}");
    }
}
