//! `bpm crush` as a library call: a grain whose bonds break follows the
//! same grain with unbreakable bonds exactly until its first break, and
//! the report's counts agree with the engine's bonds.

mod common;

use bpm::kernels::BondFailure;
use bpm::scene::builders::grain::{build_grain, GrainKind, GrainParams};
use bpm::studies::crush::{run_crush, CrushOptions, CrushReport};
use bpm::studies::hertz::GrainSource;
use bpm::studies::StudyRuntime;

fn crush(grain: &std::path::Path, critical_strain: f64, out: &std::path::Path) -> CrushReport {
    let opts = CrushOptions {
        source: GrainSource::File {
            path: grain.to_path_buf(),
            radius: 3.0,
        },
        seeds: vec![5],
        a_bs: vec![0.0],
        rotations: 0,
        // No smoothing: before any bond breaks, the force is the elastic one.
        failure: BondFailure {
            smooth: false,
            ..BondFailure::breaking(critical_strain)
        },
        max_overlap: 0.4,
        records: 400,
        threads: 1,
    };
    let report = run_crush(&opts, out, &StudyRuntime::plain(1, false), &mut |_| {}).unwrap();
    assert!(out.join("crush.json").exists() && out.join("crush.svg").exists());
    report
}

#[test]
fn a_breakable_grain_follows_the_unbreakable_one_until_its_first_break() {
    let dir = common::scratch_dir("crush");
    let mut p = GrainParams::new(GrainKind::Smoother, 3.0, 5, 0.0);
    p.time_scale = 0.2;
    let (grain, _) = build_grain(&p, 1, false).unwrap();
    let file = dir.join("grain.json");
    bpm::scene::write_scene(&file, &grain).unwrap();

    let weak = crush(&file, 0.05, &dir.join("weak"));
    // A critical strain no bond reaches: the same squeeze, nothing breaks.
    let strong = crush(&file, 10.0, &dir.join("strong"));
    let (w, s) = (&weak.cases[0].crushes[0], &strong.cases[0].crushes[0]);

    assert!(s.first_break.is_none() && s.broken_fraction.iter().all(|&b| b == 0.0));
    assert_eq!(
        (s.fragments.count(), s.fragments.sizes[0]),
        (1, s.particles)
    );

    let first = w.first_break.expect("no bond broke at eps_c = 0.05");
    let contact = w.curve.contact_record.unwrap();
    assert_eq!(s.curve.contact_record, Some(contact));
    let k = contact + w.broken_fraction.iter().position(|&b| b > 0.0).unwrap();
    assert_eq!(
        w.curve.force[..k],
        s.curve.force[..k],
        "the curves part before the first break"
    );
    assert!(
        w.curve.force[k..] != s.curve.force[k..],
        "breaking bonds changed nothing"
    );
    assert_eq!(first.force, w.curve.force[k]);

    // Breaking weakens the grain: its largest force is below the
    // unbreakable grain's, and its bonds keep breaking.
    let peak = |c: &bpm::studies::crush::Crush| c.peak.unwrap().force;
    assert!(peak(w) < peak(s), "{} against {}", peak(w), peak(s));
    let broken = *w.broken_fraction.last().unwrap();
    assert!(broken > first.broken_fraction);
    assert!(w.broken_fraction.windows(2).all(|p| p[1] >= p[0]));

    // The fragments cover every particle, and the engine's intact bonds
    // that hold them are the bonds the record did not count broken.
    let f = &w.fragments;
    assert_eq!(
        f.sizes.iter().sum::<usize>() + f.single_particles,
        w.particles
    );
    assert!(f.count() >= 1 && f.largest_fraction() <= 1.0);
    let broken_bonds = (broken * w.bonds as f64).round() as usize;
    assert_eq!(w.intact_bonds + broken_bonds, w.bonds);
    let case = &weak.cases[0];
    assert_eq!(case.crushes.len(), 1);
    assert!((case.broken_fraction.unwrap().mean - broken).abs() < 1e-15);
}
