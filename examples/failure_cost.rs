//! What bonds that can break and yield cost: the same system in one
//! process, rounds of `steps` steps in turn with elastic bonds, bonds that
//! break (eps_c = 0.5, smoothed) and bonds that also yield (eps_p = 0.2),
//! none of which breaks or yields at the 0.1% strain applied, so all three
//! compute the same bonds. Prints ns per particle-step for the whole step
//! and the bond pass, then the median over rounds of each round's step
//! time over its elastic round's (round 0 is a warm-up). The system is the bench's compaction packing (32
//! smoother grains of R = 3 d, seed 1) in `copies` copies per side.
//!
//!     cargo run --release --example failure_cost -- 1 -0.5 1 400 31
//!
//! Arguments: copies per side, a_B, threads, steps per round, rounds;
//! `unsmoothed` last turns the smoothing off in both failing modes.

use bpm::engine::{BpmModel, Stage, StageDrivers};
use bpm::kernels::BondFailure;
use bpm::scene::builders::grain::GrainKind;
use bpm::scene::builders::packing::{build_packing, PackingParams};
use bpm::scene::builders::replicate::replicate;
use bpm::scene::{build_system, ForceField, StageSpec};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (args, smooth) = match &args[..] {
        [first @ .., last] if last == "unsmoothed" => (first, false),
        all => (all, true),
    };
    let [copies, a_b, threads, steps, rounds] = args else {
        anyhow::bail!("arguments: COPIES A_B THREADS STEPS ROUNDS [unsmoothed]");
    };
    let (copies, a_b, threads): (usize, f64, usize) =
        (copies.parse()?, a_b.parse()?, threads.parse()?);
    let (steps, rounds): (u64, usize) = (steps.parse()?, rounds.parse()?);
    let params = PackingParams::new(32, GrainKind::Smoother, 3.0, 0.0, 1);
    let mut scene = replicate(&build_packing(&params, threads, false)?.0, [copies; 3])?;
    scene.force_field = ForceField::paper(a_b);
    scene.stages = vec![StageSpec::hold("cost", 1, 0.1)];
    let mut sys = build_system(&scene, threads);
    let mut strained = sys.simbox.clone();
    strained.resize_about_centre(sys.simbox.lengths.map(|l| l * 0.999), [0.0; 3]);
    sys.remap_into(strained);
    let drivers = StageDrivers {
        dt: 0.1,
        ..StageDrivers::default()
    };
    let stage_box = sys.simbox.clone();
    sys.setup(&drivers)?;
    let n = sys.len();
    println!(
        "{n} particles, {} bonds, a_B = {a_b}, {threads} thread(s), {steps} steps per round{}",
        scene.bonds.pairs.len(),
        if smooth { "" } else { ", unsmoothed" }
    );
    let breaking = BondFailure {
        smooth,
        ..BondFailure::breaking(0.5)
    };
    let modes = [
        ("elastic", None),
        ("breaking", Some(breaking)),
        (
            "yielding",
            Some(BondFailure {
                plastic_strain: Some(0.2),
                ..breaking
            }),
        ),
    ];
    let mut step = 0;
    // Per-round step ratios to the elastic round, from round 1 on: rounds
    // are short and the machine shared, so the ratio within a round moves
    // less than the times themselves.
    let mut ratios = [vec![], vec![]];
    for round in 0..rounds {
        let mut elastic = f64::NAN;
        for (name, failure) in modes {
            let mut field = scene.force_field.bpm();
            field.failure = failure;
            let model = sys.model_as_mut::<BpmModel>().expect("a bonded scene");
            model.set_force_field(field, n);
            for _ in 0..5 {
                step += 1;
                sys.step(&drivers, step, &stage_box)?;
            }
            sys.timers = Default::default();
            let start = std::time::Instant::now();
            for _ in 0..steps {
                step += 1;
                sys.step(&drivers, step, &stage_box)?;
            }
            let per = |secs: f64| secs * 1e9 / (steps as f64 * n as f64);
            let step_ns = per(start.elapsed().as_secs_f64());
            match name {
                "elastic" => elastic = step_ns,
                _ if round > 0 => ratios[usize::from(name == "yielding")].push(step_ns / elastic),
                _ => {}
            }
            let broken = sys
                .model_as::<BpmModel>()
                .map_or(0, |m| m.broken_bonds().len());
            println!(
                "round {round} {name:<9} step {:6.1} ns, bonds {:6.1} ns, volumes {:5.1} ns, broken {broken}",
                step_ns,
                per(sys.timers.total(Stage::Bonds).as_secs_f64()),
                per(sys.timers.total(Stage::Volumes).as_secs_f64()),
            );
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let [breaking, yielding] = &mut ratios;
    println!(
        "median over rounds 1 to {}: step breaking / elastic {:.3}, yielding / elastic {:.3}",
        rounds.saturating_sub(1),
        median(breaking),
        median(yielding)
    );
    Ok(())
}
