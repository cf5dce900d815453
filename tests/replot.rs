//! Every committed study report reads back as this version's report type
//! and is written out again unchanged: the replot (`--from`, `--refit`)
//! of a committed result draws from exactly what was measured, and a
//! change to a report's fields that would orphan the committed results
//! fails here. Unchanged means byte for byte, or, for a report written
//! before an option existed, every committed value kept and only that
//! option added at its default (the additions listed in [`ADDED`]).

use bpm::studies::output::{replot, StudyReport};
use std::path::{Path, PathBuf};

/// The keys a committed report lacks because it was written before they
/// existed, each added at its default on a replot: (report, key path).
const ADDED: &[(&str, &str)] = &[("results/stability/stability.json", "/options/zero_net")];

fn repository() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Replots the committed `json` (relative to the repository) into a
/// scratch folder and compares the JSON written with the committed one.
fn round_trip<R: StudyReport>(json: &str) {
    let committed = repository().join(json);
    let scratch = std::env::temp_dir().join(format!(
        "bpm-replot-{}-{}",
        std::process::id(),
        json.replace('/', "_")
    ));
    let _ = std::fs::remove_dir_all(&scratch);
    let result = replot::<R>(&committed, &scratch);
    let written = scratch.join(R::JSON);
    let outcome = result.map(|_| {
        (
            std::fs::read(&committed).unwrap(),
            std::fs::read(&written).unwrap(),
        )
    });
    let _ = std::fs::remove_dir_all(&scratch);
    match outcome {
        Ok((before, after)) if before == after => {}
        Ok((before, after)) => {
            let before: serde_json::Value = serde_json::from_slice(&before).unwrap();
            let after: serde_json::Value = serde_json::from_slice(&after).unwrap();
            let mut added = Vec::new();
            assert!(
                kept(&before, &after, "", &mut added),
                "{json}: the replotted report differs from the committed one"
            );
            assert!(!added.is_empty(), "{json}: same values, different text");
            for key in &added {
                assert!(
                    ADDED.contains(&(json, key.as_str())),
                    "{json}: {key} added, not listed in ADDED"
                );
            }
        }
        Err(e) => panic!("{json}: {e}"),
    }
}

/// Whether `after` holds every value of `before` unchanged, with extra
/// keys (collected in `added`) only at a default value.
fn kept(
    before: &serde_json::Value,
    after: &serde_json::Value,
    at: &str,
    added: &mut Vec<String>,
) -> bool {
    use serde_json::Value;
    match (before, after) {
        (Value::Object(b), Value::Object(a)) => {
            for (key, value) in a {
                if !b.contains_key(key) {
                    if !matches!(value, Value::Bool(false) | Value::Null) {
                        eprintln!("{at}/{key}: added with {value}, not a default");
                        return false;
                    }
                    added.push(format!("{at}/{key}"));
                }
            }
            b.iter().all(|(key, value)| {
                a.get(key)
                    .is_some_and(|v| kept(value, v, &format!("{at}/{key}"), added))
            })
        }
        (Value::Array(b), Value::Array(a)) => {
            b.len() == a.len()
                && b.iter()
                    .zip(a)
                    .enumerate()
                    .all(|(k, (b, a))| kept(b, a, &format!("{at}/{k}"), added))
        }
        _ => {
            if before != after {
                eprintln!("{at}: {before} became {after}");
            }
            before == after
        }
    }
}

/// The committed reports of one study: every file `name` under `folder`.
fn committed(folder: &str, name: &str) -> Vec<String> {
    fn walk(dir: &Path, name: &str, found: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                walk(&path, name, found);
            } else if path.file_name().is_some_and(|n| n == name) {
                found.push(path);
            }
        }
    }
    let mut found = Vec::new();
    walk(&repository().join(folder), name, &mut found);
    found.sort();
    let found: Vec<String> = found
        .iter()
        .map(|p| {
            p.strip_prefix(repository())
                .unwrap()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    assert!(!found.is_empty(), "no {name} under {folder}");
    found
}

#[test]
fn stability_reports() {
    for json in committed("results", "stability.json") {
        round_trip::<bpm::studies::stability::StabilityReport>(&json);
    }
}

#[test]
fn accuracy_report() {
    round_trip::<bpm::studies::accuracy::AccuracyReport>("results/accuracy/accuracy.json");
}

#[test]
fn large_strain_reports() {
    for json in committed("results", "large_strain.json") {
        round_trip::<bpm::studies::large_strain::LargeStrainReport>(&json);
    }
}

#[test]
fn hertz_reports() {
    for json in committed("results/hertz", "hertz.json") {
        round_trip::<bpm::studies::hertz::HertzReport>(&json);
    }
    round_trip::<bpm::studies::hertz_sweep::SweepReport>("results/hertz/sweep-smoother/sweep.json");
}

#[test]
fn crush_reports() {
    for json in committed("results/crush", "crush.json") {
        round_trip::<bpm::studies::crush::CrushReport>(&json);
    }
}

#[test]
fn compaction_reports() {
    for json in committed("results", "compaction.json") {
        round_trip::<bpm::studies::compaction::CompactionReport>(&json);
    }
}

#[test]
fn multi_contact_reports() {
    use bpm::studies::mcdem;
    round_trip::<mcdem::compression::CompressionReport>(
        "results/mcdem/compression/compression.json",
    );
    round_trip::<mcdem::rigid_box::BoxReport>("results/mcdem/rigid-box/rigid_box.json");
    for json in committed("results/mcdem/shear", "shear.json") {
        round_trip::<mcdem::shear::ShearReport>(&json);
    }
    round_trip::<mcdem::calibration::CalibrationReport>(
        "results/mcdem/calibration/calibration.json",
    );
}

/// A report that records a blow-up (NaN and infinite measurements, written
/// as `null`) reads back, its undefined values as NaN.
#[test]
fn a_report_of_a_blown_up_run_replots() {
    use bpm::studies::large_strain::{Compression, LargeStrainOptions, LargeStrainReport, State};
    let state = |pressure: f64| State {
        time: 10.0,
        imposed_strain: 0.2,
        bond_strain: f64::NAN,
        pressure,
        shortest_bond: f64::INFINITY,
        longest_bond: 1.1,
    };
    let report = LargeStrainReport {
        provenance: bpm::studies::Provenance::new("bpm large-strain"),
        options: LargeStrainOptions::default(),
        compressions: vec![Compression {
            body: "bulk".into(),
            a_b: 0.0,
            particles: 8,
            states: vec![state(0.5), state(f64::NAN)],
            complete: false,
            failure: Some("particles lost".into()),
            seconds: 1.0,
        }],
    };
    let scratch = std::env::temp_dir().join(format!("bpm-replot-nan-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&scratch);
    bpm::studies::output::write_report(&report, &scratch).unwrap();
    let read: LargeStrainReport =
        replot(&scratch.join("large_strain.json"), &scratch.join("again")).unwrap();
    let states = &read.compressions[0].states;
    assert_eq!(states[0].pressure, 0.5);
    assert!(states[1].pressure.is_nan() && states[0].bond_strain.is_nan());
    // An infinity is written as null too, and comes back undefined.
    assert!(states[0].shortest_bond.is_nan());
    let _ = std::fs::remove_dir_all(&scratch);
}
