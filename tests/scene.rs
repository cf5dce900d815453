//! Scene validation: every bad input is rejected with the field named.

use bpm::scene::{validate, SceneError};
use serde_json::{json, Value};

fn valid() -> Value {
    json!({
        "seed": 1,
        "box": {"lo": [0, 0, 0], "lengths": [6, 6, 6], "periodic": [true, true, true]},
        "particles": {"positions": [[1, 1, 1], [2, 1, 1], [1, 2, 1]]},
        "bonds": {"pairs": [[0, 1], [0, 2]]},
        "force_field": {"bond": {"k": 1, "a": -0.5, "gamma": 1}, "pair": {"k": 1, "d": 1, "a": 50, "gamma": 1}},
        "stages": [{"name": "hold", "steps": 10}]
    })
}

fn check(doc: Value) -> Result<(), SceneError> {
    let scene = serde_json::from_value(doc)?;
    validate(&scene)
}

fn rejects(edit: impl FnOnce(&mut Value), field: &str) {
    rejects_in(valid(), edit, field);
}

/// `doc` after `edit` is refused with a message naming `field`.
fn rejects_in(mut doc: Value, edit: impl FnOnce(&mut Value), field: &str) {
    edit(&mut doc);
    let err = check(doc).expect_err("must be rejected").to_string();
    assert!(
        err.contains(field),
        "message `{err}` does not name `{field}`"
    );
}

#[test]
fn the_reference_scene_is_valid() {
    check(valid()).unwrap();
}

#[test]
fn missing_fields_are_named() {
    rejects(
        |d| {
            drop(
                d["force_field"]["bond"]
                    .as_object_mut()
                    .unwrap()
                    .remove("k"),
            )
        },
        "`k`",
    );
    rejects(
        |d| drop(d.as_object_mut().unwrap().remove("seed")),
        "`seed`",
    );
}

#[test]
fn unknown_fields_are_named() {
    rejects(|d| d["force_field"]["bond"]["kk"] = json!(1), "kk");
}

#[test]
fn negative_stiffness_is_rejected() {
    rejects(
        |d| d["force_field"]["bond"]["k"] = json!(-1),
        "force_field.bond.k",
    );
    rejects(
        |d| d["force_field"]["pair"]["k"] = json!(-1),
        "force_field.pair.k",
    );
}

#[test]
fn non_positive_contact_distance_is_rejected() {
    rejects(
        |d| d["force_field"]["pair"]["d"] = json!(0),
        "force_field.pair.d",
    );
}

#[test]
fn bond_to_a_missing_particle_is_rejected() {
    rejects(|d| d["bonds"]["pairs"][1] = json!([0, 7]), "bonds.pairs[1]");
    rejects(|d| d["bonds"]["pairs"][1] = json!([2, 2]), "bonds.pairs[1]");
    rejects(|d| d["bonds"]["pairs"][1] = json!([1, 0]), "bonds.pairs[1]");
}

#[test]
fn non_finite_values_are_rejected() {
    // JSON has no NaN; it reaches the scene from code, so test the struct.
    let mut scene: bpm::scene::Scene = serde_json::from_value(valid()).unwrap();
    scene.particles.positions[2][1] = f64::NAN;
    assert!(validate(&scene)
        .unwrap_err()
        .to_string()
        .contains("particles.positions[2]"));
    let mut scene: bpm::scene::Scene = serde_json::from_value(valid()).unwrap();
    scene.force_field.bond.a = f64::INFINITY;
    assert!(validate(&scene)
        .unwrap_err()
        .to_string()
        .contains("force_field.bond.a"));
}

#[test]
fn a_box_too_small_for_the_cutoff_is_rejected() {
    rejects(|d| d["box"]["lengths"] = json!([2.5, 6, 6]), "box.lengths");
}

#[test]
fn inconsistent_arrays_and_stages_are_rejected() {
    rejects(|d| d["bonds"]["r0"] = json!([1.0]), "bonds.r0");
    rejects(
        |d| d["particles"]["velocities"] = json!([[0, 0, 0]]),
        "particles.velocities",
    );
    rejects(|d| d["stages"][0]["dt"] = json!(0), "stages[0].dt");
    rejects(|d| d["stages"] = json!([]), "stages");
    rejects(
        |d| {
            d["stages"][0]["walls"] =
                json!([{"axis": 2, "side": "lo", "position": 0, "stiffness": 1, "cutoff": 1}])
        },
        "stages[0].walls[0].axis",
    );
    rejects(|d| d["box"]["tilt"] = json!([3.5, 0, 0]), "box.tilt[0]");
}

