//! The bond pass in windows against the full-size array of rows, on the
//! same system in one process: rounds of `steps` steps, each mode in turn
//! (full-size first), printing ns per particle-step for the whole step and
//! the bond pass, and the window's ring and halo. The system is the bench's
//! compaction packing (32 smoother grains of R = 3 d, seed 1) in `copies`
//! copies per side, or a scene file (such as a compaction study's
//! `seed-N/scene.json`), strained by 0.1% so the bonds carry force.
//!
//!     cargo run --release --example bond_window -- 4 0 2 40 6
//!     cargo run --release --example bond_window -- path/to/scene.json 0 2 10 4
//!
//! Arguments: copies per side or a scene file, a_B, threads, steps per
//! round, rounds.

use bpm::engine::{BondWindow, BpmModel, Stage, StageDrivers};
use bpm::scene::builders::grain::GrainKind;
use bpm::scene::builders::packing::{build_packing, PackingParams};
use bpm::scene::builders::replicate::replicate;
use bpm::scene::{build_system, ForceField, Scene, StageSpec};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [system, a_b, threads, steps, rounds] = &args[..] else {
        anyhow::bail!("arguments: COPIES|SCENE.json A_B THREADS STEPS ROUNDS");
    };
    let (a_b, threads): (f64, usize) = (a_b.parse()?, threads.parse()?);
    let (steps, rounds): (u64, usize) = (steps.parse()?, rounds.parse()?);
    let mut scene: Scene = if system.ends_with(".json") {
        serde_json::from_str(&std::fs::read_to_string(system)?)?
    } else {
        let copies: usize = system.parse()?;
        let params = PackingParams::new(32, GrainKind::Smoother, 3.0, 0.0, 1);
        replicate(&build_packing(&params, threads, false)?.0, [copies; 3])?
    };
    scene.force_field = ForceField::paper(a_b);
    scene.stages = vec![StageSpec::hold("window", 1, 0.1)];
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
    println!(
        "{} particles, {} bonds, a_B = {a_b}, {threads} thread(s), {steps} steps per round",
        sys.len(),
        scene.bonds.pairs.len()
    );
    let mut step = 0;
    for round in 0..rounds {
        for mode in [BondWindow::Never, BondWindow::Always] {
            let model = sys.model_as_mut::<BpmModel>().expect("a bonded scene");
            model.set_bond_window(mode);
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
            let per = |secs: f64| secs * 1e9 / (steps as f64 * sys.len() as f64);
            let window = sys.model_as::<BpmModel>().and_then(|m| m.bond_window());
            println!(
                "round {round} {:<7} step {:6.1} ns, bonds {:6.1} ns, volumes {:5.1} ns; window {}",
                format!("{mode:?}"),
                per(start.elapsed().as_secs_f64()),
                per(sys.timers.total(Stage::Bonds).as_secs_f64()),
                per(sys.timers.total(Stage::Volumes).as_secs_f64()),
                window.map_or("none".into(), |(ring, halo)| format!(
                    "ring {ring} rows, halo {:.2}%",
                    100.0 * halo
                )),
            );
        }
    }
    Ok(())
}
