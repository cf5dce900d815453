//! Bonds that break and yield in the native engine: a rule that never acts
//! changes nothing, a broken pair becomes a contact the next step, the
//! multibody term stays balanced when a bond breaks and follows the rest
//! lengths when bonds yield, and broken bonds leave the bond arrays.

mod common;

use bpm::engine::{BpmModel, Deformation, StageDrivers};
use bpm::kernels::{pair_force_magnitude, BondFailure, PairCoeffs};
use bpm::scene::builders::bulk::{build_bulk, BulkParams};
use bpm::scene::{build_system, run_scene, ForceField, RunOptions, Scene, StageSpec};
use serde_json::json;
use std::sync::OnceLock;

/// A small relaxed bulk solid (L = 5 d, shortened build), built once.
fn small_solid() -> &'static Scene {
    static SOLID: OnceLock<Scene> = OnceLock::new();
    SOLID.get_or_init(|| {
        build_bulk(&BulkParams::shortened(5.0, 4, 0.0), 1, false)
            .expect("bulk build")
            .0
    })
}

fn unsmoothed(critical_strain: f64, plastic_strain: Option<f64>) -> BondFailure {
    BondFailure {
        smooth: false,
        plastic_strain,
        ..BondFailure::breaking(critical_strain)
    }
}

/// `scene` run to its end on `threads` threads.
fn ran(scene: &Scene, threads: usize) -> bpm::engine::System {
    let mut sys = build_system(scene, threads);
    let (_, error) = run_scene(&mut sys, scene, &RunOptions::quiet(threads));
    assert!(error.is_none(), "{error:?}");
    sys
}

fn final_positions(scene: &Scene, threads: usize) -> Vec<[f64; 3]> {
    ran(scene, threads).particles.x
}

#[test]
fn a_failure_rule_that_never_acts_leaves_an_elastic_run_bit_for_bit() {
    let mut scene = small_solid().clone();
    scene.force_field = ForceField::paper(-0.5);
    let mut hold = StageSpec::hold("hold", 300, 0.05);
    hold.set_velocities = Some(bpm::scene::VelocityInit { rms_speed: 0.05 });
    scene.stages = vec![hold];
    for threads in [1, 2] {
        let elastic = final_positions(&scene, threads);
        // Bonds that could break at 500% strain: the failing pass runs, and
        // no bond gets there.
        let mut failing = scene.clone();
        failing.force_field.bond_failure = Some(unsmoothed(5.0, None));
        assert_eq!(
            final_positions(&failing, threads),
            elastic,
            "{threads} threads"
        );
        let mut moved = failing.clone();
        moved.force_field.bond_failure = Some(unsmoothed(5.0, Some(1e-3)));
        assert_ne!(
            final_positions(&moved, threads),
            elastic,
            "yielding at 0.1% strain changes the run"
        );
    }
}

/// Two bonded particles `r` apart on the x axis, bond reference length 1,
/// contact distance 1; no damping.
fn pair_scene(r: f64, failure: BondFailure) -> Scene {
    let mut scene: Scene = serde_json::from_value(json!({
        "seed": 1,
        "box": {"lo": [0, 0, 0], "lengths": [6, 6, 6], "periodic": [true, true, true]},
        "particles": {"positions": [[2, 3, 3], [2.0 + r, 3, 3]]},
        "bonds": {"pairs": [[0, 1]], "r0": [1.0]},
        "force_field": {"bond": {"k": 1, "a": 0, "gamma": 0}, "pair": {"k": 1, "d": 1, "a": 50, "gamma": 0}},
        "stages": [{"name": "hold", "steps": 10, "dt": 0.01}]
    }))
    .unwrap();
    scene.force_field.bond_failure = Some(failure);
    bpm::scene::validate(&scene).unwrap();
    scene
}

/// The contact force of [`pair_scene`]'s contact law at distance `r`.
fn pair_scene_contact(r: f64) -> f64 {
    let contact = PairCoeffs {
        k: 1.0,
        d: 1.0,
        a: 50.0,
        gamma: 0.0,
    };
    pair_force_magnitude(r, 0.0, &contact)
}

