//! The LIGGGHTS tutorial's bed (514 hydrogel beads under the closing lid),
//! the first `steps` steps of the lid's pass with one contact law (the
//! scene `bpm bench` times against LIGGGHTS), on `threads`: prints the stage's wall time, ns per particle-step and the
//! engine's pass timers. A target for `perf record` and callgrind.
//!
//!     cargo run --release --example bed_profile -- closure 30000 1

use bpm::scene::{build_system, run_scene, RunOptions};
use bpm::studies::bench::native_scene;
use bpm::verify::liggghts::{write_tutorial_bed, LiggghtsLaw};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let law = match args.get(1).map(String::as_str) {
        None | Some("hertz") => LiggghtsLaw::Hertz,
        Some("closure") => LiggghtsLaw::Closure,
        Some(other) => anyhow::bail!("law {other}: hertz or closure"),
    };
    let steps: u64 = args.get(2).map_or(Ok(30_000), |a| a.parse())?;
    let threads: usize = args.get(3).map_or(Ok(1), |a| a.parse())?;
    let work = std::env::temp_dir().join(format!("bpm-bed-profile-{}", std::process::id()));
    let bed = write_tutorial_bed(&work, "input.data")?;
    let scene = native_scene(&bed, law, steps)?;
    let mut sys = build_system(&scene, threads);
    let (stages, error) = run_scene(&mut sys, &scene, &RunOptions::quiet(threads));
    std::fs::remove_dir_all(&work).ok();
    if let Some(e) = error {
        anyhow::bail!("the run failed: {e}");
    }
    let stage = &stages[0];
    let particles = sys.particles.len() as f64;
    println!(
        "{} {steps} steps on {threads} thread(s): {:.3} s, {:.1} ns per particle-step",
        law.name(),
        stage.wall_seconds,
        stage.wall_seconds / (steps as f64 * particles) * 1e9
    );
    println!("timers: {:?}", stage.timers);
    if let Some(dem) = sys.model_as::<bpm::engine::DemModel>() {
        let touching = dem
            .contacts()
            .history
            .iter()
            .filter(|h| h.normal_force != 0.0)
            .count();
        println!("touching pairs at the end: {touching}");
    }
    let radii = &sys.particles.radius;
    let rmax = radii.iter().cloned().fold(0.0, f64::max);
    println!(
        "pair list: {} entries ({:.1} per particle), skin {:.3e} (largest radius {rmax:.3e}), {} builds",
        sys.neighbours.neighbours.len(),
        sys.neighbours.neighbours.len() as f64 / particles,
        sys.skin,
        stage.neighbour_builds
    );
    Ok(())
}
