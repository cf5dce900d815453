//! The multi-contact closure in the native engine: against its closed form
//! for a sphere squeezed between two plates, the lateral reach it gives a
//! squeezed sphere, plain Hertz at zero prefactor, and its errors.

mod common;

use bpm::scene::{build_system, run_scene, validate, RunOptions, Scene, StageOutput};
use serde_json::{json, Value};
use std::f64::consts::PI;

const RADIUS: f64 = 0.5;
const E: f64 = 100.0;
const NU: f64 = 0.3;
const E_WALL: f64 = 1e6;

fn material(e: f64) -> Value {
    json!({"youngs_modulus": e, "poisson_ratio": NU, "restitution": 0.5,
           "tangential_damping": 1.0, "sliding_friction": 0.0})
}

/// One sphere between a fixed floor (wall 0) and a plate (wall 1) closing
/// at 2.5e-4 d/tau (slow enough for the contacts' damping force to stay
/// below 0.1% of the elastic one), optionally touched at its sides by two fixed walls
/// (walls 2 and 3) from the start.
fn squeeze(multicontact: Option<Value>, side_walls: bool) -> StageOutput {
    let wall = |axis: usize, side: &str, position: f64, velocity: f64| {
        json!({"axis": axis, "side": side, "position": position, "velocity": velocity,
               "material": material(E_WALL)})
    };
    let mut walls = vec![wall(2, "lo", 0.0, 0.0), wall(2, "hi", 1.0, -2.5e-4)];
    if side_walls {
        walls.push(wall(0, "lo", -RADIUS, 0.0));
        walls.push(wall(0, "hi", RADIUS, 0.0));
    }
    let mut ff = json!({"granular": material(E)});
    if let Some(m) = multicontact {
        ff["multicontact"] = m;
    }
    let scene: Scene = serde_json::from_value(json!({
        "model": "dem", "seed": 1,
        "box": {"lo": [-1.0, -2.0, -0.5], "lengths": [2.0, 4.0, 2.0],
                "periodic": [false, true, false]},
        "particles": {"positions": [[0.0, 0.0, RADIUS]], "radius": [RADIUS]},
        "force_field": ff,
        "stages": [{"name": "squeeze", "steps": 40000, "dt": 0.01,
                    "granular_walls": walls, "record": {"every": 1000}}]
    }))
    .unwrap();
    validate(&scene).unwrap();
    let mut sys = build_system(&scene, 1);
    let (mut out, err) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
    assert!(err.is_none(), "{err:?}");
    out.remove(0)
}

fn column(stage: &StageOutput, name: &str) -> Vec<f64> {
    let c = stage
        .columns
        .iter()
        .position(|c| c.name == name)
        .unwrap_or_else(|| panic!("no column {name}"));
    stage.rows.iter().map(|r| r[c]).collect()
}

/// The quasi-static plate force at overlap `delta` per plate: with the
/// closure, each plate's overlap grows by the other plate's displacement
/// `c F`. The contact points, on the plates, are `d = 2 (R - delta)` apart
/// on opposite sides, so `c = gamma (1 + nu) (3 - 2 nu) / (2 pi E d)` and
/// `F = k (delta + c F)^(3/2)`. Iterated from the Hertz force, this climbs
/// to the smaller of its two roots, the stable one (the larger is where the
/// feedback's slope `3/2 k c (delta + c F)^(1/2)` exceeds 1).
fn closed_form(delta: f64, gamma: f64) -> f64 {
    let e_eff = 1.0 / ((1.0 - NU * NU) / E + (1.0 - NU * NU) / E_WALL);
    let k = 4.0 / 3.0 * e_eff * RADIUS.sqrt();
    let d = 2.0 * (RADIUS - delta);
    let c = gamma * (1.0 + NU) * (3.0 - 2.0 * NU) / (2.0 * PI * E * d);
    let mut f = 0.0;
    for _ in 0..10_000 {
        let next = k * (delta + c * f).powf(1.5);
        if (next - f).abs() <= 1e-15 * next {
            return next;
        }
        f = next;
    }
    panic!("no stable plate force at overlap {delta} with gamma {gamma}");
}

