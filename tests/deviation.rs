//! The deviation measures of the cross-check (`verify::single_point`,
//! `verify::compare`) on hand-made data, without running either engine.

use bpm::scene::run::{Checkpoint, StageOutput};
use bpm::verify::compare_runs;
use bpm::verify::max_relative_deviation;
use bpm::verify::tolerances::tolerance;

/// A deviation fails a tolerance unless it is a number at or below it: NaN
/// and infinity fail every tolerance (as `deviation <= tol` is false for
/// them in the harness's checks).
fn fails(deviation: f64, tol: f64) -> bool {
    deviation.is_nan() || deviation > tol
}

/// One stage recording `pxx` and `time` at steps 0, 10, 20, 30, with one
/// position checkpoint per recorded step.
fn stage(pxx: [f64; 4], positions: [[f64; 3]; 4]) -> StageOutput {
    StageOutput {
        name: "s".into(),
        steps: 30,
        columns: ["step", "time", "pxx"]
            .map(|c| bpm::scene::observables::standard_column(c).unwrap())
            .to_vec(),
        rows_file: None,
        rows: (0..4)
            .map(|k| vec![10.0 * k as f64, k as f64, pxx[k]])
            .collect(),
        checkpoints: (0..4)
            .map(|k| Checkpoint {
                step: 10 * k as u64,
                simbox: [[0.0; 3], [10.0; 3], [0.0; 3]],
                positions: vec![positions[k], [5.0, 5.0, 5.0]],
                images: vec![[0; 3]; 2],
                broken_bonds: Vec::new(),
            })
            .collect(),
        wall_seconds: 0.0,
        timers: Default::default(),
        neighbour_builds: 0,
        stopped_at: None,
    }
}

/// The bug: the shared deviation once folded with `f64::max`, which returns
/// the other operand when one is NaN, so a NaN force (or a NaN in a series)
/// read as zero deviation and passed every tolerance. The NaN sits in the
/// first row, finite rows after it, so a fold that drops it, or lets a
/// later finite value replace it, ends on a small finite number.
#[test]
fn nan_force_or_series_value_is_not_dropped_by_f64_max_as_zero_deviation() {
    let tol = tolerance("step-0 forces");
    assert!(tol > 0.0);
    let reference = vec![[1.0, -2.0, 0.5], [0.25, 3.0, -1.0], [2.0, 0.0, 1.0]];
    assert_eq!(max_relative_deviation(&reference, &reference), 0.0);
    let mut nan_row = reference.clone();
    nan_row[0][1] = f64::NAN;
    // A NaN in the compared forces, and in the reference forces.
    let dev = max_relative_deviation(&nan_row, &reference);
    assert!(fails(dev, tol), "NaN force in the run: deviation {dev:e}");
    let dev = max_relative_deviation(&reference, &nan_row);
    assert!(
        fails(dev, tol),
        "NaN force in the reference: deviation {dev:e}"
    );
    // A pressure tensor (one row of six).
    let p = [[1.0, 2.0, 3.0, 0.1, 0.2, 0.3]];
    let mut q = p;
    q[0][3] = f64::NAN;
    let dev = max_relative_deviation(&q, &p);
    assert!(
        fails(dev, tolerance("step-0 stress")),
        "NaN pressure: {dev:e}"
    );

    // A series: pxx NaN at step 0 of the run, finite and equal afterwards.
    let x = [[1.0, 1.0, 1.0]; 4];
    let reference = [stage([1.0, 2.0, 3.0, 4.0], x)];
    let run = [stage([f64::NAN, 2.0, 3.0, 4.0], x)];
    let same = compare_runs(&reference, &reference).unwrap();
    assert!(same.iter().all(|d| d.max_deviation == 0.0), "{same:?}");
    let stress = compare_runs(&reference, &run)
        .unwrap()
        .into_iter()
        .find(|d| d.observable == "stress")
        .unwrap();
    assert!(
        fails(stress.max_deviation, tolerance("trajectory stress")),
        "NaN in the pxx series: {stress:?}"
    );
    assert_eq!(stress.at_step, 0, "the NaN's step: {stress:?}");

    // A NaN position at the first checkpoint.
    let mut y = x;
    y[0][2] = f64::NAN;
    let run = [stage([1.0, 2.0, 3.0, 4.0], y)];
    let positions = compare_runs(&reference, &run)
        .unwrap()
        .into_iter()
        .find(|d| d.observable == "positions")
        .unwrap();
    assert!(
        fails(positions.max_deviation, tolerance("trajectory positions")),
        "NaN position: {positions:?}"
    );
    assert_eq!(positions.at_step, 0, "the NaN's step: {positions:?}");
}