#[test]
fn a_stage_with_both_a_barostat_and_a_deformation_is_refused() {
    let mut doc = valid();
    doc["stages"][0]["barostat"] = json!({"target_pressure": 0.0, "gain": 0.1});
    check(doc).unwrap();
    rejects(
        |d| {
            d["stages"][0]["barostat"] = json!({"target_pressure": 0.0, "gain": 0.1});
            d["stages"][0]["deformation"] = json!({"isotropic": {"true_strain_rate": -1e-4}});
        },
        "stages[0].barostat",
    );
}

#[test]
fn a_sphere_wall_that_would_shrink_through_its_cutoff_is_refused_and_a_fixed_one_is_not() {
    let wall = |velocity: f64| json!({"centre": [3, 3, 3], "radius": 3.0, "velocity": velocity, "stiffness": 1, "cutoff": 1});
    // 10 steps of dt 0.1 (the default): -1.5 d/tau shrinks 3 to 1.5, -2.5
    // to 0.5, inside the cutoff.
    let mut doc = valid();
    doc["stages"][0]["sphere_wall"] = wall(-1.5);
    check(doc).unwrap();
    rejects(
        |d| d["stages"][0]["sphere_wall"] = wall(-2.5),
        "sphere_wall.velocity",
    );
    let mut doc = valid();
    doc["stages"][0]["sphere_wall"] =
        json!({"centre": [3, 3, 3], "radius": 0.5, "stiffness": 1, "cutoff": 1});
    check(doc).unwrap();
}

#[test]
fn a_sphere_wall_moves_at_its_speed_and_writes_no_speed_when_fixed() {
    let moving: bpm::engine::SphereWall = serde_json::from_value(
        json!({"centre": [0, 0, 0], "radius": 5.0, "velocity": -0.5, "stiffness": 1, "cutoff": 1}),
    )
    .unwrap();
    assert_eq!(moving.radius_at(4.0), 3.0);
    let fixed = bpm::engine::SphereWall {
        velocity: 0.0,
        ..moving
    };
    assert_eq!(fixed.radius_at(4.0), 5.0);
    assert!(!serde_json::to_string(&fixed).unwrap().contains("velocity"));
}

/// A valid DEM scene: two spheres of radius 1, one material.
fn valid_dem() -> Value {
    json!({
        "version": 2, "model": "dem", "seed": 1,
        "box": {"lo": [0, 0, 0], "lengths": [8, 8, 8], "periodic": [true, true, true]},
        "particles": {"positions": [[1, 1, 1], [2.9, 1, 1]], "radius": [1, 1],
                      "angular_velocities": [[0, 0, 0.1], [0, 0, 0]]},
        "force_field": {"granular": {"youngs_modulus": 100, "poisson_ratio": 0.25,
                        "restitution": 0.5, "tangential_damping": 1, "sliding_friction": 0.3,
                        "rolling": {"stiffness": 10, "damping": 0.5, "friction": 0.1},
                        "twisting": "marshall"}},
        "stages": [{"name": "hold", "steps": 10, "dt": 0.01}]
    })
}

fn rejects_dem(edit: impl FnOnce(&mut Value), field: &str) {
    rejects_in(valid_dem(), edit, field);
}

#[test]
fn dem_scenes_are_checked_field_by_field() {
    check(valid_dem()).unwrap();
    let granular = |d: &mut Value| d["force_field"]["granular"].take();
    rejects_dem(|d| drop(granular(d)), "force_field.granular");
    for (field, value) in [
        ("youngs_modulus", json!(0)),
        ("poisson_ratio", json!(0.6)),
        ("poisson_ratio", json!(-1)),
        ("restitution", json!(0)),
        ("restitution", json!(1.5)),
        ("tangential_damping", json!(-1)),
        ("sliding_friction", json!(-0.1)),
    ] {
        rejects_dem(
            |d| d["force_field"]["granular"][field] = value,
            &format!("force_field.granular.{field}"),
        );
    }
    rejects_dem(
        |d| d["force_field"]["granular"]["rolling"]["stiffness"] = json!(0),
        "force_field.granular.rolling.stiffness",
    );
    rejects_dem(
        |d| {
            d["force_field"]["granular"]["twisting"] =
                json!({"sds": {"stiffness": 1, "damping": -1, "friction": 0.1}})
        },
        "force_field.granular.twisting.sds.damping",
    );
    // What belongs to the other model is refused, with the reason.
    rejects_dem(|d| d["bonds"] = json!({"pairs": [[0, 1]]}), "bonds.pairs");
    rejects_dem(
        |d| d["force_field"]["pair"] = json!({"k": 1, "d": 1, "a": 0, "gamma": 0}),
        "no bonds and no bpm contacts",
    );
    rejects_dem(
        |d| d["stages"][0]["reset_reference"] = json!(true),
        "stages[0].reset_reference",
    );
    rejects_dem(
        |d| d["particles"]["angular_velocities"] = json!([[0, 0, 0]]),
        "particles.angular_velocities",
    );
    // A sphere of radius 1.9 and the skin need half the box above 3.8 + 0.3.
    rejects_dem(
        |d| d["particles"]["radius"] = json!([1.9, 1]),
        "box.lengths",
    );
    rejects(
        |d| d["force_field"]["granular"] = valid_dem()["force_field"]["granular"].clone(),
        "force_field.granular",
    );
    rejects(
        |d| d["particles"]["angular_velocities"] = json!([[0, 0, 0], [0, 0, 0], [0, 0, 0]]),
        "particles.angular_velocities",
    );
}

