//! `bpm mc-compress --packing`: the lid protocol on a bed from a data file,
//! in the file's units. A single sphere squeezed between the floor and the
//! lid follows Hertz; bad options are refused by name.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bpm() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bpm"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bpm-lid-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// SI units, as a LIGGGHTS bed: one sphere of diameter 0.02 m, density
/// 11.5 kg/m^3, resting on the floor at the middle of a 0.1 m base.
const RADIUS: f64 = 0.01;
const ONE_SPHERE: &str = "LIGGGHTS data file\n\n 1  atoms\n\n 1  atom types\n\n \
    -0.01  0.11 xlo xhi\n -0.01  0.11 ylo yhi\n -0.01  0.05 zlo zhi\n\nAtoms\n\n\
    1 1 0.02 11.5 0.05 0.05 0.01\n";

fn write_bed(dir: &Path) -> PathBuf {
    let path = dir.join("bed.data");
    std::fs::write(&path, ONE_SPHERE).unwrap();
    path
}

/// `bpm mc-compress --packing` on `bed` with the options of the
/// single-sphere squeeze, each overridden or joined by `extra` (option,
/// value).
fn lid_run(bed: &Path, out: &Path, extra: &[(&str, &str)]) -> Output {
    let mut options = vec![
        ("--base", "0.1,0.1"),
        ("--lid-start", "0.02"),
        ("--lid-end", "0.018"),
        ("--lid-speed", "0.01"),
        ("--dt", "1e-5"),
        ("--cycles", "1"),
    ];
    for &(option, value) in extra {
        match options.iter_mut().find(|(o, _)| *o == option) {
            Some(slot) => slot.1 = value,
            None => options.push((option, value)),
        }
    }
    let mut cmd = bpm();
    cmd.args(["mc-compress", "--packing"])
        .arg(bed)
        .arg("-o")
        .arg(out);
    for (option, value) in options {
        cmd.arg(option).args(value.split_whitespace());
    }
    cmd.output().unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Hertz's force between a sphere of radius `r` and a flat wall at overlap
/// `delta`, with the effective modulus of the two materials.
fn hertz_on_wall(r: f64, delta: f64, e_sphere: f64, e_wall: f64, nu: f64) -> f64 {
    let e_star = 1.0 / ((1.0 - nu * nu) / e_sphere + (1.0 - nu * nu) / e_wall);
    4.0 / 3.0 * e_star * r.sqrt() * delta.powf(1.5)
}

#[test]
fn a_sphere_squeezed_by_the_lid_follows_hertz_at_every_row() {
    let dir = scratch("hertz");
    let bed = write_bed(&dir);
    let out = lid_run(&bed, &dir.join("out"), &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/lid.json")).unwrap()).unwrap();
    assert_eq!(report["steps_per_pass"], 20_000);
    assert_eq!(report["spheres"], 1);
    let runs = report["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2, "plain Hertz and the standard closure");
    let series = |run: &Value, key: &str| -> Vec<f64> {
        run[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let hertz = &runs[0];
    assert!(hertz["stopped"].is_null(), "{}", hertz["stopped"]);
    let lid = series(hertz, "lid_position");
    let force = series(hertz, "lid_force");
    let step = series(hertz, "step");
    assert_eq!(step.len(), 401, "rows every 100 steps over two passes");
    assert_eq!(step[200], 20_000.0);
    assert!(
        (lid[200] - 0.018).abs() < 1e-12,
        "the lid turns at 0.018, not {}",
        lid[200]
    );
    // The floor and the lid are one material, so in a slow squeeze each
    // takes half the closing as its overlap.
    let mut checked = 0;
    for (&z, &f) in lid.iter().zip(&force) {
        let delta = (2.0 * RADIUS - z) / 2.0;
        if delta < 2e-4 {
            continue;
        }
        let expected = hertz_on_wall(RADIUS, delta, 23.3e3, 5e7, 0.5);
        assert!(
            (f / expected - 1.0).abs() < 0.01,
            "lid at {z}: force {f}, Hertz {expected}"
        );
        checked += 1;
    }
    assert!(checked > 200, "only {checked} rows were loaded");
    // The closure stiffens a sphere pressed from two sides.
    let peak = |run: &Value| series(run, "lid_force").into_iter().fold(0.0, f64::max);
    assert!(peak(&runs[1]) > 1.01 * peak(hertz));
    for file in ["lid.svg", "scene-0.json", "scene-1.json"] {
        assert!(
            dir.join("out").join(file).exists(),
            "{file} was not written"
        );
    }
}

/// Hertz's stiffness factor `K` (force = `K` overlap^1.5) between the
/// test's sphere and a wall.
fn hertz_factor() -> f64 {
    hertz_on_wall(RADIUS, 1.0, 23.3e3, 5e7, 0.5)
}

/// The lid's force on a sphere of weight `weight` between the floor and
/// the lid at height `lid`, at rest: the floor carries the lid's force and
/// the weight, and the two overlaps close the gap `2 R - lid`.
fn squeezed_under_weight(lid: f64, weight: f64) -> f64 {
    let k = hertz_factor();
    let closing = 2.0 * RADIUS - lid;
    let gap = |top: f64| top + ((k * top.powf(1.5) + weight) / k).powf(2.0 / 3.0) - closing;
    let (mut lo, mut hi) = (0.0, closing);
    if gap(lo) >= 0.0 {
        return 0.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if gap(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    k * lo.powf(1.5)
}

#[test]
fn under_gravity_the_floor_carries_the_weight_and_the_lid_less() {
    let dir = scratch("gravity");
    // A dense sphere (2000 kg/m^3) resting on the floor at its
    // equilibrium overlap, the lid just touching its top.
    let density = 2000.0;
    let g = 9.81;
    let weight = 4.0 / 3.0 * std::f64::consts::PI * RADIUS.powi(3) * density * g;
    let sink = (weight / hertz_factor()).powf(2.0 / 3.0);
    let (start, end) = (2.0 * RADIUS - sink, 2.0 * RADIUS - sink - 0.002);
    let bed = dir.join("bed.data");
    std::fs::write(
        &bed,
        ONE_SPHERE.replace(
            "0.02 11.5 0.05 0.05 0.01",
            &format!("0.02 {density} 0.05 0.05 {}", RADIUS - sink),
        ),
    )
    .unwrap();
    let (start_text, end_text) = (start.to_string(), end.to_string());
    let out = lid_run(
        &bed,
        &dir.join("out"),
        &[
            ("--gravity", "0 0 -9.81"),
            ("--lid-start", &start_text),
            ("--lid-end", &end_text),
            ("--lid-speed", "0.001"),
            ("--record-every", "1000"),
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/lid.json")).unwrap()).unwrap();
    let scene: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/scene-0.json")).unwrap())
            .unwrap();
    assert_eq!(scene["force_field"]["gravity"][2], -g);
    let run = &report["runs"][0];
    let lid = run["lid_position"].as_array().unwrap();
    let force = run["lid_force"].as_array().unwrap();
    let mut checked = 0;
    for (z, f) in lid.iter().zip(force) {
        let (z, f) = (z.as_f64().unwrap(), f.as_f64().unwrap());
        let expected = squeezed_under_weight(z, weight);
        if expected < 0.05 * weight {
            continue;
        }
        assert!(
            (f / expected - 1.0).abs() < 0.01,
            "lid at {z}: force {f}, at rest under the weight {expected}"
        );
        checked += 1;
    }
    assert!(checked > 300, "only {checked} rows were loaded");
    // Without its weight the sphere would push back much harder.
    let turn = squeezed_under_weight(end, weight);
    let weightless = squeezed_under_weight(end, 0.0);
    assert!(weightless > 1.2 * turn, "{weightless} against {turn}");
}

#[test]
fn a_lid_that_starts_inside_the_bed_is_refused() {
    let dir = scratch("inside");
    let bed = write_bed(&dir);
    let out = lid_run(
        &bed,
        &dir.join("out"),
        &[("--lid-start", "0.009"), ("--lid-end", "0.005")],
    );
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(err.contains("--lid-start 0.009 is inside the bed"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn the_lid_protocol_names_each_missing_or_malformed_option() {
    let dir = scratch("options");
    let bed = write_bed(&dir);
    let refusals = [
        (("--gravity", "0 -9.81"), "--gravity <GX> <GY> <GZ>"),
        (("--base", "0.1"), "--base X,Y"),
        (("--lid-end", "0.03"), "--lid-end"),
        (("--poisson-ratio", "0.7"), "--poisson-ratio"),
        (("--skin", "0"), "--skin"),
    ];
    for (extra, message) in refusals {
        let out = lid_run(&bed, &dir.join("out"), &[extra]);
        let err = stderr(&out);
        assert!(!out.status.success(), "{extra:?} was accepted");
        assert!(err.contains(message), "{extra:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let no_dt = bpm()
        .args(["mc-compress", "--packing"])
        .arg(&bed)
        .args([
            "--base",
            "0.1,0.1",
            "--lid-start",
            "0.02",
            "--lid-end",
            "0.018",
        ])
        .arg("-o")
        .arg(dir.join("out"))
        .output()
        .unwrap();
    assert!(!no_dt.status.success());
    assert!(
        stderr(&no_dt).contains("--packing needs --dt"),
        "{}",
        stderr(&no_dt)
    );
    let no_packing = bpm()
        .args(["mc-compress", "--lid-start", "0.02", "-o"])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    assert!(!no_packing.status.success());
    assert!(stderr(&no_packing).contains("give --packing FILE.data"));
}