#[test]
fn a_bond_broken_in_compression_is_a_contact_from_the_next_evaluation() {
    let scene = pair_scene(0.85, unsmoothed(0.1, None));
    let mut sys = build_system(&scene, 1);
    let drivers = StageDrivers {
        dt: 0.01,
        ..Default::default()
    };
    sys.setup(&drivers).unwrap();
    // The set-up evaluation breaks the bond (15% > 10%): no bond force,
    // and the pair was still excluded.
    assert_eq!(sys.particles.f[0], [0.0; 3]);
    let model = sys.model_as::<BpmModel>().unwrap();
    assert_eq!(model.broken_bonds(), &[[0, 1]]);
    assert!(model.bonds().is_empty());
    sys.compute_forces(&drivers, 0.0, true);
    let expected = pair_scene_contact(0.85);
    let f = sys.particles.f[0];
    assert!(
        (f[0] + expected).abs() < 1e-12 * expected && f[1] == 0.0 && f[2] == 0.0,
        "contact force {f:?}, expected {expected} pushing particle 0 towards -x"
    );
    // Steps on, through pair-list rebuilds, the two repel and separate.
    let start = sys.simbox.clone();
    for step in 1..=400 {
        sys.step(&drivers, step, &start).unwrap();
    }
    let r = sys.particles.x[1][0] - sys.particles.x[0][0];
    assert!(r > 1.0, "the contact pushed them apart to {r}");
}

/// With the contact law overlaid on the bonds (`overlay_pair`), a bonded
/// pair squeezed below the contact distance feels the bond and the contact
/// at once, and without it the bond alone. A bond that breaks under the
/// overlay leaves the contact acting once, not twice: the pair list held
/// the pair already. The overlay needs a contact law.
#[test]
fn an_overlaid_contact_acts_between_bonded_particles_and_once_after_a_break() {
    let drivers = StageDrivers {
        dt: 0.01,
        ..Default::default()
    };
    let pushed = pair_scene_contact(0.85);
    // Particle 0's force along x, at set-up and at the next evaluation.
    let forces = |critical_strain: f64, overlay: bool| {
        let mut scene = pair_scene(0.85, unsmoothed(critical_strain, None));
        scene.force_field.overlay_pair = overlay;
        let mut sys = build_system(&scene, 1);
        sys.setup(&drivers).unwrap();
        let first = sys.particles.f[0];
        sys.compute_forces(&drivers, 0.0, true);
        let second = sys.particles.f[0];
        assert!(first[1] == 0.0 && first[2] == 0.0 && second[1] == 0.0);
        (first[0], second[0])
    };
    let close = |got: f64, want: f64| (got - want).abs() <= 1e-12 * want.abs();
    // The bond (k (r0 - r) = 0.15) holds at 15% strain with eps_c = 0.5.
    let (bond_only, _) = forces(0.5, false);
    assert!(close(bond_only, -0.15), "{bond_only}");
    let (overlaid, _) = forces(0.5, true);
    assert!(
        close(overlaid, -0.15 - pushed),
        "{overlaid} against {}",
        -0.15 - pushed
    );
    // With eps_c = 0.1 it breaks at set-up: the overlaid contact acts at
    // once and then alone; without the overlay, from the next evaluation.
    let (at_break, after) = forces(0.1, true);
    assert!(
        close(at_break, -pushed) && close(after, -pushed),
        "{at_break}, {after}"
    );
    let (at_break, after) = forces(0.1, false);
    assert!(
        at_break == 0.0 && close(after, -pushed),
        "{at_break}, {after}"
    );
    let mut scene = pair_scene(0.85, unsmoothed(0.5, None));
    scene.force_field.overlay_pair = true;
    scene.force_field.pair = None;
    let err = bpm::scene::validate(&scene).unwrap_err().to_string();
    assert!(err.contains("force_field.overlay_pair"), "{err}");
}

#[test]
fn a_stretched_bond_breaks_on_the_step_its_strain_passes_the_critical_strain() {
    // Pulled apart at 0.2 d/tau each: the bond breaks once r > 1.1.
    let mut scene = pair_scene(1.0, unsmoothed(0.1, None));
    scene.particles.velocities = Some(vec![[-0.2, 0.0, 0.0], [0.2, 0.0, 0.0]]);
    let mut sys = build_system(&scene, 1);
    let drivers = StageDrivers {
        dt: 0.01,
        ..Default::default()
    };
    sys.setup(&drivers).unwrap();
    let start = sys.simbox.clone();
    let mut broke_at = None;
    for step in 1..=200 {
        let before = sys.particles.x[1][0] - sys.particles.x[0][0];
        sys.step(&drivers, step, &start).unwrap();
        let model = sys.model_as::<BpmModel>().unwrap();
        if broke_at.is_none() && !model.broken_bonds().is_empty() {
            // A step moves the particles, then evaluates forces there.
            let r = sys.particles.x[1][0] - sys.particles.x[0][0];
            assert!(
                r > 1.1 && before <= 1.1,
                "broke at r = {r}, before {before}"
            );
            broke_at = Some(step);
        }
    }
    assert!(broke_at.is_some(), "the bond never broke");
    // Free flight after the break: no bond, no contact (r > d).
    let v = sys.particles.v[1][0] - sys.particles.v[0][0];
    assert!(v > 0.0, "still separating at {v}");
}

