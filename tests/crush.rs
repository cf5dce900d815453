//! `bpm crush` as a library call: a grain whose bonds break follows the
//! same grain with unbreakable bonds exactly until its first break, and
//! the report's counts agree with the engine's bonds.

mod common;

use bpm::kernels::BondFailure;
use bpm::scene::builders::grain::{build_grain, GrainKind, GrainParams};
use bpm::studies::crush::{run_crush, CrushOptions, CrushReport};
use bpm::studies::hertz::GrainSource;
use bpm::studies::StudyRuntime;

fn crush(
    grain: &std::path::Path,
    critical_strain: f64,
    compare_at: f64,
    out: &std::path::Path,
) -> CrushReport {
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
        compare_at: Some(compare_at),
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

    let weak = crush(&file, 0.05, 0.3, &dir.join("weak"));
    // A critical strain no bond reaches: the same squeeze, nothing breaks.
    let strong = crush(&file, 10.0, 0.3, &dir.join("strong"));
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

    // At delta/R = 0.3, on the way: the record's own broken share, and
    // fragments held by the bonds standing then, so no smaller than at
    // the end; the unbreakable grain is whole there too.
    let at = w
        .compared
        .as_ref()
        .expect("the squeeze passed delta/R = 0.3");
    let k = w
        .curve
        .overlap_over_r
        .iter()
        .position(|&x| x >= 0.3)
        .unwrap();
    assert!(k > 0 && w.curve.overlap_over_r[k - 1] < 0.3);
    assert_eq!(at.overlap_over_r, w.curve.overlap_over_r[k]);
    assert_eq!(at.broken_fraction, w.broken_fraction[k]);
    assert!(at.broken_fraction > 0.0 && at.broken_fraction < broken);
    assert_eq!(
        at.fragments.sizes.iter().sum::<usize>() + at.fragments.single_particles,
        w.particles
    );
    assert!(at.fragments.largest_fraction() >= f.largest_fraction());
    assert!(at.fragments.single_particles <= f.single_particles);
    assert_eq!(s.compared.as_ref().unwrap().fragments, s.fragments);
    assert_eq!(
        case.compared_broken_fraction.unwrap().mean,
        at.broken_fraction
    );

    // Counted before the first break, the same squeeze's grain is whole:
    // every bond broken later is put back.
    let early = first.overlap_over_r / 2.0;
    let again = crush(&file, 0.05, early, &dir.join("early"));
    let e = &again.cases[0].crushes[0];
    assert_eq!(e.curve.force, w.curve.force);
    let before = e.compared.as_ref().unwrap();
    assert!(before.overlap_over_r < first.overlap_over_r);
    assert_eq!(before.broken_fraction, 0.0);
    assert_eq!(
        (before.fragments.sizes.clone(), before.large_fragments),
        (vec![w.particles], 1)
    );
    assert!(w.fragments.sizes[0] < w.particles);
}