/// Recorded plate force (mean of floor and plate) against the closed form,
/// at every row with overlap above 0.01 d; returns the largest relative
/// deviation.
fn worst_deviation(stage: &StageOutput, gamma: f64) -> f64 {
    let floor = column(stage, "granular_wall0_force");
    let plate = column(stage, "granular_wall1_force");
    let top = column(stage, "granular_wall1_position");
    let mut worst: f64 = 0.0;
    for ((f0, f1), z) in floor.iter().zip(&plate).zip(&top) {
        let delta = RADIUS - 0.5 * z;
        if delta < 0.01 {
            continue;
        }
        let expected = closed_form(delta, gamma);
        worst = worst.max((0.5 * (f0 + f1) - expected).abs() / expected);
    }
    worst
}

#[test]
fn a_sphere_between_plates_follows_the_closed_form_of_the_closure() {
    for gamma in [0.82, 2.0] {
        let stage = squeeze(Some(json!({"prefactor": gamma})), false);
        let deviation = worst_deviation(&stage, gamma);
        let from_hertz = worst_deviation(&stage, 0.0);
        eprintln!(
            "gamma {gamma}: {deviation:.2e} from the closed form, {from_hertz:.2e} from Hertz"
        );
        assert!(deviation < 2e-3, "{deviation}");
        assert!(from_hertz > 0.05, "the closure must stiffen: {from_hertz}");
    }
    let hertz = squeeze(None, false);
    let deviation = worst_deviation(&hertz, 0.0);
    eprintln!("plain Hertz: {deviation:.2e} from Hertz");
    assert!(deviation < 2e-3, "{deviation}");
}

#[test]
fn a_squeezed_sphere_reaches_out_to_its_side_walls_only_with_the_closure() {
    let hertz = squeeze(None, true);
    for w in [2, 3] {
        let side = column(&hertz, &format!("granular_wall{w}_force"));
        assert!(side.iter().all(|&f| f == 0.0), "Hertz: {side:?}");
    }
    for mc in [
        json!({"prefactor": 0.82}),
        json!({"prefactor": 0.82, "max_penetration_ratio": 0.11}),
    ] {
        let stage = squeeze(Some(mc.clone()), true);
        let plate = column(&stage, "granular_wall1_force");
        let (left, right) = (
            column(&stage, "granular_wall2_force"),
            column(&stage, "granular_wall3_force"),
        );
        let last = plate.len() - 1;
        eprintln!(
            "{mc}: plate {:.4}, sides {:.4e} {:.4e}",
            plate[last], left[last], right[last]
        );
        assert!(left[last] > 1e-3 * plate[last], "{mc}: {left:?}");
        assert!(
            (left[last] - right[last]).abs() < 1e-6 * left[last],
            "{left:?} {right:?}"
        );
    }
}

#[test]
fn a_zero_prefactor_is_plain_hertz() {
    let mut scene = bpm::verify::dem_lattice(7, true);
    scene.stages[0].steps = 400;
    let mut with = scene.clone();
    with.force_field.multicontact = Some(bpm::engine::MultiContact::standard(0.0));
    let run = |s: &Scene| {
        validate(s).unwrap();
        let mut sys = build_system(s, 1);
        let (_, err) = run_scene(&mut sys, s, &RunOptions::quiet(1));
        assert!(err.is_none(), "{err:?}");
        sys.particles.x
    };
    let (a, b) = (run(&scene), run(&with));
    let worst = a
        .iter()
        .zip(&b)
        .flat_map(|(p, q)| p.iter().zip(q).map(|(u, v)| (u - v).abs()))
        .fold(0.0, f64::max);
    // Only the summation order may differ (the closure's longer pair list).
    assert!(worst < 1e-12, "{worst}");
    // And a positive prefactor moves the spheres.
    with.force_field.multicontact = Some(bpm::engine::MultiContact::standard(1.0));
    let c = run(&with);
    let moved = a
        .iter()
        .zip(&c)
        .flat_map(|(p, q)| p.iter().zip(q).map(|(u, v)| (u - v).abs()))
        .fold(0.0, f64::max);
    assert!(moved > 1e-6, "{moved}");
}