#[test]
fn breaking_a_bond_of_a_relaxed_solid_leaves_no_multibody_force() {
    // Every bond of the built solid is at its reference length but bond 0,
    // whose reference length makes its strain 20%: it breaks at set-up.
    let mut scene = small_solid().clone();
    scene.force_field = ForceField::paper(-0.5);
    scene.force_field.pair = None;
    scene.force_field.bond_failure = Some(unsmoothed(0.1, None));
    let mut r0 = bpm::scene::load::reference_lengths(&scene);
    r0[0] /= 1.2;
    scene.bonds.r0 = Some(r0.clone());
    scene.stages = vec![StageSpec::hold("hold", 1, 0.05)];
    let mut sys = build_system(&scene, 1);
    let drivers = StageDrivers {
        dt: 0.05,
        ..Default::default()
    };
    sys.setup(&drivers).unwrap();
    assert_eq!(sys.model_as::<BpmModel>().unwrap().broken_bonds().len(), 1);
    sys.compute_forces(&drivers, 0.0, true);
    let after_break = sys.particles.f.clone();
    let largest = common::max_abs(&after_break);
    assert!(largest < 1e-13, "largest force after the break {largest}");
    // The same as the solid built without that bond, bit for bit.
    let mut without = scene.clone();
    without.bonds.pairs.remove(0);
    r0.remove(0);
    without.bonds.r0 = Some(r0);
    let mut reference = build_system(&without, 1);
    reference.setup(&drivers).unwrap();
    assert_eq!(after_break, reference.particles.f);
    // The reference volumes are those of the bonds left, and differ from
    // the scene's with the broken bond where it was: without the update the
    // two particles would feel the multibody term.
    let model = sys.model_as::<BpmModel>().unwrap();
    let left = reference.model_as::<BpmModel>().unwrap();
    assert_eq!(model.volumes().1, left.volumes().1);
    let mut whole = scene.clone();
    whole.force_field.bond_failure = None;
    let whole = build_system(&whole, 1);
    let with_it = whole.model_as::<BpmModel>().unwrap().volumes().1;
    let [i, j] = scene.bonds.pairs[0];
    for p in [i, j] {
        assert!(with_it[p] > model.volumes().1[p], "V0 of particle {p}");
    }
}

/// A regular tetrahedron of edge 1 flying apart radially at `speed`: every
/// bond stretches alike.
fn tetrahedron(speed: f64, failure: BondFailure) -> Scene {
    let s = 1.0 / 8f64.sqrt();
    let corners = [[s, s, s], [s, -s, -s], [-s, s, -s], [-s, -s, s]];
    let positions: Vec<[f64; 3]> = corners.iter().map(|c| c.map(|v| v + 4.0)).collect();
    let velocities: Vec<[f64; 3]> = corners
        .iter()
        .map(|c| c.map(|v| v * speed / (s * 3f64.sqrt())))
        .collect();
    let mut scene: Scene = serde_json::from_value(json!({
        "seed": 1,
        "box": {"lo": [0, 0, 0], "lengths": [8, 8, 8], "periodic": [true, true, true]},
        "particles": {"positions": positions, "velocities": velocities},
        "bonds": {"pairs": [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]},
        "force_field": {"bond": {"k": 1, "a": -0.5, "gamma": 1}},
        "stages": [{"name": "fly", "steps": 4000, "dt": 0.02}]
    }))
    .unwrap();
    scene.force_field.bond_failure = Some(failure);
    bpm::scene::validate(&scene).unwrap();
    scene
}

