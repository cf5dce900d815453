//! The standing cross-check against LIGGGHTS (`verify::liggghts`): its
//! hydrogel tutorial's lid force, LIGGGHTS's committed in
//! `reference_data/liggghts/hydrogel_multicontact`, against the native
//! engine's on the same bed under the same lid, with gravity. The goal is
//! 2% of the peak, root mean square over the loaded rows.

use bpm::verify::liggghts::{
    lid_cross_check, lid_cross_check_with, tutorial_options, write_tutorial_bed, LiggghtsLaw,
};

// One thread: the cross-check compares forces, not speed, and the suite
// runs tests side by side. (A run of this test on two threads, beside the
// other test on two more, once hung in the thread team: a worker woken late
// parked again unannounced. That is fixed and tested in `engine::team`.)

fn work(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("bpm-liggghts-{name}-{}", std::process::id()))
}

/// Over both cycles, and pass by pass. The first pass, before the lid has
/// turned, agrees closest (measured 0.07%). With the walls' friction
/// springs restarted at each turn of the lid, as LAMMPS's walls would be,
/// the later passes drift further from LIGGGHTS, which keeps them
/// (measured 1.75% against 1.10% over the run).
#[test]
fn hertz_lid_force_follows_liggghts_over_both_cycles() {
    let check = lid_cross_check(LiggghtsLaw::Hertz, 2, &work("hertz"), 1).unwrap();
    let c = check.comparison;
    assert!(c.loaded_rows > 1000, "{c:?}");
    assert!(c.rms_of_peak <= 0.02, "{c:?}");
    assert!(
        (check.native_peak / c.peak - 1.0).abs() < 0.02,
        "peak {} against LIGGGHTS's {}",
        check.native_peak,
        c.peak
    );
    assert_eq!(check.by_pass.len(), 4, "{:?}", check.by_pass);
    let first = check.by_pass[0].expect("the first pass loads the lid");
    assert!(first.rms_of_peak <= 0.005, "{first:?}");

    let dir = work("hertz-restarting");
    let bed = write_tutorial_bed(&dir, "bed.data").unwrap();
    let mut restarting = tutorial_options(&bed, 2);
    restarting.keep_wall_histories = false;
    let restarted = lid_cross_check_with(LiggghtsLaw::Hertz, &restarting, 1).unwrap();
    assert!(
        c.rms_of_peak < restarted.comparison.rms_of_peak,
        "kept {c:?}, restarted {:?}",
        restarted.comparison
    );
}

/// The closure costs five times Hertz, so the test runs its first cycle
/// (`bpm check` runs both).
#[test]
fn closure_lid_force_follows_liggghts_over_the_first_cycle() {
    let check = lid_cross_check(LiggghtsLaw::Closure, 1, &work("closure"), 1).unwrap();
    let c = check.comparison;
    assert!(c.loaded_rows > 500, "{c:?}");
    assert!(c.rms_of_peak <= 0.02, "{c:?}");
    assert_eq!(check.by_pass.len(), 2, "{:?}", check.by_pass);
}