#[test]
fn corrections_beyond_the_reach_stop_the_run() {
    let stage_err = {
        let mut scene = bpm::verify::dem_lattice(7, false);
        scene.stages[0].steps = 50;
        scene.force_field.multicontact = Some(bpm::engine::MultiContact {
            reach: 1e-3,
            ..bpm::engine::MultiContact::standard(50.0)
        });
        validate(&scene).unwrap();
        let mut sys = build_system(&scene, 1);
        let (_, err) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
        err.expect("the run must stop").to_string()
    };
    assert!(
        stage_err.contains("beyond the closure's reach 0.001"),
        "{stage_err}"
    );
}

#[test]
fn the_closure_is_refused_where_it_means_nothing() {
    let mut scene = bpm::verify::dem_lattice(7, false);
    scene.force_field.multicontact = Some(bpm::engine::MultiContact::standard(-1.0));
    let err = validate(&scene).unwrap_err().to_string();
    assert!(err.contains("multicontact.prefactor"), "{err}");
    scene.force_field.multicontact = Some(bpm::engine::MultiContact {
        reach: 0.0,
        ..bpm::engine::MultiContact::standard(1.0)
    });
    let err = validate(&scene).unwrap_err().to_string();
    assert!(err.contains("multicontact.reach"), "{err}");
    let mut bonded = bpm::verify::dem_lattice(7, false);
    bonded.model = bpm::scene::ModelKind::Bpm;
    bonded.force_field = bpm::scene::ForceField::paper(0.0);
    bonded.particles.angular_velocities = None;
    bonded.force_field.multicontact = Some(bpm::engine::MultiContact::standard(1.0));
    let err = validate(&bonded).unwrap_err().to_string();
    assert!(err.contains("multicontact"), "{err}");
}

/// `bpm mc-box`'s single sphere under plain Hertz: the lid stress is
/// Hertz's force at half the lid's travel per side over the box's face
/// (d^2), and nothing reaches the side walls; the closures push on them.
#[test]
fn the_rigid_box_study_squeezes_a_single_sphere_as_hertz_says() {
    use bpm::studies::mcdem::rigid_box::{run_box, Arrangement, BoxOptions};
    let opts = BoxOptions {
        max_displacement: 0.3,
        records: 30,
        ..BoxOptions::default()
    };
    let report = run_box(&opts, "test", &bpm::studies::StudyRuntime::plain(1, false)).unwrap();
    let e = report.hydrogel.youngs_modulus;
    let (nu, wall) = (report.hydrogel.poisson_ratio, opts.wall_modulus);
    let e_eff = 1.0 / ((1.0 - nu * nu) / e + (1.0 - nu * nu) / wall);
    let d = report.hydrogel.diameter;
    let r = d / 2.0;
    let single: Vec<_> = report
        .curves
        .iter()
        .filter(|c| c.arrangement == Arrangement::Single)
        .collect();
    let hertz = single[0];
    assert_eq!(hertz.variant, "Hertz");
    let mut worst: f64 = 0.0;
    for (u, s) in hertz.displacement.iter().zip(&hertz.walls.lid_stress) {
        if *u < 0.1 {
            continue;
        }
        let delta = 0.5 * u * r;
        let expected = 4.0 / 3.0 * e_eff * r.sqrt() * delta.powf(1.5) / (d * d);
        worst = worst.max((s - expected).abs() / expected);
    }
    eprintln!("single sphere, Hertz: lid stress within {worst:.2e} of Hertz");
    assert!(worst < 5e-3, "{worst}");
    assert!(hertz.walls.side_stress.iter().all(|&s| s == 0.0));
    for closure in &single[1..] {
        let last = closure.walls.side_stress.len() - 1;
        assert!(closure.walls.side_stress[last] > 0.0, "{}", closure.variant);
        assert!(closure.walls.lid_stress[last] > 1.1 * hertz.walls.lid_stress[last]);
    }
}

