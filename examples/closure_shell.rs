//! How the multi-contact closure's correction depends on Poisson's ratio
//! at one geometry: a sphere (R = 1) with N equal contacts spread evenly
//! over its surface (Fibonacci points, each 0.03 R deep), E = 1, every
//! contact's force E_eff = E / (2 (1 - nu^2)) (so forces follow the
//! normalised pressure, as in a compaction at the same volume fraction),
//! standard closure with gamma = 1. Prints the mean correction over the
//! contacts, in units of R.
//!
//! `cargo run --release --example closure_shell > results/mcdem/calibration/shell.txt`

use bpm::kernels::{surface_corrections, Closure, ContactPoint, HalfSpace};

fn main() {
    let radius = 1.0;
    let ratios = [-0.1, 0.0, 0.25, 0.4];
    println!("# mean standard-closure correction / R, gamma = 1, E = 1, contact forces E_eff = E / (2 (1 - nu^2))");
    print!("{:>10}", "contacts");
    for nu in ratios {
        print!("{:>12}", format!("nu = {nu}"));
    }
    println!();
    for n in [2usize, 4, 6, 8, 10, 12] {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let directions: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let rho = (1.0 - z * z).sqrt();
                let phi = i as f64 * golden;
                [rho * phi.cos(), rho * phi.sin(), z]
            })
            .collect();
        print!("{n:>10}");
        for nu in ratios {
            let force = 1.0 / (2.0 * (1.0 - nu * nu));
            let half_space = HalfSpace::new(1.0, 1.0, nu);
            let contacts: Vec<ContactPoint> = directions
                .iter()
                .map(|d| ContactPoint::new(d.map(|c| 0.97 * radius * c), force, radius))
                .collect();
            let mut corrections = vec![0.0; n];
            surface_corrections(
                &half_space,
                &Closure::Standard,
                radius,
                &contacts,
                &mut corrections,
            );
            print!("{:>12.4}", corrections.iter().sum::<f64>() / n as f64);
        }
        println!();
    }
}
