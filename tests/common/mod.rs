//! Helpers shared by the integration tests.
#![allow(dead_code)]

use bpm::kernels::BondEntry;
use rand::{Rng, SeedableRng};

/// A random cloud of `n` points in a cube of side `l`, bonded within `cut`
/// (open boundaries), with reference lengths set to current lengths.
pub fn random_network(
    n: usize,
    l: f64,
    cut: f64,
    seed: u64,
) -> (Vec<[f64; 3]>, Vec<BondEntry>, Vec<f64>) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let x: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            [
                rng.gen::<f64>() * l,
                rng.gen::<f64>() * l,
                rng.gen::<f64>() * l,
            ]
        })
        .collect();
    let mut bonds = Vec::new();
    let mut r0 = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            let r = dist(&x[i], &x[j]);
            if r < cut && r > 0.3 {
                bonds.push(BondEntry {
                    i: i as i32,
                    j: j as i32,
                    ty: 1,
                });
                r0.push(r);
            }
        }
    }
    (x, bonds, r0)
}

/// Euclidean distance.
pub fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Random vectors with components in (-s, s).
pub fn random_rows(n: usize, s: f64, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            [
                rng.gen_range(-s..s),
                rng.gen_range(-s..s),
                rng.gen_range(-s..s),
            ]
        })
        .collect()
}

/// Largest absolute component.
pub fn max_abs(rows: &[[f64; 3]]) -> f64 {
    rows.iter()
        .flat_map(|r| r.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()))
}

/// The scratch folder `<tmp>/bpm-<name>-<pid>`, created if missing: one per
/// test binary and name, so parallel tests and runs do not collide.
pub fn scratch_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("bpm-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Every observable of a native-against-LAMMPS comparison of `name` within
/// its `trajectory` tolerance (a missing tolerance fails too).
#[cfg(feature = "lammps")]
pub fn assert_within_trajectory_tolerances(name: &str, deviations: &[bpm::verify::Deviation]) {
    for d in deviations {
        let tol = bpm::verify::tolerances::tolerance(&format!("trajectory {}", d.observable));
        assert!(tol > 0.0, "no tolerance for {}", d.observable);
        assert!(
            d.max_deviation <= tol,
            "{name}: {} deviates by {:e} at step {} (tolerance {tol:e})",
            d.observable,
            d.max_deviation,
            d.at_step
        );
    }
}
