//! What the squeeze saves by not searching for pairs that cannot touch: a
//! lone smoother grain squeezed to delta/R = 0.1 with the neighbour list's
//! rebuild test discounting the grain's rigid motion (the default) and
//! without, alternately, `repeats` times each, in the same process. Both
//! give bitwise the same force curve (checked here); the report is the
//! ratio of the medians of their wall-clock times, the neighbour-list
//! builds and the per-stage times.
//!
//!     cargo run --release --example squeeze_neighbours -- 8 3

use bpm::scene::builders::grain::{build_grain, GrainKind, GrainParams};
use bpm::scene::protocols::{hertz_squeeze, SqueezeParams};
use bpm::scene::{build_system, run_scene, ForceField, RunOptions, StageOutput};

fn squeeze(scene: &bpm::scene::Scene, follow: bool) -> anyhow::Result<(f64, StageOutput)> {
    let mut sys = build_system(scene, 1);
    sys.neighbours.follow_rigid_motion = follow;
    let start = std::time::Instant::now();
    let (mut stages, err) = run_scene(&mut sys, scene, &RunOptions::quiet(1));
    if let Some(e) = err {
        anyhow::bail!("squeeze failed: {e}");
    }
    Ok((start.elapsed().as_secs_f64(), stages.remove(0)))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let radius: f64 = args.next().map_or(Ok(8.0), |s| s.parse())?;
    let repeats: usize = args.next().map_or(Ok(3), |s| s.parse())?;
    let mut params = GrainParams::new(GrainKind::Smoother, radius, 1, 0.0);
    params.time_scale = 0.1;
    let (mut grain, summary) = build_grain(&params, 1, false)?;
    grain.force_field = ForceField::paper(0.0);
    let scene = hertz_squeeze(&grain, &SqueezeParams::paper(radius, 0.1));
    println!(
        "smoother grain R = {radius} (seed 1, build time scale 0.1): {} particles, a_B = 0, squeezed to delta/R = 0.1",
        summary.particles
    );
    let (mut on, mut off) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        for follow in [true, false] {
            let (secs, stage) = squeeze(&scene, follow)?;
            let label = if follow {
                "rigid motion discounted"
            } else {
                "plain displacement"
            };
            println!(
                "  {label:>24}: {secs:6.2} s, {:4} list builds, neighbours {:.2} s, pairs {:.2} s",
                stage.neighbour_builds, stage.timers["neighbours"], stage.timers["pairs"]
            );
            if follow {
                on.push((secs, stage))
            } else {
                off.push((secs, stage))
            }
        }
    }
    let same = on.iter().zip(&off).all(|(a, b)| a.1.rows == b.1.rows);
    anyhow::ensure!(same, "the two rebuild tests gave different squeezes");
    let (t_on, t_off) = (
        median(on.iter().map(|s| s.0).collect()),
        median(off.iter().map(|s| s.0).collect()),
    );
    println!(
        "median {t_on:.2} s against {t_off:.2} s: {:.3}x the time, {:.1}% saved; records identical",
        t_on / t_off,
        100.0 * (1.0 - t_on / t_off)
    );
    Ok(())
}