#[test]
fn a_plastically_stretched_grain_comes_to_rest_at_its_new_rest_length_with_no_force() {
    let rule = BondFailure {
        breaks: false,
        ..unsmoothed(0.5, Some(0.05))
    };
    let scene = tetrahedron(0.3, rule);
    let mut sys = build_system(&scene, 1);
    let (_, error) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
    assert!(error.is_none(), "{error:?}");
    let model = sys.model_as::<BpmModel>().unwrap();
    let plastic = model.plastic_strains();
    assert!(
        plastic.iter().all(|&e| e > 0.01),
        "every bond yielded: {plastic:?}"
    );
    let x = &sys.particles.x;
    for ((bond, e_p), r0) in model
        .bonds()
        .entries
        .iter()
        .zip(&plastic)
        .zip(&model.bonds().r0)
    {
        let r = common::dist(&x[bond.i as usize], &x[bond.j as usize]);
        let rest = r0 * (1.0 + e_p);
        assert!(
            (r - rest).abs() < 1e-9,
            "length {r} against rest length {rest}"
        );
    }
    let largest = common::max_abs(&sys.particles.f);
    assert!(largest < 1e-9, "largest force at rest {largest}");
    let speed = common::max_abs(&sys.particles.v);
    assert!(speed < 1e-9, "largest speed at rest {speed}");
}

#[test]
fn bonds_that_break_leave_the_arrays_and_the_broken_count_grows_with_stretch() {
    let mut scene = small_solid().clone();
    scene.force_field = ForceField::paper(-0.5);
    scene.force_field.bond_failure = Some(BondFailure::breaking(0.03));
    let mut pull = StageSpec::hold("pull", 1000, 0.05);
    pull.deformation = Some(Deformation::Isotropic {
        true_strain_rate: 1e-3,
    });
    scene.stages = vec![pull];
    let total = scene.bonds.pairs.len();
    let sys = ran(&scene, 2);
    let model = sys.model_as::<BpmModel>().unwrap();
    let broken = model.broken_bonds().len();
    assert!(
        broken > total / 10,
        "{broken} of {total} bonds broke at 5% strain"
    );
    assert_eq!(model.bonds().len() + broken, total);
    for [i, j] in model.broken_bonds() {
        assert!(!model.bonds().bonded(*i, *j), "{i}-{j} is still bonded");
    }
    // The same run on one thread breaks the same bonds in the same order.
    assert_eq!(
        ran(&scene, 1)
            .model_as::<BpmModel>()
            .unwrap()
            .broken_bonds(),
        model.broken_bonds()
    );
    // The list keeps the order the bonds broke in: the same pull stopped
    // earlier broke the list's first bonds, and the bonds standing then are
    // the bonds intact at the end and the list's rest (what `bpm crush`
    // counts its fragments at an earlier overlap from).
    let mut early_scene = scene.clone();
    early_scene.stages[0].steps = 600;
    let early = ran(&early_scene, 2);
    let early = early.model_as::<BpmModel>().unwrap();
    let count = early.broken_bonds().len();
    assert!(
        count > 0 && count < broken,
        "{count} of {broken} broke by step 600"
    );
    assert_eq!(early.broken_bonds(), &model.broken_bonds()[..count]);
    let pairs = |bonds: &mut dyn Iterator<Item = [usize; 2]>| {
        let mut p: Vec<[usize; 2]> = bonds.map(|[i, j]| [i.min(j), i.max(j)]).collect();
        p.sort_unstable();
        p
    };
    assert_eq!(
        pairs(&mut early.bonds().pairs()),
        pairs(
            &mut model
                .bonds()
                .pairs()
                .chain(model.broken_bonds()[count..].iter().copied())
        )
    );
}

