//! The LIGGGHTS case of `bpm bench` (`studies::bench::bench_liggghts`):
//! LIGGGHTS's hydrogel tutorial under its lid, plain Hertz and the
//! closure, in LIGGGHTS and natively, and the advanced closure natively. A few steps only, and no timing is
//! judged (timings belong to the benchmark): the report's fields are there
//! and positive, and a LIGGGHTS that fails is reported, not fatal.

use bpm::studies::bench::{bench_liggghts, LiggghtsInstall};
use std::path::PathBuf;

fn work(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("bpm-bench-liggghts-{name}-{}", std::process::id()))
}

#[test]
fn the_liggghts_case_times_both_laws_in_both_programs() {
    let install = match LiggghtsInstall::locate() {
        Ok(install) => install,
        Err(why) => {
            eprintln!("skipped: {why}");
            return;
        }
    };
    let mut lines = Vec::new();
    let bench = bench_liggghts(&install, 200, &work("tiny"), &mut |l: &str| {
        lines.push(l.to_string())
    });
    assert!(bench.failures.is_empty(), "{:?}", bench.failures);
    let report = serde_json::to_value(&bench).unwrap();
    let version = report["version"].as_str().unwrap();
    assert!(version.starts_with("LIGGGHTS (Version"), "{version}");
    assert_eq!(report["steps"], 200);
    let speeds = report["speeds"].as_array().unwrap();
    let laws: Vec<&str> = speeds.iter().map(|s| s["law"].as_str().unwrap()).collect();
    assert_eq!(laws, ["Hertz", "Closure"]);
    for s in speeds {
        assert_eq!(s["steps"], 200);
        assert_eq!(s["particles"], 514);
        for field in [
            "liggghts_seconds",
            "liggghts_ns",
            "native_seconds",
            "native_ns",
            "native_2_threads_ns",
            "liggghts_over_native",
        ] {
            let v = s[field].as_f64().unwrap_or(f64::NAN);
            assert!(v.is_finite() && v > 0.0, "{field}: {s}");
        }
        let command = s["command"].as_str().unwrap();
        assert!(command.contains("-in in.bench_"), "{command}");
    }
    let advanced = report["advanced_native_ns"].as_f64().unwrap_or(f64::NAN);
    assert!(advanced.is_finite() && advanced > 0.0, "{advanced}");
    assert_eq!(
        lines.len(),
        3,
        "one line per law, then the advanced closure: {lines:?}"
    );
    assert!(lines[..2].iter().all(|l| l.contains("LIGGGHTS / native")));
    assert!(
        lines[2].contains("advanced closure (native only)"),
        "{}",
        lines[2]
    );
}

#[test]
fn a_liggghts_that_cannot_run_is_reported_and_the_case_goes_on() {
    let dir = work("missing");
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = dir.join("piston_hydrogel.stl");
    std::fs::write(&mesh, "solid lid\nendsolid lid\n").unwrap();
    let install = LiggghtsInstall {
        binary: dir.join("no-such-liggghts"),
        mesh,
    };
    let mut lines = Vec::new();
    let bench = bench_liggghts(&install, 20, &dir.join("run"), &mut |l: &str| {
        lines.push(l.to_string())
    });
    assert!(bench.speeds.is_empty());
    // Nothing to compare the advanced closure with: not run.
    assert!(bench.advanced_native_ns.is_nan());
    assert_eq!(
        bench.failures.len(),
        2,
        "both laws tried: {:?}",
        bench.failures
    );
    for (failure, law) in bench.failures.iter().zip(["Hertz", "standard closure"]) {
        assert!(
            failure.starts_with(&format!("LIGGGHTS {law} failed:"))
                && failure.contains("could not start"),
            "{failure}"
        );
    }
    assert_eq!(lines, bench.failures);
    let _ = std::fs::remove_dir_all(&dir);
}