fn granular_wall() -> Value {
    json!({"axis": 2, "side": "lo", "position": 0, "velocity": 0.01,
           "material": {"youngs_modulus": 1e4, "poisson_ratio": 0.3, "restitution": 0.9,
                        "tangential_damping": 1, "sliding_friction": 0.03}})
}

#[test]
fn granular_walls_need_dem_spheres_a_closed_axis_and_a_valid_material() {
    let mut doc = valid_dem();
    doc["box"]["periodic"] = json!([true, true, false]);
    doc["stages"][0]["granular_walls"] = json!([granular_wall()]);
    check(doc.clone()).unwrap();
    rejects_in(
        doc.clone(),
        |d| d["stages"][0]["granular_walls"][0]["axis"] = json!(0),
        "stages[0].granular_walls[0].axis",
    );
    rejects_in(
        doc.clone(),
        |d| d["stages"][0]["granular_walls"][0]["material"]["restitution"] = json!(0),
        "stages[0].granular_walls[0].material.restitution",
    );
    // Spheres at z = 1 behind a wall at z = 2 that faces up.
    rejects_in(
        doc,
        |d| d["stages"][0]["granular_walls"][0]["position"] = json!(2.0),
        "stages[0].granular_walls[0].position",
    );
    // The bonded model's walls are the harmonic ones.
    rejects(
        |d| {
            d["box"]["periodic"] = json!([true, true, false]);
            d["stages"][0]["granular_walls"] = json!([granular_wall()]);
        },
        "stages[0].granular_walls[0]",
    );
}

#[test]
fn lees_edwards_shear_needs_dem_spheres() {
    let shear = json!({"simple_shear": {"tilt": "xy", "rate": 0.01, "remap": "v"}});
    let mut doc = valid_dem();
    doc["stages"][0]["deformation"] = shear.clone();
    check(doc).unwrap();
    rejects(
        |d| d["stages"][0]["deformation"] = shear,
        "stages[0].deformation.simple_shear.remap",
    );
    // Affine shear of the bonded model stays allowed.
    let mut doc = valid();
    doc["stages"][0]["deformation"] = json!({"simple_shear": {"tilt": "xy", "rate": 0.01}});
    check(doc).unwrap();
}

/// `particles.ids` (the atom ids an imported data file gave): one per
/// particle, from 1, strictly increasing; absent or `1..N` it is not
/// written, so scenes without ids of their own read and write as before.
#[test]
fn particle_ids_are_checked_and_written_only_when_not_one_to_n() {
    rejects(|d| d["particles"]["ids"] = json!([2, 5]), "particles.ids");
    rejects(
        |d| d["particles"]["ids"] = json!([0, 5, 9]),
        "particles.ids[0]",
    );
    rejects(
        |d| d["particles"]["ids"] = json!([2, 9, 5]),
        "particles.ids[2]",
    );
    rejects(
        |d| d["particles"]["ids"] = json!([2, 5, 5]),
        "particles.ids[2]",
    );
    let err = serde_json::from_value::<bpm::scene::Scene>({
        let mut d = valid();
        d["particles"]["ids"] = json!([-1, 5, 9]);
        d
    });
    assert!(err.is_err(), "a negative id must not load");
    let mut doc = valid();
    doc["particles"]["ids"] = json!([2, 5, 90]);
    check(doc.clone()).unwrap();
    let scene: bpm::scene::Scene = serde_json::from_value(doc).unwrap();
    assert_eq!(scene.particles.id(2), 90);
    let text = serde_json::to_string(&scene).unwrap();
    assert!(text.contains(r#""ids":[2,5,90]"#), "{text}");
    assert_eq!(
        serde_json::from_str::<bpm::scene::Scene>(&text).unwrap(),
        scene
    );
    // 1..N, given or not, writes the same bytes as a scene without ids.
    let plain: bpm::scene::Scene = serde_json::from_value(valid()).unwrap();
    assert_eq!(plain.particles.id(2), 3);
    let mut numbered = plain.clone();
    numbered.particles.ids = Some(vec![1, 2, 3]);
    check(serde_json::to_value(&numbered).unwrap()).unwrap();
    let plain_text = serde_json::to_string(&plain).unwrap();
    assert!(!plain_text.contains("ids"), "{plain_text}");
    assert_eq!(serde_json::to_string(&numbered).unwrap(), plain_text);
}
