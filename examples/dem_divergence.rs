//! How fast LAMMPS's `pair_style granular` and the native DEM engine drift
//! apart on the same spheres (64 spheres, Hertz-Mindlin with sliding
//! friction 0.3, Tsuji damping e = 0.5), held, compressed, sheared
//! affinely and by Lees-Edwards boundaries (sliding friction only), and
//! squeezed between granular walls (sliding friction only; the closing
//! wall slowed so that it moves 0.4 d over the whole run), for `steps`
//! steps of 0.01 tau (default 20,000). Prints the largest relative
//! stress deviation and position deviation (d) every 10% of the run. Then
//! the same with rolling and twisting friction, at rest and drifting as a
//! whole at 0.58 d/tau: a uniform drift changes no relative motion, so the
//! rotational energy must not change with it.
//!
//!     cargo run --release --example dem_divergence -- 20000

use bpm::verify::{compare_runs, dem_trajectory, run_native, DemLoading, LammpsLauncher};

fn main() -> anyhow::Result<()> {
    let steps: u64 = std::env::args().nth(1).map_or(Ok(20_000), |s| s.parse())?;
    let launcher = LammpsLauncher::for_example("dem-divergence")?;
    let dir = launcher.dir.clone();
    println!(
        "{:<12} {:<8} {:>8} {:>12} {:>12}",
        "loading", "friction", "steps", "stress dev", "position dev"
    );
    let cases = [DemLoading::Hold, DemLoading::Compress, DemLoading::Shear]
        .map(|l| (false, l))
        .into_iter()
        .chain([(false, DemLoading::LeesEdwards), (false, DemLoading::Walls)])
        .chain([DemLoading::Hold, DemLoading::Compress, DemLoading::Shear].map(|l| (true, l)));
    for (rolling_twisting, loading) in cases {
        let friction = if rolling_twisting { "s+r+t" } else { "sliding" };
        for k in 1..=10u64 {
            let n = steps * k / 10;
            let mut scene = dem_trajectory(7, rolling_twisting, loading, n);
            if loading == DemLoading::Walls {
                let stage = &mut scene.stages[0];
                stage.granular_walls[1].velocity = -0.4 / (steps as f64 * stage.dt);
            }
            let tag = format!("{}-{friction}-{n}", loading.name());
            let native = run_native(&scene, &tag, 1)?;
            let lammps = launcher.run(&scene, &tag, 1, true)?;
            let devs = compare_runs(&native.stages, &lammps.stages)?;
            let get = |o: &str| {
                devs.iter()
                    .find(|d| d.observable == o)
                    .map_or(f64::NAN, |d| d.max_deviation)
            };
            println!(
                "{:<12} {:<8} {:>8} {:>12.3e} {:>12.3e}",
                loading.name(),
                friction,
                n,
                get("stress"),
                get("positions")
            );
        }
    }
    println!("\nrolling and twisting friction, held, at rest and drifting (rotational energy):");
    println!(
        "{:<8} {:>8} {:>14} {:>14} {:>14} {:>14}",
        "engine", "step", "at rest", "drifting", "rel. change", ""
    );
    let mut runs = Vec::new();
    for drift in [0.0, 0.5] {
        let mut scene = dem_trajectory(7, true, DemLoading::Hold, steps);
        for v in scene.particles.velocities.iter_mut().flatten() {
            v[0] += drift;
            v[1] += 0.6 * drift;
        }
        scene.stages[0].record.every = steps / 10;
        let tag = format!("drift{drift}");
        runs.push((
            run_native(&scene, &tag, 1)?,
            launcher.run(&scene, &tag, 1, true)?,
        ));
    }
    for (engine, pick) in [("native", 0), ("lammps", 1)] {
        let column = |k: usize| {
            let stage = if pick == 0 {
                &runs[k].0.stages[0]
            } else {
                &runs[k].1.stages[0]
            };
            (
                stage.column("step").unwrap_or_default(),
                stage.column("e_rotational").unwrap_or_default(),
            )
        };
        let ((step, rest), (_, drifting)) = (column(0), column(1));
        for k in 0..rest.len() {
            println!(
                "{engine:<8} {:>8} {:>14.6e} {:>14.6e} {:>14.3e}",
                step[k],
                rest[k],
                drifting[k],
                (drifting[k] - rest[k]).abs() / rest[k]
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
