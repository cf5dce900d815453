//! What a checkpoint costs: a bonded solid of side L (about 1.2 L^3
//! particles) is stepped, then its state is saved and written as a run
//! checkpoint and read back, `repeats` times each, in one process. Prints
//! the file's size, the median seconds of a write and of a read, and how
//! many steps of the same solid each costs.
//!
//!     cargo run --release --example checkpoint_cost -- 20 5

use bpm::scene::builders::bulk::{build_bulk, BulkParams};
use bpm::scene::checkpoint::{scene_identity, RunCheckpoint};
use bpm::scene::{build_system, run_scene, ForceField, RunOptions, StageSpec};
use std::borrow::Cow;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let size: f64 = args.get(1).map_or(Ok(20.0), |a| a.parse())?;
    let repeats: usize = args.get(2).map_or(Ok(5), |a| a.parse())?;
    let (mut scene, _) = build_bulk(&BulkParams::shortened(size, 1, 0.0), 2, false)?;
    scene.force_field = ForceField::paper(0.5);
    let steps = 1000;
    scene.stages = vec![StageSpec::hold("hold", steps, 0.05)];
    let mut sys = build_system(&scene, 1);
    let start = Instant::now();
    let (_, error) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
    if let Some(e) = error {
        anyhow::bail!("the run failed: {e}");
    }
    let per_step = start.elapsed().as_secs_f64() / steps as f64;
    let dir = std::env::temp_dir().join(format!("bpm-checkpoint-cost-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("cost.ck");
    let (mut writes, mut reads) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        let t = Instant::now();
        let checkpoint = RunCheckpoint {
            scene: scene_identity(&scene),
            threads: 1,
            finished: Cow::Borrowed(&[]),
            current: None,
            engine: sys.save_state()?,
            thermo: None,
            dump: None,
            wall_seconds: 0.0,
            resumed_at: Vec::new(),
        };
        checkpoint.write(&path)?;
        writes.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        RunCheckpoint::read(&path, &scene, 1)?;
        reads.push(t.elapsed().as_secs_f64());
    }
    let bytes = std::fs::metadata(&path)?.len();
    std::fs::remove_dir_all(&dir)?;
    let (write, read) = (median(writes), median(reads));
    println!(
        "{} particles, {} bonds: checkpoint {:.2} MB ({:.0} bytes per particle); write {:.3} s = {:.0} steps, read {:.3} s = {:.0} steps (one step {:.2} ms, 1 thread)",
        sys.len(),
        scene.bonds.pairs.len(),
        bytes as f64 / 1e6,
        bytes as f64 / sys.len() as f64,
        write,
        write / per_step,
        read,
        read / per_step,
        per_step * 1e3
    );
    Ok(())
}