/// Two spheres stacked between a floor and a closing lid: each sphere is
/// squeezed between two opposite contacts, a wall's and the pair's, whose
/// points are `d_s = (R - delta_w) + (R - delta_p / 2)` apart. Each
/// contact's overlap grows by `c F` per sphere, `c = gamma (1 + nu) (3 -
/// 2 nu) / (2 pi E d_s)`, so `F = k_w (delta_w + c F)^(3/2)` and `F = k_p
/// (delta_p + 2 c F)^(3/2)` with the lid at `4 R - 2 delta_w - delta_p`.
/// A pair or wall contact point on the wrong side of its sphere breaks
/// this.
#[test]
fn a_stack_of_two_spheres_follows_the_closed_form_of_the_closure() {
    let gamma = 1.5;
    let wall = |side: &str, position: f64, velocity: f64| {
        json!({"axis": 2, "side": side, "position": position, "velocity": velocity,
               "material": material(E_WALL)})
    };
    let scene: Scene = serde_json::from_value(json!({
        "model": "dem", "seed": 1,
        "box": {"lo": [-2.0, -2.0, -0.5], "lengths": [4.0, 4.0, 3.0],
                "periodic": [true, true, false]},
        "particles": {"positions": [[0.0, 0.0, RADIUS], [0.0, 0.0, 3.0 * RADIUS]],
                      "radius": [RADIUS, RADIUS]},
        "force_field": {"granular": material(E), "multicontact": {"prefactor": gamma}},
        "stages": [{"name": "squeeze", "steps": 60000, "dt": 0.01,
                    "granular_walls": [wall("lo", 0.0, 0.0), wall("hi", 4.0 * RADIUS, -2.5e-4)],
                    "record": {"every": 2000}}]
    }))
    .unwrap();
    validate(&scene).unwrap();
    let mut sys = build_system(&scene, 1);
    let (mut out, err) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
    assert!(err.is_none(), "{err:?}");
    let stage = out.remove(0);
    let e_wall = 1.0 / ((1.0 - NU * NU) / E + (1.0 - NU * NU) / E_WALL);
    let e_pair = 1.0 / (2.0 * (1.0 - NU * NU) / E);
    let k_wall = 4.0 / 3.0 * e_wall * RADIUS.sqrt();
    let k_pair = 4.0 / 3.0 * e_pair * (0.5 * RADIUS).sqrt();
    let prefactor = gamma * (1.0 + NU) * (3.0 - 2.0 * NU) / (2.0 * PI * E);
    // The gap at force F: the overlaps follow from F by a fixed point in
    // the points' distance.
    let gap = |f: f64| {
        let (mut dw, mut dp) = (0.0, 0.0);
        for _ in 0..100 {
            let c = prefactor / ((RADIUS - dw) + (RADIUS - 0.5 * dp));
            dw = (f / k_wall).powf(2.0 / 3.0) - c * f;
            dp = (f / k_pair).powf(2.0 / 3.0) - 2.0 * c * f;
        }
        4.0 * RADIUS - 2.0 * dw - dp
    };
    let (floor, lid) = (
        column(&stage, "granular_wall0_force"),
        column(&stage, "granular_wall1_force"),
    );
    let top = column(&stage, "granular_wall1_position");
    let mut worst: f64 = 0.0;
    for ((f0, f1), z) in floor.iter().zip(&lid).zip(&top) {
        if 4.0 * RADIUS - z < 0.04 {
            continue;
        }
        // Bisection for the force that gives this gap (it falls with F).
        let (mut lo, mut hi) = (0.0, 50.0);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if gap(mid) > *z {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let expected = 0.5 * (lo + hi);
        worst = worst.max((0.5 * (f0 + f1) - expected).abs() / expected);
    }
    let last = lid.len() - 1;
    let hertz_gap =
        |f: f64| 4.0 * RADIUS - 2.0 * (f / k_wall).powf(2.0 / 3.0) - (f / k_pair).powf(2.0 / 3.0);
    eprintln!(
        "stack: {worst:.2e} from the closed form; lid force {:.4} where Hertz gives the gap {:.5} (lid at {:.5})",
        lid[last],
        hertz_gap(lid[last]),
        top[last]
    );
    assert!(worst < 3e-3, "{worst}");
    // Hertz needs a narrower gap for the same force.
    assert!(
        top[last] - hertz_gap(lid[last]) > 0.01,
        "the closure must stiffen the stack"
    );
}

/// The advanced closure with a zero ratio and the magnitude test switches
/// every term off, either way: plain Hertz.
#[test]
fn a_zero_ratio_on_magnitudes_is_plain_hertz() {
    let base = squeeze(None, true);
    for switch in ["whole_contact", "per_term"] {
        let mc = json!({"prefactor": 1.0, "max_penetration_ratio": 0.0,
                        "switch": switch, "test": "magnitude"});
        let stage = squeeze(Some(mc), true);
        let switched = column(&stage, "mc_switched_off");
        assert!(
            switched.iter().any(|&n| n > 0.0),
            "{switch}: the closure must be on and switch"
        );
        for w in 0..4 {
            let name = format!("granular_wall{w}_force");
            let (a, b) = (column(&base, &name), column(&stage, &name));
            let worst = a
                .iter()
                .zip(&b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-12, "{switch}, wall {w}: {worst}");
        }
    }
}

/// Between plates, the plate term `c F` is the only one each plate
/// receives: while it stays below `MPR R` the advanced closure is the
/// standard one, and where even plain Hertz's force gives a term beyond it,
/// the plates fall back to Hertz.
#[test]
fn the_advanced_closure_falls_back_to_hertz_beyond_its_ratio() {
    let (gamma, mpr) = (2.0, 0.004);
    let stage = squeeze(
        Some(json!({"prefactor": gamma, "max_penetration_ratio": mpr})),
        false,
    );
    let c = |delta: f64| {
        gamma * (1.0 + NU) * (3.0 - 2.0 * NU) / (2.0 * PI * E * 2.0 * (RADIUS - delta))
    };
    let floor = column(&stage, "granular_wall0_force");
    let plate = column(&stage, "granular_wall1_force");
    let top = column(&stage, "granular_wall1_position");
    let switched = column(&stage, "mc_switched_off");
    let (mut standard_rows, mut hertz_rows) = (0, 0);
    for (((f0, f1), z), off) in floor.iter().zip(&plate).zip(&top).zip(&switched) {
        let delta = RADIUS - 0.5 * z;
        if delta < 0.01 {
            continue;
        }
        let f = 0.5 * (f0 + f1);
        let (standard, hertz) = (closed_form(delta, gamma), closed_form(delta, 0.0));
        if c(delta) * standard < mpr * RADIUS {
            standard_rows += 1;
            assert!(
                (f - standard).abs() < 2e-3 * standard,
                "{delta}: {f} vs {standard}"
            );
            assert_eq!(*off, 0.0);
        } else if c(delta) * hertz > mpr * RADIUS {
            hertz_rows += 1;
            assert!((f - hertz).abs() < 2e-3 * hertz, "{delta}: {f} vs {hertz}");
            assert_eq!(*off, 2.0, "both plates switched off");
        }
    }
    eprintln!("{standard_rows} rows as the standard closure, {hertz_rows} as Hertz");
    assert!(standard_rows >= 3 && hertz_rows >= 3);
}

/// `bpm mc-compress` at a small scale: the bed is built without overlaps
/// and repeatably, and the closures stiffen the bed at the top of the
/// compression.
#[test]
fn a_small_bed_compresses_and_the_closures_stiffen_it() {
    use bpm::studies::mcdem::compression::{build_bed, run_compression, CompressionOptions};
    // 60 spheres fill this box to about 0.56: the bed is built taller.
    let opts = CompressionOptions {
        spheres: 60,
        box_size: [0.0825, 0.0825, 0.0825],
        lid_speed: 0.5,
        max_fraction: 0.75,
        cycles: 2,
        records: 20,
        ..CompressionOptions::default()
    };
    let bed = build_bed(&opts).unwrap();
    let n = bed.radii.len();
    let mut worst: f64 = 0.0;
    for i in 0..n {
        for j in i + 1..n {
            let r = (0..3)
                .map(|k| (bed.centres[i][k] - bed.centres[j][k]).powi(2))
                .sum::<f64>()
                .sqrt();
            worst = worst.max(bed.radii[i] + bed.radii[j] - r);
        }
        for k in 0..3 {
            let top = if k == 2 {
                bed.start_height
            } else {
                bed.edges[k]
            };
            assert!(bed.centres[i][k] >= bed.radii[i] - 1e-12);
            assert!(bed.centres[i][k] <= top - bed.radii[i] + 1e-12);
        }
    }
    assert!(worst <= 1e-6, "overlap {worst}");
    assert!(bed.start_height > bed.edges[2] + 0.1, "built taller");
    let again = build_bed(&opts).unwrap();
    assert_eq!(bed.centres, again.centres, "the seed fixes the bed");
    let (report, _) =
        run_compression(&opts, "test", &bpm::studies::StudyRuntime::plain(1, false)).unwrap();
    let built = bed.solid_volume() / (bed.edges[0] * bed.edges[1] * bed.start_height);
    for run in &report.runs {
        let ends: Vec<(f64, f64)> = run
            .passes
            .iter()
            .map(|p| (p.fraction[0], p.fraction[p.fraction.len() - 1]))
            .collect();
        let expected = [
            (built, 0.75),
            (0.75, report.start_fraction),
            (report.start_fraction, 0.75),
            (0.75, report.start_fraction),
        ];
        assert_eq!(ends.len(), 4);
        for ((a, b), (x, y)) in ends.iter().zip(expected) {
            assert!((a - x).abs() < 1e-9 && (b - y).abs() < 1e-9, "{ends:?}");
        }
        for p in &run.passes {
            assert!((p.lid_speed - opts.lid_speed).abs() < 0.05 * opts.lid_speed);
        }
    }
    let at_top = |run: usize| {
        let pass = &report.runs[run].passes[0];
        let last = pass.fraction.len() - 1;
        assert!((pass.fraction[last] - 0.75).abs() < 1e-9);
        pass.walls.lid_stress[last]
    };
    let (hertz, standard, advanced) = (at_top(0), at_top(1), at_top(2));
    eprintln!(
        "lid stress at 0.75: Hertz {hertz:.1} Pa, standard {standard:.1}, advanced {advanced:.1}"
    );
    assert!(hertz > 0.0);
    assert!(standard > 1.1 * hertz && advanced > 1.1 * hertz);
}

/// A box compressed until the closure's range spans half of it stops the
/// run: a sphere could then reach two images of one partner. With the
/// range of plain contacts the same compression goes on further.
#[test]
fn a_box_compressed_below_twice_the_contact_range_stops_the_run() {
    let run = |multicontact: Option<Value>| {
        let mut ff = json!({"granular": material(E)});
        if let Some(m) = multicontact {
            ff["multicontact"] = m;
        }
        // L = 3.4 exp(-0.1 t): the half box meets the range 1.25 (diameter
        // 1 with reach 0.25) at t = 3.075 tau, the diameter at t = 5.31.
        let scene: Scene = serde_json::from_value(json!({
            "model": "dem", "seed": 1,
            "box": {"lo": [0.0, 0.0, 0.0], "lengths": [3.4, 3.4, 3.4],
                    "periodic": [true, true, true]},
            "particles": {"positions": [[0.5, 0.5, 0.5], [2.0, 2.0, 2.0]],
                          "radius": [RADIUS, RADIUS]},
            "force_field": ff,
            "stages": [{"name": "squeeze", "steps": 500, "dt": 0.01,
                        "deformation": {"isotropic": {"true_strain_rate": -0.1}},
                        "record": {"every": 100}}]
        }))
        .unwrap();
        validate(&scene).unwrap();
        let mut sys = build_system(&scene, 1);
        let (_, err) = run_scene(&mut sys, &scene, &RunOptions::quiet(1));
        err.map(|e| e.to_string())
    };
    assert_eq!(run(None), None);
    let err = run(Some(json!({"prefactor": 0.82})))
        .expect("the compressed box must stop the closure's run");
    assert!(
        err.contains("normal to dimension 0") && err.contains("range 1.2500"),
        "{err}"
    );
    let step: u64 = err
        .split_whitespace()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no step in: {err}"));
    assert!((307..=309).contains(&step), "stopped at step {step}: {err}");
}

/// The closure sees a sheared periodic box's lattice, not its cell: the
/// tilts `+L/2` and `-L/2` describe one lattice (a Lees-Edwards flip
/// turns the first into the second), so three spheres touching across the
/// sheared face get the same corrections and forces in both cells.
#[test]
fn the_closure_is_the_same_across_a_tilt_flip() {
    let run = |tilt: f64| {
        let ff = json!({"granular": material(E), "multicontact": {"prefactor": 2.0}});
        // A at the bottom face; B's image below the face (shifted by the
        // tilt) and C touch A and each other, each overlapping by about
        // 0.05 d.
        let scene: Scene = serde_json::from_value(json!({
            "model": "dem", "seed": 1,
            "box": {"lo": [0.0, 0.0, 0.0], "lengths": [4.0, 4.0, 4.0],
                    "tilt": [tilt, 0.0, 0.0], "periodic": [true, true, true]},
            "particles": {"positions": [[1.0, 0.2, 2.0], [3.504, 3.394, 2.0], [1.95, 0.2, 2.0]],
                          "radius": [RADIUS, RADIUS, RADIUS]},
            "force_field": ff,
            "stages": [{"name": "press", "steps": 20, "dt": 1e-3, "record": {"every": 20}}]
        }))
        .unwrap();
        validate(&scene).unwrap();
        let mut sys = build_system(&scene, 1);
        let drivers = bpm::engine::StageDrivers {
            dt: 1e-3,
            ..Default::default()
        };
        sys.setup(&drivers).unwrap();
        let start = sys.simbox.clone();
        for step in 1..=20 {
            sys.step(&drivers, step, &start).unwrap();
        }
        let closure = sys
            .model_as::<bpm::engine::DemModel>()
            .and_then(|m| m.report().closure)
            .expect("no closure report");
        (
            sys.particles.f.clone(),
            closure.largest.max(-closure.smallest),
        )
    };
    let (f_plus, largest_plus) = run(2.0);
    let (f_minus, largest_minus) = run(-2.0);
    assert!(largest_plus > 1e-3, "the closure is idle: {largest_plus}");
    assert!(
        (largest_plus - largest_minus).abs() < 1e-12 * largest_plus,
        "{largest_plus} against {largest_minus}"
    );
    let scale = f_plus.iter().flatten().fold(0.0f64, |m, c| m.max(c.abs()));
    assert!(scale > 0.1, "no contact force: {f_plus:?}");
    for (a, b) in f_plus.iter().zip(&f_minus) {
        for k in 0..3 {
            assert!(
                (a[k] - b[k]).abs() < 1e-12 * scale,
                "{f_plus:?} against {f_minus:?}"
            );
        }
    }
}

/// The quick grid of `bpm mc-shear`: 108 spheres at volume fractions 0.75
/// and 0.9, friction 0.5, Poisson's ratio 0.5, one curve per law.
#[test]
fn spheres_sheared_above_jamming_resume_and_the_closure_stiffens_them() {
    use bpm::engine::{Deformation, ShearRemap};
    use bpm::studies::mcdem::shear::{
        gather_folders, prepare_packings, run_shear, shear_scene, write_report, ContactLaw, Grid,
        RecordedRun, RunKey, ShearOptions,
    };
    let opts = ShearOptions::grid(Grid::Quick);
    let dir = common::scratch_dir("mc-shear");

    // The packings sit at their volume fractions exactly, in the cube.
    let packings = prepare_packings(&opts).unwrap();
    for (p, phi) in packings.iter().zip([0.75, 0.9]) {
        let solid = 108.0 * PI / 6.0;
        assert!((solid / p.length.powi(3) - phi).abs() < 1e-12);
        assert!((p.reached - phi).abs() < 2e-3, "{} vs {phi}", p.reached);
        assert!(p
            .centres
            .iter()
            .flatten()
            .all(|&x| (0.0..p.length).contains(&x)));
    }
    let key = RunKey::new(&opts, &opts.series[2], &packings[1]);
    let scene = shear_scene(&key, &packings[1]);
    validate(&scene).unwrap();
    // Lees-Edwards shear, fast then slow: the rates' ratio is the factor,
    // and the spheres start on the fast streaming profile.
    let rates: Vec<f64> = scene
        .stages
        .iter()
        .map(|s| match s.deformation {
            Some(Deformation::SimpleShear {
                rate,
                remap: ShearRemap::V,
                ..
            }) => rate,
            _ => panic!("a Lees-Edwards shear"),
        })
        .collect();
    assert!((rates[0] / rates[1] - opts.rate_factor).abs() < 1e-12);
    let v = scene.particles.velocities.as_ref().unwrap();
    let x = &scene.particles.positions;
    assert!((v[7][0] - rates[0] * x[7][1]).abs() < 1e-15);

    let (report, example) = run_shear(&opts, &dir, "test", false).unwrap();
    assert_eq!(report.ran, 6);
    let pressure = |law: ContactLaw, phi: f64| {
        let s = report
            .analysis
            .series
            .iter()
            .find(|s| s.spec.law == law)
            .unwrap();
        let p = s.points.iter().find(|p| p.fraction == phi).unwrap();
        (p.slow.map(|w| w.mean), p.stress_ratio, p.stopped.clone())
    };
    for phi in [0.75, 0.9] {
        let (hertz, ratio, stopped) = pressure(ContactLaw::Hertz, phi);
        let (advanced, _, _) = pressure(ContactLaw::Advanced, phi);
        let (hertz, advanced) = (hertz.unwrap(), advanced.unwrap());
        assert!(stopped.is_none());
        // The closure stiffens the packing: measured 1.7 and 2.4 times
        // Hertz.
        assert!(advanced > 1.3 * hertz, "{phi}: {advanced} vs {hertz}");
        // Friction 0.5 carries shear: the stress ratio is about 0.55.
        let ratio = ratio.unwrap();
        assert!(ratio > 0.3 && ratio < 0.8, "{ratio}");
    }
    let (hertz_75, _, _) = pressure(ContactLaw::Hertz, 0.75);
    let (hertz_90, _, _) = pressure(ContactLaw::Hertz, 0.9);
    assert!(hertz_90.unwrap() > 1.5 * hertz_75.unwrap());
    // The standard closure's feedback runs away at 0.9 (the study's
    // motivation for the advanced one): the run stops, is kept, and has no
    // pressure to fit.
    let (standard, _, stopped) = pressure(ContactLaw::Standard, 0.9);
    assert!(stopped.unwrap().contains("reach"));
    assert!(standard.is_none());
    write_report(&report, &example, &dir).unwrap();
    for file in [
        "shear.json",
        "table.txt",
        "shear.svg",
        "beta.svg",
        "scene.json",
    ] {
        assert!(dir.join(file).exists(), "{file}");
    }

    // A second call reuses every run and analyses them the same; a run
    // file recorded under other parameters is run again.
    // (Wall-clock seconds aside.)
    let json = |r: &bpm::studies::mcdem::shear::ShearReport| {
        let mut series = r.analysis.series.clone();
        for p in series.iter_mut().flat_map(|s| s.points.iter_mut()) {
            p.seconds = 0.0;
        }
        serde_json::to_string(&series).unwrap()
    };
    let path = dir.join("runs").join(key.file_name());
    let mut run: RecordedRun =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    run.key.dt = 0.04;
    std::fs::write(&path, serde_json::to_string(&run).unwrap()).unwrap();
    let (again, _) = run_shear(&opts, &dir, "test", false).unwrap();
    assert_eq!(again.ran, 1);
    assert_eq!(json(&again), json(&report), "bit for bit");
    let (third, _) = run_shear(&opts, &dir, "test", false).unwrap();
    assert_eq!(third.ran, 0);

    // The trend reads the study back: one curve per law, each with a row
    // per stage at its rate, fitted over both fractions (two points are
    // too few for a power law, so no fit).
    let trend = gather_folders(&[dir.as_path()], "test").unwrap();
    assert_eq!(trend.curves.len(), 3);
    for c in &trend.curves {
        let rates: Vec<f64> = c.rows.iter().map(|r| r.rate).collect();
        assert_eq!(rates, vec![opts.rate * opts.rate_factor, opts.rate]);
        if c.spec.law == ContactLaw::Standard {
            // Stopped at 0.9: only 0.75 is measured.
            assert_eq!(c.fractions, vec![0.75]);
        } else {
            assert_eq!(c.fractions, vec![0.75, 0.9]);
        }
        assert!(c.rows.iter().all(|r| r.fit.is_none()));
    }
    let missing = gather_folders(&[dir.join("nowhere").as_path()], "test").unwrap_err();
    assert!(missing.to_string().contains("nowhere"), "{missing}");
    std::fs::remove_dir_all(&dir).ok();
}
