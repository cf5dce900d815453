//! How fast two engines' trajectories of one scene drift apart, against
//! how fast the native engine drifts from itself when one coordinate moves
//! by one unit in the last place: if the two grow alike, the engines differ
//! by round-off only, amplified by the dynamics (contacts forming and
//! sliding), and a cross-check can hold to round-off only up to the step
//! where the growth reaches the tolerances. Runs the scene natively, through
//! LAMMPS with the plugin (1 rank, newton off, as the closure needs), and
//! natively with the first sphere's x multiplied by 1 + 2^-52; prints the
//! largest relative deviation of the stress, the wall forces and the
//! multi-contact corrections up to each tenth of the run.
//!
//!     cargo run --release --example closure_divergence -- SCENE.json

use bpm::scene::{read_scene, StageOutput};
use bpm::verify::{compare_runs, run_native, LammpsLauncher};

/// The rows of `stages` up to step `last` (rows record the step count from
/// the scene's start), stages without any dropped.
fn up_to(stages: &[StageOutput], last: f64) -> Vec<StageOutput> {
    stages
        .iter()
        .map(|s| {
            let mut s = s.clone();
            s.rows.retain(|r| r[0] <= last);
            s.checkpoints.clear();
            s
        })
        .filter(|s| !s.rows.is_empty())
        .collect()
}

fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .ok_or_else(|| anyhow::anyhow!("usage: closure_divergence SCENE.json"))?;
    let (scene, _) = read_scene(std::path::Path::new(&path))?;
    let launcher = LammpsLauncher::for_example("closure-divergence")?;
    let dir = launcher.dir.clone();
    let native = run_native(&scene, "native", 1)?;
    let lammps = launcher.run(&scene, "lammps", 1, false)?;
    let mut nudged = scene.clone();
    nudged.particles.positions[0][0] *= 1.0 + f64::EPSILON;
    let nudged = run_native(&nudged, "nudged", 1)?;
    let total: u64 = scene.stages.iter().map(|s| s.steps).sum();
    let observables = ["stress", "wall forces", "multi-contact corrections"];
    println!("scene: {path} ({total} steps)");
    println!(
        "largest relative deviation from the native run up to each step: LAMMPS (1 rank) | native with one coordinate one ulp off"
    );
    print!("{:>8}", "step");
    for o in observables {
        print!(" | {:>26}", o);
    }
    println!();
    for k in 1..=10 {
        let last = (total * k / 10) as f64;
        let reference = up_to(&native.stages, last);
        let deviation = |run: &[StageOutput], o: &str| -> anyhow::Result<f64> {
            Ok(compare_runs(&reference, &up_to(run, last))?
                .iter()
                .find(|d| d.observable == o)
                .map_or(f64::NAN, |d| d.max_deviation))
        };
        print!("{last:>8}");
        for o in observables {
            print!(
                " | {:>12.2e} {:>12.2e}",
                deviation(&lammps.stages, o)?,
                deviation(&nudged.stages, o)?
            );
        }
        println!();
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
