//! The contact pass with the general minimum image against the one of an
//! untilted box (`OrthogonalImage`), on one thread, on the same neighbour
//! list in one process: rounds of `passes` passes, each image in turn
//! (general first), printing ns per particle-pass, the listed pairs and
//! the touching ones, and requiring the same forces bit for bit from each
//! round's last pass.
//!
//! The system is a scene file, such as the state late in a compaction
//! (`bpm run ... --final-scene`; results/bench/issue33-contact-image has
//! the commands), or the bench's compaction packing (32 smoother grains
//! of R = 3 d, seed 1) squeezed affinely by `squeeze` (linear) so that
//! grains touch.
//!
//!     cargo run --release --example contact_image -- late.json 0 2000 5
//!     cargo run --release --example contact_image -- packing 0.05 2000 5
//!
//! Arguments: a scene file or `packing`, the squeeze, passes per round,
//! rounds.

use bpm::kernels::{pair_forces, OrthogonalImage, Ownership, PairInputs, Separation};
use bpm::scene::builders::grain::GrainKind;
use bpm::scene::builders::packing::{build_packing, PackingParams};
use bpm::scene::{build_system, Scene, StageSpec};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [system, squeeze, passes, rounds] = &args[..] else {
        anyhow::bail!("arguments: SCENE.json|packing SQUEEZE PASSES ROUNDS");
    };
    let squeeze: f64 = squeeze.parse()?;
    let (passes, rounds): (usize, usize) = (passes.parse()?, rounds.parse()?);
    let mut scene: Scene = if system.ends_with(".json") {
        serde_json::from_str(&std::fs::read_to_string(system)?)?
    } else {
        let params = PackingParams::new(32, GrainKind::Smoother, 3.0, 0.0, 1);
        build_packing(&params, 1, false)?.0
    };
    scene.stages = vec![StageSpec::hold("contacts", 1, 0.1)];
    let mut sys = build_system(&scene, 1);
    let mut squeezed = sys.simbox.clone();
    squeezed.resize_about_centre(
        sys.simbox.lengths.map(|l| l * (1.0 - squeeze)),
        sys.simbox.tilt.map(|t| t * (1.0 - squeeze)),
    );
    sys.remap_into(squeezed);
    let Some(coeffs) = scene.force_field.pair else {
        anyhow::bail!("the scene has no contacts");
    };
    sys.neighbours.build(
        &sys.simbox,
        &sys.particles.x,
        coeffs.d,
        sys.skin,
        sys.model.exclusions(),
    );
    let general = sys.simbox.minimum_image();
    let Some(orthogonal) = OrthogonalImage::of(&general) else {
        anyhow::bail!("the box is tilted: there is no orthogonal image to compare");
    };
    let (x, v, list) = (&sys.particles.x, &sys.particles.v, &sys.neighbours);
    let coeffs = [coeffs];
    let inputs = PairInputs {
        x,
        v: (coeffs[0].gamma != 0.0).then_some(&v[..]),
        types: None,
        ntypes: 1,
        coeffs: &coeffs,
        special: [1.0; 4],
        tally: false,
        damping_taper: false,
    };
    let n = x.len();
    let touching = (0..n)
        .flat_map(|i| list.of(i).iter().map(move |&j| (i, j as usize)))
        .filter(|&(i, j)| general.distance(&x[i], &x[j]) < coeffs[0].d)
        .count();
    println!(
        "{n} particles, {} listed pairs, {touching} touching; {passes} passes per round",
        list.neighbours.len()
    );
    let mut forces = [vec![[0.0; 3]; n], vec![[0.0; 3]; n]];
    let time = |image: &dyn Fn(&mut [[f64; 3]]), f: &mut Vec<[f64; 3]>| {
        let start = std::time::Instant::now();
        for _ in 0..passes {
            f.fill([0.0; 3]);
            image(f);
        }
        start.elapsed().as_secs_f64() * 1e9 / (passes * n) as f64
    };
    let own = Ownership::all(n);
    let with_general = |f: &mut [[f64; 3]]| {
        pair_forces(&general, &inputs, list.rows(0..n), own, f);
    };
    let with_orthogonal = |f: &mut [[f64; 3]]| {
        pair_forces(&orthogonal, &inputs, list.rows(0..n), own, f);
    };
    for round in 0..rounds {
        let [a, b] = &mut forces;
        let slow = time(&with_general, a);
        let fast = time(&with_orthogonal, b);
        println!(
            "round {round}: general {slow:6.2} ns, orthogonal {fast:6.2} ns per particle-pass: {:.2}x",
            slow / fast
        );
        let bits = |f: &[[f64; 3]]| f.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
        anyhow::ensure!(bits(a) == bits(b), "the two images gave different forces");
    }
    Ok(())
}
