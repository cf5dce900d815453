//! Bad input is harmless: property tests over scene JSON, LAMMPS data files
//! and the C ABI's arguments, and every numeric option of every `bpm`
//! subcommand given a non-number, find no panic, no hang and no NaN
//! accepted.

mod common;

use bpm::ffi::*;
use bpm::kernels::{BondCoeffs, BondEntry, PairCoeffs, Tally};
use bpm::scene::datafile::{read_data_file, write_data_file};
use bpm::scene::{run_scene, validate, ForceField, RunOptions, Scene};
use proptest::prelude::*;
use serde_json::{json, Value};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A small valid scene: bonds, contacts, every kind of stage driver.
fn valid_scene() -> Value {
    json!({
        "seed": 1,
        "box": {"lo": [0, 0, 0], "lengths": [6, 6, 6], "periodic": [true, true, true]},
        "particles": {"positions": [[1, 1, 1], [2, 1, 1], [1, 2, 1], [3, 3, 3], [3.9, 3, 3]]},
        "bonds": {"pairs": [[0, 1], [0, 2], [1, 2]]},
        "force_field": {"bond": {"k": 1, "a": -0.5, "gamma": 1}, "pair": {"k": 1, "d": 1, "a": 50, "gamma": 1}},
        "stages": [
            {"name": "hold", "steps": 20, "dt": 0.1, "set_velocities": {"rms_speed": 0.03}},
            {"name": "squeeze", "steps": 20, "dt": 0.1,
             "deformation": {"isotropic": {"true_strain_rate": -1e-3}},
             "record": {"every": 5}}
        ]
    })
}

/// Numbers that break careless code: zeros of both signs, subnormals, the
/// extremes of f64, negatives, huge counts.
fn awkward_number() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(json!(0)),
        Just(json!(-0.0)),
        Just(json!(-1)),
        Just(json!(1e-320)),
        Just(json!(1e300)),
        Just(json!(-1e300)),
        Just(json!(u64::MAX)),
        Just(json!(i64::MIN)),
        Just(json!(0.5)),
        Just(json!(7)),
        Just(json!("1")),
        Just(json!(null)),
        Just(json!([])),
        (-1e3..1e3f64).prop_map(|v| json!(v)),
    ]
}

/// Every path to a leaf of `v` (object keys and array indices).
fn leaves(v: &Value, path: &mut Vec<Value>, out: &mut Vec<Vec<Value>>) {
    match v {
        Value::Object(m) => {
            for (k, c) in m {
                path.push(json!(k));
                leaves(c, path, out);
                path.pop();
            }
        }
        Value::Array(a) => {
            for (i, c) in a.iter().enumerate() {
                path.push(json!(i));
                leaves(c, path, out);
                path.pop();
            }
        }
        _ => out.push(path.clone()),
    }
}

fn at<'a>(v: &'a mut Value, path: &[Value]) -> &'a mut Value {
    path.iter().fold(v, |v, k| match k {
        Value::String(s) => &mut v[s.as_str()],
        Value::Number(n) => &mut v[n.as_u64().unwrap() as usize],
        _ => unreachable!(),
    })
}