#[test]
fn bad_failure_rules_are_refused_naming_the_field_and_the_value() {
    let base = pair_scene(1.0, BondFailure::breaking(0.1));
    let refused = |edit: &dyn Fn(&mut Scene)| {
        let mut scene = base.clone();
        edit(&mut scene);
        bpm::scene::validate(&scene).unwrap_err().to_string()
    };
    let set = |rule: BondFailure| move |s: &mut Scene| s.force_field.bond_failure = Some(rule);
    let cases: [(String, &str); 5] = [
        (
            refused(&set(BondFailure::breaking(0.0))),
            "eps_c = 0 must be positive",
        ),
        (refused(&set(BondFailure::breaking(-0.2))), "eps_c = -0.2"),
        (
            refused(&set(unsmoothed(0.1, Some(0.1)))),
            "eps_p = 0.1 must be below the critical strain eps_c = 0.1",
        ),
        (
            refused(&set(BondFailure {
                breaks: false,
                ..BondFailure::breaking(0.1)
            })),
            "smoothing needs breaking",
        ),
        (
            refused(&|s: &mut Scene| s.force_field.zero_net_multibody = true),
            "zero-net-multibody variant does not combine",
        ),
    ];
    for (message, expected) in cases {
        assert!(message.contains("force_field.bond_failure"), "{message}");
        assert!(message.contains(expected), "{message}");
    }
    // A stage's force field is checked too.
    let mut staged = base.clone();
    let mut field = staged.force_field.clone();
    field.bond_failure = Some(unsmoothed(0.1, Some(0.2)));
    staged.stages[0].force_field = Some(field);
    let message = bpm::scene::validate(&staged).unwrap_err().to_string();
    assert!(
        message.contains("stages[0]") && message.contains("eps_p = 0.2"),
        "{message}"
    );
    // The LAMMPS harness says it cannot run it yet, instead of running
    // elastic bonds.
    let dir = common::scratch_dir("failure-lammps");
    let message = bpm::lammps::write_driver(&base, &dir, "pull", false)
        .expect_err("refused")
        .to_string();
    assert!(message.contains("bonds that break or yield"), "{message}");
}

#[test]
fn a_final_scene_keeps_the_plastic_strains_and_reloads_at_rest() {
    let rule = BondFailure {
        breaks: false,
        ..unsmoothed(0.5, Some(0.05))
    };
    let scene = tetrahedron(0.3, rule);
    let mut sys = build_system(&scene, 1);
    let (_, error) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
    assert!(error.is_none(), "{error:?}");
    let fin = bpm::scene::final_scene(&scene, &sys);
    let strains = fin
        .bonds
        .plastic_strain
        .clone()
        .expect("plastic strains written");
    assert_eq!(
        strains,
        sys.model_as::<BpmModel>().unwrap().plastic_strains()
    );
    bpm::scene::validate(&fin).unwrap();
    let mut again = build_system(&fin, 1);
    let drivers = StageDrivers {
        dt: 0.02,
        ..Default::default()
    };
    again.setup(&drivers).unwrap();
    assert_eq!(
        again.model_as::<BpmModel>().unwrap().plastic_strains(),
        strains
    );
    let largest = common::max_abs(&again.particles.f);
    assert!(largest < 1e-9, "reloaded at rest: largest force {largest}");
    // Without them it would spring back to its first lengths.
    let mut lost = fin.clone();
    lost.bonds.plastic_strain = None;
    let mut lost = build_system(&lost, 1);
    lost.setup(&drivers).unwrap();
    assert!(common::max_abs(&lost.particles.f) > 1e-3);
    // A bad strain is refused, naming the bond.
    let mut bad = fin.clone();
    bad.bonds.plastic_strain.as_mut().unwrap()[2] = -1.5;
    let message = bpm::scene::validate(&bad).unwrap_err().to_string();
    assert!(
        message.contains("bonds.plastic_strain[2]") && message.contains("-1.5"),
        "{message}"
    );
}

#[test]
fn a_run_with_failing_bonds_records_bonds_intact_and_broken() {
    let mut scene = small_solid().clone();
    scene.force_field = ForceField::paper(-0.5);
    scene.force_field.bond_failure = Some(BondFailure::breaking(0.03));
    let mut pull = StageSpec::hold("pull", 1000, 0.05);
    pull.deformation = Some(Deformation::Isotropic {
        true_strain_rate: 1e-3,
    });
    pull.record.every = 100;
    scene.stages = vec![pull];
    let total = scene.bonds.pairs.len() as f64;
    let mut sys = build_system(&scene, 1);
    let (out, error) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
    assert!(error.is_none(), "{error:?}");
    let (bonds, broken) = (
        out[0].column("bonds").unwrap(),
        out[0].column("broken_bonds").unwrap(),
    );
    assert_eq!(broken[0], 0.0);
    assert!(broken.windows(2).all(|w| w[1] >= w[0]), "{broken:?}");
    assert!(*broken.last().unwrap() > 0.0);
    for (b, k) in bonds.iter().zip(&broken) {
        assert_eq!(b + k, total);
    }
    // An elastic run records neither.
    let mut elastic = scene.clone();
    elastic.force_field.bond_failure = None;
    elastic.stages[0].steps = 10;
    let mut sys = build_system(&elastic, 1);
    let (out, _) = run_scene(&mut sys, &elastic, &RunOptions::quiet(1));
    assert!(out[0].column("bonds").is_none());
}
