//! The large-compression study on a small solid and grain: both reach the
//! target strain with nothing lost, the pressure rises with the strain,
//! and a compression at a timestep above the stable limit is reported as
//! failed rather than as a result.

use bpm::studies::large_strain::{run_large_strain, LargeStrainOptions};

fn small(a_b: f64, rate: f64, wall_speed: f64) -> LargeStrainOptions {
    LargeStrainOptions {
        a_b: vec![a_b],
        volumetric_strain: 0.3,
        size: 5.0,
        rate,
        radius: 3.0,
        wall_speed,
        chunks: 6,
        ..LargeStrainOptions::default()
    }
}

#[test]
fn a_small_solid_and_grain_reach_the_strain_with_rising_pressure() {
    let report = run_large_strain(&small(0.0, 1e-3, 5e-3), 1, "test", &mut |_| {}).unwrap();
    assert_eq!(report.compressions.len(), 2);
    for c in &report.compressions {
        assert!(c.complete, "{}: {:?}", c.body, c.failure);
        assert_eq!(c.states.len(), 7, "{}: the start and six chunks", c.body);
        let last = c.states.last().unwrap();
        // The box is measured; the grain's strain follows from the wall's
        // programmed travel, so only the bulk's can miss.
        if c.body == "bulk" {
            assert!(
                (last.imposed_strain - 0.3).abs() < 0.02,
                "bulk: imposed strain {}",
                last.imposed_strain
            );
        }
        // Compressed bonds: the bonds' own volume measure follows.
        assert!(last.bond_strain > 0.05, "{}: {}", c.body, last.bond_strain);
        for pair in c.states.windows(2).skip(1) {
            assert!(
                pair[1].pressure > pair[0].pressure,
                "{}: pressure fell from {} to {}",
                c.body,
                pair[0].pressure,
                pair[1].pressure
            );
        }
    }
}

#[test]
fn a_compression_at_an_unstable_timestep_is_a_failure_not_a_result() {
    // dt = 0.3 tau is above the damped limit (about 0.18 tau, results/stability).
    let mut opts = small(0.0, 1e-3, 5e-3);
    opts.radius = 0.0;
    opts.dt = 0.3;
    let report = run_large_strain(&opts, 1, "test", &mut |_| {}).unwrap();
    let c = &report.compressions[0];
    assert!(!c.complete, "expected a failure, got {:?}", c.states.last());
    let failure = c.failure.as_deref().unwrap_or_default();
    assert!(failure.contains("timestep"), "{failure}");
}