/// Runs `scene`, if it validates, on the native engine with every stage
/// cut to at most 30 steps (a scene may legitimately ask for 1e18 steps).
/// Recorded values of a run that succeeds must be finite.
fn run_if_valid(mut scene: Scene) {
    if validate(&scene).is_err() {
        return;
    }
    for s in &mut scene.stages {
        s.steps = s.steps.min(30);
    }
    let mut sys = bpm::scene::build_system(&scene, 1);
    let (stages, error) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
    if error.is_none() {
        for stage in &stages {
            for row in &stage.rows {
                assert!(row.iter().all(|v| v.is_finite()), "non-finite row {row:?}");
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// One leaf of a valid scene replaced by an awkward value: rejected
    /// with an error, or accepted and run without a panic or a NaN.
    #[test]
    fn any_scene_edit_is_rejected_or_runs_cleanly(
        pick in any::<proptest::sample::Index>(),
        value in awkward_number(),
    ) {
        let mut doc = valid_scene();
        let mut paths = Vec::new();
        leaves(&doc, &mut Vec::new(), &mut paths);
        let path = pick.get(&paths).clone();
        *at(&mut doc, &path) = value;
        if let Ok(scene) = serde_json::from_value::<Scene>(doc) {
            run_if_valid(scene);
        }
    }

    /// One value of a breaking, yielding bond rule replaced by an awkward
    /// one: rejected with an error, or accepted and run without a panic or
    /// a NaN.
    #[test]
    fn any_bond_failure_edit_is_rejected_or_runs_cleanly(
        pick in any::<proptest::sample::Index>(),
        value in awkward_number(),
    ) {
        let mut doc = valid_scene();
        doc["force_field"]["bond_failure"] = json!({
            "critical_strain": 0.05, "plastic_strain": 0.01, "smooth": true,
            "breaks": true, "normalize": false
        });
        let mut paths = Vec::new();
        leaves(&doc["force_field"]["bond_failure"], &mut Vec::new(), &mut paths);
        let mut path = vec![json!("force_field"), json!("bond_failure")];
        path.extend(pick.get(&paths).iter().cloned());
        *at(&mut doc, &path) = value;
        if let Ok(scene) = serde_json::from_value::<Scene>(doc) {
            run_if_valid(scene);
        }
    }

    /// Scene text cut short or with a character replaced: an error, never
    /// a panic.
    #[test]
    fn damaged_scene_text_is_an_error_not_a_panic(
        cut in any::<proptest::sample::Index>(),
        at_char in any::<proptest::sample::Index>(),
        c in prop::sample::select(vec!['x', '-', '9', '"', ']', '}', 'e', '.']),
    ) {
        let text = valid_scene().to_string();
        let mut chars: Vec<char> = text.chars().collect();
        let k = at_char.index(chars.len());
        chars[k] = c;
        let damaged: String = chars[..cut.index(chars.len()).max(1)].iter().collect();
        if let Ok(scene) = serde_json::from_str::<Scene>(&damaged) {
            run_if_valid(scene);
        }
    }

    /// One token of a valid LAMMPS data file replaced (nan, inf, huge,
    /// negative, garbage) or one line dropped: an error naming the problem,
    /// or a scene that validates, holds only finite numbers and runs.
    #[test]
    fn any_data_file_edit_is_rejected_or_gives_a_valid_scene(
        line in any::<proptest::sample::Index>(),
        token in any::<proptest::sample::Index>(),
        value in prop::sample::select(vec!["nan", "inf", "-inf", "1e400", "-1", "0", "abc", "", "99999", "2.5"]),
        drop_line in any::<bool>(),
    ) {
        let scene: Scene = serde_json::from_value(valid_scene()).unwrap();
        let text = write_data_file(&scene);
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        let l = line.index(lines.len());
        if drop_line {
            lines.remove(l);
        } else {
            let mut words: Vec<String> = lines[l].split_whitespace().map(String::from).collect();
            if !words.is_empty() {
                let t = token.index(words.len());
                words[t] = value.to_string();
            }
            lines[l] = words.join(" ");
        }
        let path = common::scratch_dir("bad-input").join(format!("case-{l}.data"));
        std::fs::write(&path, lines.join("\n")).unwrap();
        if let Ok(mut read) = read_data_file(&path, [true; 3], ForceField::paper(0.0), 1) {
            // A data file holds no protocol: give it one to validate.
            read.stages = scene.stages.clone();
            let numbers = read
                .particles
                .positions
                .iter()
                .flatten()
                .chain(read.bonds.r0.iter().flatten())
                .chain(&read.simbox.lengths);
            prop_assert!(numbers.clone().all(|c| c.is_finite()), "a non-finite number was accepted");
            // Whether the box suits the force field is the scene check's
            // call (`bpm run` makes it); it must answer, not panic.
            run_if_valid(read);
        }
    }

    /// The bond and pair calls with arbitrary counts, indices, types and
    /// positions (buffers as long as the counts say): a status, never a
    /// panic; success only with finite forces.
    #[test]
    fn the_c_abi_returns_a_status_for_any_arguments(
        nall in -2i64..12,
        pairs in prop::collection::vec((-3i32..14, -3i32..14, -1i32..3), 0..10),
        ncoeffs in -1i64..3,
        nan_at in prop::option::of(0usize..12),
        n_owned in -1i64..14,
        newton in 0i32..2,
    ) {
        let n = nall.max(0) as usize;
        let mut x: Vec<[f64; 3]> = (0..n).map(|i| [i as f64 * 0.9, 0.1 * i as f64, 0.0]).collect();
        if let Some(k) = nan_at.filter(|&k| k < n) {
            x[k][0] = f64::NAN;
        }
        let bonds: Vec<BondEntry> = pairs.iter().map(|&(i, j, ty)| BondEntry { i, j, ty }).collect();
        let r0 = vec![1.0; bonds.len()];
        let coeffs = vec![BondCoeffs { k: 1.0, a: -0.5, gamma: 1.0 }; ncoeffs.max(0) as usize];
        let (mut vol, mut vol0) = (vec![0.0; n], vec![0.0; n]);
        let mut f: Vec<[f64; 3]> = vec![[0.0; 3]; n];
        let mut tally = Tally::default();
        let known = [BPM_OK, BPM_ERR_NULL, BPM_ERR_INDEX, BPM_ERR_TYPE, BPM_ERR_UNSTABLE];
        let st = unsafe {
            bpm_bond_volumes(x.as_ptr() as *const f64, nall, bonds.as_ptr(), bonds.len() as i64,
                r0.as_ptr(), n_owned, newton, vol.as_mut_ptr(), vol0.as_mut_ptr())
        };
        prop_assert!(known.contains(&st), "volumes status {}", st);
        let st = unsafe {
            bpm_bond_forces(x.as_ptr() as *const f64, x.as_ptr() as *const f64, nall,
                bonds.as_ptr(), bonds.len() as i64, r0.as_ptr(), coeffs.as_ptr(), ncoeffs,
                vol.as_ptr(), vol0.as_ptr(), n_owned, newton, f.as_mut_ptr() as *mut f64,
                &mut tally, std::ptr::null_mut())
        };
        prop_assert!(known.contains(&st), "bond status {}", st);
        if st == BPM_OK {
            prop_assert!(f.iter().flatten().all(|c| c.is_finite()), "OK with non-finite forces");
        }
        // The pair call: every atom sees every other.
        let ilist: Vec<i32> = (0..n as i32).collect();
        let neigh: Vec<Vec<i32>> = pairs.iter().map(|&(_, j, _)| vec![j]).chain(std::iter::repeat(vec![])).take(n).collect();
        let numneigh: Vec<i32> = neigh.iter().map(|v| v.len() as i32).collect();
        let firstneigh: Vec<*const i32> = neigh.iter().map(|v| v.as_ptr()).collect();
        let pc = [PairCoeffs { k: 1.0, d: 1.0, a: 50.0, gamma: 1.0 }];
        let special = [1.0, 0.0, 1.0, 1.0];
        let st = unsafe {
            bpm_pair_forces(x.as_ptr() as *const f64, std::ptr::null(), std::ptr::null(), nall, 1,
                pc.as_ptr(), n as i64, ilist.as_ptr(), numneigh.as_ptr(), firstneigh.as_ptr(),
                special.as_ptr(), 0, n_owned, newton, f.as_mut_ptr() as *mut f64, &mut tally,
                std::ptr::null_mut())
        };
        prop_assert!(known.contains(&st), "pair status {}", st);
    }
}

/// The minimal arguments of each subcommand (`{scene}`, `{data}`, `{out}`
/// are filled in), for the option sweep below.
const SUBCOMMANDS: &[&[&str]] = &[
    &["build", "bulk", "-o", "{out}"],
    &["build", "grain", "-o", "{out}"],
    &["run", "{scene}", "-o", "{out}"],
    &["bench", "-o", "{out}"],
    &["check", "-o", "{out}"],
    &["cross-check", "{scene}", "-o", "{out}"],
    &["calibrate", "-o", "{out}"],
    &["upstream-check", "-o", "{out}"],
    &["hertz", "-o", "{out}"],
    &["hertz-sweep", "-o", "{out}"],
    &["crush", "-o", "{out}"],
    &["import", "{data}", "-o", "{out}"],
    &["export", "{scene}", "-o", "{out}"],
    &["bench-lammps"],
    &["stability", "-o", "{out}"],
    &["accuracy", "-o", "{out}"],
    &["large-strain", "-o", "{out}"],
    &["compact", "-o", "{out}"],
    &[
        "analyse-packing",
        "--data",
        "{data}",
        "--dump",
        "{data}",
        "-o",
        "{out}",
    ],
    &["compare-compaction", "{data}", "-o", "{out}"],
    &["mc-box", "-o", "{out}"],
    &["mc-compress", "-o", "{out}"],
    &["mc-calibrate", "{data}", "-o", "{out}"],
    &["mc-shear", "-o", "{out}"],
    &["mc-shear-trend", "{data}", "-o", "{out}"],
];

/// Value names of options that take paths or words, not numbers.
const NOT_NUMBERS: &[&str] = &[
    "OUTPUT",
    "CHECKPOINT",
    "PROGRESS_LOG",
    "THERMO",
    "DUMP",
    "FINAL_SCENE",
    "WORKDIR",
    "GRAIN",
    "FROM",
    "DATA",
    "ENGINE",
    "KIND",
    "PROTOCOL",
    "NEWTON",
    "BOUNDARY",
    "MODEL",
    "PACKING",
    "LABELS",
    "STUDIES",
];

/// `bpm` with `args`; its exit code and error output, or `None` when it
/// ran for longer than `limit`. The error output goes to a file, so a
/// chatty child never blocks on a full pipe.
fn bpm_within(args: &[String], limit: Duration, log: &std::path::Path) -> Option<(i32, String)> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_bpm"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(log).unwrap())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let err = std::fs::read_to_string(log).unwrap_or_default();
            return Some((status.code().unwrap_or(-1), err));
        }
        if start.elapsed() > limit {
            child.kill().ok();
            child.wait().ok();
            return None;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The `--name <VALUE>` options in a `--help` text.
fn numeric_options(help: &str) -> Vec<String> {
    help.lines()
        .filter_map(|l| {
            let l = l.trim_start();
            let rest = l.strip_prefix("--")?;
            let (name, value) = rest.split_once(" <")?;
            // Short help texts follow the value on the same line.
            let value = value.split('>').next()?;
            (!NOT_NUMBERS.contains(&value)).then(|| format!("--{name}"))
        })
        .collect()
}

#[test]
fn every_numeric_option_refuses_non_numbers_before_any_work() {
    let dir = common::scratch_dir("bad-options");
    let scene: Scene = serde_json::from_value(valid_scene()).unwrap();
    let scene_path = dir.join("scene.json");
    std::fs::write(&scene_path, serde_json::to_string(&scene).unwrap()).unwrap();
    let data_path = dir.join("scene.data");
    std::fs::write(&data_path, write_data_file(&scene)).unwrap();
    let fill = |a: &&str| {
        a.replace("{scene}", scene_path.to_str().unwrap())
            .replace("{data}", data_path.to_str().unwrap())
            .replace("{out}", dir.join("out").to_str().unwrap())
    };
    // Every subcommand `bpm --help` lists is in the sweep.
    let top = Command::new(env!("CARGO_BIN_EXE_bpm"))
        .arg("--help")
        .output()
        .unwrap();
    let top = String::from_utf8(top.stdout).unwrap();
    let listed = top
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|name| *name != "help");
    for name in listed {
        assert!(
            SUBCOMMANDS.iter().any(|sub| sub[0] == name),
            "`bpm {name}` is missing from SUBCOMMANDS"
        );
    }
    let mut tried = 0;
    for sub in SUBCOMMANDS {
        let base: Vec<String> = sub.iter().map(fill).collect();
        let words = sub
            .iter()
            .take_while(|a| !a.starts_with('-') && !a.starts_with('{'));
        let mut help_args: Vec<String> = words.map(|w| w.to_string()).collect();
        help_args.push("--help".into());
        let help = String::from_utf8(
            Command::new(env!("CARGO_BIN_EXE_bpm"))
                .args(&help_args)
                .output()
                .unwrap()
                .stdout,
        )
        .unwrap();
        let options = numeric_options(&help);
        assert!(
            !options.is_empty() || sub[0] == "export" || sub[0] == "compare-compaction",
            "{sub:?}: no options found"
        );
        for option in options {
            for bad in ["nan", "inf", "-inf", "1e999", "abc"] {
                let mut args = base.clone();
                args.extend([option.clone(), bad.to_string()]);
                tried += 1;
                let Some((code, err)) =
                    bpm_within(&args, Duration::from_secs(60), &dir.join("stderr"))
                else {
                    panic!(
                        "`bpm {}` still running after 60 s: the value was not refused",
                        args.join(" ")
                    );
                };
                assert!(
                    code == 1 || code == 2,
                    "`bpm {}` exited {code}:\n{err}",
                    args.join(" ")
                );
                // Refused for this value: the message names the option, the
                // value, or says it is invalid.
                let field = option.trim_start_matches('-').replace('-', "_");
                let named = [
                    option.as_str(),
                    option.trim_start_matches('-'),
                    field.as_str(),
                    bad,
                    "NaN",
                    "inf",
                    "invalid",
                ]
                .iter()
                .any(|w| err.contains(w));
                assert!(
                    named,
                    "`bpm {}` failed for another reason:\n{err}",
                    args.join(" ")
                );
                assert!(
                    !err.contains("panicked"),
                    "`bpm {}` panicked:\n{err}",
                    args.join(" ")
                );
            }
        }
    }
    eprintln!("{tried} bad option values refused");
}
