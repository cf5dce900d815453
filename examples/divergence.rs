//! How fast LAMMPS and native trajectories of the same scene drift apart:
//! the contact solid and the grain pair, damped (the paper's Gamma = 1) and
//! undamped (Gamma = 0), for `steps` steps (default 20,000; the grains,
//! which fly apart after their collision, for an eighth of it). Prints the
//! largest relative stress deviation and position deviation (d) every
//! 10% of the run. The numbers justify `verify::tolerances`.
//!
//!     cargo run --release --example divergence -- 20000

use bpm::verify::{
    as_trajectory, compare_runs, contact_solid, grain_pair, run_native, LammpsLauncher,
};

fn main() -> anyhow::Result<()> {
    let steps: u64 = std::env::args().nth(1).map_or(Ok(20_000), |s| s.parse())?;
    let launcher = LammpsLauncher::for_example("divergence")?;
    let dir = launcher.dir.clone();
    let scenes = [
        ("contact solid L=8 a_B=-0.5", contact_solid(8.0, 1, -0.5)?),
        ("grain pair R=3 a_B=0.5", grain_pair(3.0, 1, 0.5)?),
    ];
    println!(
        "{:<28} {:<9} {:>8} {:>12} {:>12}",
        "scene", "damping", "steps", "stress dev", "position dev"
    );
    for (name, base) in scenes {
        let steps = if name.starts_with("grain") {
            steps / 8
        } else {
            steps
        };
        for damped in [true, false] {
            let mut scene = base.clone();
            if !damped {
                scene.force_field.bond.gamma = 0.0;
                if let Some(p) = scene.force_field.pair.as_mut() {
                    p.gamma = 0.0;
                }
            }
            for k in 1..=10u64 {
                let n = steps * k / 10;
                let s = as_trajectory(scene.clone(), n);
                let native = run_native(&s, name, 1)?;
                let lammps = launcher.run(&s, &format!("div-{k}-{damped}"), 1, true)?;
                let dev = compare_runs(&native.stages, &lammps.stages)?;
                let get = |o: &str| {
                    dev.iter()
                        .find(|d| d.observable == o)
                        .map_or(f64::NAN, |d| d.max_deviation)
                };
                println!(
                    "{:<28} {:<9} {:>8} {:>12.3e} {:>12.3e}",
                    name,
                    if damped { "Gamma=1" } else { "Gamma=0" },
                    n,
                    get("stress"),
                    get("positions")
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
