//! Grain builders: a rough and a smoother grain cut from the same packing.

use bpm::scene::builders::grain::{build_grain, GrainKind, GrainParams};

fn grain(kind: GrainKind) -> (bpm::scene::Scene, bpm::scene::builders::grain::GrainSummary) {
    let mut p = GrainParams::new(kind, 4.0, 7, 0.0);
    p.time_scale = 0.25;
    build_grain(&p, 1, false).unwrap()
}

#[test]
fn rough_and_smoother_grains_are_bonded_spheres_and_vibration_smooths_the_surface() {
    let (rough, rs) = grain(GrainKind::Rough);
    let (smooth, ss) = grain(GrainKind::Smoother);
    eprintln!("rough {rs:?}\nsmoother {ss:?}");
    // Same cut: same particles (the vibration moves, never adds or drops).
    assert_eq!(rs.particles, ss.particles);
    // A sphere of radius 4 d at volume fraction 0.64: about 0.64 (4/3 pi
    // 4^3) / (pi / 6) = 328 particles.
    let expected = 0.64 * 4.0 / 3.0 * 64.0 * 6.0;
    assert!(
        (rs.particles as f64 - expected).abs() < 0.15 * expected,
        "{} particles, expected about {expected}",
        rs.particles
    );
    for (s, summary) in [(&rough, &rs), (&smooth, &ss)] {
        bpm::scene::validate::validate(&{
            let mut run = s.clone();
            run.stages = vec![bpm::scene::StageSpec::hold("hold", 10, 0.1)];
            run
        })
        .unwrap();
        // Interior particles have about 15 bonds, surface ones fewer.
        assert!(
            summary.mean_bonds_per_particle > 9.0 && summary.mean_bonds_per_particle < 15.5,
            "{summary:?}"
        );
        assert!(!s.simbox.periodic.iter().any(|&p| p));
        assert!(summary.roughness.max_distance < 4.0 + 1.5);
    }
    // The cage reorders the surface: the spread of surface heights drops.
    assert!(
        ss.roughness.sd_height < rs.roughness.sd_height,
        "smoother {:?} vs rough {:?}",
        ss.roughness,
        rs.roughness
    );
}
